"""Basis matrices, derivative bases and exact changes of basis (g1patch.basis).

References are derived independently in tests/reference.py (sympy): the paper's eq. (1) typed
in, Hermite cubics solved from their interpolation conditions, Bernstein polynomials, and the
uniform cubic B-spline from the Cox–de Boor recursion.
"""

from __future__ import annotations

import itertools
import re
from fractions import Fraction

import numpy as np
import pytest
import reference as ref
import sympy as sp

from g1patch import basis
from g1patch.errors import InputError

EPS = np.finfo(np.float64).eps
FORMS = ("hermite", "bezier", "bspline")
PAIRS = list(itertools.product(FORMS, FORMS))


def fractions(matrix) -> tuple[tuple[Fraction, ...], ...]:
    return tuple(tuple(Fraction(x) for x in row) for row in matrix)


# ------------------------------------------------------------------ basis matrices
def test_hermite_matrix_is_the_papers_eq_1():
    expected = tuple(tuple(Fraction(x) for x in row) for row in ref.PAPER_M_H)
    assert basis.exact_basis_matrix("hermite") == expected
    np.testing.assert_array_equal(
        basis.basis_matrix("hermite"), np.array(ref.PAPER_M_H, dtype=float)
    )


def test_papers_hermite_matrix_interpolates_values_and_slopes():
    # The paper's M_H rows are exactly the cubics with (h(0), h(1), h'(0), h'(1)) = e_i.
    derived = ref.matrix_of(ref.hermite_basis_from_conditions())
    assert derived == sp.Matrix(ref.PAPER_M_H)


@pytest.mark.parametrize("form", FORMS)
def test_exact_basis_matrix_equals_independent_derivation(form):
    assert basis.exact_basis_matrix(form) == ref.as_fractions(ref.basis_matrix(form))
    assert all(isinstance(x, Fraction) for row in basis.exact_basis_matrix(form) for x in row)


def test_bspline_reference_is_a_partition_of_unity_with_known_knot_values():
    # Sanity of the Cox–de Boor reference itself: Σ b_i = 1, and b(0) = (1, 4, 1, 0)/6.
    polys = ref.basis_polynomials("bspline")
    assert sp.expand(sum(polys)) == 1
    assert [p.subs(ref.t, 0) for p in polys] == [
        sp.Rational(1, 6),
        sp.Rational(2, 3),
        sp.Rational(1, 6),
        0,
    ]
    assert sp.expand(sum(ref.basis_polynomials("bezier"))) == 1


@pytest.mark.parametrize("form", FORMS)
def test_float_basis_matrix_is_the_correctly_rounded_exact_one(form):
    exact = basis.exact_basis_matrix(form)
    got = basis.basis_matrix(form)
    assert got.dtype == np.float64 and got.shape == (4, 4)
    np.testing.assert_array_equal(got, np.array([[float(x) for x in row] for row in exact]))
    with pytest.raises(ValueError):
        got[0, 0] = 1.0  # cached, shared: must be read-only


@pytest.mark.parametrize("form", FORMS)
@pytest.mark.parametrize("order", range(6))
def test_derivative_matrix_equals_sympy_derivative(form, order):
    exact = ref.derivative_basis_matrix(form, order)
    got = basis.derivative_matrix(form, order)
    # Entries are small multiples of 1/6; the float product rounds them correctly.
    np.testing.assert_array_equal(got, np.array(exact.tolist(), dtype=float))
    if order >= 4:
        assert not got.any()
    with pytest.raises(ValueError):
        got[0, 0] = 1.0


@pytest.mark.parametrize("form", FORMS)
@pytest.mark.parametrize("order", range(4))
def test_basis_values_match_sympy_at_rational_parameters(form, order):
    params = [Fraction(k, d) for d in (1, 3, 7, 8, 10) for k in range(d + 1)] + [
        Fraction(-1, 3),
        Fraction(5, 4),
    ]
    t_float = np.array([float(x) for x in params])
    got = basis.basis_values(form, t_float, order)
    assert got.shape == (len(params), 4)
    polys = [sp.diff(p, ref.t, order) for p in ref.basis_polynomials(form)]
    exact = np.array([[float(p.subs(ref.t, ref.rational(x))) for p in polys] for x in params])
    # Bound: Horner on a cubic errs ≤ γ_6·B(t) = 3 eps·B (Higham 5.3) with B = Σ|a_k||t|^k;
    # rounding t itself moves b by ≤ |t b'(t)|·u ≤ 3u·B = 1.5 eps·B; a rounded coefficient
    # (the 1/6 of the B-spline) adds ≤ 0.5 eps·B; the final rounding of `exact` ≤ 0.5 eps·|b|.
    bound = 5.5 * EPS * ref.abs_weights(form, order, t_float)
    assert np.all(np.abs(got - exact) <= bound)


