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

    z = g1 x + g2 y + ½ (1 + z²/r²)(h11 x² + 2 h12 xy + h22 y²)
        + (c1 x³ + 3c2 x²y + 3c3 xy² + c4 y³)/6

by weighted least squares, ``w = exp(−r²/(2 h̄²))``, h̄² the mean squared projected length of the
ring edges; the cubic only with ≥ 12 points, else the face 1-ring without it. Then
``N ← normalize(N − g1 e1 − g2 e2)``, 3 times, a vertex stopping early once its slope ``|g|`` <
``STOP`` = 1e-14 (the further refits would move N by about that: at 1 M torus quads the slopes
are ≤ 9e-10, 6e-15, 3e-16, so 2 fits). On a sphere of radius ρ (outward normal n, frame
normal N with n = (a, b, c) in the frame) ``|q + ρn|² = ρ²`` gives exactly
``z = −(a/c) x − (b/c) y − (r² + z²)/(2ρc)``: the model holds with C = 0, so one step is exact at
any resolution (the cube's corners included). Elsewhere N is O(h³) and H O(h²).

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
* ``MIN_PIVOT``: each of the 5 unknowns g, h is determined: sin² of the angle of its column to
  the span of *all* the other columns, ``1 / (G_jj (G⁻¹)_jj)`` of the scaled normal equations
  G, is ≥ 1e-3. The hub of a split n-gon fails it: its 2-ring lies on one circle r = ρ, where
  ``x r² = x³ + xy²`` makes the slope column a combination of cubic ones, and the fit tilted a
  1000-gon's centre normal by 20° (the fan normal is exact there). Measured on the meshes above
  and the shared ones, no other vertex changes (a test against the earlier, sequential pivot
  rejected nothing). In the pivot-dropping Cholesky of the normal equations, cubic columns whose
  pivot (sin² of the angle to the earlier columns) is below 1e-10 are dropped (coefficient 0).

**Evaluation.** The fits run in a numba kernel (:func:`_fit_kernel`, compiled on first use and
cached on disk; numba is imported only then): every vertex goes through the one-vertex sequence
of operations, :data:`LANES` vertices side by side so that the inner loops vectorise, with the
neighbourhoods in scipy's order, so the sums are the same; the ring checks and fan normals are
kernels too. The NumPy reference (``vertex_frames(mesh, compiled=False)``) sorts the vertices by
neighbourhood size and fits padded blocks; the two agree to rounding (normals within 256 ε, S
within 2¹⁴ ε of its largest entry, the same masks: tests/test_frames.py).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray

from ..kernels import in_chunks, jit_kernel
from ..mesh import QuadMesh
from .local import cross, fan_normals

__all__ = ["VertexFrames", "vertex_frames", "RESIDUAL", "MAX_TILT", "MAX_STEEPNESS", "MIN_PIVOT"]

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]
BoolArray = NDArray[np.bool_]

RESIDUAL = 0.05  #: largest weighted RMS fit residual, in units of h̄
MAX_TILT = 25.0  #: largest angle (degrees) between fitted and start normal
MAX_STEEPNESS = 60.0  #: largest angle (degrees) between a ring edge and the tangent plane
MIN_PIVOT = 1e-3  #: smallest determination (sin² to the other columns) of the g, h unknowns
DROP_PIVOT = 1e-10  #: relative pivot below which a column is dropped from the fit
ITERATIONS = 3  #: most refits of the normal
STOP = 1e-14  #: a vertex's refits stop once its slope |g| is below this
CUBIC_POINTS = 12  #: fewest 2-ring points for the cubic term
#: a vertex whose face 1-ring has more points than this is a *hub* (the centre of a split n-gon, a
#: pole): its neighbours' 2-rings take the hub but not its whole ring, which keeps the fits linear
#: in the valence (a 100,000-gon's rim would otherwise see the whole centre ring from every vertex)
HUB_POINTS = 64
BLOCK = 2048  #: vertices per padded block (NumPy), per gathered block (kernel)
LANES = 32  #: vertices the kernel fits side by side
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
    """Unit e1, e2 with (e1, e2, n) right-handed: e1 ⊥ n and the coordinate axis least aligned with
    n."""
    axis = np.zeros_like(n)
    axis[np.arange(n.shape[0]), np.argmin(np.abs(n), axis=1)] = 1.0
    e1 = _unit(cross(n, axis))
    return e1, cross(n, e1)


# ----------------------------------------------------------------------------------------------
# the ring: consecutive pairs of neighbours, validity and steepness of a normal


