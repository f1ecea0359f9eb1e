"""Frames (g1patch.frame): framed patch sets evaluate, convert, store and export as the world
surface.

A framed set holds local control ``P`` and the frame ``(c, s)``; the same patches given directly in
world coordinates hold ``P_w = fl(c + s P)`` (Hermite derivative entries ``fl(s P)``). Two exact
invariants: a framed evaluation is bit for bit the local one mapped (``fl(c + fl(s x))`` for
positions, ``fl(s x)`` for derivatives, normals unchanged). Against the world set the two differ
by rounding only, bounded by

    |framed − world| ≤ ULPS · eps · W · (|c|∞ + s |P|∞),      W = Σ_ij |w_ij(u, v)|

where w are the weights of the evaluated derivative: the world evaluation's own contraction
error (≈ 16 eps · W · |P_w|, see test_patches.EVAL_REL) plus the rounding of ``P_w`` (eps · |P_w|
per point) plus that of the mapping (≈ 2 eps). ULPS = 32 leaves margin over that ≈ 20.
"""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from numpy.typing import NDArray

from g1patch import shapes
from g1patch.basis import basis_values
from g1patch.construct.corner import build_corner_network
from g1patch.errors import FormatError, InputError
from g1patch.frame import Frame
from g1patch.geometry import network_volume
from g1patch.gregory import GregoryPatchSet, gregory_weights
from g1patch.io.bpt import read_bpt, write_bpt
from g1patch.io.cad import fit_bspline_surfaces
from g1patch.io.network_file import FORMAT_VERSION, load_network, save_network
from g1patch.network import PatchNetwork
from g1patch.patches import CORNER_PARAMETERS, PatchSet
from g1patch.tessellate import tessellate

EPS = np.finfo(np.float64).eps
ULPS = 32
FORMS = ("hermite", "bezier", "bspline")
#: a frame far from the origin, the case the frames are for
FAR = Frame(np.array([1.0e6, -2.5e6, 3.0e5]), 7.25)
UV = np.array([[0.0, 0.0], [1.0, 0.0], [0.3, 0.7], [0.5, 0.5], [0.9, 0.15], [0.0, 0.4], [1.0, 1.0]])
GRID_U, GRID_V = np.linspace(0.0, 1.0, 6), np.array([0.0, 0.2, 0.55, 1.0])
ORDERS = [(0, 0), (1, 0), (0, 1), (1, 1), (2, 0), (0, 2), (3, 3)]


def local_control(n: int, seed: int) -> NDArray[np.float64]:
    return np.random.default_rng(seed).uniform(-0.5, 0.5, size=(n, 4, 4, 3))


def world_set(patches: PatchSet) -> PatchSet:
    """The same patches given directly in world coordinates."""
    return PatchSet(patches.world_control(), patches.form)


def weight_sum(
    form: str, u: NDArray[np.float64], v: NDArray[np.float64], du: int, dv: int
) -> NDArray[np.float64]:
    """W = Σ_ij |b_i^(du)(u) b_j^(dv)(v)| at the pairs (u, v)."""
    return np.abs(basis_values(form, u, du)).sum(axis=-1) * np.abs(basis_values(form, v, dv)).sum(
        axis=-1
    )


def magnitude(patches: PatchSet | GregoryPatchSet) -> float:
    """|c|∞ + s |P|∞ of a framed set."""
    assert patches.frame is not None
    local = patches.control if isinstance(patches, PatchSet) else patches.points
    return float(np.abs(patches.frame.centre).max() + patches.frame.scale * np.abs(local).max())


def assert_close_ulps(
    got: NDArray[np.float64], want: NDArray[np.float64], weights: NDArray[np.float64], size: float
) -> None:
    """|got − want| ≤ ULPS · eps · W · size, W broadcast over the value axis."""
    bound = ULPS * EPS * weights[..., None] * size
    excess = np.abs(got - want) - bound
    assert excess.max() <= 0.0, (
        f"off by {np.abs(got - want).max():.3e} where the bound is {bound.max():.3e}"
    )


