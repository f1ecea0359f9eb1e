"""Watertight triangle meshes from patch networks, in bounded size.

Every patch is sampled on the same uniform ``r × r`` grid, ``2 (r − 1)²`` triangles a patch.
Without a resolution, ``r`` follows :data:`TRIANGLE_BUDGET` (about 2 M triangles in all:
:func:`choose_resolution`, at most :data:`DEFAULT_RESOLUTION` and at least 2 samples a side, so
only a network of more than a million patches exceeds it); an explicit resolution that would make
more than :data:`MAX_TRIANGLES` triangles needs ``force=True`` (:func:`check_size`).

Points on a shared corner or edge get one index for all patches that touch them (edge samples are
numbered in the edge's canonical direction), so the triangle mesh has no cracks by construction: on
a closed network every triangle edge has exactly two triangles. Samples on a collapsed edge all
become the corner point, and the triangles that lose an area there are dropped.

**Hanging edges** (a coarse patch edge against finer ones, :class:`~g1patch.network.HangingEdges`)
stay watertight too: a fine edge sample at a coarse sample's parameter *is* that sample (the spans
are dyadic, so the fine samples land on every coarse one exactly), and each coarse boundary
triangle whose edge has fine samples inside it becomes a fan through them
(:func:`_hanging_fans`).

**Texture coordinates.** A network with :attr:`~g1patch.network.PatchNetwork.uv` gets them per
sample, bilinear in each patch's corner UVs, as face-varying data: one UV vertex per distinct
(point, UV) pair (:attr:`TriangleMesh.uv`, ``uv_points``, ``uv_triangles``), so a point on a seam
in UV space has one UV per side and the geometry stays welded. Edge samples are interpolated in
the edge's canonical direction, ``(1 − s) A + s B``, so two patches that agree on an edge's end
UVs give bit-identical UVs along it and share its UV vertices.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from .errors import InputError
from .mesh.groups import FaceGroups
from .network import PatchNetwork

__all__ = [
    "DEFAULT_RESOLUTION",
    "MAX_TRIANGLES",
    "TRIANGLE_BUDGET",
    "TooLargeError",
    "TriangleMesh",
    "check_file_size",
    "check_size",
    "choose_resolution",
    "estimated_memory",
    "tessellate",
    "triangle_count",
]

#: triangles a tessellation without an explicit resolution aims at (all patches together)
TRIANGLE_BUDGET = 2_000_000
#: the resolution chosen for small networks (the budget would allow more): the old default
DEFAULT_RESOLUTION = 17
#: an explicit resolution making more triangles than this needs ``force`` (about 2 GB of memory
#: and a 1.1 GB OBJ file)
MAX_TRIANGLES = 20_000_000
#: peak bytes of memory per triangle of :func:`tessellate` and the mesh writers, rounded up
#: (measured with tracemalloc on Spot split4 at resolution 17, 6 M triangles: 77 for OBJ and STL,
#: 88 for PLY)
BYTES_PER_TRIANGLE = 100
#: samples per block of patch evaluation
_BLOCK_SAMPLES = 1 << 18


@dataclass(frozen=True)
class TriangleMesh:
    """Points (P, 3), unit normals (P, 3) and counter-clockwise triangles (T, 3); with texture
    coordinates, ``uv`` (K, 2), the point of each (``uv_points`` (K,)) and the triangles' UV
    vertices ``uv_triangles`` (T, 3): ``points[uv_points[uv_triangles]] == points[triangles]``;
    with face groups, ``groups`` over the triangles (each its patch's group)."""

    points: NDArray[np.float64]
    normals: NDArray[np.float64]
    triangles: NDArray[np.int64]
    uv: NDArray[np.float64] | None = None
    uv_points: NDArray[np.int64] | None = None
    uv_triangles: NDArray[np.int64] | None = None
    groups: FaceGroups | None = None


def _grid_indices(network: PatchNetwork, resolution: int) -> tuple[NDArray[np.int64], int]:
    """Global point index of every grid sample, shape (N, r, r), and the number of points."""
    r = resolution
    count = network.n_patches
    inner = r - 2
    n_corners = network.n_corners
    edge_base = n_corners
    face_base = edge_base + network.n_edges * inner
    index = np.empty((count, r, r), dtype=np.int64)
    index[:, 1:-1, 1:-1] = face_base + np.arange(count * inner * inner).reshape(count, inner, inner)

    # Edge samples in counter-clockwise order s = 0..r-3, mapped to the canonical order.
    s = np.arange(inner)
    canonical = np.where(network.edge_reversed[:, :, None], inner - 1 - s, s)  # (N, 4, inner)
    edge_samples = edge_base + network.edge_ids[:, :, None] * inner + canonical
    collapsed = network.edge_collapsed[network.edge_ids]
    edge_samples = np.where(collapsed[:, :, None], network.corner_ids[:, :, None], edge_samples)
    index[:, 1:-1, 0] = edge_samples[:, 0]
    index[:, -1, 1:-1] = edge_samples[:, 1]
    index[:, -2:0:-1, -1] = edge_samples[:, 2]
    index[:, 0, -2:0:-1] = edge_samples[:, 3]
    index[:, 0, 0], index[:, -1, 0] = network.corner_ids[:, 0], network.corner_ids[:, 1]
    index[:, -1, -1], index[:, 0, -1] = network.corner_ids[:, 2], network.corner_ids[:, 3]
    return index, face_base + count * inner * inner


def _edge_grid(
    edge: NDArray[np.int64], m: NDArray[np.int64], r: int
) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
    """Grid position (i, j) of the counter-clockwise sample ``m`` of patch edge ``edge``: edge 0
    at (m, 0), 1 at (r − 1, m), 2 at (r − 1 − m, r − 1), 3 at (0, r − 1 − m)."""
    cases = [edge == 0, edge == 1, edge == 2]
    i = np.select(cases, [m, r - 1 + 0 * m, r - 1 - m], 0 * m)
    j = np.select(cases, [0 * m, m, r - 1 + 0 * m], r - 1 - m)
    return i, j


@dataclass(frozen=True)
class _Fans:
    """The hanging edges' part of a tessellation at ``r`` samples a side. ``alias`` (A, 2, 3):
    (patch, i, j) of a fine sample and of the coarse sample at the same point. Fans: ``triangle``
    (G,) the flat ids of the coarse triangles to replace (``which · N · cells + patch · cells +
    cell``), ``apex`` (G,) the corner of each opposite its hanging edge, and ``member`` (X, 3) the
    (patch, i, j) of the fine samples inside each, ``group`` (X,) its fan, sorted along the coarse
    edge."""

    alias: NDArray[np.int64]
    triangle: NDArray[np.int64]
    apex: NDArray[np.int64]
    member: NDArray[np.int64]
    group: NDArray[np.int64]


def _hanging_fans(network: PatchNetwork, r: int) -> _Fans | None:
    """Where the fine samples of each hanging edge fall on its coarse edge: at coarse sample
    ``n`` exactly (an alias) or inside segment ``n`` (a member of the fan replacing the coarse
    triangle on it). Fine sample m sits at ``t0 (r − 1) + m (t1 − t0)`` coarse samples along."""
    hanging = network.hanging
    if hanging is None or not len(hanging):
        return None
    fine, fine_edge, coarse, coarse_edge = (column[:, None] for column in hanging.sides.T)
    m = np.arange(r)[None, :]
    position = hanging.span[:, :1] * (r - 1) + m * (hanging.span[:, 1:] - hanging.span[:, :1])
    n = np.minimum(np.floor(position).astype(np.int64), r - 1)
    on = position == n
    fi, fj = _edge_grid(fine_edge, m + 0 * fine, r)
    ci, cj = _edge_grid(coarse_edge, n, r)
    fine_at = np.stack(np.broadcast_arrays(fine, fi, fj), axis=-1)  # (H, r, 3)
    coarse_at = np.stack(np.broadcast_arrays(coarse, ci, cj), axis=-1)
    alias = np.stack([fine_at[on], coarse_at[on]], axis=1)
    inside = ~on
    edge, segment = np.broadcast_to(coarse_edge, n.shape)[inside], n[inside]
    # the coarse triangle on segment n of edge k (module docstring of the grid): its cell, which
    # of the cell's two triangles, and the corner where the edge starts
    cases = [edge == 0, edge == 1, edge == 2]
    zero = 0 * segment
    cell_i = np.select(cases, [segment, r - 2 + zero, r - 2 - segment], zero)
    cell_j = np.select(cases, [zero, segment, r - 2 + zero], r - 2 - segment)
    which = (edge >= 2).astype(np.int64)
    start = np.array([0, 1, 1, 2])[edge]
    cells = (r - 1) ** 2
    patch = np.broadcast_to(coarse, n.shape)[inside]
    triangle = which * network.n_patches * cells + patch * cells + cell_i * (r - 1) + cell_j
    # one member per point (two fine edges meeting inside a segment both hold their corner)
    keys = np.column_stack([triangle, position[inside]])
    _, first = np.unique(keys, axis=0, return_index=True)  # sorted by triangle, then position
    member = fine_at[inside][first]
    triangles, group = np.unique(triangle[first], return_inverse=True)
    apex = start[first][np.r_[0, np.flatnonzero(np.diff(group)) + 1]]
    return _Fans(alias, triangles, (apex + 2) % 3, member, group.reshape(-1))


def _fan_triangles(
    fans: _Fans, triangles: NDArray[np.int64], member_ids: NDArray[np.int64]
) -> NDArray[np.int64]:
    """The fans replacing ``triangles[fans.triangle]`` (rows ``(A, B, O)`` up to rotation, A→B
    the hanging edge): ``(A, X1, O), (X1, X2, O), …, (Xc, B, O)`` through the members' ids."""
    base = triangles[fans.triangle]
    rows = np.arange(len(base))
    apex = base[rows, fans.apex]
    start = base[rows, (fans.apex + 1) % 3]
    end = base[rows, (fans.apex + 2) % 3]
    first = np.r_[True, np.diff(fans.group) != 0]
    last = np.r_[np.diff(fans.group) != 0, True]
    previous = np.where(first, start[fans.group], np.roll(member_ids, 1))
    inner = np.column_stack([previous, member_ids, apex[fans.group]])
    closing = np.column_stack([member_ids[last], end, apex])
    return np.concatenate([inner, closing])


def _aliased(index: NDArray[np.int64], total: int, alias: NDArray[np.int64]) -> NDArray[np.int64]:
    """``index`` with every fine sample of ``alias`` (A, 2, 3) renamed to its coarse sample (a
    coarse sample may itself be the fine side of a coarser edge: followed to the end)."""
    rename = np.arange(total)
    fine, coarse = alias[:, 0], alias[:, 1]
    rename[index[fine[:, 0], fine[:, 1], fine[:, 2]]] = index[
        coarse[:, 0], coarse[:, 1], coarse[:, 2]
    ]
    while True:
        further = rename[rename]
        if np.array_equal(further, rename):
            return rename[index]
        rename = further


def _uv_grid(
    uv: NDArray[np.float64], reversed_: NDArray[np.bool_], grid: NDArray[np.float64]
) -> NDArray[np.float64]:
    """UVs (N, r, r, 2) of every grid sample: inside, bilinear ``(1−s)(1−t) c_0 + s(1−t) c_1 +
    s t c_2 + (1−s) t c_3``; on edge k, ``(1 − s) A + s B`` along its canonical direction (A, B
    the UVs of its canonical start and end), so neighbours agree bit for bit."""
    s, t = grid[:, None, None], grid[None, :, None]
    c = uv[:, :, None, None, :]
    out = (
        (1 - s) * (1 - t) * c[:, 0]
        + s * (1 - t) * c[:, 1]
        + s * t * c[:, 2]
        + (1 - s) * t * c[:, 3]
    )
    r = grid.size
    m = np.arange(r)
    rows = ((m, 0 * m), (0 * m + r - 1, m), (r - 1 - m, 0 * m + r - 1), (0 * m, r - 1 - m))
    for k, (i, j) in enumerate(rows):  # the 4 edges, counter-clockwise samples m = 0..r−1
        back = reversed_[:, k, None, None]
        first = np.where(back, uv[:, (k + 1) % 4, None], uv[:, k, None])
        last = np.where(back, uv[:, k, None], uv[:, (k + 1) % 4, None])
        along = np.where(back, grid[::-1][None, :, None], grid[None, :, None])
        out[:, i, j] = (1 - along) * first + along * last
    return out


def _uv_vertices(
    uv: NDArray[np.float64], point: NDArray[np.int64], corners: NDArray[np.int64]
) -> tuple[NDArray[np.float64], NDArray[np.int64], NDArray[np.int64]]:
    """The distinct (point, UV) pairs of the samples ``corners`` (T, 3) use: their UVs, points and
    the triangles over them."""
    used = np.unique(corners)
    keys = np.column_stack([point[used], (uv[used] + 0.0).view(np.int64)])  # -0.0 as 0.0
    _, first, inverse = np.unique(keys, axis=0, return_index=True, return_inverse=True)
    lookup = np.empty(point.size, dtype=np.int64)
    lookup[used] = inverse.reshape(-1)
    return uv[used[first]], point[used[first]], lookup[corners]


def triangle_count(n_patches: int, resolution: int) -> int:
    """Triangles of a tessellation of ``n_patches`` at ``resolution`` (an upper bound: collapsed
    edges drop some)."""
    return 2 * (int(resolution) - 1) ** 2 * int(n_patches)


def estimated_memory(n_patches: int, resolution: int) -> int:
    """Bytes of memory, about, that tessellating and writing ``n_patches`` at ``resolution``
    takes."""
    return BYTES_PER_TRIANGLE * triangle_count(n_patches, resolution)


def choose_resolution(n_patches: int, budget: int = TRIANGLE_BUDGET) -> int:
    """Samples per patch side r for about ``budget`` triangles: the largest r ≤
    :data:`DEFAULT_RESOLUTION` with ``2 (r − 1)² n_patches ≤ budget``, and at least 2.

    Spot split4 (11 712 patches): 10, 1.9 M triangles; the cube (6 patches): 17.
    """
    cells = budget / (2.0 * max(int(n_patches), 1))
    r = math.isqrt(max(int(cells), 0)) + 1
    return int(min(max(r, 2), DEFAULT_RESOLUTION))


def _size_text(count: float, unit: str = "") -> str:
    for scale, prefix in ((1e12, "T"), (1e9, "G"), (1e6, "M"), (1e3, "k")):
        if count >= scale:
            return f"{count / scale:.3g} {prefix}{unit}"
    return f"{count:.3g} {unit}".rstrip()


class TooLargeError(InputError):
    """A tessellation would exceed :data:`MAX_TRIANGLES` and was not forced."""


def samples_per_side(resolution: object, n_patches: int) -> int:
    """``resolution`` checked (an integer ≥ 2), or :func:`choose_resolution` where it is None."""
    if resolution is None:
        return choose_resolution(n_patches)
    if (
        isinstance(resolution, bool)
        or not isinstance(resolution, (int, np.integer))
        or resolution < 2
    ):
        raise InputError(f"resolution: expected an integer ≥ 2, got {resolution!r}")
    return int(resolution)


def check_size(
    n_patches: int, resolution: int, force: bool = False, max_triangles: int = MAX_TRIANGLES
) -> int:
    """The triangle count of ``n_patches`` at ``resolution``; raises :class:`TooLargeError` (an
    :class:`InputError`) with the size when it exceeds ``max_triangles`` and not ``force``."""
    triangles = triangle_count(n_patches, resolution)
    if triangles > max_triangles and not force:
        raise TooLargeError(
            f"resolution {resolution} on {n_patches} patches would make {_size_text(triangles)} "
            "triangles "
            f"(~{_size_text(estimated_memory(n_patches, resolution), 'B')} of memory), above the "
            "cap of "
            f"{_size_text(max_triangles)}; pass force=True or a lower resolution"
        )
    return triangles


def _estimated_file_size(
    suffix: str, n_points: int, n_triangles: int, textured: bool = False
) -> int:
    """Bytes of a triangle mesh file, about: OBJ ~60 bytes a point (shortest round-trip digits)
    and 3 indices a triangle, with texture coordinates ~40 bytes a ``vt`` and twice the indices;
    binary PLY 24 bytes a point (32 with ``s``, ``t``), 13 a triangle; binary STL 50 a
    triangle."""
    if suffix == ".obj":
        index = 3 * (len(str(max(n_points, 1))) + 1) * (2 if textured else 1) + 2
        return (100 if textured else 60) * n_points + index * n_triangles
    if suffix == ".ply":
        return (32 if textured else 24) * n_points + 13 * n_triangles
    return 84 + 50 * n_triangles


def check_file_size(
    n_patches: int, resolution: int, suffix: str, force: bool = False, textured: bool = False
) -> None:
    """Refuse (:class:`TooLargeError`) a triangle file of ``n_patches`` at an explicit
    ``resolution`` above :data:`MAX_TRIANGLES` triangles unless ``force``, saying how large the
    file (``textured``: with texture coordinates) and the memory would be and which resolution
    stays within the cap."""
    if resolution < 2:
        return  # tessellate names the bad resolution
    triangles = triangle_count(n_patches, resolution)
    if force or triangles <= MAX_TRIANGLES:
        return
    points = n_patches * (resolution - 1) ** 2
    largest = 1 + int((MAX_TRIANGLES / (2 * max(n_patches, 1))) ** 0.5)
    size = _size_text(_estimated_file_size(suffix, points, triangles, textured), "B")
    memory = _size_text(estimated_memory(n_patches, resolution), "B")
    raise TooLargeError(
        f"--resolution {resolution} on {n_patches} patches would write {_size_text(triangles)} "
        f"triangles (~{size}, ~{memory} of memory); use --force or a lower resolution "
        f"(at most {largest} stays within {_size_text(MAX_TRIANGLES)} triangles)"
    )


def tessellate(
    network: PatchNetwork, resolution: int | None = None, *, force: bool = False
) -> TriangleMesh:
    """Sample every patch on a ``resolution × resolution`` grid and weld shared samples.

    ``resolution`` None: :func:`choose_resolution` (about :data:`TRIANGLE_BUDGET` triangles). A
    resolution making more than :data:`MAX_TRIANGLES` triangles raises :class:`TooLargeError`
    unless ``force``. Triangles are ordered like the parameter domain (u, v counter-clockwise), so
    their normals agree with ``p_u × p_v``. Points that no triangle uses (collapsed edge samples)
    are removed. Patches are evaluated a block at a time, so the memory is the output's and a
    little more (:func:`estimated_memory`).
    """
    r = samples_per_side(resolution, network.n_patches)
    check_size(network.n_patches, r, force)
    grid = np.linspace(0.0, 1.0, r)
    index, total = _grid_indices(network, r)
    count = network.n_patches
    fans = _hanging_fans(network, r)
    if fans is not None:
        index = _aliased(index, total, fans.alias)

    points = np.zeros((total, 3))
    point_normals = np.zeros((total, 3))
    cells = (r - 1) ** 2
    a, b = (
        axis.reshape(-1) for axis in np.meshgrid(np.arange(r - 1), np.arange(r - 1), indexing="ij")
    )
    triangles: NDArray[np.int64] = np.empty((2, count, cells, 3), dtype=np.int64)
    step = max(1, _BLOCK_SAMPLES // (r * r))
    for start in range(0, count, step):
        block = slice(start, min(start + step, count))
        patches = network.patches.take(np.arange(block.start, block.stop))
        flat_index = index[block].reshape(-1)
        points[flat_index] = patches.evaluate_grid(grid, grid).reshape(-1, 3)
        normals = np.cross(
            patches.evaluate_grid(grid, grid, 1, 0), patches.evaluate_grid(grid, grid, 0, 1)
        )
        np.add.at(point_normals, flat_index, normals.reshape(-1, 3))
        p00, p10 = index[block, a, b], index[block, a + 1, b]
        p11, p01 = index[block, a + 1, b + 1], index[block, a, b + 1]
        first, second = triangles[0, block], triangles[1, block]
        first[..., 0], first[..., 1], first[..., 2] = p00, p10, p11
        second[..., 0], second[..., 1], second[..., 2] = p00, p11, p01
    sample_point = index.reshape(-1) if network.uv is not None else None
    triangles = triangles.reshape(-1, 3)
    keep = (
        (triangles[:, 0] != triangles[:, 1])
        & (triangles[:, 1] != triangles[:, 2])
        & (triangles[:, 0] != triangles[:, 2])
    )
    # each triangle's patch (flat id which · N · cells + patch · cells + cell), for the groups
    patch_of = (np.arange(len(triangles)) // cells) % count if network.groups is not None else None
    fan_points = fan_samples = None
    if fans is not None:
        member = fans.member
        fan_points = _fan_triangles(
            fans, triangles, index[member[:, 0], member[:, 1], member[:, 2]]
        )
        keep[fans.triangle] = False
    del index
    uv_parts = None
    if network.uv is not None and sample_point is not None:
        samples = np.arange(count * r * r).reshape(count, r, r)
        p00, p10 = samples[:, a, b], samples[:, a + 1, b]
        p11, p01 = samples[:, a + 1, b + 1], samples[:, a, b + 1]
        corners = np.stack(
            [np.stack([p00, p10, p11], axis=-1), np.stack([p00, p11, p01], axis=-1)]
        ).reshape(-1, 3)
        if fans is not None:
            member = fans.member
            fan_samples = _fan_triangles(
                fans, corners, (member[:, 0] * r + member[:, 1]) * r + member[:, 2]
            )
        corners = corners[keep]
        if fan_samples is not None:
            corners = np.concatenate([corners, fan_samples])
        uv_grid = _uv_grid(network.uv, network.edge_reversed, grid).reshape(-1, 2)
        uv_parts = _uv_vertices(uv_grid, sample_point, corners)
        del samples, corners, uv_grid, sample_point
    if not keep.all():
        triangles = triangles[keep]
    groups = None
    if network.groups is not None and patch_of is not None:
        patch_of = patch_of[keep]
        if fans is not None:  # a fan's triangles: the coarse triangle's patch
            coarse = (fans.triangle // cells) % count
            patch_of = np.concatenate([patch_of, coarse[fans.group], coarse])
        groups = network.groups.take(patch_of)
    del keep
    if fan_points is not None:
        triangles = np.concatenate([triangles, fan_points])

    used = np.zeros(total, dtype=bool)
    used[triangles.reshape(-1)] = True
    if not used.all():
        renumber = np.cumsum(used) - 1
        np.take(renumber, triangles, out=triangles)
        points, point_normals = points[used], point_normals[used]
        if uv_parts is not None:
            uv_parts = (uv_parts[0], renumber[uv_parts[1]], uv_parts[2])
        del renumber
    length = np.linalg.norm(point_normals, axis=-1, keepdims=True)
    np.divide(point_normals, length, out=point_normals, where=length > 0)
    point_normals[~(length > 0)[:, 0]] = 0.0
    if uv_parts is None:
        return TriangleMesh(points, point_normals, triangles, groups=groups)
    return TriangleMesh(points, point_normals, triangles, *uv_parts, groups=groups)
