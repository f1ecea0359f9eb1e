"""Quad meshes: topology as flat half-edge arrays, and meshes that pair it with positions.

:class:`QuadTopology` is built from faces alone (it never looks at positions), so one topology
serves many position sets; :class:`QuadMesh` adds the positions and the OpenSubdiv tags of its
file. :meth:`QuadMesh.from_arrays` is the way in from any polygons. The modules, bottom to top:

* :mod:`~g1patch.mesh.faces`: faces as flat ``corners`` with ``sizes``;
* :mod:`~g1patch.mesh.tags`: the :class:`Tag` record and how tags follow the polygons;
* :mod:`~g1patch.mesh.validate`: the checks no repair can mend (finite coordinates, index range,
  repeated vertices, face areas, tags);
* :mod:`~g1patch.mesh.connectivity`: half-edge connectivity of polygons and its checks
  (manifold edges and vertices, orientation, valence), with its compiled kernel;
* :mod:`~g1patch.mesh.topology`: :class:`QuadTopology`;
* :mod:`~g1patch.mesh.vertex_sectors`: the sectors of every vertex between seams;
* :mod:`~g1patch.mesh.features`: :class:`Features`, the sharpness and holes the tags ask for;
* :mod:`~g1patch.mesh.polygons`: the split of non-quad faces (:func:`refine_polygons`);
* :mod:`~g1patch.mesh.conforming`: local refinement that stays a quad mesh (no T-junctions);
* :mod:`~g1patch.mesh.repair`: repairs of meshes the checks would refuse;
* :mod:`~g1patch.mesh.quadmesh`: :class:`QuadMesh`, :func:`strict_meshes`, :func:`subdivide`.

Indices in error messages are 0-based.
"""

from __future__ import annotations

# flat polygon arrays, for the readers (io.meshfile, api) and sharpen
from .faces import _as_polygons as _as_polygons
from .faces import _edge_keys as _edge_keys
from .faces import _following_corner as _following_corner
from .features import Features, features_from_tags
from .polygons import refine_polygons
from .quadmesh import REPAIRABLE, QuadMesh, strict_meshes, subdivide
from .tags import INFINITE_SHARPNESS, Tag
from .topology import QuadTopology
from .validate import DEGENERATE_AREA_TOLERANCE, MAX_COORDINATE
from .vertex_sectors import Sectors, lonely_seams, sectors

__all__ = [
    "Tag",
    "Features",
    "Sectors",
    "features_from_tags",
    "lonely_seams",
    "sectors",
    "INFINITE_SHARPNESS",
    "MAX_COORDINATE",
    "QuadTopology",
    "QuadMesh",
    "refine_polygons",
    "subdivide",
    "strict_meshes",
    "REPAIRABLE",
    "DEGENERATE_AREA_TOLERANCE",
]
