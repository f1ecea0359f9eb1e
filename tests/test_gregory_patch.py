"""Gregory patches (g1patch.gregory) against an independent sympy derivation and their invariants.

The reference builds the patch from its definition (g1-constructions.md §4.1): the Bernstein sum
over the 4×4 net whose interior points are the rational blends written out per corner, e.g.
``b11 = (u Fn0 + v Fp0)/(u + v)``; sympy differentiates it exactly and takes the corner limits.
Float tolerances are relative to ``S = max |points|``: the weights are sums of ≤ 6 rounded
products each within a few eps, and 20 of them are contracted, so the error is ≲ 100 eps · S;
1e-13 · S is ≈ 450 eps.
"""

from __future__ import annotations

from fractions import Fraction

import numpy as np
import pytest
import sympy as sp
from hypothesis import given, settings
from hypothesis import strategies as st

from g1patch.errors import InputError
from g1patch.gregory import GregoryPatchSet, gregory_weights
from g1patch.network import edge_parameters
from g1patch.patches import CORNER_PARAMETERS, PatchSet

REL = 1e-13
EPS = np.finfo(float).eps
u, v = sp.symbols("u v")


def random_points(seed: int, count: int = 3) -> np.ndarray:
    return np.random.default_rng(seed).normal(size=(count, 20, 3))


def scattered(seed: int, count: int = 12) -> np.ndarray:
    """Parameters in [0, 1]² including corners, edge points and points next to the corners."""
    rng = np.random.default_rng(seed)
    special = np.array(
        [
            [0, 0],
            [1, 0],
            [1, 1],
            [0, 1],
            [0.3, 0],
            [1, 0.6],
            [0.2, 1],
            [0, 0.9],
            [1e-9, 2e-9],
            [1 - 1e-9, 1],
        ]
    )
    return np.vstack([special, rng.random((count, 2))])


# ------------------------------------------------------------------------------ sympy reference
def sympy_patch(points: list[list[sp.Rational]]) -> list[sp.Expr]:
    """x, y, z of the Gregory patch with the 20 rational ``points``, built from §4.1."""
    P = [sp.Matrix(p) for p in points]
    corner, e_next, e_prev, fn, fp = P[0:4], P[4:12:2], P[5:12:2], P[12:20:2], P[13:20:2]
    net = [[None] * 4 for _ in range(4)]
    net[0][0], net[3][0], net[3][3], net[0][3] = corner
    net[1][0], net[3][1], net[2][3], net[0][2] = e_next
    net[0][1], net[2][0], net[3][2], net[1][3] = e_prev
    net[1][1] = (u * fn[0] + v * fp[0]) / (u + v)
    net[2][1] = ((1 - u) * fp[1] + v * fn[1]) / ((1 - u) + v)
    net[2][2] = ((1 - v) * fp[2] + (1 - u) * fn[2]) / ((1 - u) + (1 - v))
    net[1][2] = (u * fp[3] + (1 - v) * fn[3]) / (u + (1 - v))

    def bernstein(i: int, t: sp.Symbol) -> sp.Expr:
        return sp.binomial(3, i) * t**i * (1 - t) ** (3 - i)

    total = sp.zeros(3, 1)
    for i in range(4):
        for j in range(4):
            total += bernstein(i, u) * bernstein(j, v) * net[i][j]
    return list(total)


def exact_value(expr: sp.Expr, uu: Fraction, vv: Fraction) -> float:
    """expr at (uu, vv); at a corner, where a blend is 0/0, the limit (the patch is continuous)."""
    try:
        value = expr.subs({u: sp.Rational(uu), v: sp.Rational(vv)})
        if value.has(sp.nan, sp.zoo) or not value.is_finite:
            raise ZeroDivisionError
    except ZeroDivisionError:
        value = sp.limit(sp.limit(expr, u, sp.Rational(uu)), v, sp.Rational(vv))
    return float(value)


SYMPY_UV = [
    (Fraction(0), Fraction(0)),
    (Fraction(1), Fraction(0)),
    (Fraction(1), Fraction(1)),
    (Fraction(0), Fraction(1)),
    (Fraction(1, 3), Fraction(0)),
    (Fraction(1), Fraction(2, 5)),
    (Fraction(3, 7), Fraction(1)),
    (Fraction(0), Fraction(5, 6)),
    (Fraction(1, 5), Fraction(2, 7)),
    (Fraction(5, 8), Fraction(3, 4)),
    (Fraction(9, 10), Fraction(1, 9)),
]


