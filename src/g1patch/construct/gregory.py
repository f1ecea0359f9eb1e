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
  ``d1 = (2β0 G1 + β1 G0)/3 + (2 h0 q1 + h1 q0)/3``, ``d2 = (β0 G2 + 2β1 G1)/3 + (h0 q2 + 2 h1
  q1)/3`` (L; R with −α for β and h_R), ``q1 = 3(b2 − b1)``; interior points ``b1 + d1/3``, ``b2 +
  d2/3``.
* **Symmetric edges** (α ≡ β ≡ 1 at both ends, as on any C1 data): there the k-h family is a
  4-dimensional part of the 6-dimensional solution set ``D_L + D_R = Φ c'`` with Φ linear, so
  those edges take the minimum-norm correction of their targets onto it instead: both sides
  move by the same vector, and targets that are already G1 (a bicubic B-spline) come back unchanged.

Boundary edges and seams (``Targets.seams``: creased on purpose) keep their targets: the two faces
of a seam share its boundary cubic (C0) and each keeps its own cross-boundary derivative. At a
vertex the corner split of an edge uses the normal of the edge's sector
(``Targets.corner_normals``), and every slot tangent is moved into its sectors' planes
(:func:`tangent_plane_tangents`), so each sector is G1 at the corner by itself.

The assembly runs in one numba kernel, half-edge by half-edge and edge by edge, writing the
(F, 20, 3) points directly (:func:`_assemble_kernel`; on large meshes in ranges side by side,
:func:`~g1patch.kernels.in_chunks`); the NumPy reference
(``assemble_gregory(targets, compiled=False)``) does the same with gathers, scatters and
closed-form solves batched over edges. No Python loop over vertices, edges or faces either way.
"""

from __future__ import annotations

import operator
from collections.abc import Iterable
from functools import reduce

import numpy as np
from numpy.typing import NDArray

from ..errors import ConstructionError
from ..gregory import GregoryPatchSet
from ..kernels import in_chunks, jit_kernel, use_kernels
from ..mesh import QuadTopology
from ..targets import Targets, halfedge_slots, slot_sector_normals
from ..targets.local import in_vertex_planes, slot_tables

__all__ = ["assemble_gregory", "corner_split", "tangent_plane_tangents"]

FloatArray = NDArray[np.float64]

#: edges whose corner splits are within this of α = β = 1 at both ends take the symmetric form
SYMMETRIC_TOLERANCE = 1e-12
#: ridge of the k-h fit, relative to each unknown's own diagonal entry of its normal equations
#: (G1 is a length, h_L1 a number: one ridge for both, scaled by the larger entry, made the
#: fit depend on the model's size and damped h_L1 on fine meshes, where |c'|² ≪ 1): keeps
#: the free values bounded where G1 and h_L1 are nearly dependent (edge cubic nearly quadratic,
#: α nearly constant), which would otherwise inflate round-off (shape-quality.md §3.4)
RIDGE = 1e-6


def _total(terms: Iterable[FloatArray]) -> FloatArray:
    """``t_0 + t_1 + …`` of arrays, left to right as ``sum`` does (typed: no ``0`` start)."""
    return reduce(operator.add, terms)


def _dot(a: FloatArray, b: FloatArray) -> FloatArray:
    return np.einsum("...d,...d->...", a, b)


def _bracket(a: FloatArray, b: FloatArray, n: FloatArray) -> FloatArray:
    """``[a, b] = (a × b)·n``, by components (rows of 3-vectors)."""
    a0, a1, a2 = a[:, 0], a[:, 1], a[:, 2]
    b0, b1, b2 = b[:, 0], b[:, 1], b[:, 2]
    return (
        (a1 * b2 - a2 * b1) * n[:, 0]
        + (a2 * b0 - a0 * b2) * n[:, 1]
        + (a0 * b1 - a1 * b0) * n[:, 2]
    )


def corner_split(
    q: FloatArray, d_left: FloatArray, d_right: FloatArray, normal: FloatArray
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    """``(α, β, φ, Δ-sign check)`` with ``α d_L + β d_R = φ q`` and ``α + β = 2`` (module
    docstring).

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
    size = np.linalg.norm(q, axis=-1) * np.maximum(
        np.linalg.norm(d_left, axis=-1), np.linalg.norm(d_right, axis=-1)
    )
    margin = np.minimum(left, right) / np.where(size > 0, size, 1.0)
    return alpha, beta, phi, margin


