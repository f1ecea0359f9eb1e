"""Batched cubic curves (g1patch.curves) against the independent sympy reference."""

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

from g1patch.curves import CubicCurves, power_coefficients, reversal_matrix
from g1patch.errors import InputError

EPS = np.finfo(np.float64).eps
FORMS = ("hermite", "bezier", "bspline")
#: Absolute floor for underflow: a product that underflows errs by ≤ 2^-1074 absolutely.
UNDERFLOW = 1e-300

PARAMS = [Fraction(k, d) for d in (1, 3, 8, 7) for k in range(d + 1)] + [
    Fraction(2, 5),
    Fraction(9, 10),
]


def curve_abs_sum(form, control, t, order=0):
    """S[..., k, d] = Σ_i B_i(t_k) |x_i,d|: magnitude of the terms of the evaluation sum."""
    weights = ref.abs_weights(form, order, t)
    if weights.ndim == 2:
        return np.einsum("ki,...id->...kd", weights, np.abs(control))
    return np.einsum("...ki,...id->...kd", weights, np.abs(control))


# Evaluation error bound, in units of eps · S (S = curve_abs_sum):
#   Horner on each basis cubic ≤ γ_6 B = 3 eps B; rounding of t moves b by ≤ |t b'| u ≤ 1.5 eps B;
#   rounded coefficients (1/6) ≤ 0.5 eps B; rounding the rational control values ≤ 0.5 eps;
#   the 4-term dot product ≤ γ_4 = 2 eps; the final rounding of the reference ≤ 0.5 eps.
CURVE_EVAL_ULPS = 8


@pytest.fixture(scope="module")
def rational_curves():
    rng = np.random.default_rng(20240611)
    return ref.random_rationals(rng, (3, 4, 3))


@pytest.mark.parametrize("form", FORMS)
@pytest.mark.parametrize("order", range(5))
def test_evaluate_matches_sympy(form, order, rational_curves):
    curves = CubicCurves(ref.to_float(rational_curves), form)
    t = np.array([float(x) for x in PARAMS])
    got = curves.evaluate(t, order)
    assert got.shape == (3, len(PARAMS), 3)
    np.testing.assert_array_equal(got, curves.derivative(t, order))
    exact = np.empty_like(got)
    for n in range(3):
        polys = [sp.diff(p, ref.t, order) for p in ref.curve_polynomials(form, rational_curves[n])]
        exact[n] = [[float(p.subs(ref.t, ref.rational(x))) for p in polys] for x in PARAMS]
    bound = CURVE_EVAL_ULPS * EPS * curve_abs_sum(form, ref.to_float(rational_curves), t, order)
    assert np.all(np.abs(got - exact) <= bound)
    if order >= 4:
        assert not got.any()


@pytest.mark.parametrize("form", FORMS)
def test_power_coefficients_match_sympy(form, rational_curves):
    control = ref.to_float(rational_curves)
    got = CubicCurves(control, form).power_coefficients()
    np.testing.assert_array_equal(got, power_coefficients(control, form))
    assert got.shape == (3, 4, 3)
    for n in range(3):
        exact = np.array(
            [
                [float(c) for c in ref.coefficients(p, 3)]
                for p in ref.curve_polynomials(form, rational_curves[n])
            ]
        ).T
        # coefficient k = Σ_i x_i M[i, 3-k]: a 4-term sum with exactly representable (or 1/6)
        # weights
        scale = np.abs(np.array(ref.basis_matrix(form).tolist(), dtype=float)).T[::-1] @ np.abs(
            control[n]
        )
        assert np.all(np.abs(got[n] - exact) <= 4 * EPS * scale)


def test_hermite_layout_is_exact():
    rng = np.random.default_rng(1)
    control = rng.normal(size=(5, 4, 3))
    curves = CubicCurves(control, "hermite")
    np.testing.assert_array_equal(curves.evaluate([0.0, 1.0]), control[:, 0:2])
    np.testing.assert_array_equal(curves.derivative([0.0, 1.0]), control[:, 2:4])


def test_bezier_interpolates_its_end_points_and_end_tangents_exactly():
    rng = np.random.default_rng(2)
    control = rng.integers(-50, 50, size=(5, 4, 2)).astype(float)
    curves = CubicCurves(control, "bezier")
    np.testing.assert_array_equal(curves.evaluate([0.0, 1.0]), control[:, [0, 3]])
    np.testing.assert_array_equal(
        curves.derivative([0.0, 1.0]),
        np.stack([3 * (control[:, 1] - control[:, 0]), 3 * (control[:, 3] - control[:, 2])], 1),
    )


