"""The compiled check (numba kernels) against its NumPy reference (``compiled=False``).

Counts, folds, their locations and the turn histogram must be equal; the turn maximum to
:data:`TURN_RTOL`, or to ``continuity.TENSOR_TURN_ATOL`` where more than
``continuity.EXACT_TURN_CANDIDATES`` patches tie for it (the kernels recompute its pair as the
reference sums it, but the reference's products go through BLAS, whose tail kernels round a row
differently: one ULP on the coarse torus's largest turn once its tangents ran straight along the
mesh lines). Angles and gaps may differ by the rounding of the tangents: the kernels sum the edge
and corner samples as OpenBLAS's dgemm micro-kernel does (a sequential fused multiply-add), which
equals the reference except on the rows OpenBLAS gives its tail kernels; there a tangent differs by
a few ULP of ``Σ |w_m| |P_m|``, and so does a normal, so an angle (atan2 of vectors of that
accuracy) differs by at most :data:`ANGLE_ATOL`, plus the noise of the angle itself where it is
the rounding of an exactly G1 edge (:data:`G1_NOISE_DEG`), and a gap by :data:`GAP_ATOL` of the
diagonal. The reference is no steadier: its own gaps move as much with its ``chunk`` (which rows
fall in BLAS's tail kernels)."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

from g1patch import continuity, kernels, shapes
from g1patch.api import as_network, read
from g1patch.build import build_gregory_network, build_split4_network
from g1patch.continuity import ContinuityReport, check, fairness, folded_patches
from g1patch.gregory import BEZIER_INDEX, INTERIOR_INDEX, GregoryPatchSet
from g1patch.network import PatchNetwork
from g1patch.patches import PatchSet

EPS = float(np.finfo(float).eps)
#: angles (degrees): 1024 ε radians, 2× the largest difference measured on well-conditioned
#: edges: a normal's direction is off by a few ULP of Σ |w_m| |P_m| / |p_u|, and the NumPy
#: reference's matrix products go through BLAS, whose summation order depends on its build (32 ε
#: with the OpenBLAS of earlier NumPy wheels, 454 ε on the shared Gregory networks with NumPy 2.4's)
ANGLE_ATOL = 1024 * EPS * 180 / np.pi
#: below this (degrees) an angle is rounding noise of an exactly G1 edge: its size is set by the
#: conditioning (a split4 sub-patch's tangents are a quarter of its corner's, the teapot's
#: networks reach 2e-10°), and the two evaluators' noises differ by up to the noise itself
#: (measured 0.45× the reference's largest angle on the teapot's split4 network, 0.69× on one
#: edge): both may differ by :data:`ANGLE_ATOL` plus the reference's largest angle up to this
G1_NOISE_DEG = 1e-9
#: gaps relative to the diagonal: 4 ε (measured ≤ 0.3 ε)
GAP_ATOL = 4 * EPS
#: thin-plate energy, relative: its sums run in another order over tangents of a few ULP
#: difference, whose neighbours' differences lose up to log2(G) bits (measured ≤ 1.4 ε)
ENERGY_RTOL = 64 * EPS


def energy_atol(report: ContinuityReport) -> float:
    """Absolute slack of the thin-plate energy of flat patches (energy at the rounding level): per
    patch 4 G² squared differences of tangents (~ diag) each off by up to 16 ε."""
    return report.patches * 4 * report.fold_samples**2 * (16 * EPS) ** 2


EXACT = (
    "patches",
    "shared_edges",
    "open_edges",
    "collapsed_edges",
    "collapsed_patch_edges",
    "samples_per_edge",
    "degenerate_normals",
    "folds",
    "inconsistent_orientation_edges",
    "bounding_box_diagonal",
    "max_vertex_deviation",
    "fold_samples",
    "fold_locations",
    "turn_median_deg",
    "turn_p99_deg",
    "seam_edges",
)
#: the turn maximum, relative: the angle of one pair of normals, each a few ULP off where BLAS
#: sums its row in a tail kernel (measured 1 ULP)
TURN_RTOL = 8 * EPS
ANGLES = (
    "max_edge_angle_deg",
    "mean_edge_angle_deg",
    "max_corner_angle_deg",
    "seam_angle_min_deg",
    "seam_angle_max_deg",
)


def assert_same_report(compiled: ContinuityReport, reference: ContinuityReport) -> None:
    """The kernels' report equals the reference's: exactly, or within the bounds above."""
    for name in EXACT:
        assert getattr(compiled, name) == getattr(reference, name), name
    assert compiled.turn_max_deg == pytest.approx(reference.turn_max_deg, rel=TURN_RTOL, abs=0.0)
    for name in ("edge_patches", "edge_sides", "edge_seam"):
        np.testing.assert_array_equal(
            getattr(compiled, name), getattr(reference, name), err_msg=name
        )
    noise = min(reference.max_edge_angle_deg or 0.0, G1_NOISE_DEG)
    for name in ANGLES:
        value, expected = getattr(compiled, name), getattr(reference, name)
        assert (value is None) == (expected is None), name
        if value is not None:
            assert abs(value - expected) <= ANGLE_ATOL + noise, (name, value, expected)
    np.testing.assert_allclose(
        compiled.edge_angle_deg, reference.edge_angle_deg, rtol=0, atol=ANGLE_ATOL + noise
    )
    np.testing.assert_allclose(compiled.edge_gap, reference.edge_gap, rtol=0, atol=GAP_ATOL)
    assert abs(compiled.max_g0_gap - reference.max_g0_gap) <= GAP_ATOL
    assert abs(compiled.seam_g0_max - reference.seam_g0_max) <= GAP_ATOL
    assert compiled.thin_plate == pytest.approx(
        reference.thin_plate, rel=ENERGY_RTOL, abs=energy_atol(reference)
    )


MESHES: dict[str, Callable[[], object]] = {
    "torus": lambda: shapes.torus(12, 8),
    "cube_sphere": lambda: shapes.cube_sphere(2),
    "fan": lambda: shapes.fan(7, 2),
    "flat_fan": lambda: shapes.flat_fan(9),
    "noisy_sphere": lambda: shapes.noisy_sphere(2, 0.3),
    "filleted_box": lambda: shapes.filleted_box(4),
    "box_cage": lambda: shapes.box_cage(),
}


@pytest.mark.parametrize("build", [build_gregory_network, build_split4_network])
@pytest.mark.parametrize("name", sorted(MESHES))
def test_generated_meshes_report_as_the_reference(
    name: str, build: Callable[..., PatchNetwork]
) -> None:
    network = build(MESHES[name]())
    assert_same_report(check(network, compiled=True), check(network, compiled=False))


@pytest.mark.slow
def test_shared_meshes_report_as_the_reference(shared_data: Path) -> None:
    paths = sorted(shared_data.glob("*.obj")) + [shared_data / "teapot.bpt"]
    for path in paths:
        source = read(path)
        networks = (
            [source]
            if isinstance(source, PatchNetwork)
            else [build_gregory_network(source), build_split4_network(source)]
        )
        for network in networks:
            assert_same_report(check(network, compiled=True), check(network, compiled=False))


@pytest.mark.parametrize("name", ["torus", "noisy_sphere", "filleted_box"])
def test_turn_maximum_of_many_tied_candidates_from_the_tensor_sums(
    name: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Above ``EXACT_TURN_CANDIDATES`` candidates (here: any) the turn maximum is the tensor
    evaluation's, within ``TENSOR_TURN_ATOL`` of the reference's; everything else as before."""
    network = build_gregory_network(MESHES[name]())
    reference = check(network, compiled=False)
    monkeypatch.setattr(continuity.grid, "EXACT_TURN_CANDIDATES", 0)
    compiled = check(network, compiled=True)
    assert abs(compiled.turn_max_deg - reference.turn_max_deg) <= continuity.TENSOR_TURN_ATOL
    assert_same_report(
        dataclasses.replace(compiled, turn_max_deg=reference.turn_max_deg), reference
    )


