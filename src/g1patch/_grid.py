"""Fast kernels: batched bicubic patches on tensor-product grids, in plain NumPy + BLAS.

``out[n, a, b] = Σ_ij wu[a, i] P[n, i, j] wv[b, j]`` on a ``Gu × Gv`` grid is separable. The kernels
work block by block (a few patches, or part of one patch's grid) and use matrix products only:

1. contract u with one GEMM per block: ``R[(e, j), (n, a)] = Σ_i P[n, i, j, e] wu[a, i]``
   (the block's control points as a ``(12·count × 4)`` matrix times ``wu^T``);
2. contract v with one GEMM whose output is already the interleaved ``(N, Gu, Gv, 3)`` layout::

       out[(n, a), (b, d)] = Σ_(e, j) R[(e, j), (n, a)] · W[(e, j), (b, d)],    W = wv[b, j] δ_ed

   written straight into the caller's array.

Unit normals. Along a grid row (fixed n, a) both tangents are cubics in v with known coefficients,
``p_u = Σ_j U_j wv_j(v)`` and ``p_v = Σ_k V_k dwv_k(v)`` (U, V: the rows of step 1 for dwu and wu),
so ``(p_u × p_v)_d = Σ_jk C_d[j, k] wv_j(v) dwv_k(v)`` with ``C_d[j, k] = U_i[j] V_l[k] − U_l[j] V_i[k]``,
(d, i, l) cyclic.
The 16 coefficients per row and component are formed with contiguous ufuncs (48 per row, against
3 per grid point for a pointwise cross product), then one GEMM per component against the
``16 × Gv`` table of basis products gives the three planar components on the whole row. Every
term of that sum is a term of the pointwise cross product, so the rounding error is bounded by the
same local quantity ``|p_u|_abs |p_v|_abs`` as for ``cross(p_u, p_v)`` (no error from far away on the
patch, unlike an interpolated or power-form normal). The length (one ``einsum``), ``sqrt`` and the
division into the interleaved output are ``out=`` ufuncs on cache-sized scratch; nothing the size of
the output is allocated besides the output.

Blocks hold about :data:`BLOCK_POINTS` grid points: the scratch stays in the L2 cache, and every GEMM
stays below the size (M·N·K ≈ 10^6) at which OpenBLAS splits a product over threads; on a 2-core
machine shared with other work that split made the small products several times slower.

Degenerate points: where ``p_u × p_v = 0`` the normal is the zero vector, never NaN — the squared
length is clamped to the smallest normal float before the square root and ``0 / 1.5e-154 = 0``. (A
cross product shorter than ``sqrt(tiny) ≈ 1.5e-154`` comes out shorter than unit, never longer.)

Compiled kernels. From :data:`KERNEL_POINTS` grid points on (``compiled=None``; ``True`` always,
``False`` never) numba kernels do the same work, compiled on first use and cached on disk; the
NumPy code stays as their reference (tests/test_grid_kernels.py holds them to it). They are the
tensor-product evaluation one grid row at a time: for row ``a`` of patch ``n`` and coordinate ``e``
the row curve ``r_j = Σ_i wu[a, i] P[n, i, j, e]`` (and ``s_j`` with ``dwu``), then along the row

    p = Σ_j r_j wv[b, j],   p_u = Σ_j s_j wv[b, j],   p_v = Σ_j r_j dwv[b, j]

(4 products and 3 sums each, vectorised over b into an L1-sized planar scratch), the unit normal
``c / sqrt(max(|c|², tiny))`` with ``c = p_u × p_v`` (one square root), and one pass interleaving
the row into the ``(N, Gu, Gv, 3)`` outputs. The same 16-term sums as the reference, associated
the same way (u first, then v), with a cross product of evaluated tangents instead of the
reference's expanded coefficients: tests/test_grid_kernels.py states the ULP bound. The patches are
split into contiguous ranges, one per core, run on threads (the kernels release the GIL); every
point is written by exactly one range, so the result does not depend on the split.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from functools import cache
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .basis import Form, basis_values
from .errors import InputError

__all__ = ["BLOCK_POINTS", "KERNEL_POINTS", "contract", "normals", "positions_and_normals"]

#: Grid points per block (rows of several patches, or part of one patch's grid).
BLOCK_POINTS = 16384

#: grid points (N Gu Gv) from which the compiled kernels run by default: below, the NumPy code takes
#: a few ms at most, and a first use should not pay the kernels' one-time compile
KERNEL_POINTS = 1 << 20

_TINY = np.finfo(np.float64).tiny

#: (d, i, l) cyclic: (a × b)_d = a_i b_l − a_l b_i.
_CROSS = ((0, 1, 2), (1, 2, 0), (2, 0, 1))


def _interleaving_weights(weights_v: NDArray[np.float64]) -> NDArray[np.float64]:
    """``W[(e, j), (b, d)] = wv[b, j] δ_ed``, shape (12, 3 Gv)."""
    gv = weights_v.shape[0]
    w = np.zeros((3, 4, gv, 3))
    for d in range(3):
        w[d, :, :, d] = weights_v.T
    return w.reshape(12, 3 * gv)


def _check_out(name: str, out: NDArray[np.float64] | None, shape: tuple[int, ...]) -> NDArray[np.float64]:
    if out is None:
        return np.empty(shape)
    if out.shape != shape or out.dtype != np.float64 or not out.flags.c_contiguous:
        raise InputError(f"{name}: expected a C-contiguous float64 array of shape {shape}, got {out.dtype} {out.shape}")
    return out


def _layout(n: int, gu: int, gv: int) -> tuple[int, int]:
    """(patches per block, grid rows per sub-block): whole patches when one fits in a block."""
    if gu * gv <= BLOCK_POINTS:
        patches = max(1, min(n, BLOCK_POINTS // max(1, gu * gv)))
        return patches, patches * gu
    return 1, max(1, BLOCK_POINTS // gv)


def _use_kernels(points: int, compiled: bool | None) -> bool:
    """Whether to run the compiled kernels: ``compiled`` when given, else from :data:`KERNEL_POINTS` on."""
    return points >= KERNEL_POINTS if compiled is None else compiled


def contract(
    control: NDArray[np.float64],
    weights_u: NDArray[np.float64],
    weights_v: NDArray[np.float64],
    out: NDArray[np.float64] | None = None,
    compiled: bool | None = None,
) -> NDArray[np.float64]:
    """``out[n, a, b, :] = Σ_ij wu[a, i] P[n, i, j, :] wv[b, j]``, C-contiguous ``(N, Gu, Gv, 3)``."""
    n, gu, gv = control.shape[0], weights_u.shape[0], weights_v.shape[0]
    out = _check_out("out", out, (n, gu, gv, 3))
    if out.size == 0:
        return out
    if _use_kernels(out.size // 3, compiled):
        kernel = _compiled(_contract_kernel)
        control, wu, wv_t = np.ascontiguousarray(control), np.ascontiguousarray(weights_u), np.ascontiguousarray(weights_v.T)
        _in_ranges(lambda lo, hi: kernel(control, wu, wv_t, out, lo, hi), n)
    else:
        _run(control, weights_u, None, weights_v, None, out, None)
    return out


def positions_and_normals(
    control: NDArray[np.float64],
    form: Form,
    u: NDArray[np.float64],
    v: NDArray[np.float64],
    out: NDArray[np.float64] | None = None,
    normals_out: NDArray[np.float64] | None = None,
    compiled: bool | None = None,
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Positions and unit normals ``p_u × p_v / |p_u × p_v|`` on the grid ``u × v`` (zero where degenerate)."""
    shape = (control.shape[0], u.shape[0], v.shape[0], 3)
    out = _check_out("out", out, shape)
    return out, _normals_into(control, form, u, v, out, normals_out, compiled)


