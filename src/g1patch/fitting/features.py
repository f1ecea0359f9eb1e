"""Sharp features of a scan carried onto its quad layout (``g1patch fit --sharp-angle``).

A scan edge is sharp where its two triangles' normals differ by more than the angle
(:func:`g1patch.sharpen.sharp_angle_tags`, as ``build --sharp-angle`` does for a cage). Instant
Meshes puts layout vertices and edges on such lines (its extrinsic field snaps to them), so a
layout edge is tagged an infinitely sharp crease when it runs along them:
:data:`EDGE_SAMPLES` points spread along it all lie within :data:`REACH` of its length from a
sharp scan edge whose direction is within :data:`ALIGNMENT_DEG` of its own. A lone sharp scan
edge (noise, a coarse tessellation of a curved region) tags nothing: a layout edge is several
scan edges long, and all of its samples must be near aligned sharp edges. The tagged layout is
then fitted by the crease rules (its limit has the crease curve there, tangent planes on either
side) and its creases become seams of the network, i.e. edges of the STEP solid. A vertex with
three or more tagged edges is a corner by OpenSubdiv's rules.

An open scan's boundary turns sharply at its corners (a height field's square): the layout's
boundary vertex nearest each such scan vertex is moved onto it and tagged a ``corner``
(:func:`layout_corners`), so that the limit's boundary curve has the corner too instead of
rounding it off.

Instant Meshes' vertices sit near a feature line but not on it: on the L-bracket's concave edge
a row of them ran 0.16 of an edge off the line, just outside :data:`REACH`, and a nine-edge gap
in the crease let the fit round the edge (3.8e-3 of the diagonal at 1,024 quads). Before the
edges are tagged (:func:`snap_to_features`) a layout vertex within :data:`LINE_SNAP` of its mean
edge length of a sharp edge is moved onto its nearest point there (its edges then lie along the
line), and at each scan corner (a vertex where three or more sharp edges meet) the layout vertex
within :data:`CORNER_SNAP` of it where most creases meet is moved onto it (the nearest one may
be a vertex of a flat side beside it whose edges cross the lines), so the creases run on into
the corner, which is tagged a ``corner`` (:func:`layout_creases`, where two or more creases
meet there: a corner tag where the edges do not follow the lines pinches the surface, a stepped
block's concave corner with one crease was 6° off G1 and 1.5e-2 of the diagonal off the scan).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from ..mesh import INFINITE_SHARPNESS, QuadMesh, Tag, lonely_seams
from ..sharpen import sharp_angle_tags
from .scan_topology import boundary_edges, boundary_loops

__all__ = [
    "ALIGNMENT_DEG",
    "BRIDGE_ALIGNMENT_DEG",
    "BRIDGE_REACH",
    "BRIDGE_ROUNDS",
    "CHAIN_EDGES",
    "CORNER_SNAP",
    "CORNER_STEPS",
    "EDGE_SAMPLES",
    "GAP_REACH",
    "LINE_SNAP",
    "PIECE",
    "REACH",
    "SNAP_KEEP_AREA",
    "crease_gaps",
    "layout_corners",
    "layout_creases",
    "median_edge",
    "quad_areas",
    "sharp_corners",
    "sharp_segments",
    "snap_to_features",
    "without_lonely_creases",
]

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

#: points along a layout edge that must all be near an aligned sharp scan edge
EDGE_SAMPLES = 5
#: how near, as a fraction of the layout edge's length
REACH = 0.15
#: how parallel the layout edge and the sharp scan edge must be, degrees
ALIGNMENT_DEG = 25.0
#: a chain's gap is bridged by an edge whose samples lie within this fraction of its length of
#: sharp scan edges running within :data:`BRIDGE_ALIGNMENT_DEG` of it
BRIDGE_REACH = 0.4
BRIDGE_ALIGNMENT_DEG = 40.0
#: edges a gap is bridged by at most, from each end
BRIDGE_ROUNDS = 3
#: a layout vertex this near a scan corner (of its mean edge length) is moved onto it
CORNER_SNAP = 0.5
#: scan boundary edges each way a boundary turn is measured over at most
#: (:func:`boundary_corners`)
CORNER_STEPS = 64
#: a layout vertex this near a sharp scan edge (of its mean edge length) is moved onto it (the
#: remesher's vertices on a feature line lie within 0.2 of it on the box and the L-bracket, the
#: next ones 0.5 or more away)
LINE_SNAP = 0.3
#: a snap is undone at the vertices of a face it leaves with less than this share of its area
#: (the four vertices of a layout face of pyvista's ant, 912 triangles, all snapped onto one
#: straight feature line: a face of no area, the layout refused)
SNAP_KEEP_AREA = 0.1
#: connected sharp scan edges are a feature line vertices are snapped onto when they are at least
#: this many layout edges long (the median edge; a CAD part's lines are one network of tens, the
#: steepest facets of Spot at 2,000 quads a chain of 3.3 and two single edges)
CHAIN_EDGES = 6.0
#: a feature line farther than this from every crease edge (of the median layout edge) is in a
#: gap of the crease chain (:func:`crease_gaps`)
GAP_REACH = 0.25
#: sharp scan edges are cut into pieces no longer than this share of the median layout edge
#: before they are matched to the layout (:func:`_pieces`): a CAD part's flat sides are long
#: slivers, and one sharp edge across a whole side made every layout edge a candidate for every
#: segment (a cycloidal gear's 43 k triangles: 24 GB, killed at a 12,721-quad layout)
PIECE = 0.5


def sharp_segments(points: FloatArray, triangles: IntArray, degrees: float) -> FloatArray:
    """The sharp edges of a triangle mesh as segments ``(S, 2, 3)`` (none: shape ``(0, 2, 3)``)."""
    sizes = np.full(len(triangles), 3, dtype=np.int64)
    tags = sharp_angle_tags(points, np.asarray(triangles, np.int64).ravel(), sizes, degrees)
    creases = [tag for tag in tags if tag.name == "crease"]
    if not creases:
        return np.zeros((0, 2, 3))
    ends = np.asarray(creases[0].ints, dtype=np.int64).reshape(-1, 2)
    return np.asarray(points, dtype=np.float64)[ends]


def sharp_corners(points: FloatArray, triangles: IntArray, degrees: float) -> FloatArray:
    """The scan's vertices (C, 3) where three or more sharp edges meet (none: shape (0, 3))."""
    sizes = np.full(len(triangles), 3, dtype=np.int64)
    tags = sharp_angle_tags(points, np.asarray(triangles, np.int64).ravel(), sizes, degrees)
    found = [tag for tag in tags if tag.name == "corner"]
    if not found:
        return np.zeros((0, 3))
    return np.asarray(points, dtype=np.float64)[np.asarray(found[0].ints, dtype=np.int64)]


