"""Quad meshes: positions on a :class:`~g1patch.mesh.QuadTopology` with the tags of their file
(:class:`QuadMesh`), built from any polygons by :meth:`QuadMesh.from_arrays` (checked, non-quads
split, repaired unless strict: :func:`strict_meshes`), and :func:`subdivide`.
"""

from __future__ import annotations

import logging
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from contextvars import ContextVar
from dataclasses import dataclass
from functools import cached_property

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..display import bbox_text, picture, short_source
from ..errors import (
    DegenerateFaceError,
    InputError,
    NonManifoldError,
    OrientationError,
    ValenceError,
    as_float_array,
    named_errors,
)
from .cage import PolygonCage
from .features import Features, _read_only, features_from_tags
from .groups import FaceGroups
from .polygons import _quads_from_polygons, refine_corner_uvs, refine_polygons
from .repair import repair_polygons
from .tags import Tag, _refine_tags
from .topology import QuadTopology
from .validate import _check_face_areas, _check_finite, _checked_polygons

__all__ = ["REPAIRABLE", "UV_DROPPED", "QuadMesh", "strict_meshes", "subdivide"]

logger = logging.getLogger(__name__)

IntArray = NDArray[np.int64]
FloatArray = NDArray[np.float64]

#: what :meth:`QuadMesh.from_arrays` repairs unless strict (:mod:`g1patch.mesh.repair`)
REPAIRABLE = (DegenerateFaceError, NonManifoldError, OrientationError, ValenceError)

#: the repair note when texture coordinates cannot follow a repair (faces merged)
UV_DROPPED = "texture coordinates (vt) dropped: faces were merged, their UVs cannot follow"

_STRICT: ContextVar[bool] = ContextVar("g1patch_strict_meshes", default=False)


@contextmanager
def strict_meshes(strict: bool = True) -> Iterator[None]:
    """Within the block, :meth:`QuadMesh.from_arrays` calls that do not pass ``strict`` use this
    one: for callers that cannot pass it on, such as :func:`~g1patch.io.meshfile.read_mesh`."""
    token = _STRICT.set(strict)
    try:
        yield
    finally:
        _STRICT.reset(token)


