"""The sharp features a mesh's tags ask for, per item of its quad topology (:class:`Features`,
from :func:`features_from_tags`): sharpness per edge and vertex, holes, the boundary rule and the
crease method, with OpenSubdiv's semantics."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ..errors import MeshError
from .cage import PolygonTopology
from .tags import INFINITE_SHARPNESS, Tag
from .topology import QuadTopology

__all__ = ["BOUNDARY_RULES", "CREASE_METHODS", "Features", "features_from_tags"]

FloatArray = NDArray[np.float64]

#: the boundary rules of the ``interpolateboundary`` tag, by its integer (OpenSubdiv's numbering)
BOUNDARY_RULES = ("none", "edge-only", "edge-and-corner")
CREASE_METHODS = ("normal", "chaikin")


def _read_only(array: np.ndarray) -> np.ndarray:
    array.flags.writeable = False
    return array


@dataclass(frozen=True, eq=False)
class Features:
    """The sharp features a mesh's tags ask for, OpenSubdiv's semantics, per topology item.

    * ``edge_sharpness`` (E,), in ``QuadTopology.edges`` order, and ``vertex_sharpness`` (V,):
      0 smooth, ≥ :data:`INFINITE_SHARPNESS` infinitely sharp, in between semi-sharp (sharp for
      that many subdivision levels, then smooth);
    * ``holes`` (F,): faces that get no surface (their edges bound it);
    * ``boundary``: the ``interpolateboundary`` rule, ``none`` / ``edge-only`` /
      ``edge-and-corner`` (default ``edge-only``);
    * ``crease_method``: ``normal`` or ``chaikin`` (the ``creasemethod`` tag).
    """

    edge_sharpness: FloatArray
    vertex_sharpness: FloatArray
    holes: NDArray[np.bool_]
    boundary: str = "edge-only"
    crease_method: str = "normal"

    def __post_init__(self) -> None:
        for name in ("edge_sharpness", "vertex_sharpness", "holes"):
            _read_only(getattr(self, name))

    @classmethod
    def smooth(cls, topology: QuadTopology) -> Features:
        """No sharp edge or vertex, no hole, edge-only boundary."""
        return cls(
            np.zeros(topology.n_edges),
            np.zeros(topology.n_vertices),
            np.zeros(topology.n_faces, dtype=bool),
        )

    @property
    def sharp_edges(self) -> NDArray[np.bool_]:
        """Edges tagged infinitely sharp (boundary edges not included)."""
        return self.edge_sharpness >= INFINITE_SHARPNESS

    @property
    def corner_vertices(self) -> NDArray[np.bool_]:
        """Vertices tagged infinitely sharp (``t corner`` ≥ 10)."""
        return self.vertex_sharpness >= INFINITE_SHARPNESS

    @property
    def is_semi_sharp(self) -> bool:
        """Whether any edge or vertex has a sharpness strictly between 0 and infinite."""
        values = np.concatenate([self.edge_sharpness, self.vertex_sharpness])
        return bool(((values > 0) & (values < INFINITE_SHARPNESS)).any())

    @property
    def is_smooth(self) -> bool:
        """No sharpness anywhere and no hole (the boundary rule aside)."""
        return not (self.edge_sharpness.any() or self.vertex_sharpness.any() or self.holes.any())


def _tag_values(tag: Tag, count: int) -> FloatArray:
    """One sharpness per item: the tag's floats, or its one float for all of them (10 if it has
    none)."""
    floats = np.asarray(tag.floats, dtype=np.float64)
    if floats.size == count:
        values = floats
    elif floats.size <= 1:
        values = np.full(count, floats[0] if floats.size else INFINITE_SHARPNESS)
    else:
        raise MeshError(
            f"tag {tag.name!r} has {count} items but {floats.size} sharpness values; expected 1 "
            f"or {count}"
        )
    bad = np.flatnonzero(~np.isfinite(values) | (values < 0))
    if bad.size:
        raise MeshError(
            f"tag {tag.name!r} has sharpness {values[bad[0]]:g}; a sharpness is a finite number ≥ 0"
        )
    return values


def features_from_tags(topology: QuadTopology | PolygonTopology, tags: Sequence[Tag]) -> Features:
    """The :class:`Features` of OpenSubdiv tags on ``topology``: ``crease`` (vertex pairs, one
    sharpness each or one for all), ``corner`` (vertices), ``hole`` (faces), ``interpolateboundary``
    (0/1/2) and ``creasemethod`` (``normal``/``chaikin``); repeated items keep their largest
    sharpness, other tags are ignored. A crease pair that is not an edge raises
    :class:`MeshError`."""
    nv = topology.n_vertices
    edge_keys = topology.edges[:, 0] * nv + topology.edges[:, 1]
    edge = np.zeros(topology.n_edges)
    vertex = np.zeros(nv)
    holes = np.zeros(topology.n_faces, dtype=bool)
    boundary, method = "edge-only", "normal"
    for tag in tags:
        ints = np.asarray(tag.ints, dtype=np.int64)
        if tag.name == "crease":
            a, b = ints[0::2], ints[1::2]
            keys = np.minimum(a, b) * nv + np.maximum(a, b)
            found = np.minimum(np.searchsorted(edge_keys, keys), max(edge_keys.size - 1, 0))
            missing = np.flatnonzero(edge_keys[found] != keys)
            if missing.size:
                raise MeshError(
                    f"tag 'crease' names ({a[missing[0]]}, {b[missing[0]]}), which is not an edge"
                )
            np.maximum.at(edge, found, _tag_values(tag, a.size))
        elif tag.name == "corner":
            np.maximum.at(vertex, ints, _tag_values(tag, ints.size))
        elif tag.name == "hole":
            holes[ints] = True
        elif tag.name == "interpolateboundary" and ints.size:
            if not 0 <= ints[0] < len(BOUNDARY_RULES):
                raise MeshError(
                    f"tag 'interpolateboundary' has value {ints[0]}; expected 0, 1 or 2"
                )
            boundary = BOUNDARY_RULES[ints[0]]
        elif tag.name == "creasemethod" and tag.strings:
            if tag.strings[0] not in CREASE_METHODS:
                raise MeshError(
                    f"tag 'creasemethod' has value {tag.strings[0]!r}; expected 'normal' or "
                    "'chaikin'"
                )
            method = tag.strings[0]
    return Features(edge, vertex, holes, boundary, method)
