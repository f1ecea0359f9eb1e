"""Sharp edges by angle: tag the creases a CAD-like mesh has but does not say (``--sharp-angle``).

An edge shared by two polygons is *sharp* when the angle between their normals (the dihedral
angle's supplement: 0 on a flat region, 90° on a box edge) exceeds the threshold; a vertex with
three or more sharp edges is a *corner*. Both become OpenSubdiv tags (``crease`` with sharpness
10, ``corner`` with 10), so they follow the mesh through splitting, refinement and every shape
rule like tags read from a file. Polygon normals are Newell's, ``N = Σ p_i × p_{i+1}``, so a
non-planar quad gets its average plane.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from .errors import InputError
from .mesh import INFINITE_SHARPNESS, Tag, _edge_keys, _following_corner

__all__ = ["sharp_angle_tags"]


def _polygon_normals(
    vertices: NDArray[np.float64], corners: NDArray[np.int64], sizes: NDArray[np.int64]
) -> NDArray[np.float64]:
    """Unit Newell normals of polygons given as flat ``corners`` with ``sizes`` (zero where
    degenerate)."""
    here = vertices[corners]
    there = vertices[corners[_following_corner(sizes)]]
    face = np.repeat(np.arange(sizes.size), sizes)
    product = np.cross(here, there)
    total = np.stack(
        [np.bincount(face, product[:, d], minlength=sizes.size) for d in range(3)], axis=1
    )
    length = np.linalg.norm(total, axis=1, keepdims=True)
    return np.divide(total, length, out=np.zeros_like(total), where=length > 0)


def sharp_angle_tags(
    vertices: NDArray[np.float64],
    corners: NDArray[np.int64],
    sizes: NDArray[np.int64],
    degrees: float,
) -> tuple[Tag, ...]:
    """``crease`` tags for the edges whose two polygons' normals differ by more than ``degrees``,
    and a ``corner`` tag for the vertices with at least three of them (empty tuple if none).
    Edges with one or more than two polygons are left alone (boundary and repair handle them)."""
    if not (isinstance(degrees, (int, float)) and np.isfinite(degrees) and 0 < degrees < 180):
        raise InputError(f"sharp angle: expected degrees between 0 and 180, got {degrees!r}")
    nv = vertices.shape[0]
    normals = _polygon_normals(vertices, corners, sizes)
    keys = _edge_keys(corners, sizes, nv)
    face = np.repeat(np.arange(sizes.size), sizes)
    order = np.argsort(keys, kind="stable")
    sorted_keys = keys[order]
    first = np.flatnonzero(np.concatenate([[True], sorted_keys[1:] != sorted_keys[:-1]]))
    count = np.diff(np.append(first, keys.size))
    pair = first[count == 2]
    f0, f1 = face[order[pair]], face[order[pair + 1]]
    cosine = np.einsum("ij,ij->i", normals[f0], normals[f1])
    sharp = cosine < np.cos(np.radians(degrees))
    edge_keys = sorted_keys[pair[sharp]]
    if not edge_keys.size:
        return ()
    a, b = edge_keys // nv, edge_keys % nv
    tags = [Tag("crease", tuple(np.stack([a, b], axis=1).ravel().tolist()), (INFINITE_SHARPNESS,))]
    ends = np.bincount(np.concatenate([a, b]), minlength=nv)
    corner = np.flatnonzero(ends >= 3)
    if corner.size:
        tags.append(Tag("corner", tuple(corner.tolist()), (INFINITE_SHARPNESS,)))
    return tuple(tags)