def normals(
    control: NDArray[np.float64],
    form: Form,
    u: NDArray[np.float64],
    v: NDArray[np.float64],
    out: NDArray[np.float64] | None = None,
    compiled: bool | None = None,
) -> NDArray[np.float64]:
    """Unit normals on the grid ``u × v``, ``(N, Gu, Gv, 3)``; zero where ``p_u × p_v = 0``."""
    return _normals_into(control, form, u, v, None, out, compiled)


def _normals_into(
    control: NDArray[np.float64],
    form: Form,
    u: NDArray[np.float64],
    v: NDArray[np.float64],
    positions: NDArray[np.float64] | None,
    normals_out: NDArray[np.float64] | None,
    compiled: bool | None,
) -> NDArray[np.float64]:
    """Unit normals into ``normals_out`` (allocated when None), and positions too when given."""
    normals_out = _check_out("normals_out" if positions is not None else "out", normals_out,
                             (control.shape[0], u.shape[0], v.shape[0], 3))
    if normals_out.size == 0:
        return normals_out
    wu, dwu = basis_values(form, u), basis_values(form, u, 1)
    wv, dwv = basis_values(form, v), basis_values(form, v, 1)
    if _use_kernels(normals_out.size // 3, compiled):
        kernel = _compiled(_normals_kernel)
        control, wu, dwu = np.ascontiguousarray(control), np.ascontiguousarray(wu), np.ascontiguousarray(dwu)
        wv_t, dwv_t = np.ascontiguousarray(wv.T), np.ascontiguousarray(dwv.T)
        into = np.empty((0, 0, 0, 3)) if positions is None else positions
        _in_ranges(lambda lo, hi: kernel(control, wu, dwu, wv_t, dwv_t, into, normals_out, lo, hi), control.shape[0])
    else:
        _run(control, wu, dwu, wv, dwv, positions, normals_out)
    return normals_out


def _run(
    control: NDArray[np.float64],
    wu: NDArray[np.float64],
    dwu: NDArray[np.float64] | None,
    wv: NDArray[np.float64],
    dwv: NDArray[np.float64] | None,
    positions: NDArray[np.float64] | None,
    normals: NDArray[np.float64] | None,
) -> None:
    """Fill ``positions`` (weights wu, wv) and/or unit ``normals`` (from dwu, wv and wu, dwv) block by block."""
    n, gu, gv = control.shape[0], wu.shape[0], wv.shape[0]
    per_block, rows = _layout(n, gu, gv)
    by_coordinate = control.transpose(3, 2, 0, 1)  # [e, j, n, i]
    block_control = np.empty(12 * per_block * 4)
    wu_t = np.ascontiguousarray(wu.T)
    r_val = np.empty(12 * per_block * gu)
    if positions is not None:
        interleave = _interleaving_weights(wv)
        flat_positions = positions.reshape(n * gu, 3 * gv)
    if normals is not None:
        assert dwu is not None and dwv is not None
        dwu_t = np.ascontiguousarray(dwu.T)
        r_du = np.empty(12 * per_block * gu)
        # products[(j, k), b] = wv[b, j] dwv[b, k]; along a grid row (p_u × p_v)_d = Σ_jk C_d[j, k] products[(j, k), b]
        products = np.ascontiguousarray((wv[:, :, None] * dwv[:, None, :]).reshape(gv, 16).T)
        coeff_buf, tmp_buf = np.empty(16 * rows), np.empty(16 * rows)
        u_rep_buf, v_tile_buf = np.empty(48 * rows), np.empty(48 * rows)
        cross, length = np.empty((3, rows, gv)), np.empty((rows, gv))
        flat_normals = normals.reshape(n * gu, gv, 3)
    for start in range(0, n, per_block):
        stop = min(start + per_block, n)
        count = stop - start
        block = block_control[: 12 * count * 4].reshape(12 * count, 4)
        np.copyto(block.reshape(3, 4, count, 4), by_coordinate[:, :, start:stop])
        # step 1 as one GEMM: r[(e, j), (n, a)] = Σ_i P[n, i, j, e] wu[a, i]
        r_v = r_val[: 12 * count * gu].reshape(12 * count, gu)
        np.matmul(block, wu_t, out=r_v)
        r_v = r_v.reshape(12, count * gu)
        if normals is not None:
            r_u = r_du[: 12 * count * gu].reshape(12 * count, gu)
            np.matmul(block, dwu_t, out=r_u)
            r_u = r_u.reshape(12, count * gu)
        for lo in range(0, count * gu, rows):
            hi = min(lo + rows, count * gu)
            out_rows = slice(start * gu + lo, start * gu + hi)
            if positions is not None:
                np.matmul(r_v[:, lo:hi].T, interleave, out=flat_positions[out_rows])
            if normals is None:
                continue
            m = hi - lo
            # u_rep[e, (j, k)] = U_e[j] and v_tile[e, (j, k)] = V_e[k]: the products below are then contiguous
            # (a broadcast operand makes NumPy's multiply about 3x slower)
            u_rep, v_tile = u_rep_buf[: 48 * m].reshape(3, 16, m), v_tile_buf[: 48 * m].reshape(3, 16, m)
            np.copyto(u_rep.reshape(3, 4, 4, m), r_u[:, lo:hi].reshape(3, 4, 1, m))
            np.copyto(v_tile.reshape(3, 4, 4, m), r_v[:, lo:hi].reshape(3, 1, 4, m))
            coeff, tmp = coeff_buf[: 16 * m].reshape(16, m), tmp_buf[: 16 * m].reshape(16, m)
            nrm, length_m = cross[:, :m], length[:m]
            for d, i, l in _CROSS:
                # C_d[(j, k)] = U_i[j] V_l[k] - U_l[j] V_i[k] for every grid row, then one GEMM along v
                np.multiply(u_rep[i], v_tile[l], out=coeff)
                np.multiply(u_rep[l], v_tile[i], out=tmp)
                np.subtract(coeff, tmp, out=coeff)
                np.matmul(coeff.T, products, out=nrm[d])
            np.einsum("dmb,dmb->mb", nrm, nrm, out=length_m)
            np.maximum(length_m, _TINY, out=length_m)
            np.sqrt(length_m, out=length_m)
            target = flat_normals[out_rows]
            for d in range(3):
                np.divide(nrm[d], length_m, out=target[:, :, d])


# ---------------------------------------------------------------------------------------------
# Compiled kernels (see the module docstring); ``_run`` above is their reference.

_pool: ThreadPoolExecutor | None = None


@cache
def _compiled(kernel: Callable[..., Any]) -> Callable[..., Any]:
    """``kernel`` compiled by numba on first use: cached on disk, without the GIL (ranges run on
    threads side by side), float64 IEEE arithmetic as NumPy's (no fastmath: no contraction into
    fused multiply-adds). numba is imported here, so that ``import g1patch`` stays fast."""
    import numba

    return numba.njit(cache=True, nogil=True, error_model="numpy")(kernel)  # type: ignore[no-any-return]


def _workers() -> int:
    """Cores this process may run on."""
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1


def _forget_pool() -> None:
    """A forked child has none of its parent's threads: it starts its own pool when it needs one."""
    global _pool
    _pool = None


if hasattr(os, "register_at_fork"):
    os.register_at_fork(after_in_child=_forget_pool)


def _in_ranges(call: Callable[[int, int], object], count: int) -> None:
    """``call(lo, hi)`` over ``[0, count)`` cut into one contiguous range per core, on threads."""
    global _pool
    parts = max(1, min(_workers(), count))
    if parts == 1:
        call(0, count)
        return
    if _pool is None:
        _pool = ThreadPoolExecutor(max_workers=parts, thread_name_prefix="g1patch-grid")
    bounds = [count * k // parts for k in range(parts + 1)]
    for future in [_pool.submit(call, lo, hi) for lo, hi in zip(bounds[:-1], bounds[1:])]:
        future.result()


def _contract_kernel(
    control: NDArray[np.float64],
    wu: NDArray[np.float64],
    wv_t: NDArray[np.float64],
    out: NDArray[np.float64],
    lo: int,
    hi: int,
) -> None:
    """``out[n, a, b, e] = Σ_j (Σ_i wu[a, i] P[n, i, j, e]) wv_t[j, b]`` for patches ``lo ≤ n < hi``."""
    gu, gv = wu.shape[0], wv_t.shape[1]
    row = np.empty((3, gv))
    for n in range(lo, hi):
        for a in range(gu):
            w0, w1, w2, w3 = wu[a, 0], wu[a, 1], wu[a, 2], wu[a, 3]
            for e in range(3):
                r0 = w0 * control[n, 0, 0, e] + w1 * control[n, 1, 0, e] + w2 * control[n, 2, 0, e] + w3 * control[n, 3, 0, e]
                r1 = w0 * control[n, 0, 1, e] + w1 * control[n, 1, 1, e] + w2 * control[n, 2, 1, e] + w3 * control[n, 3, 1, e]
                r2 = w0 * control[n, 0, 2, e] + w1 * control[n, 1, 2, e] + w2 * control[n, 2, 2, e] + w3 * control[n, 3, 2, e]
                r3 = w0 * control[n, 0, 3, e] + w1 * control[n, 1, 3, e] + w2 * control[n, 2, 3, e] + w3 * control[n, 3, 3, e]
                for b in range(gv):
                    row[e, b] = r0 * wv_t[0, b] + r1 * wv_t[1, b] + r2 * wv_t[2, b] + r3 * wv_t[3, b]
            for b in range(gv):
                out[n, a, b, 0] = row[0, b]
                out[n, a, b, 1] = row[1, b]
                out[n, a, b, 2] = row[2, b]


def _normals_kernel(
    control: NDArray[np.float64],
    wu: NDArray[np.float64],
    dwu: NDArray[np.float64],
    wv_t: NDArray[np.float64],
    dwv_t: NDArray[np.float64],
    positions: NDArray[np.float64],
    normals: NDArray[np.float64],
    lo: int,
    hi: int,
) -> None:
    """Unit normals ``c / sqrt(max(|c|², tiny))``, ``c = p_u × p_v``, for patches ``lo ≤ n < hi``, and the
    positions as :func:`_contract_kernel` computes them unless ``positions`` is empty."""
    gu, gv = wu.shape[0], wv_t.shape[1]
    with_positions = positions.shape[0] > 0
    tiny = 2.2250738585072014e-308  # the smallest normal float64
    row = np.empty((12, gv))  # p, p_u, p_v, unit normal; 3 coordinates each
    for n in range(lo, hi):
        for a in range(gu):
            w0, w1, w2, w3 = wu[a, 0], wu[a, 1], wu[a, 2], wu[a, 3]
            d0, d1, d2, d3 = dwu[a, 0], dwu[a, 1], dwu[a, 2], dwu[a, 3]
            for e in range(3):
                r0 = w0 * control[n, 0, 0, e] + w1 * control[n, 1, 0, e] + w2 * control[n, 2, 0, e] + w3 * control[n, 3, 0, e]
                r1 = w0 * control[n, 0, 1, e] + w1 * control[n, 1, 1, e] + w2 * control[n, 2, 1, e] + w3 * control[n, 3, 1, e]
                r2 = w0 * control[n, 0, 2, e] + w1 * control[n, 1, 2, e] + w2 * control[n, 2, 2, e] + w3 * control[n, 3, 2, e]
                r3 = w0 * control[n, 0, 3, e] + w1 * control[n, 1, 3, e] + w2 * control[n, 2, 3, e] + w3 * control[n, 3, 3, e]
                s0 = d0 * control[n, 0, 0, e] + d1 * control[n, 1, 0, e] + d2 * control[n, 2, 0, e] + d3 * control[n, 3, 0, e]
                s1 = d0 * control[n, 0, 1, e] + d1 * control[n, 1, 1, e] + d2 * control[n, 2, 1, e] + d3 * control[n, 3, 1, e]
                s2 = d0 * control[n, 0, 2, e] + d1 * control[n, 1, 2, e] + d2 * control[n, 2, 2, e] + d3 * control[n, 3, 2, e]
                s3 = d0 * control[n, 0, 3, e] + d1 * control[n, 1, 3, e] + d2 * control[n, 2, 3, e] + d3 * control[n, 3, 3, e]
                for b in range(gv):
                    row[e, b] = r0 * wv_t[0, b] + r1 * wv_t[1, b] + r2 * wv_t[2, b] + r3 * wv_t[3, b]
                    row[3 + e, b] = s0 * wv_t[0, b] + s1 * wv_t[1, b] + s2 * wv_t[2, b] + s3 * wv_t[3, b]
                    row[6 + e, b] = r0 * dwv_t[0, b] + r1 * dwv_t[1, b] + r2 * dwv_t[2, b] + r3 * dwv_t[3, b]
            for b in range(gv):
                cx = row[4, b] * row[8, b] - row[5, b] * row[7, b]
                cy = row[5, b] * row[6, b] - row[3, b] * row[8, b]
                cz = row[3, b] * row[7, b] - row[4, b] * row[6, b]
                square = cx * cx + cy * cy + cz * cz
                length = np.sqrt(square if square > tiny else tiny)
                row[9, b] = cx / length
                row[10, b] = cy / length
                row[11, b] = cz / length
            if with_positions:
                for b in range(gv):
                    positions[n, a, b, 0] = row[0, b]
                    positions[n, a, b, 1] = row[1, b]
                    positions[n, a, b, 2] = row[2, b]
            for b in range(gv):
                normals[n, a, b, 0] = row[9, b]
                normals[n, a, b, 1] = row[10, b]
                normals[n, a, b, 2] = row[11, b]
