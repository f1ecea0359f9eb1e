"""Batched cubic curves: control values ``(..., 4, dim)`` in one of the three forms.

``c(t) = Σ_i b_i(t) x_i`` with ``b(t) = M_F t`` (see :mod:`g1patch.basis`). Every operation
works on all curves of the batch at once.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .basis import FORMS, Form, basis_matrix, basis_values, conversion_matrix
from .errors import InputError, as_float_array, check_choice

__all__ = ["CubicCurves", "reversal_matrix", "power_coefficients"]

_REVERSAL = {
    # x(1-t) in Hermite form: [p(1), p(0), -p'(1), -p'(0)]
    "hermite": np.array(
        [[0, 1, 0, 0], [1, 0, 0, 0], [0, 0, 0, -1], [0, 0, -1, 0]], dtype=np.float64
    ),
    # Bernstein and uniform B-spline bases are symmetric: reverse the control values.
    "bezier": np.eye(4)[::-1].copy(),
    "bspline": np.eye(4)[::-1].copy(),
}


def reversal_matrix(form: Form) -> NDArray[np.float64]:
    """``R`` with ``y = R x`` the same curve traversed backwards, ``y(t) = x(1 - t)`` (exact)."""
    return _REVERSAL[check_choice("form", form, FORMS)]


def power_coefficients(control: NDArray[np.float64], form: Form) -> NDArray[np.float64]:
    """Power coefficients ``a[..., k, :]`` of ``t^k`` (ascending, k = 0..3) of curves in ``form``.

    ``x(t) = x^T M_F t`` with ``t = [t^3, t^2, t, 1]``, so the coefficient of ``t^(3-p)`` is
    ``Σ_i x_i M_F[i, p]``.
    """
    checked = as_float_array("control", control, (4, None))
    return np.einsum("ip,...id->...pd", basis_matrix(form), checked)[..., ::-1, :]


@dataclass(frozen=True)
class CubicCurves:
    """A batch of cubic curves: ``control`` of shape ``(..., 4, dim)`` in ``form``."""

    control: NDArray[np.float64]
    form: Form = "bezier"

    def __post_init__(self) -> None:
        check_choice("form", self.form, FORMS)
        control = as_float_array("control", self.control, (4, None))
        object.__setattr__(self, "control", control)

    @property
    def dim(self) -> int:
        return int(self.control.shape[-1])

    @property
    def batch_shape(self) -> tuple[int, ...]:
        return tuple(self.control.shape[:-2])

    def evaluate(self, t: ArrayLike, order: int = 0) -> NDArray[np.float64]:
        """Points (or ``order``-th derivatives) at parameters ``t``.

        ``t`` of shape ``(K,)`` is shared by all curves; ``t`` of shape ``batch + (K,)`` gives each
        curve its own parameters. Returns ``batch + (K, dim)``.
        """
        params = as_float_array("t", t)
        if params.ndim not in (1, len(self.batch_shape) + 1) or (
            params.ndim > 1 and params.shape[:-1] != self.batch_shape
        ):
            expected = "(" + ", ".join([*map(str, self.batch_shape), "K"]) + ")"
            raise InputError(f"t: expected shape (K,) or {expected}, got {params.shape}")
        weights = basis_values(self.form, params, order)  # (..., K, 4)
        if params.ndim == 1:
            return np.einsum("ki,...id->...kd", weights, self.control)
        return np.einsum("...ki,...id->...kd", weights, self.control)

    def derivative(self, t: ArrayLike, order: int = 1) -> NDArray[np.float64]:
        """``d^order c / dt^order`` at ``t`` (same shapes as :meth:`evaluate`)."""
        return self.evaluate(t, order)

    def convert(self, form: Form) -> CubicCurves:
        """The same curves in another form: ``y = C x`` with ``C = (M_src M_dst^-1)^T``."""
        check_choice("form", form, FORMS)
        if form == self.form:
            return self
        matrix = conversion_matrix(self.form, form)
        return CubicCurves(np.einsum("ij,...jd->...id", matrix, self.control), form)

    def reversed(self) -> CubicCurves:
        """The same curves traversed from t = 1 to t = 0 (exact in every form)."""
        return CubicCurves(
            np.einsum("ij,...jd->...id", reversal_matrix(self.form), self.control), self.form
        )

    def power_coefficients(self) -> NDArray[np.float64]:
        """Ascending power coefficients, shape ``batch + (4, dim)``."""
        return power_coefficients(self.control, self.form)
