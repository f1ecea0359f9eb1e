"""Vertex normals and second fundamental forms for surfaces that interpolate a quad mesh's vertices.

**Start.** The area-weighted fan normal ``N_A = normalize(Σ d_i × d_{i+1})`` over consecutive
ring edges ``d_i = x_i − A`` (:func:`g1patch.targets.local.fan_normals`).

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
``N ← normalize(N − g1 e1 − g2 e2)``, 3 times, a vertex stopping early once its slope ``|g|`` <
``STOP`` = 1e-14 (the further refits would move N by about that: at 1 M torus quads the slopes
are ≤ 9e-10, 6e-15, 3e-16, so 2 fits). On a sphere of radius ρ (outward normal n, frame
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

**Evaluation.** The fits run vertex by vertex in a numba kernel (:func:`_fit_kernel`, compiled
on first use and cached on disk; numba is imported only then). The NumPy reference
(``vertex_frames(mesh, compiled=False)``) sorts the vertices by neighbourhood size and fits
padded blocks; the two agree to rounding (normals within 256 ε, S within 2¹⁴ ε of its
largest entry, the same masks: tests/test_frames.py).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray

from .local import cross, fan_normals, jit_kernel
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
ITERATIONS = 3  #: most refits of the normal
STOP = 1e-14  #: a vertex's refits stop once its slope |g| is below this
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
    e1 = _unit(cross(n, axis))
    return e1, cross(n, e1)


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
    dot: FloatArray  # d_first · d_second
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
        a, b = d[first], d[second]
        return cls(offsets, owner, d, pair_owner, first, second, cross(a, b), np.einsum("pd,pd->p", a, b),
                   topo.is_boundary_vertex)

    def valid(self, n: FloatArray) -> BoolArray:
        """The projected ring goes once around ``n`` (V, 3) counter-clockwise (see the module doc)."""
        np_ = n[self.pair_owner]
        sine = np.einsum("pd,pd->p", np_, self.cross)
        height = np.einsum("nd,nd->n", self.d, n[self.owner])
        cosine = self.dot - height[self.first] * height[self.second]
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
        np.add.at(unit_fan, owner, cross(u[self.first[pick]], u[self.second[pick]]))
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

    offsets: NDArray[np.integer]
    points: NDArray[np.integer]

    @classmethod
    def without_self(cls, pattern: sp.csr_matrix) -> _Hood:
        """The rows of a boolean ``pattern`` whose diagonal is all set, without it (order kept)."""
        pattern = pattern.copy()
        pattern.setdiag(False)
        pattern.eliminate_zeros()
        return cls(pattern.indptr, pattern.indices)

    @property
    def sizes(self) -> IntArray:
        return np.diff(self.offsets)


def _face_rings(mesh: QuadMesh) -> tuple[_Hood, _Hood]:
    """Face 1-ring (vertices of the faces at v) and face 2-ring (vertices of the faces at those), from
    the vertex–face incidence ``I``: the patterns of ``I Iᵀ`` and ``(I Iᵀ)²``."""
    nv, nf = mesh.n_vertices, mesh.n_faces
    incidence = sp.csr_matrix((np.ones(4 * nf, dtype=bool), (mesh.faces.ravel(), np.repeat(np.arange(nf), 4))),
                              shape=(nv, nf))
    one = (incidence @ incidence.T).tocsr()
    return _Hood.without_self(one), _Hood.without_self((one @ one).tocsr())


def _padded(vertices: IntArray, offsets: IntArray) -> tuple[IntArray, BoolArray]:
    """Positions ``offsets[v] + j`` (0 where padded) and their mask, one row per vertex."""
    start = offsets[vertices]
    count = offsets[vertices + 1] - start
    column = np.arange(int(count.max()))
    mask = column < count[:, None]
    return np.where(mask, start[:, None] + column, 0), mask


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

    @classmethod
    def empty(cls, size: int) -> _Fit:
        return cls(np.empty((size, 3)), np.empty((size, 3, 3)), np.empty(size), np.empty(size))


def _circle_fit(q: FloatArray, mask: BoolArray, edges: FloatArray, edge_mask: BoolArray,
                n: FloatArray, cubic: bool, tilt: bool) -> _Fit:
    """The circle-aware fit (module doc) of points ``q`` (b, 3, m) relative to their vertex, padding ``mask`` (b, m).

    ``edges`` (b, 3, k) are the ring edges for h̄. With ``tilt`` the normal ``n`` (b, 3) is refitted
    up to :data:`ITERATIONS` times, a vertex stopping once its slope ``|g|`` < :data:`STOP`, else
    held (g1, g2 left out, one pass). Columns: [x, y,] a x², 2a xy, a y² [, x³/6, x²y/2, xy²/2, y³/6]
    with a = ½(1 + z²/r²), coordinates in units of h̄.
    """
    out = _Fit(n.copy(), np.empty((n.shape[0], 3, 3)), np.empty(n.shape[0]), np.empty(n.shape[0]))
    edge_length2 = np.einsum("bdk,bdk->bk", edges, edges)
    count = edge_mask.sum(axis=1)
    k = 3 + 2 * tilt + 4 * cubic
    active = np.arange(n.shape[0])
    for _ in range(ITERATIONS if tilt else 1):
        n = out.normals[active]
        e1, e2 = _frame(n)
        height = np.matmul(n[:, None, :], edges)[:, 0]
        hbar = np.sqrt(np.sum(np.where(edge_mask, edge_length2 - height**2, 0.0), axis=1) / count)[:, None]
        x, y, z = np.matmul(np.stack([e1, e2, n], axis=1) / hbar[:, :, None], q).transpose(1, 0, 2)
        xx, xy, yy = x * x, x * y, y * y
        r2 = xx + yy
        away = mask & (r2 > 1e-24)
        a = 0.5 + 0.5 * z * z / np.where(away, r2, 1.0)
        w = np.where(away, np.exp(-0.5 * r2), 0.0)
        design = np.empty((n.shape[0], k, q.shape[2]))
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
        out.residual[active] = np.sqrt(
            np.maximum(np.sum(w * z * z, axis=1) - np.einsum("kb,kb->b", c, rhs), 0.0) / np.sum(w, axis=1))
        out.pivot[active] = np.min(pivot[:2 * tilt + 3], axis=0)
        h11, h12, h22 = c[2 * tilt:2 * tilt + 3] / hbar[:, 0]
        out.shape_operator[active] = (
            h11[:, None, None] * e1[:, :, None] * e1[:, None, :]
            + h12[:, None, None] * (e1[:, :, None] * e2[:, None, :] + e2[:, :, None] * e1[:, None, :])
            + h22[:, None, None] * e2[:, :, None] * e2[:, None, :])
        if tilt:
            out.normals[active] = _unit(n - c[0][:, None] * e1 - c[1][:, None] * e2)
            going = ~(np.hypot(c[0], c[1]) < STOP)
            active = active[going]
            q, mask, edges, edge_mask = q[going], mask[going], edges[going], edge_mask[going]
            edge_length2, count = edge_length2[going], count[going]
            if not active.size:
                break
    project = np.eye(3) - out.normals[:, :, None] * out.normals[:, None, :]
    out.shape_operator[:] = -project @ out.shape_operator @ project
    return out


def _fit_kernel(x: FloatArray, faces: IntArray, ring_offsets: IntArray, ring_halfedges: IntArray,
                neighbor_offsets: IntArray, neighbors: IntArray, vertices: IntArray, start: FloatArray, tilt: bool,
                out_normals: FloatArray, out_shape: FloatArray, out_residual: FloatArray, out_pivot: FloatArray) -> None:
    """:func:`_circle_fit` of ``vertices`` one at a time, compiled by :func:`~g1patch.targets.local.jit_kernel`
    (same formulas and steps), with each vertex's neighbourhood gathered from the topology on the spot.

    The face 1-ring are the corners of the faces at v; the face 2-ring adds the corners of the
    faces at those (the rows of ``I Iᵀ`` and ``(I Iᵀ)²`` of :func:`_face_rings`, in the same
    order). With ``tilt`` a vertex with a 2-ring of ≥ :data:`CUBIC_POINTS` points fits it with the
    cubic, else its 1-ring without; without ``tilt`` the 1-ring, normal held. The Gram matrix is
    accumulated point by point, each entry summed over the points in order.
    Writes row i of the ``out_`` arrays for ``vertices[i]``; S as in :func:`_circle_fit`, before symmetrising.
    """
    most = 1  # the largest face count: bounds the scratch of one ring
    for u in range(ring_offsets.size - 1):
        most = max(most, ring_offsets[u + 1] - ring_offsets[u])
    ring_faces = np.empty(most, dtype=np.int64)
    ring = np.empty(4 * most, dtype=np.int64)
    centres = np.empty(4 * most, dtype=np.int64)
    corners = np.empty(4, dtype=np.int64)
    seen = np.full(x.shape[0], -1)  # stamp of the ring being gathered
    taken = np.full(x.shape[0], -1)  # v once a point is in v's 2-ring
    stamp = 0
    hood = np.empty(64, dtype=np.int64)
    q = np.empty((64, 3))
    row = np.empty(9)
    gram = np.empty((9, 9))
    lower = np.empty((9, 9))
    rhs = np.empty(9)
    pivot = np.empty(9)
    c = np.empty(9)
    n = np.empty(3)
    e1 = np.empty(3)
    e2 = np.empty(3)
    frame_h = np.empty((3, 3))
    project = np.empty((3, 3))
    product = np.empty((3, 3))
    for i in range(vertices.size):
        v = vertices[i]
        # Rows of I Iᵀ in scipy's order (reversed first encounter, over the faces in increasing
        # order and their corners in increasing order), so that the sums are those of the NumPy
        # reference: R(v) gives the 1-ring, and the 2-ring is the reversed first encounter over
        # R(c) for c in R(v).
        count = 0
        m = 0
        for at in range(-1, 4 * most):
            if at == count or (at >= 0 and not tilt):
                break
            centre = v if at < 0 else centres[at]
            stamp += 1
            first, faces_here = ring_offsets[centre], ring_offsets[centre + 1] - ring_offsets[centre]
            for r in range(faces_here):  # insertion sort of the ring's faces
                f = ring_halfedges[first + r] >> 2
                j = r
                while j > 0 and ring_faces[j - 1] > f:
                    ring_faces[j] = ring_faces[j - 1]
                    j -= 1
                ring_faces[j] = f
            size = 0
            for r in range(faces_here):
                for corner in range(4):
                    p = faces[ring_faces[r], corner]
                    j = corner
                    while j > 0 and corners[j - 1] > p:
                        corners[j] = corners[j - 1]
                        j -= 1
                    corners[j] = p
                for corner in range(4):
                    p = corners[corner]
                    if seen[p] != stamp:
                        seen[p] = stamp
                        ring[size] = p
                        size += 1
            if at < 0:
                count = size
                for j in range(size):
                    centres[j] = ring[size - 1 - j]
                continue
            for j in range(size - 1, -1, -1):
                p = ring[j]
                if taken[p] != v:
                    taken[p] = v
                    if m == hood.size:
                        grown = np.empty(2 * m, dtype=np.int64)
                        grown[:m] = hood
                        hood = grown
                    hood[m] = p
                    m += 1
        cubic = tilt and m - 1 >= CUBIC_POINTS
        if cubic:  # the 2-ring: reversed, without v
            for j in range(m // 2):
                hood[j], hood[m - 1 - j] = hood[m - 1 - j], hood[j]
        else:  # the 1-ring, without v
            if hood.size < count:
                hood = np.empty(count, dtype=np.int64)
            m = count
            hood[:m] = centres[:m]
        kept = 0
        for j in range(m):
            if hood[j] != v:
                hood[kept] = hood[j]
                kept += 1
        m = kept
        k = 3 + 2 * tilt + 4 * cubic
        h = 2 * tilt
        if q.shape[0] < m:
            q = np.empty((hood.size, 3))
        for j in range(m):
            for d in range(3):
                q[j, d] = x[hood[j], d] - x[v, d]
        n[:] = start[v]
        for _ in range(ITERATIONS if tilt else 1):
            # the frame (_frame): e1 = unit(n × axis), axis the first coordinate axis least aligned with n
            axis = 0
            for d in (1, 2):
                if abs(n[d]) < abs(n[axis]):
                    axis = d
            e1[0], e1[1], e1[2] = 0.0, 0.0, 0.0
            e1[(axis + 1) % 3] = n[(axis + 2) % 3]
            e1[(axis + 2) % 3] = -n[(axis + 1) % 3]
            length = np.sqrt(e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2])
            e1 /= length
            e2[0] = n[1] * e1[2] - n[2] * e1[1]
            e2[1] = n[2] * e1[0] - n[0] * e1[2]
            e2[2] = n[0] * e1[1] - n[1] * e1[0]
            spread = 0.0
            for j in range(neighbor_offsets[v], neighbor_offsets[v + 1]):
                dx, dy, dz = x[neighbors[j], 0] - x[v, 0], x[neighbors[j], 1] - x[v, 1], x[neighbors[j], 2] - x[v, 2]
                height = n[0] * dx + n[1] * dy + n[2] * dz
                spread += (dx * dx + dy * dy + dz * dz) - height * height
            hbar = np.sqrt(spread / (neighbor_offsets[v + 1] - neighbor_offsets[v]))
            ux, uy, uz = e1[0] / hbar, e1[1] / hbar, e1[2] / hbar
            vx, vy, vz = e2[0] / hbar, e2[1] / hbar, e2[2] / hbar
            nx, ny, nz = n[0] / hbar, n[1] / hbar, n[2] / hbar
            gram[:k, :k] = 0.0
            rhs[:k] = 0.0
            sum_w = 0.0
            sum_wzz = 0.0
            for j in range(m):
                px, py, pz = q[j, 0], q[j, 1], q[j, 2]
                xj = ux * px + uy * py + uz * pz
                yj = vx * px + vy * py + vz * pz
                zj = nx * px + ny * py + nz * pz
                xx, xy, yy = xj * xj, xj * yj, yj * yj
                r2 = xx + yy
                if r2 > 1e-24:
                    a = 0.5 + 0.5 * zj * zj / r2
                    w = np.exp(-0.5 * r2)
                else:
                    a, w = 0.5 + 0.5 * zj * zj, 0.0
                if tilt:
                    row[0], row[1] = xj, yj
                row[h], row[h + 1], row[h + 2] = a * xx, 2.0 * a * xy, a * yy
                if cubic:
                    row[h + 3], row[h + 4] = xx * (xj / 6.0), xx * (yj / 2.0)
                    row[h + 5], row[h + 6] = yy * (xj / 2.0), yy * (yj / 6.0)
                for r in range(k):
                    weighted = row[r] * w
                    for s in range(r, k):
                        gram[r, s] += weighted * row[s]
                    rhs[r] += weighted * zj
                sum_w += w
                sum_wzz += w * zj * zj
            for r in range(k):
                for s in range(r + 1, k):
                    gram[s, r] = gram[r, s]
            # the pivot-dropping Cholesky of _solve, in place in ``lower``
            lower[:k, :k] = gram[:k, :k]
            for j in range(k):
                diagonal = gram[j, j]
                pivot[j] = lower[j, j] / diagonal if diagonal > 0 else 0.0
                root = np.sqrt(lower[j, j]) if pivot[j] > DROP_PIVOT else 0.0
                for r in range(j, k):
                    lower[r, j] = lower[r, j] / root if pivot[j] > DROP_PIVOT else 0.0
                for r in range(j + 1, k):
                    for s in range(j + 1, r + 1):
                        lower[r, s] -= lower[r, j] * lower[s, j]
            for j in range(k):
                total = rhs[j]
                for r in range(j):
                    total -= lower[j, r] * c[r]
                c[j] = total / lower[j, j] if pivot[j] > DROP_PIVOT else 0.0
            for j in range(k - 1, -1, -1):
                total = c[j]
                for r in range(j + 1, k):
                    total -= lower[r, j] * c[r]
                c[j] = total / lower[j, j] if pivot[j] > DROP_PIVOT else 0.0
            explained = 0.0
            for r in range(k):
                explained += c[r] * rhs[r]
            unexplained = sum_wzz - explained
            out_residual[i] = np.sqrt((0.0 if unexplained < 0.0 else unexplained) / sum_w)
            smallest = pivot[0]
            for j in range(1, h + 3):
                if pivot[j] < smallest or np.isnan(pivot[j]):
                    smallest = pivot[j]
            out_pivot[i] = smallest
            h11, h12, h22 = c[h] / hbar, c[h + 1] / hbar, c[h + 2] / hbar
            for r in range(3):
                for s in range(3):
                    frame_h[r, s] = (h11 * e1[r] * e1[s] + h12 * (e1[r] * e2[s] + e2[r] * e1[s])
                                     + h22 * e2[r] * e2[s])
            if tilt:
                for d in range(3):
                    n[d] = n[d] - c[0] * e1[d] - c[1] * e2[d]
                n /= np.sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2])
                if np.hypot(c[0], c[1]) < STOP:
                    break
        out_normals[i] = n
        for r in range(3):  # S = ((−P) H) P
            for s in range(3):
                project[r, s] = (1.0 if r == s else 0.0) - n[r] * n[s]
        for r in range(3):
            for s in range(3):
                total = 0.0
                for t in range(3):
                    total += -project[r, t] * frame_h[t, s]
                product[r, s] = total
        for r in range(3):
            for s in range(3):
                total = 0.0
                for t in range(3):
                    total += product[r, t] * project[t, s]
                out_shape[i, r, s] = total


def _ring_kernel(x: FloatArray, neighbor_offsets: IntArray, neighbors: IntArray, face_count: IntArray,
                 boundary: BoolArray, normals: FloatArray, vertices: IntArray, out_valid: BoolArray,
                 out_steepness: FloatArray) -> None:
    """:meth:`_Ring.valid` and :meth:`_Ring.steepness` of ``normals[v]`` at ``vertices``, vertex by vertex
    (row i for ``vertices[i]``): turning angles ``atan2(N·(d_i × d_{i+1}), d_i·d_{i+1} − (N·d_i)(N·d_{i+1}))``
    summed over the ring's consecutive pairs, and the largest ``|N·d|/|d|``."""
    for i in range(vertices.size):
        v = vertices[i]
        n0, n1, n2 = normals[v, 0], normals[v, 1], normals[v, 2]
        first, count = neighbor_offsets[v], neighbor_offsets[v + 1] - neighbor_offsets[v]
        total = 0.0
        folded = False
        for step in range(face_count[v]):
            a, b = neighbors[first + step], neighbors[first + (step + 1) % count]
            ax, ay, az = x[a, 0] - x[v, 0], x[a, 1] - x[v, 1], x[a, 2] - x[v, 2]
            bx, by, bz = x[b, 0] - x[v, 0], x[b, 1] - x[v, 1], x[b, 2] - x[v, 2]
            sine = n0 * (ay * bz - az * by) + n1 * (az * bx - ax * bz) + n2 * (ax * by - ay * bx)
            cosine = (ax * bx + ay * by + az * bz) - (ax * n0 + ay * n1 + az * n2) * (bx * n0 + by * n1 + bz * n2)
            total += np.arctan2(sine, cosine)
            folded |= not sine > 0
        once = total < 2.0 * np.pi if boundary[v] else abs(total - 2.0 * np.pi) < np.pi
        out_valid[i] = once and not folded
        steepest = 0.0
        for j in range(first, first + count):
            p = neighbors[j]
            dx, dy, dz = x[p, 0] - x[v, 0], x[p, 1] - x[v, 1], x[p, 2] - x[v, 2]
            sine = abs(dx * n0 + dy * n1 + dz * n2) / np.sqrt(dx * dx + dy * dy + dz * dz)
            if not sine <= steepest:
                steepest = sine
        out_steepness[i] = steepest