@dataclass(frozen=True)
class _Ring:
    """Ring edges ``d`` (one per neighbour, grouped by vertex) and consecutive pairs ``(first,
    second)``."""

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
        return cls(
            offsets,
            owner,
            d,
            pair_owner,
            first,
            second,
            cross(a, b),
            np.einsum("pd,pd->p", a, b),
            topo.is_boundary_vertex,
        )

    def valid(self, n: FloatArray) -> BoolArray:
        """The projected ring goes once around ``n`` (V, 3) counter-clockwise (see the module
        doc)."""
        np_ = n[self.pair_owner]
        sine = np.einsum("pd,pd->p", np_, self.cross)
        height = np.einsum("nd,nd->n", self.d, n[self.owner])
        cosine = self.dot - height[self.first] * height[self.second]
        total = np.bincount(self.pair_owner, np.arctan2(sine, cosine), minlength=n.shape[0])
        folded = np.bincount(self.pair_owner, ~(sine > 0), minlength=n.shape[0]) > 0
        once = np.where(self.boundary, total < 2.0 * np.pi, np.abs(total - 2.0 * np.pi) < np.pi)
        return ~folded & once

    def steepness(self, n: FloatArray) -> FloatArray:
        """Largest ``|N·d| / |d|`` (sine of the angle to the plane) over each vertex's ring
        edges."""
        sine = np.abs(np.einsum("nd,nd->n", self.d, n[self.owner])) / np.linalg.norm(self.d, axis=1)
        return np.maximum.reduceat(sine, self.offsets[:-1])

    def repair(self, n: FloatArray, bad: IntArray) -> tuple[FloatArray, BoolArray]:
        """Valid normals for vertices ``bad``: unit-direction fan, else max–min of unit corner
        normals. A zero ring edge or corner (coincident points) gives a NaN candidate, which is not
        taken."""
        pick = np.isin(self.pair_owner, bad)
        owner = np.searchsorted(bad, self.pair_owner[pick])
        with np.errstate(invalid="ignore", divide="ignore"):
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
    """Approximate nearest-to-origin point of the convex hull of each group's ``points`` (Gilbert's
    algorithm).

    ``x ← x + t (p − x)`` with p minimising ``x·p`` in the group and ``t = clip(x·(x − p)/|x − p|²,
    0, 1)``.
    """
    start = np.zeros((groups, 3))
    np.add.at(start, owner, points)
    x = start / np.bincount(owner, minlength=groups)[:, None]
    bounds = np.searchsorted(np.sort(owner), np.arange(groups))
    for _ in range(GILBERT_STEPS):
        score = np.einsum("pd,pd->p", points, x[owner])
        p = points[np.lexsort((score, owner))[bounds]]  # the lowest score of each group
        gap = x - p
        t = np.clip(
            np.einsum("gd,gd->g", x, gap) / np.maximum(np.einsum("gd,gd->g", gap, gap), 1e-300),
            0.0,
            1.0,
        )
        x = x - t[:, None] * gap
    return x


# ----------------------------------------------------------------------------------------------
# the circle-aware fit, in padded blocks of vertices with similar neighbourhood sizes


@dataclass(frozen=True)
class _Hood:
    """A neighbourhood per vertex as CSR: ``points[offsets[v]:offsets[v + 1]]`` (the vertex itself
    excluded)."""

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
    """Face 1-ring (vertices of the faces at v) and face 2-ring (vertices of the faces at those),
    from the vertex–face incidence ``I``: the patterns of ``I Iᵀ`` and ``(I Iᵀ)²``."""
    nv, nf = mesh.n_vertices, mesh.n_faces
    incidence = sp.csr_matrix(
        (np.ones(4 * nf, dtype=bool), (mesh.faces.ravel(), np.repeat(np.arange(nf), 4))),
        shape=(nv, nf),
    )
    one = (incidence @ incidence.T).tocsr()
    # through a hub (a face 1-ring of more than HUB_POINTS points) the 2-ring takes the hub alone
    hub = np.flatnonzero(np.diff(one.indptr) > HUB_POINTS)
    passed = one
    if hub.size:
        coo = one.tocoo()
        keep = ~np.isin(coo.row, hub) | (coo.row == coo.col)
        passed = sp.csr_matrix((coo.data[keep], (coo.row[keep], coo.col[keep])), shape=one.shape)
    return _Hood.without_self(one), _Hood.without_self((one @ passed).tocsr())


def _padded(vertices: IntArray, offsets: IntArray) -> tuple[IntArray, BoolArray]:
    """Positions ``offsets[v] + j`` (0 where padded) and their mask, one row per vertex."""
    start = offsets[vertices]
    count = offsets[vertices + 1] - start
    column = np.arange(int(count.max()))
    mask = column < count[:, None]
    return np.where(mask, start[:, None] + column, 0), mask