@pytest.mark.parametrize("du, dv", [(0, 0), (1, 0), (0, 1)])
def test_matches_the_sympy_derivation(du: int, dv: int) -> None:
    rng = np.random.default_rng(7)
    numerators = rng.integers(-20, 21, size=(20, 3))
    denominators = rng.choice([1, 2, 3, 4, 5, 7], size=(20, 3))
    exact = [
        [sp.Rational(int(n), int(d)) for n, d in zip(row_n, row_d, strict=True)]
        for row_n, row_d in zip(numerators, denominators, strict=True)
    ]
    points = np.array([[float(c) for c in row] for row in exact])
    expressions = [sp.diff(e, u, du, v, dv) for e in sympy_patch(exact)]
    reference = np.array([[exact_value(e, a, b) for e in expressions] for a, b in SYMPY_UV])
    uv = np.array([[float(a), float(b)] for a, b in SYMPY_UV])
    got = GregoryPatchSet(points[None]).evaluate(uv, du, dv)[0]
    np.testing.assert_allclose(got, reference, rtol=0, atol=REL * np.abs(points).max() * 10)


# ------------------------------------------------------------------------------ structure
def test_equal_pairs_give_the_bicubic_bezier_patch() -> None:
    """With Fn = Fp every blend is that point: the patch is the Bézier net of
    to_bezier_control()."""
    points = random_points(1)
    points[:, 13::2] = points[:, 12::2]
    gregory = GregoryPatchSet(points)
    bezier = PatchSet(gregory.to_bezier_control(), "bezier")
    uv = scattered(2)
    scale = np.abs(points).max()
    for du, dv in [(0, 0), (1, 0), (0, 1)]:
        np.testing.assert_allclose(
            gregory.evaluate(uv, du, dv), bezier.evaluate(uv, du, dv), rtol=0, atol=REL * scale
        )


def test_layout_is_rotation_symmetric() -> None:
    """Relabelling corner k as k − 1 is the patch with the parameters turned: Q(u, v) = P(1 − v,
    u)."""
    points = random_points(3)
    rolled = np.concatenate(
        [
            np.roll(points[:, :4], -1, axis=1),
            np.roll(points[:, 4:12], -2, axis=1),
            np.roll(points[:, 12:], -2, axis=1),
        ],
        axis=1,
    )
    P, Q = GregoryPatchSet(points), GregoryPatchSet(rolled)
    uv = scattered(4)
    turned = np.stack([1.0 - uv[:, 1], uv[:, 0]], axis=1)
    scale = np.abs(points).max()
    np.testing.assert_allclose(Q.evaluate(uv), P.evaluate(turned), rtol=0, atol=REL * scale)
    np.testing.assert_allclose(
        Q.evaluate(uv, 1, 0), P.evaluate(turned, 0, 1), rtol=0, atol=REL * scale
    )
    np.testing.assert_allclose(
        Q.evaluate(uv, 0, 1), -P.evaluate(turned, 1, 0), rtol=0, atol=REL * scale
    )


@pytest.mark.parametrize("edge", range(4))
def test_an_edge_sees_only_its_own_interior_points(edge: int) -> None:
    """Position and both first derivatives on edge k do not depend on the interior points of the
    other edges: on edge k only Fn_k and Fp_{k+1} act (their blend weights there are exactly
    0/1)."""
    points = random_points(5)
    own = {12 + 2 * edge, 13 + 2 * ((edge + 1) % 4)}
    others = [m for m in range(12, 20) if m not in own]
    moved = points.copy()
    moved[:, others] += 10.0
    uv = edge_parameters(np.array(edge), np.linspace(0.0, 1.0, 17))
    for du, dv in [(0, 0), (1, 0), (0, 1)]:
        np.testing.assert_array_equal(
            GregoryPatchSet(moved).evaluate(uv, du, dv),
            GregoryPatchSet(points).evaluate(uv, du, dv),
        )


def test_cross_derivative_on_an_edge_is_the_bezier_row() -> None:
    """On v = 0: ∂p/∂v = 3 Σ B_i(t) (g_i − b_i) with rows b = (P0, E+0, E-1, P1), g = (E-0, Fn0,
    Fp1, E+1)."""
    points = random_points(6)
    t = np.linspace(0.0, 1.0, 9)
    bernstein = np.stack([(1 - t) ** 3, 3 * t * (1 - t) ** 2, 3 * t**2 * (1 - t), t**3], axis=1)
    boundary, second = points[:, [0, 4, 7, 1]], points[:, [5, 12, 15, 6]]
    expected = 3.0 * np.einsum("ki,nid->nkd", bernstein, second - boundary)
    got = GregoryPatchSet(points).evaluate(np.stack([t, np.zeros_like(t)], axis=1), 0, 1)
    np.testing.assert_allclose(got, expected, rtol=0, atol=REL * np.abs(points).max())