def test_batch_shapes_and_per_curve_parameters():
    rng = np.random.default_rng(3)
    control = rng.normal(size=(2, 3, 4, 2))
    curves = CubicCurves(control, "bspline")
    assert curves.batch_shape == (2, 3) and curves.dim == 2
    t_shared = np.linspace(0, 1, 5)
    assert curves.evaluate(t_shared).shape == (2, 3, 5, 2)
    t_own = rng.random((2, 3, 7))
    own = curves.evaluate(t_own, 1)
    assert own.shape == (2, 3, 7, 2)
    for a, b in itertools.product(range(2), range(3)):
        single = CubicCurves(control[a, b], "bspline").evaluate(t_own[a, b], 1)
        # same arithmetic up to summation order: both within CURVE_EVAL_ULPS·eps·S of the exact
        # value
        bound = 2 * CURVE_EVAL_ULPS * EPS * curve_abs_sum("bspline", control[a, b], t_own[a, b], 1)
        assert np.all(np.abs(own[a, b] - single) <= bound)
    assert curves.control.flags.c_contiguous and curves.control.dtype == np.float64


def test_default_form_is_bezier_and_control_is_converted():
    curves = CubicCurves([[0, 0], [1, 2], [3, 4], [5, 6]])
    assert curves.form == "bezier"
    assert curves.control.dtype == np.float64 and curves.control.shape == (4, 2)


# ----------------------------------------------------------------------- reversal
@pytest.mark.parametrize("form", FORMS)
def test_reversal_matrix_is_exact_in_sympy(form):
    xs = sp.symbols("x0:4")
    R = sp.Matrix(reversal_matrix(form).astype(int))
    np.testing.assert_array_equal(reversal_matrix(form), np.array(R.tolist(), dtype=float))
    basis = ref.basis_polynomials(form)
    forward = sum(x * b.subs(ref.t, 1 - ref.t) for x, b in zip(xs, basis, strict=True))
    backward = sum(y * b for y, b in zip(R * sp.Matrix(xs), basis, strict=True))
    assert sp.expand(forward - backward) == 0


@pytest.mark.parametrize("form", FORMS)
def test_reversed_is_exact(form):
    rng = np.random.default_rng(4)
    control = rng.normal(size=(6, 4, 3)) * 10.0 ** rng.integers(-5, 5, size=(6, 1, 1))
    curves = CubicCurves(control, form)
    back = curves.reversed()
    expected = (
        control[:, [1, 0, 3, 2]] * np.array([1, 1, -1, -1])[:, None]
        if form == "hermite"
        else control[:, ::-1]
    )
    np.testing.assert_array_equal(back.control, expected)
    np.testing.assert_array_equal(back.reversed().control, control)
    assert back.form == form
    t = np.arange(17) / 16.0  # 1 - t exact
    bound = (
        CURVE_EVAL_ULPS
        * EPS
        * (curve_abs_sum(form, control, t) + curve_abs_sum(form, control, 1 - t))
    )
    assert np.all(np.abs(back.evaluate(t) - curves.evaluate(1 - t)) <= bound)


# ------------------------------------------------------------------ conversions
def conversion_bound(source, target, control, t):
    """Magnitude bound for |c_target(t) − c_source(t)| after y = C x in floats.

    y_i = Σ_k C_ik x_k errs by ≤ (γ_4 + u)(|C| |x|)_i (4-term sum, rounded C); evaluating y
    adds ≤ ~6 eps Σ_i B^T_i(t) |y_i|, evaluating x ≤ ~6 eps Σ_i B^S_i(t) |x_i|. So the error is
    a few eps × S with S = Σ_i B^T_i(t) (|C||x|)_i + Σ_i B^S_i(t)|x_i|: |C||x| is where the
    conditioning of the conversion enters (|C| for B-spline → Bézier → Hermite grows to 7).
    """
    abs_c = np.abs(np.array(ref.conversion_matrix(source, target).tolist(), dtype=float))
    converted = np.einsum("ij,...jd->...id", abs_c, np.abs(control))
    return curve_abs_sum(target, converted, t) + curve_abs_sum(source, control, t) + UNDERFLOW


FINITE = st.floats(-1e6, 1e6, allow_nan=False, allow_infinity=False, allow_subnormal=False)
UNIT = st.floats(0.0, 1.0, allow_nan=False, allow_subnormal=False)
CURVE_CONTROL = arrays(
    np.float64, st.tuples(st.integers(1, 3), st.just(4), st.integers(1, 3)), elements=FINITE
)
CURVE_PARAMS = arrays(np.float64, st.integers(1, 6), elements=UNIT)


@settings(deadline=None, max_examples=60)
@given(
    control=CURVE_CONTROL,
    t=CURVE_PARAMS,
    source=st.sampled_from(FORMS),
    target=st.sampled_from(FORMS),
)
def test_conversion_keeps_the_curve(control, t, source, target):
    curves = CubicCurves(control, source)
    converted = curves.convert(target)
    assert converted.form == target
    err = np.abs(converted.evaluate(t) - curves.evaluate(t))
    assert np.all(err <= 4 * EPS * conversion_bound(source, target, control, t))


