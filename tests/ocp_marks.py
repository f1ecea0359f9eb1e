"""Whether OpenCASCADE's Python binding (the ``cad`` extra) is installed, and the mark that skips
the CAD tests without it. Shared by the test modules that write or read STEP/IGES."""

from __future__ import annotations

import importlib.util

import pytest

HAVE_OCP = importlib.util.find_spec("OCP") is not None
requires_ocp = pytest.mark.skipif(
    not HAVE_OCP,
    reason="OCP is not installed (extra 'cad': pip install 'g1patch[cad]', i.e. "
    "cadquery-ocp-novtk)",
)