def _solve(gram: FloatArray, rhs: FloatArray, leading: int) -> tuple[FloatArray, FloatArray]:
    """Least-squares coefficients (k, b) from the normal equations ``gram c = rhs`` ((k, k, b), (k,
    b)), and how well the first ``leading`` coefficients are determined (b,).

    Cholesky ``gram = L Lᵀ`` across the batch, one column at a time; a column whose pivot is at most
    :data:`DROP_PIVOT` of its diagonal (sin² of its angle to the earlier columns) is dropped, its
    coefficient 0: the least-squares solution without it. Column j's determination is sin² of its
    angle to the span of *all* the other kept columns, ``1 / (G_jj (G⁻¹)_jj)`` with
    ``(G⁻¹)_jj = |L⁻¹ e_j|²`` (0 if dropped); the smallest over the leading columns is returned.
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
        work[j + 1 :, j + 1 :] -= column[1:, None] * column[None, 1:]
    kept = pivot > DROP_PIVOT
    root = np.where(kept, np.einsum("iib->ib", lower), 1.0)
    y = np.zeros(rhs.shape)
    for j in range(k):
        y[j] = np.where(
            kept[j], (rhs[j] - np.einsum("lb,lb->b", lower[j, :j], y[:j])) / root[j], 0.0
        )
    c = np.zeros(rhs.shape)
    for j in reversed(range(k)):
        c[j] = np.where(
            kept[j], (y[j] - np.einsum("lb,lb->b", lower[j + 1 :, j], c[j + 1 :])) / root[j], 0.0
        )
    determined = np.full(rhs.shape[1], np.inf)
    for j in range(leading):
        unit = np.zeros(rhs.shape)  # L⁻¹ e_j: zero above j
        unit[j] = np.where(kept[j], 1.0 / root[j], 0.0)
        for r in range(j + 1, k):
            unit[r] = np.where(
                kept[r], -np.einsum("lb,lb->b", lower[r, j:r], unit[j:r]) / root[r], 0.0
            )
        inverse = np.sum(unit * unit, axis=0)
        column = np.where(kept[j], 1.0 / (gram[j, j] * np.where(kept[j], inverse, 1.0)), 0.0)
        determined = np.minimum(determined, np.where(np.isnan(column), -np.inf, column))
    return c, determined


@dataclass(frozen=True)
class _Fit:
    normals: FloatArray  # (b, 3)
    shape_operator: FloatArray  # (b, 3, 3)
    residual: FloatArray  # (b,) weighted RMS residual / h̄
    pivot: FloatArray  # (b,) smallest relative pivot of the g, h unknowns

    @classmethod
    def empty(cls, size: int) -> _Fit:
        return cls(np.empty((size, 3)), np.empty((size, 3, 3)), np.empty(size), np.empty(size))


def _circle_fit(
    q: FloatArray,
    mask: BoolArray,
    edges: FloatArray,
    edge_mask: BoolArray,
    n: FloatArray,
    cubic: bool,
    tilt: bool,
) -> _Fit:
    """The circle-aware fit (module doc) of points ``q`` (b, 3, m) relative to their vertex, padding
    ``mask`` (b, m).

    ``edges`` (b, 3, k) are the ring edges for h̄. With ``tilt`` the normal ``n`` (b, 3) is refitted
    up to :data:`ITERATIONS` times, a vertex stopping once its slope ``|g|`` < :data:`STOP`, else
    held (g1, g2 left out, one pass). Columns: [x, y,] a x², 2a xy, a y² [, x³/6, x²y/2, xy²/2,
    y³/6] with a = ½(1 + z²/r²), coordinates in units of h̄.
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
        hbar = np.sqrt(np.sum(np.where(edge_mask, edge_length2 - height**2, 0.0), axis=1) / count)[
            :, None
        ]
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
        gram = np.ascontiguousarray(
            np.matmul(weighted, design.transpose(0, 2, 1)).transpose(1, 2, 0)
        )
        rhs = np.matmul(weighted, z[:, :, None])[:, :, 0].T
        c, determined = _solve(gram, rhs, 2 * tilt + 3)
        out.residual[active] = np.sqrt(
            np.maximum(np.sum(w * z * z, axis=1) - np.einsum("kb,kb->b", c, rhs), 0.0)
            / np.sum(w, axis=1)
        )
        out.pivot[active] = determined
        h11, h12, h22 = c[2 * tilt : 2 * tilt + 3] / hbar[:, 0]
        out.shape_operator[active] = (
            h11[:, None, None] * e1[:, :, None] * e1[:, None, :]
            + h12[:, None, None]
            * (e1[:, :, None] * e2[:, None, :] + e2[:, :, None] * e1[:, None, :])
            + h22[:, None, None] * e2[:, :, None] * e2[:, None, :]
        )
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


#: faces around a vertex up to which :func:`_rows_kernel` sorts them by insertion and finds repeated
# : points by scanning the row (a valence-4 row holds 9 points); beyond it, in time linear in the
# ring
SMALL_RING = 16


def _rows_kernel(
    faces: IntArray,
    ring_offsets: IntArray,
    ring_halfedges: IntArray,
    offsets: IntArray,
    points: IntArray,
    fill: bool,
    lo: int,
    hi: int,
) -> None:
    """The rows of ``I Iᵀ`` (I the vertex–face incidence, :func:`_face_rings`) in scipy's order: per
    vertex the corners of its faces, the faces in increasing order and each face's corners in
    increasing order, each point once, reversed (scipy's sparse product lists a row's columns in
    reverse order of first encounter). ``fill=False`` writes the row sizes to ``offsets[v + 1]``,
    then ``fill=True`` the points, from ``offsets[v]``; vertices ``lo`` to ``hi``. A ring of at
    most :data:`SMALL_RING` faces is sorted by insertion and a point already in its row found by a
    scan of the row; a larger one (a hub of a split polygon: 100,000 faces took 40 s that way) is
    sorted by ``ndarray.sort`` and its points marked per vertex in an array over all points, which
    each range allocates for itself, so ranges run side by side without shared state."""
    most = 1
    for u in range(lo, hi):
        most = max(most, ring_offsets[u + 1] - ring_offsets[u])
    ring_faces = np.empty(most, dtype=np.int64)
    ring = np.empty(4 * most, dtype=np.int64)
    corners = np.empty(4, dtype=np.int64)
    in_row = np.full(
        offsets.size - 1 if most > SMALL_RING else 0, -1, dtype=np.int64
    )  # the last vertex whose row holds a point
    for v in range(lo, hi):
        first, count = ring_offsets[v], ring_offsets[v + 1] - ring_offsets[v]
        small = count <= SMALL_RING
        for r in range(count):  # the faces at v, sorted
            f = ring_halfedges[first + r] >> 2
            j = r
            while small and j > 0 and ring_faces[j - 1] > f:
                ring_faces[j] = ring_faces[j - 1]
                j -= 1
            ring_faces[j] = f
        if not small:
            ring_faces[:count].sort()
        size = 0
        for r in range(count):
            for corner in range(4):
                p = faces[ring_faces[r], corner]
                j = corner
                while j > 0 and corners[j - 1] > p:
                    corners[j] = corners[j - 1]
                    j -= 1
                corners[j] = p
            for corner in range(4):
                p = corners[corner]
                known = False
                if small:
                    for j in range(size):
                        known = known or ring[j] == p
                else:
                    known = in_row[p] == v
                    in_row[p] = v
                if not known:
                    ring[size] = p
                    size += 1
        if fill:
            for j in range(size):
                points[offsets[v] + j] = ring[size - 1 - j]
        else:
            offsets[v + 1] = size