@dataclass(frozen=True, eq=False)
class QuadMesh:
    """Positions ``vertices`` (nv, 3) on a :class:`~g1patch.mesh.QuadTopology`, with the OpenSubdiv
    tags of its file.

    Validated on construction: finite coordinates, and no face of zero area
    (:data:`DEGENERATE_AREA_TOLERANCE`). ``repairs`` names what :meth:`from_arrays` repaired
    (short phrases, :attr:`repair_note` joins them), empty if nothing. ``cage``: the polygons
    :meth:`from_arrays` split into these quads (:class:`~g1patch.mesh.cage.PolygonCage`), where
    some face was not a quad; the limit shapes take their first Catmull–Clark step from it
    (:func:`g1patch.subdivision.catmull_clark_cage`). New positions (:meth:`with_vertices`) drop it.
    ``uv``: texture coordinates per face corner (F, 4, 2), face-varying (a vertex may have other
    UVs in other faces: a seam in UV space), the file's ``vt``; None without. ``groups``: each
    face's named group (:class:`~g1patch.mesh.groups.FaceGroups`, the file's materials or
    groups); None without.
    """

    vertices: FloatArray
    topology: QuadTopology
    tags: tuple[Tag, ...] = ()
    source: str | None = None
    repairs: tuple[str, ...] = ()
    cage: PolygonCage | None = None
    uv: FloatArray | None = None
    groups: FaceGroups | None = None

    def __post_init__(self) -> None:
        with named_errors(self.source):
            vertices = as_float_array("vertices", self.vertices, (3,), finite=False)
            if vertices.shape != (self.topology.n_vertices, 3):
                raise InputError(
                    f"vertices: expected shape ({self.topology.n_vertices}, 3) for this topology, "
                    f"got {vertices.shape}"
                )
            _check_finite(vertices)
            _check_face_areas(vertices, self.topology.faces)
            if self.uv is not None:
                uv = _checked_uv(self.uv, (self.topology.n_faces, 4, 2))
                object.__setattr__(self, "uv", _read_only(uv.copy()))
            if self.groups is not None and len(self.groups) != self.topology.n_faces:
                raise InputError(
                    f"groups: expected one per face ({self.topology.n_faces}), got "
                    f"{len(self.groups)}"
                )
        object.__setattr__(self, "vertices", _read_only(vertices.copy()))
        object.__setattr__(self, "tags", tuple(Tag(*tag) for tag in self.tags))
        object.__setattr__(self, "repairs", tuple(self.repairs))

    @classmethod
    def from_arrays(
        cls,
        vertices: ArrayLike,
        faces: ArrayLike | Sequence[Sequence[int]],
        *,
        split: bool = True,
        source: str | None = None,
        tags: Sequence[Tag] = (),
        strict: bool | None = None,
        uv: ArrayLike | None = None,
        groups: FaceGroups | None = None,
    ) -> QuadMesh:
        """Validate and build a quad mesh from positions and faces ((nf, 4) array or lists of
        indices).

        Unused vertices are dropped (one ``logging`` info line). If any face has 3 or ≥ 5 corners
        the whole mesh is refined once (:func:`refine_polygons`, new points on a smooth surface
        through the vertices) with ``split``, else a :class:`MeshError` is raised. A mesh the
        checks refuse (:data:`REPAIRABLE`: repeated vertices, non-manifold edges or vertices,
        inconsistent orientation, interior valence 2) is repaired
        (:func:`g1patch.mesh.repair.repair_polygons`, one info line, the repairs kept in
        :attr:`repairs`), unless ``strict`` (default: the one of :func:`strict_meshes`, else False),
        which raises the check's error. Non-finite coordinates, out-of-range indices, faces of < 3
        corners, zero area and non-orientable components raise either way. Errors name ``source`` (a
        file name) when given. ``uv`` (one per face corner) and ``groups`` (one per face) follow
        the split and the repairs: a split face's quads keep its group, a merged face the group
        of the first of its faces.
        """
        strict = _STRICT.get() if strict is None else strict
        tags = tuple(Tag(*tag) for tag in tags)
        repairs: tuple[str, ...] = ()
        with named_errors(source):
            points, corners, sizes = _checked_polygons(vertices, faces, tags)
            corner_uv = None if uv is None else _checked_uv(uv, (corners.size, 2))
            if groups is not None and len(groups) != sizes.size:
                raise InputError(f"groups: expected one per face ({sizes.size}), got {len(groups)}")
            try:
                quad_points, quads, quad_tags, cage, quad_uv = _quads_from_polygons(
                    points, corners, sizes, split, source, tags, corner_uv
                )
                topology = QuadTopology.from_faces(quads, quad_points.shape[0])
            except REPAIRABLE as refusal:
                if strict:
                    raise
                repaired = repair_polygons(points, corners, sizes, tags)
                if not repaired.repairs:
                    raise refusal
                repairs = repaired.repairs
                if corner_uv is not None and repaired.corner_source is not None:
                    if repaired.merged:
                        corner_uv = None
                        repairs += (UV_DROPPED,)
                    else:
                        corner_uv = corner_uv[repaired.corner_source]
                if groups is not None and repaired.face_source is not None:
                    groups = groups.take(repaired.face_source)
                logger.info("%s: repaired: %s", source or "mesh", ", ".join(repairs))
                quad_points, quads, quad_tags, cage, quad_uv = _quads_from_polygons(
                    repaired.points,
                    repaired.corners,
                    repaired.sizes,
                    split,
                    source,
                    repaired.tags,
                    corner_uv,
                )
                topology = QuadTopology.from_faces(quads, quad_points.shape[0])
            if groups is not None and cage is not None:  # polygon f split into sizes[f] quads
                groups = groups.repeat(cage.sizes)
        return cls(quad_points, topology, quad_tags, source, repairs, cage, quad_uv, groups)

    def __repr__(self) -> str:
        """``<QuadMesh 8 vertices, 6 quads, 12 edges, closed, bbox (-1, -1, -1)…(1, 1, 1),
        cube.obj>``: counts, tags, repairs, the box and the file name, never the arrays."""
        parts = [self.topology._counts()]
        if self.tags:
            parts.append("tags " + " ".join(dict.fromkeys(tag.name for tag in self.tags)))
        if self.repairs:
            parts.append("repaired")
        parts.append(bbox_text(*self.bounding_box))
        if self.source:
            parts.append(short_source(self.source))
        return f"<QuadMesh {', '.join(parts)}>"

    def _repr_png_(self) -> bytes | None:
        """A small flat-shaded picture of the quads for Jupyter (None above
        :data:`g1patch.display.PREVIEW_MAX_PATCHES` faces)."""
        return picture("mesh", self, self.n_faces)

    def with_vertices(self, new_vertices: ArrayLike) -> QuadMesh:
        """The same topology, tags, repair record, UVs and groups with new positions (validated
        the same way)."""
        return QuadMesh(
            np.asarray(new_vertices),
            self.topology,
            self.tags,
            self.source,
            self.repairs,
            uv=self.uv,
            groups=self.groups,
        )

    @property
    def repair_note(self) -> str:
        """The repairs as one line, ``"repaired: 1 valence-2 vertex (137) dissolved, …"``; empty if
        none."""
        return "repaired: " + ", ".join(self.repairs) if self.repairs else ""

    @cached_property
    def features(self) -> Features:
        """Sharpness per edge and vertex, holes and boundary rule from the tags
        (:func:`features_from_tags`)."""
        with named_errors(self.source):
            return features_from_tags(self.topology, self.tags)

    @property
    def faces(self) -> IntArray:
        return self.topology.faces

    @property
    def n_vertices(self) -> int:
        return self.topology.n_vertices

    @property
    def n_faces(self) -> int:
        return self.topology.n_faces

    @property
    def n_edges(self) -> int:
        return self.topology.n_edges

    @property
    def bounding_box(self) -> tuple[FloatArray, FloatArray]:
        """(lowest, highest) corner of the axis-aligned box around the vertices."""
        return self.vertices.min(axis=0), self.vertices.max(axis=0)

    @property
    def bounding_box_diagonal(self) -> float:
        low, high = self.bounding_box
        return float(np.linalg.norm(high - low))


