"""Quad layouts of dense triangle meshes: Instant Meshes (Jakob et al. 2015, field-aligned
remeshing) through its maintained nanobind binding ``pynanoinstantmeshes``.

The remesher runs in a child process (:func:`quad_layout`): a crash inside native code becomes
a clear :class:`~g1patch.errors.ConstructionError`, its progress chatter on stdout stays out of
ours, and a hang ends at ``timeout``. It runs deterministically (``deterministic=True``, on one
CPU: the same input gives the same layout, bit for bit). Its raw output is quad-dominant; it
returns the pure-quad mesh of one regular split of that (about 4 quads per requested vertex),
which is the cage the fit solves for. On some inputs that output has coincident vertices and
degenerate quads (a corner repeated, zero area); :func:`clean_layout` merges and drops them
before the cage is built.
"""

from __future__ import annotations

import subprocess
import sys
import tempfile
from collections.abc import Sequence
from pathlib import Path

import numpy as np
from numpy.typing import NDArray
from scipy.spatial import cKDTree

from ..errors import ConstructionError, InputError, MissingDependencyError
from ..mesh import QuadMesh, Tag
from ..mesh.conforming import local_split
from ..mesh.tags import FACE_TAGS, VERTEX_TAGS
from ..mesh.validate import DEGENERATE_AREA_TOLERANCE
from .scan_topology import boundary_edges, boundary_loops, triangle_parts

__all__ = [
    "BRIDGE_GAP",
    "BRIDGE_HOLE",
    "BRIDGE_SIDEWAYS",
    "LAYOUT_TIMEOUT",
    "bridging_faces",
    "clean_layout",
    "quad_layout",
    "refined_layout",
]

#: seconds the remesher may take before it is stopped
LAYOUT_TIMEOUT = 600.0
#: a layout face whose centre is farther than this share of its mean edge length from the scan,
#: a scan boundary vertex the nearest, spans a hole of the scan (:func:`bridging_faces`): a face
#: over the scan is a sag away (0.03 of its edge where it turns by 30°); the faces over a slit
#: in the Stanford bunny's base, 0.12 of the diagonal long and 0.02 wide, 0.2–0.5
BRIDGE_GAP = 0.25
#: ... the hole at least this many of the layout's edges across (its rim's bounding box): a
#: smaller one is closed over, as mesh repair closes holes under a size (the Stanford bunny's
#: smallest base hole is 3.7 edges across at 4,300 quads, and closed over 1.3e-2 of the diagonal
#: from the scan)
BRIDGE_HOLE = 1.0
#: ... and the scan lies sideways of it: the offset to the nearest scan vertex at least this
#: sine off the face's normal (a face wrapping a teapot's curled rim lip has the scan under it)
BRIDGE_SIDEWAYS = np.sin(np.radians(45.0))

#: the child: read the triangles, remesh each part, write the quads (stdout is the remesher's
#: chatter). It runs on one CPU: the remesher's thread pool sizes itself from the CPUs it may use,
#: and with more than one its extraction step orders equal-weight merges differently from run to
#: run (the teapot at 6,320 quads: three different layouts in eight runs; on one CPU, one).
_CHILD = """
import os
import sys
import numpy as np
if hasattr(os, "sched_setaffinity"):
    os.sched_setaffinity(0, {min(os.sched_getaffinity(0))})
import pynanoinstantmeshes
given = np.load(sys.argv[1])
points, triangles, part = given["points"], given["triangles"], given["part"]
vertices, quads, offset = [], [], 0
for label, count in enumerate(given["vertex_counts"]):
    used, local = np.unique(triangles[part == label], return_inverse=True)
    made, faces = pynanoinstantmeshes.remesh(
        points[used].astype(np.float32),
        local.reshape(-1, 3).astype(np.uint32),
        int(count),
        deterministic=True,
        align_to_boundaries=True,
    )
    vertices.append(np.asarray(made, dtype=np.float64).reshape(-1, 3))
    quads.append(np.asarray(faces, dtype=np.int64).reshape(-1, 4) + offset)
    offset += len(vertices[-1])
np.savez(sys.argv[2], vertices=np.concatenate(vertices), quads=np.concatenate(quads))
"""