def _fit_kernel(
    x: FloatArray,
    row_offsets: IntArray,
    rows: IntArray,
    neighbor_offsets: IntArray,
    neighbors: IntArray,
    vertices: IntArray,
    start: FloatArray,
    tilt: bool,
    lanes: int,
    out_normals: FloatArray,
    out_shape: FloatArray,
    out_residual: FloatArray,
    out_pivot: FloatArray,
) -> None:
    """:func:`_circle_fit` of ``vertices``, compiled by :func:`~g1patch.kernels.jit_kernel`: each
    vertex goes through the same formulas and steps, in the same order, as in the NumPy reference
    one vertex at a time; ``lanes`` vertices (of one column count) are fitted side by side, so
    that the innermost loops run over them and vectorise, while each lane's arithmetic is that of
    the vertex alone.

    Neighbourhoods: the face 1-ring is v's row of ``I Iᵀ`` (``rows``, :func:`_rows_kernel`) without
    v; the face 2-ring is v's row of ``(I Iᵀ)²``, in scipy's order too (reversed first encounter
    over the rows of v's row), without v. With ``tilt`` a vertex with a 2-ring of ≥
    :data:`CUBIC_POINTS` points fits it with the cubic, else its 1-ring without; without ``tilt``
    the 1-ring, normal held. :data:`BLOCK` vertices at a time are gathered, then fitted in lanes of
    one column count (sorted by column count and size; a batch's largest is at most twice its
    smallest, plus :data:`CUBIC_POINTS`); a lane with fewer points than the largest of its batch is
    padded with points at the vertex itself, which get weight 0 and add exactly nothing. Writes row
    i of the ``out_`` arrays for ``vertices[i]``; S as in :func:`_circle_fit`, before symmetrising.
    """
    taken = np.full(x.shape[0], -1, dtype=np.int32)  # v once a point is in v's 2-ring
    hood = np.empty(32 * BLOCK, dtype=np.int64)
    hood_begin = np.empty(BLOCK, dtype=np.int64)
    hood_size = np.empty(BLOCK, dtype=np.int64)
    key = np.empty(BLOCK, dtype=np.int64)
    order = np.empty(BLOCK, dtype=np.int64)
    large = np.int64(1) << 40  # key = size, + large for the cubic fits
    relative = np.zeros(
        32 * 3 * lanes
    )  # the batch's points relative to their vertex, (most, 3, nl)
    n = np.empty((3, lanes))
    e1 = np.empty((3, lanes))
    e2 = np.empty((3, lanes))
    scaled = np.empty((9, lanes))  # e1/h̄, e2/h̄, n/h̄
    hbar = np.empty(lanes)
    row = np.empty((11, lanes))
    weighted = np.empty(lanes)
    ws = np.empty(lanes)
    root = np.empty(lanes)
    total = np.empty(lanes)
    sum_w = np.empty(lanes)
    sum_wzz = np.empty(lanes)
    gram = np.empty((9, 9, lanes))
    lower = np.empty((9, 9, lanes))
    rhs = np.empty((9, lanes))
    pivot = np.empty((9, lanes))
    c = np.empty((9, lanes))
    unit = np.empty((9, lanes))  # L⁻¹ e_j
    inverse = np.empty(lanes)  # |L⁻¹ e_j|²
    smallest = np.empty(lanes)
    stopped = np.empty(lanes, dtype=np.bool_)
    finishing = np.empty(lanes, dtype=np.bool_)
    sweeps = ITERATIONS if tilt else 1
    frame_h = np.empty((3, 3, lanes))
    active = np.empty(lanes, dtype=np.bool_)
    axis_e1 = np.empty(3)
    project = np.empty((3, 3))
    product = np.empty((3, 3))
    for low in range(0, vertices.size, BLOCK):
        count = min(BLOCK, vertices.size - low)
        used = 0
        for b in range(count):
            v = vertices[low + b]
            # room: the 2-ring has at most Σ |row(c)| points over c in v's row (1 through a hub)
            room = row_offsets[v + 1] - row_offsets[v]
            if tilt:
                room = 0
                for at in range(row_offsets[v], row_offsets[v + 1]):
                    centre = rows[at]
                    size = row_offsets[centre + 1] - row_offsets[centre]
                    room += 1 if centre != v and size > HUB_POINTS else size
            if used + room > hood.size:
                grown = np.empty(max(2 * hood.size, used + room), dtype=np.int64)
                for j in range(used):
                    grown[j] = hood[j]
                hood = grown
            m = 0
            if (
                tilt
            ):  # the 2-ring: first encounter over the rows of v's row, written backwards (reversed)
                taken[v] = v  # without v
                end = used + room
                for at in range(row_offsets[v], row_offsets[v + 1]):
                    centre = rows[at]
                    size = row_offsets[centre + 1] - row_offsets[centre]
                    hub = (
                        centre != v and size > HUB_POINTS
                    )  # through a hub the 2-ring takes the hub alone
                    for j in range(1 if hub else size):
                        p = centre if hub else rows[row_offsets[centre] + j]
                        if taken[p] != v:
                            taken[p] = v
                            m += 1
                            hood[end - m] = p
            cubic = tilt and m >= CUBIC_POINTS
            if cubic:
                hood_begin[b] = used + room - m
            else:  # the 1-ring: v's row without v
                hood_begin[b] = used
                m = 0
                for j in range(row_offsets[v], row_offsets[v + 1]):
                    if rows[j] != v:
                        hood[used + m] = rows[j]
                        m += 1
            hood_size[b] = m
            used += room
            key[b] = m + (large if cubic else 0)
        # lanes share a column count and about a size (the padding stays below the batch's own
        # points: a hub is fitted alone): the block sorted by key, the others, then the cubic fits
        order[:count] = np.argsort(key[:count], kind="mergesort")
        first = 0
        while first < count:
            cubic = key[order[first]] >= large
            nl = 1
            while (
                nl < lanes
                and first + nl < count
                and (key[order[first + nl]] >= large) == cubic
                and hood_size[order[first + nl]] <= 2 * hood_size[order[first]] + CUBIC_POINTS
            ):
                nl += 1
            k = 3 + 2 * tilt + 4 * cubic
            h = 2 * tilt
            offset = 2 - h  # column r is feature offset + r
            most = 0
            for l in range(nl):
                b = order[first + l]
                most = max(most, hood_size[b])
            if relative.size < 3 * most * nl:
                relative = np.zeros(max(3 * most * nl, 2 * relative.size))
            q = relative[: 3 * most * nl].reshape((most, 3, nl))
            for l in range(nl):
                b = order[first + l]
                v = vertices[low + b]
                m, begin = hood_size[b], hood_begin[b]
                for j in range(most):
                    for d in range(3):
                        q[j, d, l] = x[hood[begin + j], d] - x[v, d] if j < m else 0.0
                for d in range(3):
                    n[d, l] = start[v, d]
                active[l] = True
            for sweep in range(sweeps):
                # per lane: the frame (_frame: e1 = unit(n × axis), axis the first coordinate axis
                # least aligned with n), h̄ from the ring edges, the scaled axes
                for l in range(nl):
                    v = vertices[low + order[first + l]]
                    axis = 0
                    for d in (1, 2):
                        if abs(n[d, l]) < abs(n[axis, l]):
                            axis = d
                    axis_e1[0], axis_e1[1], axis_e1[2] = 0.0, 0.0, 0.0
                    axis_e1[(axis + 1) % 3] = n[(axis + 2) % 3, l]
                    axis_e1[(axis + 2) % 3] = -n[(axis + 1) % 3, l]
                    length = np.sqrt(
                        axis_e1[0] * axis_e1[0] + axis_e1[1] * axis_e1[1] + axis_e1[2] * axis_e1[2]
                    )
                    for d in range(3):
                        e1[d, l] = axis_e1[d] / length
                    e2[0, l] = n[1, l] * e1[2, l] - n[2, l] * e1[1, l]
                    e2[1, l] = n[2, l] * e1[0, l] - n[0, l] * e1[2, l]
                    e2[2, l] = n[0, l] * e1[1, l] - n[1, l] * e1[0, l]
                    spread = 0.0
                    for j in range(neighbor_offsets[v], neighbor_offsets[v + 1]):
                        p = neighbors[j]
                        dx, dy, dz = x[p, 0] - x[v, 0], x[p, 1] - x[v, 1], x[p, 2] - x[v, 2]
                        height = n[0, l] * dx + n[1, l] * dy + n[2, l] * dz
                        spread += (dx * dx + dy * dy + dz * dz) - height * height
                    hbar[l] = np.sqrt(spread / (neighbor_offsets[v + 1] - neighbor_offsets[v]))
                    for d in range(3):
                        scaled[d, l] = e1[d, l] / hbar[l]
                        scaled[3 + d, l] = e2[d, l] / hbar[l]
                        scaled[6 + d, l] = n[d, l] / hbar[l]
                for r in range(k):
                    for s in range(k):
                        for l in range(nl):
                            gram[r, s, l] = 0.0
                    for l in range(nl):
                        rhs[r, l] = 0.0
                for l in range(nl):
                    sum_w[l] = 0.0
                    sum_wzz[l] = 0.0
                for j in range(most):
                    # features of point j (lane loops of few arrays each, so that they vectorise):
                    # x, y, a x², 2a xy, a y², the cubic's x³/6, x²y/2, xy²/2, y³/6, then z and r²
                    for l in range(nl):
                        px, py, pz = q[j, 0, l], q[j, 1, l], q[j, 2, l]
                        xj = scaled[0, l] * px + scaled[1, l] * py + scaled[2, l] * pz
                        yj = scaled[3, l] * px + scaled[4, l] * py + scaled[5, l] * pz
                        zj = scaled[6, l] * px + scaled[7, l] * py + scaled[8, l] * pz
                        xx, xy, yy = xj * xj, xj * yj, yj * yj
                        r2 = xx + yy
                        away = (
                            r2 if r2 > 1e-24 else 1.0
                        )  # a = ½(1 + z²) at the vertex itself (weight 0)
                        a = 0.5 + 0.5 * zj * zj / away
                        row[0, l] = xj
                        row[1, l] = yj
                        row[2, l] = a * xx
                        row[3, l] = 2.0 * a * xy
                        row[4, l] = a * yy
                        row[9, l] = zj
                        row[10, l] = r2
                    if cubic:
                        for l in range(nl):
                            xj, yj = row[0, l], row[1, l]
                            xx, yy = xj * xj, yj * yj
                            row[5, l] = xx * (xj / 6.0)
                            row[6, l] = xx * (yj / 2.0)
                            row[7, l] = yy * (xj / 2.0)
                            row[8, l] = yy * (yj / 6.0)
                    for l in range(nl):
                        weight = np.exp(-0.5 * row[10, l])
                        ws[l] = weight if row[10, l] > 1e-24 else 0.0
                    for r in range(k):
                        feature = row[offset + r]
                        for l in range(nl):
                            weighted[l] = feature[l] * ws[l]
                        for s in range(r, k):
                            into, by = gram[r, s], row[offset + s]
                            for l in range(nl):
                                into[l] += weighted[l] * by[l]
                        into, by = rhs[r], row[9]
                        for l in range(nl):
                            into[l] += weighted[l] * by[l]
                    for l in range(nl):
                        sum_w[l] += ws[l]
                        sum_wzz[l] += ws[l] * row[9, l] * row[9, l]
                for r in range(k):
                    for s in range(k):
                        into, by = lower[r, s], gram[min(r, s), max(r, s)]
                        for l in range(nl):
                            into[l] = by[l]
                # the pivot-dropping Cholesky of _solve, in place in ``lower`` (quotients and roots
                # computed in every lane, then kept or dropped: the same values as the branches)
                for j in range(k):
                    diagonal, here, kept = gram[j, j], lower[j, j], pivot[j]
                    for l in range(nl):
                        quotient = here[l] / diagonal[l]
                        kept[l] = quotient if diagonal[l] > 0 else 0.0
                    for l in range(nl):
                        square_root = np.sqrt(here[l])
                        root[l] = square_root if kept[l] > DROP_PIVOT else 0.0
                    for r in range(j, k):
                        into = lower[r, j]
                        for l in range(nl):
                            quotient = into[l] / root[l]
                            into[l] = quotient if kept[l] > DROP_PIVOT else 0.0
                    for r in range(j + 1, k):
                        for s in range(j + 1, r + 1):
                            into, left, right = lower[r, s], lower[r, j], lower[s, j]
                            for l in range(nl):
                                into[l] -= left[l] * right[l]
                for j in range(k):
                    for l in range(nl):
                        total[l] = rhs[j, l]
                    for r in range(j):
                        left, right = lower[j, r], c[r]
                        for l in range(nl):
                            total[l] -= left[l] * right[l]
                    diagonal, kept, into = lower[j, j], pivot[j], c[j]
                    for l in range(nl):
                        quotient = total[l] / diagonal[l]
                        into[l] = quotient if kept[l] > DROP_PIVOT else 0.0
                for j in range(k - 1, -1, -1):
                    for l in range(nl):
                        total[l] = c[j, l]
                    for r in range(j + 1, k):
                        left, right = lower[r, j], c[r]
                        for l in range(nl):
                            total[l] -= left[l] * right[l]
                    diagonal, kept, into = lower[j, j], pivot[j], c[j]
                    for l in range(nl):
                        quotient = total[l] / diagonal[l]
                        into[l] = quotient if kept[l] > DROP_PIVOT else 0.0
                # a lane's residual, determination and H are those of its last fit: after the last
                # sweep, or once its slope is below STOP (earlier sweeps' would be overwritten)
                finishing_any = False
                for l in range(nl):
                    stopped[l] = tilt and np.hypot(c[0, l], c[1, l]) < STOP
                    finishing[l] = active[l] and (sweep == sweeps - 1 or stopped[l])
                    finishing_any |= finishing[l]
                if (
                    finishing_any
                ):  # the determination of _solve, 1 / (G_jj |L⁻¹ e_j|²) over g, h, in every lane
                    for l in range(nl):
                        smallest[l] = np.inf
                    for j in range(h + 3):
                        diagonal, unit_j = lower[j, j], unit[j]
                        for l in range(nl):
                            unit_j[l] = 1.0 / diagonal[l]
                        for l in range(nl):
                            inverse[l] = unit_j[l] * unit_j[l]
                        for r in range(j + 1, k):
                            for l in range(nl):
                                total[l] = 0.0
                            for s in range(j, r):
                                left, right = lower[r, s], unit[s]
                                for l in range(nl):
                                    total[l] += left[l] * right[l]
                            diagonal, kept, unit_r = lower[r, r], pivot[r], unit[r]
                            for l in range(nl):
                                quotient = -total[l] / diagonal[l]
                                unit_r[l] = quotient if kept[l] > DROP_PIVOT else 0.0
                            for l in range(nl):
                                inverse[l] += unit_r[l] * unit_r[l]
                        diagonal, kept = gram[j, j], pivot[j]
                        for l in range(nl):
                            column = (
                                1.0 / (diagonal[l] * inverse[l]) if kept[l] > DROP_PIVOT else 0.0
                            )
                            smallest[l] = min(smallest[l], -np.inf if np.isnan(column) else column)
                going = False
                for l in range(nl):
                    if not active[l]:
                        continue
                    if finishing[l]:
                        i = low + order[first + l]
                        explained = 0.0
                        for r in range(k):
                            explained += c[r, l] * rhs[r, l]
                        unexplained = sum_wzz[l] - explained
                        out_residual[i] = np.sqrt(
                            (0.0 if unexplained < 0.0 else unexplained) / sum_w[l]
                        )
                        out_pivot[i] = smallest[l]
                        h11, h12, h22 = (
                            c[h, l] / hbar[l],
                            c[h + 1, l] / hbar[l],
                            c[h + 2, l] / hbar[l],
                        )
                        for r in range(3):
                            for s in range(3):
                                frame_h[r, s, l] = (
                                    h11 * e1[r, l] * e1[s, l]
                                    + h12 * (e1[r, l] * e2[s, l] + e2[r, l] * e1[s, l])
                                    + h22 * e2[r, l] * e2[s, l]
                                )
                    if tilt:
                        for d in range(3):
                            n[d, l] = n[d, l] - c[0, l] * e1[d, l] - c[1, l] * e2[d, l]
                        length = np.sqrt(n[0, l] * n[0, l] + n[1, l] * n[1, l] + n[2, l] * n[2, l])
                        for d in range(3):
                            n[d, l] /= length
                        if stopped[l]:
                            active[l] = False
                    going |= active[l]
                if not going:
                    break
            for l in range(nl):
                i = low + order[first + l]
                for d in range(3):
                    out_normals[i, d] = n[d, l]
                for r in range(3):  # S = ((−P) H) P
                    for s in range(3):
                        project[r, s] = (1.0 if r == s else 0.0) - n[r, l] * n[s, l]
                for r in range(3):
                    for s in range(3):
                        acc = 0.0
                        for t in range(3):
                            acc += -project[r, t] * frame_h[t, s, l]
                        product[r, s] = acc
                for r in range(3):
                    for s in range(3):
                        acc = 0.0
                        for t in range(3):
                            acc += product[r, t] * project[t, s]
                        out_shape[i, r, s] = acc
            first += nl


