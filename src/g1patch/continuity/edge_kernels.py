"""G0 and G1 along shared edges in a numba kernel: :func:`_edge_measures_compiled`, the compiled
twin of :func:`.edges._edge_measures`, both sides of every shared edge in one parallel pass."""

from __future__ import annotations

import itertools
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..network import edge_parameters
from .jit import _chunks, _compiled, _fma, _sparse, _weights
from .sampling import position_entries

prange = range  # numba.prange once a kernel is compiled (:func:`.jit._bind`)

_CANDIDATE_RTOL = 1e-12
"""An edge's extreme angles are computed (``atan2``) only at the samples whose pseudo-angle
``y / (y + x)`` (``2 − y / (y + |x|)`` where x < 0; y = |n_L × n_R|, x = n_L · n_R; strictly
increasing in the angle) is within this relative distance of the extreme one. Its rounding
(≤ 2 ULP) and atan2's (≤ 1 ULP), scaled by the pseudo-angle's slope (between ½ and 1 per radian),
stay below 10 ULP: this margin is 400× that."""

# : shared edges the edge kernel measures side by side (its vector lanes; a run-time argument, as
# _LANES)
_EDGE_LANES = 32


def _edge_measures_compiled(
    points: NDArray[np.float64],
    form: str,
    sides: tuple[NDArray[Any], ...],
    samples: int,
    degenerate_level: float,
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.int64], NDArray[np.float64]]:
    """:func:`_edge_measures` of all the given edges, both sides of each in one kernel pass (both
    sides' points less the left patch's first, as the reference's :func:`.sampling.anchors`)."""
    left_patch, left_edge, right_patch, right_edge, same = sides
    origin = np.ascontiguousarray(points[left_patch, 0])
    position = position_entries(form, points.shape[1])
    t = np.linspace(0.0, 1.0, samples)
    uv = np.stack(
        [
            np.stack(
                [
                    edge_parameters(np.asarray(edge, dtype=np.int64), t[::-1] if reverse else t)
                    for reverse in (False, True)
                ]
            )
            for edge in range(4)
        ]
    )  # (edge, reversed, K, 2)
    table = np.stack([_weights(form, uv, du, dv) for du, dv in ((0, 0), (1, 0), (0, 1))], axis=2)
    weights, index, count = _sparse(table)  # (edge, reversed, derivative, M, K)
    blocks = (count + 3) // 4
    padded = np.full(
        (*index.shape[:-1], 4 * max(int(blocks.max()), 1)), index.shape[-1], dtype=np.int64
    )
    for key in np.ndindex(count.shape):
        padded[key][: count[key]] = index[key][: count[key]]
    weights = np.concatenate(
        [weights, np.zeros((*weights.shape[:-2], 1, samples))], axis=-2
    )  # point M: weight +0
    edges = len(left_patch)
    angle, least, gap = np.empty(edges), np.empty(edges), np.empty(edges)
    worst = np.empty(edges, dtype=np.int64)
    if edges:
        # the sides' edges and directions (the weights an edge takes), 32 classes: a stable sort of
        # 8-bit keys is NumPy's radix sort (2 M edges: 0.1 s -> 0.02 s for the sort and the classes)
        key = ((left_edge * 4 + right_edge) * 2 + same).astype(np.int8)
        order = np.argsort(key, kind="stable")
        bounds = np.r_[0, np.cumsum(np.bincount(key, minlength=32))]
        groups = np.unique(
            np.concatenate(
                [np.arange(a, b, _EDGE_LANES) for a, b in itertools.pairwise(bounds)] + [[edges]]
            )
        )
        _compiled(_edge_kernel)(
            points,
            origin,
            position,
            left_patch,
            left_edge,
            right_patch,
            right_edge,
            same,
            order,
            groups,
            weights,
            padded,
            blocks,
            degenerate_level,
            _CANDIDATE_RTOL,
            _EDGE_LANES,
            _chunks(len(groups) - 1),
            angle,
            least,
            worst,
            gap,
        )
    return angle, least, worst, gap