def median_edge(layout: QuadMesh, edges: IntArray | None = None) -> float:
    """The median length of ``layout``'s ``edges`` (E, 2) (all its edges when None)."""
    ends = layout.vertices[layout.topology.edges if edges is None else edges]
    return float(np.median(np.linalg.norm(ends[:, 1] - ends[:, 0], axis=1)))


def _pieces(segments: FloatArray, median_edge: float) -> FloatArray:
    """``segments`` (S, 2, 3) cut into equal pieces no longer than :data:`PIECE` of the layout's
    ``median_edge``, in order along each (a segment's ends stay exactly its own, so chains and
    corners still meet there)."""
    if not len(segments):
        return segments
    longest = PIECE * median_edge
    length = np.linalg.norm(segments[:, 1] - segments[:, 0], axis=1)
    count = np.ones(len(segments), dtype=np.int64)
    if longest > 0:
        count = np.maximum(np.ceil(length / longest), 1).astype(np.int64)
    if (count == 1).all():
        return segments
    owner = np.repeat(np.arange(len(segments)), count)
    step = np.arange(int(count.sum())) - np.repeat(np.cumsum(count) - count, count)
    start, direction = segments[owner, 0], segments[owner, 1] - segments[owner, 0]
    first = start + (step / count[owner])[:, None] * direction
    last = start + ((step + 1) / count[owner])[:, None] * direction
    first[step == 0] = segments[owner[step == 0], 0]
    final = step + 1 == count[owner]
    last[final] = segments[owner[final], 1]
    return np.stack([first, last], axis=1)


