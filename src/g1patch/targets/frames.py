"""Vertex normals and second fundamental forms for surfaces that interpolate a quad mesh's vertices.

**Start.** The area-weighted fan normal ``N_A = normalize(Σ d_i × d_{i+1})`` over consecutive
ring edges ``d_i = x_i − A`` (:func:`g1patch.construct.corner.fan_normals`).

**Ring repair.** ``N`` is *valid* at A when the ring edges projected on its plane go once around
it counter-clockwise: every ``N·(d_i × d_{i+1}) > 0`` (the sign of the projected pair's 2-D cross
product, since ``N·(a × b)`` ignores the components along N) and the turning angles
``atan2(N·(d_i × d_{i+1}), (P d_i)·(P d_{i+1}))`` sum to 2π (to less than 2π on a boundary
vertex, whose open fan has no pair between the last and the first neighbour). Where the fan
normal is invalid we try ``normalize(Σ u_i × u_{i+1})`` with unit edge directions ``u_i``, then
the max–min normal ``argmax_{|N|=1} min_i N·ĉ_i`` of the unit corner normals ``ĉ_i`` (the
direction of the point of their convex hull nearest the origin, by Gilbert's algorithm); the
first valid one is used and ``repaired`` set. If neither is valid the fan normal stays.

**Circle-aware fit** (shape-quality.md §3.1). In the frame (e1, e2, N) at A, each point p of the
face 2-ring has coordinates (x, y, z) of p − A, r² = x² + y². A circle through A tangent to the
plane, of curvature k in the direction x̂ = (x, y)/r, satisfies x̂-section ``r² + z² = 2z/k``, i.e.
``z = ½ k (r² + z²) = ½ (1 + z²/r²) k r²``; with ``k r² = (x, y) H (x, y)ᵀ`` the fit is linear:

    z = g1 x + g2 y + ½ (1 + z²/r²)(h11 x² + 2 h12 xy + h22 y²) + (c1 x³ + 3c2 x²y + 3c3 xy² + c4 y³)/6

by weighted least squares, ``w = exp(−r²/(2 h̄²))``, h̄² the mean squared projected length of the
ring edges; the cubic only with ≥ 12 points, else the face 1-ring without it. Then
``N ← normalize(N − g1 e1 − g2 e2)``, 3 times. On a sphere of radius ρ (outward normal n, frame
normal N with n = (a, b, c) in the frame) ``|q + ρn|² = ρ²`` gives exactly
``z = −(a/c) x − (b/c) y − (r² + z²)/(2ρc)``: the model holds with C = 0, so one step is exact at any
resolution (the cube's corners included). Elsewhere N is O(h³) and H O(h²).

**Shape operator.** ``S = −P E H Eᵀ P`` (E = [e1 e2] of the last fit, P = I − N Nᵀ): S = dN, so the
unit sphere with outward normals has S = I − N Nᵀ and principal curvatures are positive on convex
parts. Note the sign: a parametric surface has ``N·X_ab = −aᵀ S b``.

**Reliability switch.** The fit is used (``fitted``) only at interior vertices (a boundary
vertex sees its surface from one side only, and its fitted normal tilted 10–20° off the fan
normal on OpenSubdiv's boundary fans and folded the surface there) and only where all of these
hold; elsewhere the
(repaired) fan normal stays and S comes from the same circle fit with N fixed (3 unknowns h, face
1-ring), which is exact for spheres too when N is exact:

* ``RESIDUAL``: weighted RMS fit residual ≤ 0.05 h̄. Measured (ellipsoid = cube_sphere scaled by
  (1, 0.7, 0.5); tori R = 2, r = 0.7 and R = 1, r = 0.25): 96-quad ellipsoid ≤ 0.054 (98 % pass;
  fit error ≤ 1.2° against the fan's 5.5°), 24×12 tori ≤ 0.050 (pass); 24-quad ellipsoid ≥ 0.059
  and 12×6 tori ≥ 0.11 are rejected: there the fit is off by 4–6° while the (symmetric) fan
  normal is exact. With 8 % noise the 24-quad ellipsoid is rejected (fit 2–4× worse than the
  fan), the 96-quad one passes at 72–88 %; a 0.08 bar let 12–15 % of the coarse noisy vertices in
  and raised their worst error from 3.9° to 5.5°.
* ``MAX_TILT``: the fitted normal within 25° of the start normal. Largest tilt measured: 6° on the
  smooth 96-quad ellipsoid, 9° (96 quads) and 14° (24 quads) with 8 % noise.
* the fitted normal is valid (ring goes once around CCW) and every ring edge is less than
  ``MAX_STEEPNESS`` = 60° from its plane (the diagnosis: quads with a steeper edge fold 27 % of
  the time).
* ``MIN_PIVOT``: each of the 5 unknowns g, h is determined: in the pivot-dropping Cholesky of the
  scaled normal equations its pivot ≥ 1e-3 of its diagonal (sin² of the angle of its column to
  the span of the earlier ones; ≥ 0.5 on every mesh above). Cubic columns below 1e-10 are
  dropped (coefficient 0).

Vectorised: vertices are sorted by neighbourhood size and processed in padded blocks.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray

from ..construct.corner import fan_normals
from ..mesh import QuadMesh

__all__ = ["VertexFrames", "vertex_frames", "RESIDUAL", "MAX_TILT", "MAX_STEEPNESS", "MIN_PIVOT"]

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]
BoolArray = NDArray[np.bool_]

RESIDUAL = 0.05  #: largest weighted RMS fit residual, in units of h̄
MAX_TILT = 25.0  #: largest angle (degrees) between fitted and start normal
MAX_STEEPNESS = 60.0  #: largest angle (degrees) between a ring edge and the tangent plane
MIN_PIVOT = 1e-3  #: smallest relative Cholesky pivot of the g, h unknowns
DROP_PIVOT = 1e-10  #: relative pivot below which a column is dropped from the fit
ITERATIONS = 3
CUBIC_POINTS = 12  #: fewest 2-ring points for the cubic term
BLOCK = 2048  #: vertices per padded block
GILBERT_STEPS = 64


@dataclass(frozen=True)
class VertexFrames:
    """Per-vertex unit normals, shape operators S (``II(a, b) = aᵀ S b``, ``S N = 0``) and flags."""

    normals: FloatArray  # (V, 3) unit
    shape_operator: FloatArray  # (V, 3, 3) symmetric
    fitted: BoolArray  # (V,) the circle-aware fit was trusted and used
    repaired: BoolArray  # (V,) the start normal was replaced so that the ring goes once around it


def _unit(v: FloatArray) -> FloatArray:
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def _frame(n: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Unit e1, e2 with (e1, e2, n) right-handed: e1 ⊥ n and the coordinate axis least aligned with n."""
    axis = np.zeros_like(n)
    axis[np.arange(n.shape[0]), np.argmin(np.abs(n), axis=1)] = 1.0
    e1 = _unit(np.cross(n, axis))
    return e1, np.cross(n, e1)