def _ring_kernel(
    x: FloatArray,
    neighbor_offsets: IntArray,
    neighbors: IntArray,
    face_count: IntArray,
    boundary: BoolArray,
    normals: FloatArray,
    vertices: IntArray,
    out_valid: BoolArray,
    out_steepness: FloatArray,
) -> None:
    """:meth:`_Ring.valid` and :meth:`_Ring.steepness` of ``normals[v]`` at ``vertices``, vertex by
    vertex (row i for ``vertices[i]``): turning angles ``atan2(N·(d_i × d_{i+1}), d_i·d_{i+1} −
    (N·d_i)(N·d_{i+1}))`` summed over the ring's consecutive pairs, and the largest ``|N·d|/|d|``.
    An interior vertex of valence ≤ 4 whose turns are all positive goes around exactly once (its n <
    5 turns of less than π each sum to 2π times a whole number), so there the angles are not
    computed."""
    for i in range(vertices.size):
        v = vertices[i]
        n0, n1, n2 = normals[v, 0], normals[v, 1], normals[v, 2]
        first, count = neighbor_offsets[v], neighbor_offsets[v + 1] - neighbor_offsets[v]
        turns = boundary[v] or face_count[v] > 4
        total = 0.0
        folded = False
        for step in range(face_count[v]):
            a, b = neighbors[first + step], neighbors[first + (step + 1) % count]
            ax, ay, az = x[a, 0] - x[v, 0], x[a, 1] - x[v, 1], x[a, 2] - x[v, 2]
            bx, by, bz = x[b, 0] - x[v, 0], x[b, 1] - x[v, 1], x[b, 2] - x[v, 2]
            sine = n0 * (ay * bz - az * by) + n1 * (az * bx - ax * bz) + n2 * (ax * by - ay * bx)
            folded |= not sine > 0
            if turns:
                cosine = (ax * bx + ay * by + az * bz) - (ax * n0 + ay * n1 + az * n2) * (
                    bx * n0 + by * n1 + bz * n2
                )
                total += np.arctan2(sine, cosine)
        once = not turns or (
            total < 2.0 * np.pi if boundary[v] else abs(total - 2.0 * np.pi) < np.pi
        )
        out_valid[i] = once and not folded
        steepest = 0.0
        for j in range(first, first + count):
            p = neighbors[j]
            dx, dy, dz = x[p, 0] - x[v, 0], x[p, 1] - x[v, 1], x[p, 2] - x[v, 2]
            sine = abs(dx * n0 + dy * n1 + dz * n2) / np.sqrt(dx * dx + dy * dy + dz * dz)
            if not sine <= steepest:
                steepest = sine
        out_steepness[i] = steepest