def perturbed(
    network: PatchNetwork, scale: float, seed: int, moved: slice = slice(12, 20)
) -> PatchNetwork:
    """``network`` with its Gregory points ``moved`` (default: the interior ones, so shared
    boundaries are kept) moved at random by ``scale`` × the diagonal: patches folded, edges and
    corners (edge points moved) far from G1."""
    patches = network.patches
    assert isinstance(patches, GregoryPatchSet)
    points = patches.points.copy()
    rng = np.random.default_rng(seed)
    points[:, moved] += (
        scale * network.bounding_box_diagonal() * rng.standard_normal(points[:, moved].shape)
    )
    return dataclasses.replace(network, patches=GregoryPatchSet(points, patches.frame))


def test_flipped_patches_report_as_the_reference() -> None:
    # every third patch transposed (u <-> v): its edges run the same way as their neighbours', so
    # the edge kernel takes them in classes of their own (flipped normals) beside the others, in
    # lane groups that are not full
    patches = build_split4_network(shapes.torus(12, 8)).patches
    assert isinstance(patches, PatchSet)
    control = patches.control.copy()
    control[::3] = control[::3].transpose(0, 2, 1, 3)
    flipped = PatchSet(control, patches.form, patches.frame)
    compiled, reference = check(flipped, compiled=True), check(flipped, compiled=False)
    assert 0 < reference.inconsistent_orientation_edges < reference.shared_edges
    assert_same_report(compiled, reference)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_folds_and_their_locations_as_the_reference(seed: int) -> None:
    network = perturbed(build_gregory_network(shapes.torus(10, 6)), 0.2, seed)
    compiled, reference = check(network, compiled=True), check(network, compiled=False)
    assert reference.folds > 10  # the test can fail: many folds, located
    assert_same_report(compiled, reference)


