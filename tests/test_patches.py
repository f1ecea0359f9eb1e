"""Bicubic patches (g1patch.patches) against an independent sympy expansion of the paper's eq. (3).

Evaluation accuracy is stated against S = Σ_ij B_i(u) |P_ij| B_j(v) (reference.abs_patch_sum),
the magnitude of every term the floating-point evaluation sums. A relative error ≤ 1e-14 of S
is ≈ 45 ULP of S. The a-priori bound is ≈ 16 eps·S (see EVAL_REL below), so this leaves margin
without being loose; where S ≈ |p| (no cancellation) it is the plain relative error.
"""

from __future__ import annotations

import itertools
import re
from fractions import Fraction

import numpy as np
import pytest
import reference as ref
import sympy as sp
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from g1patch.basis import conversion_matrix
from g1patch.errors import InputError
from g1patch.patches import (
    CORNER_PARAMETERS,
    PatchSet,
    closure,
    diagonal_polynomials,
    hs_twists,
    polynomial_degree,
)

EPS = np.finfo(np.float64).eps
FORMS = ("hermite", "bezier", "bspline")
UNDERFLOW = 1e-300

# Evaluation error budget, in eps · S:
#   each basis value by Horner: γ_6 B = 3 eps B, + rounding of the parameter ≤ |t b'(t)| u ≤ 1.5 eps
# B,
#   + rounded 1/6 coefficients ≤ 0.5 eps B  →  5 eps per direction, 10 eps for b_i(u) b_j(v);
#   rounding of the rational control values 0.5 eps; the 16-term contraction (two 4-term stages
#   or one 16-term sum, with the products) ≤ γ_5 + γ_5 ≈ 5 eps; the reference's final rounding 0.5
# eps.
#   Total ≈ 16 eps. Asserted: 1e-14 ≈ 45 eps.
EVAL_REL = 1e-14

R = Fraction
UV = [
    (R(0), R(0)), (R(1), R(1)), (R(1, 3), R(2, 7)), (R(1, 2), R(1, 4)), (R(3, 4), R(1, 5)),
    (R(2, 3), R(5, 6)), (R(1, 7), R(9, 10)), (R(0), R(1, 3)), (R(1), R(2, 3)), (R(5, 8), R(3, 8)),
    (R(1, 10), R(1)),
]  # fmt: skip
DERIVATIVES = [
    (0, 0),
    (1, 0),
    (0, 1),
    (1, 1),
    (2, 0),
    (0, 2),
    (2, 1),
    (1, 2),
    (2, 2),
    (3, 0),
    (3, 3),
    (4, 0),
    (1, 4),
]
GRID_U = [R(0), R(1, 3), R(1, 2), R(6, 7), R(1)]
GRID_V = [R(1, 5), R(1, 4), R(3, 4)]


def floats(values) -> np.ndarray:
    return np.array(
        [
            [float(a) for a in row] if isinstance(row, (tuple, list)) else float(row)
            for row in values
        ]
    )


class Reference:
    """Rational control values of N patches in one form and their sympy polynomials."""

    def __init__(self, form: str, control):
        self.form = form
        self.exact = control
        self.control = ref.to_float(control)
        self.polys = [ref.patch_polynomials(form, control[n]) for n in range(control.shape[0])]

    def values(self, uv_per_patch, du=0, dv=0) -> np.ndarray:
        """Exact values (rounded once) at uv_per_patch[n] = list of (u, v)."""
        out = []
        for polys, uvs in zip(self.polys, uv_per_patch, strict=True):
            derived = ref.derivative(polys, du, dv)
            out.append([[float(x) for x in ref.evaluate(derived, a, b)] for a, b in uvs])
        return np.array(out, dtype=float).reshape(len(self.polys), len(uv_per_patch[0]), 3)


@pytest.fixture(scope="module", params=FORMS)
def reference(request):
    rng = np.random.default_rng({"hermite": 11, "bezier": 12, "bspline": 13}[request.param])
    return Reference(request.param, ref.random_rationals(rng, (3, 4, 4, 3)))


def assert_close_to_exact(got, exact, scale, rel=EVAL_REL):
    """|got − exact| ≤ rel·S per component; and the plain norm-wise relative error ≤ rel wherever
    the exact value is not the result of heavy cancellation (|p| ≥ |S|/1000 — there ≤ 45 eps·S would
    allow up to 1000× more than 1e-14 of |p|, so the S-based bound is the meaningful one)."""
    err = np.abs(got - exact)
    assert np.all(err <= rel * scale + UNDERFLOW), (
        f"worst error {np.max(err / (scale + UNDERFLOW)) / EPS:.1f} eps·S"
    )
    size = np.linalg.norm(exact, axis=-1)
    plain = size >= np.linalg.norm(scale, axis=-1) / 1000
    assert np.all(np.linalg.norm(got - exact, axis=-1)[plain] <= rel * size[plain])


def abs_conversion(source, target):
    return np.abs(np.array(ref.conversion_matrix(source, target).tolist(), dtype=float))


def abs_convert(source, target, abs_net):
    """|C| N |C|^T: the magnitude of the terms of P' = C P C^T (N = |P| or a bound on it)."""
    C = abs_conversion(source, target)
    return np.einsum("ik,nkld,jl->nijd", C, abs_net, C)


def abs_hs_net(N):
    """Magnitude bound of a Hermite net after hs_twists: each twist sums 8 boundary vectors (±1)."""
    out = N.copy()
    corners = N[:, 0, 0] + N[:, 0, 1] + N[:, 1, 0] + N[:, 1, 1]
    for a, b in itertools.product((0, 1), repeat=2):
        out[:, 2 + a, 2 + b] = (
            corners + N[:, 2 + a, 1] + N[:, 2 + a, 0] + N[:, 1, 2 + b] + N[:, 0, 2 + b]
        )
    return out


def closure_abs(N):
    """Σ |coefficient|·N over the 12 terms of C (4 per corner point, 1 per tangent)."""
    return (
        4 * N[:, :2, :2].sum(axis=(1, 2))
        + N[:, 2:, :2].sum(axis=(1, 2))
        + N[:, :2, 2:].sum(axis=(1, 2))
    )


def diagonal_scale(form, N):
    """|[t^k] D|, |[t^k] E| ≤ Σ_ij |A_ij|·3 with |A| ≤ |M|^T N |M| (binomials of (1−t)^m ≤ 3)."""
    abs_m = np.abs(np.array(ref.basis_matrix(form).tolist(), dtype=float))
    return 3 * np.einsum("ip,nijd,jq->nd", abs_m, N, abs_m)