def _ring_checks(
    mesh: QuadMesh, normals: FloatArray, vertices: IntArray
) -> tuple[BoolArray, FloatArray]:
    """:func:`_ring_kernel`: validity and steepness of ``normals`` at ``vertices``."""
    topo = mesh.topology
    valid = np.empty(vertices.size, dtype=bool)
    steepness = np.empty(vertices.size)
    jit_kernel(_ring_kernel)(
        mesh.vertices,
        topo.neighbor_offsets,
        topo.neighbors,
        topo.face_count,
        topo.is_boundary_vertex,
        normals,
        vertices,
        valid,
        steepness,
    )
    return valid, steepness


def _fit_all(
    mesh: QuadMesh,
    ring: _Ring,
    hood: _Hood,
    vertices: IntArray,
    n: FloatArray,
    cubic: bool,
    tilt: bool,
) -> _Fit:
    """:func:`_circle_fit` of ``vertices`` with neighbourhoods ``hood`` and start normals ``n`` (V,
    3), row i for ``vertices[i]``, block by block in NumPy (the reference of
    :func:`_fit_kernel`)."""
    out = _Fit.empty(vertices.size)
    x = mesh.vertices
    order = np.argsort(hood.sizes[vertices], kind="stable")
    for rows in (order[s : s + BLOCK] for s in range(0, order.size, BLOCK)):
        block = vertices[rows]
        where, mask = _padded(block, hood.offsets)
        q = (x[hood.points[where]] - x[block, None, :]).transpose(0, 2, 1)
        edge_where, edge_mask = _padded(block, ring.offsets)
        fit = _circle_fit(
            q, mask, ring.d[edge_where].transpose(0, 2, 1), edge_mask, n[block], cubic, tilt
        )
        out.normals[rows], out.shape_operator[rows], out.residual[rows], out.pivot[rows] = (
            fit.normals,
            fit.shape_operator,
            fit.residual,
            fit.pivot,
        )
    return out


