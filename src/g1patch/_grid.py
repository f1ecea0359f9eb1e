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
so ``(p_u × p_v)_d = Σ_jk C_d[j, k] wv_j(v) dwv_k(v)`` with ``C_d[j, k] = U_i[j] V_l[k] − U_l[j]
V_i[k]``, (d, i, l) cyclic. The 16 coefficients per row and component are formed with contiguous
ufuncs (48 per row, against 3 per grid point for a pointwise cross product), then one GEMM per
component against the ``16 × Gv`` table of basis products gives the three planar components on the
whole row. Every term of that sum is a term of the pointwise cross product, so the rounding error is
bounded by the same local quantity ``|p_u|_abs |p_v|_abs`` as for ``cross(p_u, p_v)`` (no error from
far away on the patch, unlike an interpolated or power-form normal). The length (one ``einsum``),
``sqrt`` and the division into the interleaved output are ``out=`` ufuncs on cache-sized scratch;
nothing the size of the output is allocated besides the output.

Blocks hold about :data:`BLOCK_POINTS` grid points: the scratch stays in the L2 cache, and every
GEMM stays below the size (M·N·K ≈ 10^6) at which OpenBLAS splits a product over threads; on a
2-core machine shared with other work that split made the small products several times slower.

Degenerate points: where ``p_u × p_v = 0`` the normal is the zero vector, never NaN — the squared
length is clamped to the smallest normal float before the square root and ``0 / 1.5e-154 = 0``. (A
cross product shorter than ``sqrt(tiny) ≈ 1.5e-154`` comes out shorter than unit, never longer.)

Compiled kernels. From :data:`KERNEL_POINTS` grid points on (``compiled=None``; ``True`` always,
``False`` never) numba kernels do the same work, compiled on first use and cached on disk; the
NumPy code stays as their reference (tests/test_grid_kernels.py holds them to it). They are the
tensor-product evaluation, a patch at a time: first its row curves at every u (vectorised over u),
``r_j[a] = Σ_i wu[a, i] P[n, i, j]`` and ``s_j[a]`` with ``dwu``; then along each grid row

    p = Σ_j r_j wv[b, j],   p_u = Σ_j s_j wv[b, j],   p_v = Σ_j r_j dwv[b, j]