# ------------------------------------------------------------- evaluation vs sympy
@pytest.mark.parametrize("form", FORMS)
def test_reference_is_the_tensor_product_of_its_basis(form):
    # The reference evaluates u^T M^T X M v (eq. 3 literally for Hermite); cross-check it against
    # Σ b_i(u) X_ij b_j(v) — for Hermite with the cubics solved from the interpolation conditions.
    X = sp.Matrix(4, 4, sp.symbols("x0:16"))
    H = ref.hermite_basis_from_conditions() if form == "hermite" else ref.basis_polynomials(form)
    polys = ref.patch_polynomials(form, np.array(X.tolist(), dtype=object)[..., None])
    tensor = sum(
        H[i].subs(ref.t, ref.u) * X[i, j] * H[j].subs(ref.t, ref.v)
        for i in range(4)
        for j in range(4)
    )
    assert sp.expand(polys[0].as_expr() - tensor) == 0


@pytest.mark.parametrize("du,dv", DERIVATIVES)
def test_evaluate_shared_parameters(reference, du, dv):
    patches = PatchSet(reference.control, reference.form)
    uv = floats(UV)
    got = patches.evaluate(uv, du, dv)
    assert got.shape == (3, len(UV), 3)
    exact = reference.values([UV] * 3, du, dv)
    assert_close_to_exact(
        got, exact, ref.abs_patch_sum(reference.form, reference.control, uv, du, dv)
    )
    if du >= 4 or dv >= 4:
        assert not got.any()


@pytest.mark.parametrize("du,dv", [(0, 0), (1, 0), (0, 1), (1, 1), (2, 1), (3, 3)])
def test_evaluate_per_patch_parameters(reference, du, dv):
    patches = PatchSet(reference.control, reference.form)
    per_patch = [UV[n:] + UV[:n] for n in range(3)]  # a different order for each patch
    uv = np.stack([floats(p) for p in per_patch])
    got = patches.evaluate(uv, du, dv)
    assert got.shape == (3, len(UV), 3)
    exact = reference.values(per_patch, du, dv)
    assert_close_to_exact(
        got, exact, ref.abs_patch_sum(reference.form, reference.control, uv, du, dv)
    )


@pytest.mark.parametrize("du,dv", [(0, 0), (1, 0), (0, 1), (1, 1), (2, 0), (0, 2), (3, 2)])
def test_evaluate_grid(reference, du, dv):
    patches = PatchSet(reference.control, reference.form)
    got = patches.evaluate_grid(floats(GRID_U), floats(GRID_V), du, dv)
    assert got.shape == (3, len(GRID_U), len(GRID_V), 3)
    assert got.flags.c_contiguous and got.dtype == np.float64
    pairs = list(itertools.product(GRID_U, GRID_V))  # u slow, v fast = grid order
    exact = reference.values([pairs] * 3, du, dv).reshape(got.shape)
    scale = ref.abs_patch_sum(reference.form, reference.control, floats(pairs), du, dv).reshape(
        got.shape
    )
    assert_close_to_exact(got, exact, scale)


def test_evaluate_grid_square_and_resolution(reference):
    patches = PatchSet(reference.control, reference.form)
    u = floats(GRID_U)
    square = patches.evaluate_grid(u)
    assert square.shape == (3, 5, 5, 3)
    pairs = list(itertools.product(GRID_U, GRID_U))
    scale = ref.abs_patch_sum(reference.form, reference.control, floats(pairs)).reshape(
        square.shape
    )
    assert_close_to_exact(square, reference.values([pairs] * 3).reshape(square.shape), scale)
    # grid(G) is the uniform G×G grid including both borders
    grid = patches.grid(9)
    assert grid.shape == (3, 9, 9, 3)
    lin = [R(k, 8) for k in range(9)]
    pairs = list(itertools.product(lin, lin))
    scale = ref.abs_patch_sum(reference.form, reference.control, floats(pairs)).reshape(grid.shape)
    assert_close_to_exact(grid, reference.values([pairs] * 3).reshape(grid.shape), scale)


def test_tangents_twist_corners_are_the_derivatives(reference):
    patches = PatchSet(reference.control, reference.form)
    uv = floats(UV)
    p_u, p_v = patches.tangents(uv)
    for got, (du, dv) in ((p_u, (1, 0)), (p_v, (0, 1)), (patches.twist(uv), (1, 1))):
        assert_close_to_exact(
            got,
            reference.values([UV] * 3, du, dv),
            ref.abs_patch_sum(reference.form, reference.control, uv, du, dv),
        )
    corners = [(R(0), R(0)), (R(1), R(0)), (R(1), R(1)), (R(0), R(1))]
    np.testing.assert_array_equal(CORNER_PARAMETERS, floats(corners))
    assert_close_to_exact(
        patches.corners(),
        reference.values([corners] * 3),
        ref.abs_patch_sum(reference.form, reference.control, CORNER_PARAMETERS),
    )


def exact_unit_normals(reference, uv_per_patch):
    """n = p_u × p_v / |p_u × p_v| from the exact derivatives, normalised to 30 digits."""
    out = []
    for polys, uvs in zip(reference.polys, uv_per_patch, strict=True):
        pu_polys, pv_polys = ref.derivative(polys, 1, 0), ref.derivative(polys, 0, 1)
        row = []
        for a, b in uvs:
            cross = sp.Matrix(ref.evaluate(pu_polys, a, b)).cross(
                sp.Matrix(ref.evaluate(pv_polys, a, b))
            )
            norm = sp.sqrt(cross.dot(cross))
            row.append([float(sp.N(c / norm, 30)) for c in cross])
        out.append(row)
    return np.array(out)


def normal_tolerance(reference, uv):
    """|n̂ − n| ≤ 2|δc|/|c| + 3 eps with c = p_u × p_v and
    |δc| ≤ e_u |p_v| + |p_u| e_v + e_u e_v + 2γ_2 |p_u||p_v|  (e_* = EVAL_REL·|S_*|, the derivative
    bounds); the final normalisation (norm, divide) adds ≤ 2 eps and the reference's rounding 0.5
    eps."""
    patches = PatchSet(reference.control, reference.form)
    p_u, p_v = patches.tangents(uv)
    e_u = np.linalg.norm(
        EVAL_REL * ref.abs_patch_sum(reference.form, reference.control, uv, 1, 0), axis=-1
    )
    e_v = np.linalg.norm(
        EVAL_REL * ref.abs_patch_sum(reference.form, reference.control, uv, 0, 1), axis=-1
    )
    n_u, n_v = np.linalg.norm(p_u, axis=-1), np.linalg.norm(p_v, axis=-1)
    c = np.linalg.norm(np.cross(p_u, p_v), axis=-1)
    delta = e_u * n_v + n_u * e_v + e_u * e_v + 2 * EPS * n_u * n_v
    return 2 * delta / c + 3 * EPS


