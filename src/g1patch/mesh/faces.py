"""Faces as flat arrays: ``corners`` (every face's vertex indices, one face after another) with
``sizes`` (corners per face), the form polygons of any size take on their way to quads.

Corner ``i`` runs to the next corner of its face; the edge between them is named by the key
``min·nv + max`` of its two vertices.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import cast

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InputError, as_index_array

IntArray = NDArray[np.int64]


def _as_polygons(faces: ArrayLike | Sequence[Sequence[int]]) -> tuple[IntArray, IntArray]:
    """Faces as flat ``corners`` and ``sizes``, from an (nf, n) array or a list of index lists."""
    try:
        table = np.asarray(faces)
    except ValueError:  # ragged: a list of lists of different lengths
        table = None
    if table is not None and table.dtype != object:
        table = as_index_array("faces", table, (None,))
        if table.ndim != 2:
            raise InputError(
                f"faces: expected shape (nf, n) or a list of index lists, got shape {table.shape}"
            )
        return table.ravel(), np.full(table.shape[0], table.shape[1], dtype=np.int64)
    rows = cast(Sequence[Sequence[int]], faces)  # ragged, or an array of objects
    try:
        sizes = np.fromiter(map(len, rows), dtype=np.int64)
        corners = np.fromiter(
            (int(v) for face in rows for v in face), dtype=np.int64, count=int(sizes.sum())
        )
    except (TypeError, ValueError) as exc:
        raise InputError(f"faces: expected a list of lists of vertex indices ({exc})") from None
    return corners, sizes


def _following_corner(sizes: IntArray) -> IntArray:
    """Index of the next corner in the same face, for flat corners with ``sizes`` per face."""
    offsets = np.cumsum(sizes)
    following = np.arange(1, int(offsets[-1]) + 1)
    following[offsets - 1] = offsets - sizes
    return following


def _edge_keys(corners: IntArray, sizes: IntArray, n_vertices: int) -> IntArray:
    """Undirected edge key ``min·nv + max`` of each corner's edge to the next corner."""
    target = corners[_following_corner(sizes)]
    return np.minimum(corners, target) * n_vertices + np.maximum(corners, target)