def _closest_on_segments(points: FloatArray, segments: FloatArray) -> FloatArray:
    """Per point its closest point on the segments (among those whose midpoints are nearest)."""
    k = min(8, len(segments))
    near = cKDTree(segments.mean(axis=1)).query(points, k=k)[1].reshape(len(points), k)
    a, ab = segments[near, 0], segments[near, 1] - segments[near, 0]
    length = np.maximum((ab * ab).sum(-1), np.finfo(float).tiny)
    t = np.clip(((points[:, None] - a) * ab).sum(-1) / length, 0.0, 1.0)
    foot = a + t[..., None] * ab
    best = np.argmin(np.linalg.norm(foot - points[:, None], axis=-1), axis=1)
    return np.asarray(foot[np.arange(len(points)), best])


def _lines(
    segments: FloatArray, corners: FloatArray, shortest: float
) -> tuple[FloatArray, FloatArray]:
    """The ``segments`` of connected chains at least ``shortest`` long, and the ``corners`` that
    are ends of them (a lone steep scan edge of an organic mesh is no feature line)."""
    ends, index = np.unique(segments.reshape(-1, 3), axis=0, return_inverse=True)
    pairs = index.reshape(-1, 2)
    graph = sp.coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), (len(ends),) * 2)
    chain = connected_components(graph, directed=False)[1][pairs[:, 0]]
    length = np.bincount(chain, np.linalg.norm(segments[:, 1] - segments[:, 0], axis=1))
    keep = length[chain] >= shortest
    kept = np.zeros(len(ends), dtype=bool)
    kept[pairs[keep].ravel()] = True
    on = np.zeros(len(corners), dtype=bool)
    if len(corners):
        gap, nearest = cKDTree(ends).query(corners)
        on = (gap == 0) & kept[nearest]
    return segments[keep], corners[on]


def snap_to_features(layout: QuadMesh, segments: FloatArray, corners: FloatArray) -> QuadMesh:
    """``layout`` with its vertices near the scan's features moved onto them (module docstring):
    every vertex within :data:`LINE_SNAP` of its mean edge length of a sharp edge (``segments``
    (S, 2, 3)) onto its nearest point there; then per scan corner (``corners`` (C, 3)), of the
    vertices within :data:`CORNER_SNAP` of it, the one where most creases meet
    (:func:`layout_creases` of the snapped layout; at least two; the nearest of equals) onto
    it. :func:`layout_creases` of the result tags that vertex a corner. Only chains of sharp
    edges :data:`CHAIN_EDGES` layout edges long or longer, and the corners at their ends, count."""
    if not len(segments):
        return layout
    vertices = layout.vertices.copy()
    edges = layout.topology.edges
    length = np.linalg.norm(vertices[edges[:, 0]] - vertices[edges[:, 1]], axis=1)
    degree = np.bincount(edges.ravel(), minlength=len(vertices))
    size = np.bincount(edges.ravel(), np.repeat(length, 2), len(vertices)) / np.maximum(degree, 1)
    used = np.flatnonzero(degree)
    median = float(np.median(length))
    segments, corners = _lines(_pieces(segments, median), corners, CHAIN_EDGES * median)
    if not len(segments):
        return layout
    feet = _closest_on_segments(vertices[used], segments)
    near = np.linalg.norm(feet - vertices[used], axis=1) <= LINE_SNAP * size[used]
    vertices[used[near]] = feet[near]
    vertices = _uncrushed(layout.vertices, vertices, layout.faces)
    snapped = QuadMesh.from_arrays(vertices, layout.faces, tags=layout.tags, source=layout.source)
    if not len(corners):
        return snapped
    tagged = layout_creases(snapped, segments).features.edge_sharpness > 0
    creases = np.bincount(edges[tagged].ravel(), minlength=len(vertices))
    tree = cKDTree(vertices[used])
    taken = np.zeros(len(vertices), dtype=bool)
    for corner in corners:
        found = used[tree.query_ball_point(corner, CORNER_SNAP * size[used].max())]
        gap = np.linalg.norm(vertices[found] - corner, axis=1)
        fit = found[(gap <= CORNER_SNAP * size[found]) & (creases[found] >= 2) & ~taken[found]]
        if fit.size:
            gap = np.linalg.norm(vertices[fit] - corner, axis=1)
            best = fit[np.lexsort((gap, -creases[fit]))[0]]
            vertices[best], taken[best] = corner, True
    vertices = _uncrushed(snapped.vertices, vertices, layout.faces)
    return QuadMesh.from_arrays(vertices, layout.faces, tags=layout.tags, source=layout.source)