def assert_normals_close(
    framed: NDArray[np.float64],
    p_u: NDArray[np.float64],
    p_v: NDArray[np.float64],
    error: NDArray[np.float64],
) -> None:
    """World normals from tangents known to ``error`` each: |δn| ≤ 2 (|δa| |b| + |a| |δb|) / |a × b|
    + 4 eps."""
    direct = np.cross(p_u, p_v)
    length = np.linalg.norm(direct, axis=-1)
    bound = (
        2.0 * error * (np.linalg.norm(p_u, axis=-1) + np.linalg.norm(p_v, axis=-1)) / length
        + 4 * EPS
    )
    assert (np.linalg.norm(framed - direct / length[..., None], axis=-1) <= bound).all()


# ------------------------------------------------------------------------------------------ Frame


def test_of_points_is_the_bounding_box_centre_and_diagonal() -> None:
    points = np.array([[1.0, 2.0, 3.0], [3.0, -2.0, 4.0], [2.0, 0.0, 5.0]])
    frame = Frame.of_points(points)
    np.testing.assert_array_equal(frame.centre, [2.0, 0.0, 4.0])
    assert frame.scale == np.linalg.norm([2.0, 4.0, 2.0])
    local = frame.to_local(points)
    assert np.abs(local).max() <= 0.5
    np.testing.assert_allclose(frame.to_world(local), points, rtol=0, atol=4 * EPS * 5)
    assert Frame.of_points([[1.0, 1.0, 1.0]] * 3) == Frame(np.ones(3), 1.0)
    assert Frame.of_points(np.zeros((0, 3))) == Frame.identity()
    assert Frame.of_points(points.reshape(1, 3, 3)) == frame


def test_maps_and_their_formulas() -> None:
    frame = Frame(np.array([1.0, -2.0, 0.5]), 4.0)
    x = np.array([[0.25, 0.5, -1.0]])
    np.testing.assert_array_equal(frame.to_world(x), [[2.0, 0.0, -3.5]])
    np.testing.assert_array_equal(frame.to_local(frame.to_world(x)), x)
    np.testing.assert_array_equal(frame.vectors_to_world(x), 4.0 * x)
    np.testing.assert_array_equal(frame.vectors_to_local(frame.vectors_to_world(x)), x)
    np.testing.assert_array_equal(frame.derivative_to_world(x, 0), frame.to_world(x))
    np.testing.assert_array_equal(frame.derivative_to_world(x, 2), frame.vectors_to_world(x))
    identity = Frame.identity()
    np.testing.assert_array_equal(identity.to_world(x), x)
    np.testing.assert_array_equal(identity.to_local(x), x)


def test_to_world_in_place_matches_a_fresh_result_across_chunks() -> None:
    values = np.random.default_rng(3).normal(
        size=(5, 71, 67, 3)
    )  # more rows than one in-place chunk
    fresh = FAR.to_world(values)
    np.testing.assert_array_equal(fresh, FAR.centre + FAR.scale * values)
    assert FAR.to_world(values, out=values) is values
    np.testing.assert_array_equal(values, fresh)
    strided = np.random.default_rng(4).normal(size=(40, 6))[:, ::2]
    np.testing.assert_array_equal(FAR.to_world(strided), FAR.centre + FAR.scale * strided)
    with pytest.raises(InputError, match=r"out: expected a float64 array of shape \(2, 3\)"):
        FAR.to_world(np.zeros((2, 3)), out=np.zeros((3, 3)))


def test_equality_hash_and_immutability() -> None:
    a, b = Frame([1, 2, 3], 2), Frame(np.array([1.0, 2.0, 3.0]), 2.0)
    assert a == b and hash(a) == hash(b) and a != Frame([1, 2, 3], 3.0) and a != "frame"
    with pytest.raises(ValueError):
        a.centre[0] = 5.0
    source = np.zeros(3)
    frame = Frame(source, 1.0)
    source[0] = 9.0  # the frame keeps its own copy
    assert frame.centre[0] == 0.0


