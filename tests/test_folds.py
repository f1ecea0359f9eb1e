"""Folds (the surface turning back on itself), the check verdict, and the fairness figures."""

from __future__ import annotations

import json
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from numpy.typing import ArrayLike, NDArray

from g1patch import shapes
from g1patch.construct.corner import build_corner_network
from g1patch.continuity import angle_between, check, fairness
from g1patch.continuity.grid import _GridMeasures
from g1patch.io.bpt import read_bpt, write_bpt
from g1patch.network import PatchNetwork, network_from_patch_points
from g1patch.patches import PatchSet

EPS = np.finfo(float).eps


def flat_sheet(fold: bool = False) -> PatchSet:
    """A 2 × 2 sheet of flat Bézier patches in z = 0; with ``fold`` the interior control points of
    patch 0 are pushed across each other along x, so p_u reverses inside it (the sheet laps over
    itself)."""
    s = np.arange(4) / 3.0
    control = []
    for x0, y0 in ((0, 0), (1, 0), (1, 1), (0, 1)):
        net = np.stack(
            np.broadcast_arrays(x0 + s[:, None], y0 + s[None, :], 0.0 * s[:, None]), axis=-1
        )
        control.append(net)
    patches = np.stack(control)
    if fold:
        patches[0, 1:3, 1:3, 0] = np.array([2.0, -1.0])[:, None]
    return PatchSet(patches, "bezier")


def test_a_sheet_lapping_over_itself_folds_and_fails_the_verdict() -> None:
    clean, folded = (
        check(network_from_patch_points(flat_sheet())),
        check(network_from_patch_points(flat_sheet(True))),
    )
    assert clean.folds == 0 and clean.fold_locations == () and clean.passes(1e-9)
    # the boundary curves are unchanged and the sheet stays in its plane: still exactly G1
    assert folded.is_g1(1e-9) and folded.max_edge_angle_deg == 0.0
    assert folded.folds == 1 and not folded.passes(1e-9)
    ((patch, u, v),) = folded.fold_locations
    assert patch == 0 and 0.0 < u < 1.0 and 0.0 < v < 1.0
    assert folded.turn_max_deg == 180.0
    assert folded.to_dict()["fold_locations"] == [{"patch": 0, "u": u, "v": v}]
    assert f"patch 0 at (u, v) = ({u:.4g}, {v:.4g})" in folded.summary()


def test_fan_normals_do_not_decide_folds() -> None:
    network = build_corner_network(shapes.cube())
    flipped = PatchNetwork(**{**network.__dict__, "vertex_normals": -network.vertex_normals})
    assert check(network).folds == check(flipped).folds == 0


@pytest.mark.parametrize(("angle", "folds"), [(60.0, 0), (89.0, 0), (120.0, 2), (170.0, 2)])
def test_a_crease_beyond_90_degrees_folds_both_patches(angle: float, folds: int) -> None:
    from test_continuity import hinge

    report = check(hinge(angle))
    assert report.folds == folds
    if folds:
        assert [location[0] for location in report.fold_locations] == [0, 1]
        assert report.fold_locations[0][1] == 1.0  # patch 0's side of the shared edge is u = 1


def test_teapot_curls_need_the_17_grid(shared_data: Path) -> None:
    network = network_from_patch_points(read_bpt(shared_data / "teapot.bpt"))
    fine, coarse = check(network), check(network, fold_samples=9)
    assert fine.fold_samples == 17 and fine.folds == 0
    assert 60.0 < fine.turn_max_deg < 90.0
    # on the 9 × 9 grid the spout tip turns by 115° between neighbours: the 90° rule fires there
    assert coarse.folds > 0 and coarse.turn_max_deg > 110.0
    assert {location[0] for location in coarse.fold_locations} <= set(range(16, 20))  # the spout