def quad_areas(vertices: FloatArray, faces: IntArray) -> FloatArray:
    """Per quad its area, half its diagonals' cross product ``|(c − a) × (d − b)| / 2``."""
    a, b, c, d = (vertices[faces[:, k]] for k in range(4))
    return 0.5 * np.linalg.norm(np.cross(c - a, d - b), axis=1)


def _uncrushed(original: FloatArray, moved: FloatArray, faces: IntArray) -> FloatArray:
    """``moved`` with the vertices of every face it leaves with less than
    :data:`SNAP_KEEP_AREA` of its area in ``original`` put back where they were, until none is
    (each round puts back one vertex at least, so it ends)."""
    moved = moved.copy()
    before = quad_areas(original, faces)
    while True:
        crushed = quad_areas(moved, faces) < SNAP_KEEP_AREA * before
        back = np.unique(faces[crushed])
        back = back[(moved[back] != original[back]).any(axis=1)]
        if not back.size:
            return moved
        moved[back] = original[back]


def _segment_distance(points: FloatArray, segments: FloatArray) -> FloatArray:
    """Distance from each point to the segment of the same row."""
    a, ab = segments[:, 0], segments[:, 1] - segments[:, 0]
    length = np.maximum((ab * ab).sum(1), np.finfo(float).tiny)
    t = np.clip(((points - a) * ab).sum(1) / length, 0.0, 1.0)
    return np.linalg.norm(points - (a + t[:, None] * ab), axis=1)


def _worst_sample(ends: FloatArray, segments: FloatArray, alignment_deg: float) -> FloatArray:
    """Per edge ``ends`` (E, 2, 3): the largest distance of its :data:`EDGE_SAMPLES` samples to
    the nearest sharp segment running its way (within ``alignment_deg``), as a fraction of the
    edge's length; ∞ where a sample has no such segment within :data:`BRIDGE_REACH`."""
    direction = ends[:, 1] - ends[:, 0]
    length = np.linalg.norm(direction, axis=1)
    t = np.linspace(0.0, 1.0, EDGE_SAMPLES)
    samples = (ends[:, None, 0] + t[None, :, None] * direction[:, None]).reshape(-1, 3)
    owner = np.repeat(np.arange(len(ends)), EDGE_SAMPLES)
    half = 0.5 * float(np.linalg.norm(segments[:, 1] - segments[:, 0], axis=1).max())
    reach = BRIDGE_REACH * length[owner]
    found = cKDTree(segments.mean(axis=1)).query_ball_point(samples, reach + half)
    counts = np.fromiter(map(len, found), dtype=np.int64, count=len(found))
    candidate = np.fromiter((i for row in found for i in row), dtype=np.int64, count=counts.sum())
    sample = np.repeat(np.arange(len(found)), counts)
    along = segments[candidate, 1] - segments[candidate, 0]
    edge = owner[sample]
    cosine = np.abs((along * direction[edge]).sum(1)) / np.maximum(
        np.linalg.norm(along, axis=1) * length[edge], np.finfo(float).tiny
    )
    distance = np.where(
        cosine >= np.cos(np.radians(alignment_deg)),
        _segment_distance(samples[sample], segments[candidate]),
        np.inf,
    )
    nearest = np.full(len(samples), np.inf)
    np.minimum.at(nearest, sample, distance)
    worst = nearest.reshape(-1, EDGE_SAMPLES).max(axis=1)
    return np.where(length > 0, worst / np.maximum(length, np.finfo(float).tiny), np.inf)