@pytest.mark.parametrize("samples", [2, 3, 9, 17])
def test_folded_patches_as_the_reference(samples: int) -> None:
    # flat unit squares with their control points moved at random: some fold, some do not
    rng = np.random.default_rng(samples)
    grid = np.stack(
        np.meshgrid(np.arange(4) / 3, np.arange(4) / 3, [0.0], indexing="ij"), axis=-1
    ).reshape(4, 4, 3)
    index = np.r_[BEZIER_INDEX, np.repeat(INTERIOR_INDEX, 2, axis=0)]
    gregory = GregoryPatchSet(
        grid[index[:, 0], index[:, 1]] + 0.3 * rng.standard_normal((300, 20, 3))
    )
    bezier = PatchSet(grid + 0.3 * rng.standard_normal((300, 4, 4, 3)), "bezier")
    bspline = PatchSet(grid + 0.3 * rng.standard_normal((300, 4, 4, 3)), "bspline")
    for patches in (gregory, bezier, bspline):
        folded = folded_patches(patches, samples, compiled=True)
        np.testing.assert_array_equal(folded, folded_patches(patches, samples, compiled=False))
        assert 0 < folded.sum() < len(folded)


def test_degenerate_normals_counted_as_the_reference() -> None:
    # a collapsed edge: corners 0 and 1 of every patch are one point
    network = build_gregory_network(shapes.cube_sphere(1))
    points = network.patches.points.copy()
    points[:, [1, 6, 7]] = points[:, [0]]
    patches = GregoryPatchSet(points)
    compiled = fairness(as_network(patches), compiled=True)
    reference = fairness(as_network(patches), compiled=False)
    assert compiled["turn_max_deg"] == reference["turn_max_deg"]
    assert compiled["thin_plate"] == pytest.approx(reference["thin_plate"], rel=ENERGY_RTOL)
    assert (
        check(patches, compiled=True).degenerate_normals
        == check(patches, compiled=False).degenerate_normals
        > 0
    )


@pytest.mark.parametrize("valence", [65, 200])
def test_large_sectors_as_the_reference(valence: int) -> None:
    # more corners than the kernels compare pairwise: the gnomonic hull's vertices only
    network = build_gregory_network(shapes.fan(valence))
    assert_same_report(check(network, compiled=True), check(network, compiled=False))
    bent = perturbed(network, 0.01, 3, slice(4, 12))
    compiled, reference = check(bent), check(bent, compiled=False)
    assert reference.max_corner_angle_deg > 1.0
    assert abs(compiled.max_corner_angle_deg - reference.max_corner_angle_deg) <= ANGLE_ATOL


def test_kernels_by_default_only_from_kernel_patches_on(monkeypatch: pytest.MonkeyPatch) -> None:
    """Below KERNEL_PATCHES the default check runs the NumPy reference (no minute-long compile on a
    first small check); at or above it, and with compiled=True, the kernels."""
    from g1patch import continuity

    def no_kernels(patches: object) -> None:
        raise AssertionError("the kernels were asked for")

    network = build_gregory_network(shapes.cube_sphere(1))
    monkeypatch.setattr(continuity.jit, "_evaluation_form", no_kernels)
    check(network), fairness(network), folded_patches(network.patches)  # the reference, untouched
    with pytest.raises(AssertionError, match="kernels were asked"):
        check(network, compiled=True)
    monkeypatch.setattr(continuity.jit, "KERNEL_PATCHES", len(network.patches))
    monkeypatch.setattr(kernels, "kernels_cached", lambda: True)  # NumPy where it is not
    with pytest.raises(AssertionError, match="kernels were asked"):
        folded_patches(network.patches)
