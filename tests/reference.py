"""Independent exact (sympy / Fraction) reference for the foundation tests.

Nothing here imports g1patch. Every basis is derived from its definition, not copied from
the library:

* Hermite: the matrix ``M_H`` typed in from the paper's eq. (1), and, separately, the four
  cubics solved from their interpolation conditions h(0), h(1), h'(0), h'(1).
* Bézier: the Bernstein polynomials ``C(3, i) t^i (1 - t)^(3 - i)``.
* Uniform cubic B-spline: the Cox–de Boor recursion on the knots 0, 1, …, 7, restricted to the
  span [3, 4] and shifted to t ∈ [0, 1].

A patch in form F with control ``P[i][j]`` (i along u, j along v) is
``p(u, v) = Σ_ij b_i(u) P_ij b_j(v)``; for Hermite it is built literally as the paper's eq. (3),
``x(u, v) = u^T M_H^T X M_H v`` with ``u = [u^3, u^2, u, 1]^T``.
"""

from __future__ import annotations

from fractions import Fraction
from functools import cache

import numpy as np
import sympy as sp

t, u, v = sp.symbols("t u v")

FORMS = ("hermite", "bezier", "bspline")

#: The paper's eq. (1), typed in from the text: rows H1..H4, columns t^3, t^2, t, 1.
PAPER_M_H = (
    (2, -3, 0, 1),
    (-2, 3, 0, 0),
    (1, -2, 1, 0),
    (1, -1, 0, 0),
)


# ---------------------------------------------------------------------------- bases
def hermite_basis_from_conditions() -> list[sp.Expr]:
    """H_i: the cubic with (h(0), h(1), h'(0), h'(1)) = e_i, solved exactly."""
    a = sp.symbols("a0:4")
    cubic = a[0] * t**3 + a[1] * t**2 + a[2] * t + a[3]
    slope = sp.diff(cubic, t)
    conditions = [cubic.subs(t, 0), cubic.subs(t, 1), slope.subs(t, 0), slope.subs(t, 1)]
    basis = []
    for i in range(4):
        target = [1 if k == i else 0 for k in range(4)]
        solution = sp.solve([c - w for c, w in zip(conditions, target, strict=True)], a, dict=True)[
            0
        ]
        basis.append(sp.expand(cubic.subs(solution)))
    return basis


def bernstein_basis() -> list[sp.Expr]:
    return [sp.expand(sp.binomial(3, i) * t**i * (1 - t) ** (3 - i)) for i in range(4)]


def bspline_basis() -> list[sp.Expr]:
    """Cox–de Boor on the uniform knots 0..7; the four B-splines alive on [3, 4], as t = x − 3."""
    x = sp.Symbol("x")
    knots = list(range(8))
    span = 3
    # Degree 0 restricted to the span [3, 4): only N_{3,0} is 1 there.
    basis = {i: sp.Integer(1 if i == span else 0) for i in range(7)}
    for k in range(1, 4):
        basis = {
            i: sp.Rational(1, knots[i + k] - knots[i]) * (x - knots[i]) * basis[i]
            + sp.Rational(1, knots[i + k + 1] - knots[i + 1])
            * (knots[i + k + 1] - x)
            * basis[i + 1]
            for i in range(7 - k)
        }
    return [sp.expand(basis[i].subs(x, t + span)) for i in range(4)]


@cache
def basis_polynomials(form: str) -> tuple[sp.Expr, ...]:
    if form == "hermite":
        return tuple(
            sp.expand(sum(sp.Integer(c) * t ** (3 - k) for k, c in enumerate(row)))
            for row in PAPER_M_H
        )
    if form == "bezier":
        return tuple(bernstein_basis())
    if form == "bspline":
        return tuple(bspline_basis())
    raise KeyError(form)


def matrix_of(polys) -> sp.Matrix:
    """``M[i, k]`` = coefficient of t^(3-k) in polys[i] (the paper's monomial convention)."""
    return sp.Matrix(4, 4, lambda i, k: sp.Poly(polys[i], t).coeff_monomial(t ** (3 - k)))


@cache
def basis_matrix(form: str) -> sp.Matrix:
    return matrix_of(basis_polynomials(form))


@cache
def derivative_basis_matrix(form: str, order: int) -> sp.Matrix:
    return matrix_of([sp.diff(p, t, order) for p in basis_polynomials(form)])


