"""The numba kernels of the vertex frames (:mod:`g1patch.targets.frames`), each the same formulas
in the same order as its NumPy reference in :mod:`g1patch.targets.frame_fit`: the rows of the face
rings, the circle-aware fit in lanes of vertices side by side, the ring checks, and the
symmetrisation of S. Compiled by :func:`~g1patch.kernels.jit_kernel` on first use.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from .frame_fit import (
    BLOCK,
    CUBIC_POINTS,
    DROP_PIVOT,
    HUB_POINTS,
    ITERATIONS,
    PRINCIPAL_ANISOTROPY,
    STOP,
)

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]
BoolArray = NDArray[np.bool_]

LANES = 32  #: vertices the kernel fits side by side
#: faces around a vertex up to which :func:`_rows_kernel` sorts them by insertion and finds repeated
#: points by scanning the row (a valence-4 row holds 9 points); beyond it, in time linear in the
#: ring
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
            for lane in range(nl):
                b = order[first + lane]
                most = max(most, hood_size[b])
            if relative.size < 3 * most * nl:
                relative = np.zeros(max(3 * most * nl, 2 * relative.size))
            q = relative[: 3 * most * nl].reshape((most, 3, nl))
            for lane in range(nl):
                b = order[first + lane]
                v = vertices[low + b]
                m, begin = hood_size[b], hood_begin[b]
                for j in range(most):
                    for d in range(3):
                        q[j, d, lane] = x[hood[begin + j], d] - x[v, d] if j < m else 0.0
                for d in range(3):
                    n[d, lane] = start[v, d]
                active[lane] = True
            for sweep in range(sweeps):
                # per lane: the frame (_frame: e1 = unit(n × axis), axis the first coordinate axis
                # least aligned with n), h̄ from the ring edges, the scaled axes
                for lane in range(nl):
                    v = vertices[low + order[first + lane]]
                    axis = 0
                    for d in (1, 2):
                        if abs(n[d, lane]) < abs(n[axis, lane]):
                            axis = d
                    axis_e1[0], axis_e1[1], axis_e1[2] = 0.0, 0.0, 0.0
                    axis_e1[(axis + 1) % 3] = n[(axis + 2) % 3, lane]
                    axis_e1[(axis + 2) % 3] = -n[(axis + 1) % 3, lane]
                    length = np.sqrt(
                        axis_e1[0] * axis_e1[0] + axis_e1[1] * axis_e1[1] + axis_e1[2] * axis_e1[2]
                    )
                    for d in range(3):
                        e1[d, lane] = axis_e1[d] / length
                    e2[0, lane] = n[1, lane] * e1[2, lane] - n[2, lane] * e1[1, lane]
                    e2[1, lane] = n[2, lane] * e1[0, lane] - n[0, lane] * e1[2, lane]
                    e2[2, lane] = n[0, lane] * e1[1, lane] - n[1, lane] * e1[0, lane]
                    spread = 0.0
                    m11, m12, m22 = 0.0, 0.0, 0.0
                    for j in range(neighbor_offsets[v], neighbor_offsets[v + 1]):
                        p = neighbors[j]
                        dx, dy, dz = x[p, 0] - x[v, 0], x[p, 1] - x[v, 1], x[p, 2] - x[v, 2]
                        height = n[0, lane] * dx + n[1, lane] * dy + n[2, lane] * dz
                        spread += (dx * dx + dy * dy + dz * dz) - height * height
                        du = e1[0, lane] * dx + e1[1, lane] * dy + e1[2, lane] * dz
                        dv = e2[0, lane] * dx + e2[1, lane] * dy + e2[2, lane] * dz
                        m11 += du * du
                        m12 += du * dv
                        m22 += dv * dv
                    # _principal_frame (tilted fits only): onto the ring's principal axis where
                    # anisotropic
                    anisotropic = np.hypot(m11 - m22, 2.0 * m12) >= PRINCIPAL_ANISOTROPY * (
                        m11 + m22
                    )
                    if tilt and anisotropic:
                        psi = 0.5 * np.arctan2(2.0 * m12, m11 - m22)
                        cos_psi, sin_psi = np.cos(psi), np.sin(psi)
                        for d in range(3):
                            f1, f2 = e1[d, lane], e2[d, lane]
                            e1[d, lane] = cos_psi * f1 + sin_psi * f2
                            e2[d, lane] = cos_psi * f2 - sin_psi * f1
                    hbar[lane] = np.sqrt(spread / (neighbor_offsets[v + 1] - neighbor_offsets[v]))
                    for d in range(3):
                        scaled[d, lane] = e1[d, lane] / hbar[lane]
                        scaled[3 + d, lane] = e2[d, lane] / hbar[lane]
                        scaled[6 + d, lane] = n[d, lane] / hbar[lane]
                for r in range(k):
                    for s in range(k):
                        for lane in range(nl):
                            gram[r, s, lane] = 0.0
                    for lane in range(nl):
                        rhs[r, lane] = 0.0
                for lane in range(nl):
                    sum_w[lane] = 0.0
                    sum_wzz[lane] = 0.0
                for j in range(most):
                    # features of point j (lane loops of few arrays each, so that they vectorise):
                    # x, y, a x², 2a xy, a y², the cubic's x³/6, x²y/2, xy²/2, y³/6, then z and r²
                    for lane in range(nl):
                        px, py, pz = q[j, 0, lane], q[j, 1, lane], q[j, 2, lane]
                        xj = scaled[0, lane] * px + scaled[1, lane] * py + scaled[2, lane] * pz
                        yj = scaled[3, lane] * px + scaled[4, lane] * py + scaled[5, lane] * pz
                        zj = scaled[6, lane] * px + scaled[7, lane] * py + scaled[8, lane] * pz
                        xx, xy, yy = xj * xj, xj * yj, yj * yj
                        r2 = xx + yy
                        away = (
                            r2 if r2 > 1e-24 else 1.0
                        )  # a = ½(1 + z²) at the vertex itself (weight 0)
                        a = 0.5 + 0.5 * zj * zj / away
                        row[0, lane] = xj
                        row[1, lane] = yj
                        row[2, lane] = a * xx
                        row[3, lane] = 2.0 * a * xy
                        row[4, lane] = a * yy
                        row[9, lane] = zj
                        row[10, lane] = r2
                    if cubic:
                        for lane in range(nl):
                            xj, yj = row[0, lane], row[1, lane]
                            xx, yy = xj * xj, yj * yj
                            row[5, lane] = xx * (xj / 6.0)
                            row[6, lane] = xx * (yj / 2.0)
                            row[7, lane] = yy * (xj / 2.0)
                            row[8, lane] = yy * (yj / 6.0)
                    for lane in range(nl):
                        weight = np.exp(-0.5 * row[10, lane])
                        ws[lane] = weight if row[10, lane] > 1e-24 else 0.0
                    for r in range(k):
                        feature = row[offset + r]
                        for lane in range(nl):
                            weighted[lane] = feature[lane] * ws[lane]
                        for s in range(r, k):
                            into, by = gram[r, s], row[offset + s]
                            for lane in range(nl):
                                into[lane] += weighted[lane] * by[lane]
                        into, by = rhs[r], row[9]
                        for lane in range(nl):
                            into[lane] += weighted[lane] * by[lane]
                    for lane in range(nl):
                        sum_w[lane] += ws[lane]
                        sum_wzz[lane] += ws[lane] * row[9, lane] * row[9, lane]
                for r in range(k):
                    for s in range(k):
                        into, by = lower[r, s], gram[min(r, s), max(r, s)]
                        for lane in range(nl):
                            into[lane] = by[lane]
                # the pivot-dropping Cholesky of _solve, in place in ``lower`` (quotients and roots
                # computed in every lane, then kept or dropped: the same values as the branches)
                for j in range(k):
                    diagonal, here, kept = gram[j, j], lower[j, j], pivot[j]
                    for lane in range(nl):
                        quotient = here[lane] / diagonal[lane]
                        kept[lane] = quotient if diagonal[lane] > 0 else 0.0
                    for lane in range(nl):
                        square_root = np.sqrt(here[lane])
                        root[lane] = square_root if kept[lane] > DROP_PIVOT else 0.0
                    for r in range(j, k):
                        into = lower[r, j]
                        for lane in range(nl):
                            quotient = into[lane] / root[lane]
                            into[lane] = quotient if kept[lane] > DROP_PIVOT else 0.0
                    for r in range(j + 1, k):
                        for s in range(j + 1, r + 1):
                            into, left, right = lower[r, s], lower[r, j], lower[s, j]
                            for lane in range(nl):
                                into[lane] -= left[lane] * right[lane]
                # L y = rhs forwards, then Lᵀ c = y backwards (y kept in c)
                for step in range(2 * k):
                    backward = step >= k
                    j = 2 * k - 1 - step if backward else step
                    for lane in range(nl):
                        total[lane] = c[j, lane] if backward else rhs[j, lane]
                    for r in range(j + 1, k) if backward else range(j):
                        left, right = (lower[r, j] if backward else lower[j, r]), c[r]
                        for lane in range(nl):
                            total[lane] -= left[lane] * right[lane]
                    diagonal, kept, into = lower[j, j], pivot[j], c[j]
                    for lane in range(nl):
                        quotient = total[lane] / diagonal[lane]
                        into[lane] = quotient if kept[lane] > DROP_PIVOT else 0.0
                # a lane's residual, determination and H are those of its last fit: after the last
                # sweep, or once its slope is below STOP (earlier sweeps' would be overwritten)
                finishing_any = False
                for lane in range(nl):
                    stopped[lane] = tilt and np.hypot(c[0, lane], c[1, lane]) < STOP
                    finishing[lane] = active[lane] and (sweep == sweeps - 1 or stopped[lane])
                    finishing_any |= finishing[lane]
                if (
                    finishing_any
                ):  # the determination of _solve, 1 / (G_jj |L⁻¹ e_j|²) over g, h, in every lane
                    for lane in range(nl):
                        smallest[lane] = np.inf
                    for j in range(h + 3):
                        diagonal, unit_j = lower[j, j], unit[j]
                        for lane in range(nl):
                            unit_j[lane] = 1.0 / diagonal[lane]
                        for lane in range(nl):
                            inverse[lane] = unit_j[lane] * unit_j[lane]
                        for r in range(j + 1, k):
                            for lane in range(nl):
                                total[lane] = 0.0
                            for s in range(j, r):
                                left, right = lower[r, s], unit[s]
                                for lane in range(nl):
                                    total[lane] += left[lane] * right[lane]
                            diagonal, kept, unit_r = lower[r, r], pivot[r], unit[r]
                            for lane in range(nl):
                                quotient = -total[lane] / diagonal[lane]
                                unit_r[lane] = quotient if kept[lane] > DROP_PIVOT else 0.0
                            for lane in range(nl):
                                inverse[lane] += unit_r[lane] * unit_r[lane]
                        diagonal, kept = gram[j, j], pivot[j]
                        for lane in range(nl):
                            column = (
                                1.0 / (diagonal[lane] * inverse[lane])
                                if kept[lane] > DROP_PIVOT
                                else 0.0
                            )
                            smallest[lane] = min(
                                smallest[lane], -np.inf if np.isnan(column) else column
                            )
                going = False
                for lane in range(nl):
                    if not active[lane]:
                        continue
                    if finishing[lane]:
                        i = low + order[first + lane]
                        explained = 0.0
                        for r in range(k):
                            explained += c[r, lane] * rhs[r, lane]
                        unexplained = sum_wzz[lane] - explained
                        out_residual[i] = np.sqrt(
                            (0.0 if unexplained < 0.0 else unexplained) / sum_w[lane]
                        )
                        out_pivot[i] = smallest[lane]
                        h11, h12, h22 = (
                            c[h, lane] / hbar[lane],
                            c[h + 1, lane] / hbar[lane],
                            c[h + 2, lane] / hbar[lane],
                        )
                        for r in range(3):
                            for s in range(3):
                                frame_h[r, s, lane] = (
                                    h11 * e1[r, lane] * e1[s, lane]
                                    + h12 * (e1[r, lane] * e2[s, lane] + e2[r, lane] * e1[s, lane])
                                    + h22 * e2[r, lane] * e2[s, lane]
                                )
                    if tilt:
                        for d in range(3):
                            n[d, lane] = (
                                n[d, lane] - c[0, lane] * e1[d, lane] - c[1, lane] * e2[d, lane]
                            )
                        length = np.sqrt(
                            n[0, lane] * n[0, lane]
                            + n[1, lane] * n[1, lane]
                            + n[2, lane] * n[2, lane]
                        )
                        for d in range(3):
                            n[d, lane] /= length
                        if stopped[lane]:
                            active[lane] = False
                    going |= active[lane]
                if not going:
                    break
            for lane in range(nl):
                i = low + order[first + lane]
                for d in range(3):
                    out_normals[i, d] = n[d, lane]
                for r in range(3):  # S = ((−P) H) P
                    for s in range(3):
                        project[r, s] = (1.0 if r == s else 0.0) - n[r, lane] * n[s, lane]
                for r in range(3):
                    for s in range(3):
                        acc = 0.0
                        for t in range(3):
                            acc += -project[r, t] * frame_h[t, s, lane]
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


def _symmetric_kernel(s: FloatArray) -> None:
    """``S ← ½ (S + Sᵀ)`` in place, (V, 3, 3)."""
    for i in range(s.shape[0]):
        for r in range(3):
            for c in range(r, 3):
                s[i, r, c] = s[i, c, r] = 0.5 * (s[i, r, c] + s[i, c, r])