def test_normals_match_sympy(reference):
    patches = PatchSet(reference.control, reference.form)
    uv = floats(UV)
    got = patches.normals(uv)
    assert got.shape == (3, len(UV), 3)
    exact = exact_unit_normals(reference, [UV] * 3)
    err = np.linalg.norm(got - exact, axis=-1)
    assert np.all(err <= normal_tolerance(reference, uv))
    np.testing.assert_allclose(np.linalg.norm(got, axis=-1), 1.0, rtol=0, atol=4 * EPS)


def test_normals_grid_match_sympy(reference):
    patches = PatchSet(reference.control, reference.form)
    got = patches.normals_grid(floats(GRID_U), floats(GRID_V))
    assert got.shape == (3, len(GRID_U), len(GRID_V), 3)
    pairs = list(itertools.product(GRID_U, GRID_V))
    exact = exact_unit_normals(reference, [pairs] * 3).reshape(got.shape)
    tol = normal_tolerance(reference, floats(pairs)).reshape(got.shape[:-1])
    assert np.all(np.linalg.norm(got - exact, axis=-1) <= tol)


@pytest.mark.parametrize("form", FORMS)
def test_normals_are_zero_not_nan_on_a_collapsed_edge(form):
    rng = np.random.default_rng(7)
    bezier = rng.normal(size=(2, 4, 4, 3))
    # v = 0 edge collapsed to the origin: p_u(u, 0) = Σ b_i'(u)·0 = 0 exactly in Bézier and Hermite
    # form (the Hermite net's v = 0 row is C·0 = 0 exactly). In B-spline form the edge is not
    # exactly representable; there, only finiteness is required. (Collapsed to a point other than
    # the origin, Σ b_i'(u) rounds to ±tiny and the "normal" is a unit vector of rounding noise.)
    bezier[:, :, 0] = 0.0
    patches = PatchSet(bezier, "bezier").convert(form)
    uv = np.array([[0.0, 0.0], [0.5, 0.0], [1.0, 0.0], [0.3, 0.0]])
    normals, grid = patches.normals(uv), patches.normals_grid([0.0, 0.3, 0.5, 1.0], [0.0, 0.5])
    assert np.isfinite(normals).all() and np.isfinite(grid).all()
    if form != "bspline":
        np.testing.assert_array_equal(normals, 0.0)
        np.testing.assert_array_equal(grid[:, :, 0], 0.0)
        np.testing.assert_allclose(
            np.linalg.norm(grid[:, :, 1], axis=-1), 1.0, rtol=0, atol=4 * EPS
        )


# ------------------------------------------------------------------ Hermite layout
def test_hermite_layout_is_the_papers_eq_4():
    """Corners → X[0:2, 0:2], p_u → X[2:4, 0:2], p_v → X[0:2, 2:4], p_uv → X[2:4, 2:4], exactly."""
    rng = np.random.default_rng(8)
    X = rng.normal(size=(4, 4, 4, 3)) * 10.0 ** rng.integers(-3, 4, size=(4, 1, 1, 1))
    patches = PatchSet(X, "hermite")
    ab = np.array([[a, b] for a in (0.0, 1.0) for b in (0.0, 1.0)])  # (a, b) ↦ X[a, b]
    for (du, dv), (rows, cols) in {
        (0, 0): (slice(0, 2), slice(0, 2)),
        (1, 0): (slice(2, 4), slice(0, 2)),
        (0, 1): (slice(0, 2), slice(2, 4)),
        (1, 1): (slice(2, 4), slice(2, 4)),
    }.items():
        np.testing.assert_array_equal(
            patches.evaluate(ab, du, dv), X[:, rows, cols].reshape(4, 4, 3)
        )
        np.testing.assert_array_equal(
            patches.evaluate_grid([0.0, 1.0], [0.0, 1.0], du, dv), X[:, rows, cols]
        )
    np.testing.assert_array_equal(patches.corners(), X[:, [0, 1, 1, 0], [0, 0, 1, 1]])


# -------------------------------------------------------------------- conversions
def conversion_scale(source, target, control, uv):
    """Bound on the magnitude of the sums for P' = C P C^T evaluated in ``target`` vs P in
    ``source``: S = Σ_ij B^T_i(u) (|C| |P| |C|^T)_ij B^T_j(v) + Σ_ij B^S_i(u) |P_ij| B^S_j(v).
    Converting is a 16-term sum of products with rounded C (≤ ~γ_9 |C||P||C|^T); evaluating each
    form errs by ≤ ~16 eps of its own S. |C||P||C|^T carries the conditioning of the conversion."""
    abs_c = np.abs(np.array(ref.conversion_matrix(source, target).tolist(), dtype=float))
    converted = np.einsum("ik,nkld,jl->nijd", abs_c, np.abs(control), abs_c)
    return (
        ref.abs_patch_sum(target, converted, uv)
        + ref.abs_patch_sum(source, control, uv)
        + UNDERFLOW
    )


FINITE = st.floats(-1e6, 1e6, allow_nan=False, allow_infinity=False, allow_subnormal=False)
UNIT = st.floats(0.0, 1.0, allow_nan=False, allow_subnormal=False)
PATCH_CONTROL = arrays(
    np.float64, st.tuples(st.integers(1, 3), st.just(4), st.just(4), st.just(3)), elements=FINITE
)
UV_PARAMS = arrays(np.float64, st.tuples(st.integers(1, 5), st.just(2)), elements=UNIT)


@settings(deadline=None, max_examples=60)
@given(
    control=PATCH_CONTROL,
    uv=UV_PARAMS,
    source=st.sampled_from(FORMS),
    target=st.sampled_from(FORMS),
)
def test_conversion_keeps_the_surface(control, uv, source, target):
    patches = PatchSet(control, source)
    converted = patches.convert(target)
    assert converted.form == target and converted.control.shape == control.shape
    err = np.abs(converted.evaluate(uv) - patches.evaluate(uv))
    assert np.all(err <= 4 * EPS * conversion_scale(source, target, control, uv))


@settings(deadline=None, max_examples=80)
@given(
    control=PATCH_CONTROL,
    uv=UV_PARAMS,
    start=st.sampled_from(FORMS),
    via=st.lists(st.sampled_from(FORMS), min_size=1, max_size=2),
)
def test_round_trips_keep_the_surface(control, uv, start, via):
    """start → via… → start (A → B → A, A → B → C → A): control values and points come back up to
    4 eps × the magnitudes composed along the path (Skeel-style: |C_n|…|C_1| |P| (…)^T)."""
    path = [start, *via, start]
    patches = PatchSet(control, start)
    back = patches
    for target in path[1:]:
        back = back.convert(target)
    assert back.form == start
    abs_chain = np.eye(4)
    scale_points = ref.abs_patch_sum(start, control, uv)
    current = np.abs(control)
    for source, target in itertools.pairwise(path):
        step = abs_conversion(source, target)
        abs_chain = step @ abs_chain
        current = np.einsum("ik,nkld,jl->nijd", step, current, step)
        scale_points = scale_points + ref.abs_patch_sum(target, current, uv)
    bound = (
        4 * EPS * np.einsum("ik,nkld,jl->nijd", abs_chain, np.abs(control), abs_chain) + UNDERFLOW
    )
    assert np.all(np.abs(back.control - control) <= bound)
    assert np.all(
        np.abs(back.evaluate(uv) - patches.evaluate(uv)) <= 4 * EPS * scale_points + UNDERFLOW
    )