def _ring_checks(mesh: QuadMesh, normals: FloatArray, vertices: IntArray) -> tuple[BoolArray, FloatArray]:
    """:func:`_ring_kernel`: validity and steepness of ``normals`` at ``vertices``."""
    topo = mesh.topology
    valid = np.empty(vertices.size, dtype=bool)
    steepness = np.empty(vertices.size)
    jit_kernel(_ring_kernel)(mesh.vertices, topo.neighbor_offsets, topo.neighbors, topo.face_count, topo.is_boundary_vertex,
                           normals, vertices, valid, steepness)
    return valid, steepness


def _fit_all(mesh: QuadMesh, ring: _Ring, hood: _Hood, vertices: IntArray, n: FloatArray,
             cubic: bool, tilt: bool) -> _Fit:
    """:func:`_circle_fit` of ``vertices`` with neighbourhoods ``hood`` and start normals ``n`` (V, 3), row i for
    ``vertices[i]``, block by block in NumPy (the reference of :func:`_fit_kernel`)."""
    out = _Fit.empty(vertices.size)
    x = mesh.vertices
    order = np.argsort(hood.sizes[vertices], kind="stable")
    for rows in (order[s:s + BLOCK] for s in range(0, order.size, BLOCK)):
        block = vertices[rows]
        where, mask = _padded(block, hood.offsets)
        q = (x[hood.points[where]] - x[block, None, :]).transpose(0, 2, 1)
        edge_where, edge_mask = _padded(block, ring.offsets)
        fit = _circle_fit(q, mask, ring.d[edge_where].transpose(0, 2, 1), edge_mask, n[block], cubic, tilt)
        out.normals[rows], out.shape_operator[rows], out.residual[rows], out.pivot[rows] = (
            fit.normals, fit.shape_operator, fit.residual, fit.pivot)
    return out


