"""Feature-adaptive refinement of a Catmull–Clark limit network: finer patches only where the
network is off the limit (OpenSubdiv's idea, DESIGN §1).

One patch per face is within the tolerance of the exact limit almost everywhere: on faces with four
regular corners the patch *is* the limit (a bicubic B-spline), and the distance is largest at
extraordinary vertices, where it roughly halves with each Catmull–Clark step. So only the faces that
are off, and a ring around them (region R), are refined: their neighbourhood (R and
:data:`SUPPORT_RINGS` rings more, :func:`~g1patch.mesh.neighbourhood.neighbourhood`) is cut out,
takes one Catmull–Clark step and is built again; its faces inside R replace R's patches, and the
step repeats on them while any is off. Subdivision reads a face's 1-ring only, so those faces are
the whole cage's refinement, and their patches its limit network.

Where a coarse patch meets finer ones the network has *hanging edges*
(:class:`~g1patch.network.HangingEdges`): a coarse patch edge against two (or four, …) finer ones.
They join exactly G1 because both sides are the limit itself there: the region grows until every
coarse face sharing a vertex with it, and every fine face along its rim, is within
:data:`EXACT` of the limit at dense samples (a bicubic that agrees with the limit's bicubic at
17 × 17 points is that bicubic); the check measures them as every other edge. Where that cannot be
had (a cage where nearly every face is irregular) the region is the whole level: the plain global
step.

Each face of every level knows its *root* face of the cage and its corners' parameters there
(dyadic fractions, exact in floating point), so a patch edge is a segment of a cage edge or of a
line inside a root face; hanging edges are the segments of one line that lie inside a longer one
of the other side.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import NDArray

from .errors import G1PatchError
from .fidelity import limit_distance
from .gregory import GregoryPatchSet
from .mesh import INFINITE_SHARPNESS, QuadMesh, QuadTopology
from .mesh.neighbourhood import grow, neighbourhood
from .network import PARAMETER_CORNERS, HangingEdges, PatchNetwork
from .subdivision import refine_grids

__all__ = ["EXACT", "SUPPORT_RINGS", "Adaptive", "refine_adaptively", "semi_sharp_faces"]

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]
BoolArray = NDArray[np.bool_]
logger = logging.getLogger(__name__)

#: distance from the limit (of the diagonal) below which a face's patch is the limit itself:
#: rounding leaves ~1e-16 on B-spline faces; one touched by an extraordinary vertex is ≥ 1e-8 off
EXACT = 1e-12
#: vertex rings of faces cut out around the refined region: the step's points read one ring, the
#: targets' fits and the assembly two more
SUPPORT_RINGS = 3
#: times the region may grow to make its rim exact before it becomes the whole level
_CLOSURE_STEPS = 8
_RIM_RETRIES = 2
#: a child face's corners in its parent's parameters: cell (i, j) corner m at ((i, j) + _CELL[m])/2
_CELL = PARAMETER_CORNERS


@dataclass(frozen=True)
class _Level:
    """One level of the refinement: its cage (a neighbourhood refined ``depth`` steps), its
    network (one patch per face, holes without), each face's root face and corner parameters
    there, each vertex's id across levels, which faces are this level's (``active``: the
    refined region's, whose 1-rings are whole) and each active face's distance from the limit."""

    mesh: QuadMesh
    network: PatchNetwork
    root: IntArray
    corners: FloatArray
    ids: IntArray
    active: BoolArray
    distance: FloatArray

    @property
    def patch_of(self) -> IntArray:
        """The patch of every face (−1 on holes)."""
        holes = self.mesh.features.holes
        out = np.full(self.mesh.n_faces, -1, dtype=np.int64)
        out[~holes] = np.arange(int((~holes).sum()))
        return out


@dataclass(frozen=True)
class Adaptive:
    """The refined network, its largest distance from the limit (absolute, world units), the
    steps taken (levels below the cage) and, where it stopped short, why."""

    network: PatchNetwork
    distance: float
    steps: int
    stop: str


def _bilinear(corners: FloatArray, st: FloatArray) -> FloatArray:
    """Points at parameters ``st`` (..., 2) of the bilinear maps with ``corners`` (..., 4, 2)."""
    s, t = st[..., 0:1], st[..., 1:2]
    return (
        (1 - s) * (1 - t) * corners[..., 0, :]
        + s * (1 - t) * corners[..., 1, :]
        + s * t * corners[..., 2, :]
        + (1 - s) * t * corners[..., 3, :]
    )


def _children(fine: QuadTopology, grid: IntArray) -> tuple[IntArray, IntArray]:
    """Per refined face and cell (i, j), its child face and the child's slot at the cell's corner
    (i, j), both (S, 2, 2): the face holding the half-edge ``grid[i, j] → grid[i + 1, j]``."""
    nv = fine.n_vertices
    h = np.arange(fine.n_halfedges)
    directed = fine.origin(h) * nv + fine.target(h)
    order = np.argsort(directed)
    keys = grid[:, :-1, :-1] * nv + grid[:, 1:, :-1]
    half = order[np.searchsorted(directed[order], keys)]
    return half >> 2, half & 3


def semi_sharp_faces(mesh: QuadMesh) -> BoolArray:
    """Faces with a vertex on a semi-sharp edge or at a semi-sharp vertex (sharpness strictly
    between 0 and infinite): their limit follows the crease rules for ⌈s⌉ more levels, so they
    are refined whatever their distance (OpenSubdiv's feature-adaptive rule; a partly resolved
    crease is within a tolerance but ripples in reflections)."""
    features = mesh.features

    def semi(values: FloatArray) -> BoolArray:
        return (values > 0.0) & (values < INFINITE_SHARPNESS)

    vertices = semi(features.vertex_sharpness).copy()
    vertices[mesh.topology.edges[semi(features.edge_sharpness)].reshape(-1)] = True
    return np.asarray(vertices[mesh.faces].any(axis=1))


def _face_distance(network: PatchNetwork, mesh: QuadMesh, active: BoolArray) -> FloatArray:
    """Each ``active`` face's largest distance from the limit (0 on holes and elsewhere: the
    faces of the support rings have no whole 1-ring, their patches are not the cage's)."""
    return np.nan_to_num(limit_distance(network, mesh, 1, only=active).per_face, nan=0.0)


def _refined(
    level: _Level,
    region: BoolArray,
    build: Callable[[QuadMesh, IntArray], PatchNetwork],
    next_id: int,
) -> _Level:
    """The next level: ``region``'s neighbourhood cut out, one step, built."""
    part = neighbourhood(level.mesh, np.flatnonzero(region), SUPPORT_RINGS)
    fine, grid = refine_grids(part.mesh, 1)
    child, slot = _children(fine.topology, grid)
    n_faces = fine.n_faces
    root = np.empty(n_faces, dtype=np.int64)
    corners = np.empty((n_faces, 4, 2))
    parent = part.faces
    for i in (0, 1):
        for j in (0, 1):
            faces = child[:, i, j]
            root[faces] = level.root[parent]
            local = (np.array([i, j], dtype=np.float64) + _CELL) / 2.0  # (4, 2): m = 0…3
            at = _bilinear(level.corners[parent][:, None], local[None])  # (S, 4, 2)
            order = (slot[:, i, j, None] + np.arange(4)) % 4  # child corner of each m
            corners[faces[:, None], order] = at
    ids = np.concatenate(
        [level.ids[part.vertices], next_id + np.arange(fine.n_vertices - part.mesh.n_vertices)]
    )

    def children_of(faces: BoolArray) -> BoolArray:
        out = np.zeros(n_faces, dtype=bool)
        out[child[faces[parent]].reshape(-1)] = True
        return out

    network = build(fine, ids)
    active = children_of(region)
    return _Level(fine, network, root, corners, ids, active, _face_distance(network, fine, active))


def _region(level: _Level, bad: BoolArray, exact: float) -> BoolArray:
    """``bad`` and a ring round it, grown until every active face sharing a vertex with it is
    exact; the whole active level where that does not settle."""
    topology = level.mesh.topology
    region = grow(topology, bad, 1) & level.active
    for _ in range(_CLOSURE_STEPS):
        collar = grow(topology, region, 1) & ~region & level.active
        inexact = collar & (level.distance > exact)
        if not inexact.any():
            return region
        region |= inexact
    return level.active.copy()


def _rim_inexact(level: _Level, exact: float) -> BoolArray:
    """Active faces that share a vertex with a face that is not (they meet coarser patches) and
    are not exact."""
    outside = grow(level.mesh.topology, ~level.active, 1)
    return outside & level.active & (level.distance > exact)


def refine_adaptively(
    network: PatchNetwork,
    cage: QuadMesh,
    build: Callable[[QuadMesh, IntArray], PatchNetwork],
    tolerance: float,
    max_steps: int,
    allowed: Callable[[int], str],
) -> Adaptive:
    """The network of ``cage`` (``network``, one Gregory patch per face, built by ``build``)
    refined where it is more than ``tolerance`` (absolute) from the exact limit or touches a
    semi-sharp feature (:func:`semi_sharp_faces`), at most ``max_steps`` levels deep (module
    docstring). ``allowed(patches)`` says why a network of that
    many patches may not be built ("" when it may)."""
    diagonal = network.bounding_box_diagonal()
    exact = EXACT * diagonal
    level = _Level(
        cage,
        network,
        np.arange(cage.n_faces),
        np.broadcast_to(PARAMETER_CORNERS, (cage.n_faces, 4, 2)).copy(),
        np.arange(cage.n_vertices),
        np.ones(cage.n_faces, dtype=bool),
        _face_distance(network, cage, np.ones(cage.n_faces, dtype=bool)),
    )
    levels: list[_Level] = [level]
    regions: list[BoolArray] = []
    next_id = cage.n_vertices
    stop = ""
    while True:
        bad = level.active & ((level.distance > tolerance) | semi_sharp_faces(level.mesh))
        if not bad.any():
            break
        if len(regions) == max_steps:
            stop = f"{max_steps} steps added; a larger --tolerance lets it through"
            break
        region = _region(level, bad, exact)
        for retry in range(_RIM_RETRIES + 1):
            finer = _refined(level, region, build, next_id)
            if not _rim_inexact(finer, exact).any() or region.all():
                break
            # the fine faces along the rim are not the limit yet: a ring more, at last all
            region = (
                grow(level.mesh.topology, region, 1) & level.active
                if retry < _RIM_RETRIES
                else level.active.copy()
            )
        if _rim_inexact(finer, exact).any():
            stop = "the refined faces do not meet the coarser ones exactly here"
            break
        patches = (
            _count(levels[:-1], regions)
            + int((level.active & ~region).sum())
            + int(finer.active.sum())
        )
        why = allowed(patches)
        if why:
            stop = why
            break
        regions.append(region)
        levels.append(finer)
        next_id += finer.mesh.n_vertices
        level = finer
    regions.append(np.zeros(level.mesh.n_faces, dtype=bool))
    combined, distance = _combine(levels, regions, cage, diagonal)
    return Adaptive(combined, distance, len(levels) - 1, stop)


def _count(levels: list[_Level], regions: list[BoolArray]) -> int:
    """Patches kept on ``levels`` (their active faces outside their refined regions)."""
    return sum(int((lv.active & ~r).sum()) for lv, r in zip(levels, regions, strict=True))


def _combine(
    levels: list[_Level], regions: list[BoolArray], cage: QuadMesh, diagonal: float
) -> tuple[PatchNetwork, float]:
    """One network of every level's kept patches (its active faces outside its refined region),
    in the cage network's frame, with the hanging edges between levels, the UVs and groups of
    each patch's root face; and the largest distance of a kept face."""
    base = levels[0].network
    frame = getattr(base.patches, "frame", None)
    points, corner_ids, edge_ids, reversed_, neighbor, neighbor_edge, seam = (
        [],
        [],
        [],
        [],
        [],
        [],
        [],
    )
    collapsed, root, corners = [], [], []
    n_ids = max(int(lv.ids.max()) for lv in levels) + 1
    vertices = np.zeros((n_ids, 3))
    normals = np.zeros((n_ids, 3)) if base.vertex_normals is not None else None
    offset = edge_offset = 0
    distance = 0.0
    for level, region in zip(levels, regions, strict=True):
        keep_faces = level.active & ~region & ~level.mesh.features.holes
        distance = max(distance, float(level.distance[keep_faces].max(initial=0.0)))
        patch_of = level.patch_of
        keep = np.zeros(level.network.n_patches, dtype=bool)
        keep[patch_of[keep_faces]] = True
        part = level.network.take_patches(keep)
        faces = np.flatnonzero(keep_faces)  # patch order is face order
        patches = part.patches
        if not isinstance(patches, GregoryPatchSet):
            raise G1PatchError("feature-adaptive refinement joins Gregory networks only")
        points.append(
            patches.world_points() if frame is None else frame.to_local(patches.world_points())
        )
        corner_ids.append(level.ids[part.corner_ids])
        edge_ids.append(part.edge_ids + edge_offset)
        reversed_.append(part.edge_reversed)
        neighbor.append(np.where(part.neighbor >= 0, part.neighbor + offset, -1))
        neighbor_edge.append(part.neighbor_edge)
        seam.append(part.seam)
        collapsed.append(part.edge_collapsed)
        root.append(level.root[faces])
        corners.append(level.corners[faces])
        used = np.unique(part.corner_ids)
        if level.network.vertices is not None:
            vertices[level.ids[used]] = level.network.vertices[used]
        if normals is not None and level.network.vertex_normals is not None:
            normals[level.ids[used]] = level.network.vertex_normals[used]
        offset += part.n_patches
        edge_offset += part.n_edges
    root_all, corners_all = np.concatenate(root), np.concatenate(corners)
    # only the vertices and edges the kept patches use, numbered in order
    used_ids, corner_index = np.unique(np.concatenate(corner_ids), return_inverse=True)
    used_edges, edge_index = np.unique(np.concatenate(edge_ids), return_inverse=True)
    network = PatchNetwork(
        patches=GregoryPatchSet(np.concatenate(points), frame),
        corner_ids=corner_index.reshape(offset, 4),
        edge_ids=edge_index.reshape(offset, 4),
        edge_reversed=np.concatenate(reversed_),
        neighbor=np.concatenate(neighbor),
        neighbor_edge=np.concatenate(neighbor_edge),
        same_direction=np.zeros((offset, 4), dtype=bool),
        edge_collapsed=np.concatenate(collapsed)[used_edges],
        vertices=vertices[used_ids] if base.vertices is not None else None,
        vertex_normals=None if normals is None else normals[used_ids],
        provenance=dict(base.provenance),
        seam=np.concatenate(seam),
    )
    hanging = hanging_edges(network, cage.topology, root_all, corners_all)
    uv = None
    if cage.uv is not None:
        uv = _bilinear(cage.uv[root_all][:, None], corners_all)
    groups = None if cage.groups is None else cage.groups.take(root_all)
    return replace(network, hanging=hanging, uv=uv, groups=groups), distance


def hanging_edges(
    network: PatchNetwork, cage: QuadTopology, root: IntArray, corners: FloatArray
) -> HangingEdges:
    """The T-junctions of ``network`` whose patch p covers the square with ``corners[p]`` (4, 2)
    of cage face ``root[p]``: its open patch edges that lie inside a longer open edge of the other
    side (module docstring). Raises :class:`G1PatchError` where a longer edge is not covered."""
    patch, edge = np.nonzero(network.neighbor < 0)
    a = corners[patch, edge]
    b = corners[patch, (edge + 1) % 4]
    face = root[patch]
    # the line each edge lies on: a cage edge (key 0, its id; x along its canonical direction) or
    # a line inside the root face (key 1 + axis, face, the fixed coordinate; x the other one)
    on_u = a[:, 0] == b[:, 0]  # u fixed: x = v
    fixed = np.where(on_u, a[:, 0], a[:, 1])
    xa = np.where(on_u, a[:, 1], a[:, 0])
    xb = np.where(on_u, b[:, 1], b[:, 0])
    boundary = (fixed == 0.0) | (fixed == 1.0)
    # root edge k: 0 (v = 0), 1 (u = 1), 2 (v = 1), 3 (u = 0)
    k = np.where(on_u, np.where(fixed == 1.0, 1, 3), np.where(fixed == 0.0, 0, 2))
    h = 4 * face + k
    along = np.where((k == 0) | (k == 1), 1.0, -1.0)  # the half-edge's own direction in x
    start = np.where(along > 0, 0.0, 1.0)
    ta, tb = start + along * xa, start + along * xb  # fractions along the half-edge
    e = cage.halfedge_edge[h]
    canonical = cage.origin(h) == cage.edges[e, 0]
    ta = np.where(canonical, ta, 1.0 - ta)
    tb = np.where(canonical, tb, 1.0 - tb)
    key = np.stack(
        [
            np.where(boundary, 0, 1 + on_u),
            np.where(boundary, e, face),
            np.where(boundary, 0.0, fixed),
        ],
        axis=1,
    )
    xa, xb = np.where(boundary, ta, xa), np.where(boundary, tb, xb)
    line = np.unique(key, axis=0, return_inverse=True)[1].reshape(-1)
    low, high = np.minimum(xa, xb), np.maximum(xa, xb)
    forward = xb > xa
    links = []
    for side in (True, False):  # the fine edges of one direction inside the other's
        mine = np.flatnonzero(forward == side)
        theirs = np.flatnonzero(forward != side)
        if not len(mine) or not len(theirs):
            continue
        order = theirs[np.lexsort((low[theirs], line[theirs]))]
        position = line[order] * 4.0 + low[order]
        slot = np.searchsorted(position, line[mine] * 4.0 + low[mine], side="right") - 1
        ok = slot >= 0
        host = order[np.maximum(slot, 0)]
        ok &= (line[host] == line[mine]) & (high[host] >= high[mine])
        ok &= high[host] - low[host] > high[mine] - low[mine]
        links.append((mine[ok], host[ok]))
    fine = np.concatenate([m for m, _ in links]) if links else np.zeros(0, dtype=np.int64)
    coarse = np.concatenate([c for _, c in links]) if links else np.zeros(0, dtype=np.int64)
    covered = np.bincount(coarse, weights=high[fine] - low[fine], minlength=len(patch))
    hosts = np.unique(coarse)
    short = np.abs(covered[hosts] - (high[hosts] - low[hosts])) > 1e-12
    if short.any():
        bad = hosts[int(np.argmax(short))]
        raise G1PatchError(
            f"adaptive network: patch {patch[bad]} edge {edge[bad]} is covered by finer edges "
            f"over {covered[bad]:.6g} of its {high[bad] - low[bad]:.6g}"
        )
    length = xb[coarse] - xa[coarse]
    span = np.stack([(xa[fine] - xa[coarse]) / length, (xb[fine] - xa[coarse]) / length], axis=1)
    sides = np.stack([patch[fine], edge[fine], patch[coarse], edge[coarse]], axis=1)
    return HangingEdges(sides, span)