def quadratic_patch(a: float, b: float, c: float) -> PatchSet:
    """p(u, v) = (u, v, a u² + b uv + c v²) as a bicubic Bézier patch (u² has coefficients 0, 0, ⅓,
    1)."""
    s = np.arange(4) / 3.0
    square = np.array([0.0, 0.0, 1.0 / 3.0, 1.0])
    z = a * square[:, None] + b * s[:, None] * s[None, :] + c * square[None, :]
    return PatchSet(
        np.stack(np.broadcast_arrays(s[:, None], s[None, :], z), axis=-1)[None], "bezier"
    )


@pytest.mark.parametrize("samples", [2, 5, 17])
def test_thin_plate_energy_of_a_quadratic_is_exact(samples: int) -> None:
    a, b, c = 0.3, -0.7, 0.45
    patches = quadratic_patch(a, b, c)
    corners = patches.corners().reshape(-1, 3)
    diagonal = np.linalg.norm(corners.max(axis=0) - corners.min(axis=0))
    # p_uu = (0, 0, 2a), p_uv = (0, 0, b), p_vv = (0, 0, 2c): ∫∫ 4a² + 2b² + 4c²; differences of
    # p_u, p_v are exact
    figures = fairness(network_from_patch_points(patches), samples=samples)
    assert figures["thin_plate"] == pytest.approx(
        (4 * a * a + 2 * b * b + 4 * c * c) / diagonal**2, rel=1e-12
    )


def test_thin_plate_energy_is_scale_free() -> None:
    network = build_corner_network(shapes.torus(8, 5))
    scaled = build_corner_network(
        shapes.torus(8, 5).with_vertices(1e3 * shapes.torus(8, 5).vertices)
    )
    assert fairness(scaled)["thin_plate"] == pytest.approx(
        fairness(network)["thin_plate"], rel=1e-12
    )


def exact_turns(patches: Any, samples: int) -> NDArray[np.float64]:
    grid = np.linspace(0.0, 1.0, samples)
    normals = np.cross(
        patches.evaluate_grid(grid, grid, 1, 0), patches.evaluate_grid(grid, grid, 0, 1)
    )
    return np.concatenate(
        [
            angle_between(normals[:, 1:], normals[:, :-1]).ravel(),
            angle_between(normals[:, :, 1:], normals[:, :, :-1]).ravel(),
        ]
    )


@pytest.mark.parametrize("samples", [5, 17])
def test_turn_percentiles_match_the_exact_ones(samples: int) -> None:
    rng = np.random.default_rng(3)
    mesh = shapes.genus2()
    mesh = mesh.with_vertices(mesh.vertices + rng.normal(scale=0.02, size=mesh.vertices.shape))
    network = build_corner_network(mesh)
    turns = exact_turns(network.patches, samples)
    figures = fairness(network, samples=samples)
    # histogram bins are 0.27 % wide in |n̂_a − n̂_b|², so ≤ 0.14 % (+ rounding) in the angle
    assert figures["turn_median_deg"] == pytest.approx(np.percentile(turns, 50), rel=2e-3)
    assert figures["turn_p99_deg"] == pytest.approx(np.percentile(turns, 99), rel=2e-3)
    assert figures["turn_max_deg"] == pytest.approx(turns.max(), rel=1e-12)
    report = check(network, fold_samples=samples)
    assert {key: getattr(report, key) for key in figures} == figures


def test_flat_patches_do_not_turn() -> None:
    figures = fairness(network_from_patch_points(flat_sheet()))
    assert figures["turn_median_deg"] == figures["turn_p99_deg"] == figures["turn_max_deg"] == 0.0
    assert figures["thin_plate"] <= 1e-28  # p_u = (1, 0, 0) up to rounding


def test_gregory_grid_tangents_equal_their_evaluation() -> None:
    from g1patch.build import build_network

    patches = build_network(shapes.torus(6, 4), "gregory").patches
    measures = _GridMeasures(len(patches), 9, 0.0)
    p_u, p_v = measures._tangents(patches)
    for tangent, (du, dv) in ((p_u, (1, 0)), (p_v, (0, 1))):
        expected = np.moveaxis(patches.evaluate_grid(measures.grid, measures.grid, du, dv), -1, 0)
        np.testing.assert_allclose(
            tangent, expected, rtol=0, atol=64 * EPS * np.abs(expected).max()
        )