def _check_remesher() -> None:
    """:class:`MissingDependencyError` naming the extra to install when the binding is absent."""
    import importlib.util

    if importlib.util.find_spec("pynanoinstantmeshes") is None:
        raise MissingDependencyError(
            "pynanoinstantmeshes", "fit", "a quad layout (Instant Meshes; or pass one: --layout)"
        )


def quad_layout(
    points: NDArray[np.float64],
    triangles: NDArray[np.int64],
    faces: int,
    *,
    timeout: float = LAYOUT_TIMEOUT,
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """A pure-quad layout of about ``faces`` quads over the triangles (``points`` (V, 3),
    ``triangles`` (T, 3)), by Instant Meshes in a child process: ``(vertices, quads)``.

    Each connected part of the triangles is remeshed on its own (:func:`triangle_parts`; one
    layout over parts that touch or cross, a teapot's spout and body, bridges them), asked for
    its share by area of ``faces / 4`` vertices (its quad-dominant result is split once into
    quads, four per face); the whole is then cleaned (:func:`clean_layout`). Raises
    :class:`ConstructionError` when it fails, crashes, times out or returns no usable quads."""
    if isinstance(faces, bool) or not isinstance(faces, (int, np.integer)) or faces < 16:
        raise InputError(f"faces: expected a number of quads ≥ 16, got {faces!r}")
    _check_remesher()
    with tempfile.TemporaryDirectory(prefix="g1patch-layout-") as folder:
        given, taken = Path(folder) / "given.npz", Path(folder) / "taken.npz"
        part = triangle_parts(triangles, len(points))
        a, b, c = (points[triangles[:, k]] for k in range(3))
        area = np.bincount(part, np.linalg.norm(np.cross(b - a, c - a), axis=1))
        counts = np.maximum(np.round(faces / 4 * area / max(area.sum(), 1e-300)), 4)
        np.savez(given, points=points, triangles=triangles, part=part, vertex_counts=counts)
        try:
            result = subprocess.run(
                [sys.executable, "-c", _CHILD, str(given), str(taken)],
                capture_output=True,
                text=True,
                timeout=timeout,
                check=False,
            )
        except subprocess.TimeoutExpired:
            raise ConstructionError(
                f"the quad remesher (Instant Meshes) did not finish in {timeout:g} s"
            ) from None
        if result.returncode != 0 or not taken.exists():
            last = (result.stderr.strip().splitlines() or [f"exit status {result.returncode}"])[-1]
            raise ConstructionError(f"the quad remesher (Instant Meshes) failed: {last[:200]}")
        with np.load(taken) as made:
            vertices, quads = made["vertices"], made["quads"]
    if quads.ndim != 2 or quads.shape[1] != 4 or not len(quads):
        raise ConstructionError("the quad remesher (Instant Meshes) returned no quads")
    vertices, quads, _ = clean_layout(vertices, quads)
    if not len(quads):
        raise ConstructionError("the quad remesher (Instant Meshes) returned only degenerate quads")
    return vertices, quads


def bridging_faces(
    layout: QuadMesh, points: NDArray[np.float64], triangles: NDArray[np.int64]
) -> NDArray[np.bool_]:
    """The faces of a remesher's ``layout`` that span a hole of the scan (``points``,
    ``triangles``): their centre (the mean of the corners) farther than :data:`BRIDGE_GAP` of
    the face's mean edge length from the scan's triangles, nearest a boundary vertex of them on a
    hole :data:`BRIDGE_HOLE` layout edges across or more, which lies sideways
    (:data:`BRIDGE_SIDEWAYS`).
    Instant Meshes follows a scan's boundaries but not always: it spanned two of the Stanford
    bunny's five base holes (0.05 and 0.12 of the diagonal across; another two after the
    non-manifold edges were removed), where the fitted surface then lay 1.3e-2 of the diagonal
    from the scan at every layout up to 4,400 quads."""
    from ..compare import mesh_distance

    edges = boundary_edges(triangles)
    if not len(edges):
        return np.zeros(layout.n_faces, dtype=bool)
    loop = boundary_loops(edges, len(points))
    rim = np.unique(edges)
    low = np.full((loop.max() + 1, 3), np.inf)
    high = np.full((loop.max() + 1, 3), -np.inf)
    np.minimum.at(low, loop[rim], points[rim])
    np.maximum.at(high, loop[rim], points[rim])
    extent = np.linalg.norm(high - low, axis=1)
    extent[_buried_loops(points, triangles, rim, loop, extent)] = 0.0
    across = np.zeros(len(points))  # per rim vertex its loop's extent (bounding-box diagonal)
    across[rim] = extent[loop[rim]]
    corners = layout.vertices[layout.faces]
    centre = corners.mean(axis=1)
    size = np.linalg.norm(corners - np.roll(corners, -1, axis=1), axis=-1).mean(axis=1)
    normal = np.cross(corners[:, 2] - corners[:, 0], corners[:, 3] - corners[:, 1])
    normal /= np.maximum(np.linalg.norm(normal, axis=1, keepdims=True), np.finfo(float).tiny)
    used = np.unique(triangles)
    nearest = used[cKDTree(points[used]).query(centre)[1]]
    offset = points[nearest] - centre
    sideways = np.linalg.norm(np.cross(offset, normal), axis=1) >= BRIDGE_SIDEWAYS * np.linalg.norm(
        offset, axis=1
    )
    edge = float(np.median(size))
    candidate = (across[nearest] >= BRIDGE_HOLE * edge) & sideways
    far = np.zeros(layout.n_faces, dtype=bool)
    far[candidate] = (
        mesh_distance(centre[candidate], points, triangles) > BRIDGE_GAP * size[candidate]
    )
    return far


def _buried_loops(
    points: NDArray[np.float64],
    triangles: NDArray[np.int64],
    rim: NDArray[np.int64],
    loop: NDArray[np.int64],
    extent: NDArray[np.float64],
) -> NDArray[np.int64]:
    """The boundary loops (labels ``loop`` of the ``rim`` vertices, ``extent`` across) that end
    a part of the scan inside another (a teapot's handle and spout, their open ends in its
    body): their rim vertices' median distance to the other parts' triangles under half the
    loop's extent. The other part closes such a hole."""
    from ..compare import mesh_distance

    part = triangle_parts(triangles, len(points))
    if part.max() == 0:
        return np.zeros(0, dtype=np.int64)
    vertex_part = np.empty(len(points), dtype=np.int64)
    vertex_part[triangles.reshape(-1)] = np.repeat(part, 3)
    distance = np.full(len(rim), np.inf)
    for label in np.unique(vertex_part[rim]):  # one search per part
        mine = vertex_part[rim] == label
        distance[mine] = mesh_distance(points[rim[mine]], points, triangles[part != label])
    labels, inverse, counts = np.unique(loop[rim], return_inverse=True, return_counts=True)
    ordered = distance[np.lexsort((distance, inverse))]  # loop after loop, each ascending
    median = ordered[np.cumsum(counts) - counts + counts // 2]  # the upper median
    return labels[median < 0.5 * extent[labels]]


def clean_layout(
    vertices: NDArray[np.float64], quads: NDArray[np.int64], tags: Sequence[Tag] = ()
) -> tuple[NDArray[np.float64], NDArray[np.int64], tuple[Tag, ...]]:
    """The layout with coincident vertices merged and the quads dropped that a cage cannot have:
    a corner repeated, zero area (``|d1 × d2| ≤ tol · max(|d1|², |d2|²)``, d1 and d2 the
    diagonals, as :mod:`~g1patch.mesh.validate` refuses) or an edge shared by more than two
    quads (every quad at such an edge). Unused vertices stay (the mesh drops them). ``tags`` (a
    layout file's own creases, corners, holes) follow: vertices merged, a crease on an edge
    that merging collapsed and a hole on a dropped quad left out."""
    merged, inverse = np.unique(vertices, axis=0, return_inverse=True)
    inverse = inverse.reshape(-1)
    quads = inverse[quads]
    ordered = np.sort(quads, axis=1)
    repeated = (ordered[:, 1:] == ordered[:, :-1]).any(axis=1)
    corners = merged[quads]
    d1, d2 = corners[:, 2] - corners[:, 0], corners[:, 3] - corners[:, 1]
    size = np.maximum((d1 * d1).sum(1), (d2 * d2).sum(1))
    flat = np.linalg.norm(np.cross(d1, d2), axis=1) <= DEGENERATE_AREA_TOLERANCE * size
    kept = np.flatnonzero(~(repeated | flat))
    sides = np.stack([quads[kept], np.roll(quads[kept], -1, axis=1)], axis=-1)
    key = sides.min(axis=-1) * len(merged) + sides.max(axis=-1)
    _, shared, counts = np.unique(key, return_inverse=True, return_counts=True)
    kept = kept[~(counts[shared] > 2).reshape(key.shape).any(axis=1)]
    return merged, quads[kept], _carried_tags(tags, inverse, kept, len(quads))


def _carried_tags(
    tags: Sequence[Tag], vertex: NDArray[np.int64], kept: NDArray[np.int64], faces: int
) -> tuple[Tag, ...]:
    """``tags`` through :func:`clean_layout`: ``vertex[old]`` the merged vertex, ``kept`` the
    old faces kept (of ``faces``)."""
    face = np.full(faces, -1)
    face[kept] = np.arange(kept.size)
    carried = []
    for tag in tags:
        ints, floats = np.asarray(tag.ints, dtype=np.int64), tag.floats
        if tag.name == "crease":
            pairs = vertex[ints].reshape(-1, 2)
            edge = pairs[:, 0] != pairs[:, 1]
            ints = pairs[edge].ravel()
            if len(floats) == len(pairs) > 1:  # a sharpness per edge
                floats = tuple(np.asarray(floats)[edge].tolist())
        elif tag.name in VERTEX_TAGS:
            ints = vertex[ints]
        elif tag.name in FACE_TAGS:
            ints = face[ints][face[ints] >= 0]
        if ints.size or not tag.ints:
            carried.append(tag._replace(ints=tuple(ints.tolist()), floats=floats))
    return tuple(carried)


def refined_layout(layout: QuadMesh, marked: NDArray[np.bool_]) -> QuadMesh:
    """``layout`` with the faces ``marked`` split into four and the faces round them closed
    into quads (:func:`g1patch.mesh.conforming.local_split`), new vertices at edge midpoints and
    face centres. Its creases follow the split (both halves of a split crease edge keep its
    sharpness) and its vertex tags (corners) stay on their vertices."""
    split = local_split(layout.topology, marked)
    edges = layout.topology.edges
    sharpness = layout.features.edge_sharpness
    midpoint = layout.n_vertices + np.cumsum(split.split) - 1  # of the split edges
    tags = [tag for tag in layout.tags if tag.name != "crease"]
    for value in np.unique(sharpness[sharpness > 0]):
        chosen = np.flatnonzero(sharpness == value)
        whole, halved = chosen[~split.split[chosen]], chosen[split.split[chosen]]
        pairs = np.concatenate(
            [
                edges[whole],
                np.stack([edges[halved, 0], midpoint[halved]], axis=1),
                np.stack([midpoint[halved], edges[halved, 1]], axis=1),
            ]
        )
        tags.append(Tag("crease", tuple(pairs.ravel().tolist()), (float(value),)))
    return QuadMesh.from_arrays(
        split.weights @ layout.vertices, split.faces, tags=tags, source=layout.source
    )