(4 products and 3 sums each, the 24 row coefficients held in registers), the unit normal
``c / sqrt(max(|c|², tiny))`` with ``c = p_u × p_v`` (one square root), all in one pass vectorised
over b into an L1-sized planar scratch, and one pass interleaving the row into the
``(N, Gu, Gv, 3)`` outputs. The same 16-term sums as the reference, associated the same way (u
first, then v), with a cross product of evaluated tangents instead of the reference's expanded
coefficients: tests/test_grid_kernels.py states the ULP bound. The patches are cut into contiguous
ranges, a few per core, taken in turn by one thread per core (the kernels release the GIL); every
point is written by exactly one range, so the result does not depend on the split.
"""

from __future__ import annotations

from collections.abc import Callable
from functools import cache
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .basis import Form, basis_values
from .errors import InputError
from .kernels import in_chunks, jit_kernel, use_kernels

__all__ = ["BLOCK_POINTS", "KERNEL_POINTS", "contract", "normals", "positions_and_normals"]

#: Grid points per block (rows of several patches, or part of one patch's grid).
BLOCK_POINTS = 16384

#: grid points (N Gu Gv) from which the compiled kernels run by default (4096 patches at 32²). Their
#: first use costs ~2.5 s once per install (compile into numba's disk cache) and ~0.5 s once per
#: process (numba's import and cache load); a call this size takes ~70 ms in NumPy for positions +
#: normals and ~20 ms for positions, the kernels about a third to a half of that
KERNEL_POINTS = 1 << 22

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


def _check_out(
    name: str, out: NDArray[np.float64] | None, shape: tuple[int, ...]
) -> NDArray[np.float64]:
    if out is None:
        return np.empty(shape)
    if out.shape != shape or out.dtype != np.float64 or not out.flags.c_contiguous:
        raise InputError(
            f"{name}: expected a C-contiguous float64 array of shape {shape}, got {out.dtype} "
            f"{out.shape}"
        )
    return out


def _layout(n: int, gu: int, gv: int) -> tuple[int, int]:
    """(patches per block, grid rows per sub-block): whole patches when one fits in a block."""
    if gu * gv <= BLOCK_POINTS:
        patches = max(1, min(n, BLOCK_POINTS // max(1, gu * gv)))
        return patches, patches * gu
    return 1, max(1, BLOCK_POINTS // gv)


def _use_kernels(points: int, compiled: bool | None) -> bool:
    """Whether to run the compiled kernels: ``compiled`` when given, else from :data:`KERNEL_POINTS`
    on."""
    return use_kernels(points >= KERNEL_POINTS) if compiled is None else compiled


def contract(
    control: NDArray[np.float64],
    weights_u: NDArray[np.float64],
    weights_v: NDArray[np.float64],
    out: NDArray[np.float64] | None = None,
    compiled: bool | None = None,
) -> NDArray[np.float64]:
    """``out[n, a, b, :] = Σ_ij wu[a, i] P[n, i, j, :] wv[b, j]``, C-contiguous ``(N, Gu, Gv,
    3)``."""
    n, gu, gv = control.shape[0], weights_u.shape[0], weights_v.shape[0]
    out = _check_out("out", out, (n, gu, gv, 3))
    if out.size == 0:
        return out
    if _use_kernels(out.size // 3, compiled):
        kernel = _compiled(_contract_kernel)
        control, wu_t, wv_t = (
            np.ascontiguousarray(control),
            np.ascontiguousarray(weights_u.T),
            np.ascontiguousarray(weights_v.T),
        )
        in_chunks(lambda lo, hi: kernel(control, wu_t, wv_t, out, lo, hi), n, least=1)
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
    """Positions and unit normals ``p_u × p_v / |p_u × p_v|`` on the grid ``u × v`` (zero where
    degenerate)."""
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
    normals_out = _check_out(
        "normals_out" if positions is not None else "out",
        normals_out,
        (control.shape[0], u.shape[0], v.shape[0], 3),
    )
    if normals_out.size == 0:
        return normals_out
    wu, dwu = basis_values(form, u), basis_values(form, u, 1)
    wv, dwv = basis_values(form, v), basis_values(form, v, 1)
    if _use_kernels(normals_out.size // 3, compiled):
        kernel = _compiled(_normals_kernel)
        control = np.ascontiguousarray(control)
        wu_t, dwu_t, wv_t, dwv_t = (np.ascontiguousarray(w.T) for w in (wu, dwu, wv, dwv))
        into = np.empty((0, 0, 0, 3)) if positions is None else positions
        in_chunks(
            lambda lo, hi: kernel(control, wu_t, dwu_t, wv_t, dwv_t, into, normals_out, lo, hi),
            control.shape[0],
            least=1,
        )
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
    """Fill ``positions`` (weights wu, wv) and/or unit ``normals`` (from dwu, wv and wu, dwv) block
    by block."""
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
        # products[(j, k), b] = wv[b, j] dwv[b, k]; along a grid row (p_u × p_v)_d = Σ_jk C_d[j, k]
        # products[(j, k), b]
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
            # u_rep[e, (j, k)] = U_e[j] and v_tile[e, (j, k)] = V_e[k]: the products below are then
            # contiguous
            # (a broadcast operand makes NumPy's multiply about 3x slower)
            u_rep, v_tile = (
                u_rep_buf[: 48 * m].reshape(3, 16, m),
                v_tile_buf[: 48 * m].reshape(3, 16, m),
            )
            np.copyto(u_rep.reshape(3, 4, 4, m), r_u[:, lo:hi].reshape(3, 4, 1, m))
            np.copyto(v_tile.reshape(3, 4, 4, m), r_v[:, lo:hi].reshape(3, 1, 4, m))
            coeff, tmp = coeff_buf[: 16 * m].reshape(16, m), tmp_buf[: 16 * m].reshape(16, m)
            nrm, length_m = cross[:, :m], length[:m]
            for d, i, m_ in _CROSS:
                # C_d[(j, k)] = U_i[j] V_m[k] - U_m[j] V_i[k] for every grid row, then one GEMM
                # along v
                np.multiply(u_rep[i], v_tile[m_], out=coeff)
                np.multiply(u_rep[m_], v_tile[i], out=tmp)
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


@cache
def _compiled(kernel: Callable[..., Any]) -> Callable[..., Any]:
    """``kernel`` by :func:`~g1patch.kernels.jit_kernel` (cached on disk, without the GIL, no
    fastmath: no contraction into fused multiply-adds); the helper :func:`_row_curves` is compiled
    (and rebound) with the first kernel."""
    global _row_curves
    if not hasattr(_row_curves, "py_func"):
        _row_curves = jit_kernel(_row_curves)
    return jit_kernel(kernel)


def _row_curves(
    control: NDArray[np.float64],
    n: int,
    weights_t: NDArray[np.float64],
    rows: NDArray[np.float64],
    first: int,
) -> None:
    """``rows[first + 3 j + e, a] = Σ_i weights_t[i, a] P[n, i, j, e]``: patch n's row curves at
    every u, vectorised over a."""
    for k in range(12):
        j, e = k // 3, k % 3
        p0, p1, p2, p3 = (
            control[n, 0, j, e],
            control[n, 1, j, e],
            control[n, 2, j, e],
            control[n, 3, j, e],
        )
        for a in range(weights_t.shape[1]):
            rows[first + k, a] = (
                weights_t[0, a] * p0
                + weights_t[1, a] * p1
                + weights_t[2, a] * p2
                + weights_t[3, a] * p3
            )


def _contract_kernel(
    control: NDArray[np.float64],
    wu_t: NDArray[np.float64],
    wv_t: NDArray[np.float64],
    out: NDArray[np.float64],
    lo: int,
    hi: int,
) -> None:
    """``out[n, a, b, e] = Σ_j r_j[e] wv_t[j, b]`` with ``r_j = Σ_i wu_t[i, a] P[n, i, j]``, patches
    ``lo ≤ n < hi``."""
    gu, gv = wu_t.shape[1], wv_t.shape[1]
    rows = np.empty((12, gu))
    line = np.empty((3, gv))
    for n in range(lo, hi):
        _row_curves(control, n, wu_t, rows, 0)
        for a in range(gu):
            r0x, r0y, r0z = rows[0, a], rows[1, a], rows[2, a]
            r1x, r1y, r1z = rows[3, a], rows[4, a], rows[5, a]
            r2x, r2y, r2z = rows[6, a], rows[7, a], rows[8, a]
            r3x, r3y, r3z = rows[9, a], rows[10, a], rows[11, a]
            for b in range(gv):
                v0, v1, v2, v3 = wv_t[0, b], wv_t[1, b], wv_t[2, b], wv_t[3, b]
                line[0, b] = r0x * v0 + r1x * v1 + r2x * v2 + r3x * v3
                line[1, b] = r0y * v0 + r1y * v1 + r2y * v2 + r3y * v3
                line[2, b] = r0z * v0 + r1z * v1 + r2z * v2 + r3z * v3
            for b in range(gv):
                out[n, a, b, 0] = line[0, b]
                out[n, a, b, 1] = line[1, b]
                out[n, a, b, 2] = line[2, b]


def _normals_kernel(
    control: NDArray[np.float64],
    wu_t: NDArray[np.float64],
    dwu_t: NDArray[np.float64],
    wv_t: NDArray[np.float64],
    dwv_t: NDArray[np.float64],
    positions: NDArray[np.float64],
    normals: NDArray[np.float64],
    lo: int,
    hi: int,
) -> None:
    """Unit normals ``c / sqrt(max(|c|², tiny))``, ``c = p_u × p_v``, for patches ``lo ≤ n < hi``,
    and the positions as :func:`_contract_kernel` computes them unless ``positions`` is empty. Row
    curves ``r_j`` (weights wu) and ``s_j`` (dwu); along a row ``p = Σ r_j wv_j``, ``p_u = Σ s_j
    wv_j``, ``p_v = Σ r_j dwv_j``."""
    gu, gv = wu_t.shape[1], wv_t.shape[1]
    with_positions = positions.shape[0] > 0
    tiny = 2.2250738585072014e-308  # the smallest normal float64
    rows = np.empty((24, gu))
    line = np.empty((6, gv))  # positions, unit normals
    for n in range(lo, hi):
        _row_curves(control, n, wu_t, rows, 0)
        _row_curves(control, n, dwu_t, rows, 12)
        for a in range(gu):
            r0x, r0y, r0z = rows[0, a], rows[1, a], rows[2, a]
            r1x, r1y, r1z = rows[3, a], rows[4, a], rows[5, a]
            r2x, r2y, r2z = rows[6, a], rows[7, a], rows[8, a]
            r3x, r3y, r3z = rows[9, a], rows[10, a], rows[11, a]
            s0x, s0y, s0z = rows[12, a], rows[13, a], rows[14, a]
            s1x, s1y, s1z = rows[15, a], rows[16, a], rows[17, a]
            s2x, s2y, s2z = rows[18, a], rows[19, a], rows[20, a]
            s3x, s3y, s3z = rows[21, a], rows[22, a], rows[23, a]
            for b in range(gv):
                v0, v1, v2, v3 = wv_t[0, b], wv_t[1, b], wv_t[2, b], wv_t[3, b]
                d0, d1, d2, d3 = dwv_t[0, b], dwv_t[1, b], dwv_t[2, b], dwv_t[3, b]
                line[0, b] = r0x * v0 + r1x * v1 + r2x * v2 + r3x * v3
                line[1, b] = r0y * v0 + r1y * v1 + r2y * v2 + r3y * v3
                line[2, b] = r0z * v0 + r1z * v1 + r2z * v2 + r3z * v3
                ux = s0x * v0 + s1x * v1 + s2x * v2 + s3x * v3
                uy = s0y * v0 + s1y * v1 + s2y * v2 + s3y * v3
                uz = s0z * v0 + s1z * v1 + s2z * v2 + s3z * v3
                vx = r0x * d0 + r1x * d1 + r2x * d2 + r3x * d3
                vy = r0y * d0 + r1y * d1 + r2y * d2 + r3y * d3
                vz = r0z * d0 + r1z * d1 + r2z * d2 + r3z * d3
                cx, cy, cz = uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx
                square = cx * cx + cy * cy + cz * cz
                length = np.sqrt(square if square > tiny else tiny)
                line[3, b] = cx / length
                line[4, b] = cy / length
                line[5, b] = cz / length
            if with_positions:
                for b in range(gv):
                    positions[n, a, b, 0] = line[0, b]
                    positions[n, a, b, 1] = line[1, b]
                    positions[n, a, b, 2] = line[2, b]
            for b in range(gv):
                normals[n, a, b, 0] = line[3, b]
                normals[n, a, b, 1] = line[4, b]
                normals[n, a, b, 2] = line[5, b]