@pytest.mark.parametrize(
    "centre,scale,match",
    [
        ([0.0, np.nan, 0.0], 1.0, r"frame centre: non-finite value nan at index \(1,\)"),
        ([0.0, 0.0], 1.0, r"frame centre: expected shape \(\.\.\., 3\), got \(2,\)"),
        ([[0.0, 0.0, 0.0]], 1.0, r"frame centre: expected shape \(3,\), got \(1, 3\)"),
        ("abc", 1.0, "frame centre: expected an array of numbers"),
        ([0.0, 0.0, 0.0], 0.0, "frame scale: expected a positive finite number, got 0.0"),
        ([0.0, 0.0, 0.0], -2.0, "frame scale: expected a positive finite number, got -2.0"),
        ([0.0, 0.0, 0.0], np.inf, "frame scale: expected a positive finite number, got inf"),
        ([0.0, 0.0, 0.0], True, "frame scale: expected a positive finite number, got True"),
        ([0.0, 0.0, 0.0], "2", "frame scale: expected a positive finite number, got '2'"),
    ],
)
def test_invalid_frames_are_refused_by_name(centre: object, scale: object, match: str) -> None:
    with pytest.raises(InputError, match=match):
        Frame(centre, scale)  # type: ignore[arg-type]


def test_frame_arrays_round_trip_and_errors() -> None:
    assert Frame.from_arrays(FAR.to_arrays()) == FAR
    assert Frame.from_arrays({"points": np.zeros(3)}) is None
    with pytest.raises(
        InputError, match="needs both 'frame_centre' and 'frame_scale', got only 'frame_scale'"
    ):
        Frame.from_arrays({"frame_scale": np.array(1.0)})
    with pytest.raises(
        InputError, match=r"frame scale: expected one number, got an array of float64 \(2,\)"
    ):
        Frame.from_arrays({"frame_centre": np.zeros(3), "frame_scale": np.ones(2)})
    with pytest.raises(
        InputError, match="frame: expected a g1patch.frame.Frame or None, got tuple"
    ):
        PatchSet(local_control(1, 0), frame=(np.zeros(3), 1.0))  # type: ignore[arg-type]
    with pytest.raises(
        InputError, match="frame: expected a g1patch.frame.Frame or None, got float"
    ):
        GregoryPatchSet(np.zeros((1, 20, 3)), frame=1.0)  # type: ignore[arg-type]


# ------------------------------------------------------------------------------------- PatchSet


@pytest.mark.parametrize("form", FORMS)
def test_framed_evaluation_is_the_local_one_mapped_bit_for_bit(form: str) -> None:
    local = PatchSet(local_control(4, 1), form)  # type: ignore[arg-type]
    framed = local.with_frame(FAR)
    assert framed.local().frame is None and framed.local().control is framed.control
    for du, dv in ORDERS:
        want = local.evaluate(UV, du, dv)
        want = FAR.vectors_to_world(want) if du or dv else FAR.to_world(want)
        np.testing.assert_array_equal(framed.evaluate(UV, du, dv), want)
        grid = local.evaluate_grid(GRID_U, GRID_V, du, dv)
        grid = FAR.vectors_to_world(grid) if du or dv else FAR.to_world(grid)
        np.testing.assert_array_equal(framed.evaluate_grid(GRID_U, GRID_V, du, dv), grid)
    np.testing.assert_array_equal(framed.normals(UV), local.normals(UV))
    np.testing.assert_array_equal(
        framed.normals_grid(GRID_U, GRID_V), local.normals_grid(GRID_U, GRID_V)
    )
    positions, normals = framed.evaluate_grid_with_normals(GRID_U, GRID_V)
    np.testing.assert_array_equal(positions, FAR.to_world(local.evaluate_grid(GRID_U, GRID_V)))
    np.testing.assert_array_equal(normals, local.normals_grid(GRID_U, GRID_V))