# ----------------------------------------------------------------------------------------------
# the ring: consecutive pairs of neighbours, validity and steepness of a normal


@dataclass(frozen=True)
class _Ring:
    """Ring edges ``d`` (one per neighbour, grouped by vertex) and consecutive pairs ``(first, second)``."""

    offsets: IntArray  # neighbor_offsets
    owner: IntArray  # vertex of each neighbour entry
    d: FloatArray  # (n, 3) ring edges
    pair_owner: IntArray  # vertex of each pair (4F entries)
    first: IntArray  # index into d
    second: IntArray
    cross: FloatArray  # d_first × d_second
    boundary: BoolArray

    @classmethod
    def of(cls, mesh: QuadMesh) -> _Ring:
        topo = mesh.topology
        offsets = topo.neighbor_offsets
        count = np.diff(offsets)
        owner = np.repeat(np.arange(topo.n_vertices), count)
        d = mesh.vertices[topo.neighbors] - mesh.vertices[owner]
        pair_owner = np.repeat(np.arange(topo.n_vertices), topo.face_count)
        step = np.arange(pair_owner.size) - np.repeat(topo.ring_offsets[:-1], topo.face_count)
        first = offsets[pair_owner] + step
        second = offsets[pair_owner] + (step + 1) % count[pair_owner]
        cross = np.cross(d[first], d[second])
        return cls(offsets, owner, d, pair_owner, first, second, cross, topo.is_boundary_vertex)

    def valid(self, n: FloatArray) -> BoolArray:
        """The projected ring goes once around ``n`` (V, 3) counter-clockwise (see the module doc)."""
        np_ = n[self.pair_owner]
        sine = np.einsum("pd,pd->p", np_, self.cross)
        height = np.einsum("nd,nd->n", self.d, n[self.owner])
        a, b = self.first, self.second
        cosine = np.einsum("pd,pd->p", self.d[a], self.d[b]) - height[a] * height[b]
        total = np.bincount(self.pair_owner, np.arctan2(sine, cosine), minlength=n.shape[0])
        folded = np.bincount(self.pair_owner, ~(sine > 0), minlength=n.shape[0]) > 0
        once = np.where(self.boundary, total < 2.0 * np.pi, np.abs(total - 2.0 * np.pi) < np.pi)
        return ~folded & once

    def steepness(self, n: FloatArray) -> FloatArray:
        """Largest ``|N·d| / |d|`` (sine of the angle to the plane) over each vertex's ring edges."""
        sine = np.abs(np.einsum("nd,nd->n", self.d, n[self.owner])) / np.linalg.norm(self.d, axis=1)
        return np.maximum.reduceat(sine, self.offsets[:-1])

    def repair(self, n: FloatArray, bad: IntArray) -> tuple[FloatArray, BoolArray]:
        """Valid normals for vertices ``bad``: unit-direction fan, else max–min of unit corner normals."""
        pick = np.isin(self.pair_owner, bad)
        owner = np.searchsorted(bad, self.pair_owner[pick])
        u = _unit(self.d)
        unit_fan = np.zeros((bad.size, 3))
        np.add.at(unit_fan, owner, np.cross(u[self.first[pick]], u[self.second[pick]]))
        corner = _unit(self.cross[pick])
        candidates = [_unit(unit_fan), _unit(_gilbert(corner, owner, bad.size))]
        out = n.copy()
        done = np.zeros(bad.size, dtype=bool)
        for candidate in candidates:
            trial = out.copy()
            trial[bad[~done]] = candidate[~done]
            ok = self.valid(trial)[bad] & ~done & np.isfinite(candidate).all(axis=1)
            out[bad[ok]] = candidate[ok]
            done |= ok
        return out, done


