"""Batched Gregory patches: bicubic boundary curves, rational interior, ``points`` of shape (N, 20,
3).

A Gregory patch is the bicubic Bézier patch ``p(u, v) = Σ_ij B_i(u) B_j(v) b_ij`` whose four
interior points are blends of two points each, one per edge meeting at that corner (Gregory 1974;
OpenSubdiv's ``EvalBasisGregory`` uses the same weights). Corners and edges are numbered like a
quad (see :mod:`g1patch.patches`): corner k is F_k, edge k runs from corner k to corner k + 1.

Layout of ``points[n, m]`` (Bézier index ``(i, j)``, i along u, j along v):

======  =====================================================  ==============================
m       point                                                  b_ij
======  =====================================================  ==============================
0..3    corner P_k                                             b00, b30, b33, b03
4 + 2k  edge point E+_k on edge k, next to corner k            b10, b31, b23, b02  (k = 0..3)
5 + 2k  edge point E-_k on edge k − 1, next to corner k        b01, b20, b32, b13
12 + 2k interior point Fn_k at corner k, seen by edge k        b11, b21, b22, b12  (blended)
13 + 2k interior point Fp_k at corner k, seen by edge k − 1
======  =====================================================  ==============================

So the boundary curve of edge k is the cubic Bézier curve ``(P_k, E+_k, E-_{k+1}, P_{k+1})``.
With ``d_e`` the distance of (u, v) to the line of edge e (``d = (v, 1 − u, 1 − v, u)``), corner
k blends its pair with the distances to its two edges, ``α = d_{k−1}`` and ``β = d_k``:

    b_k(u, v) = (α Fn_k + β Fp_k) / (α + β) = w_α Fn_k + w_β Fp_k,

so on edge k (β = 0) the patch sees only Fn_k and on edge k − 1 (α = 0) only Fp_k: corner 0 is
``b11 = (u Fn_0 + v Fp_0)/(u + v)``. The Bernstein factor of corner k factors as
``B_k = Q_k α β`` with ``Q_k = 9 d_{k+1}² d_{k+2}²``; by the quotient rule

    ∂(B_k b_k)/∂u = ∂B_k/∂u (w_α Fn_k + w_β Fp_k) + Q_k w_α w_β (α_u β − α β_u) (Fn_k − Fp_k)

and likewise for v. Every factor is bounded, so positions and first derivatives are evaluated
without dividing by a vanishing ``α + β``; at corner k (α = β = 0) both B_k and its gradient
vanish, so the blend's 0/0 takes no part and the limit is exact (w_α = w_β = ½ is used there).

The weights sum to one (the derivative weights to zero), so a :class:`~g1patch.frame.Frame`
``(c, s)`` applies after evaluation: with a frame the points are local and the surface is
``c + s p(u, v)``; evaluations return world values (derivatives ``s ∂p``, normals unchanged).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import ClassVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .basis import basis_values
from .curves import CubicCurves
from .display import BOX_SAMPLES, patch_set_repr, sampled_box
from .errors import InputError, as_batch_array, as_float_array
from .frame import Frame, check_frame, in_world
from .patches import CORNER_PARAMETERS, unit

__all__ = ["BEZIER_INDEX", "INTERIOR_INDEX", "GregoryPatchSet", "gregory_weights"]

#: Bézier index (i, j) of points 0..11 (corners and edge points).
BEZIER_INDEX = np.array(
    [(0, 0), (3, 0), (3, 3), (0, 3), (1, 0), (0, 1), (3, 1), (2, 0), (2, 3), (3, 2), (0, 2), (1, 3)]
)
#: Bézier index (i, j) of the blended interior point of corner k (pair 12 + 2k, 13 + 2k).
INTERIOR_INDEX = np.array([(1, 1), (2, 1), (2, 2), (1, 2)])

# d = (v, 1 − u, 1 − v, u): derivatives of the edge distances by u and by v.
_DIST_DU = np.array([0.0, -1.0, 0.0, 1.0])
_DIST_DV = np.array([1.0, 0.0, -1.0, 0.0])
_PREV = np.array([3, 0, 1, 2])  # edge k − 1
_OPPOSITE = (np.array([1, 2, 3, 0]), np.array([2, 3, 0, 1]))  # edges k + 1 and k + 2


def _check_orders(du: int, dv: int) -> tuple[int, int]:
    if not all(isinstance(d, (int, np.integer)) and d >= 0 for d in (du, dv)) or du + dv > 1:
        raise InputError(
            f"du, dv: Gregory patches evaluate positions and first derivatives only "
            f"(non-negative integers, du + dv ≤ 1), got du={du!r}, dv={dv!r}"
        )
    return int(du), int(dv)


def _check_domain(name: str, params: NDArray[np.float64]) -> NDArray[np.float64]:
    outside = (params < 0.0) | (params > 1.0)
    if outside.any():
        bad = np.argwhere(outside)[0]
        raise InputError(
            f"{name}: Gregory patches are defined on [0, 1]², got {params[tuple(bad)]} at index "
            f"{tuple(int(i) for i in bad)}"
        )
    return params


def gregory_weights(u: ArrayLike, v: ArrayLike, du: int = 0, dv: int = 0) -> NDArray[np.float64]:
    """Weights of the 20 points in ``∂^(du+dv) p / ∂u^du ∂v^dv`` at (u, v), shape ``broadcast +
    (20,)``.

    ``p = Σ_m W[m] points[m]`` (see the module docstring); du + dv ≤ 1, (u, v) in [0, 1]².
    """
    du, dv = _check_orders(du, dv)
    u_params, v_params = np.broadcast_arrays(as_float_array("u", u), as_float_array("v", v))
    _check_domain("u", u_params)
    _check_domain("v", v_params)
    bu = basis_values("bezier", u_params, du)
    bv = basis_values("bezier", v_params, dv)
    weights = np.empty(u_params.shape + (20,))
    weights[..., :12] = bu[..., BEZIER_INDEX[:, 0]] * bv[..., BEZIER_INDEX[:, 1]]

    dist = np.stack([v_params, 1.0 - u_params, 1.0 - v_params, u_params], axis=-1)
    alpha, beta = dist[..., _PREV], dist
    total = alpha + beta
    inside = total > 0.0
    safe = np.where(inside, total, 1.0)
    w_alpha = np.where(inside, alpha / safe, 0.5)
    w_beta = np.where(inside, beta / safe, 0.5)
    bernstein = bu[..., INTERIOR_INDEX[:, 0]] * bv[..., INTERIOR_INDEX[:, 1]]
    weights[..., 12::2] = bernstein * w_alpha
    weights[..., 13::2] = bernstein * w_beta
    if du or dv:
        grad = _DIST_DU if du else _DIST_DV
        q = 9.0 * (dist[..., _OPPOSITE[0]] * dist[..., _OPPOSITE[1]]) ** 2
        blend = q * w_alpha * w_beta * (grad[_PREV] * beta - alpha * grad)
        weights[..., 12::2] += blend
        weights[..., 13::2] -= blend
    return weights


def _contract(weights: NDArray[np.float64], points: NDArray[np.float64]) -> NDArray[np.float64]:
    """``out[n, k] = Σ_m W[k, m] points[n, m]`` for shared (K, 20) or per-patch (N, K, 20) weights.

    Shared weights make one matrix product ``(N, 60) @ (W ⊗ I_3)ᵀ`` written straight into the
    C-contiguous (N, K, 3) result (the Kronecker zeros add exactly nothing).
    """
    if weights.ndim == 3:
        return np.matmul(weights, points)
    count, samples = points.shape[0], weights.shape[0]
    out = np.empty((count, samples, 3))
    np.matmul(
        points.reshape(count, 60),
        np.kron(weights, np.eye(3)).T,
        out=out.reshape(count, 3 * samples),
    )
    return out


@dataclass(frozen=True)
class GregoryPatchSet:
    """``N`` Gregory patches: ``points`` of shape ``(N, 20, 3)`` in the layout of the module
    docstring, local to ``frame`` if set."""

    points: NDArray[np.float64]
    #: the surface is ``frame.to_world(p)``; None: points in world coordinates
    frame: Frame | None = None
    kind: ClassVar[str] = "gregory"

    def __post_init__(self) -> None:
        points = as_batch_array("points", self.points, (20, 3))
        object.__setattr__(self, "points", points)
        check_frame(self.frame)

    def __len__(self) -> int:
        return int(self.points.shape[0])

    def __repr__(self) -> str:
        """``<GregoryPatchSet 6 patches, bbox (-1, -1, -1)…(1, 1, 1)>``."""
        return patch_set_repr("GregoryPatchSet", len(self), "patches", self.box)

    def box(self, samples: int = BOX_SAMPLES) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """(lowest, highest) corner of the box around the surface sampled on a ``samples²`` grid
        per patch, world coordinates (:func:`g1patch.display.sampled_box`)."""
        t = np.linspace(0.0, 1.0, samples)
        weights = gregory_weights(t[:, None], t[None, :]).reshape(-1, 20)
        to_world = self.frame.to_world if self.frame is not None else None
        return sampled_box(weights, self.points, to_world)

    def take(self, indices: ArrayLike) -> GregoryPatchSet:
        """The patches at ``indices`` (any integer array, repeats allowed), in that order."""
        return GregoryPatchSet(self.points[np.asarray(indices, dtype=np.int64)], self.frame)

    # ----------------------------------------------------------------- frame
    def local(self) -> GregoryPatchSet:
        """The same points without the frame: the patches in local coordinates (``self`` if no
        frame)."""
        return self if self.frame is None else GregoryPatchSet(self.points)

    def with_frame(self, frame: Frame | None) -> GregoryPatchSet:
        """The same points read in ``frame`` (None: as world coordinates)."""
        return GregoryPatchSet(self.points, check_frame(frame))

    def local_to(self, frame: Frame) -> GregoryPatchSet:
        """The same surface in ``frame``'s local coordinates, ``(W − c)/s``, without a frame."""
        return GregoryPatchSet(frame.to_local(self.world_points()))

    def world_points(self) -> NDArray[np.float64]:
        """Points in world coordinates, ``c + s P`` (``points`` itself without a frame), (N, 20,
        3)."""
        return self.points if self.frame is None else self.frame.to_world(self.points)

    def _to_world(self, values: NDArray[np.float64], du: int, dv: int) -> NDArray[np.float64]:
        """Local values of ``∂^(du+dv) p`` mapped to world in place (:func:`frame.in_world`)."""
        return in_world(self.frame, values, du + dv)

    # ------------------------------------------------------------- evaluation
    def evaluate(self, uv: ArrayLike, du: int = 0, dv: int = 0) -> NDArray[np.float64]:
        """Position (du = dv = 0) or first derivative at scattered parameters in [0, 1]².

        ``uv`` of shape ``(K, 2)`` is shared by all patches; ``(N, K, 2)`` gives each patch its own.
        Returns ``(N, K, 3)``, world values.
        """
        params = _check_domain("uv", as_float_array("uv", uv, (2,)))
        if params.ndim == 2:
            return self._to_world(
                _contract(gregory_weights(params[:, 0], params[:, 1], du, dv), self.points), du, dv
            )
        if params.ndim == 3 and params.shape[0] == len(self):
            # Per-patch parameters usually repeat (edge samples, grids): weigh each distinct (u, v)
            # once.
            keys, inverse = np.unique(
                params.view(np.complex128)[..., 0], return_inverse=True
            )  # u + iv
            weights = gregory_weights(keys.real, keys.imag, du, dv)
            return self._to_world(
                _contract(weights[inverse.reshape(params.shape[:2])], self.points), du, dv
            )
        raise InputError(f"uv: expected shape (K, 2) or ({len(self)}, K, 2), got {params.shape}")

    def evaluate_grid(
        self, u: ArrayLike, v: ArrayLike | None = None, du: int = 0, dv: int = 0
    ) -> NDArray[np.float64]:
        """Position or first derivative on the grid ``u × v``: shape ``(N, len(u), len(v), 3)``,
        world values."""
        u_params = _check_parameters("u", u)
        v_params = u_params if v is None else _check_parameters("v", v)
        weights = gregory_weights(u_params[:, None], v_params[None, :], du, dv)
        values = _contract(weights.reshape(-1, 20), self.points)
        return self._to_world(values, du, dv).reshape(len(self), len(u_params), len(v_params), 3)

    def normals(self, uv: ArrayLike) -> NDArray[np.float64]:
        """Unit normals ``p_u × p_v / |p_u × p_v|``, ``(N, K, 3)``; the zero vector where
        degenerate.

        Computed from the local tangents (the frame does not turn normals)."""
        local = self.local()
        return unit(np.cross(local.evaluate(uv, 1, 0), local.evaluate(uv, 0, 1)))

    def corners(self) -> NDArray[np.float64]:
        """Corner positions F0..F3 (world), shape (N, 4, 3) (exactly ``world_points()[:, :4]``)."""
        return self.evaluate(CORNER_PARAMETERS)

    # ----------------------------------------------------------- conversions
    def boundary_curves(self) -> CubicCurves:
        """The four boundary curves in Bézier form (world), batch (N, 4), counter-clockwise: edge k
        is ``(P_k, E+_k, E-_{k+1}, P_{k+1})``."""
        k = np.arange(4)
        following = (k + 1) % 4
        index = np.stack(
            [k, 4 + 2 * k, 5 + 2 * following, following], axis=1
        )  # (4 edges, 4 points)
        return CubicCurves(self.world_points()[:, index], "bezier")

    def to_bezier_control(self) -> NDArray[np.float64]:
        """The bicubic Bézier net (N, 4, 4, 3) with each interior pair replaced by its mean.

        In the coordinates of ``points`` (local when framed: ``PatchSet(net, frame=self.frame)`` is
        the surface). Same boundary curves and corner tangent planes; the surface equals the Gregory
        patch exactly when every pair coincides, and is not G1 across edges in general.
        """
        net = np.empty((len(self), 4, 4, 3))
        net[:, BEZIER_INDEX[:, 0], BEZIER_INDEX[:, 1]] = self.points[:, :12]
        net[:, INTERIOR_INDEX[:, 0], INTERIOR_INDEX[:, 1]] = 0.5 * (
            self.points[:, 12::2] + self.points[:, 13::2]
        )
        return net

    def to_arrays(self) -> dict[str, NDArray[np.float64]]:
        """The arrays a network file stores: ``{"points": (N, 20, 3)}``, and the frame's
        (:meth:`Frame.to_arrays`) when set."""
        return {"points": self.points, **({} if self.frame is None else self.frame.to_arrays())}

    @classmethod
    def from_arrays(cls, arrays: Mapping[str, ArrayLike]) -> GregoryPatchSet:
        """Inverse of :meth:`to_arrays`."""
        if "points" not in arrays:
            raise InputError(
                f"arrays: Gregory patches need the array 'points', got {sorted(arrays)}"
            )
        return cls(np.asarray(arrays["points"]), Frame.from_arrays(arrays))


def _check_parameters(name: str, values: ArrayLike) -> NDArray[np.float64]:
    params = as_float_array(name, values, (None,), min_ndim=1)
    if params.ndim != 1:
        raise InputError(f"{name}: expected a 1-D array of parameters, got shape {params.shape}")
    return _check_domain(name, params)