def test_corner_values_and_derivatives_are_exact_limits() -> None:
    """At the corners the blends are 0/0; the result is the limit: p = P_k, p_u, p_v from the edge
    points."""
    points = random_points(8)
    patches = GregoryPatchSet(points)
    np.testing.assert_array_equal(patches.corners(), points[:, :4])
    p_u, p_v = patches.evaluate(CORNER_PARAMETERS, 1, 0), patches.evaluate(CORNER_PARAMETERS, 0, 1)
    scale = REL * np.abs(points).max()
    np.testing.assert_allclose(p_u[:, 0], 3 * (points[:, 4] - points[:, 0]), rtol=0, atol=scale)
    np.testing.assert_allclose(p_v[:, 0], 3 * (points[:, 5] - points[:, 0]), rtol=0, atol=scale)
    np.testing.assert_allclose(
        p_u[:, 2], 3 * (points[:, 2] - points[:, 8]), rtol=0, atol=scale
    )  # b33 − b23 (E+_2)
    np.testing.assert_allclose(
        p_v[:, 2], 3 * (points[:, 2] - points[:, 9]), rtol=0, atol=scale
    )  # b33 − b32 (E-_2)


@pytest.mark.parametrize("tiny", [1e-9, 1e-200, 1e-300, 5e-324])
def test_no_nan_next_to_the_corners(tiny: float) -> None:
    """Parameters down to the smallest subnormal: finite, and continuous into the corner values."""
    points = random_points(9)
    patches = GregoryPatchSet(points)
    near = np.array([[tiny, tiny], [tiny, 0.0], [0.0, tiny], [1 - tiny, 1.0], [1.0, 1 - tiny]])
    corners = np.array([[0.0, 0.0], [0.0, 0.0], [0.0, 0.0], [1.0, 1.0], [1.0, 1.0]])
    with np.errstate(divide="raise", invalid="raise", over="raise"):
        for du, dv in [(0, 0), (1, 0), (0, 1)]:
            got, limit = patches.evaluate(near, du, dv), patches.evaluate(corners, du, dv)
            assert np.isfinite(got).all()
            np.testing.assert_allclose(got, limit, rtol=0, atol=1e-7 * np.abs(points).max())


@settings(deadline=None, max_examples=40)
@given(
    st.integers(0, 2**32 - 1),
    st.floats(0.02, 0.98),
    st.floats(0.02, 0.98),
)
def test_derivatives_match_central_differences(seed: int, uu: float, vv: float) -> None:
    """Central differences with h = 1e-6: truncation h² |p'''| ≲ 1e-9 here, rounding eps |p|/h ≈
    1e-10."""
    patches = GregoryPatchSet(random_points(seed, 2))
    h = 1e-6
    uv = np.array([[uu, vv]])
    fu = (patches.evaluate(uv + [h, 0]) - patches.evaluate(uv - [h, 0])) / (2 * h)
    fv = (patches.evaluate(uv + [0, h]) - patches.evaluate(uv - [0, h])) / (2 * h)
    scale = np.abs(patches.points).max()
    np.testing.assert_allclose(patches.evaluate(uv, 1, 0), fu, rtol=0, atol=1e-6 * scale)
    np.testing.assert_allclose(patches.evaluate(uv, 0, 1), fv, rtol=0, atol=1e-6 * scale)


unit_parameter = st.one_of(st.sampled_from([0.0, 1.0]), st.floats(0.0, 1.0))


@settings(deadline=None, max_examples=60)
@given(
    st.integers(0, 2**32 - 1),
    st.lists(st.tuples(unit_parameter, unit_parameter), min_size=1, max_size=6),
)
def test_affine_invariance(seed: int, params: list[tuple[float, float]]) -> None:
    """Weights sum to 1 (positions) and to 0 (derivatives): p(A x + c) = A p(x) + c, p_u(A x + c) =
    A p_u(x)."""
    rng = np.random.default_rng(seed)
    points = rng.normal(size=(2, 20, 3))
    matrix, shift = rng.normal(size=(3, 3)), rng.normal(size=3)
    moved = GregoryPatchSet(points @ matrix.T + shift)
    patches = GregoryPatchSet(points)
    uv = np.array(params)
    scale = REL * 10 * np.abs(points).max() * np.abs(matrix).sum() + REL * np.abs(shift).max()
    np.testing.assert_allclose(
        moved.evaluate(uv), patches.evaluate(uv) @ matrix.T + shift, rtol=0, atol=scale
    )
    for du, dv in [(1, 0), (0, 1)]:
        np.testing.assert_allclose(
            moved.evaluate(uv, du, dv),
            patches.evaluate(uv, du, dv) @ matrix.T,
            rtol=0,
            atol=scale * 10,
        )
    weights = gregory_weights(uv[:, 0], uv[:, 1])
    # The 20 weights are ≥ 0 up to rounding (Σ|w| = 1), each with a few roundings (Bernstein
    # products, the blend's quotient), then summed: ≲ 25 ULPs of Σ|w| (measured ≤ 5 on 2e6
    # parameters; an absolute 1e-15 = 4.5 ULPs failed at 5). 32 ULPs of the weights' scale.
    scale_w = np.abs(weights).sum(axis=-1).max()
    np.testing.assert_allclose(weights.sum(axis=-1), 1.0, rtol=0, atol=32 * EPS * scale_w)