def test_convert_same_form_is_identity_and_uses_exact_matrices(reference):
    patches = PatchSet(reference.control, reference.form)
    assert patches.convert(reference.form) is patches
    for target in FORMS:
        C = conversion_matrix(reference.form, target)
        expected = np.einsum("ik,nkld,jl->nijd", C, reference.control, C)
        abs_c = np.abs(C)
        scale = np.einsum("ik,nkld,jl->nijd", abs_c, np.abs(reference.control), abs_c)
        assert np.all(np.abs(patches.convert(target).control - expected) <= 8 * EPS * scale)


@pytest.mark.parametrize("target", FORMS)
def test_converted_rational_patches_match_sympy(reference, target):
    """The converted patch is the same polynomial: compare with the exact source at rational (u,
    v)."""
    converted = PatchSet(reference.control, reference.form).convert(target)
    uv = floats(UV)
    got = converted.evaluate(uv, 1, 1)
    exact = reference.values([UV] * 3, 1, 1)
    # converting errs by ≤ ~γ_9 of |C||P||C|^T, evaluating by ≤ 16 eps of its own S: the sum of the
    # two S (converted net, source net) times EVAL_REL bounds it with margin.
    converted_abs = abs_convert(reference.form, target, np.abs(reference.control))
    scale = ref.abs_patch_sum(target, converted_abs, uv, 1, 1) + ref.abs_patch_sum(
        reference.form, reference.control, uv, 1, 1
    )
    assert_close_to_exact(got, exact, scale)


# ---------------------------------------------------------------- boundary curves
EDGE_PARAMETERS = [  # edge k runs corner k → k+1: (u(t), v(t))
    (ref.t, 0),
    (1, ref.t),
    (1 - ref.t, 1),
    (0, 1 - ref.t),
]


def test_boundary_curves_match_sympy_restrictions(reference):
    patches = PatchSet(reference.control, reference.form)
    curves = patches.boundary_curves()
    assert curves.batch_shape == (3, 4) and curves.form == reference.form and curves.dim == 3
    got = curves.power_coefficients()  # (3, 4, 4 powers, 3)
    for n, k in itertools.product(range(3), range(4)):
        uu, vv = EDGE_PARAMETERS[k]
        exact = np.array(
            [
                [float(c) for c in ref.coefficients(e, 3)]
                for e in ref.restrict(reference.polys[n], uu, vv)
            ]
        ).T
        # boundary control c_i = Σ_j b_j(end) P_ij (|b_j(end)| ≤ 1; ≤ 3 eps with the rounded 1/6,
        # 4/6),
        # then coefficient p = Σ_i c_i M[i, 3-p] (≤ γ_4 = 2 eps): ≤ 5 eps·colsum|M|·max_i Σ_j |P|,
        # plus
        # the reference's rounding; asserted with 8 eps.
        abs_m = np.abs(np.array(ref.basis_matrix(reference.form).tolist(), dtype=float))
        net = np.abs(reference.control[n])
        lines = np.maximum(
            net.sum(axis=0).max(axis=0), net.sum(axis=1).max(axis=0)
        )  # per coordinate
        magnitude = abs_m.sum(axis=0)[::-1, None] * lines[None, :]
        assert np.all(np.abs(got[n, k] - exact) <= 8 * EPS * magnitude), (n, k)


@pytest.mark.parametrize("form", FORMS)
def test_boundary_curves_are_the_patch_restricted_to_its_edges(form):
    rng = np.random.default_rng(9)
    patches = PatchSet(rng.normal(size=(4, 4, 4, 3)), form)
    curves = patches.boundary_curves()
    t = np.arange(17) / 16.0  # 1 − t exact
    on_patch = {
        0: np.stack([t, 0 * t], -1),
        1: np.stack([1 + 0 * t, t], -1),
        2: np.stack([1 - t, 1 + 0 * t], -1),
        3: np.stack([0 * t, 1 - t], -1),
    }
    along = curves.evaluate(t)  # (4, 4 edges, 17, 3)
    for k, uv in on_patch.items():
        expected = patches.evaluate(uv)
        # boundary control Σ_j b_j(end) P_ij (≤ 3 eps), curve evaluation (≤ 8 eps of Σ B_i |c_i|,
        # and
        # Σ B_i |c_i| ≤ S since B_j(end) = |b_j(end)|), patch evaluation (≤ 16 eps S): ≤ 27 eps S.
        scale = ref.abs_patch_sum(form, patches.control, uv)
        assert np.all(np.abs(along[:, k] - expected) <= EVAL_REL * scale), k
    # CCW: edge k starts at corner k and ends at corner k+1
    corners = patches.corners()
    start, end = curves.evaluate([0.0, 1.0]).transpose(2, 0, 1, 3)
    scale = ref.abs_patch_sum(form, patches.control, CORNER_PARAMETERS)
    assert np.all(np.abs(start - corners) <= EVAL_REL * scale)
    assert np.all(
        np.abs(end - np.roll(corners, -1, axis=1))
        <= EVAL_REL * (scale + np.roll(scale, -1, axis=1))
    )
    if form != "bspline":  # integer basis values at the ends: exact
        np.testing.assert_array_equal(start, corners)
        np.testing.assert_array_equal(end, np.roll(corners, -1, axis=1))


def test_boundary_curves_control_is_exact_for_hermite_and_bezier():
    rng = np.random.default_rng(10)
    X = rng.normal(size=(3, 4, 4, 3))
    hermite = PatchSet(X, "hermite").boundary_curves().control
    flip = np.array([1, 1, -1, -1])[:, None]
    np.testing.assert_array_equal(hermite[:, 0], X[:, :, 0])  # v = 0: [p00, p10, pu00, pu10]
    np.testing.assert_array_equal(hermite[:, 1], X[:, 1, :])  # u = 1: [p10, p11, pv10, pv11]
    np.testing.assert_array_equal(hermite[:, 2], X[:, [1, 0, 3, 2], 1] * flip)  # v = 1 reversed
    np.testing.assert_array_equal(hermite[:, 3], X[:, 0, [1, 0, 3, 2]] * flip)  # u = 0 reversed
    bezier = PatchSet(X, "bezier").boundary_curves().control
    np.testing.assert_array_equal(bezier[:, 0], X[:, :, 0])
    np.testing.assert_array_equal(bezier[:, 1], X[:, 3, :])
    np.testing.assert_array_equal(bezier[:, 2], X[:, ::-1, 3])
    np.testing.assert_array_equal(bezier[:, 3], X[:, 0, ::-1])