def as_fractions(matrix: sp.Matrix) -> tuple[tuple[Fraction, ...], ...]:
    return tuple(
        tuple(Fraction(int(sp.fraction(x)[0]), int(sp.fraction(x)[1])) for x in matrix.row(i))
        for i in range(matrix.rows)
    )


@cache
def conversion_matrix(source: str, target: str) -> sp.Matrix:
    """C with y = C x, found by matching power coefficients of Σ y_i b^T_i(t) = Σ x_i b^S_i(t)."""
    xs = sp.symbols("x0:4")
    ys = sp.symbols("y0:4")
    difference = sp.expand(
        sum(y * b for y, b in zip(ys, basis_polynomials(target), strict=True))
        - sum(x * b for x, b in zip(xs, basis_polynomials(source), strict=True))
    )
    equations = sp.Poly(difference, t).all_coeffs()
    (solution,) = sp.linsolve(equations, ys)
    return sp.Matrix(4, 4, lambda i, j: sp.diff(solution[i], xs[j]))


# --------------------------------------------------------------------- rationals
def rational(value) -> sp.Expr:
    """Exact sympy number for a Fraction, float (its exact binary value), int; symbols pass
    through."""
    if isinstance(value, sp.Basic):
        return value
    if isinstance(value, Fraction):
        return sp.Rational(value.numerator, value.denominator)
    if isinstance(value, float):
        return sp.Rational(*value.as_integer_ratio())
    return sp.Rational(value)


def random_rationals(
    rng: np.random.Generator, shape, numerator: int = 40, denominators=(1, 2, 3, 4, 5, 6, 7, 9, 12)
):
    """Object array of Fractions n/d with |n| ≤ numerator and d from ``denominators``."""
    flat = [
        Fraction(int(rng.integers(-numerator, numerator + 1)), int(rng.choice(denominators)))
        for _ in range(int(np.prod(shape)))
    ]
    out = np.empty(len(flat), dtype=object)
    out[:] = flat
    return out.reshape(shape)


def to_float(values) -> np.ndarray:
    return np.vectorize(float, otypes=[np.float64])(np.asarray(values, dtype=object))


# ----------------------------------------------------------------------- curves
def curve_polynomials(form: str, control) -> list[sp.Expr]:
    """Coordinates of Σ_i b_i(t) x_i for control (4, dim) of rationals."""
    control = np.asarray(control, dtype=object)
    basis = basis_polynomials(form)
    return [
        sp.expand(sum(rational(control[i, d]) * basis[i] for i in range(4)))
        for d in range(control.shape[1])
    ]


# ---------------------------------------------------------------------- patches
def patch_polynomials(form: str, control) -> list[sp.Poly]:
    """Coordinates of one patch (control (4, 4, dim)) as Polys in (u, v).

    The paper's eq. (3) for every form: ``x(u, v) = u^T M^T X M v`` with ``u = [u^3, u^2, u, 1]``,
    i.e. ``Σ_ij A_ij u^(3-i) v^(3-j)`` with ``A = M^T X M`` in exact rationals. For Hermite ``M`` is
    the paper's ``M_H`` as typed in; for the other forms it is read off the independently derived
    basis polynomials (``Σ_ij b_i(u) X_ij b_j(v)`` — cross-checked against the tensor sum in the
    tests).
    """
    control = np.asarray(control, dtype=object)
    key = (form, control.shape, tuple(control.ravel().tolist()))
    return list(_patch_polynomials(key))


@cache
def _patch_polynomials(key) -> tuple[sp.Poly, ...]:
    form, shape, flat = key
    control = np.array(flat, dtype=object).reshape(shape)
    M = sp.Matrix(PAPER_M_H) if form == "hermite" else basis_matrix(form)
    out = []
    for d in range(shape[-1]):
        X = sp.Matrix(4, 4, lambda i, j, d=d: rational(control[i, j, d]))
        A = M.T * X * M
        terms = {(3 - i, 3 - j): A[i, j] for i in range(4) for j in range(4) if A[i, j] != 0}
        out.append(sp.Poly.from_dict(terms, u, v) if terms else sp.Poly(0, u, v))
    return tuple(out)


def derivative(polys: list[sp.Poly], du: int, dv: int) -> list[sp.Poly]:
    return [p.diff((u, du), (v, dv)) if (du or dv) else p for p in polys]


