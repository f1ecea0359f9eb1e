"""Cubic basis matrices in the paper's monomial convention, and exact changes of basis.

A cubic curve in form F with control values ``x = [x0, x1, x2, x3]`` is

    x(t) = x^T M_F t,        t = [t^3, t^2, t, 1]^T                      (paper, eq. 1)

so the rows of ``M_F`` are the four basis functions of F written as power coefficients.
Forms: ``hermite`` (x = [p(0), p(1), p'(0), p'(1)], the paper's ``M_H``), ``bezier``
(cubic Bernstein) and ``bspline`` (one span of the uniform cubic B-spline).

Derivatives act on ``t``: ``dt/dt = D t``, hence ``M_F' = M_F D``. Changing form keeps the
curve: ``x^T M_A t = y^T M_B t`` for all t gives ``y = C x`` with ``C = (M_A M_B^-1)^T``.
The matrices are computed once, exactly, in rational arithmetic.
"""

from __future__ import annotations

from fractions import Fraction
from functools import cache
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .errors import InputError, as_float_array, check_choice

__all__ = [
    "FORMS",
    "Form",
    "basis_matrix",
    "derivative_matrix",
    "conversion_matrix",
    "basis_values",
    "exact_basis_matrix",
    "exact_conversion_matrix",
    "check_order",
]

Form = Literal["hermite", "bezier", "bspline"]
FORMS: tuple[Form, ...] = ("hermite", "bezier", "bspline")

RationalMatrix = tuple[tuple[Fraction, ...], ...]

_F = Fraction
_EXACT: dict[str, RationalMatrix] = {
    # Paper, eq. (1): rows H1 = 2t^3-3t^2+1, H2 = -2t^3+3t^2, H3 = t^3-2t^2+t, H4 = t^3-t^2.
    "hermite": (
        (_F(2), _F(-3), _F(0), _F(1)),
        (_F(-2), _F(3), _F(0), _F(0)),
        (_F(1), _F(-2), _F(1), _F(0)),
        (_F(1), _F(-1), _F(0), _F(0)),
    ),
    # Bernstein: (1-t)^3, 3t(1-t)^2, 3t^2(1-t), t^3.
    "bezier": (
        (_F(-1), _F(3), _F(-3), _F(1)),
        (_F(3), _F(-6), _F(3), _F(0)),
        (_F(-3), _F(3), _F(0), _F(0)),
        (_F(1), _F(0), _F(0), _F(0)),
    ),
    # Uniform cubic B-spline span: (1-t)^3/6, (3t^3-6t^2+4)/6, (-3t^3+3t^2+3t+1)/6, t^3/6.
    "bspline": (
        (_F(-1, 6), _F(3, 6), _F(-3, 6), _F(1, 6)),
        (_F(3, 6), _F(-6, 6), _F(0), _F(4, 6)),
        (_F(-3, 6), _F(3, 6), _F(3, 6), _F(1, 6)),
        (_F(1, 6), _F(0), _F(0), _F(0)),
    ),
}

#: d/dt [t^3, t^2, t, 1] = D [t^3, t^2, t, 1]
_DERIVATIVE = np.array(
    [[0.0, 3.0, 0.0, 0.0], [0.0, 0.0, 2.0, 0.0], [0.0, 0.0, 0.0, 1.0], [0.0, 0.0, 0.0, 0.0]]
)


def _matmul(a: RationalMatrix, b: RationalMatrix) -> RationalMatrix:
    return tuple(
        tuple(sum((a[i][k] * b[k][j] for k in range(4)), Fraction(0)) for j in range(4))
        for i in range(4)
    )


def _inverse(a: RationalMatrix) -> RationalMatrix:
    """Gauss–Jordan inverse in exact rational arithmetic (4×4, nonsingular by construction)."""
    rows = [list(row) + [_F(int(i == j)) for j in range(4)] for i, row in enumerate(a)]
    for col in range(4):
        pivot = next(r for r in range(col, 4) if rows[r][col] != 0)
        rows[col], rows[pivot] = rows[pivot], rows[col]
        scale = rows[col][col]
        rows[col] = [x / scale for x in rows[col]]
        for r in range(4):
            if r != col and rows[r][col] != 0:
                factor = rows[r][col]
                rows[r] = [x - factor * y for x, y in zip(rows[r], rows[col], strict=True)]
    return tuple(tuple(row[4:]) for row in rows)


def _transpose(a: RationalMatrix) -> RationalMatrix:
    return tuple(tuple(a[j][i] for j in range(4)) for i in range(4))


def _to_array(a: RationalMatrix) -> NDArray[np.float64]:
    array = np.array([[float(x) for x in row] for row in a])
    array.setflags(write=False)
    return array


def exact_basis_matrix(form: Form) -> RationalMatrix:
    """``M_F`` as exact fractions."""
    return _EXACT[check_choice("form", form, FORMS)]


def check_order(name: str, order: object) -> int:
    """``order`` as a non-negative derivative order, else :class:`InputError` naming ``name``."""
    if isinstance(order, bool) or not isinstance(order, (int, np.integer)) or order < 0:
        raise InputError(f"{name}: expected a non-negative integer, got {order!r}")
    return int(order)


@cache
def _exact_conversion(source: Form, target: Form) -> RationalMatrix:
    return _transpose(_matmul(_EXACT[source], _inverse(_EXACT[target])))


@cache
def _basis(form: Form) -> NDArray[np.float64]:
    return _to_array(_EXACT[form])


@cache
def _derivative_basis(form: Form, order: int) -> NDArray[np.float64]:
    result = _basis(form) @ np.linalg.matrix_power(_DERIVATIVE, order)
    result.setflags(write=False)
    return result


@cache
def _conversion(source: Form, target: Form) -> NDArray[np.float64]:
    return _to_array(_exact_conversion(source, target))


def exact_conversion_matrix(source: Form, target: Form) -> RationalMatrix:
    """Exact ``C = (M_source M_target^-1)^T``: control values ``y = C x`` describe the same
    cubic."""
    return _exact_conversion(
        check_choice("source", source, FORMS), check_choice("target", target, FORMS)
    )


def basis_matrix(form: Form) -> NDArray[np.float64]:
    """``M_F`` (4×4, read-only): ``x(t) = x^T M_F [t^3, t^2, t, 1]^T``."""
    return _basis(check_choice("form", form, FORMS))


def derivative_matrix(form: Form, order: int = 1) -> NDArray[np.float64]:
    """``M_F D^order`` (read-only): the basis of the ``order``-th derivative, same convention."""
    return _derivative_basis(check_choice("form", form, FORMS), check_order("order", order))


def conversion_matrix(source: Form, target: Form) -> NDArray[np.float64]:
    """Float64 ``C`` with ``y = C x`` (see :func:`exact_conversion_matrix`)."""
    return _conversion(check_choice("source", source, FORMS), check_choice("target", target, FORMS))


def basis_values(form: Form, t: ArrayLike, order: int = 0) -> NDArray[np.float64]:
    """Values of the four basis functions (or their ``order``-th derivatives) at ``t``.

    Returns shape ``t.shape + (4,)``: ``b[..., i] = (M_F D^order t)_i``. Evaluated in
    Horner form on the power coefficients.
    """
    params = as_float_array("t", t)
    coeffs = derivative_matrix(form, order)  # (4 basis functions, 4 powers t^3..t^0)
    result = np.empty(params.shape + (4,))
    result[...] = coeffs[:, 0]
    for power in range(1, 4):
        result *= params[..., None]
        result += coeffs[:, power]
    return result