def _edge_kernel(
    points: NDArray[np.float64],
    origin: NDArray[np.float64],
    position: NDArray[np.bool_],
    left_patch: NDArray[np.int64],
    left_edge: NDArray[np.int64],
    right_patch: NDArray[np.int64],
    right_edge: NDArray[np.int64],
    same: NDArray[np.bool_],
    order: NDArray[np.int64],
    groups: NDArray[np.int64],
    weights: NDArray[np.float64],
    index: NDArray[np.int64],
    blocks: NDArray[np.int64],
    level: float,
    rtol: float,
    lanes: int,
    chunks: int,
    angle: NDArray[np.float64],
    least: NDArray[np.float64],
    worst: NDArray[np.int64],
    gap: NDArray[np.float64],
) -> None:
    """Per edge: both sides' points (less ``origin[e]`` at the ``position`` entries) and normals at
    the K samples, then the reference's max and min angle, worst sample and max gap; ``atan2``
    only at the candidates (:data:`_CANDIDATE_RTOL`).

    ``lanes`` edges at a time, ``order[groups[i]:groups[i + 1]]`` for group i, whose edges share
    their sides' edge numbers and directions, so their weights: the lanes are the last axis of
    every scratch array, and the arithmetic vectorises across edges (the three coordinates of
    every lane in one loop, as the weights do not depend on them), sample by sample. A sum
    ``Σ_m P_m W_m`` runs over ``index[edge, backwards, q]`` four terms at a time (``blocks``
    of them), padded with the point ``M`` (−1 in every lane) of weight +0: ``fma(−1, +0, acc)``
    is ``acc`` exactly (``acc + (−0)``), so every value is the sequential sum of the edge-by-edge
    formulation, bit for bit."""
    samples, padded, group_count = weights.shape[-1], points.shape[1] + 1, groups.size - 1
    for chunk in prange(chunks):
        net = np.zeros((2, padded, 3 * lanes))  # side, point, (coordinate, lane)
        net[:, padded - 1] = -1.0
        values = np.empty((2, 3, 3, lanes))  # side, derivative (p, p_u, p_v), coordinate, lane
        sums = values.reshape((2, 3, 3 * lanes))
        normal, cross = np.empty((2, 3, lanes)), np.empty((3, lanes))
        distance, y, x = np.empty(lanes), np.empty((samples, lanes)), np.empty((samples, lanes))
        pseudo, usable = np.empty((samples, lanes)), np.empty((samples, lanes), dtype=np.bool_)
        candidate = np.empty((samples, lanes), dtype=np.bool_)
        top, bottom, gap2 = np.empty(lanes), np.empty(lanes), np.empty(lanes)
        for group in range(chunk * group_count // chunks, (chunk + 1) * group_count // chunks):
            first, stop = groups[group], groups[group + 1]
            lead = order[first]
            flip = -1.0 if same[lead] else 1.0
            for lane in range(stop - first):
                e = order[first + lane]
                for side in range(2):
                    patch = left_patch[e] if side == 0 else right_patch[e]
                    for m in range(padded - 1):
                        for d in range(3):
                            net[side, m, d * lanes + lane] = (
                                points[patch, m, d] - origin[e, d]
                                if position[m]
                                else points[patch, m, d]
                            )
            top[:] = -1.0
            bottom[:] = np.inf
            gap2[:] = 0.0
            for k in range(samples):
                for side in range(2):
                    edge = left_edge[lead] if side == 0 else right_edge[lead]
                    back = 1 if side == 1 and not same[lead] else 0
                    p = net[side]
                    for q in range(
                        3
                    ):  # the three coordinates of every lane in one loop (the weights are the same)
                        out = sums[side, q]
                        if blocks[edge, back, q] == 0:
                            out[:] = 0.0
                        for block in range(blocks[edge, back, q]):
                            m0, m1 = (
                                index[edge, back, q, 4 * block],
                                index[edge, back, q, 4 * block + 1],
                            )
                            m2, m3 = (
                                index[edge, back, q, 4 * block + 2],
                                index[edge, back, q, 4 * block + 3],
                            )
                            w0, w1 = weights[edge, back, q, m0, k], weights[edge, back, q, m1, k]
                            w2, w3 = weights[edge, back, q, m2, k], weights[edge, back, q, m3, k]
                            p0, p1, p2, p3 = p[m0], p[m1], p[m2], p[m3]
                            if block == 0:
                                for t in range(3 * lanes):
                                    out[t] = _fma(
                                        p3[t],
                                        w3,
                                        _fma(p2[t], w2, _fma(p1[t], w1, _fma(p0[t], w0, 0.0))),
                                    )
                            else:
                                for t in range(3 * lanes):
                                    out[t] = _fma(
                                        p3[t],
                                        w3,
                                        _fma(p2[t], w2, _fma(p1[t], w1, _fma(p0[t], w0, out[t]))),
                                    )
                for side in range(
                    2
                ):  # normals p_u × p_v (side R's flipped where both sides run the same way)
                    u, v, n = values[side, 1], values[side, 2], normal[side]
                    sign = flip if side == 1 else 1.0
                    for lane in range(lanes):
                        n[0, lane] = (u[1, lane] * v[2, lane] - u[2, lane] * v[1, lane]) * sign
                    for lane in range(lanes):
                        n[1, lane] = (u[2, lane] * v[0, lane] - u[0, lane] * v[2, lane]) * sign
                    for lane in range(lanes):
                        n[2, lane] = (u[0, lane] * v[1, lane] - u[1, lane] * v[0, lane]) * sign
                a, b = normal[0], normal[1]
                for lane in range(lanes):
                    usable[k, lane] = (
                        np.sqrt(
                            (a[0, lane] * a[0, lane] + a[1, lane] * a[1, lane])
                            + a[2, lane] * a[2, lane]
                        )
                        > level
                    ) & (
                        np.sqrt(
                            (b[0, lane] * b[0, lane] + b[1, lane] * b[1, lane])
                            + b[2, lane] * b[2, lane]
                        )
                        > level
                    )
                for lane in range(lanes):
                    cross[0, lane] = a[1, lane] * b[2, lane] - a[2, lane] * b[1, lane]
                for lane in range(lanes):
                    cross[1, lane] = a[2, lane] * b[0, lane] - a[0, lane] * b[2, lane]
                for lane in range(lanes):
                    cross[2, lane] = a[0, lane] * b[1, lane] - a[1, lane] * b[0, lane]
                for lane in range(lanes):
                    y[k, lane] = np.sqrt(
                        (cross[0, lane] * cross[0, lane] + cross[1, lane] * cross[1, lane])
                        + cross[2, lane] * cross[2, lane]
                    )
                for lane in range(lanes):
                    x[k, lane] = (a[0, lane] * b[0, lane] + a[2, lane] * b[2, lane]) + a[
                        1, lane
                    ] * b[1, lane]
                for lane in range(lanes):
                    total = y[k, lane] + abs(x[k, lane])
                    ratio = y[k, lane] / total if total > 0.0 else 0.0
                    pseudo[k, lane] = ratio if x[k, lane] >= 0.0 else 2.0 - ratio
                q0, q1 = values[0, 0], values[1, 0]
                for lane in range(lanes):
                    g0, g1, g2 = (
                        q0[0, lane] - q1[0, lane],
                        q0[1, lane] - q1[1, lane],
                        q0[2, lane] - q1[2, lane],
                    )
                    distance[lane] = (g0 * g0 + g1 * g1) + g2 * g2
                for lane in range(lanes):
                    gap2[lane] = max(gap2[lane], distance[lane])
                for lane in range(lanes):
                    top[lane] = max(top[lane], pseudo[k, lane]) if usable[k, lane] else top[lane]
                for lane in range(lanes):
                    bottom[lane] = (
                        min(bottom[lane], pseudo[k, lane]) if usable[k, lane] else bottom[lane]
                    )
            for k in range(samples):
                for lane in range(lanes):
                    candidate[k, lane] = usable[k, lane] & (
                        (pseudo[k, lane] >= top[lane] * (1.0 - rtol))
                        | (pseudo[k, lane] <= bottom[lane] * (1.0 + rtol))
                    )
            for lane in range(stop - first):
                e = order[first + lane]
                best, best_at, low = 0.0, 0, np.inf
                for k in range(samples):
                    if candidate[k, lane]:
                        value = np.degrees(np.arctan2(y[k, lane], x[k, lane]))
                        if value > best:
                            best, best_at = value, k
                        low = min(low, value)
                angle[e], worst[e], least[e], gap[e] = best, best_at, low, np.sqrt(gap2[lane])
