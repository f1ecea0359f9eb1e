"""Exact G1 from any valid targets: the Gregory assembly with flexible fans (shape-quality.md §3.4).

One Gregory patch per quad (:mod:`g1patch.gregory`): corners at the target positions, edge points
``A + t/3`` from the target tangents (projected onto the tangent plane of their vertex, which is
all G1 asks at corners), and per corner two interior points, one per edge, so every edge is
solved on its own. For an interior edge A → B with boundary cubic ``c = (A, b1, b2, B)``, face L
holding A → B and face R holding B → A, cross-boundary derivatives D_L, D_R (cubic, pointing into
each face) are made to satisfy the general G1 identity

    α(t) D_L(t) + β(t) D_R(t) = Φ(t) c'(t),     α, β > 0 linear, Φ quadratic,              (G1)

which makes ``c' × D_L`` and ``D_R × c'`` parallel for every t: the tangent planes agree.

* **Corner split.** At A, with ``[x, y] = (x × y)·N_A``, ``q = c'(0) = t_AB`` and the fan's other
  tangents of L and R there, d_L (counter-clockwise next) and d_R (clockwise previous):
  ``α = 2[d_R, q]/Δ``, ``β = 2[q, d_L]/Δ``, ``φ = −2[d_L, d_R]/Δ``, ``Δ = [q, d_L] + [d_R, q]``, so
  ``α d_L + β d_R = φ q`` and α + β = 2; at B the same with ``q = c'(1) = −t_BA``. α, β > 0 iff
  the fan turns counter-clockwise there (the targets' job). A regular star gives α = β = 1 and
  φ = 2 cos(2π/n), the symmetric form.
* **All solutions** (the "k-h form"): ``D_L = β G + h_L c'``, ``D_R = −α G + h_R c'`` with G
  quadratic and h_L, h_R linear satisfy (G1) identically, ``α D_L + β D_R = (α h_L + β h_R) c'``.
  The end values fix ``G0 = (d_L(A) − h_L0 q0)/β0``, ``G2 = (d_L(B) − h_L1 q2)/β1``,
  ``h_R0 = (φ0 − α0 h_L0)/β0``, ``h_R1 = (φ2 − α1 h_L1)/β1``; ``h_L0 = 0`` fixes the gauge
  (``G → G + σ c'`` with ``h_L → h_L − σ β``, ``h_R → h_R + σ α`` changes nothing), which leaves
  G1 (a vector) and h_L1 free: fitted to the four interior targets by ridge least squares.
  Interior Bézier coefficients of the product forms:
  ``d1 = (2β0 G1 + β1 G0)/3 + (2 h0 q1 + h1 q0)/3``, ``d2 = (β0 G2 + 2β1 G1)/3 + (h0 q2 + 2 h1 q1)/3``
  (L; R with −α for β and h_R), ``q1 = 3(b2 − b1)``; interior points ``b1 + d1/3``, ``b2 + d2/3``.
* **Symmetric edges** (α ≡ β ≡ 1 at both ends, as on any C1 data): there the k-h family is a
  4-dimensional part of the 6-dimensional solution set ``D_L + D_R = Φ c'`` with Φ linear, so
  those edges take the minimum-norm correction of their targets onto it instead: both sides
  move by the same vector, and targets that are already G1 (a bicubic B-spline) come back unchanged.

Boundary edges and seams (``Targets.seams``: creased on purpose) keep their targets: the two faces
of a seam share its boundary cubic (C0) and each keeps its own cross-boundary derivative. At a
vertex the corner split of an edge uses the normal of the edge's sector
(``Targets.corner_normals``), and every slot tangent is moved into its sectors' planes
(:func:`tangent_plane_tangents`), so each sector is G1 at the corner by itself. Every step is a gather, a scatter or a batched 4 × 4 solve
over edges: no Python loop over vertices, edges or faces.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ..errors import ConstructionError
from ..gregory import GregoryPatchSet
from ..mesh import QuadTopology
from ..targets import Targets, halfedge_slots, slot_sector_normals

__all__ = ["assemble_gregory", "corner_split", "tangent_plane_tangents"]

FloatArray = NDArray[np.float64]

#: edges whose corner splits are within this of α = β = 1 at both ends take the symmetric form
SYMMETRIC_TOLERANCE = 1e-12
#: ridge of the k-h fit, relative to the largest diagonal entry of its normal equations: keeps
#: the free values bounded where G1 and h_L1 are nearly dependent (edge cubic nearly quadratic,
#: α nearly constant), which would otherwise inflate round-off (shape-quality.md §3.4)
RIDGE = 1e-6


def _dot(a: FloatArray, b: FloatArray) -> FloatArray:
    return np.einsum("...d,...d->...", a, b)


def _bracket(a: FloatArray, b: FloatArray, n: FloatArray) -> FloatArray:
    """``[a, b] = (a × b)·n``, by components (rows of 3-vectors)."""
    a0, a1, a2 = a[:, 0], a[:, 1], a[:, 2]
    b0, b1, b2 = b[:, 0], b[:, 1], b[:, 2]
    return (a1 * b2 - a2 * b1) * n[:, 0] + (a2 * b0 - a0 * b2) * n[:, 1] + (a0 * b1 - a1 * b0) * n[:, 2]


def corner_split(
    q: FloatArray, d_left: FloatArray, d_right: FloatArray, normal: FloatArray
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    """``(α, β, φ, Δ-sign check)`` with ``α d_L + β d_R = φ q`` and ``α + β = 2`` (module docstring).

    The last value is ``min([q, d_L], [d_R, q])`` relative to the vectors' sizes: positive iff
    d_L and d_R lie on opposite sides of q, counter-clockwise and clockwise from it.
    """
    left = _bracket(q, d_left, normal)
    right = _bracket(d_right, q, normal)
    total = left + right
    safe = np.where(total != 0.0, total, 1.0)
    alpha = 2.0 * right / safe
    beta = 2.0 * left / safe
    phi = -2.0 * _bracket(d_left, d_right, normal) / safe
    size = np.linalg.norm(q, axis=-1) * np.maximum(np.linalg.norm(d_left, axis=-1), np.linalg.norm(d_right, axis=-1))
    margin = np.minimum(left, right) / np.where(size > 0, size, 1.0)
    return alpha, beta, phi, margin


def tangent_plane_tangents(targets: Targets) -> FloatArray:
    """The target tangents moved into their sectors' tangent planes, which is all G1 asks at a corner.

    A smooth slot: ``t − (N·t) N`` with its sector's normal N. A slot on a seam or on the
    boundary between two different sector planes: onto their common line, ``(t·l) l`` with
    ``l = N_L × N_R`` normalised (the crease curve's tangent lies in both planes); where the two
    planes agree (to 1e-9) it is the plane's projection again. Without seams every slot of a
    vertex takes the vertex normal.
    """
    topology = targets.topology
    if not targets.has_sectors:
        slot_vertex = np.repeat(np.arange(topology.n_vertices), np.diff(topology.neighbor_offsets))
        n = targets.normals[slot_vertex]
        return targets.tangents - _dot(targets.tangents, n)[:, None] * n
    left, right = slot_sector_normals(targets)
    t = targets.tangents - _dot(targets.tangents, right)[:, None] * right
    line = np.cross(left, right)
    length = np.linalg.norm(line, axis=1)
    crease = length > 1e-9
    unit = line[crease] / length[crease, None]
    t[crease] = _dot(targets.tangents[crease], unit)[:, None] * unit
    return t


def _raise_invalid(topology: QuadTopology, vertex: NDArray[np.int64], margin: FloatArray) -> None:
    bad = np.flatnonzero(~(margin > 0))
    if bad.size:
        v = int(vertex[bad[0]])
        raise ConstructionError(
            f"gregory: the target tangents at vertex {v} (valence {topology.valence[v]}) do not turn "
            f"counter-clockwise about its normal (margin {margin[bad[0]]:.3g}); the targets rule must "
            f"supply a valid fan ({bad.size} edge ends affected)"
        )


def assemble_gregory(targets: Targets) -> GregoryPatchSet:
    """The Gregory patches of ``targets``, one per face, exactly G1 on every interior edge (module docstring).

    Raises :class:`ConstructionError` when the targets' fan is invalid at some vertex.
    """
    topology = targets.topology
    faces = topology.faces
    count = topology.n_faces
    x = targets.positions
    t = tangent_plane_tangents(targets)
    slot_out, slot_in = halfedge_slots(topology)
    halfedges = np.arange(4 * count)
    prev, nxt = QuadTopology.prev(halfedges), QuadTopology.next(halfedges)

    points = np.empty((count, 20, 3))
    corners = x[faces]
    points[:, :4] = corners
    points[:, 4:12:2] = corners + t[slot_out].reshape(count, 4, 3) / 3.0  # E+_k = A + t_AB/3
    points[:, 5:12:2] = corners + t[slot_in[prev]].reshape(count, 4, 3) / 3.0  # E-_k = A + t_AD/3
    near = targets.interior[:, :, 0].copy()  # Fn_k, seen by edge k
    far = targets.interior[:, :, 1].copy()  # Fp_k, seen by edge k − 1

    pairs = topology.edge_halfedges[(topology.edge_halfedges[:, 1] >= 0) & ~targets.seams]
    h, g = pairs[:, 0], pairs[:, 1]
    a_vertex, b_vertex = topology.origin(h), topology.target(h)
    a, b = x[a_vertex], x[b_vertex]
    q0 = t[slot_out[h]]
    t_ba = t[slot_in[h]]
    q2 = -t_ba
    b1 = a + q0 / 3.0
    b2 = b + t_ba / 3.0
    q1 = 3.0 * (b2 - b1)
    d0_left, d0_right = t[slot_in[prev[h]]], t[slot_out[nxt[g]]]
    d3_left, d3_right = t[slot_out[nxt[h]]], t[slot_in[prev[g]]]
    corner_normals = targets.corner_normals.reshape(-1, 3)  # a smooth edge's two faces share A's sector, and B's
    alpha0, beta0, phi0, margin0 = corner_split(q0, d0_left, d0_right, corner_normals[h])
    alpha1, beta1, phi2, margin1 = corner_split(q2, d3_left, d3_right, corner_normals[nxt[h]])
    _raise_invalid(topology, np.concatenate([a_vertex, b_vertex]), np.concatenate([margin0, margin1]))

    left, right = h >> 2, g >> 2
    k_left, k_right = h & 3, g & 3
    # targets of the four cross-boundary coefficients: 3 (F − b)
    r1_left = 3.0 * (near[left, k_left] - b1)
    r2_left = 3.0 * (far[left, (k_left + 1) & 3] - b2)
    r1_right = 3.0 * (far[right, (k_right + 1) & 3] - b1)
    r2_right = 3.0 * (near[right, k_right] - b2)

    symmetric = (np.abs(alpha0 - 1.0) <= SYMMETRIC_TOLERANCE) & (np.abs(alpha1 - 1.0) <= SYMMETRIC_TOLERANCE)
    d1_left, d2_left, d1_right, d2_right = (np.empty_like(q0) for _ in range(4))
    s = symmetric
    if s.any():  # D_L + D_R = Φ c', Φ linear: both sides move by the same vector
        sum1 = (2.0 * phi0[s, None] * q1[s] + phi2[s, None] * q0[s]) / 3.0
        sum2 = (phi0[s, None] * q2[s] + 2.0 * phi2[s, None] * q1[s]) / 3.0
        shift1 = 0.5 * (sum1 - r1_left[s] - r1_right[s])
        shift2 = 0.5 * (sum2 - r2_left[s] - r2_right[s])
        d1_left[s], d1_right[s] = r1_left[s] + shift1, r1_right[s] + shift1
        d2_left[s], d2_right[s] = r2_left[s] + shift2, r2_right[s] + shift2
    k = ~symmetric
    if k.any():
        d1_left[k], d2_left[k], d1_right[k], d2_right[k] = _kh_fit(
            q0[k], q1[k], q2[k], d0_left[k], d3_left[k], alpha0[k], beta0[k], phi0[k], alpha1[k], beta1[k], phi2[k],
            (r1_left[k], r2_left[k], r1_right[k], r2_right[k]),
        )

    near[left, k_left] = b1 + d1_left / 3.0
    far[left, (k_left + 1) & 3] = b2 + d2_left / 3.0
    far[right, (k_right + 1) & 3] = b1 + d1_right / 3.0
    near[right, k_right] = b2 + d2_right / 3.0
    points[:, 12::2] = near
    points[:, 13::2] = far
    return GregoryPatchSet(points)


def _kh_fit(
    q0: FloatArray, q1: FloatArray, q2: FloatArray, d0_left: FloatArray, d3_left: FloatArray,
    alpha0: FloatArray, beta0: FloatArray, phi0: FloatArray, alpha1: FloatArray, beta1: FloatArray, phi2: FloatArray,
    wanted: tuple[FloatArray, FloatArray, FloatArray, FloatArray],
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    """Interior coefficients ``d1_L, d2_L, d1_R, d2_R`` of the k-h form (h_L0 = 0) whose free values
    p = (G1, h_L1) fit ``wanted`` best: each coefficient is ``k_i + c_i G1 + v_i h_L1``, and
    ``min Σ_i |k_i + c_i G1 + v_i h − r_i|² + λ |p|²`` is a 4 × 4 system per edge whose G1 block
    is a multiple of I, solved in closed form."""
    b0, b1_, a0, a1 = beta0[:, None], beta1[:, None], alpha0[:, None], alpha1[:, None]
    g0 = d0_left / b0
    h_r0 = phi0[:, None] / b0
    h_r1 = phi2[:, None] / b1_  # at h_L1 = 0
    g2 = d3_left / b1_  # at h_L1 = 0
    constant = (
        b1_ * g0 / 3.0,
        b0 * g2 / 3.0,
        -a1 * g0 / 3.0 + (2.0 * h_r0 * q1 + h_r1 * q0) / 3.0,
        -a0 * g2 / 3.0 + (h_r0 * q2 + 2.0 * h_r1 * q1) / 3.0,
    )
    along = (  # ∂/∂h_L1
        q0 / 3.0,
        -b0 * q2 / (3.0 * b1_) + 2.0 * q1 / 3.0,
        -a1 * q0 / (3.0 * b1_),
        a0 * q2 / (3.0 * b1_) - 2.0 * a1 * q1 / (3.0 * b1_),
    )
    scalar = (2.0 * b0 / 3.0, 2.0 * b1_ / 3.0, -2.0 * a0 / 3.0, -2.0 * a1 / 3.0)  # ∂/∂G1 = c_i I
    # normal equations [[a I, c], [cᵀ, d]] p = [r_G; r_h]: a = Σ c_i², c = Σ c_i v_i, d = Σ |v_i|²
    a = sum(c_i[:, 0] ** 2 for c_i in scalar)
    c = sum(c_i * v_i for c_i, v_i in zip(scalar, along, strict=True))
    d = sum(_dot(v_i, v_i) for v_i in along)
    residuals = [r_i - k_i for r_i, k_i in zip(wanted, constant, strict=True)]
    r_g = sum(c_i * y for c_i, y in zip(scalar, residuals, strict=True))
    r_h = sum(_dot(v_i, y) for v_i, y in zip(along, residuals, strict=True))
    ridge = RIDGE * np.maximum(a, d)
    a = a + ridge
    d = d + ridge
    # Schur complement: h = (r_h − c·r_G/a) / (d − |c|²/a), G1 = (r_G − c h)/a
    h1 = (r_h - _dot(c, r_g) / a) / (d - _dot(c, c) / a)
    g1 = (r_g - c * h1[:, None]) / a[:, None]
    h1 = h1[:, None]
    return tuple(k_i + c_i * g1 + v_i * h1 for k_i, v_i, c_i in zip(constant, along, scalar, strict=True))  # type: ignore[return-value]
