"""Honest verdicts on odd geometry: degenerate patches fail the check, and a surface 1e-25 or 1e25
in size is measured, drawn and shown as the same surface at size 1."""

from __future__ import annotations

import base64
import io
import json
import re
from pathlib import Path
from typing import Any

import matplotlib.image as mpimg
import numpy as np
import pytest

from g1patch import shapes
from g1patch.api import Surface, mesh_png
from g1patch.build import build_network
from g1patch.cli import main
from g1patch.continuity import ContinuityReport, check
from g1patch.io.bpt import read_bpt, write_bpt
from g1patch.io.network_file import MAX_COORDINATE, load_network, save_network
from g1patch.network import PatchNetwork, network_from_patch_points
from g1patch.patches import PatchSet
from g1patch.viewer import view_html

GRID = np.stack(np.meshgrid(np.arange(4.0), np.arange(4.0), indexing="ij"), axis=-1)
FLAT = np.concatenate([GRID, np.zeros((4, 4, 1))], axis=-1)  # a sound planar patch


def _bezier(*control: np.ndarray) -> PatchSet:
    return PatchSet(np.stack(control), "bezier")


DEGENERATE = {
    "a point": _bezier(np.full((4, 4, 3), 5.0)),
    "a segment (two collapsed edges)": _bezier(np.repeat(FLAT[:, :1] + [0, 0, 9], 4, axis=1)),
    "a line, no edge collapsed": _bezier(np.stack([GRID.sum(-1)] * 3, axis=-1)),
}


