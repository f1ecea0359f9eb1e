"""The continuity report: known angles and gaps, the teapot, folds, per-edge arrays."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from g1patch import shapes
from g1patch.construct.corner import build_corner_network
from g1patch.continuity import angle_between, check
from g1patch.continuity.sampling import translated
from g1patch.errors import InputError, NonManifoldError
from g1patch.io.bpt import read_bpt
from g1patch.network import PatchNetwork, network_from_patch_points
from g1patch.patches import PatchSet

EPS = np.finfo(float).eps
REPORT_KEYS = {
    "max_edge_angle_deg",
    "mean_edge_angle_deg",
    "max_corner_angle_deg",
    "max_g0_gap",
    "degenerate_normals",
    "folds",
    "patches",
    "shared_edges",
    "fold_samples",
    "fold_locations",
    "turn_median_deg",
    "turn_p99_deg",
    "turn_max_deg",
    "thin_plate",
}


def bilinear_bezier(corners: np.ndarray) -> np.ndarray:
    """Bézier control net (4, 4, 3) of the bilinear patch through corners c0..c3 (CCW)."""
    s = np.arange(4) / 3.0
    u, v = s[:, None, None], s[None, :, None]
    c0, c1, c2, c3 = corners
    return (1 - u) * (1 - v) * c0 + u * (1 - v) * c1 + u * v * c2 + (1 - u) * v * c3


def hinge(angle_deg: float, lift: float = 0.0) -> PatchNetwork:
    """Two flat patches sharing the edge x = 1, the second turned up by ``angle_deg`` and lifted."""
    a = np.radians(angle_deg)
    first = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], dtype=float)
    far = np.array([1 + np.cos(a), 0.0, np.sin(a)])
    second = np.array([[1, 0, 0], far, far + [0, 1, 0], [1, 1, 0]], dtype=float) + [0, 0, lift]
    patches = PatchSet(np.stack([bilinear_bezier(first), bilinear_bezier(second)]), "bezier")
    return network_from_patch_points(patches, rtol=1e-9 if lift == 0 else 1e-2)


@settings(max_examples=30, deadline=None)
@given(angle=st.floats(1e-6, 170.0))
def test_hinge_angle_is_measured_exactly(angle: float) -> None:
    report = check(hinge(angle))
    assert report.shared_edges == 1 and report.open_edges == 6
    # atan2 of exactly computed vectors: relative error a few ULPs of the angle.
    assert report.max_edge_angle_deg == pytest.approx(angle, rel=64 * EPS, abs=1e-13)
    assert report.mean_edge_angle_deg == pytest.approx(angle, rel=64 * EPS, abs=1e-13)
    assert report.max_corner_angle_deg == pytest.approx(angle, rel=64 * EPS, abs=1e-13)
    assert report.max_g0_gap == 0.0
    assert report.worst_edge is not None and report.worst_edge["patches"] == [0, 1]


def test_g0_gap_is_relative_to_the_bounding_box() -> None:
    lift = 1e-4
    network = hinge(30.0, lift=lift)
    report = check(network)
    assert report.max_g0_gap == pytest.approx(lift / network.bounding_box_diagonal(), rel=1e-9)


def test_angle_between_is_accurate_near_zero() -> None:
    tiny = 1e-12
    assert float(angle_between(np.array([1.0, 0, 0]), np.array([1.0, tiny, 0]))) == pytest.approx(
        np.degrees(tiny), rel=1e-12
    )


def test_teapot_report(shared_data: Path) -> None:
    report = check(network_from_patch_points(read_bpt(shared_data / "teapot.bpt")))
    # The data README: 32 patches, boundary curves 52 shared / 16 open / 8 collapsed.
    assert (
        report.patches,
        report.shared_edges,
        report.open_edges,
        report.collapsed_patch_edges,
    ) == (32, 52, 16, 8)
    assert report.collapsed_edges == 2  # the lid's and the bottom's poles
    assert report.max_g0_gap <= 1e-15  # shared curves have identical control points
    assert (
        report.max_edge_angle_deg <= 1e-9
    )  # Newell's patches are tangent-continuous across shared curves
    assert report.degenerate_normals > 0  # at the poles p_u × p_v = 0
    assert report.folds == 0 and report.inconsistent_orientation_edges == 0
    # The handle's ends meet the body's patches at one point at an angle: a real corner crease.
    assert report.max_corner_angle_deg > 90.0


def test_per_edge_arrays_locate_the_worst_edge() -> None:
    rng = np.random.default_rng(5)
    mesh = shapes.torus(10, 6)
    mesh = mesh.with_vertices(mesh.vertices + rng.normal(scale=0.01, size=mesh.vertices.shape))
    report = check(build_corner_network(mesh))
    assert report.edge_angle_deg.shape == (report.shared_edges,) == (mesh.topology.n_edges,)
    assert report.edge_angle_deg.max() == report.max_edge_angle_deg
    worst = report.worst_edge
    assert worst is not None
    index = int(np.argmax(report.edge_angle_deg))
    assert list(report.edge_patches[index]) == worst["patches"]


def test_report_serialises_to_json() -> None:
    data = json.loads(json.dumps(check(build_corner_network(shapes.cube())).to_dict()))
    assert REPORT_KEYS <= set(data)
    assert data["patches"] == 6 and data["shared_edges"] == 12


def test_summary_names_the_figures() -> None:
    text = check(build_corner_network(shapes.cube())).summary()
    for label in (
        "max G1 angle on edges",
        "max G1 angle at corners",
        "max G0 gap",
        "folds",
        "worst edge",
        "normal turn median / p99 / max",
        "thin-plate energy",
    ):
        assert label in text


@pytest.mark.parametrize("argument", [{"samples": 1}, {"samples": 2.5}, {"fold_samples": 0}])
def test_bad_sample_counts(argument: dict[str, float]) -> None:
    ((name, _),) = argument.items()
    with pytest.raises(InputError, match=name):
        check(build_corner_network(shapes.cube()), **argument)  # type: ignore[arg-type]


def test_a_curve_shared_by_more_than_two_patches_is_non_manifold() -> None:
    first = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], dtype=float)
    fins = [
        np.array([[1, 0, 0], [1 + c, 0, s], [1 + c, 1, s], [1, 1, 0]])
        for c, s in ((1, 0), (0, 1), (-0.5, 0.5))
    ]
    patches = PatchSet(
        np.stack([bilinear_bezier(first)] + [bilinear_bezier(f) for f in fins]), "bezier"
    )
    with pytest.raises(NonManifoldError, match="shared by 4 patches"):
        network_from_patch_points(patches)


def test_blocks_do_not_change_the_report() -> None:
    rng = np.random.default_rng(9)
    mesh = shapes.genus2()
    mesh = mesh.with_vertices(mesh.vertices + rng.normal(scale=0.01, size=mesh.vertices.shape))
    network = build_corner_network(mesh)
    whole, blocked = check(network), check(network, chunk=7)
    assert whole.to_dict() == blocked.to_dict()
    np.testing.assert_array_equal(whole.edge_angle_deg, blocked.edge_angle_deg)


def test_planar_vector_algebra_equals_the_interleaved_numpy_formulas() -> None:
    # The measures run on planar (3, ...) arrays; they must give the numbers of np.cross,
    # np.linalg.norm and np.einsum on interleaved (..., 3) arrays (today bit for bit; allowed:
    # a different summation order, 4 eps of |a||b| for 3-term sums).
    from g1patch.continuity.vectors import _angle3, _cross3, _dot3, _norm3, _planar

    rng = np.random.default_rng(4)
    a = rng.normal(size=(50, 33, 3)) * 10.0 ** rng.integers(-8, 9, size=(50, 33, 3))
    b = rng.normal(size=(50, 33, 3)) * 10.0 ** rng.integers(-8, 9, size=(50, 33, 3))
    pa, pb = _planar(a), _planar(b)
    scale = np.linalg.norm(a, axis=-1) * np.linalg.norm(b, axis=-1)
    tolerance = 4 * EPS * scale
    assert (
        np.abs(np.moveaxis(_cross3(pa, pb), 0, -1) - np.cross(a, b)).max(axis=-1) <= tolerance
    ).all()
    np.testing.assert_allclose(_norm3(pa), np.linalg.norm(a, axis=-1), rtol=4 * EPS, atol=0)
    assert (np.abs(_dot3(pa, pb) - np.einsum("...d,...d->...", a, b)) <= tolerance).all()
    reference = np.degrees(
        np.arctan2(np.linalg.norm(np.cross(a, b), axis=-1), np.einsum("...d,...d->...", a, b))
    )
    # an angle moves by at most (error of cross or dot) / (|a||b|) radians
    np.testing.assert_allclose(_angle3(pa, pb), reference, rtol=0, atol=np.degrees(16 * EPS))
    np.testing.assert_allclose(angle_between(a, b), reference, rtol=0, atol=np.degrees(16 * EPS))


def test_angle_between_broadcasts_and_keeps_the_batch_shape() -> None:
    rng = np.random.default_rng(5)
    a, b = rng.normal(size=(4, 7, 3)), rng.normal(size=(7, 3))
    angles = angle_between(a, b)
    assert angles.shape == (4, 7)
    np.testing.assert_array_equal(angles[2], angle_between(a[2], b))
    assert angle_between(np.array([1.0, 0, 0]), np.array([0, 2.0, 0])).shape == ()
    assert float(angle_between(np.array([1.0, 0, 0]), np.array([0, 2.0, 0]))) == 90.0


def test_corner_points_and_world_diagonal_as_the_evaluation() -> None:
    """The check reads a Gregory patch's corners from its points 0–3 and maps them to world for the
    reported diagonal: bit for bit the evaluation at the corners and the network's own diagonal."""
    from g1patch.build import build_gregory_network
    from g1patch.continuity.sampling import _corner_points, _world_diagonal
    from g1patch.patches import CORNER_PARAMETERS

    network = build_gregory_network(shapes.noisy_sphere(2, 0.3))
    local = network.patches.local()
    assert network.patches.frame is not None  # the world map is exercised
    np.testing.assert_array_equal(_corner_points(local), local.evaluate(CORNER_PARAMETERS))
    assert _world_diagonal(network, _corner_points(local)) == network.bounding_box_diagonal()