def _face_ring_rows(mesh: QuadMesh) -> tuple[IntArray, IntArray]:
    """The rows of ``I Iᵀ`` as CSR (offsets, int32 points), by :func:`_rows_kernel`."""
    topo = mesh.topology
    offsets = np.zeros(mesh.n_vertices + 1, dtype=np.int64)
    kernel = jit_kernel(_rows_kernel)
    in_chunks(
        lambda lo, hi: kernel(
            topo.faces,
            topo.ring_offsets,
            topo.ring_halfedges,
            offsets,
            np.empty(0, dtype=np.int32),
            False,
            lo,
            hi,
        ),
        mesh.n_vertices,
    )
    np.cumsum(offsets, out=offsets)
    points = np.empty(int(offsets[-1]), dtype=np.int32)
    in_chunks(
        lambda lo, hi: kernel(
            topo.faces, topo.ring_offsets, topo.ring_halfedges, offsets, points, True, lo, hi
        ),
        mesh.n_vertices,
    )
    return offsets, points


def _fit_compiled(
    mesh: QuadMesh, rows: tuple[IntArray, IntArray], vertices: IntArray, n: FloatArray, tilt: bool
) -> _Fit:
    """:func:`_fit_kernel` of ``vertices`` (row i for ``vertices[i]``) with start normals ``n`` (V,
    3), in ranges of rows side by side (:func:`~g1patch.kernels.in_chunks`)."""
    topo = mesh.topology
    out = _Fit.empty(vertices.size)
    kernel = jit_kernel(_fit_kernel)
    in_chunks(
        lambda lo, hi: kernel(
            mesh.vertices,
            rows[0],
            rows[1],
            topo.neighbor_offsets,
            topo.neighbors,
            vertices[lo:hi],
            n,
            tilt,
            LANES,
            out.normals[lo:hi],
            out.shape_operator[lo:hi],
            out.residual[lo:hi],
            out.pivot[lo:hi],
        ),
        vertices.size,
    )
    return out