def _gilbert(points: FloatArray, owner: IntArray, groups: int) -> FloatArray:
    """Approximate nearest-to-origin point of the convex hull of each group's ``points`` (Gilbert's algorithm).

    ``x ← x + t (p − x)`` with p minimising ``x·p`` in the group and ``t = clip(x·(x − p)/|x − p|², 0, 1)``.
    """
    start = np.zeros((groups, 3))
    np.add.at(start, owner, points)
    x = start / np.bincount(owner, minlength=groups)[:, None]
    bounds = np.searchsorted(np.sort(owner), np.arange(groups))
    for _ in range(GILBERT_STEPS):
        score = np.einsum("pd,pd->p", points, x[owner])
        p = points[np.lexsort((score, owner))[bounds]]  # the lowest score of each group
        gap = x - p
        t = np.clip(np.einsum("gd,gd->g", x, gap) / np.maximum(np.einsum("gd,gd->g", gap, gap), 1e-300), 0.0, 1.0)
        x = x - t[:, None] * gap
    return x


# ----------------------------------------------------------------------------------------------
# the circle-aware fit, in padded blocks of vertices with similar neighbourhood sizes


@dataclass(frozen=True)
class _Hood:
    """A neighbourhood per vertex as CSR: ``points[offsets[v]:offsets[v + 1]]`` (the vertex itself excluded)."""

    offsets: IntArray
    points: IntArray

    @classmethod
    def without_self(cls, matrix: sp.csr_matrix) -> _Hood:
        rows = np.repeat(np.arange(matrix.shape[0]), np.diff(matrix.indptr))
        keep = matrix.indices != rows
        counts = np.bincount(rows[keep], minlength=matrix.shape[0])
        return cls(np.concatenate([[0], np.cumsum(counts)]), matrix.indices[keep].astype(np.int64))

    @property
    def sizes(self) -> IntArray:
        return np.diff(self.offsets)


def _face_rings(mesh: QuadMesh) -> tuple[_Hood, _Hood]:
    """Face 1-ring (vertices of the faces at v) and face 2-ring (vertices of the faces at those), from
    the vertex–face incidence ``I``: the patterns of ``I Iᵀ`` and ``(I Iᵀ)²``."""
    nv, nf = mesh.n_vertices, mesh.n_faces
    incidence = sp.csr_matrix((np.ones(4 * nf), (mesh.faces.ravel(), np.repeat(np.arange(nf), 4))), shape=(nv, nf))
    one = (incidence @ incidence.T).tocsr()
    one.data[:] = 1.0
    return _Hood.without_self(one), _Hood.without_self((one @ one).tocsr())


def _padded(vertices: IntArray, offsets: IntArray) -> tuple[IntArray, BoolArray]:
    """Positions ``offsets[v] + j`` (0 where padded) and their mask, one row per vertex."""
    start = offsets[vertices]
    count = offsets[vertices + 1] - start
    column = np.arange(int(count.max()))
    mask = column < count[:, None]
    return np.where(mask, start[:, None] + column, 0), mask