@pytest.mark.parametrize("form", FORMS)
def test_framed_patches_equal_the_same_patches_in_world_coordinates(form: str) -> None:
    framed = PatchSet(local_control(5, 2), form, FAR)  # type: ignore[arg-type]
    world = world_set(framed)
    size = magnitude(framed)
    for du, dv in ORDERS:
        weights = weight_sum(form, UV[:, 0], UV[:, 1], du, dv)
        assert_close_ulps(framed.evaluate(UV, du, dv), world.evaluate(UV, du, dv), weights, size)
        per_patch = np.random.default_rng(du + 3 * dv).uniform(size=(len(framed), 9, 2))
        assert_close_ulps(
            framed.evaluate(per_patch, du, dv),
            world.evaluate(per_patch, du, dv),
            weight_sum(form, per_patch[..., 0], per_patch[..., 1], du, dv),
            size,
        )
        grid_weights = weight_sum(form, GRID_U[:, None], GRID_V[None, :], du, dv)
        assert_close_ulps(
            framed.evaluate_grid(GRID_U, GRID_V, du, dv),
            world.evaluate_grid(GRID_U, GRID_V, du, dv),
            grid_weights,
            size,
        )
    p_u, p_v = world.tangents(UV)
    tangent_error = (
        ULPS
        * EPS
        * size
        * np.maximum(
            weight_sum(form, UV[:, 0], UV[:, 1], 1, 0), weight_sum(form, UV[:, 0], UV[:, 1], 0, 1)
        )
    )
    assert_normals_close(framed.normals(UV), p_u, p_v, tangent_error)
    for (du, dv), got, want in zip(((1, 0), (0, 1)), framed.tangents(UV), (p_u, p_v), strict=True):
        assert_close_ulps(got, want, weight_sum(form, UV[:, 0], UV[:, 1], du, dv), size)
    assert_close_ulps(
        framed.twist(UV), world.twist(UV), weight_sum(form, UV[:, 0], UV[:, 1], 1, 1), size
    )
    corner_weights = weight_sum(form, CORNER_PARAMETERS[:, 0], CORNER_PARAMETERS[:, 1], 0, 0)
    assert_close_ulps(framed.corners(), world.corners(), corner_weights, size)
    t = np.linspace(0.0, 1.0, 7)
    curve_weights = (
        np.abs(basis_values(form, t)).sum(axis=-1) * 2.0
    )  # one row of the net, then the curve
    assert_close_ulps(
        framed.boundary_curves().evaluate(t),
        world.boundary_curves().evaluate(t),
        curve_weights,
        size,
    )


def test_grid_outputs_are_mapped_in_place() -> None:
    framed = PatchSet(local_control(3, 5), "bezier", FAR)
    shape = (3, len(GRID_U), len(GRID_V), 3)
    out, normals_out = np.empty(shape), np.empty(shape)
    assert framed.evaluate_grid(GRID_U, GRID_V, out=out) is out
    np.testing.assert_array_equal(out, framed.evaluate_grid(GRID_U, GRID_V))
    assert framed.evaluate_grid(GRID_U, GRID_V, 1, 0, out=out) is out
    np.testing.assert_array_equal(out, framed.evaluate_grid(GRID_U, GRID_V, 1, 0))
    positions, normals = framed.evaluate_grid_with_normals(
        GRID_U, GRID_V, out=out, normals_out=normals_out
    )
    assert positions is out and normals is normals_out
    np.testing.assert_array_equal(out, framed.evaluate_grid(GRID_U, GRID_V))
    np.testing.assert_array_equal(normals_out, framed.normals_grid(GRID_U, GRID_V))
    np.testing.assert_array_equal(framed.grid(5), framed.evaluate_grid(np.linspace(0.0, 1.0, 5)))


def test_world_control_maps_hermite_positions_as_points_and_the_rest_as_vectors() -> None:
    framed = PatchSet(local_control(2, 6), "hermite", FAR)
    world = framed.world_control()
    np.testing.assert_array_equal(world[:, :2, :2], FAR.to_world(framed.control[:, :2, :2]))
    np.testing.assert_array_equal(world[:, 2:], FAR.scale * framed.control[:, 2:])
    np.testing.assert_array_equal(world[:, :2, 2:], FAR.scale * framed.control[:, :2, 2:])
    bezier = framed.convert("bezier")
    np.testing.assert_array_equal(bezier.world_control(), FAR.to_world(bezier.control))
    unframed = framed.local()
    assert unframed.world_control() is unframed.control


