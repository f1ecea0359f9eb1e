"""Corners in numba kernels: the box around the patch corners with their largest distance to the
mesh vertices (the compiled :func:`.sampling._diagonal` and vertex deviation), the corner normals,
and the largest angle between corner normals within a corner sector (the compiled
:func:`.edges._max_corner_angle`)."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ..network import PatchNetwork
from ..patches import CORNER_PARAMETERS
from .jit import _chunks, _compiled, _fma, _pair_angle, _serial, _sparse, _weights
from .sampling import position_entries

prange = range  # numba.prange once a kernel is compiled (:func:`.jit._bind`)

_PAIRWISE_SECTOR = 64
"""Sectors of at most this many corners compare all pairs of corner normals; larger ones only the
pairs of the vertices of their gnomonic convex hull (see :func:`_corner_kernel`)."""


def _corner_extent_compiled(
    points: NDArray[np.float64], vertices: NDArray[np.float64] | None, corner_ids: NDArray[np.int64]
) -> tuple[NDArray[np.float64], NDArray[np.float64], float]:
    """The low and high corner of the box around the patch corners (the first four points of
    ``points (N, M, 3)``: a Gregory patch's corners, or evaluated corners ``(N, 4, 3)``), and the
    largest squared distance ``(d₀² + d₁²) + d₂²`` of a corner to its vertex
    ``vertices[corner_ids]`` (0 without vertices), in one pass over the corners without copying
    them: what :func:`_diagonal` and ``np.linalg.norm(corners - vertices[ids], axis=-1)`` read (each
    coordinate's extremes are exact; the norm is monotone in its square, so its maximum is the root
    of the largest square)."""
    chunks = _chunks(len(points))
    low, high, far = np.empty((chunks, 3)), np.empty((chunks, 3)), np.empty(chunks)
    _compiled(_corner_extent_kernel)(
        points,
        np.zeros((0, 3)) if vertices is None else np.ascontiguousarray(vertices, dtype=np.float64),
        corner_ids,
        chunks,
        low,
        high,
        far,
    )
    return low.min(axis=0), high.max(axis=0), float(far.max())


def _corner_extent_kernel(
    points: NDArray[np.float64],
    vertices: NDArray[np.float64],
    corner_ids: NDArray[np.int64],
    chunks: int,
    low: NDArray[np.float64],
    high: NDArray[np.float64],
    far: NDArray[np.float64],
) -> None:
    """Per chunk of patches: each coordinate's least and greatest corner value and the largest
    squared distance of a corner to its vertex (NaN where one is NaN, as NumPy's extremes)."""
    patches, measure = points.shape[0], vertices.shape[0] > 0
    for chunk in prange(chunks):
        least, most = np.full(3, np.inf), np.full(3, -np.inf)
        farthest = 0.0
        for n in range(chunk * patches // chunks, (chunk + 1) * patches // chunks):
            for k in range(4):
                for d in range(3):
                    x = points[n, k, d]
                    if not np.isnan(least[d]) and (x < least[d] or np.isnan(x)):
                        least[d] = x
                    if not np.isnan(most[d]) and (x > most[d] or np.isnan(x)):
                        most[d] = x
                if measure:
                    vertex = corner_ids[n, k]
                    d0, d1, d2 = (
                        points[n, k, 0] - vertices[vertex, 0],
                        points[n, k, 1] - vertices[vertex, 1],
                        points[n, k, 2] - vertices[vertex, 2],
                    )
                    square = (d0 * d0 + d1 * d1) + d2 * d2
                    if not np.isnan(farthest) and (square > farthest or np.isnan(square)):
                        farthest = square
        low[chunk], high[chunk], far[chunk] = least, most, farthest


def _corner_normals_compiled(points: NDArray[np.float64], form: str) -> NDArray[np.float64]:
    """``p_u × p_v`` at the four corners of every patch, ``(N, 4, 3)`` (the reference's
    ``_cross3`` of ``evaluate(CORNER_PARAMETERS, 1, 0)`` and ``(0, 1)``, each patch's points less
    its first at the ``position`` entries, as there)."""
    table = np.stack(
        [_weights(form, CORNER_PARAMETERS[:, None], du, dv) for du, dv in ((1, 0), (0, 1))]
    )  # (2, 4, 1, M)
    weights, index, count = _sparse(table)  # (2, 4, M, 1)
    position = position_entries(form, points.shape[1])
    normals = np.empty((len(points), 4, 3))
    if len(points):
        _compiled(_corner_normal_kernel)(
            points, position, weights, index, count, _chunks(len(points)), normals
        )
    return normals


def _corner_normal_kernel(
    points: NDArray[np.float64],
    position: NDArray[np.bool_],
    weights: NDArray[np.float64],
    index: NDArray[np.int64],
    count: NDArray[np.int64],
    chunks: int,
    normals: NDArray[np.float64],
) -> None:
    """Corner normals patch by patch (``weights (derivative, corner, M, 1)``)."""
    patches = points.shape[0]
    for chunk in prange(chunks):
        tangent = np.empty((2, 3))
        for n in range(chunk * patches // chunks, (chunk + 1) * patches // chunks):
            for corner in range(4):
                for q in range(2):
                    for d in range(3):
                        acc = 0.0
                        for r in range(count[q, corner]):
                            m = index[q, corner, r]
                            value = (
                                points[n, m, d] - points[n, 0, d]
                                if position[m]
                                else points[n, m, d]
                            )
                            acc = _fma(value, weights[q, corner, m, 0], acc)
                        tangent[q, d] = acc
                a, b = tangent[0], tangent[1]
                normals[n, corner, 0] = a[1] * b[2] - a[2] * b[1]
                normals[n, corner, 1] = a[2] * b[0] - a[0] * b[2]
                normals[n, corner, 2] = a[0] * b[1] - a[1] * b[0]


def _max_corner_angle_compiled(
    network: PatchNetwork, normals: NDArray[np.float64], degenerate_level: float, oriented: bool
) -> float:
    """:func:`_max_corner_angle` from the corner normals ``(N, 4, 3)``, sector by sector in a
    kernel."""
    normals = normals.reshape(-1, 3)
    ids = network.corner_sectors().reshape(-1).astype(np.int64)
    if not len(ids):
        return 0.0
    # the corners by sector, in order within each (a counting sort: the stable argsort's
    # permutation; 4 M corners 0.1 s -> 0.03 s), and where each sector starts
    counts = np.bincount(ids)
    cursor = np.r_[0, np.cumsum(counts)[:-1]]
    starts = np.r_[cursor[counts > 0], len(ids)]
    order = np.empty(len(ids), dtype=np.int64)
    _serial(_counting_sort_kernel)(ids, cursor, order)
    worst = np.zeros(len(starts) - 1)
    _compiled(_corner_kernel)(
        normals,
        order,
        starts,
        degenerate_level,
        oriented,
        _PAIRWISE_SECTOR,
        _chunks(len(worst)),
        worst,
    )
    return float(worst.max(initial=0.0))


def _counting_sort_kernel(
    keys: NDArray[np.int64], cursor: NDArray[np.int64], order: NDArray[np.int64]
) -> None:
    """``order``: the items by key, in their order within a key (``cursor[k]``: where key k's first
    goes; advanced as items are placed). Serial: the placement is what makes it stable."""
    for item in range(keys.size):
        key = keys[item]
        order[cursor[key]] = item
        cursor[key] += 1


def _corner_kernel(
    normals: NDArray[np.float64],
    order: NDArray[np.int64],
    starts: NDArray[np.int64],
    level: float,
    oriented: bool,
    pairwise: int,
    chunks: int,
    worst: NDArray[np.float64],
) -> None:
    """Per sector (corners ``order[starts[s]:starts[s + 1]]``): the largest angle between two of its
    usable corner normals. Sectors of more than ``pairwise`` corners, oriented, whose normals lie in
    one open hemisphere around their mean m compare only the vertices of the convex hull of their
    gnomonic projections ``(n·e₁, n·e₂) / (n·m)`` (e₁, e₂ ⟂ m): great circles project to lines,
    and the angle to a point is quasi-convex along the arcs of a hemisphere, so the largest angle
    is between hull vertices (up to rounding). Work O(m log m + h²) for h hull vertices."""
    sectors = starts.size - 1
    for chunk in prange(chunks):
        for s in range(chunk * sectors // chunks, (chunk + 1) * sectors // chunks):
            members = order[starts[s] : starts[s + 1]]
            keep = np.empty(members.size, dtype=np.int64)
            kept = 0
            for corner in members:
                a = normals[corner]
                if np.sqrt((a[0] * a[0] + a[1] * a[1]) + a[2] * a[2]) > level:
                    keep[kept] = corner
                    kept += 1
            keep = keep[:kept]
            if kept > pairwise and oriented:
                keep = _hull_corners(normals, keep)
            best = 0.0
            for i in range(keep.size):
                for j in range(i + 1, keep.size):
                    best = max(best, _pair_angle(normals[keep[i]], normals[keep[j]], oriented))
            worst[s] = best


def _hull_corners(normals: NDArray[np.float64], corners: NDArray[np.int64]) -> NDArray[np.int64]:
    """The corners whose unit normals' gnomonic projections are vertices of their convex hull
    (Andrew's monotone chain), or all of them when some normal is not within 90° of the mean."""
    unit = np.empty((corners.size, 3))
    mean = np.zeros(3)
    for i in range(corners.size):
        a = normals[corners[i]]
        unit[i] = a / np.sqrt((a[0] * a[0] + a[1] * a[1]) + a[2] * a[2])
        mean += unit[i]
    mean /= np.sqrt((mean[0] * mean[0] + mean[1] * mean[1]) + mean[2] * mean[2])
    axis = np.zeros(3)
    axis[np.argmin(np.abs(mean))] = 1.0
    e1 = np.cross(mean, axis)
    e1 /= np.sqrt((e1[0] * e1[0] + e1[1] * e1[1]) + e1[2] * e1[2])
    e2 = np.cross(mean, e1)
    heights = unit @ mean
    if heights.min() <= 0.0:
        return corners
    px, py = (unit @ e1) / heights, (unit @ e2) / heights
    by_y = np.argsort(py, kind="mergesort")
    sort = by_y[np.argsort(px[by_y], kind="mergesort")]  # by x, then y
    hull = np.empty(2 * sort.size, dtype=np.int64)
    size = 0
    for sweep in range(2):
        base = size
        for step in range(sort.size):
            p = sort[step] if sweep == 0 else sort[sort.size - 1 - step]
            while size >= base + 2:
                a, b = hull[size - 2], hull[size - 1]
                if (px[b] - px[a]) * (py[p] - py[a]) - (py[b] - py[a]) * (px[p] - px[a]) > 0.0:
                    break
                size -= 1
            hull[size] = p
            size += 1
        size -= 1  # each chain's last point starts the other
    return corners[np.unique(hull[: max(size, 1)])]