def _blocks(vertices: IntArray, sizes: IntArray) -> list[IntArray]:
    """``vertices`` sorted by ``sizes`` and cut into blocks of :data:`BLOCK`."""
    order = vertices[np.argsort(sizes[vertices], kind="stable")]
    return [order[s:s + BLOCK] for s in range(0, order.size, BLOCK)]


def _solve(gram: FloatArray, rhs: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Least-squares coefficients (k, b) from the normal equations ``gram c = rhs`` ((k, k, b), (k, b)), and pivots.

    Cholesky across the batch, one column at a time; a column whose pivot is at most
    :data:`DROP_PIVOT` of its diagonal (sin² of its angle to the earlier columns) is dropped, its
    coefficient 0: the least-squares solution without it.
    """
    k = gram.shape[0]
    work = gram.copy()
    lower = np.zeros_like(gram)
    pivot = np.zeros(rhs.shape)
    for j in range(k):
        diagonal = gram[j, j]
        pivot[j] = np.where(diagonal > 0, work[j, j] / np.where(diagonal > 0, diagonal, 1.0), 0.0)
        keep = pivot[j] > DROP_PIVOT
        column = np.where(keep, work[j:, j] / np.sqrt(np.where(keep, work[j, j], 1.0)), 0.0)
        lower[j:, j] = column
        work[j + 1:, j + 1:] -= column[1:, None] * column[None, 1:]
    kept = pivot > DROP_PIVOT
    root = np.where(kept, np.einsum("iib->ib", lower), 1.0)
    y = np.zeros(rhs.shape)
    for j in range(k):
        y[j] = np.where(kept[j], (rhs[j] - np.einsum("lb,lb->b", lower[j, :j], y[:j])) / root[j], 0.0)
    c = np.zeros(rhs.shape)
    for j in reversed(range(k)):
        c[j] = np.where(kept[j], (y[j] - np.einsum("lb,lb->b", lower[j + 1:, j], c[j + 1:])) / root[j], 0.0)
    return c, pivot


@dataclass(frozen=True)
class _Fit:
    normals: FloatArray  # (b, 3)
    shape_operator: FloatArray  # (b, 3, 3)
    residual: FloatArray  # (b,) weighted RMS residual / h̄
    pivot: FloatArray  # (b,) smallest relative pivot of the g, h unknowns


def _circle_fit(q: FloatArray, mask: BoolArray, edges: FloatArray, edge_mask: BoolArray,
                n: FloatArray, cubic: bool, tilt: bool) -> _Fit:
    """The circle-aware fit (module doc) of points ``q`` (b, 3, m) relative to their vertex, padding ``mask`` (b, m).

    ``edges`` (b, 3, k) are the ring edges for h̄. With ``tilt`` the normal ``n`` (b, 3) is refitted
    :data:`ITERATIONS` times, else held (g1, g2 left out, one pass). Columns: [x, y,] a x², 2a xy,
    a y² [, x³/6, x²y/2, xy²/2, y³/6] with a = ½(1 + z²/r²), coordinates in units of h̄.
    """
    edge_length2 = np.einsum("bdk,bdk->bk", edges, edges)
    count = edge_mask.sum(axis=1)
    k = 3 + 2 * tilt + 4 * cubic
    design = np.empty((q.shape[0], k, q.shape[2]))
    for _ in range(ITERATIONS if tilt else 1):
        e1, e2 = _frame(n)
        height = np.matmul(n[:, None, :], edges)[:, 0]
        hbar = np.sqrt(np.sum(np.where(edge_mask, edge_length2 - height**2, 0.0), axis=1) / count)[:, None]
        x, y, z = np.matmul(np.stack([e1, e2, n], axis=1) / hbar[:, :, None], q).transpose(1, 0, 2)
        xx, xy, yy = x * x, x * y, y * y
        r2 = xx + yy
        away = mask & (r2 > 1e-24)
        a = 0.5 + 0.5 * z * z / np.where(away, r2, 1.0)
        w = np.where(away, np.exp(-0.5 * r2), 0.0)
        if tilt:
            design[:, 0], design[:, 1] = x, y
        h = 2 * tilt
        np.multiply(a, xx, out=design[:, h])
        np.multiply(2.0 * a, xy, out=design[:, h + 1])
        np.multiply(a, yy, out=design[:, h + 2])
        if cubic:
            np.multiply(xx, x / 6.0, out=design[:, h + 3])
            np.multiply(xx, y / 2.0, out=design[:, h + 4])
            np.multiply(yy, x / 2.0, out=design[:, h + 5])
            np.multiply(yy, y / 6.0, out=design[:, h + 6])
        weighted = design * w[:, None, :]
        gram = np.ascontiguousarray(np.matmul(weighted, design.transpose(0, 2, 1)).transpose(1, 2, 0))
        rhs = np.matmul(weighted, z[:, :, None])[:, :, 0].T
        c, pivot = _solve(gram, rhs)
        residual = np.sqrt(np.maximum(np.sum(w * z * z, axis=1) - np.einsum("kb,kb->b", c, rhs), 0.0) / np.sum(w, axis=1))
        h11, h12, h22 = c[2 * tilt:2 * tilt + 3] / hbar[:, 0]
        frame_h = (h11[:, None, None] * e1[:, :, None] * e1[:, None, :]
                   + h12[:, None, None] * (e1[:, :, None] * e2[:, None, :] + e2[:, :, None] * e1[:, None, :])
                   + h22[:, None, None] * e2[:, :, None] * e2[:, None, :])
        if tilt:
            n = _unit(n - c[0][:, None] * e1 - c[1][:, None] * e2)
    project = np.eye(3) - n[:, :, None] * n[:, None, :]
    return _Fit(n, -project @ frame_h @ project, residual, np.min(pivot[:2 * tilt + 3], axis=0))


def _fit_all(mesh: QuadMesh, ring: _Ring, hood: _Hood, vertices: IntArray, n: FloatArray,
             cubic: bool, tilt: bool, store: Callable[[IntArray, _Fit], None]) -> None:
    """:func:`_circle_fit` over ``vertices`` with neighbourhoods ``hood``, block by block, handing each to ``store``."""
    x = mesh.vertices
    for block in _blocks(vertices, hood.sizes):
        where, mask = _padded(block, hood.offsets)
        q = (x[hood.points[where]] - x[block, None, :]).transpose(0, 2, 1)
        edge_where, edge_mask = _padded(block, ring.offsets)
        store(block, _circle_fit(q, mask, ring.d[edge_where].transpose(0, 2, 1), edge_mask, n[block], cubic, tilt))


def vertex_frames(mesh: QuadMesh) -> VertexFrames:
    """Unit normals and shape operators at the vertices of ``mesh``: repaired fan normal, circle-aware
    fit where trusted, else the fan normal with the fixed-normal circle fit of S (module doc)."""
    nv = mesh.n_vertices
    ring = _Ring.of(mesh)
    start = fan_normals(mesh)
    repaired = np.zeros(nv, dtype=bool)
    bad = np.flatnonzero(~ring.valid(start))
    if bad.size:
        start, done = ring.repair(start, bad)
        repaired[bad[done]] = True

    one, two = _face_rings(mesh)
    normals = np.empty((nv, 3))
    shape_operator = np.empty((nv, 3, 3))
    residual = np.empty(nv)
    pivot = np.empty(nv)

    def keep_fit(block: IntArray, fit: _Fit) -> None:
        normals[block], shape_operator[block], residual[block], pivot[block] = (
            fit.normals, fit.shape_operator, fit.residual, fit.pivot)

    with np.errstate(invalid="ignore", divide="ignore"):
        large = two.sizes >= CUBIC_POINTS
        _fit_all(mesh, ring, two, np.flatnonzero(large), start, True, True, keep_fit)
        _fit_all(mesh, ring, one, np.flatnonzero(~large), start, False, True, keep_fit)
        fitted = (
            ~mesh.topology.is_boundary_vertex  # a one-sided neighbourhood extrapolates the normal
            & np.isfinite(normals).all(axis=1)
            & np.isfinite(shape_operator).all(axis=(1, 2))
            & (residual <= RESIDUAL)
            & (pivot >= MIN_PIVOT)
            & (np.einsum("vd,vd->v", normals, start) >= np.cos(np.radians(MAX_TILT)))
            & (ring.steepness(normals) <= np.sin(np.radians(MAX_STEEPNESS)))
        )
        fitted &= ring.valid(np.where(fitted[:, None], normals, start))
        rest = np.flatnonzero(~fitted)
        normals[rest] = start[rest]

        def keep_curvature(block: IntArray, fit: _Fit) -> None:
            shape_operator[block] = np.nan_to_num(fit.shape_operator)

        if rest.size:
            _fit_all(mesh, ring, one, rest, start, False, False, keep_curvature)
    return VertexFrames(normals, 0.5 * (shape_operator + shape_operator.transpose(0, 2, 1)), fitted, repaired)