@pytest.mark.parametrize("source", FORMS)
def test_conversions_take_and_coons_keep_the_frame(source: str) -> None:
    framed = PatchSet(local_control(3, 7), source, FAR)  # type: ignore[arg-type]
    for target in FORMS:
        converted = framed.convert(target)  # type: ignore[arg-type]
        assert converted.frame == FAR
        back = converted.convert(source)  # type: ignore[arg-type]
        assert back.frame == FAR
        # conversion acts on the local control alone: its round-trip error (test_patches) is that of
        # unit-sized numbers, whatever the frame
        np.testing.assert_array_equal(converted.control, framed.local().convert(target).control)  # type: ignore[arg-type]
        np.testing.assert_array_equal(
            back.control, framed.local().convert(target).convert(source).control
        )  # type: ignore[arg-type]
        assert_close_ulps(
            back.evaluate(UV), framed.evaluate(UV), np.full(len(UV), 8.0), magnitude(framed)
        )
    assert framed.take([2, 0, 2]).frame == FAR
    np.testing.assert_array_equal(framed.take([2, 0]).control, framed.control[[2, 0]])
    coons = framed.with_coons_twists()
    assert coons.frame == FAR and coons.form == source
    np.testing.assert_array_equal(coons.control, framed.local().with_coons_twists().control)
    assert (
        framed.with_frame(None).frame is None
        and framed.with_frame(Frame.identity()).frame == Frame.identity()
    )


def test_power_form_diagonals_and_closure_are_world_values() -> None:
    framed = PatchSet(local_control(3, 8), "hermite", FAR)
    world = world_set(framed)
    size = magnitude(framed)
    # p(u, v) = Σ A_ij u^(3-i) v^(3-j): evaluate the power form at UV and compare with evaluate
    power = framed.power_coefficients()
    u, v = UV[:, 0], UV[:, 1]
    monomials = (u[:, None] ** np.arange(3, -1, -1))[:, :, None] * (
        v[:, None] ** np.arange(3, -1, -1)
    )[:, None, :]
    np.testing.assert_allclose(
        np.einsum("kij,nijd->nkd", monomials, power),
        framed.evaluate(UV),
        rtol=0,
        atol=1e3 * EPS * size,
    )
    np.testing.assert_allclose(power, world.power_coefficients(), rtol=0, atol=1e3 * EPS * size)
    for got, want in zip(framed.diagonal_polynomials(), world.diagonal_polynomials(), strict=True):
        np.testing.assert_allclose(got, want, rtol=0, atol=1e4 * EPS * size)
    np.testing.assert_array_equal(framed.closure(), FAR.scale * framed.local().closure())


@settings(max_examples=60, deadline=None)
@given(
    centre=st.lists(st.floats(-1e8, 1e8), min_size=3, max_size=3),
    scale=st.floats(1e-3, 1e5),
    seed=st.integers(0, 2**32 - 1),
    form=st.sampled_from(FORMS),
    order=st.sampled_from(ORDERS[:5]),
)
def test_property_framed_equals_world_for_any_frame(
    centre: list[float], scale: float, seed: int, form: str, order: tuple[int, int]
) -> None:
    frame = Frame(np.array(centre), scale)
    framed = PatchSet(local_control(2, seed), form, frame)  # type: ignore[arg-type]
    uv = np.random.default_rng(seed).uniform(size=(6, 2))
    du, dv = order
    local = framed.local().evaluate(uv, du, dv)
    got = framed.evaluate(uv, du, dv)
    np.testing.assert_array_equal(
        got, frame.vectors_to_world(local) if du or dv else frame.to_world(local)
    )
    assert_close_ulps(
        got,
        world_set(framed).evaluate(uv, du, dv),
        weight_sum(form, uv[:, 0], uv[:, 1], du, dv),
        magnitude(framed),
    )


