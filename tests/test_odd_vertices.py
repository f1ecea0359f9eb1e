"""Vertices a cage may well have that once stopped a build: a boundary vertex whose one face has a
straight corner there (valence 2, its corner normal zero), and the file named when a build does
fail."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import g1patch
from g1patch.continuity import check
from g1patch.errors import ConstructionError

#: a quad with a straight corner at vertex 1 (the middle of its bottom edge) and a triangle
STRAIGHT = (
    np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0], [2, 1, 0], [0, 1, 0.3]], dtype=float),
    [[0, 1, 2, 3], [0, 3, 4]],
)


@pytest.mark.parametrize("shape", ["interpolate", "limit", "limit-interpolate"])
@pytest.mark.parametrize("method", ["gregory", "split4"])
def test_a_straight_boundary_corner_builds(shape: str, method: str) -> None:
    surface = g1patch.smooth(STRAIGHT, shape=shape, method=method)
    report = check(surface.network)
    assert report.max_edge_angle_deg < 1e-9 and report.folds == 0


def test_a_failed_build_names_its_file(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    path = tmp_path / "cage.obj"
    path.write_text("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n")

    def refuse(*args: object, **kwargs: object) -> None:
        raise ConstructionError("fan normal: vertex 1 has no defined normal")

    monkeypatch.setattr("g1patch.build.build_network", refuse)
    with pytest.raises(ConstructionError, match=rf"^{path}: fan normal: vertex 1"):
        g1patch.smooth(path)