def layout_creases(
    layout: QuadMesh, segments: FloatArray, corners: FloatArray | None = None
) -> QuadMesh:
    """``layout`` with a ``crease`` tag (sharpness ∞) on every edge that runs along ``segments``
    (module docstring; its own crease tags, a ``--layout`` file's, kept), and the gaps of those
    chains bridged: where a chain ends at a vertex (its one tagged edge there), the untagged
    edge there that follows the sharp line best within :data:`BRIDGE_REACH` and
    :data:`BRIDGE_ALIGNMENT_DEG` is tagged too, up to :data:`BRIDGE_ROUNDS` edges on from the
    end (a remesher's vertex a little off a feature line otherwise breaks the crease, which the
    fit then rounds). As it is where no edge runs along them. A layout vertex at one of
    ``corners`` (C, 3; :func:`snap_to_features` moved it there) with two or more creases is
    tagged a ``corner``."""
    if not len(segments):
        return layout
    segments = _pieces(segments, median_edge(layout))
    edges = layout.topology.edges
    ends = layout.vertices[edges]
    sharp = _worst_sample(ends, segments, ALIGNMENT_DEG) <= REACH
    if not sharp.any():
        return layout
    loose = _worst_sample(ends, segments, BRIDGE_ALIGNMENT_DEG)
    count = layout.n_vertices
    for _ in range(BRIDGE_ROUNDS):
        degree = np.bincount(edges[sharp].ravel(), minlength=count)
        at_end = (degree[edges] == 1).any(axis=1) & ~sharp & (loose <= BRIDGE_REACH)
        if not at_end.any():
            break
        candidates = np.flatnonzero(at_end)
        vertex = np.where(
            degree[edges[candidates, 0]] == 1, edges[candidates, 0], edges[candidates, 1]
        )
        order = np.lexsort((loose[candidates], vertex))  # per chain end, the best first
        first = np.concatenate([[True], vertex[order][1:] != vertex[order][:-1]])
        sharp[candidates[order[first]]] = True
    pairs = edges[sharp]
    tags = (*layout.tags, Tag("crease", tuple(pairs.ravel().tolist()), (INFINITE_SHARPNESS,)))
    if corners is not None and len(corners):
        gap, nearest = cKDTree(corners).query(layout.vertices)
        scale = float(np.abs(layout.vertices).max())
        creases = np.bincount(pairs.ravel(), minlength=count)
        corner = np.flatnonzero((gap <= 1e-12 * scale) & (creases >= 2))
        if corner.size:
            tags += (Tag("corner", tuple(corner.tolist()), (INFINITE_SHARPNESS,)),)
    return QuadMesh.from_arrays(layout.vertices, layout.faces, tags=tags, source=layout.source)


def without_lonely_creases(layout: QuadMesh) -> QuadMesh:
    """``layout`` without the crease tags of its lonely edges (:func:`~g1patch.mesh.lonely_seams`:
    an isolated crease edge between two darts). split4 cannot cut such an edge open and builds it
    smooth, so the fit must model it smooth too: a cage fitted to a crease the network then
    rounds is off the scan by the rounding (on a cube-sphere cage a lonely crease edge built
    smooth lies 6.4e-4 of the diagonal from the creased limit; 14 of 41 public scans' layouts
    had such edges)."""
    topology = layout.topology
    seams = (layout.features.edge_sharpness > 0) & ~topology.is_boundary_edge
    lonely = lonely_seams(topology, seams)
    if not lonely.any():
        return layout
    count = layout.n_vertices
    dropped = np.sort(topology.edges[lonely], axis=1) @ np.array([count, 1])
    tags = []
    for tag in layout.tags:
        if tag.name == "crease":
            pairs = np.sort(np.asarray(tag.ints, dtype=np.int64).reshape(-1, 2), axis=1)
            kept = ~np.isin(pairs @ np.array([count, 1]), dropped)
            if not kept.any():
                continue
            floats = tag.floats if len(tag.floats) <= 1 else np.asarray(tag.floats)[kept].tolist()
            tag = tag._replace(ints=tuple(pairs[kept].ravel().tolist()), floats=tuple(floats))
        tags.append(tag)
    return QuadMesh.from_arrays(
        layout.vertices, layout.faces, tags=tuple(tags), source=layout.source
    )


def crease_gaps(layout: QuadMesh, segments: FloatArray) -> float:
    """How much of the scan's feature lines (``segments`` (S, 2, 3); the chains that count, as
    for :func:`snap_to_features`) no crease of ``layout`` follows: the length of the sharp
    segments whose midpoints lie farther than :data:`GAP_REACH` of the median layout edge from
    every crease edge, of the lines' whole length (0: every line is a crease chain; the fit
    rounds a line across a gap, a kink of 10–20° in the surface there)."""
    if not len(segments):
        return 0.0
    edges = layout.topology.edges
    scale = median_edge(layout)
    segments, _ = _lines(_pieces(segments, scale), np.zeros((0, 3)), CHAIN_EDGES * scale)
    if not len(segments):
        return 0.0
    weight = np.linalg.norm(segments[:, 1] - segments[:, 0], axis=1)
    creases = layout.vertices[edges[layout.features.edge_sharpness > 0]]
    if not len(creases):
        return 1.0
    middle = segments.mean(axis=1)
    gap = np.linalg.norm(_closest_on_segments(middle, creases) - middle, axis=1)
    return float(weight[gap > GAP_REACH * scale].sum() / weight.sum())