# ------------------------------------------------------------------------------ GregoryPatchSet


def gregory_local(n: int, seed: int) -> NDArray[np.float64]:
    """Points of Gregory patches over the unit square with distinct interior pairs (not a Bézier
    patch)."""
    net = local_control(n, seed)
    steps = np.arange(4) / 3.0 - 0.5
    net[..., :2] = 0.2 * net[..., :2] + np.stack(np.meshgrid(steps, steps, indexing="ij"), axis=-1)
    from g1patch.gregory import BEZIER_INDEX, INTERIOR_INDEX

    points = np.empty((n, 20, 3))
    points[:, :12] = net[:, BEZIER_INDEX[:, 0], BEZIER_INDEX[:, 1]]
    interior = net[:, INTERIOR_INDEX[:, 0], INTERIOR_INDEX[:, 1]]
    offset = np.random.default_rng(seed + 1).uniform(-0.1, 0.1, size=(n, 4, 3))
    points[:, 12::2], points[:, 13::2] = interior + offset, interior - offset
    return points


def test_framed_gregory_patches_equal_the_world_ones() -> None:
    framed = GregoryPatchSet(gregory_local(4, 9), FAR)
    world = GregoryPatchSet(framed.world_points())
    local = framed.local()
    assert local.frame is None and local.points is framed.points
    np.testing.assert_array_equal(framed.world_points(), FAR.to_world(framed.points))
    size = magnitude(framed)
    for du, dv in [(0, 0), (1, 0), (0, 1)]:
        weights = np.abs(gregory_weights(UV[:, 0], UV[:, 1], du, dv)).sum(axis=-1)
        got = framed.evaluate(UV, du, dv)
        mapped = local.evaluate(UV, du, dv)
        np.testing.assert_array_equal(
            got, FAR.vectors_to_world(mapped) if du or dv else FAR.to_world(mapped)
        )
        assert_close_ulps(got, world.evaluate(UV, du, dv), weights, size)
        per_patch = np.broadcast_to(UV, (len(framed),) + UV.shape)
        # per-patch weights take a batched product, shared ones one matrix product: BLAS may sum
        # them in another order
        assert_close_ulps(framed.evaluate(per_patch, du, dv), got, weights, size)
        grid_weights = np.abs(gregory_weights(GRID_U[:, None], GRID_V[None, :], du, dv)).sum(
            axis=-1
        )
        assert_close_ulps(
            framed.evaluate_grid(GRID_U, GRID_V, du, dv),
            world.evaluate_grid(GRID_U, GRID_V, du, dv),
            grid_weights,
            size,
        )
    np.testing.assert_array_equal(framed.normals(UV), local.normals(UV))
    tangent_error = (
        ULPS * EPS * size * np.abs(gregory_weights(UV[:, 0], UV[:, 1], 1, 0)).sum(axis=-1).clip(3.0)
    )
    assert_normals_close(
        framed.normals(UV), world.evaluate(UV, 1, 0), world.evaluate(UV, 0, 1), tangent_error
    )
    np.testing.assert_array_equal(framed.corners(), framed.world_points()[:, :4])
    np.testing.assert_array_equal(framed.boundary_curves().control, world.boundary_curves().control)
    assert framed.take([1, 1]).frame == FAR and framed.with_frame(None).frame is None
    np.testing.assert_array_equal(framed.to_bezier_control(), local.to_bezier_control())
    again = GregoryPatchSet.from_arrays(framed.to_arrays())
    assert again.frame == FAR
    np.testing.assert_array_equal(again.points, framed.points)
    assert GregoryPatchSet.from_arrays(local.to_arrays()).frame is None


# ------------------------------------------------------------------------------ files and export


def framed_cube(frame: Frame = FAR) -> tuple[PatchNetwork, PatchNetwork]:
    """A corner network of the cube (unit-sized control, taken as local), framed and in world
    coordinates."""
    network = build_corner_network(shapes.cube())
    framed = network.patches.with_frame(frame)  # type: ignore[attr-defined]
    vertices = frame.to_world(network.vertices)
    return (
        dataclasses.replace(network, patches=framed, vertices=vertices),
        dataclasses.replace(network, patches=world_set(framed), vertices=vertices),
    )