def tangent_plane_tangents(targets: Targets, *, compiled: bool = True) -> FloatArray:
    """The target tangents moved into their sectors' tangent planes, which is all G1 asks at a
    corner.

    A smooth slot: ``t − (N·t) N`` with its sector's normal N. A slot on a seam or on the
    boundary between two different sector planes: onto their common line, ``(t·l) l`` with
    ``l = N_L × N_R`` normalised (the crease curve's tangent lies in both planes); where the two
    planes agree (to 1e-9) it is the plane's projection again. Without seams every slot of a
    vertex takes the vertex normal (``compiled``: vertex by vertex in a numba kernel).
    """
    compiled = use_kernels(compiled)  # NumPy where kernels cannot be cached
    topology = targets.topology
    if not targets.has_sectors:
        if compiled:
            return in_vertex_planes(targets.tangents, targets.normals, topology.neighbor_offsets)
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


def _raise_invalid(topology: QuadTopology, bad: int, end: int, edge: int, margin: float) -> None:
    """Raise if ``bad`` corner splits have a margin that is not positive; the first of them is at
    ``end`` (0: the origin of the edge's first half-edge, 1: its target) of ``edge``."""
    if bad:
        h = int(topology.edge_halfedges[edge, 0])
        v = int(topology.origin(h) if end == 0 else topology.target(h))
        raise ConstructionError(
            f"gregory: the target tangents at vertex {v} (valence {topology.valence[v]}) do not "
            "turn "
            f"counter-clockwise about its normal (margin {margin:.3g}); the targets rule must "
            f"supply a valid fan ({bad} edge ends affected)"
        )


def assemble_gregory(targets: Targets, *, compiled: bool = True) -> GregoryPatchSet:
    """The Gregory patches of ``targets``, one per face, exactly G1 on every interior edge (module
    docstring).

    ``compiled`` runs the assembly in a numba kernel (:func:`_assemble_kernel`, which moves the
    tangents into their vertex planes as it reads them where there are no seams); ``False`` runs
    the NumPy reference (the same to rounding, tests/test_kernels_match.py). Raises
    :class:`ConstructionError` when the targets' fan is invalid at some vertex.
    """
    compiled = use_kernels(compiled)  # NumPy where kernels cannot be cached
    topology = targets.topology
    points = np.empty((topology.n_faces, 20, 3))
    if not compiled:
        margins = np.full((2, topology.n_edges), np.inf)
        _assemble_numpy(
            targets,
            tangent_plane_tangents(targets, compiled=False),
            *halfedge_slots(topology),
            points,
            margins,
        )
        return GregoryPatchSet(points)
    sectors = targets.has_sectors
    slot_out, slot_in = slot_tables(topology)
    kernel = jit_kernel(_assemble_kernel)
    tangents = tangent_plane_tangents(targets) if sectors else targets.tangents
    origin, corner_normals = topology.faces.reshape(-1), targets.corner_normals.reshape(-1, 3)

    def run(
        halfedges: tuple[int, int], edges: tuple[int, int]
    ) -> tuple[int, int, float, int, float]:
        return kernel(
            targets.positions,
            tangents,
            targets.normals,
            not sectors,
            origin,
            slot_out,
            slot_in,
            corner_normals,
            targets.interior,
            topology.edge_halfedges,
            targets.seams,
            SYMMETRIC_TOLERANCE,
            RIDGE,
            points,
            *halfedges,
            *edges,
        )

    # the corners and targets of every face first, then the edges overwrite the interior points they
    # solve
    in_chunks(lambda lo, hi: run((lo, hi), (0, 0)), origin.size)
    ranges = in_chunks(lambda lo, hi: run((0, 0), (lo, hi)), topology.n_edges)
    bad = sum(found[0] for found in ranges)
    first_origin, origin_margin = next(((e, m) for _, e, m, _, _ in ranges if e >= 0), (-1, 0.0))
    first_target, target_margin = next(((e, m) for _, _, _, e, m in ranges if e >= 0), (-1, 0.0))
    if first_origin >= 0:
        _raise_invalid(topology, bad, 0, first_origin, origin_margin)
    _raise_invalid(topology, bad, 1, first_target, target_margin)
    return GregoryPatchSet(points)


