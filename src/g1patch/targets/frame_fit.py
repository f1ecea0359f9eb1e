"""The circle-aware fit of vertex frames in NumPy (:mod:`g1patch.targets.frames` tells the recipe):
the ring checks and repair of a start normal, the face rings, and the fit itself in padded blocks.

The fit is the reference of the compiled one (:mod:`g1patch.targets.frame_kernels`, which shares
the constants below); ``vertex_frames(mesh, compiled=False)`` runs it, and the ring repair always
runs here.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray

from ..mesh import QuadMesh
from .local import cross

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]
BoolArray = NDArray[np.bool_]

DROP_PIVOT = 1e-10  #: relative pivot below which a column is dropped from the fit
ITERATIONS = 3  #: most refits of the normal
STOP = 1e-14  #: a vertex's refits stop once its slope |g| is below this
CUBIC_POINTS = 12  #: fewest 2-ring points for the cubic term
#: a vertex whose face 1-ring has more points than this is a *hub* (the centre of a split n-gon, a
#: pole): its neighbours' 2-rings take the hub but not its whole ring, which keeps the fits linear
#: in the valence (a 100,000-gon's rim would otherwise see the whole centre ring from every vertex)
HUB_POINTS = 64
BLOCK = 2048  #: vertices per padded block (NumPy), per gathered block (kernel)
GILBERT_STEPS = 64
#: the fit's frame follows the ring's principal axis where the projected ring edges are this
#: anisotropic, ``|λ1 − λ2|/(λ1 + λ2)`` of their second moments (:func:`_principal_frame`)
PRINCIPAL_ANISOTROPY = 0.5


def _unit(v: FloatArray) -> FloatArray:
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def _frame(n: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Unit e1, e2 with (e1, e2, n) right-handed: e1 ⊥ n and the coordinate axis least aligned with
    n."""
    axis = np.zeros_like(n)
    axis[np.arange(n.shape[0]), np.argmin(np.abs(n), axis=1)] = 1.0
    e1 = _unit(cross(n, axis))
    return e1, cross(n, e1)


def _principal_frame(
    n: FloatArray, edges: FloatArray, edge_mask: BoolArray
) -> tuple[FloatArray, FloatArray]:
    """:func:`_frame` turned about n onto the principal axis of the ring edges ``edges`` (b, 3, k)
    where they are anisotropic: with ``m11, m12, m22`` the second moments of their coordinates in
    :func:`_frame`'s (f1, f2), ``e1 = cos ψ f1 + sin ψ f2``, ``ψ = ½ atan2(2 m12, m11 − m22)``,
    where ``√((m11 − m22)² + 4 m12²) ≥`` :data:`PRINCIPAL_ANISOTROPY` ``(m11 + m22)``.

    The fit itself does not depend on the frame, but the determination of its single columns
    does: round a pole, whose rings are thin wedges all alike, the axis-bound frame accepted the
    fit in some wedges and refused it in the others, and the fan normal that replaced it tilted
    the surface 34° there. The principal frame is the same for every wedge.
    """
    f1, f2 = _frame(n)
    # summed edge by edge, in the kernel's order (its frames are the same to the last bit)
    u = f1[:, 0, None] * edges[:, 0] + f1[:, 1, None] * edges[:, 1] + f1[:, 2, None] * edges[:, 2]
    v = f2[:, 0, None] * edges[:, 0] + f2[:, 1, None] * edges[:, 1] + f2[:, 2, None] * edges[:, 2]
    m11, m12, m22 = (np.zeros(n.shape[0]) for _ in range(3))
    for j in range(edges.shape[2]):
        m11 += np.where(edge_mask[:, j], u[:, j] * u[:, j], 0.0)
        m12 += np.where(edge_mask[:, j], u[:, j] * v[:, j], 0.0)
        m22 += np.where(edge_mask[:, j], v[:, j] * v[:, j], 0.0)
    spread = np.hypot(m11 - m22, 2.0 * m12)
    turn = spread >= PRINCIPAL_ANISOTROPY * (m11 + m22)
    psi = np.where(turn, 0.5 * np.arctan2(2.0 * m12, m11 - m22), 0.0)[:, None]
    e1 = np.cos(psi) * f1 + np.sin(psi) * f2
    e2 = np.cos(psi) * f2 - np.sin(psi) * f1
    return e1, e2


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


def _padded(
    vertices: IntArray, offsets: NDArray[np.integer]
) -> tuple[NDArray[np.integer], BoolArray]:
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
        # the frame decides only the determination of a tilted fit (a held fit's S does not
        # depend on it): the held fits keep the axis-bound frame
        e1, e2 = _principal_frame(n, edges, edge_mask) if tilt else _frame(n)
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
