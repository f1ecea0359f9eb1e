"""Batched bicubic tensor-product patches in Hermite, Bézier or uniform B-spline form.

A patch set holds ``control[n, i, j, :]`` with i along u and j along v, and

    p(u, v) = Σ_ij b_i(u) P_ij b_j(v) = u^T M^T P M v        (paper, eqs. 3 and 5)

with ``b(t) = M t`` the basis of the form. In Hermite form the layout is the paper's eq. (4):
i, j ∈ {0, 1} positions at u, v = 0, 1; i ∈ {2, 3} ∂/∂u at u = 0, 1; j ∈ {2, 3} ∂/∂v; and the
block (2..3, 2..3) holds the twists ∂²p/∂u∂v.

Patch edges follow the quad's counter-clockwise corners F0 = (0,0), F1 = (1,0), F2 = (1,1),
F3 = (0,1): edge k runs from corner k to corner k+1 (edges 2 and 3 against the parameter).

With a :class:`~g1patch.frame.Frame` ``(c, s)`` the control is in local coordinates and the surface
is ``c + s p(u, v)``: every evaluation returns world values (positions ``c + s p``, derivatives
``s ∂p``, unit normals unchanged), computed from the local control and mapped afterwards, so the
stored surface keeps the exactness its construction gave it. :meth:`PatchSet.local` is the same
patches in local coordinates, :meth:`PatchSet.world_control` the control in world coordinates.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, cast

import numpy as np
from numpy.typing import ArrayLike, NDArray

from . import _grid
from .basis import FORMS, Form, basis_matrix, basis_values, check_order, conversion_matrix
from .curves import CubicCurves
from .display import BOX_SAMPLES, patch_set_repr, sampled_box
from .errors import InputError, as_batch_array, as_float_array, check_choice
from .frame import Frame, check_frame, in_world

__all__ = [
    "PatchSet",
    "CORNER_PARAMETERS",
    "hs_twists",
    "closure",
    "diagonal_polynomials",
    "polynomial_degree",
]

#: (u, v) of the corners F0..F3.
CORNER_PARAMETERS = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])


def _check_parameters(name: str, values: ArrayLike) -> NDArray[np.float64]:
    params = as_float_array(name, values, (None,), min_ndim=1)
    if params.ndim != 1:
        raise InputError(f"{name}: expected a 1-D array of parameters, got shape {params.shape}")
    return params


def _curve_control_to_world(
    control: NDArray[np.float64], form: Form, frame: Frame | None
) -> NDArray[np.float64]:
    """Curve control (..., 4, 3) in world coordinates: ``c + s x`` for points, ``s x`` for Hermite's
    derivative entries 2, 3."""
    if frame is None:
        return control
    world = frame.vectors_to_world(control)
    world[..., : 2 if form == "hermite" else 4, :] += frame.centre
    return world


@dataclass(frozen=True)
class PatchSet:
    """``N`` bicubic patches: ``control`` of shape ``(N, 4, 4, 3)`` in ``form``, local to ``frame``
    if set."""

    control: NDArray[np.float64]
    form: Form = "bezier"
    #: the surface is ``frame.to_world(p)``; None: control in world coordinates
    frame: Frame | None = None

    def __post_init__(self) -> None:
        check_choice("form", self.form, FORMS)
        control = as_batch_array("control", self.control, (4, 4, 3))
        object.__setattr__(self, "control", control)
        check_frame(self.frame)

    def __len__(self) -> int:
        return int(self.control.shape[0])

    def __repr__(self) -> str:
        """``<PatchSet 6 bezier patches, bbox (-1, -1, -1)…(1, 1, 1)>``."""
        return patch_set_repr("PatchSet", len(self), f"{self.form} patches", self.box)

    def box(self, samples: int = BOX_SAMPLES) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """(lowest, highest) corner of the box around the surface sampled on a ``samples²`` grid
        per patch, world coordinates (:func:`g1patch.display.sampled_box`)."""
        values = basis_values(self.form, np.linspace(0.0, 1.0, samples))  # (samples, 4)
        weights = np.einsum("ia,jb->ijab", values, values).reshape(-1, 16)
        to_world = self.frame.to_world if self.frame is not None else None
        return sampled_box(weights, self.control.reshape(-1, 16, 3), to_world)

    def take(self, indices: ArrayLike) -> PatchSet:
        """The patches at ``indices`` (any integer array, repeats allowed), in that order."""
        return PatchSet(self.control[np.asarray(indices, dtype=np.int64)], self.form, self.frame)

    # ----------------------------------------------------------------- frame
    def local(self) -> PatchSet:
        """The same control without the frame: the patches in local coordinates (``self`` if no
        frame)."""
        return self if self.frame is None else PatchSet(self.control, self.form)

    def with_frame(self, frame: Frame | None) -> PatchSet:
        """The same control read in ``frame`` (None: as world coordinates)."""
        return PatchSet(self.control, self.form, check_frame(frame))

    def local_to(self, frame: Frame) -> PatchSet:
        """The same surface in ``frame``'s local coordinates, without a frame: positions
        ``(W − c)/s``, Hermite's derivative and twist entries ``W/s``."""
        world = self.world_control()
        local = frame.vectors_to_local(world)
        positions = (slice(None), slice(0, 2), slice(0, 2)) if self.form == "hermite" else ...
        local[positions] = frame.to_local(world[positions])
        return PatchSet(local, self.form)

    def world_control(self) -> NDArray[np.float64]:
        """Control in world coordinates (``control`` itself without a frame), (N, 4, 4, 3).

        Bézier and B-spline control points map as positions, ``c + s P``; in Hermite form only the
        corner positions ``P[:, :2, :2]`` do, the derivative and twist entries map as vectors, ``s
        P``.
        """
        if self.frame is None:
            return self.control
        world = self.frame.vectors_to_world(self.control)
        if self.form == "hermite":
            world[:, :2, :2] += self.frame.centre
        else:
            world += self.frame.centre
        return world

    def to_arrays(self) -> dict[str, NDArray[Any]]:
        """The arrays a network file stores: ``control`` (N, 4, 4, 3), ``form`` (a 0-d string) and
        the frame's (:meth:`Frame.to_arrays`) when set."""
        frame = {} if self.frame is None else self.frame.to_arrays()
        return {"control": self.control, "form": np.array(self.form), **frame}

    @classmethod
    def from_arrays(cls, arrays: Mapping[str, ArrayLike]) -> PatchSet:
        """Inverse of :meth:`to_arrays`."""
        if "control" not in arrays or "form" not in arrays:
            raise InputError(
                "arrays: bicubic patches need the arrays 'control' and 'form', got "
                f"{sorted(arrays)}"
            )
        form = cast(Form, str(np.asarray(arrays["form"])))  # checked by __post_init__
        return cls(np.asarray(arrays["control"]), form, Frame.from_arrays(arrays))

    # ------------------------------------------------------------------ forms
    def convert(self, form: Form) -> PatchSet:
        """The same surfaces in another form: ``P' = C P C^T`` per coordinate, on the local control
        (the frame is kept: conversion is linear and the frame applies after evaluation)."""
        check_choice("form", form, FORMS)
        if form == self.form:
            return self
        matrix = conversion_matrix(self.form, form)
        return PatchSet(
            np.einsum("ik,nkld,jl->nijd", matrix, self.control, matrix, optimize=True),
            form,
            self.frame,
        )

    def power_coefficients(self) -> NDArray[np.float64]:
        """``A = M^T P M`` per coordinate, shape (N, 4, 4, 3): ``p = Σ A_ij u^(3-i) v^(3-j)``, in
        world coordinates (with a frame: ``s A``, plus ``c`` on the constant term ``A_33``)."""
        matrix = basis_matrix(self.form)
        power = np.einsum("ip,nijd,jq->npqd", matrix, self.control, matrix, optimize=True)
        if self.frame is not None:
            self.frame.vectors_to_world(power, out=power)
            power[:, 3, 3] += self.frame.centre
        return power

    def _to_world(self, values: NDArray[np.float64], du: int, dv: int) -> NDArray[np.float64]:
        """Local values of ``∂^(du+dv) p`` mapped to world in place (:func:`frame.in_world`)."""
        return in_world(self.frame, values, du + dv)

    # ------------------------------------------------------------- evaluation
    def evaluate_grid(
        self,
        u: ArrayLike,
        v: ArrayLike | None = None,
        du: int = 0,
        dv: int = 0,
        out: NDArray[np.float64] | None = None,
    ) -> NDArray[np.float64]:
        """``∂^(du+dv) p / ∂u^du ∂v^dv`` on the grid ``u × v``: shape ``(N, len(u), len(v), 3)``,
        world values.

        ``out``: a C-contiguous float64 array of that shape to write into (saves the page faults
        of a fresh allocation when a grid is evaluated repeatedly).
        """
        du, dv = check_order("du", du), check_order("dv", dv)
        u_params = _check_parameters("u", u)
        v_params = u_params if v is None else _check_parameters("v", v)
        weights_u = basis_values(self.form, u_params, du)
        weights_v = basis_values(self.form, v_params, dv)
        return self._to_world(_grid.contract(self.control, weights_u, weights_v, out=out), du, dv)

    def grid(self, resolution: int) -> NDArray[np.float64]:
        """Positions on a uniform ``resolution × resolution`` grid including the borders."""
        return self.evaluate_grid(np.linspace(0.0, 1.0, _check_resolution(resolution)))

    def evaluate(self, uv: ArrayLike, du: int = 0, dv: int = 0) -> NDArray[np.float64]:
        """Derivative ``(du, dv)`` at scattered parameters.

        ``uv`` of shape ``(K, 2)`` is shared by all patches; ``(N, K, 2)`` gives each patch its own.
        Returns ``(N, K, 3)``, world values.
        """
        du, dv = check_order("du", du), check_order("dv", dv)
        params = as_float_array("uv", uv, (2,))
        count = len(self)
        if params.ndim == 2:
            # p[n, k] = Σ_(i,j) (wu[k, i] wv[k, j]) P[n, i, j]: one (K × 16) @ (16 × 3) product per
            # patch
            weights_u = basis_values(self.form, params[:, 0], du)
            weights_v = basis_values(self.form, params[:, 1], dv)
            tensor = (weights_u[:, :, None] * weights_v[:, None, :]).reshape(-1, 16)
            return self._to_world(np.matmul(tensor, self.control.reshape(count, 16, 3)), du, dv)
        if params.ndim == 3 and params.shape[0] == count:
            # contract v first: q[n, k, i] = Σ_j wv[n, k, j] P[n, i, j], then u
            weights_u = basis_values(self.form, params[..., 0], du)
            weights_v = basis_values(self.form, params[..., 1], dv)
            by_v = self.control.transpose(0, 2, 1, 3).reshape(count, 4, 12)
            partial = np.matmul(weights_v, by_v).reshape(count, -1, 4, 3)
            return self._to_world(np.einsum("nki,nkid->nkd", weights_u, partial), du, dv)
        raise InputError(f"uv: expected shape (K, 2) or ({len(self)}, K, 2), got {params.shape}")

    def tangents(self, uv: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """``(p_u, p_v)`` at scattered parameters, each ``(N, K, 3)``."""
        return self.evaluate(uv, 1, 0), self.evaluate(uv, 0, 1)

    def twist(self, uv: ArrayLike) -> NDArray[np.float64]:
        """``p_uv`` at scattered parameters, ``(N, K, 3)``."""
        return self.evaluate(uv, 1, 1)

    def normals(self, uv: ArrayLike) -> NDArray[np.float64]:
        """Unit normals ``n = p_u × p_v / |p_u × p_v|`` (paper, eq. 10), ``(N, K, 3)``.

        Where ``p_u × p_v`` is exactly zero the normal is the zero vector, never NaN. On a collapsed
        edge away from the origin the derivative is rounding noise and so is its direction: use
        :func:`g1patch.continuity.check`, which counts such normals with a tolerance. Computed from
        the local tangents (the frame does not turn normals).
        """
        local = self.local()
        return unit(np.cross(local.evaluate(uv, 1, 0), local.evaluate(uv, 0, 1)))

    def normals_grid(self, u: ArrayLike, v: ArrayLike | None = None) -> NDArray[np.float64]:
        """Unit normals on the grid ``u × v``, ``(N, len(u), len(v), 3)``; zero where degenerate."""
        u_params = _check_parameters("u", u)
        v_params = u_params if v is None else _check_parameters("v", v)
        return _grid.normals(self.control, self.form, u_params, v_params)

    def evaluate_grid_with_normals(
        self,
        u: ArrayLike,
        v: ArrayLike | None = None,
        out: NDArray[np.float64] | None = None,
        normals_out: NDArray[np.float64] | None = None,
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Positions and unit normals on the grid ``u × v``, each ``(N, len(u), len(v), 3)``, in one
        pass.

        Equal to ``(evaluate_grid(u, v), normals_grid(u, v))``; the normal is zero where degenerate.
        ``out`` / ``normals_out``: arrays to write into, as in :meth:`evaluate_grid`.
        """
        u_params = _check_parameters("u", u)
        v_params = u_params if v is None else _check_parameters("v", v)
        positions, normals = _grid.positions_and_normals(
            self.control, self.form, u_params, v_params, out, normals_out
        )
        return self._to_world(positions, 0, 0), normals

    def corners(self) -> NDArray[np.float64]:
        """Corner positions F0..F3 (world), shape (N, 4, 3)."""
        return self.evaluate(CORNER_PARAMETERS)

    # ------------------------------------------------------------------ curves
    def boundary_curves(self) -> CubicCurves:
        """The four boundary curves (world), batch shape (N, 4), counter-clockwise: edge k runs
        corner k → k+1.

        Curve v = v0 in the u-form: ``c_i = Σ_j b_j(v0) P_ij``: exact in Hermite and Bézier form
        (the weights are 0 and 1), rounded in B-spline form (weights 1/6, 4/6, 1/6); then mapped
        to world (:meth:`world_control`'s rule for curves).
        """
        ends = basis_values(self.form, np.array([0.0, 1.0]))  # (2, 4)
        bottom = np.einsum("j,nijd->nid", ends[0], self.control)  # v = 0, u: 0 -> 1
        right = np.einsum("i,nijd->njd", ends[1], self.control)  # u = 1, v: 0 -> 1
        top = np.einsum("j,nijd->nid", ends[1], self.control)  # v = 1, u: 0 -> 1 (reverse)
        left = np.einsum("i,nijd->njd", ends[0], self.control)  # u = 0, v: 0 -> 1 (reverse)
        forward = CubicCurves(np.stack([bottom, right, top, left], axis=1), self.form)
        backward = forward.reversed()
        control = np.where(
            np.array([False, False, True, True])[None, :, None, None],
            backward.control,
            forward.control,
        )
        return CubicCurves(_curve_control_to_world(control, self.form, self.frame), self.form)

    def diagonal_polynomials(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Power coefficients (ascending, degree 6) of ``D(t) = p(t, t)`` and ``E(t) = p(t, 1-t)``.

        Each is shape (N, 7, 3), world coordinates. See :func:`diagonal_polynomials`.
        """
        return diagonal_polynomials(self.power_coefficients())

    def with_coons_twists(self) -> PatchSet:
        """The S-/HS-patch: the same boundary, twists from the 12 boundary vectors
        (:func:`hs_twists`).

        Computed on the local control; the frame is kept."""
        hermite = self.convert("hermite").control.copy()
        hermite[:, 2:, 2:] = hs_twists(hermite)
        return PatchSet(hermite, "hermite", self.frame).convert(self.form)

    def closure(self) -> NDArray[np.float64]:
        """The vector ``C`` of :func:`closure` (world: ``s C_local``), shape (N, 3): both diagonals
        cubic iff ``C = 0``."""
        value = closure(self.convert("hermite").control)
        return value if self.frame is None else self.frame.vectors_to_world(value, out=value)


def _check_resolution(resolution: int) -> int:
    if not isinstance(resolution, (int, np.integer)) or resolution < 2:
        raise InputError(f"resolution: expected an integer ≥ 2, got {resolution!r}")
    return int(resolution)


def unit(vectors: NDArray[np.float64]) -> NDArray[np.float64]:
    """``x / |x|`` along the last axis; the zero vector stays zero (no NaN)."""
    length = np.linalg.norm(vectors, axis=-1, keepdims=True)
    return np.divide(vectors, length, out=np.zeros_like(vectors), where=length > 0)


def _corner_defect(control: NDArray[np.float64]) -> NDArray[np.float64]:
    """``δ = p(0,1) + p(1,0) − p(0,0) − p(1,1)`` of Hermite control ``(..., 4, 4, 3)``."""
    return (
        control[..., 0, 1, :]
        + control[..., 1, 0, :]
        - control[..., 0, 0, :]
        - control[..., 1, 1, :]
    )


def hs_twists(hermite: ArrayLike) -> NDArray[np.float64]:
    """Twists of the S-/HS-patch from the 12 boundary vectors of Hermite patches ``(N, 4, 4, 3)``.

    With ``δ = p(0,1) + p(1,0) − p(0,0) − p(1,1)``:

        p_uv(a, b) = δ + [p_u(a, 1) − p_u(a, 0)] + [p_v(1, b) − p_v(0, b)]     a, b ∈ {0, 1}

    which makes the patch the bilinearly blended Coons patch of its four boundary cubics
    (the power coefficients of u^3 v^3, u^3 v^2, u^2 v^3 and u^2 v^2 vanish). Returns (N, 2, 2, 3).
    """
    control = as_float_array("hermite", hermite, (4, 4, 3))
    delta = _corner_defect(control)
    p_u = control[..., 2:4, 0:2, :]  # p_u[a, b] = ∂p/∂u at corner (a, b)
    p_v = control[..., 0:2, 2:4, :]  # p_v[a, b] = ∂p/∂v at corner (a, b)
    u_term = (p_u[..., :, 1, :] - p_u[..., :, 0, :])[..., :, None, :]  # depends on a
    v_term = (p_v[..., 1, :, :] - p_v[..., 0, :, :])[..., None, :, :]  # depends on b
    return delta[..., None, None, :] + u_term + v_term


def closure(hermite: ArrayLike) -> NDArray[np.float64]:
    """The closure vector of an S-/HS-patch with Hermite control ``(N, 4, 4, 3)``, shape (N, 3).

        C = 4δ + [p_u(0,1) + p_u(1,1) − p_u(0,0) − p_u(1,0)]
               + [p_v(1,0) + p_v(1,1) − p_v(0,0) − p_v(0,1)]

    With Coons twists the diagonal and anti-diagonal have t^4 coefficients +C and −C: both are
    cubic iff ``C = 0``. C depends on the boundary only.
    """
    control = as_float_array("hermite", hermite, (4, 4, 3))
    delta = _corner_defect(control)
    p_u = control[..., 2:4, 0:2, :]
    p_v = control[..., 0:2, 2:4, :]
    u_sum = p_u[..., 0, 1, :] + p_u[..., 1, 1, :] - p_u[..., 0, 0, :] - p_u[..., 1, 0, :]
    v_sum = p_v[..., 1, 0, :] + p_v[..., 1, 1, :] - p_v[..., 0, 0, :] - p_v[..., 0, 1, :]
    return 4.0 * delta + u_sum + v_sum


def _binomial_rows() -> NDArray[np.float64]:
    """``rows[m, k]`` = coefficient of t^k in (1 − t)^m, m, k = 0..3."""
    rows = np.zeros((4, 4))
    rows[0, 0] = 1.0
    for m in range(1, 4):
        rows[m, : m + 1] = np.convolve(rows[m - 1, :m], [1.0, -1.0])
    return rows


_ONE_MINUS_T = _binomial_rows()


def diagonal_polynomials(power: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Diagonal and anti-diagonal of patches given by power coefficients ``A`` (N, 4, 4, 3).

    ``p(u, v) = Σ A_ij u^(3-i) v^(3-j)``; ``D(t) = p(t, t) = Σ A_ij t^(6-i-j)`` and
    ``E(t) = p(t, 1-t) = Σ A_ij t^(3-i) (1-t)^(3-j)``. Both returned as ascending coefficients
    (N, 7, 3); exact integer arithmetic on the coefficients, so no rounding beyond the sums.
    """
    coefficients = as_float_array("power", power, (4, 4, 3))
    batch = coefficients.shape[:-3]
    diagonal = np.zeros(batch + (7, 3))
    anti = np.zeros(batch + (7, 3))
    for i in range(4):
        for j in range(4):
            a_ij = coefficients[..., i, j, :]
            diagonal[..., 6 - i - j, :] += a_ij
            for k in range(4 - j):  # (1-t)^(3-j) = Σ_k rows[3-j, k] t^k
                anti[..., 3 - i + k, :] += _ONE_MINUS_T[3 - j, k] * a_ij
    return diagonal, anti


def polynomial_degree(coefficients: ArrayLike, rtol: float = 1e-12) -> NDArray[np.int64]:
    """Degree of vector polynomials with ascending coefficients ``(..., K, dim)``.

    A coefficient counts as zero when its norm is ≤ ``rtol`` × the largest coefficient norm of
    that polynomial. The default, ~4500 ULP, sits above the rounding of the power-form sums for
    control values spanning twelve orders of magnitude (measured: ≤ 70 ULP) and far below any
    coefficient that shapes a curve. The zero polynomial has degree 0.
    """
    if not (isinstance(rtol, (float, int)) and 0 <= rtol < 1):
        raise InputError(f"rtol: expected a number in [0, 1), got {rtol!r}")
    coeffs = as_float_array("coefficients", coefficients, (None, None))
    norms = np.linalg.norm(coeffs, axis=-1)
    scale = norms.max(axis=-1, keepdims=True)
    significant = norms > rtol * scale
    last = coeffs.shape[-2] - 1 - np.argmax(significant[..., ::-1], axis=-1)
    return np.where(significant.any(axis=-1), last, 0).astype(np.int64)