@pytest.mark.parametrize("compiled", [False, True], ids=["numpy", "kernels"])
@pytest.mark.parametrize("name", DEGENERATE)
def test_degenerate_patches_are_reported_and_fail(
    name: str, compiled: bool, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    patches = _bezier(FLAT, DEGENERATE[name].control[0])
    report = check(network_from_patch_points(patches), compiled=compiled)
    assert (report.degenerate_patches, report.degenerate_patch_ids) == (1, (1,))
    assert report.to_dict()["degenerate_patches"] == 1
    assert "degenerate patches" in report.summary()
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


def test_kernels_and_reference_find_the_same_degenerate_patches() -> None:
    """The grid pass flags a patch with no area itself (no second evaluation): the kernel and the
    NumPy reference agree, in a set of many patches among sound and triangular ones."""
    rng = np.random.default_rng(7)
    sound = FLAT + rng.normal(scale=0.05, size=(40, 4, 4, 3))
    triangle = sound[:10].copy()
    triangle[:, :, 0] = triangle[:, :1, 0]  # one collapsed edge: intended, as the teapot's poles
    point = np.broadcast_to(rng.normal(size=(5, 1, 1, 3)), (5, 4, 4, 3))
    line = np.stack([GRID.sum(-1)] * 3, axis=-1) * rng.uniform(1, 2, size=(5, 1, 1, 1))
    control = (
        np.concatenate([sound, triangle, point, line]) + 10.0 * np.arange(60)[:, None, None, None]
    )  # apart, so that no two patches share an edge
    order = rng.permutation(60)
    network = network_from_patch_points(PatchSet(control[order], "bezier"))
    reports = [check(network, compiled=compiled) for compiled in (False, True)]
    expected = tuple(int(i) for i in np.flatnonzero(order >= 50)[:10])
    for report in reports:
        assert report.degenerate_patches == 10 and report.degenerate_patch_ids == expected
    assert reports[0].degenerate_normals == reports[1].degenerate_normals


def test_the_teapot_keeps_its_verdict(
    shared_data: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Newell's teapot: its poles are collapsed edges of triangular patches, none degenerate; the
    check fails at 1e-9° on its kinks only, as before, and passes at 180°."""
    teapot = shared_data / "teapot.bpt"
    report = check(read_bpt(teapot))
    assert report.collapsed_edges and report.degenerate_normals
    assert report.degenerate_patches == 0 and report.passes(180.0)
    assert main(["check", "-q", str(teapot)]) == 0
    assert main(["check", "-q", str(teapot), "--max-angle", "180"]) == 0
    assert main(["check", "-q", str(teapot), "--max-angle", "1e-9"]) == 1
    failed = capsys.readouterr().err
    assert "G1 angle" in failed and "degenerate" not in failed


# ------------------------------------------------------------------- huge and tiny coordinates


def _same_verdict(measured: ContinuityReport, expected: ContinuityReport, scale: float) -> None:
    """The figures of a copy scaled by ``scale`` are those of the original: counts equal, angles
    within the check's rounding (exact G1 stays below 1e-9°), relative figures close."""
    for name in (
        "patches",
        "shared_edges",
        "open_edges",
        "collapsed_edges",
        "collapsed_patch_edges",
        "degenerate_normals",
        "degenerate_patches",
        "folds",
        "seam_edges",
    ):
        assert getattr(measured, name) == getattr(expected, name), name
    assert measured.passes() == expected.passes()
    assert measured.passes(180.0) == expected.passes(180.0)
    assert measured.is_g1() == expected.is_g1()
    for name in ("max_edge_angle_deg", "max_corner_angle_deg", "turn_max_deg"):
        assert getattr(measured, name) == pytest.approx(getattr(expected, name), abs=1e-9), name
    assert measured.thin_plate == pytest.approx(expected.thin_plate, rel=1e-9)
    assert measured.max_g0_gap <= 1e-12 and expected.max_g0_gap <= 1e-12
    ratio = measured.bounding_box_diagonal / expected.bounding_box_diagonal
    assert ratio == pytest.approx(scale, rel=1e-12)


def _picture(network: PatchNetwork, mode: str) -> np.ndarray:
    png = Surface(network).render(size=(160, 160), mode=mode)
    return np.asarray(mpimg.imread(io.BytesIO(png)))[..., :3]


def _close_pictures(measured: np.ndarray, expected: np.ndarray) -> None:
    """Not blank, and the same picture but for the colours of rounding noise (a deviation map
    colours exact-G1 edges by their angles, ~1e-13°, which round differently at each size)."""
    assert measured.std() > 0.1
    assert measured.mean() == pytest.approx(expected.mean(), abs=2e-3)
    assert measured.std() == pytest.approx(expected.std(), abs=2e-3)
    assert np.mean(np.abs(measured - expected) > 0.02) < 0.01


def _page_points(page: str) -> tuple[np.ndarray, dict[str, Any]]:
    """The page's sample positions (centred) over its radius, and its metadata."""
    match = re.search(r'id="g1-positions">([^<]*)<', page)
    meta = re.search(r'id="g1-meta">(.*?)</script>', page, re.S)
    assert match is not None and meta is not None
    data = json.loads(meta.group(1))
    positions = np.frombuffer(base64.b64decode(match.group(1)), dtype=np.float32).reshape(-1, 3)
    return positions / data["radius"], data


@pytest.mark.parametrize("scale", [1e-25, 1e25, 1e-150, 1e150])
def test_a_scaled_bpt_is_measured_drawn_and_shown_alike(
    scale: float, shared_data: Path, tmp_path: Path
) -> None:
    """Frame-free patches (a .bpt) far from size 1 are measured in their unit box: 1e-150 gave 32
    degenerate patches, 1e150 a NaN angle; their pictures and pages are the unscaled ones'."""
    teapot = read_bpt(shared_data / "teapot.bpt")
    unit = network_from_patch_points(teapot)
    scaled = network_from_patch_points(PatchSet(teapot.control * scale, "bezier"))
    for compiled in (False, True):
        _same_verdict(check(scaled, compiled=compiled), check(unit, compiled=compiled), scale)
    for mode in ("shaded", "zebra", "deviation"):
        _close_pictures(_picture(scaled, mode), _picture(unit, mode))
    (measured, meta), (expected, expected_meta) = (
        _page_points(view_html(network)) for network in (scaled, unit)
    )
    assert np.isfinite(measured).all() and measured.std() > 0.1
    assert np.abs(measured - expected).max() < 1e-5
    assert meta["verdict"] == expected_meta["verdict"]
    if abs(np.log10(scale)) <= 25:  # the .bpt format stores it, and the commands read it
        path = tmp_path / "scaled.bpt"
        write_bpt(path, scaled.patches)
        assert main(["check", "-q", str(path), "--max-angle", "180"]) == 0
        assert (
            main(["render", "-q", str(path), "-o", str(tmp_path / "s.png"), "--size", "99", "99"])
            == 0
        )
        assert main(["view", "-q", str(path), "-o", str(tmp_path / "s.html")]) == 0


@pytest.mark.parametrize("scale", [1e-25, 1e25, 1e29])
def test_a_scaled_network_file_round_trips_and_is_shown(scale: float, tmp_path: Path) -> None:
    """A built network 1e29 in size is stored with its frame below the file's coordinate limit,
    read back with the same verdict, and drawn and shown by the commands."""
    mesh = shapes.cube()
    network = build_network(mesh.with_vertices(mesh.vertices * scale))
    assert np.abs(network.patches.box()).max() < MAX_COORDINATE
    path = tmp_path / "scaled.npz"
    save_network(path, network)
    _same_verdict(check(load_network(path)), check(build_network(mesh)), scale)
    assert main(["check", "-q", str(path), "--max-angle", "1e-9"]) == 0
    assert (
        main(["render", "-q", str(path), "-o", str(tmp_path / "s.png"), "--size", "99", "99"]) == 0
    )
    assert main(["view", "-q", str(path), "-o", str(tmp_path / "s.html")]) == 0
    points, _ = _page_points((tmp_path / "s.html").read_text(encoding="utf-8"))
    assert np.isfinite(points).all() and points.std() > 0.1


@pytest.mark.parametrize("scale", [1e-25, 1e25])
def test_a_scaled_mesh_preview_is_not_blank(scale: float) -> None:
    """Triangle meshes (render_surfaces, the preview of a quad mesh) are drawn in their unit box
    too: at 1e-25 the picture was blank."""
    mesh = shapes.torus(8, 4)
    pictures = [
        np.asarray(mpimg.imread(io.BytesIO(mesh_png(m, (160, 160)))))[..., :3]
        for m in (mesh, mesh.with_vertices(mesh.vertices * scale))
    ]
    _close_pictures(pictures[1], pictures[0])


def test_the_viewer_names_degenerate_patches() -> None:
    """A network whose only fault is a degenerate patch: the page says so (its verdict was
    empty)."""
    network = network_from_patch_points(_bezier(FLAT, DEGENERATE["a point"].control[0]))
    _, meta = _page_points(view_html(network))
    assert meta["verdict"] == "1 degenerate patches" and not meta["exact"]
    assert ["degenerate patches", "1"] in meta["summary"]