def test_network_file_keeps_the_frame_and_the_local_numbers(tmp_path: Path) -> None:
    framed, _ = framed_cube()
    save_network(tmp_path / "n.npz", framed)
    with np.load(tmp_path / "n.npz") as data:
        assert (
            json.loads(str(data["header"]))["version"] == FORMAT_VERSION >= 2
        )  # frames since version 2
        np.testing.assert_array_equal(data["frame_centre"], FAR.centre)
        assert data["frame_scale"].shape == () and float(data["frame_scale"]) == FAR.scale
    loaded = load_network(tmp_path / "n.npz")
    assert loaded.patches.frame == FAR  # type: ignore[attr-defined]
    np.testing.assert_array_equal(loaded.patches.control, framed.patches.control)  # type: ignore[attr-defined]
    unframed = dataclasses.replace(framed, patches=framed.patches.local())  # type: ignore[attr-defined]
    save_network(tmp_path / "plain.npz", unframed)
    with np.load(tmp_path / "plain.npz") as data:
        assert "frame_centre" not in data.files
    assert load_network(tmp_path / "plain.npz").patches.frame is None  # type: ignore[attr-defined]

    gregory = dataclasses.replace(framed, patches=GregoryPatchSet(gregory_local(6, 10), FAR))
    save_network(tmp_path / "g.npz", gregory)
    loaded_gregory = load_network(tmp_path / "g.npz").patches
    assert isinstance(loaded_gregory, GregoryPatchSet) and loaded_gregory.frame == FAR
    np.testing.assert_array_equal(loaded_gregory.points, gregory.patches.points)  # type: ignore[attr-defined]


def rewrite(path: Path, target: Path, version: int | None = None, **arrays: object) -> Path:
    with np.load(path) as data:
        contents = {name: data[name] for name in data.files}
    if version is not None:
        header = json.loads(str(contents["header"]))
        header["version"] = version
        contents["header"] = np.array(json.dumps(header))
    for name, value in arrays.items():
        if value is None:
            contents.pop(name)
        else:
            contents[name] = np.asarray(value)
    np.savez(target, **contents)  # type: ignore[arg-type]
    return target


def test_version_1_files_still_load_without_a_frame(tmp_path: Path) -> None:
    framed, _ = framed_cube()
    save_network(tmp_path / "n.npz", framed)
    old = rewrite(
        tmp_path / "n.npz", tmp_path / "v1.npz", version=1, frame_centre=None, frame_scale=None
    )
    loaded = load_network(old)
    assert isinstance(loaded.patches, PatchSet) and loaded.patches.frame is None
    np.testing.assert_array_equal(loaded.patches.control, framed.patches.control)  # type: ignore[attr-defined]
    # version 1 has no frame: arrays of that name in such a file are not read
    assert (
        load_network(rewrite(tmp_path / "n.npz", tmp_path / "v1f.npz", version=1)).patches.frame
        is None
    )  # type: ignore[attr-defined]


@pytest.mark.parametrize(
    "arrays,match",
    [
        (
            {"frame_scale": None},
            "corrupt network file: arrays: a frame needs both 'frame_centre' and 'frame_scale'",
        ),
        (
            {"frame_scale": np.array(-1.0)},
            "corrupt network file: frame scale: expected a positive finite number, got -1.0",
        ),
        ({"frame_scale": np.ones(3)}, r"corrupt network file: frame scale: expected one number"),
        (
            {"frame_centre": np.array([0.0, np.inf, 0.0])},
            "corrupt network file: frame centre: non-finite value inf",
        ),
        (
            {"frame_centre": np.zeros(4)},
            r"corrupt network file: frame centre: expected shape \(\.\.\., 3\)",
        ),
    ],
)
def test_bad_frame_arrays_are_format_errors(
    tmp_path: Path, arrays: dict[str, object], match: str
) -> None:
    save_network(tmp_path / "n.npz", framed_cube()[0])
    with pytest.raises(FormatError, match=match):
        load_network(rewrite(tmp_path / "n.npz", tmp_path / "bad.npz", **arrays))


