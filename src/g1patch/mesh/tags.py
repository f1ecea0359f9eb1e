"""OpenSubdiv tags: the :class:`Tag` record of a mesh file, which tags' integers name vertices and
which name faces, and how tags follow the polygons when unused vertices are dropped
(:func:`_renumber_tags`) or every face is split (:func:`_refine_tags`).

What the tags mean on a quad topology (sharpness per edge and vertex, holes, the boundary rule)
is :mod:`g1patch.mesh.features`.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from ..errors import MeshError
from .faces import _edge_keys

__all__ = ["FACE_TAGS", "INFINITE_SHARPNESS", "VERTEX_TAGS", "Tag"]

IntArray = NDArray[np.int64]

#: OpenSubdiv's infinitely sharp crease (``Sdc::Crease::SHARPNESS_INFINITE``): at or above it an
#: edge or vertex is sharp at every level of refinement
INFINITE_SHARPNESS = 10.0
#: OpenSubdiv tags whose integers are vertex indices, and those whose integers are face indices.
VERTEX_TAGS = frozenset({"crease", "corner"})
FACE_TAGS = frozenset({"hole"})


class Tag(NamedTuple):
    """An OpenSubdiv tag line ``t name nints/nfloats/nstrings ints… floats… strings…``."""

    name: str
    ints: tuple[int, ...] = ()
    floats: tuple[float, ...] = ()
    strings: tuple[str, ...] = ()


def _renumber_tags(tags: Sequence[Tag], new_index: IntArray) -> tuple[Tag, ...]:
    """Carry vertex tags through dropping unused vertices: ``new_index[old]``, -1 where dropped."""
    renumbered = []
    for tag in tags:
        if tag.name in VERTEX_TAGS:
            ints = new_index[np.asarray(tag.ints, dtype=np.int64)]
            if (ints < 0).any():
                raise MeshError(f"tag {tag.name!r} names a vertex that no face uses")
            tag = tag._replace(ints=tuple(ints.tolist()))
        renumbered.append(tag)
    return tuple(renumbered)


def _refine_tags(
    tags: Sequence[Tag], corners: IntArray, sizes: IntArray, n_vertices: int
) -> tuple[Tag, ...]:
    """Carry tags through :func:`~g1patch.mesh.refine_polygons`: crease (a, b) becomes (a, m),
    (m, b); a hole its quads."""
    edge_keys = np.unique(_edge_keys(corners, sizes, n_vertices))
    refined = []
    for tag in tags:
        ints = np.asarray(tag.ints, dtype=np.int64)
        if tag.name == "crease":
            a, b = ints[0::2], ints[1::2]
            keys = np.minimum(a, b) * n_vertices + np.maximum(a, b)
            m = np.minimum(np.searchsorted(edge_keys, keys), edge_keys.size - 1)
            missing = np.flatnonzero(edge_keys[m] != keys)
            if missing.size:
                raise MeshError(
                    f"tag 'crease' names ({a[missing[0]]}, {b[missing[0]]}), which is not an edge"
                )
            m += n_vertices
            tag = tag._replace(ints=tuple(np.stack([a, m, m, b], axis=1).ravel().tolist()))
            if len(tag.floats) == a.size > 1:  # one sharpness per edge
                tag = tag._replace(floats=tuple(np.repeat(tag.floats, 2).tolist()))
        elif tag.name in FACE_TAGS:
            quads_of_holes = np.isin(np.repeat(np.arange(sizes.size), sizes), ints)
            tag = tag._replace(ints=tuple(np.flatnonzero(quads_of_holes).tolist()))
        refined.append(tag)
    return tuple(refined)