@pytest.mark.parametrize("form", FORMS)
def test_boundary_reversed_is_exact(form):
    rng = np.random.default_rng(11)
    curves = PatchSet(rng.normal(size=(2, 4, 4, 3)), form).boundary_curves()
    np.testing.assert_array_equal(curves.reversed().reversed().control, curves.control)


# ---------------------------------------------------------------------- diagonals
def exact_diagonals(polys):
    D = [ref.coefficients(e) for e in ref.restrict(polys, ref.t, ref.t)]
    E = [ref.coefficients(e) for e in ref.restrict(polys, ref.t, 1 - ref.t)]
    return np.array(D, dtype=object).T, np.array(E, dtype=object).T  # (7, 3)


def test_diagonal_polynomials_match_sympy(reference):
    patches = PatchSet(reference.control, reference.form)
    D, E = patches.diagonal_polynomials()
    assert D.shape == E.shape == (3, 7, 3)
    scale = diagonal_scale(reference.form, np.abs(reference.control))[:, None, :]
    for n in range(3):
        exact_D, exact_E = exact_diagonals(reference.polys[n])
        # A = M^T P M (≤ γ_9) then ≤ 16 accumulations with binomial weights (≤ γ_16): ≤ 13 eps·scale
        assert np.all(np.abs(D[n] - ref.to_float(exact_D)) <= 16 * EPS * scale[n])
        assert np.all(np.abs(E[n] - ref.to_float(exact_E)) <= 16 * EPS * scale[n])


def random_integer_hermite(seed, n=4, low=-20, high=21):
    return np.random.default_rng(seed).integers(low, high, size=(n, 4, 4, 3)).astype(float)


def test_hermite_diagonals_are_exact_for_integer_data():
    """Integer control: every float operation is exact, so the coefficients equal sympy's
    exactly."""
    X = random_integer_hermite(12)
    D, E = PatchSet(X, "hermite").diagonal_polynomials()
    for n in range(len(X)):
        exact_D, exact_E = exact_diagonals(
            ref.patch_polynomials("hermite", X[n].astype(int).astype(object))
        )
        np.testing.assert_array_equal(D[n], ref.to_float(exact_D))
        np.testing.assert_array_equal(E[n], ref.to_float(exact_E))


@pytest.mark.parametrize("form", FORMS)
def test_generic_patch_has_degree_six_diagonals(form):
    X = random_integer_hermite(13, n=8)
    D, E = PatchSet(X, "hermite").convert(form).diagonal_polynomials()
    np.testing.assert_array_equal(polynomial_degree(D), 6)
    np.testing.assert_array_equal(polynomial_degree(E), 6)
    for n in range(2):
        exact_D, exact_E = exact_diagonals(
            ref.patch_polynomials("hermite", X[n].astype(int).astype(object))
        )
        assert all(ref.exact_degree(list(exact_D[:, d])) == 6 for d in range(3))
        assert all(ref.exact_degree(list(exact_E[:, d])) == 6 for d in range(3))


# ------------------------------------------------ S-/HS-patch, Coons, closure C
def coons_reference(X_int):
    """Sympy Coons patch of the four boundary curves of the Hermite patch X (integers)."""
    return ref.coons_patch(ref.patch_polynomials("hermite", X_int.astype(int).astype(object)))


def test_coons_identity_symbolically():
    """Re-derive the S-/HS-patch in sympy (one coordinate, 16 symbols):
    the Coons patch of the four Hermite boundary cubics is the bicubic Hermite patch with the same
    12 boundary vectors and twists δ + [p_u(a,1) − p_u(a,0)] + [p_v(1,b) − p_v(0,b)]; its diagonal
    and anti-diagonal have no t^6, t^5 terms and t^4 coefficients +C and −C."""
    X = sp.Matrix(4, 4, sp.symbols("x0:16"))
    patch = ref.patch_polynomials("hermite", np.array(X.tolist(), dtype=object)[..., None])
    coons = ref.coons_patch(patch)[0].as_expr()
    u, v = ref.u, ref.v
    for a, b in itertools.product((0, 1), repeat=2):
        at = {u: a, v: b}
        assert sp.expand(coons.subs(at) - X[a, b]) == 0
        assert sp.expand(sp.diff(coons, u).subs(at) - X[2 + a, b]) == 0
        assert sp.expand(sp.diff(coons, v).subs(at) - X[a, 2 + b]) == 0
        delta = X[0, 1] + X[1, 0] - X[0, 0] - X[1, 1]
        twist = delta + (X[2 + a, 1] - X[2 + a, 0]) + (X[1, 2 + b] - X[0, 2 + b])
        assert sp.expand(sp.diff(coons, u, v).subs(at) - twist) == 0
    # The Coons patch is bicubic: with those twists it *is* the Hermite patch.
    hs = X.copy()
    for a, b in itertools.product((0, 1), repeat=2):
        hs[2 + a, 2 + b] = sp.diff(coons, u, v).subs({u: a, v: b})
    hs_patch = ref.patch_polynomials("hermite", np.array(hs.tolist(), dtype=object)[..., None])[0]
    assert sp.expand(hs_patch.as_expr() - coons) == 0
    # Diagonals.
    delta = X[0, 1] + X[1, 0] - X[0, 0] - X[1, 1]
    C = (
        4 * delta
        + (X[2, 1] + X[3, 1] - X[2, 0] - X[3, 0])
        + (X[1, 2] + X[1, 3] - X[0, 2] - X[0, 3])
    )
    D = sp.Poly(sp.expand(coons.subs({u: ref.t, v: ref.t})), ref.t)
    E = sp.Poly(sp.expand(coons.subs({u: ref.t, v: 1 - ref.t}, simultaneous=True)), ref.t)
    assert D.degree() <= 4 and E.degree() <= 4
    assert sp.expand(D.coeff_monomial(ref.t**4) - C) == 0
    assert sp.expand(E.coeff_monomial(ref.t**4) + C) == 0


def test_hs_twists_equal_sympy_coons_twists_exactly():
    X = random_integer_hermite(14)
    twists = hs_twists(X)
    assert twists.shape == (4, 2, 2, 3)
    for n in range(len(X)):
        coons = coons_reference(X[n])
        for a, b in itertools.product((0, 1), repeat=2):
            expected = [float(x) for x in ref.evaluate(ref.derivative(coons, 1, 1), a, b)]
            np.testing.assert_array_equal(twists[n, a, b], expected)
    # unbatched input works too
    np.testing.assert_array_equal(hs_twists(X[0]), twists[0])