def boundary_reach(layout: QuadMesh) -> float:
    """The median length of ``layout``'s boundary edges (0 when it is closed)."""
    edges = boundary_edges(layout.faces)
    return median_edge(layout, edges) if len(edges) else 0.0


def boundary_corners(
    points: FloatArray, triangles: IntArray, degrees: float, reach: float
) -> FloatArray:
    """The scan's boundary vertices (C, 3) where its boundary polyline turns by more than
    ``degrees`` at the scale ``reach`` (a layout's boundary edge length): ``angle(p − p₋, p₊ − p)``,
    p± the first boundary vertices at least ``reach`` along the boundary before and after (at
    most :data:`CORNER_STEPS` edges, and under half the loop), and the largest turn among the
    vertices that near. A scanned rim zigzags by a triangle's width, turns of 60–120° from one
    edge to the next (the Stanford bunny's base holes: 13 such vertices, tied to its layout as
    corners they folded it; a range scan's ragged rim: 252), which cancel over a layout edge,
    while a corner's sides stay straight; a bend tighter than a layout edge is a corner to it."""
    edges = boundary_edges(triangles)
    if not len(edges):
        return np.zeros((0, 3))
    after = np.full(len(points), -1)
    before = np.full(len(points), -1)
    after[edges[:, 0]] = edges[:, 1]
    before[edges[:, 1]] = edges[:, 0]
    vertex = np.flatnonzero((after >= 0) & (before >= 0))
    loop = boundary_loops(edges, len(points))
    steps = np.clip((np.bincount(loop[vertex])[loop[vertex]] - 2) // 2, 1, CORNER_STEPS)
    ahead, behind = [vertex], [vertex]  # the vertices 0, 1, 2, … steps along, while short
    for step in range(1, CORNER_STEPS + 1):
        forward, backward = after[ahead[-1]], before[behind[-1]]
        short_ahead = np.linalg.norm(points[ahead[-1]] - points[vertex], axis=1) < reach
        short_behind = np.linalg.norm(points[behind[-1]] - points[vertex], axis=1) < reach
        ahead.append(np.where((step <= steps) & short_ahead & (forward >= 0), forward, ahead[-1]))
        behind.append(
            np.where((step <= steps) & short_behind & (backward >= 0), backward, behind[-1])
        )
        if (ahead[-1] == ahead[-2]).all() and (behind[-1] == behind[-2]).all():
            break
    into = points[vertex] - points[behind[-1]]
    out = points[ahead[-1]] - points[vertex]
    lengths = np.linalg.norm(into, axis=1) * np.linalg.norm(out, axis=1)
    cosine = np.ones(len(vertex))
    np.divide((into * out).sum(1), lengths, out=cosine, where=lengths > 0)
    turn = np.full(len(points), -np.inf)
    turn[vertex] = np.arccos(np.clip(cosine, -1.0, 1.0))
    peak = np.ones(len(vertex), dtype=bool)
    for forward, backward in zip(ahead[1:], behind[1:], strict=True):
        peak &= (forward == vertex) | (turn[vertex] >= turn[forward])  # ties: the first wins
        peak &= (backward == vertex) | (turn[vertex] > turn[backward])
    corner = peak & (turn[vertex] > np.radians(degrees))
    return np.asarray(points[vertex[corner]])


def layout_corners(layout: QuadMesh, corners: FloatArray) -> QuadMesh:
    """``layout`` with its boundary vertex nearest each scan boundary corner (``corners`` (C,
    3)) moved onto it and tagged ``corner`` (sharpness ∞), where it is within the layout's median
    boundary edge length of it: a corner farther off is on a scan boundary the layout does not
    have (a hole it bridges), and the layout vertex nearest it is some other boundary's."""
    boundary = np.unique(boundary_edges(layout.faces))
    if not len(corners) or not len(boundary):
        return layout
    reach = boundary_reach(layout)
    distance, index = cKDTree(layout.vertices[boundary]).query(corners)
    near = distance <= reach
    if not near.any():
        return layout
    nearest, corners = boundary[index[near]], corners[near]
    vertices = layout.vertices.copy()
    vertices[nearest] = corners
    tags = (*layout.tags, Tag("corner", tuple(np.unique(nearest).tolist()), (INFINITE_SHARPNESS,)))
    return QuadMesh.from_arrays(vertices, layout.faces, tags=tags, source=layout.source)