def _assemble_numpy(
    targets: Targets,
    t: FloatArray,
    slot_out: NDArray[np.int64],
    slot_in: NDArray[np.int64],
    points: FloatArray,
    margins: FloatArray,
) -> None:
    """The NumPy reference of :func:`_assemble_kernel`: gathers, scatters and batched closed-form
    solves over edges (corner-split margins into ``margins`` (2, E), raising where one is not
    positive)."""
    topology = targets.topology
    faces = topology.faces
    count = topology.n_faces
    x = targets.positions
    halfedges = np.arange(4 * count)
    prev, nxt = QuadTopology.prev(halfedges), QuadTopology.next(halfedges)

    corners = x[faces]
    points[:, :4] = corners
    points[:, 4:12:2] = corners + t[slot_out].reshape(count, 4, 3) / 3.0  # E+_k = A + t_AB/3
    points[:, 5:12:2] = corners + t[slot_in[prev]].reshape(count, 4, 3) / 3.0  # E-_k = A + t_AD/3
    near = targets.interior[:, :, 0].copy()  # Fn_k, seen by edge k
    far = targets.interior[:, :, 1].copy()  # Fp_k, seen by edge k − 1

    split = np.flatnonzero((topology.edge_halfedges[:, 1] >= 0) & ~targets.seams)
    h, g = topology.edge_halfedges[split, 0], topology.edge_halfedges[split, 1]
    a, b = x[topology.origin(h)], x[topology.target(h)]
    q0 = t[slot_out[h]]
    t_ba = t[slot_in[h]]
    q2 = -t_ba
    b1 = a + q0 / 3.0
    b2 = b + t_ba / 3.0
    q1 = 3.0 * (b2 - b1)
    d0_left, d0_right = t[slot_in[prev[h]]], t[slot_out[nxt[g]]]
    d3_left, d3_right = t[slot_out[nxt[h]]], t[slot_in[prev[g]]]
    corner_normals = targets.corner_normals.reshape(
        -1, 3
    )  # a smooth edge's two faces share A's sector, and B's
    alpha0, beta0, phi0, margins[0, split] = corner_split(q0, d0_left, d0_right, corner_normals[h])
    alpha1, beta1, phi2, margins[1, split] = corner_split(
        q2, d3_left, d3_right, corner_normals[nxt[h]]
    )
    bad = np.flatnonzero(~(margins.ravel() > 0))
    if bad.size:
        end, edge = divmod(int(bad[0]), topology.n_edges)
        _raise_invalid(topology, bad.size, end, edge, float(margins.ravel()[bad[0]]))

    left, right = h >> 2, g >> 2
    k_left, k_right = h & 3, g & 3
    # targets of the four cross-boundary coefficients: 3 (F − b)
    r1_left = 3.0 * (near[left, k_left] - b1)
    r2_left = 3.0 * (far[left, (k_left + 1) & 3] - b2)
    r1_right = 3.0 * (far[right, (k_right + 1) & 3] - b1)
    r2_right = 3.0 * (near[right, k_right] - b2)

    symmetric = (np.abs(alpha0 - 1.0) <= SYMMETRIC_TOLERANCE) & (
        np.abs(alpha1 - 1.0) <= SYMMETRIC_TOLERANCE
    )
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
            q0[k],
            q1[k],
            q2[k],
            d0_left[k],
            d3_left[k],
            alpha0[k],
            beta0[k],
            phi0[k],
            alpha1[k],
            beta1[k],
            phi2[k],
            (r1_left[k], r2_left[k], r1_right[k], r2_right[k]),
        )

    near[left, k_left] = b1 + d1_left / 3.0
    far[left, (k_left + 1) & 3] = b2 + d2_left / 3.0
    far[right, (k_right + 1) & 3] = b1 + d1_right / 3.0
    near[right, k_right] = b2 + d2_right / 3.0
    points[:, 12::2] = near
    points[:, 13::2] = far