@pytest.mark.parametrize("form", FORMS)
def test_hs_patch_is_the_coons_patch_of_its_boundary(form):
    X = random_integer_hermite(15, n=3)
    patches = PatchSet(X, "hermite").convert(form)
    hs = patches.with_coons_twists()
    assert hs.form == form and hs.control.shape == patches.control.shape
    # Magnitudes along with_coons_twists: X → form (F0) → Hermite (N1) → twists (H) → form (F).
    # Each conversion errs by ≤ ~4 eps of its |C| N |C|^T, each twist sum by ≤ 4 eps of its 8 terms;
    # propagated through the |C| these stay ≤ 16 eps of F, plus ≤ 16 eps·S_F to evaluate: ≤ 45
    # eps·S_F.
    F0 = abs_convert("hermite", form, np.abs(X))
    F = abs_convert("hermite", form, abs_hs_net(abs_convert(form, "hermite", F0)))
    uv = floats(UV)
    exact = np.array(
        [
            [[float(x) for x in ref.evaluate(coons_reference(X[n]), a, b)] for a, b in UV]
            for n in range(3)
        ]
    )
    assert_close_to_exact(hs.evaluate(uv), exact, ref.abs_patch_sum(form, F, uv))
    # The boundary does not change.
    t = np.arange(9) / 8.0
    edges = np.concatenate(
        [
            np.stack([t, 0 * t], -1),
            np.stack([1 + 0 * t, t], -1),
            np.stack([t, 1 + 0 * t], -1),
            np.stack([0 * t, t], -1),
        ]
    )
    scale = ref.abs_patch_sum(form, F, edges) + ref.abs_patch_sum(form, F0, edges)
    assert np.all(np.abs(hs.evaluate(edges) - patches.evaluate(edges)) <= EVAL_REL * scale)


def test_hermite_hs_patch_power_form_is_exactly_coons():
    X = random_integer_hermite(16)
    A = PatchSet(X, "hermite").with_coons_twists().power_coefficients()
    for n in range(len(X)):
        coons = coons_reference(X[n])
        exact = np.array(
            [
                [
                    [float(p.coeff_monomial(ref.u ** (3 - i) * ref.v ** (3 - j))) for p in coons]
                    for j in range(4)
                ]
                for i in range(4)
            ]
        )
        np.testing.assert_array_equal(A[n], exact)
    # a33 = a32 = a23 = a22 = 0 (skala-patches.md A.2)
    assert not A[:, :2, :2].any()


def test_closure_is_the_t4_coefficient_of_the_coons_diagonals():
    X = random_integer_hermite(17, n=6)
    C = closure(X)
    assert C.shape == (6, 3)
    np.testing.assert_array_equal(PatchSet(X, "hermite").closure(), C)
    hs = PatchSet(X, "hermite").with_coons_twists()
    D, E = hs.diagonal_polynomials()
    np.testing.assert_array_equal(D[:, 4], C)
    np.testing.assert_array_equal(E[:, 4], -C)
    assert not D[:, 5:].any() and not E[:, 5:].any()
    assert np.all(np.linalg.norm(C, axis=-1) > 0)  # generic data: C ≠ 0
    np.testing.assert_array_equal(polynomial_degree(D), 4)
    np.testing.assert_array_equal(polynomial_degree(E), 4)
    for n in range(2):
        exact_D, exact_E = exact_diagonals(coons_reference(X[n]))
        np.testing.assert_array_equal(ref.to_float(exact_D[4]), C[n])
        np.testing.assert_array_equal(ref.to_float(exact_E[4]), -C[n])
        assert not any(exact_D[5:].ravel()) and not any(exact_E[5:].ravel())


@pytest.mark.parametrize("form", FORMS)
def test_closure_and_hs_degree_in_every_form(form):
    X = random_integer_hermite(18, n=5)
    patches = PatchSet(X, "hermite").convert(form)
    C = closure(X)
    # closure() converts back to Hermite: entries err by ≤ 4 eps of N1 = |C_fh||C_hf||X|..., then
    # the
    # 12-term closure sum adds ≤ γ_12 = 6 eps of closure_abs: ≤ 10 eps·closure_abs(N1).
    N1 = abs_convert(form, "hermite", abs_convert("hermite", form, np.abs(X)))
    assert np.all(np.abs(patches.closure() - C) <= 12 * EPS * closure_abs(N1))
    D, E = patches.with_coons_twists().diagonal_polynomials()
    np.testing.assert_array_equal(polynomial_degree(D), 4)
    np.testing.assert_array_equal(polynomial_degree(E), 4)
    # HS net in this form errs by ≤ 16 eps of F (see the Coons test), the power form and the
    # diagonal
    # sums by ≤ 16 eps of the diagonal scale: ≤ 32 eps·diagonal_scale(F).
    F = abs_convert("hermite", form, abs_hs_net(N1))
    assert np.all(np.abs(D[:, 4] - C) <= 32 * EPS * diagonal_scale(form, F))
    assert np.all(np.abs(E[:, 4] + C) <= 32 * EPS * diagonal_scale(form, F))


def test_moving_one_tangent_by_minus_c_makes_both_diagonals_cubic():
    """skala-patches.md A.3 (ii): p_u(1,1) −= C; C enters with coefficient +1, so the new C is 0."""
    X = random_integer_hermite(19, n=5)
    assert np.all(np.linalg.norm(closure(X), axis=-1) > 0)
    X[:, 3, 1] -= closure(X)  # X[3, 1] = p_u(1, 1)
    np.testing.assert_array_equal(closure(X), 0.0)
    hs = PatchSet(X, "hermite").with_coons_twists()
    D, E = hs.diagonal_polynomials()
    np.testing.assert_array_equal(polynomial_degree(D), 3)
    np.testing.assert_array_equal(polynomial_degree(E), 3)
    for n in range(2):
        exact_D, exact_E = exact_diagonals(coons_reference(X[n]))
        assert max(ref.exact_degree(list(exact_D[:, d])) for d in range(3)) == 3
        assert max(ref.exact_degree(list(exact_E[:, d])) for d in range(3)) == 3


# The symmetric cube example (skala-patches.md A.6): 6 faces of [−1, 1]^3, counter-clockwise seen
# from outside; corner normals are the vertices; corner tangents are the edge chords projected into
# the tangent plane, t' = t − (n·t)/(n·n) n, scaled by λ.
CUBE_FACES = [
    [(-1, -1, 1), (1, -1, 1), (1, 1, 1), (-1, 1, 1)],  # +z
    [(-1, -1, -1), (-1, 1, -1), (1, 1, -1), (1, -1, -1)],  # −z
    [(1, -1, -1), (1, 1, -1), (1, 1, 1), (1, -1, 1)],  # +x
    [(-1, -1, -1), (-1, -1, 1), (-1, 1, 1), (-1, 1, -1)],  # −x
    [(-1, 1, -1), (-1, 1, 1), (1, 1, 1), (1, 1, -1)],  # +y
    [(-1, -1, -1), (1, -1, -1), (1, -1, 1), (-1, -1, 1)],  # −y
]


