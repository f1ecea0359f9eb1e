"""Degenerate normals, folds and fairness on every patch's grid in numba kernels (the compiled path
of :class:`.grid._GridMeasures`): the grid kernel, the turn kernel that recomputes candidate turns
as the reference sums them, and their tables.

The grid measures use the tensor structure: a Gregory patch is the bicubic Bézier patch of its net
with Fp_k inside plus ``Σ_k S_k (Fn_k − Fp_k)`` (``S_k``: the weight of Fn_k in
:func:`~g1patch.gregory.gregory_weights`, as ``w_α + w_β = 1``), so a grid row of tangents costs
one u contraction of the net, then 8 products and 4 blends per point and derivative, against 20
weights.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..basis import basis_values
from ..gregory import BEZIER_INDEX, INTERIOR_INDEX, gregory_weights
from .jit import _fma, _pair_angle
from .turns import _SHIFT

prange = range  # numba.prange once a kernel is compiled (:func:`.jit._bind`)

_TINY = float(np.finfo(np.float64).tiny)

#: patches the grid kernel measures side by side, its vector lanes (a run-time argument: a
#: constant trip count is unrolled before the loop vectoriser sees it, and left scalar); 64 rather
#: than 16: each inner loop runs 8 AVX-512 steps instead of 2 for the same loop overhead (the
#: scratch, ~0.7 MB, stays in a core's L2)
_LANES = 64


def _grid_tables(form: str, grid: NDArray[np.float64]) -> tuple[NDArray[Any], ...]:
    """The grid kernel's tables: ``index (16,)`` (the point of net entry ``4 i + j``), the blend
    pairs ``fn, fp (B,)``, the bases ``bu, dbu (G, 4)`` and ``bv, dbv (4, G)``, the blend weights
    ``su, sv (B, G, G)`` (B = 4 for Gregory patches, 0 for a PatchSet)."""
    basis = "bezier" if form == "gregory" else form
    bu, dbu = basis_values(basis, grid), basis_values(basis, grid, 1)  # type: ignore[arg-type]
    tables_v = np.ascontiguousarray(bu.T), np.ascontiguousarray(dbu.T)
    if form != "gregory":
        empty = np.zeros((0, len(grid), len(grid)))
        none = np.zeros(0, dtype=np.int64)
        return np.arange(16), none, none, bu, dbu, *tables_v, empty, empty
    index = np.empty(16, dtype=np.int64)
    index[4 * BEZIER_INDEX[:, 0] + BEZIER_INDEX[:, 1]] = np.arange(12)
    index[4 * INTERIOR_INDEX[:, 0] + INTERIOR_INDEX[:, 1]] = 13 + 2 * np.arange(4)  # Fp_k
    su, sv = (
        np.ascontiguousarray(
            np.moveaxis(table.reshape(len(grid), len(grid), 20)[..., 12::2], -1, 0)
        )
        for table in _gregory_grid_weights(grid)
    )
    return index, 12 + 2 * np.arange(4), 13 + 2 * np.arange(4), bu, dbu, *tables_v, su, sv


def _gregory_grid_weights(grid: NDArray[np.float64]) -> NDArray[np.float64]:
    """The point weights of p_u and p_v on the grid, ``(2, G², 20)``, as
    :meth:`_GridMeasures._tangents` forms them."""
    u, v = grid[:, None], grid[None, :]
    return np.stack([gregory_weights(u, v, du, dv).reshape(-1, 20) for du, dv in ((1, 0), (0, 1))])


def _turn_kernel(
    points: NDArray[np.float64],
    exact: NDArray[np.float64],
    level: float,
    patches: NDArray[np.int64],
    axes: NDArray[np.int64],
    chunks: int,
    chord2: NDArray[np.float64],
    angle: NDArray[np.float64],
) -> None:
    """For Gregory patches ``patches[c]`` and ``axes[c]`` (0: along u): the first largest squared
    chord between neighbouring unit normals along that axis and the angle of its pair, from the
    tangents summed as the reference's matrix product sums them (``exact (2, 20, G²)``: the point
    weights of p_u and p_v, a sequential fused multiply-add over the points, each sample's sum in
    its own lane: the loops over the samples vectorise), so the reference's values (chord² −1
    without pairs)."""
    samples, candidates = exact.shape[2], patches.size
    g = int(round(np.sqrt(samples)))
    for chunk in prange(chunks):
        tangent, normal = np.empty((2, 3, samples)), np.empty((3, samples))
        unit, length = np.empty((3, samples)), np.empty(samples)
        usable = np.empty(samples, dtype=np.bool_)
        pair = np.empty((2, 3))
        for c in range(chunk * candidates // chunks, (chunk + 1) * candidates // chunks):
            n, axis = patches[c], axes[c]
            for q in range(2):
                for d in range(3):
                    acc = tangent[q, d]
                    for s in range(samples):
                        acc[s] = 0.0
                    for m in range(20):
                        p, w = points[n, m, d], exact[q, m]
                        for s in range(samples):
                            acc[s] = _fma(p, w[s], acc[s])
            a, b = tangent[0], tangent[1]
            for s in range(samples):
                normal[0, s] = a[1, s] * b[2, s] - a[2, s] * b[1, s]
            for s in range(samples):
                normal[1, s] = a[2, s] * b[0, s] - a[0, s] * b[2, s]
            for s in range(samples):
                normal[2, s] = a[0, s] * b[1, s] - a[1, s] * b[0, s]
            for s in range(samples):
                length[s] = np.sqrt(
                    (normal[0, s] * normal[0, s] + normal[1, s] * normal[1, s])
                    + normal[2, s] * normal[2, s]
                )
            for s in range(samples):
                usable[s] = length[s] > level
            for s in range(samples):
                length[s] = 1.0 / max(length[s], _TINY)
            for d in range(3):
                for s in range(samples):
                    unit[d, s] = normal[d, s] * length[s]
            top, top_at, step = -1.0, -1, g if axis == 0 else 1
            for i in range(g - 1 + axis):
                for j in range(g - axis):
                    s = i * g + j
                    if usable[s] and usable[s + step]:
                        c0, c1, c2 = (
                            unit[0, s + step] - unit[0, s],
                            unit[1, s + step] - unit[1, s],
                            unit[2, s + step] - unit[2, s],
                        )
                        value = (c0 * c0 + c2 * c2) + c1 * c1
                        if value > top:
                            top, top_at = value, s
            chord2[c] = top
            angle[c] = 0.0
            if top_at >= 0:
                for d in range(3):
                    pair[0, d], pair[1, d] = normal[d, top_at], normal[d, top_at + step]
                angle[c] = _pair_angle(pair[0], pair[1], True)


def _grid_kernel(
    points: NDArray[np.float64],
    index: NDArray[np.int64],
    fn: NDArray[np.int64],
    fp: NDArray[np.int64],
    bu: NDArray[np.float64],
    dbu: NDArray[np.float64],
    bv: NDArray[np.float64],
    dbv: NDArray[np.float64],
    su: NDArray[np.float64],
    sv: NDArray[np.float64],
    weights: NDArray[np.float64],
    level: float,
    fairness: bool,
    code_min: int,
    lanes: int,
    chunks: int,
    location: NDArray[np.int64],
    degenerate: NDArray[np.int64],
    zero_area: NDArray[np.bool_],
    histogram: NDArray[np.int64],
    best: NDArray[np.float64],
    energy: NDArray[np.float64],
) -> None:
    """:meth:`_GridMeasures.add` for ``lanes`` patches at a time (the lanes, last axis of
    every scratch array, so the arithmetic vectorises across patches), row by row of their grids:
    tangents (fused multiply-adds: one u contraction of the net per row, 4 products and 4 blends
    per point; rows a − 1 and a kept), normals (the whole grid), the corner-cell and 90° tests
    (``location``: the first offending sample ``G i + j``, −1 if none), degenerate normals
    (``zero_area``: a patch's every sample degenerate, ``|p_u × p_v| ≤ level``) and, if
    ``fairness``, the histogram of the turns (a row per chunk; a run of one bin along a patch's row
    is counted in a register and added once), the thin-plate energy, and per axis (u, v) the first
    largest squared chord with the angle of its pair (``best (N, 4)``: chord², angle, chord², angle;
    chord² −1 without pairs; kept per grid column row by row, then the columns' largest, the lowest
    ``G i + j`` among equals: the first in row-major order). Inner loops index one-dimensional views
    taken before the loop by the loop variable only: LLVM vectorises such loops (computed indices
    whose sign it cannot prove left the previous kernel scalar: 2× slower), also where they store
    to several arrays, as the normals' pass does (normal, unit normal and usable in one pass: 8–14 %
    less time than a pass per array). Outputs are bitwise those of the sample-major formulation
    (same operations in the same order per value)."""
    patches, g, blends, bins = points.shape[0], bu.shape[0], fn.size, histogram.shape[1]
    last, gl, run = g - 1, g * lanes, (g - 1) * lanes
    groups = (patches + lanes - 1) // lanes
    for chunk in prange(chunks):
        net, blend = np.zeros((3, 16, lanes)), np.zeros((3, 4, lanes))
        row_u, row_v = np.empty((4, lanes)), np.empty((4, lanes))
        tu, tv = (
            np.empty((2, 3, gl)),
            np.empty((2, 3, gl)),
        )  # p_u, p_v of rows a − 1, a (by parity), [row, xyz, g b + lane]
        tu4, tv4 = tu.reshape((2, 3, g, lanes)), tv.reshape((2, 3, g, lanes))
        tu_ahead, tv_ahead = tu[:, :, lanes:], tv[:, :, lanes:]  # the sample at b + 1
        normal, usable, offending = (
            np.empty((3, g, gl)),
            np.empty((g, gl), dtype=np.bool_),
            np.empty((g, gl), dtype=np.bool_),
        )
        unit = np.empty((2, 3, gl))
        unit_ahead, usable_ahead = unit[:, :, lanes:], usable[:, lanes:]
        chord, together = np.empty(gl), np.empty(gl, dtype=np.bool_)
        chord2, together2 = chord.reshape((g, lanes)), together.reshape((g, lanes))
        narrow, code = np.empty(gl, dtype=np.float32), np.empty(gl, dtype=np.int64)
        code2, bits = code.reshape((g, lanes)), narrow.view(np.int32)
        column_top, column_row = np.empty((2, gl)), np.empty((2, gl), dtype=np.int64)
        top, top_at = np.empty((2, lanes)), np.empty((2, lanes), dtype=np.int64)
        along_u, along_v = np.empty((2, gl)), np.empty((2, g, lanes))
        pair = np.empty((2, 3))
        folded = np.empty(gl, dtype=np.bool_)
        for group in range(chunk * groups // chunks, (chunk + 1) * groups // chunks):
            first = group * lanes
            count = min(lanes, patches - first)
            for lane in range(count):
                for d in range(3):
                    for m in range(16):
                        net[d, m, lane] = points[first + lane, index[m], d]
                    for k in range(blends):
                        blend[d, k, lane] = (
                            points[first + lane, fn[k], d] - points[first + lane, fp[k], d]
                        )
            column_top[:] = -1.0
            column_row[:] = -1
            along_u[:] = 0.0
            lost = 0
            for a in range(g):
                r, p = a & 1, 1 - (a & 1)
                for d in range(
                    3
                ):  # tangents: the u contraction of the net, then 4 products and 4 blends a point
                    w0, w1, w2, w3 = dbu[a, 0], dbu[a, 1], dbu[a, 2], dbu[a, 3]
                    x0, x1, x2, x3 = bu[a, 0], bu[a, 1], bu[a, 2], bu[a, 3]
                    for j in range(4):
                        for lane in range(lanes):
                            row_u[j, lane] = _fma(
                                w3,
                                net[d, 12 + j, lane],
                                _fma(
                                    w2,
                                    net[d, 8 + j, lane],
                                    _fma(w1, net[d, 4 + j, lane], w0 * net[d, j, lane]),
                                ),
                            )
                        for lane in range(lanes):
                            row_v[j, lane] = _fma(
                                x3,
                                net[d, 12 + j, lane],
                                _fma(
                                    x2,
                                    net[d, 8 + j, lane],
                                    _fma(x1, net[d, 4 + j, lane], x0 * net[d, j, lane]),
                                ),
                            )
                    for b in range(g):
                        y0, y1, y2, y3 = bv[0, b], bv[1, b], bv[2, b], bv[3, b]
                        z0, z1, z2, z3 = dbv[0, b], dbv[1, b], dbv[2, b], dbv[3, b]
                        if blends:
                            s0, s1, s2, s3 = su[0, a, b], su[1, a, b], su[2, a, b], su[3, a, b]
                            t0, t1, t2, t3 = sv[0, a, b], sv[1, a, b], sv[2, a, b], sv[3, a, b]
                            out_u, out_v = tu4[r, d, b], tv4[r, d, b]
                            e0, e1, e2, e3 = blend[d, 0], blend[d, 1], blend[d, 2], blend[d, 3]
                            ru0, ru1, ru2, ru3 = row_u[0], row_u[1], row_u[2], row_u[3]
                            rv0, rv1, rv2, rv3 = row_v[0], row_v[1], row_v[2], row_v[3]
                            for lane in range(lanes):
                                value = _fma(
                                    ru3[lane],
                                    y3,
                                    _fma(ru2[lane], y2, _fma(ru1[lane], y1, ru0[lane] * y0)),
                                )
                                out_u[lane] = _fma(
                                    s3,
                                    e3[lane],
                                    _fma(
                                        s2, e2[lane], _fma(s1, e1[lane], _fma(s0, e0[lane], value))
                                    ),
                                )
                            for lane in range(lanes):
                                value = _fma(
                                    rv3[lane],
                                    z3,
                                    _fma(rv2[lane], z2, _fma(rv1[lane], z1, rv0[lane] * z0)),
                                )
                                out_v[lane] = _fma(
                                    t3,
                                    e3[lane],
                                    _fma(
                                        t2, e2[lane], _fma(t1, e1[lane], _fma(t0, e0[lane], value))
                                    ),
                                )
                        else:
                            for lane in range(lanes):
                                tu4[r, d, b, lane] = _fma(
                                    row_u[3, lane],
                                    y3,
                                    _fma(
                                        row_u[2, lane],
                                        y2,
                                        _fma(row_u[1, lane], y1, row_u[0, lane] * y0),
                                    ),
                                )
                            for lane in range(lanes):
                                tv4[r, d, b, lane] = _fma(
                                    row_v[3, lane],
                                    z3,
                                    _fma(
                                        row_v[2, lane],
                                        z2,
                                        _fma(row_v[1, lane], z1, row_v[0, lane] * z0),
                                    ),
                                )
                # normals, unit normals, usable: one pass over the row's samples
                n0, n1, n2 = normal[0, a], normal[1, a], normal[2, a]
                u0, u1, u2 = unit[r, 0], unit[r, 1], unit[r, 2]
                ua = usable[a]
                a0, a1, a2 = tu[r, 0], tu[r, 1], tu[r, 2]
                b0, b1, b2 = tv[r, 0], tv[r, 1], tv[r, 2]
                for s in range(gl):
                    x = a1[s] * b2[s] - a2[s] * b1[s]
                    y = a2[s] * b0[s] - a0[s] * b2[s]
                    z = a0[s] * b1[s] - a1[s] * b0[s]
                    n0[s] = x
                    n1[s] = y
                    n2[s] = z
                    size = np.sqrt((x * x + y * y) + z * z)
                    inverse = 1.0 / max(size, _TINY)
                    u0[s] = x * inverse
                    u1[s] = y * inverse
                    u2[s] = z * inverse
                    ua[s] = size > level
                offending[a, :] = False
                if count == lanes:
                    for s in range(gl):
                        lost += 0 if usable[a, s] else 1
                else:
                    for b in range(g):
                        for lane in range(count):
                            lost += 0 if usable[a, b * lanes + lane] else 1
                for axis in range(
                    2
                ):  # neighbours along u: (a − 1, b), (a, b); along v: (a, b), (a, b + 1)
                    if axis == 0 and a == 0:
                        continue
                    behind, span = (a - 1, gl) if axis == 0 else (a, run)
                    if axis == 0:
                        for s in range(gl):
                            c0, c1, c2 = (
                                unit[r, 0, s] - unit[p, 0, s],
                                unit[r, 1, s] - unit[p, 1, s],
                                unit[r, 2, s] - unit[p, 2, s],
                            )
                            chord[s] = (
                                c0 * c0 + c2 * c2
                            ) + c1 * c1  # |n̂_a − n̂_b|² = 4 sin²(θ/2): > 2 where θ > 90°
                        for s in range(gl):
                            together[s] = usable[a - 1, s] & usable[a, s]
                    else:
                        for s in range(run):
                            c0, c1, c2 = (
                                unit_ahead[r, 0, s] - unit[r, 0, s],
                                unit_ahead[r, 1, s] - unit[r, 1, s],
                                unit_ahead[r, 2, s] - unit[r, 2, s],
                            )
                            chord[s] = (c0 * c0 + c2 * c2) + c1 * c1
                        for s in range(run):
                            together[s] = usable[a, s] & usable_ahead[a, s]
                    for s in range(span):
                        offending[behind, s] = offending[behind, s] | (
                            together[s] & (chord[s] > 2.0)
                        )
                    if not fairness:
                        continue
                    best_top, best_row = (
                        column_top[axis],
                        column_row[axis],
                    )  # per column: the first largest chord
                    for s in range(span):
                        best_row[s] = (
                            behind if together[s] & (chord[s] > best_top[s]) else best_row[s]
                        )
                    for s in range(span):
                        best_top[s] = (
                            chord[s] if together[s] & (chord[s] > best_top[s]) else best_top[s]
                        )
                    for s in range(span):
                        narrow[s] = chord[s]
                    for s in range(span):
                        code[s] = min(max((bits[s] >> _SHIFT) - (code_min - 1), 0), bins - 1)
                    for lane in range(
                        count
                    ):  # runs of one bin along the row, counted in a register
                        current, tally = 0, 0
                        for b in range(span // lanes):
                            if together2[b, lane]:
                                code_b = code2[b, lane]
                                if code_b != current:
                                    histogram[chunk, current] += tally
                                    current, tally = code_b, 0
                                tally += 1
                        histogram[chunk, current] += tally
                if not fairness:
                    continue
                for plane in range(
                    2
                    # thin plate: squared differences of p_u, p_v along u (per column), along v (per
                    # row)
                ):
                    t, ahead = (tu, tu_ahead) if plane == 0 else (tv, tv_ahead)
                    if a > 0:
                        for s in range(gl):
                            c0, c1, c2 = (
                                t[r, 0, s] - t[p, 0, s],
                                t[r, 1, s] - t[p, 1, s],
                                t[r, 2, s] - t[p, 2, s],
                            )
                            along_u[plane, s] += (c0 * c0 + c2 * c2) + c1 * c1
                    for s in range(run):
                        c0, c1, c2 = (
                            ahead[r, 0, s] - t[r, 0, s],
                            ahead[r, 1, s] - t[r, 1, s],
                            ahead[r, 2, s] - t[r, 2, s],
                        )
                        chord[s] = (c0 * c0 + c2 * c2) + c1 * c1
                    along_v[plane, a, :] = 0.0
                    for b in range(last):
                        for lane in range(lanes):
                            along_v[plane, a, lane] += chord2[b, lane]
            degenerate[chunk] += lost
            # per lane and axis the first largest chord in row-major order: the largest of the
            # columns', first
            if fairness:
                for axis in range(2):
                    for lane in range(lanes):
                        value, at = -1.0, -1
                        for b in range(g - axis):
                            row = column_row[axis, b * lanes + lane]
                            if row < 0:
                                continue
                            chord_b = column_top[axis, b * lanes + lane]
                            if chord_b > value or (chord_b == value and row * g + b < at):
                                value, at = chord_b, row * g + b
                        top[axis, lane], top_at[axis, lane] = value, at
            for lane in range(count):
                for corner in range(4):  # the corner's grid cell: a patch turned over at its corner
                    cu = 0 if corner == 0 or corner == 3 else last
                    cv = 0 if corner < 2 else last
                    o = cv * lanes + lane
                    if not usable[cu, o]:
                        continue
                    step_u, step_v = (1 if cu == 0 else -1), (lanes if cv == 0 else -lanes)
                    for cell in range(3):
                        i, s = cu + (0 if cell == 1 else step_u), o + (0 if cell == 0 else step_v)
                        dot = (
                            normal[0, i, s] * normal[0, cu, o] + normal[2, i, s] * normal[2, cu, o]
                        ) + normal[1, i, s] * normal[1, cu, o]
                        if usable[i, s] and dot < 0.0:
                            offending[i, s] = True
            for lane in range(count):  # no usable sample: only where a patch's worth is lost
                zero_area[first + lane] = False
            if lost >= g * g:
                for lane in range(count):
                    seen = False
                    for i in range(g):
                        for b in range(g):
                            seen = seen | usable[i, b * lanes + lane]
                    zero_area[first + lane] = not seen
            folded[:] = False  # per lane: any offending sample? then the first, row by row
            for i in range(g):
                for s in range(gl):
                    folded[s] = folded[s] | offending[i, s]
            for lane in range(count):
                location[first + lane] = -1
                hit = False
                for b in range(g):
                    hit = hit | folded[b * lanes + lane]
                if not hit:
                    continue
                for i in range(g * g):
                    if offending[i // g, (i % g) * lanes + lane]:
                        location[first + lane] = i
                        break
            if not fairness:
                continue
            for lane in range(count):
                n = first + lane
                for axis in range(2):
                    best[n, 2 * axis], best[n, 2 * axis + 1] = top[axis, lane], 0.0
                    s = top_at[axis, lane]
                    if s >= 0:
                        i, j = s // g, s % g
                        k, h = (i + 1, j) if axis == 0 else (i, j + 1)
                        for d in range(3):
                            pair[0, d], pair[1, d] = (
                                normal[d, i, j * lanes + lane],
                                normal[d, k, h * lanes + lane],
                            )
                        best[n, 2 * axis + 1] = _pair_angle(pair[0], pair[1], True)
            for lane in range(count):
                total = 0.0
                for plane in range(2):
                    row = 0.0
                    for b in range(g):
                        row += weights[b] * along_u[plane, b * lanes + lane]
                    total += row
                    row = 0.0
                    for a in range(g):
                        row += weights[a] * along_v[plane, a, lane]
                    total += row
                energy[first + lane] = total