def test_bpt_of_a_framed_set_is_the_world_one(tmp_path: Path) -> None:
    framed = PatchSet(local_control(3, 11), "hermite", FAR)
    write_bpt(tmp_path / "framed.bpt", framed)
    write_bpt(tmp_path / "world.bpt", PatchSet(framed.convert("bezier").world_control(), "bezier"))
    assert (tmp_path / "framed.bpt").read_text() == (tmp_path / "world.bpt").read_text()
    read = read_bpt(tmp_path / "framed.bpt")
    assert read.frame is None
    np.testing.assert_array_equal(read.control, framed.convert("bezier").world_control())


def test_volume_tessellation_and_fit_are_in_world_coordinates() -> None:
    frame = Frame(np.array([1.0e6, 2.0, -3.0e6]), 3.0)
    framed, world = framed_cube(frame)
    local_volume = network_volume(framed.patches.local())  # type: ignore[attr-defined]
    assert network_volume(framed) == local_volume * frame.scale**3
    assert network_volume(world) == pytest.approx(local_volume * frame.scale**3, rel=1e-8)

    mesh, reference = tessellate(framed, 5), tessellate(world, 5)
    np.testing.assert_array_equal(mesh.triangles, reference.triangles)
    # W ≤ 4 bounds the Hermite position weights Σ_ij |H_i(u) H_j(v)|
    np.testing.assert_allclose(
        mesh.points, reference.points, rtol=0, atol=ULPS * EPS * magnitude(framed.patches) * 4
    )  # type: ignore[arg-type]
    # the world set's tangents carry the rounding of its control, ≈ eps |c| against tangents of size
    # ≈ s
    np.testing.assert_allclose(
        mesh.normals,
        reference.normals,
        rtol=0,
        atol=16 * EPS * np.abs(frame.centre).max() / frame.scale,
    )

    gregory = GregoryPatchSet(gregory_local(2, 12), frame)
    fit = fit_bspline_surfaces(gregory, 1e-4 * frame.scale)
    fit_world = fit_bspline_surfaces(GregoryPatchSet(gregory.world_points()), 1e-4 * frame.scale)
    assert fit.control.shape == fit_world.control.shape
    assert 0 < fit.deviation <= 1e-4 * frame.scale
    np.testing.assert_allclose(fit.deviation, fit_world.deviation, rtol=1e-3)
    np.testing.assert_allclose(fit.control, fit_world.control, rtol=0, atol=1e-8 * frame.scale)
    local_fit = fit_bspline_surfaces(gregory.local(), 1e-4)
    np.testing.assert_array_equal(fit.control, frame.to_world(local_fit.control))


def test_step_export_of_a_framed_network_writes_world_coordinates(tmp_path: Path) -> None:
    pytest.importorskip("OCP", reason="OCP is not installed (extra 'cad')")
    from g1patch.io.cad import export_step, read_step_faces

    framed, world = framed_cube()
    results = [
        export_step(tmp_path / f"{name}.step", network, g1_samples=5)
        for name, network in (("framed", framed), ("world", world))
    ]
    for result in results:
        assert result.exact and result.solid and result.valid and result.free_edges == 0
    assert results[0].volume == pytest.approx(results[1].volume, rel=1e-9)
    assert results[0].sewing_tolerance == results[1].sewing_tolerance
    poles = [np.stack([face.poles() for face in read_step_faces(r.path).faces]) for r in results]
    np.testing.assert_array_equal(poles[0], poles[1])
    bezier = framed.patches.convert("bezier").world_control()  # type: ignore[attr-defined]
    distance = np.abs(poles[0][:, None] - bezier[None]).max(axis=(2, 3, 4)).min(axis=1)
    assert distance.max() <= 1e-9 * np.abs(FAR.centre).max()  # every face is one of the world nets