def cube_hermite(lam):
    """Hermite nets (6, 4, 4, 3) as Fractions; zero twists."""
    X = np.full((6, 4, 4, 3), Fraction(0), dtype=object)
    for f, face in enumerate(CUBE_FACES):
        P = {(0, 0): face[0], (1, 0): face[1], (1, 1): face[2], (0, 1): face[3]}
        P = {k: np.array([Fraction(c) for c in p], dtype=object) for k, p in P.items()}

        def project(chord, n):
            return chord - (chord @ n) / (n @ n) * n

        for a, b in itertools.product((0, 1), repeat=2):
            n = P[a, b]
            X[f, a, b] = P[a, b]
            X[f, 2 + a, b] = lam * project(P[1, b] - P[0, b], n)
            X[f, a, 2 + b] = lam * project(P[a, 1] - P[a, 0], n)
    return X


def test_cube_example_has_zero_closure_and_cubic_diagonals():
    X = cube_hermite(Fraction(3, 2))  # λ = 3/2 makes every tangent an integer vector: all exact
    Xf = ref.to_float(X)
    np.testing.assert_array_equal(Xf, np.round(Xf))
    # eq. (13): every tangent at a corner is orthogonal to the corner normal
    for f, a, b in itertools.product(range(6), (0, 1), (0, 1)):
        n = Xf[f, a, b]
        assert Xf[f, 2 + a, b] @ n == 0 and Xf[f, a, 2 + b] @ n == 0
    np.testing.assert_array_equal(closure(Xf), 0.0)
    hs = PatchSet(Xf, "hermite").with_coons_twists()
    D, E = hs.diagonal_polynomials()
    np.testing.assert_array_equal(polynomial_degree(D), 3)
    np.testing.assert_array_equal(polynomial_degree(E), 3)
    for f in range(6):
        exact_D, exact_E = exact_diagonals(ref.coons_patch(ref.patch_polynomials("hermite", X[f])))
        assert max(ref.exact_degree(list(exact_D[:, d])) for d in range(3)) == 3
        assert max(ref.exact_degree(list(exact_E[:, d])) for d in range(3)) == 3
    # the corner normals are the outward vertex directions
    normals = hs.normals(CORNER_PARAMETERS)
    vertices = np.array(CUBE_FACES, dtype=float) / np.sqrt(3.0)
    assert np.all(np.abs(normals - vertices) <= 4 * EPS)


def test_cube_example_with_irrational_scale_and_a_moved_tangent():
    lam = 2.19
    X = ref.to_float(cube_hermite(Fraction(1)))
    X[:, 2:, :2] *= lam
    X[:, :2, 2:] *= lam
    # C = 0 by symmetry; in floats the 12-term sum errs by ≤ γ_12 closure_abs (+ λ·t rounding).
    assert np.all(np.abs(closure(X)) <= 8 * EPS * closure_abs(np.abs(X)))
    # Break the symmetry: lengthen one tangent of the +z face. C ≠ 0, the HS diagonals are quartic.
    X[0, 2, 0] *= 1.5
    C = closure(X)
    assert np.linalg.norm(C[0]) > 0.5
    D, E = PatchSet(X, "hermite").with_coons_twists().diagonal_polynomials()
    assert polynomial_degree(D)[0] == 4 and polynomial_degree(E)[0] == 4
    # twists (≤ 4 eps of the 8 terms) then power form and diagonal (≤ 16 eps): ≤ 32 eps·diagonal
    # scale
    bound = 32 * EPS * diagonal_scale("hermite", abs_hs_net(np.abs(X)))
    assert np.all(np.abs(D[0, 4] - C[0]) <= bound[0])
    # Move p_u(1,1) by −C: closure vanishes, both diagonals cubic again.
    X[0, 3, 1] -= C[0]
    # new C = (old C − computed C) + rounding of the subtraction and of the new sum: ≤ 16
    # eps·closure_abs
    assert np.all(np.abs(closure(X)) <= 16 * EPS * closure_abs(np.abs(X)))
    D, E = PatchSet(X, "hermite").with_coons_twists().diagonal_polynomials()
    np.testing.assert_array_equal(polynomial_degree(D), 3)
    np.testing.assert_array_equal(polynomial_degree(E), 3)


# ----------------------------------------------------------- polynomial_degree
def test_polynomial_degree():
    coefficients = np.zeros((4, 7, 3))
    coefficients[1, 2] = [0, 1, 0]
    coefficients[2, :, 0] = 1.0
    coefficients[3, 0] = 1.0
    coefficients[3, 5] = [0, 0, 1e-13]  # below the default 1e-12 × largest: rounding noise
    np.testing.assert_array_equal(polynomial_degree(coefficients), [0, 2, 6, 0])
    coefficients[3, 5] = [0, 0, 1e-11]
    assert polynomial_degree(coefficients)[3] == 5
    assert polynomial_degree(coefficients, rtol=1e-10)[3] == 0
    with pytest.raises(InputError, match="rtol"):
        polynomial_degree(coefficients, rtol=-1.0)
    assert polynomial_degree(np.ones((2, 3, 5, 1))).shape == (2, 3)


# ---------------------------------------------------------------------- bad input
@pytest.mark.parametrize(
    "shape,message",
    [
        ((4, 4, 3), "control: expected shape (N, 4, 4, 3), got (4, 4, 3)"),
        ((1, 2, 4, 4, 3), "control: expected shape (N, 4, 4, 3), got (1, 2, 4, 4, 3)"),
        ((2, 4, 4, 2), "control: expected shape (..., 4, 4, 3), got (2, 4, 4, 2)"),
        ((2, 3, 4, 3), "control: expected shape (..., 4, 4, 3), got (2, 3, 4, 3)"),
        ((4, 3), "control: expected shape (..., 4, 4, 3), got (4, 3)"),
    ],
)
def test_bad_control_shape_is_named(shape, message):
    with pytest.raises(InputError, match="^" + re.escape(message) + "$"):
        PatchSet(np.zeros(shape))


@pytest.mark.parametrize("value", [np.nan, np.inf, -np.inf])
def test_non_finite_control_is_named(value):
    control = np.zeros((2, 4, 4, 3))
    control[1, 3, 2, 1] = value
    with pytest.raises(
        InputError,
        match="^" + re.escape(f"control: non-finite value {value} at index (1, 3, 2, 1)"),
    ):
        PatchSet(control, "hermite")


