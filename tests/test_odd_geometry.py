"""Honest verdicts on odd geometry: degenerate patches fail the check, and a surface 1e-25 or 1e25
in size is measured, drawn and shown as the same surface at size 1."""

from __future__ import annotations

import io
from pathlib import Path

import matplotlib.image as mpimg
import numpy as np
import pytest

from g1patch import shapes
from g1patch.api import Surface
from g1patch.build import build_network
from g1patch.cli import main
from g1patch.continuity import check
from g1patch.io.bpt import write_bpt
from g1patch.network import network_from_patch_points
from g1patch.patches import PatchSet

GRID = np.stack(np.meshgrid(np.arange(4.0), np.arange(4.0), indexing="ij"), axis=-1)
FLAT = np.concatenate([GRID, np.zeros((4, 4, 1))], axis=-1)  # a sound planar patch


def _bezier(*control: np.ndarray) -> PatchSet:
    return PatchSet(np.stack(control), "bezier")


DEGENERATE = {
    "a point": _bezier(np.full((4, 4, 3), 5.0)),
    "a segment (two collapsed edges)": _bezier(np.repeat(FLAT[:, :1] + [0, 0, 9], 4, axis=1)),
    "a line, no edge collapsed": _bezier(np.stack([GRID.sum(-1)] * 3, axis=-1)),
}


@pytest.mark.parametrize("name", DEGENERATE)
def test_degenerate_patches_are_reported_and_fail(
    name: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    patches = _bezier(FLAT, DEGENERATE[name].control[0])
    report = check(network_from_patch_points(patches))
    assert (report.degenerate_patches, report.degenerate_patch_ids) == (1, (1,))
    assert not report.passes() and "1 degenerate patches" in report.verdict()
    path = tmp_path / "odd.bpt"
    write_bpt(path, patches)
    assert main(["check", str(path), "--max-angle", "1e-9"]) == 1
    assert "FAILED: 1 degenerate patches" in capsys.readouterr().err


def test_a_triangular_patch_is_not_degenerate() -> None:
    """One collapsed edge is an intended triangular patch (the teapot's poles)."""
    triangle = FLAT.copy()
    triangle[:, 0] = FLAT[0, 0]  # the edge v = 0 collapsed to one point
    report = check(network_from_patch_points(_bezier(FLAT + [0, 0, 1], triangle)))
    assert report.collapsed_edges == 1 and report.degenerate_patches == 0


@pytest.mark.parametrize("scale", [1e-25, 1e25])
def test_a_scaled_surface_has_the_same_verdict_picture_and_page(scale: float) -> None:
    mesh = shapes.torus(8, 4)
    unit = build_network(mesh)
    scaled = build_network(mesh.with_vertices(mesh.vertices * scale))
    expected, measured = check(unit), check(scaled)
    assert measured.passes() and expected.passes() and measured.folds == expected.folds == 0
    # both angles are rounding noise of exact G1 (~1e-13°), each from its own frame's arithmetic
    assert measured.degenerate_normals == expected.degenerate_normals == 0
    pngs = [Surface(network).render(size=(160, 160)) for network in (unit, scaled)]
    pictures = [mpimg.imread(io.BytesIO(png)) for png in pngs]
    assert np.abs(pictures[0] - pictures[1]).max() <= 1 / 255
    assert Surface(scaled).view().startswith("<!DOCTYPE html>")