@pytest.mark.parametrize("compiled", [False, True])
def test_a_tiny_skewed_pair_is_measured_in_its_own_precision(compiled: bool) -> None:
    """Two split4 sub-patches of a sliver face (1/7000 of the model's diagonal, their tangents
    2° apart) from a fitted layout of trimesh's octagonal_pocket.stl, saved in the network's
    unit frame: exactly G1 (a long-double evaluation, recentred, gives 0), and measured so once
    both sides' points are taken relative to one of them; derivatives summed from coordinates of
    the model's size lost six digits (the check said 1.1e-8°, its kernels 4.1e-9°)."""
    control = np.load(Path(__file__).parent / "data" / "patches" / "split4_sliver_pair.npy")
    report = check(PatchSet(control), compiled=compiled)
    assert report.shared_edges == 1
    assert report.max_edge_angle_deg <= 1e-10


@pytest.mark.parametrize("form", ["bezier", "bspline", "hermite"])
def test_the_check_moves_a_patch_not_its_shape(form: str) -> None:
    """What the check samples relative to a point (:func:`~g1patch.continuity.sampling.
    translated`) is the same surface moved: points less the offset, derivatives unchanged, in
    every form (a Hermite patch's derivative and twist entries stay where they are)."""
    rng = np.random.default_rng(7)
    patches = PatchSet(rng.normal(size=(3, 4, 4, 3)), "bezier").convert(form)
    offset = rng.normal(size=(3, 3))
    moved = translated(patches, offset)
    uv = rng.uniform(size=(5, 2))
    scale = np.abs(patches.control).max()
    np.testing.assert_allclose(
        moved.evaluate(uv), patches.evaluate(uv) - offset[:, None], atol=64 * EPS * scale
    )
    for du, dv in ((1, 0), (0, 1)):
        np.testing.assert_allclose(
            moved.evaluate(uv, du, dv), patches.evaluate(uv, du, dv), atol=64 * EPS * scale
        )