def subdivide(mesh: QuadMesh) -> QuadMesh:
    """One Catmull–Clark topology step with linear positions: 4 F quads on V + E + F vertices.

    Old vertices keep their indices, edge midpoints follow (in edge order), then face centroids
    (:func:`refine_polygons`). Crease and hole tags are carried over, UVs bilinearly
    (:func:`refine_corner_uvs`), groups to the 4 children of each face.
    """
    corners = mesh.faces.ravel()
    sizes = np.full(mesh.n_faces, 4, dtype=np.int64)
    vertices, quads, _ = refine_polygons(mesh.vertices, corners, sizes)
    tags = _refine_tags(mesh.tags, corners, sizes, mesh.n_vertices)
    uv = None if mesh.uv is None else refine_corner_uvs(mesh.uv.reshape(-1, 2), sizes)
    return QuadMesh(
        vertices,
        QuadTopology.from_faces(quads, vertices.shape[0]),
        tags,
        mesh.source,
        mesh.repairs,
        uv=uv,
        groups=None if mesh.groups is None else mesh.groups.repeat(4),
    )


def _checked_uv(uv: ArrayLike, shape: tuple[int, ...]) -> FloatArray:
    """Texture coordinates of the expected ``shape``, finite, as float64 (:class:`InputError`)."""
    array = as_float_array("uv", uv, shape[1:])
    if array.shape != shape:
        raise InputError(f"uv: expected shape {shape} (one per face corner), got {array.shape}")
    return array