# ------------------------------------------------------------------------------ API
def test_grid_and_per_patch_parameters_agree_with_shared_ones() -> None:
    patches = GregoryPatchSet(random_points(10, 4))
    u_grid, v_grid = np.linspace(0.0, 1.0, 5), np.array([0.0, 0.25, 1.0])
    uv = np.stack(np.meshgrid(u_grid, v_grid, indexing="ij"), axis=-1).reshape(-1, 2)
    for du, dv in [(0, 0), (1, 0), (0, 1)]:
        shared = patches.evaluate(uv, du, dv)
        np.testing.assert_array_equal(
            patches.evaluate_grid(u_grid, v_grid, du, dv), shared.reshape(4, 5, 3, 3)
        )
        np.testing.assert_allclose(
            patches.evaluate(np.broadcast_to(uv, (4,) + uv.shape), du, dv),
            shared,
            rtol=0,
            atol=1e-14 * np.abs(shared).max(),
        )
    assert patches.evaluate_grid(u_grid).shape == (4, 5, 5, 3)


def test_boundary_curves_are_the_patch_edges() -> None:
    patches = GregoryPatchSet(random_points(11))
    curves = patches.boundary_curves()
    assert curves.form == "bezier" and curves.batch_shape == (3, 4)
    t = np.linspace(0.0, 1.0, 11)
    uv = edge_parameters(np.arange(4)[:, None], t[None, :]).reshape(-1, 2)
    on_edges = patches.evaluate(uv).reshape(3, 4, 11, 3)
    np.testing.assert_allclose(
        curves.evaluate(t), on_edges, rtol=0, atol=REL * np.abs(patches.points).max()
    )


def test_normals_are_unit_and_zero_where_degenerate() -> None:
    points = random_points(12, 2)
    points[1] = 0.0  # a patch collapsed to a point: p_u = p_v = 0
    normals = GregoryPatchSet(points).normals(scattered(13))
    np.testing.assert_allclose(np.linalg.norm(normals[0], axis=-1), 1.0, rtol=1e-14)
    np.testing.assert_array_equal(normals[1], 0.0)


def test_arrays_round_trip_and_kind() -> None:
    patches = GregoryPatchSet(random_points(14))
    again = GregoryPatchSet.from_arrays(patches.to_arrays())
    np.testing.assert_array_equal(again.points, patches.points)
    assert GregoryPatchSet.kind == "gregory" and len(again) == 3
    np.testing.assert_array_equal(patches.take([2, 0, 2]).points, patches.points[[2, 0, 2]])


@pytest.mark.parametrize(
    "call, match",
    [
        (lambda p: p.evaluate([[0.5, 0.5]], 2, 0), "du, dv"),
        (lambda p: p.evaluate([[0.5, 0.5]], 1, 1), "du \\+ dv"),
        (lambda p: p.evaluate([[0.5, 1.5]]), "uv: Gregory patches are defined on"),
        (lambda p: p.evaluate([[0.5, 0.5, 0.5]]), "uv: expected shape"),
        (
            lambda p: p.evaluate(np.zeros((2, 4, 2))),
            "uv: expected shape \\(K, 2\\) or \\(3, K, 2\\)",
        ),
        (lambda p: p.evaluate_grid([-0.1, 0.5]), "u: Gregory patches"),
        (lambda p: p.evaluate_grid([[0.1]]), "u: expected a 1-D"),
        (lambda p: GregoryPatchSet(np.zeros((2, 16, 3))), "points: expected shape"),
        (lambda p: GregoryPatchSet(np.zeros((20, 3))), "points: expected shape \\(N, 20, 3\\)"),
        (
            lambda p: GregoryPatchSet.from_arrays({"control": np.zeros((1, 20, 3))}),
            "arrays: .*'points'",
        ),
    ],
)
def test_bad_input_names_the_argument(call, match: str) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(InputError, match=match):
        call(GregoryPatchSet(random_points(15)))