@settings(deadline=None, max_examples=60)
@given(control=CURVE_CONTROL, source=st.sampled_from(FORMS), target=st.sampled_from(FORMS))
def test_round_trip_returns_the_control_values(control, source, target):
    """x → C_AB x → C_BA C_AB x = x up to 4 eps (|C_BA| |C_AB| |x|): the Skeel condition of the
    pair."""
    back = CubicCurves(control, source).convert(target).convert(source)
    assert back.form == source
    abs_ab = np.abs(np.array(ref.conversion_matrix(source, target).tolist(), dtype=float))
    abs_ba = np.abs(np.array(ref.conversion_matrix(target, source).tolist(), dtype=float))
    bound = 4 * EPS * np.einsum("ij,jk,...kd->...id", abs_ba, abs_ab, np.abs(control)) + UNDERFLOW
    assert np.all(np.abs(back.control - control) <= bound)


def test_convert_to_same_form_is_identity():
    curves = CubicCurves(np.ones((4, 3)), "hermite")
    assert curves.convert("hermite") is curves


def test_conversion_of_rational_curves_matches_sympy():
    rng = np.random.default_rng(5)
    control = ref.random_rationals(rng, (4, 3))
    for source, target in itertools.product(FORMS, FORMS):
        converted = CubicCurves(ref.to_float(control), source).convert(target)
        C = ref.conversion_matrix(source, target)
        exact = np.array(
            (C * sp.Matrix(control.tolist()).applyfunc(ref.rational)).tolist(), dtype=float
        )
        abs_c = np.abs(np.array(C.tolist(), dtype=float))
        # 4-term sum with rounded inputs and rounded C: ≤ (γ_4 + 2u) |C||x| + u|y| ≤ 4 eps |C||x|
        assert np.all(
            np.abs(converted.control - exact) <= 4 * EPS * abs_c @ np.abs(ref.to_float(control))
        )


# -------------------------------------------------------------------- bad input
@pytest.mark.parametrize("shape", [(4,), (3, 2), (5, 3), (2, 3, 3)])
def test_bad_control_shape_is_named(shape):
    with pytest.raises(
        InputError, match=re.escape(f"control: expected shape (..., 4, N), got {shape}")
    ):
        CubicCurves(np.zeros(shape))


@pytest.mark.parametrize("value", [np.nan, np.inf, -np.inf])
def test_non_finite_control_is_named(value):
    control = np.zeros((2, 4, 3))
    control[1, 2, 0] = value
    with pytest.raises(
        InputError, match=re.escape(f"control: non-finite value {value} at index (1, 2, 0)")
    ):
        CubicCurves(control, "hermite")


def test_non_numeric_control_is_named():
    with pytest.raises(InputError, match=r"^control: expected an array of numbers"):
        CubicCurves([["a", "b"]] * 4)


@pytest.mark.parametrize("bad", ["Bezier", "nurbs", None])
def test_unknown_form_is_named(bad):
    pattern = "^" + re.escape(
        f"form: unknown value {bad!r}; expected one of 'hermite', 'bezier', 'bspline'"
    )
    with pytest.raises(InputError, match=pattern):
        CubicCurves(np.zeros((4, 3)), bad)
    with pytest.raises(InputError, match=pattern):
        CubicCurves(np.zeros((4, 3))).convert(bad)
    with pytest.raises(InputError, match=pattern):
        reversal_matrix(bad)
    with pytest.raises(InputError, match=pattern):
        power_coefficients(np.zeros((4, 3)), bad)


def test_bad_parameters_are_named():
    curves = CubicCurves(np.zeros((2, 3, 4, 3)))
    with pytest.raises(
        InputError, match=re.escape("t: expected shape (K,) or (2, 3, K), got (3, 5)")
    ):
        curves.evaluate(np.zeros((3, 5)))
    with pytest.raises(InputError, match=r"^t: expected shape .* got \(2, 3, 4, 5\)"):
        curves.evaluate(np.zeros((2, 3, 4, 5)))
    with pytest.raises(InputError, match=re.escape("t: non-finite value nan at index (1,)")):
        curves.evaluate([0.5, np.nan])
    with pytest.raises(InputError, match=r"^t: expected an array of numbers"):
        curves.evaluate("abc")
    with pytest.raises(InputError, match=r"^t: expected shape .* got \(\)$"):
        CubicCurves(np.zeros((4, 3))).evaluate(0.5)


@pytest.mark.parametrize("order", [-1, 0.5, "2"])
def test_bad_derivative_order_is_named(order):
    curves = CubicCurves(np.zeros((4, 3)))
    for call in (lambda: curves.evaluate([0.5], order), lambda: curves.derivative([0.5], order)):
        with pytest.raises(
            InputError, match=r"^order: expected a non-negative integer, got "
        ) as info:
            call()
        assert repr(order) in str(info.value)


@pytest.mark.parametrize(
    "control", [np.zeros((3, 2)), np.full((4, 2), np.nan)], ids=["shape", "nan"]
)
def test_power_coefficients_checks_its_control(control):
    with pytest.raises(InputError, match=r"^control: "):
        power_coefficients(control, "bezier")