def vertex_frames(mesh: QuadMesh, *, compiled: bool = True) -> VertexFrames:
    """Unit normals and shape operators at the vertices of ``mesh``: repaired fan normal,
    circle-aware fit where trusted, else the fan normal with the fixed-normal circle fit of S
    (module doc).

    ``compiled`` runs the fits and ring checks in numba kernels (:func:`_fit_kernel`,
    :func:`_ring_kernel`); ``False`` runs the NumPy reference (the same to rounding,
    tests/test_frames.py).
    """
    nv = mesh.n_vertices
    everything = np.arange(nv)
    ring = None if compiled else _Ring.of(mesh)
    start = fan_normals(mesh, compiled=compiled)
    repaired = np.zeros(nv, dtype=bool)
    bad = np.flatnonzero(
        ~(_ring_checks(mesh, start, everything)[0] if compiled else ring.valid(start))
    )
    if bad.size:
        ring = ring or _Ring.of(mesh)
        start, done = ring.repair(start, bad)
        repaired[bad[done]] = True

    with np.errstate(invalid="ignore", divide="ignore"):
        if compiled:
            rows = _face_ring_rows(mesh)
            fit = _fit_compiled(mesh, rows, everything, start, True)
            normals, shape_operator, residual, pivot = (
                fit.normals,
                fit.shape_operator,
                fit.residual,
                fit.pivot,
            )
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
                    fit.normals,
                    fit.shape_operator,
                    fit.residual,
                    fit.pivot,
                )
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
            held = (
                _fit_compiled(mesh, rows, rest, start, False)
                if compiled
                else _fit_all(mesh, ring, one, rest, start, False, False)
            )
            shape_operator[rest] = np.nan_to_num(held.shape_operator)
    if compiled:
        jit_kernel(_symmetric_kernel)(shape_operator)
    else:
        shape_operator = 0.5 * (shape_operator + shape_operator.transpose(0, 2, 1))
    return VertexFrames(normals, shape_operator, fitted, repaired)


def _symmetric_kernel(s: FloatArray) -> None:
    """``S ← ½ (S + Sᵀ)`` in place, (V, 3, 3)."""
    for i in range(s.shape[0]):
        for r in range(3):
            for c in range(r, 3):
                s[i, r, c] = s[i, c, r] = 0.5 * (s[i, r, c] + s[i, c, r])