def test_basis_values_shape_follows_parameters():
    t = np.linspace(0.0, 1.0, 12).reshape(3, 4)
    assert basis.basis_values("bezier", t).shape == (3, 4, 4)
    # Endpoints of the Hermite basis are exact: b(0) = e_0, b(1) = e_1, b'(0) = e_2, b'(1) = e_3.
    np.testing.assert_array_equal(basis.basis_values("hermite", [0.0, 1.0]), np.eye(4)[:2])
    np.testing.assert_array_equal(basis.basis_values("hermite", [0.0, 1.0], 1), np.eye(4)[2:])


def test_basis_values_of_a_scalar_has_shape_4():
    # documented: shape t.shape + (4,); a 0-d t must not be promoted to (1,)
    assert basis.basis_values("bezier", 0.25).shape == (4,)
    np.testing.assert_array_equal(basis.basis_values("hermite", 1.0, 1), [0.0, 0.0, 0.0, 1.0])


# -------------------------------------------------------------- change of basis
@pytest.mark.parametrize("source,target", PAIRS)
def test_conversion_keeps_the_polynomial_exactly(source, target):
    xs = sp.symbols("x0:4")
    C = sp.Matrix(basis.exact_conversion_matrix(source, target))
    ys = C * sp.Matrix(xs)
    before = sum(x * b for x, b in zip(xs, ref.basis_polynomials(source), strict=True))
    after = sum(y * b for y, b in zip(ys, ref.basis_polynomials(target), strict=True))
    assert sp.expand(after - before) == 0
    assert C == ref.conversion_matrix(source, target)
    assert all(
        isinstance(x, Fraction)
        for row in basis.exact_conversion_matrix(source, target)
        for x in row
    )


@pytest.mark.parametrize("source,target", PAIRS)
def test_conversions_are_mutually_inverse_exactly(source, target):
    forward = sp.Matrix(basis.exact_conversion_matrix(source, target))
    backward = sp.Matrix(basis.exact_conversion_matrix(target, source))
    assert forward * backward == sp.eye(4)
    assert backward * forward == sp.eye(4)


@pytest.mark.parametrize("a,b,c", list(itertools.product(FORMS, repeat=3)))
def test_conversions_compose_exactly(a, b, c):
    ab = sp.Matrix(basis.exact_conversion_matrix(a, b))
    bc = sp.Matrix(basis.exact_conversion_matrix(b, c))
    assert bc * ab == sp.Matrix(basis.exact_conversion_matrix(a, c))


@pytest.mark.parametrize("source,target", PAIRS)
def test_float_conversion_matrix_is_correctly_rounded(source, target):
    exact = basis.exact_conversion_matrix(source, target)
    got = basis.conversion_matrix(source, target)
    np.testing.assert_array_equal(got, np.array([[float(x) for x in row] for row in exact]))
    with pytest.raises(ValueError):
        got[0, 0] = 1.0