@dataclass(frozen=True)
class Similarity:
    centre: NDArray[np.float64]
    scale: float

    def to_local(self, x: ArrayLike) -> NDArray[np.float64]:
        return (np.asarray(x) - self.centre) / self.scale


@dataclass(frozen=True)
class Framed:
    """Patches stored in local coordinates, evaluated in world ones (the frame of a patch set)."""

    inner: PatchSet
    frame: Similarity

    def __len__(self) -> int:
        return len(self.inner)

    def take(self, indices: ArrayLike) -> Framed:
        return Framed(self.inner.take(indices), self.frame)

    def local(self) -> PatchSet:
        return self.inner

    def _world(self, values: NDArray[np.float64], du: int, dv: int) -> NDArray[np.float64]:
        return self.frame.scale * values + (0.0 if du or dv else self.frame.centre)

    def evaluate(self, uv: ArrayLike, du: int = 0, dv: int = 0) -> NDArray[np.float64]:
        return self._world(self.inner.evaluate(uv, du, dv), du, dv)

    def evaluate_grid(
        self, u: ArrayLike, v: ArrayLike | None = None, du: int = 0, dv: int = 0
    ) -> NDArray[np.float64]:
        return self._world(self.inner.evaluate_grid(u, v, du, dv), du, dv)


def test_a_framed_network_is_measured_in_its_local_coordinates() -> None:
    rng = np.random.default_rng(8)
    mesh = shapes.torus(9, 5)
    network = build_corner_network(
        mesh.with_vertices(mesh.vertices + rng.normal(scale=0.02, size=mesh.vertices.shape))
    )
    assert isinstance(network.patches, PatchSet) and network.vertices is not None
    frame = Similarity(np.array([1e6, -2e6, 3e5]), 1e4)
    framed = PatchNetwork(
        **{
            **network.__dict__,
            "patches": Framed(network.patches, frame),
            "vertices": frame.centre + frame.scale * network.vertices,
        }
    )
    local, world = check(network).to_dict(), check(framed).to_dict()
    assert world.pop("bounding_box_diagonal") == pytest.approx(
        frame.scale * local.pop("bounding_box_diagonal"), rel=1e-12
    )
    # the vertices' round trip through the frame (c + s x − c) / s rounds at 1e-16 · |c| / s
    assert world.pop("max_vertex_deviation") <= 1e-13 and local.pop("max_vertex_deviation") == 0.0
    assert world == local


def g1patch_cli(*args: str | Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "g1patch.cli", *map(str, args)],
        capture_output=True,
        text=True,
        timeout=300,
    )


@pytest.mark.slow
def test_check_exits_1_on_folds_and_says_so(tmp_path: Path) -> None:
    clean, folded = tmp_path / "clean.bpt", tmp_path / "folded.bpt"
    write_bpt(clean, flat_sheet())
    write_bpt(folded, flat_sheet(True))
    passed = g1patch_cli("check", clean, "--max-angle", "1e-9")
    assert passed.returncode == 0 and "passed" in passed.stdout
    failed = g1patch_cli("check", folded, "--max-angle", "90")
    assert failed.returncode == 1
    verdict = failed.stderr.strip().splitlines()
    assert len(verdict) == 1 and verdict[0].startswith(
        "FAILED: 1 folded patches (first: patch 0 at"
    )
    assert "G1 angle" not in verdict[0]
    data = json.loads(g1patch_cli("check", folded, "--json", "--max-angle", "90").stdout)
    assert data["folds"] == 1 and data["fold_locations"][0]["patch"] == 0
    assert {"turn_median_deg", "turn_p99_deg", "turn_max_deg", "thin_plate"} <= set(data)
    assert g1patch_cli("check", folded).returncode == 0  # no verdict asked