def _fit_compiled(mesh: QuadMesh, vertices: IntArray, n: FloatArray, tilt: bool) -> _Fit:
    """:func:`_fit_kernel` of ``vertices`` (row i for ``vertices[i]``) with start normals ``n`` (V, 3)."""
    topo = mesh.topology
    out = _Fit.empty(vertices.size)
    jit_kernel(_fit_kernel)(mesh.vertices, topo.faces, topo.ring_offsets, topo.ring_halfedges, topo.neighbor_offsets,
                          topo.neighbors, vertices, n, tilt, out.normals, out.shape_operator, out.residual, out.pivot)
    return out


def vertex_frames(mesh: QuadMesh, *, compiled: bool = True) -> VertexFrames:
    """Unit normals and shape operators at the vertices of ``mesh``: repaired fan normal, circle-aware
    fit where trusted, else the fan normal with the fixed-normal circle fit of S (module doc).

    ``compiled`` runs the fits and ring checks in numba kernels (:func:`_fit_kernel`,
    :func:`_ring_kernel`); ``False`` runs the NumPy reference (the same to rounding, tests/test_frames.py).
    """
    nv = mesh.n_vertices
    everything = np.arange(nv)
    ring = None if compiled else _Ring.of(mesh)
    start = fan_normals(mesh, compiled=compiled)
    repaired = np.zeros(nv, dtype=bool)
    bad = np.flatnonzero(~(_ring_checks(mesh, start, everything)[0] if compiled else ring.valid(start)))
    if bad.size:
        ring = ring or _Ring.of(mesh)
        start, done = ring.repair(start, bad)
        repaired[bad[done]] = True

    with np.errstate(invalid="ignore", divide="ignore"):
        if compiled:
            fit = _fit_compiled(mesh, everything, start, True)
            normals, shape_operator, residual, pivot = fit.normals, fit.shape_operator, fit.residual, fit.pivot
        else:
            one, two = _face_rings(mesh)
            normals = np.empty((nv, 3))
            shape_operator = np.empty((nv, 3, 3))
            residual = np.empty(nv)
            pivot = np.empty(nv)
            large = two.sizes >= CUBIC_POINTS
            for hood, cubic in ((two, True), (one, False)):
                vertices = np.flatnonzero(large == cubic)
                fit = _fit_all(mesh, ring, hood, vertices, start, cubic, True)
                normals[vertices], shape_operator[vertices], residual[vertices], pivot[vertices] = (
                    fit.normals, fit.shape_operator, fit.residual, fit.pivot)
        fitted = (
            ~mesh.topology.is_boundary_vertex  # a one-sided neighbourhood extrapolates the normal
            & np.isfinite(normals).all(axis=1)
            & np.isfinite(shape_operator).all(axis=(1, 2))
            & (residual <= RESIDUAL)
            & (pivot >= MIN_PIVOT)
            & (np.einsum("vd,vd->v", normals, start) >= np.cos(np.radians(MAX_TILT)))
        )
        if compiled:
            candidates = np.flatnonzero(fitted)
            valid, steepness = _ring_checks(mesh, normals, candidates)
            fitted[candidates] = valid & (steepness <= np.sin(np.radians(MAX_STEEPNESS)))
        else:
            fitted &= ring.steepness(normals) <= np.sin(np.radians(MAX_STEEPNESS))
            fitted &= ring.valid(np.where(fitted[:, None], normals, start))
        rest = np.flatnonzero(~fitted)
        normals[rest] = start[rest]
        if rest.size:
            held = _fit_compiled(mesh, rest, start, False) if compiled else _fit_all(mesh, ring, one, rest, start, False, False)
            shape_operator[rest] = np.nan_to_num(held.shape_operator)
    shape_operator += shape_operator.transpose(0, 2, 1).copy()
    shape_operator *= 0.5
    return VertexFrames(normals, shape_operator, fitted, repaired)