F = Fraction
CLOSED_FORMS = {
    # Hermite [p0, p1, p0', p1'] → Bézier: b0 = p0, b1 = p0 + p0'/3, b2 = p1 − p1'/3, b3 = p1.
    ("hermite", "bezier"): [[1, 0, 0, 0], [1, 0, F(1, 3), 0], [0, 1, 0, F(-1, 3)], [0, 1, 0, 0]],
    # Bézier → Hermite: p0' = 3(b1 − b0), p1' = 3(b3 − b2).
    ("bezier", "hermite"): [[1, 0, 0, 0], [0, 0, 0, 1], [-3, 3, 0, 0], [0, 0, -3, 3]],
    # B-spline → Bézier: b0 = (d0 + 4d1 + d2)/6, b1 = (2d1 + d2)/3, b2 = (d1 + 2d2)/3, b3 = (d1 +
    # 4d2 + d3)/6.
    ("bspline", "bezier"): [
        [F(1, 6), F(4, 6), F(1, 6), 0],
        [0, F(2, 3), F(1, 3), 0],
        [0, F(1, 3), F(2, 3), 0],
        [0, F(1, 6), F(4, 6), F(1, 6)],
    ],
    # Bézier → B-spline: d0 = 6b0 − 7b1 + 2b2, d1 = 2b1 − b2, d2 = −b1 + 2b2, d3 = 2b1 − 7b2 + 6b3.
    ("bezier", "bspline"): [[6, -7, 2, 0], [0, 2, -1, 0], [0, -1, 2, 0], [0, 2, -7, 6]],
    # B-spline → Hermite: p0 = (d0 + 4d1 + d2)/6, p1 = (d1 + 4d2 + d3)/6, p0' = (d2 − d0)/2, p1' =
    # (d3 − d1)/2.
    ("bspline", "hermite"): [
        [F(1, 6), F(4, 6), F(1, 6), 0],
        [0, F(1, 6), F(4, 6), F(1, 6)],
        [F(-1, 2), 0, F(1, 2), 0],
        [0, F(-1, 2), 0, F(1, 2)],
    ],
}


@pytest.mark.parametrize("pair", sorted(CLOSED_FORMS))
def test_known_closed_forms(pair):
    assert basis.exact_conversion_matrix(*pair) == fractions(CLOSED_FORMS[pair])


@pytest.mark.parametrize("form", FORMS)
def test_identity_conversion(form):
    assert basis.exact_conversion_matrix(form, form) == fractions(np.eye(4, dtype=int).tolist())


# -------------------------------------------------------------------- bad input
BAD_FORMS = ["Hermite", "nurbs", "", None, 3]


@pytest.mark.parametrize("bad", BAD_FORMS)
def test_unknown_form_is_named(bad):
    calls = {
        "form": [
            lambda: basis.exact_basis_matrix(bad),
            lambda: basis.basis_matrix(bad),
            lambda: basis.derivative_matrix(bad, 1),
            lambda: basis.basis_values(bad, [0.5]),
        ],
        "source": [
            lambda: basis.exact_conversion_matrix(bad, "bezier"),
            lambda: basis.conversion_matrix(bad, "bezier"),
        ],
        "target": [
            lambda: basis.exact_conversion_matrix("bezier", bad),
            lambda: basis.conversion_matrix("hermite", bad),
        ],
    }
    for name, functions in calls.items():
        for call in functions:
            with pytest.raises(
                InputError, match="^" + re.escape(f"{name}: unknown value {bad!r}; expected one of")
            ) as info:
                call()
            assert "'hermite', 'bezier', 'bspline'" in str(info.value)


@pytest.mark.parametrize(
    "call",
    [
        lambda: basis.basis_matrix(["hermite"]),
        lambda: basis.derivative_matrix("hermite", [1]),
        lambda: basis.conversion_matrix(["hermite"], "bezier"),
    ],
    ids=["basis_matrix", "derivative_matrix", "conversion_matrix"],
)
def test_unhashable_arguments_raise_input_error(call):
    with pytest.raises(InputError):
        call()


@pytest.mark.parametrize("order", [-1, 1.5, "1", None])
def test_bad_derivative_order_is_named(order):
    with pytest.raises(InputError, match=r"^order: expected a non-negative integer, got ") as info:
        basis.derivative_matrix("bezier", order)
    assert repr(order) in str(info.value)
    with pytest.raises(InputError, match=r"^order: ") as info:
        basis.basis_values("bezier", [0.5], order)
    assert repr(order) in str(info.value)


@pytest.mark.parametrize("value", [np.nan, np.inf, -np.inf])
def test_non_finite_parameter_is_named(value):
    with pytest.raises(InputError, match=r"^t: non-finite value") as info:
        basis.basis_values("hermite", [0.0, 0.5, value])
    assert f"{value}" in str(info.value) and "index (2,)" in str(info.value)


def test_non_numeric_parameter_is_named():
    with pytest.raises(InputError, match=r"^t: expected an array of numbers, got str"):
        basis.basis_values("hermite", "abc")
    with pytest.raises(InputError, match=r"^t: expected an array of numbers"):
        basis.basis_values("hermite", [[0.0, 1.0], [0.5]])