def test_all_finite_tells_overflow_from_non_finite_entries():
    """The fast test sums: finite entries that overflow the sum are still finite; one NaN or ±inf
    anywhere is not."""
    from g1patch.errors import all_finite

    huge = np.full(1000, np.finfo(float).max)
    assert all_finite(huge) and all_finite(-huge) and all_finite(np.zeros(0))
    for value in (np.nan, np.inf, -np.inf):
        spoiled = huge.copy()
        spoiled[617] = value
        assert not all_finite(spoiled) and not all_finite(
            np.where(np.arange(1000) == 3, value, 1.0)
        )
    mixed = np.array([np.inf, -np.inf, 1.0])  # a NaN sum
    assert not all_finite(mixed)


def test_non_numeric_control_is_named():
    with pytest.raises(InputError, match=r"^control: expected an array of numbers, got str"):
        PatchSet("not an array")


@pytest.mark.parametrize("bad", ["Hermite", "nurbs", None])
def test_unknown_form_is_named(bad):
    pattern = "^" + re.escape(
        f"form: unknown value {bad!r}; expected one of 'hermite', 'bezier', 'bspline'"
    )
    with pytest.raises(InputError, match=pattern):
        PatchSet(np.zeros((1, 4, 4, 3)), bad)
    with pytest.raises(InputError, match=pattern):
        PatchSet(np.zeros((1, 4, 4, 3))).convert(bad)


@pytest.fixture
def patches():
    return PatchSet(np.random.default_rng(0).normal(size=(3, 4, 4, 3)), "hermite")


@pytest.mark.parametrize(
    "shape,message",
    [
        ((5, 3), "uv: expected shape (..., 2), got (5, 3)"),
        ((2,), "uv: expected shape (K, 2) or (3, K, 2), got (2,)"),
        ((4, 5, 2), "uv: expected shape (K, 2) or (3, K, 2), got (4, 5, 2)"),
        ((1, 3, 5, 2), "uv: expected shape (K, 2) or (3, K, 2), got (1, 3, 5, 2)"),
    ],
)
def test_bad_scattered_parameters_are_named(patches, shape, message):
    for call in (patches.evaluate, patches.tangents, patches.twist, patches.normals):
        with pytest.raises(InputError, match="^" + re.escape(message) + "$"):
            call(np.zeros(shape))


@pytest.mark.parametrize("value", [np.nan, np.inf])
def test_non_finite_parameters_are_named(patches, value):
    uv = np.full((3, 2), 0.5)
    uv[2, 1] = value
    for call in (patches.evaluate, patches.tangents, patches.twist, patches.normals):
        with pytest.raises(
            InputError, match="^" + re.escape(f"uv: non-finite value {value} at index (2, 1)")
        ):
            call(uv)
    grid = [0.0, 0.5, value]
    for name, call in (
        ("u", lambda: patches.evaluate_grid(grid)),
        ("v", lambda: patches.evaluate_grid([0.5], grid)),
        ("u", lambda: patches.normals_grid(grid)),
        ("v", lambda: patches.normals_grid([0.5], grid)),
    ):
        with pytest.raises(
            InputError, match="^" + re.escape(f"{name}: non-finite value {value} at index (2,)")
        ):
            call()


def test_bad_grid_parameters_are_named(patches):
    for name, call in (
        ("u", lambda: patches.evaluate_grid(np.zeros((2, 2)))),
        ("v", lambda: patches.evaluate_grid([0.5], np.zeros((2, 3)))),
        ("u", lambda: patches.normals_grid(np.zeros((2, 2)))),
        ("v", lambda: patches.normals_grid([0.5], np.zeros((2, 3)))),
    ):
        with pytest.raises(
            InputError, match=rf"^{name}: expected a 1-D array of parameters, got shape \(2, [23]\)"
        ):
            call()
    with pytest.raises(InputError, match=r"^u: expected an array of numbers"):
        patches.evaluate_grid("abc")
    with pytest.raises(InputError, match=r"^u: expected shape .* got \(\)$"):
        patches.evaluate_grid(0.5)


@pytest.mark.parametrize("resolution", [1, 0, -3, 2.5, "8", None, 4.0])
def test_bad_resolution_is_named(patches, resolution):
    with pytest.raises(
        InputError,
        match="^" + re.escape(f"resolution: expected an integer ≥ 2, got {resolution!r}"),
    ):
        patches.grid(resolution)


def test_good_resolution_types(patches):
    assert patches.grid(np.int64(3)).shape == (3, 3, 3, 3)
    assert patches.grid(2).shape == (3, 2, 2, 3)


@pytest.mark.parametrize("order", [-1, 1.5, "1"])
def test_bad_derivative_order_raises_input_error(patches, order):
    for call in (
        lambda: patches.evaluate([[0.5, 0.5]], du=order),
        lambda: patches.evaluate([[0.5, 0.5]], dv=order),
        lambda: patches.evaluate_grid([0.5], du=order),
        lambda: patches.evaluate_grid([0.5], dv=order),
    ):
        with pytest.raises(InputError) as info:
            call()
        assert repr(order) in str(info.value)


@pytest.mark.parametrize("name", ["du", "dv"])
def test_bad_derivative_order_names_du_or_dv(patches, name):
    with pytest.raises(InputError, match=rf"^{name}: "):
        patches.evaluate([[0.5, 0.5]], **{name: -1})
    with pytest.raises(InputError, match=rf"^{name}: "):
        patches.evaluate_grid([0.5], **{name: -1})


@pytest.mark.parametrize(
    "function,name", [(hs_twists, "hermite"), (closure, "hermite"), (diagonal_polynomials, "power")]
)
def test_free_functions_check_their_argument(function, name):
    with pytest.raises(
        InputError,
        match="^" + re.escape(f"{name}: expected shape (..., 4, 4, 3), got (2, 4, 3, 3)"),
    ):
        function(np.zeros((2, 4, 3, 3)))
    bad = np.zeros((2, 4, 4, 3))
    bad[0, 1, 2, 0] = np.nan
    with pytest.raises(
        InputError, match="^" + re.escape(f"{name}: non-finite value nan at index (0, 1, 2, 0)")
    ):
        function(bad)


def test_polynomial_degree_checks_its_argument():
    with pytest.raises(
        InputError, match="^" + re.escape("coefficients: expected shape (..., N, N), got (7,)")
    ):
        polynomial_degree(np.zeros(7))
    with pytest.raises(
        InputError, match="^" + re.escape("coefficients: non-finite value inf at index (3, 1)")
    ):
        bad = np.zeros((7, 3))
        bad[3, 1] = np.inf
        polynomial_degree(bad)