def evaluate(polys: list[sp.Poly], uu, vv) -> list[sp.Rational]:
    point = {u: rational(uu), v: rational(vv)}
    return [p.eval(point) if not p.is_zero else sp.Integer(0) for p in polys]


def restrict(polys: list[sp.Poly], uu, vv) -> list[sp.Poly]:
    """Coordinates of the curve p(uu(t), vv(t)) for polynomials uu, vv in t, as Polys in t."""
    U, V = sp.Poly(uu, t), sp.Poly(vv, t)
    out = []
    for p in polys:
        acc = sp.Poly(0, t)
        for (a, b), c in p.terms():
            acc += U**a * V**b * c
        out.append(acc)
    return out


def coefficients(expr, degree: int = 6) -> list[sp.Rational]:
    """Ascending coefficients of a polynomial (expression or Poly) in t, padded to ``degree +
    1``."""
    poly = expr if isinstance(expr, sp.Poly) else sp.Poly(expr, t)
    return [poly.coeff_monomial(t**k) for k in range(degree + 1)]


def exact_degree(coeffs: list[sp.Rational]) -> int:
    nonzero = [k for k, c in enumerate(coeffs) if c != 0]
    return nonzero[-1] if nonzero else 0


def coons_patch(polys: list[sp.Poly]) -> list[sp.Poly]:
    """The bilinearly blended Coons patch of the patch's four boundary curves (cached)."""
    return list(_coons_patch(tuple(polys)))


@cache
def _coons_patch(polys: tuple[sp.Poly, ...]) -> tuple[sp.Poly, ...]:
    """Bilinearly blended Coons patch of the four boundary curves of a patch.

    S(u,v) = (1−v) p(u,0) + v p(u,1) + (1−u) p(0,v) + u p(1,v)
             − [(1−u)(1−v) p(0,0) + u(1−v) p(1,0) + (1−u) v p(0,1) + u v p(1,1)]
    """
    out = []
    for p in polys:
        e = p.as_expr()
        bottom, top = e.subs(v, 0), e.subs(v, 1)
        left, right = e.subs(u, 0), e.subs(u, 1)
        corners = {(a, b): e.subs({u: a, v: b}) for a in (0, 1) for b in (0, 1)}
        bilinear = (
            (1 - u) * (1 - v) * corners[0, 0]
            + u * (1 - v) * corners[1, 0]
            + (1 - u) * v * corners[0, 1]
            + u * v * corners[1, 1]
        )
        coons = (1 - v) * bottom + v * top + (1 - u) * left + u * right - bilinear
        out.append(sp.Poly(sp.expand(coons), u, v))
    return tuple(out)


# ------------------------------------------------------------ rounding bounds
def abs_weights(form: str, order: int, params) -> np.ndarray:
    """``B_i(t) = Σ_k |(M D^order)_ik| |t|^(3-k)``, shape params.shape + (4,).

    This is the magnitude of the terms Horner's rule sums for each basis function: Higham's
    bound for the rounding error of Horner evaluation of Σ a_k t^k is γ_2n Σ |a_k| |t|^k.
    """
    M = np.abs(np.array(derivative_basis_matrix(form, order).tolist(), dtype=float))
    params = np.abs(np.asarray(params, dtype=float))
    powers = np.stack([params**3, params**2, params, np.ones_like(params)], axis=-1)
    return powers @ M.T


def abs_patch_sum(
    form: str, control: np.ndarray, uv: np.ndarray, du: int = 0, dv: int = 0
) -> np.ndarray:
    """``S[n, k] = Σ_ij B_i(u_k) |P[n,i,j,:]| B_j(v_k)`` (per coordinate), shape (N, K, 3).

    The magnitude of every term of the evaluation sum (with the Horner terms of each basis
    value expanded): a floating-point evaluation of the patch errs by at most a small
    multiple of eps · S, whatever the cancellation in the exact value.
    """
    wu = abs_weights(form, du, uv[..., 0])
    wv = abs_weights(form, dv, uv[..., 1])
    if uv.ndim == 2:
        return np.einsum("ki,nijd,kj->nkd", wu, np.abs(control), wv)
    return np.einsum("nki,nijd,nkj->nkd", wu, np.abs(control), wv)