def _kh_fit(
    q0: FloatArray,
    q1: FloatArray,
    q2: FloatArray,
    d0_left: FloatArray,
    d3_left: FloatArray,
    alpha0: FloatArray,
    beta0: FloatArray,
    phi0: FloatArray,
    alpha1: FloatArray,
    beta1: FloatArray,
    phi2: FloatArray,
    wanted: tuple[FloatArray, FloatArray, FloatArray, FloatArray],
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    """Interior coefficients ``d1_L, d2_L, d1_R, d2_R`` of the k-h form (h_L0 = 0) whose free values
    p = (G1, h_L1) fit ``wanted`` best: each coefficient is ``k_i + c_i G1 + v_i h_L1``, and
    ``min Σ_i |k_i + c_i G1 + v_i h − r_i|² + λ (a |G1|² + d h²)`` (a, d: the diagonal entries of
    G1 and h, λ = :data:`RIDGE`) is a 4 × 4 system per edge whose G1 block
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
    a = _total(c_i[:, 0] ** 2 for c_i in scalar)
    c = _total(c_i * v_i for c_i, v_i in zip(scalar, along, strict=True))
    d = _total(_dot(v_i, v_i) for v_i in along)
    residuals = [r_i - k_i for r_i, k_i in zip(wanted, constant, strict=True)]
    r_g = _total(c_i * y for c_i, y in zip(scalar, residuals, strict=True))
    r_h = _total(_dot(v_i, y) for v_i, y in zip(along, residuals, strict=True))
    a = a * (1.0 + RIDGE)
    d = d * (1.0 + RIDGE)
    # Schur complement: h = (r_h − c·r_G/a) / (d − |c|²/a), G1 = (r_G − c h)/a
    h1 = (r_h - _dot(c, r_g) / a) / (d - _dot(c, c) / a)
    g1 = (r_g - c * h1[:, None]) / a[:, None]
    h1 = h1[:, None]
    return tuple(
        k_i + c_i * g1 + v_i * h1 for k_i, v_i, c_i in zip(constant, along, scalar, strict=True)
    )  # type: ignore[return-value]


# ----------------------------------------------------------------------------------------------
# the numba kernel (compiled on first use by :func:`g1patch.kernels.jit_kernel`): the formulas
# and operation order of the NumPy code above, one half-edge or one edge at a time


def _assemble_kernel(
    x: FloatArray,
    t: FloatArray,
    normals: FloatArray,
    project: bool,
    origin: NDArray[np.int64],
    slot_out: NDArray[np.int32],
    slot_in: NDArray[np.int32],
    corner_normals: FloatArray,
    interior: FloatArray,
    edge_halfedges: NDArray[np.int64],
    seams: NDArray[np.bool_],
    symmetric_tolerance: float,
    ridge: float,
    points: FloatArray,
    first_halfedge: int,
    stop_halfedge: int,
    first_edge: int,
    stop_edge: int,
) -> tuple[int, int, float, int, float]:
    """:func:`_assemble_numpy` one half-edge, then one edge at a time, straight into ``points`` (F,
    20, 3), for the half-edges ``first_halfedge ≤ i < stop_halfedge`` and the edges ``first_edge ≤ e
    < stop_edge`` (an edge's interior points overwrite its half-edges' targets: all half-edges go
    first).

    Each slot tangent is read as ``t − (N·t) N`` with its vertex's normal N when ``project`` (the
    seam-free :func:`tangent_plane_tangents`, same operations), else as given. Per half-edge:
    corner, edge points ``A + t/3`` and the interior targets. Per interior non-seam edge: both
    corner splits, then the symmetric correction or the closed-form k-h fit of :func:`_kh_fit`, and
    its four interior points. Returns how many splits have a margin that is not positive and, per
    end (the origin, then the target of the edge's first half-edge), the first such edge (−1 if
    none) and its margin.
    """
    for i in range(first_halfedge, stop_halfedge):
        f, k = i >> 2, i & 3
        prev = (i & ~3) | ((k + 3) & 3)
        v, s_out, s_in = origin[i], slot_out[i], slot_in[prev]
        height_out = height_in = 0.0
        if project:
            height_out = (
                t[s_out, 0] * normals[v, 0]
                + t[s_out, 1] * normals[v, 1]
                + t[s_out, 2] * normals[v, 2]
            )
            height_in = (
                t[s_in, 0] * normals[v, 0] + t[s_in, 1] * normals[v, 1] + t[s_in, 2] * normals[v, 2]
            )
        for d in range(3):
            points[f, k, d] = x[v, d]
            points[f, 4 + 2 * k, d] = x[v, d] + (t[s_out, d] - height_out * normals[v, d]) / 3.0
            points[f, 5 + 2 * k, d] = x[v, d] + (t[s_in, d] - height_in * normals[v, d]) / 3.0
            points[f, 12 + 2 * k, d] = interior[f, k, 0, d]
            points[f, 13 + 2 * k, d] = interior[f, k, 1, d]
    tangent = np.empty((6, 3))  # t_AB = q0, t_BA = −q2, then d_L, d_R at A and d_L, d_R at B
    q0, q1, q2 = np.empty(3), np.empty(3), np.empty(3)
    b1, b2 = np.empty(3), np.empty(3)
    r = np.empty((4, 3))  # targets r1_L, r2_L, r1_R, r2_R
    const = np.empty((4, 3))  # k_i
    along = np.empty((4, 3))  # v_i
    scalar = np.empty(4)  # c_i
    c, r_g = np.empty(3), np.empty(3)  # Σ c_i v_i, Σ c_i (r_i − k_i)
    out = np.empty((4, 3))  # d1_L, d2_L, d1_R, d2_R
    split = np.empty((2, 3))  # α, β, φ at A and at B
    slots = np.empty(6, dtype=np.int64)  # of the six tangents
    bad = 0
    first = np.full(2, -1)
    first_margin = np.zeros(2)
    for e in range(first_edge, stop_edge):
        h, g = edge_halfedges[e, 0], edge_halfedges[e, 1]
        if g < 0 or seams[e]:
            continue
        h_next, h_prev = (h & ~3) | ((h + 1) & 3), (h & ~3) | ((h + 3) & 3)
        g_next, g_prev = (g & ~3) | ((g + 1) & 3), (g & ~3) | ((g + 3) & 3)
        a_vertex, b_vertex = origin[h], origin[h_next]
        slots[0], slots[1], slots[2] = slot_out[h], slot_in[h], slot_in[h_prev]
        slots[3], slots[4], slots[5] = slot_out[g_next], slot_out[h_next], slot_in[g_prev]
        for u in range(6):
            s, v = slots[u], a_vertex if u == 0 or u == 2 or u == 3 else b_vertex
            height = 0.0
            if project:
                height = t[s, 0] * normals[v, 0] + t[s, 1] * normals[v, 1] + t[s, 2] * normals[v, 2]
            for d in range(3):
                tangent[u, d] = t[s, d] - height * normals[v, d] if project else t[s, d]
        for d in range(3):
            q0[d] = tangent[0, d]
            q2[d] = -tangent[1, d]
            b1[d] = x[a_vertex, d] + tangent[0, d] / 3.0
            b2[d] = x[b_vertex, d] + tangent[1, d] / 3.0
            q1[d] = 3.0 * (b2[d] - b1[d])
        # corner splits at A (q = q0, d_L, d_R, N) and at B (q = q2)
        for end in range(2):
            corner = h if end == 0 else h_next
            n0, n1, n2 = (
                corner_normals[corner, 0],
                corner_normals[corner, 1],
                corner_normals[corner, 2],
            )
            qx, qy, qz = (q0[0], q0[1], q0[2]) if end == 0 else (q2[0], q2[1], q2[2])
            lx, ly, lz = tangent[2 + 2 * end, 0], tangent[2 + 2 * end, 1], tangent[2 + 2 * end, 2]
            rx, ry, rz = tangent[3 + 2 * end, 0], tangent[3 + 2 * end, 1], tangent[3 + 2 * end, 2]
            left = (
                (qy * lz - qz * ly) * n0 + (qz * lx - qx * lz) * n1 + (qx * ly - qy * lx) * n2
            )  # [q, d_L]
            right = (
                (ry * qz - rz * qy) * n0 + (rz * qx - rx * qz) * n1 + (rx * qy - ry * qx) * n2
            )  # [d_R, q]
            total = left + right
            safe = total if total != 0.0 else 1.0
            split[end, 0] = 2.0 * right / safe
            split[end, 1] = 2.0 * left / safe
            split[end, 2] = (
                -2.0
                * ((ly * rz - lz * ry) * n0 + (lz * rx - lx * rz) * n1 + (lx * ry - ly * rx) * n2)
                / safe
            )
            size = np.sqrt(qx * qx + qy * qy + qz * qz) * max(
                np.sqrt(lx * lx + ly * ly + lz * lz), np.sqrt(rx * rx + ry * ry + rz * rz)
            )
            smaller = left if left < right else right
            if np.isnan(left) or np.isnan(right):
                smaller = np.nan
            margin = smaller / (size if size > 0 else 1.0)
            if not margin > 0:
                bad += 1
                if first[end] < 0:
                    first[end], first_margin[end] = e, margin
        alpha0, beta0, phi0 = split[0, 0], split[0, 1], split[0, 2]
        alpha1, beta1, phi2 = split[1, 0], split[1, 1], split[1, 2]
        left_face, right_face, k_left, k_right = h >> 2, g >> 2, h & 3, g & 3
        for d in range(3):
            r[0, d] = 3.0 * (interior[left_face, k_left, 0, d] - b1[d])
            r[1, d] = 3.0 * (interior[left_face, (k_left + 1) & 3, 1, d] - b2[d])
            r[2, d] = 3.0 * (interior[right_face, (k_right + 1) & 3, 1, d] - b1[d])
            r[3, d] = 3.0 * (interior[right_face, k_right, 0, d] - b2[d])
        if abs(alpha0 - 1.0) <= symmetric_tolerance and abs(alpha1 - 1.0) <= symmetric_tolerance:
            for d in range(3):  # D_L + D_R = Φ c', Φ linear: both sides move by the same vector
                sum1 = (2.0 * phi0 * q1[d] + phi2 * q0[d]) / 3.0
                sum2 = (phi0 * q2[d] + 2.0 * phi2 * q1[d]) / 3.0
                shift1 = 0.5 * (sum1 - r[0, d] - r[2, d])
                shift2 = 0.5 * (sum2 - r[1, d] - r[3, d])
                out[0, d], out[2, d] = r[0, d] + shift1, r[2, d] + shift1
                out[1, d], out[3, d] = r[1, d] + shift2, r[3, d] + shift2
        else:  # _kh_fit
            scalar[0], scalar[1] = 2.0 * beta0 / 3.0, 2.0 * beta1 / 3.0
            scalar[2], scalar[3] = -2.0 * alpha0 / 3.0, -2.0 * alpha1 / 3.0
            h_r0, h_r1 = phi0 / beta0, phi2 / beta1
            for d in range(3):
                g0, g2 = tangent[2, d] / beta0, tangent[4, d] / beta1
                const[0, d] = beta1 * g0 / 3.0
                const[1, d] = beta0 * g2 / 3.0
                const[2, d] = -alpha1 * g0 / 3.0 + (2.0 * h_r0 * q1[d] + h_r1 * q0[d]) / 3.0
                const[3, d] = -alpha0 * g2 / 3.0 + (h_r0 * q2[d] + 2.0 * h_r1 * q1[d]) / 3.0
                along[0, d] = q0[d] / 3.0
                along[1, d] = -beta0 * q2[d] / (3.0 * beta1) + 2.0 * q1[d] / 3.0
                along[2, d] = -alpha1 * q0[d] / (3.0 * beta1)
                along[3, d] = alpha0 * q2[d] / (3.0 * beta1) - 2.0 * alpha1 * q1[d] / (3.0 * beta1)
            a = scalar[0] ** 2 + scalar[1] ** 2 + scalar[2] ** 2 + scalar[3] ** 2
            dd = 0.0
            r_h = 0.0
            for i in range(4):
                dd += (
                    along[i, 0] * along[i, 0]
                    + along[i, 1] * along[i, 1]
                    + along[i, 2] * along[i, 2]
                )
                r_h += (
                    along[i, 0] * (r[i, 0] - const[i, 0])
                    + along[i, 1] * (r[i, 1] - const[i, 1])
                    + along[i, 2] * (r[i, 2] - const[i, 2])
                )
            c_r, c_c = 0.0, 0.0
            for d in range(3):
                c[d] = (
                    scalar[0] * along[0, d]
                    + scalar[1] * along[1, d]
                    + scalar[2] * along[2, d]
                    + scalar[3] * along[3, d]
                )
                r_g[d] = (
                    scalar[0] * (r[0, d] - const[0, d])
                    + scalar[1] * (r[1, d] - const[1, d])
                    + scalar[2] * (r[2, d] - const[2, d])
                    + scalar[3] * (r[3, d] - const[3, d])
                )
                c_r += c[d] * r_g[d]
                c_c += c[d] * c[d]
            a *= 1.0 + ridge
            dd *= 1.0 + ridge
            h1 = (r_h - c_r / a) / (dd - c_c / a)  # Schur complement, then G1 = (r_G − c h)/a
            for d in range(3):
                g1 = (r_g[d] - c[d] * h1) / a
                for i in range(4):
                    out[i, d] = const[i, d] + scalar[i] * g1 + along[i, d] * h1
        for d in range(3):
            points[left_face, 12 + 2 * k_left, d] = b1[d] + out[0, d] / 3.0
            points[left_face, 13 + 2 * ((k_left + 1) & 3), d] = b2[d] + out[1, d] / 3.0
            points[right_face, 13 + 2 * ((k_right + 1) & 3), d] = b1[d] + out[2, d] / 3.0
            points[right_face, 12 + 2 * k_right, d] = b2[d] + out[3, d] / 3.0
    return bad, first[0], first_margin[0], first[1], first_margin[1]
