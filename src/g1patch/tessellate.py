"""Watertight triangle meshes from patch networks.

Every patch is sampled on the same uniform ``r × r`` grid. Points on a shared corner or edge
get one index for all patches that touch them (edge samples are numbered in the edge's
canonical direction), so the triangle mesh has no cracks by construction: on a closed network
every triangle edge has exactly two triangles. Samples on a collapsed edge all become the
corner point, and the triangles that lose an area there are dropped.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from .errors import InputError
from .network import PatchNetwork

__all__ = ["TriangleMesh", "tessellate"]


@dataclass(frozen=True)
class TriangleMesh:
    """Points (P, 3), unit normals (P, 3) and counter-clockwise triangles (T, 3)."""

    points: NDArray[np.float64]
    normals: NDArray[np.float64]
    triangles: NDArray[np.int64]


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


def tessellate(network: PatchNetwork, resolution: int = 17) -> TriangleMesh:
    """Sample every patch on a ``resolution × resolution`` grid and weld shared samples.

    Triangles are ordered like the parameter domain (u, v counter-clockwise), so their normals
    agree with ``p_u × p_v``. Points that no triangle uses (collapsed edge samples) are removed.
    """
    if not isinstance(resolution, (int, np.integer)) or resolution < 2:
        raise InputError(f"resolution: expected an integer ≥ 2, got {resolution!r}")
    r = int(resolution)
    grid = np.linspace(0.0, 1.0, r)
    positions = network.patches.evaluate_grid(grid, grid)
    normals = np.cross(network.patches.evaluate_grid(grid, grid, 1, 0), network.patches.evaluate_grid(grid, grid, 0, 1))
    index, total = _grid_indices(network, r)

    points = np.zeros((total, 3))
    point_normals = np.zeros((total, 3))
    flat_index = index.reshape(-1)
    points[flat_index] = positions.reshape(-1, 3)
    np.add.at(point_normals, flat_index, normals.reshape(-1, 3))

    a, b = np.meshgrid(np.arange(r - 1), np.arange(r - 1), indexing="ij")
    p00, p10 = index[:, a, b], index[:, a + 1, b]
    p11, p01 = index[:, a + 1, b + 1], index[:, a, b + 1]
    triangles = np.concatenate(
        [np.stack([p00, p10, p11], axis=-1).reshape(-1, 3), np.stack([p00, p11, p01], axis=-1).reshape(-1, 3)]
    )
    keep = (triangles[:, 0] != triangles[:, 1]) & (triangles[:, 1] != triangles[:, 2]) & (triangles[:, 0] != triangles[:, 2])
    triangles = triangles[keep]

    used = np.zeros(total, dtype=bool)
    used[triangles.reshape(-1)] = True
    renumber = np.cumsum(used) - 1
    length = np.linalg.norm(point_normals[used], axis=-1, keepdims=True)
    unit_normals = np.divide(point_normals[used], length, out=np.zeros_like(point_normals[used]), where=length > 0)
    return TriangleMesh(points[used], unit_normals, renumber[triangles])
