"""Repairs of polygon meshes that :meth:`QuadMesh.from_arrays <g1patch.mesh.QuadMesh.from_arrays>`
would refuse.

Polygons are flat ``corners`` with ``sizes`` per face (corner ``i`` runs to the next corner of its
face). The rules, in this order, each vectorised over the whole mesh (Python loops run over rounds
only):

1. **Repeated vertex.** A face that visits a vertex twice is cut there into its loops, and loops of
   fewer than 3 corners are dropped: a consecutive duplicate goes, ``(a, b, a, c)`` vanishes (its
   loops ``(a, b)``, ``(a, c)`` are edges walked twice), ``(a, b, c, a, d, e)`` becomes the
   triangles ``(a, b, c)`` and ``(a, d, e)``. The polygons left go to the usual non-quad split.
2. **Non-manifold edges and vertices.** An edge of 3 or more faces is cut open: no two of its faces
   are neighbours across it. Then every vertex gets one copy per fan (the corners around it that
   are connected through its uncut edges), so every sheet is manifold; the first fan keeps the
   vertex, the others get new vertices at the same position, appended in vertex order.
3. **Orientation.** Faces are flipped (corner order reversed) so that each connected component is
   consistent: a two-colouring of the face graph whose edges say "same" or "opposite", from the
   components of its double cover. The majority of each component keeps its orientation (its
   first face's on a tie). A component that cannot be oriented (a Möbius strip) raises
   :class:`OrientationError` naming a face.
4. **Interior valence 2.** A vertex ``v`` whose only faces are ``(v, a, P…, b)`` and
   ``(v, b, Q…, a)`` (a closed fan of two) is dissolved: the faces merge into ``(a, P…, b, Q…)``,
   which keeps their orientation; two quads ``(v, a, x, b)``, ``(v, b, y, a)`` give the quad
   ``(a, x, b, y)``. Where ``P`` and ``Q`` share a vertex the merged face is cut by rule 1, which
   drops the edges it walks twice (a closed two-face pillow vanishes; say so). Rounds until no such
   vertex is left; in a round each face takes part in one merge at most (the claimant of lowest
   pseudo-random priority wins), so chains take a few rounds.

Vertices left without a face by a repair are dropped; vertices the input never used are left for
:meth:`~g1patch.mesh.QuadMesh.from_arrays`' own note. Tags follow: a ``corner`` names every copy of
its vertex, a ``crease`` pair every edge between copies of its two vertices, a ``hole`` every face
made from a hole (a merged face is a hole if either of its faces was); items whose vertex or edge a
repair removed are dropped, and said so. Every repair is counted and named, by input indices, in
:attr:`Repaired.repairs`.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from ..errors import DegenerateFaceError, MeshError, OrientationError, ValenceError
from .faces import _edge_keys, _following_corner
from .tags import FACE_TAGS, Tag
from .validate import _few

__all__ = ["Repaired", "repair_polygons"]

IntArray = NDArray[np.int64]
BoolArray = NDArray[np.bool_]

#: passes of rules 2–3: a cut edge whose faces meet again around both ends is paired anew and
#: oriented in the next pass; what is still wrong after these is left to the checks
SHEET_PASSES = 3


class Repaired(NamedTuple):
    """Repaired polygons over ``points`` (input positions, copies appended) and their tags."""

    points: NDArray[np.float64]
    corners: IntArray
    sizes: IntArray
    tags: tuple[Tag, ...]
    repairs: tuple[str, ...]
    #: per repaired corner, the input corner it comes from (what face-varying data follows)
    corner_source: IntArray | None = None
    #: whether faces were merged (rule 4): face-varying data cannot follow a merge
    merged: bool = False
    #: per repaired face, the input face it comes from (a merged face: the first of its two;
    #: what per-face data such as groups follows)
    face_source: IntArray | None = None


class _Polygons(NamedTuple):
    """Polygons in repair: ``source`` is each face's input face, ``holes`` (hole tags, faces) its
    hole flags, ``origin`` each vertex's input vertex."""

    corners: IntArray
    sizes: IntArray
    source: IntArray
    holes: BoolArray
    origin: IntArray
    corner_source: IntArray  # per corner, the input corner it comes from


def _plural(count: int, noun: str, plural: str | None = None) -> str:
    return f"{count} {noun if count == 1 else plural or noun + 's'}"


def _few_pairs(pairs: IntArray, limit: int = 3) -> str:
    text = ", ".join(f"({a}, {b})" for a, b in pairs[:limit].tolist())
    return text + (f" and {len(pairs) - limit} more" if len(pairs) > limit else "")


def _positions(sizes: IntArray) -> tuple[IntArray, IntArray]:
    """Each corner's face and its position in the face."""
    face = np.repeat(np.arange(sizes.size, dtype=np.int64), sizes)
    offsets = np.concatenate([[0], np.cumsum(sizes)[:-1]]).astype(np.int64)
    return face, np.arange(face.size, dtype=np.int64) - offsets[face]


def _regroup(
    p: _Polygons, face: IntArray, key: IntArray, keep: BoolArray, source: IntArray, holes: BoolArray
) -> _Polygons:
    """Corners ``keep`` re-sorted into faces ``face`` (ids into ``source``/``holes``) by ``key``;
    faces left with fewer than 3 corners are dropped, the others numbered in order."""
    selected = np.flatnonzero(keep)
    order = selected[np.lexsort((key[selected], face[selected]))]
    counts = np.bincount(face[order], minlength=source.size)
    alive = counts >= 3
    order = order[alive[face[order]]]
    return _Polygons(
        p.corners[order],
        counts[alive],
        source[alive],
        holes[:, alive],
        p.origin,
        p.corner_source[order],
    )


def _cut_repeats(p: _Polygons) -> tuple[_Polygons, IntArray]:
    """Rule 1: consecutive duplicates go at once, then each round cuts from every face that still
    repeats a vertex its shortest loop ``[i, j)`` between two visits; returns the sources of the
    faces that repeated a vertex."""
    face, position = _positions(p.sizes)
    following = _following_corner(p.sizes)
    duplicate = np.zeros(face.size, dtype=bool)
    duplicate[following] = p.corners[following] == p.corners
    repeating = [p.source[np.unique(face[duplicate])]]
    if duplicate.any():
        p = _regroup(p, face, position, ~duplicate, p.source, p.holes)
    while True:
        face, position = _positions(p.sizes)
        order = np.argsort(
            face * p.origin.size + p.corners, kind="stable"
        )  # by face, vertex, position
        again = (face[order][1:] == face[order][:-1]) & (
            p.corners[order][1:] == p.corners[order][:-1]
        )
        if not again.any():
            break
        first, second = order[:-1][again], order[1:][again]
        span = position[second] - position[first]
        shortest = np.lexsort((span, face[first]))
        keep = np.ones(shortest.size, dtype=bool)
        keep[1:] = face[first][shortest][1:] != face[first][shortest][:-1]
        cut_face = face[first][shortest][keep]
        start, stop = position[first][shortest][keep], position[second][shortest][keep]
        loop = np.full(p.sizes.size, -1, dtype=np.int64)
        loop[cut_face] = np.arange(cut_face.size)
        index = loop[face]
        inside = (index >= 0) & (position >= start[index]) & (position < stop[index])
        new_face = np.where(inside, p.sizes.size + index, face)
        repeating.append(p.source[cut_face])
        p = _regroup(
            p,
            new_face,
            position,
            np.ones(face.size, dtype=bool),
            np.concatenate([p.source, p.source[cut_face]]),
            np.concatenate([p.holes, p.holes[:, cut_face]], axis=1),
        )
    return p, np.unique(np.concatenate(repeating))


class _Pairs(NamedTuple):
    """Half-edges grouped by undirected edge: pairs ``(first, second)`` of 2-face edges, and the
    half-edges of edges with 3 or more faces."""

    first: IntArray
    second: IntArray
    crowded: IntArray
    crowded_edges: IntArray  # (k, 2) vertex pairs
    crowded_counts: IntArray


def _pairs(corners: IntArray, sizes: IntArray, n_vertices: int) -> _Pairs:
    keys = _edge_keys(corners, sizes, n_vertices)
    order = np.argsort(keys, kind="stable")
    sorted_keys = keys[order]
    starts = np.flatnonzero(np.concatenate([[True], sorted_keys[1:] != sorted_keys[:-1]]))
    counts = np.diff(np.append(starts, keys.size))
    two = starts[counts == 2]
    many = counts >= 3
    crowded = order[np.repeat(many, counts)]
    edges = sorted_keys[starts[many]]
    return _Pairs(
        order[two],
        order[two + 1],
        crowded,
        np.stack([edges // n_vertices, edges % n_vertices], axis=1),
        counts[many],
    )


def _components(n: int, a: IntArray, b: IntArray) -> IntArray:
    graph = coo_matrix((np.ones(a.size, dtype=np.int8), (a, b)), shape=(n, n))
    return connected_components(graph, directed=False)[1]


class _Notes:
    """What the repairs did, by input indices, to be named in one line."""

    def __init__(self) -> None:
        self.ids: dict[str, list[IntArray]] = {}

    def add(self, what: str, ids: IntArray) -> None:
        if ids.size:
            self.ids.setdefault(what, []).append(ids)

    def get(self, what: str) -> IntArray:
        return np.concatenate(self.ids[what]) if what in self.ids else np.zeros(0, dtype=np.int64)


def _sheets(p: _Polygons, notes: _Notes) -> tuple[_Polygons, bool]:
    """Rules 2 and 3 on one grouping of half-edges: cut crowded edges, one vertex copy per fan,
    then flip the minority of each component; returns whether anything changed."""
    n_vertices = p.origin.size
    pairs = _pairs(p.corners, p.sizes, n_vertices)
    following = _following_corner(p.sizes)
    face, position = _positions(p.sizes)
    same = p.corners[pairs.first] == p.corners[pairs.second]

    # fans: corners of one vertex joined across the uncut edges at it
    here, there = pairs.second, following[pairs.second]
    ends = np.concatenate([pairs.first, following[pairs.first]])
    partners = np.concatenate([np.where(same, here, there), np.where(same, there, here)])
    fan = _components(face.size, ends, partners)
    fan_vertex = np.empty(int(fan.max()) + 1, dtype=np.int64)
    fan_vertex[fan] = p.corners
    fan_first = np.full(fan_vertex.size, face.size, dtype=np.int64)
    np.minimum.at(fan_first, fan, np.arange(face.size))
    vertex_first = np.full(n_vertices, face.size, dtype=np.int64)
    np.minimum.at(vertex_first, p.corners, np.arange(face.size))
    extra = np.flatnonzero(fan_first != vertex_first[fan_vertex])
    extra = extra[np.lexsort((fan_first[extra], fan_vertex[extra]))]
    fan_new = fan_vertex.copy()
    fan_new[extra] = n_vertices + np.arange(extra.size)
    corners = fan_new[fan]
    origin = np.concatenate([p.origin, p.origin[fan_vertex[extra]]])

    # orientation: (f, 0) and (f, 1) of the double cover are one component on a non-orientable sheet
    f1, f2, flip_pair = face[pairs.first], face[pairs.second], same.astype(np.int64)
    n_faces = p.sizes.size
    cover = (
        np.concatenate([2 * f1, 2 * f1 + 1]),
        np.concatenate([2 * f2 + flip_pair, 2 * f2 + 1 - flip_pair]),
    )
    label = _components(2 * n_faces, *cover)
    up, down = label[0::2], label[1::2]
    twisted = np.flatnonzero(up == down)
    if twisted.size:
        bad = np.unique(p.source[twisted])
        raise OrientationError(
            f"face {bad[0]} lies on a non-orientable sheet (like a Möbius strip): its faces "
            "cannot all be "
            f"oriented consistently ({_plural(bad.size, 'face')} on such sheets: {_few(bad)})"
        )
    component = np.minimum(up, down)
    side = up != component
    total = np.bincount(component, minlength=2 * n_faces)
    upper = np.bincount(component, weights=side, minlength=2 * n_faces).astype(np.int64)[component]
    lower = total[component] - upper
    first_face = np.full(2 * n_faces, n_faces, dtype=np.int64)
    np.minimum.at(first_face, component, np.arange(n_faces))
    kept = np.where(upper == lower, side[first_face[component]], upper > lower)
    flip = side != kept

    crowded_ends = np.zeros(n_vertices, dtype=bool)
    crowded_ends[pairs.crowded_edges.ravel()] = True
    copied = fan_vertex[extra]
    if pairs.crowded.size:
        notes.add("edges", np.sort(p.origin[pairs.crowded_edges], axis=1).ravel())
        notes.add("edge faces", pairs.crowded_counts)
        notes.add("edge copies", p.origin[copied[crowded_ends[copied]]])
    notes.add("vertices", p.origin[copied[~crowded_ends[copied]]])
    notes.add("flipped", p.source[flip])

    split = _Polygons(corners, p.sizes, p.source, p.holes, origin, p.corner_source)
    if flip.any():
        reversed_position = np.where(
            flip[face], (p.sizes[face] - position) % p.sizes[face], position
        )
        split = _regroup(
            split, face, reversed_position, np.ones(face.size, dtype=bool), p.source, p.holes
        )
    return split, bool(pairs.crowded.size or extra.size or flip.any())


def _dissolve(p: _Polygons, notes: _Notes) -> _Polygons:
    """Rule 4 in rounds: merge the two faces of each chosen interior valence-2 vertex."""
    rng = np.random.default_rng(0)
    while p.sizes.size:
        n_vertices = p.origin.size
        face, position = _positions(p.sizes)
        following = _following_corner(p.sizes)
        pairs = _pairs(p.corners, p.sizes, n_vertices)
        paired = np.zeros(face.size, dtype=bool)
        paired[pairs.first] = paired[pairs.second] = True
        open_vertex = np.zeros(n_vertices, dtype=bool)
        open_vertex[p.corners[~paired]] = open_vertex[p.corners[following[~paired]]] = True
        candidate = (np.bincount(p.corners, minlength=n_vertices) == 2) & ~open_vertex
        if not candidate.any():
            break
        priority = rng.permutation(n_vertices)
        at = np.flatnonzero(candidate[p.corners])
        claim = np.full(p.sizes.size, n_vertices, dtype=np.int64)
        np.minimum.at(claim, face[at], priority[p.corners[at]])
        won = at[claim[face[at]] == priority[p.corners[at]]]
        both = np.bincount(p.corners[won], minlength=n_vertices) == 2
        won = won[both[p.corners[won]]]
        won = won[
            np.argsort(p.corners[won], kind="stable")
        ]  # the two corners of each vertex, in face order
        c1, c2 = won[0::2], won[1::2]
        f1, f2 = face[c1], face[c2]
        n1, n2 = p.sizes[f1], p.sizes[f2]

        # (v, a, P…, b) keeps keys 1…n1−1 of f1; (v, b, Q…, a) gives Q at keys n1 + 2 … n1 + n2 − 2
        role1 = np.full(p.sizes.size, -1, dtype=np.int64)
        role2 = np.full(p.sizes.size, -1, dtype=np.int64)
        role1[f1] = role2[f2] = np.arange(f1.size)
        key, new_face = position.copy(), face.copy()
        keep = np.ones(face.size, dtype=bool)
        r1, r2 = role1[face], role2[face]
        in1, in2 = r1 >= 0, r2 >= 0
        relative1 = (position[in1] - position[c1][r1[in1]]) % n1[r1[in1]]
        relative2 = (position[in2] - position[c2][r2[in2]]) % n2[r2[in2]]
        key[in1] = relative1
        key[in2] = n1[r2[in2]] + relative2
        new_face[in2] = f1[r2[in2]]
        keep[np.flatnonzero(in1)[relative1 == 0]] = False
        keep[np.flatnonzero(in2)[(relative2 < 2) | (relative2 == n2[r2[in2]] - 1)]] = False
        holes = p.holes.copy()
        holes[:, f1] |= p.holes[:, f2]
        # merged faces carry the marker −1 − k as source until rule 1 has cut them
        source = p.source.copy()
        source[f1] = -1 - np.arange(f1.size)

        notes.add("dissolved", p.origin[p.corners[c1]])
        parents = np.stack([p.source[f1], p.source[f2]], axis=1)
        p, _ = _cut_repeats(_regroup(p, new_face, key, keep, source, holes))
        marker = p.source < 0
        notes.add("merge dropped", np.delete(parents, -1 - p.source[marker], axis=0).ravel())
        restored = p.source.copy()
        restored[marker] = parents[-1 - p.source[marker], 0]
        p = p._replace(source=restored)
    return p


class _EdgeTable(NamedTuple):
    """The repaired edges ``(a, b)`` sorted by the input edge they come from, and the input's
    edges."""

    a: IntArray
    b: IntArray
    input_keys: IntArray  # per repaired edge, sorted
    input_edges: IntArray  # sorted keys of the input's edges


def _edge_table(p: _Polygons, corners: IntArray, sizes: IntArray, n_input: int) -> _EdgeTable:
    keys = np.unique(_edge_keys(p.corners, p.sizes, p.origin.size))
    a, b = keys // p.origin.size, keys % p.origin.size
    low, high = np.minimum(p.origin[a], p.origin[b]), np.maximum(p.origin[a], p.origin[b])
    order = np.lexsort((high, low))
    input_edges = np.unique(_edge_keys(corners, sizes, n_input))
    return _EdgeTable(a[order], b[order], (low * n_input + high)[order], input_edges)


def _matches(sorted_keys: IntArray, wanted: IntArray) -> tuple[IntArray, IntArray]:
    """For each wanted key, the positions of its matches in ``sorted_keys`` (concatenated), and
    their counts."""
    start = np.searchsorted(sorted_keys, wanted, side="left")
    counts = np.searchsorted(sorted_keys, wanted, side="right") - start
    offsets = np.cumsum(counts) - counts
    return np.repeat(start - offsets, counts) + np.arange(int(counts.sum())), counts


def _repeat_floats(tag: Tag, counts: IntArray) -> tuple[float, ...]:
    """One sharpness per item stays one per item (repeated like the items); one for all stays."""
    return (
        tuple(np.repeat(tag.floats, counts).tolist())
        if len(tag.floats) == counts.size > 1
        else tag.floats
    )


def _carry_tags(
    tags: Sequence[Tag],
    p: _Polygons,
    corners: IntArray,
    sizes: IntArray,
    n_input: int,
    notes: _Notes,
) -> tuple[Tag, ...]:
    """Corners to every copy of their vertex, crease pairs to every edge between copies of their
    ends, holes to the faces made from holes (module docstring); ``corners``, ``sizes`` are the
    input's."""
    by_origin = np.argsort(p.origin, kind="stable")
    edges = (
        _edge_table(p, corners, sizes, n_input)
        if any(tag.name == "crease" for tag in tags)
        else None
    )
    carried = []
    hole_tag = 0
    for tag in tags:
        ints = np.asarray(tag.ints, dtype=np.int64)
        if tag.name == "corner":
            found, counts = _matches(p.origin[by_origin], ints)
            notes.add("tag items", ints[counts == 0])
            tag = tag._replace(
                ints=tuple(by_origin[found].tolist()), floats=_repeat_floats(tag, counts)
            )
        elif tag.name == "crease" and edges is not None:
            u, w = ints[0::2], ints[1::2]
            keys = np.minimum(u, w) * n_input + np.maximum(u, w)
            not_edge = np.flatnonzero(~np.isin(keys, edges.input_edges))
            if not_edge.size:
                raise MeshError(
                    f"tag 'crease' names ({u[not_edge[0]]}, {w[not_edge[0]]}), which is not an edge"
                )
            found, counts = _matches(edges.input_keys, keys)
            notes.add("tag items", u[counts == 0])
            pairs = np.stack([edges.a[found], edges.b[found]], axis=1)
            tag = tag._replace(
                ints=tuple(pairs.ravel().tolist()), floats=_repeat_floats(tag, counts)
            )
        elif tag.name in FACE_TAGS:
            tag = tag._replace(ints=tuple(np.flatnonzero(p.holes[hole_tag]).tolist()))
            hole_tag += 1
        carried.append(tag)
    return tuple(carried)


def _phrases(notes: _Notes) -> tuple[str, ...]:
    """The repairs as short phrases, input indices named (the first few)."""
    lines = []
    repeated = notes.get("repeated")
    if repeated.size:
        polygons = notes.get("polygons").size
        lines.append(
            f"{_plural(repeated.size, 'face')} repeating a vertex ({_few(repeated)}) reduced to "
            f"{_plural(polygons, 'simple polygon')}"
        )
    dropped = notes.get("dropped")
    if dropped.size:
        lines.append(f"{_plural(dropped.size, 'degenerate face')} ({_few(dropped)}) dropped")
    edges = notes.get("edges").reshape(-1, 2)
    if edges.size:
        faces = notes.get("edge faces")
        counts = (
            f"{faces.min()}" if faces.min() == faces.max() else f"{faces.min()} to {faces.max()}"
        )
        named = _few_pairs(edges) if len(edges) == 1 else f"({_few_pairs(edges)})"
        copies = _plural(notes.get("edge copies").size, "vertex copy", "vertex copies")
        edge_count = _plural(len(edges), "non-manifold edge")
        lines.append(f"{edge_count} {named} with {counts} faces split into sheets (+{copies})")
    vertices = np.unique(notes.get("vertices"))
    if vertices.size:
        lines.append(
            f"{_plural(vertices.size, 'non-manifold vertex', 'non-manifold vertices')} "
            f"({_few(vertices)}) split into "
            f"one copy per fan (+{_plural(notes.get('vertices').size, 'vertex', 'vertices')})"
        )
    flipped = np.unique(notes.get("flipped"))
    if flipped.size:
        lines.append(f"{_plural(flipped.size, 'face')} ({_few(flipped)}) reoriented")
    dissolved = notes.get("dissolved")
    if dissolved.size:
        named = _plural(dissolved.size, "valence-2 vertex", "valence-2 vertices")
        lines.append(f"{named} ({_few(np.sort(dissolved))}) dissolved")
    merge_dropped = np.unique(notes.get("merge dropped"))
    if merge_dropped.size:
        named = _plural(merge_dropped.size, "face")
        lines.append(f"{named} ({_few(merge_dropped)}) dropped: their merge left no polygon")
    orphans = np.unique(notes.get("orphans"))
    if orphans.size:
        lines.append(
            f"{_plural(orphans.size, 'vertex', 'vertices')} left without a face ({_few(orphans)}) "
            "dropped"
        )
    tag_items = notes.get("tag items")
    if tag_items.size:
        named = _plural(tag_items.size, "tag item")
        lines.append(f"{named} on removed vertices or edges ({_few(tag_items)}) dropped")
    return tuple(lines)


def repair_polygons(
    points: NDArray[np.float64], corners: IntArray, sizes: IntArray, tags: Sequence[Tag] = ()
) -> Repaired:
    """Apply the module's rules to checked polygons (indices in range, ≥ 3 corners, tags naming
    existing items); ``repairs`` is empty when there was nothing to repair."""
    n_input = points.shape[0]
    hole_tags = [tag for tag in tags if tag.name in FACE_TAGS]
    holes = np.zeros((len(hole_tags), sizes.size), dtype=bool)
    for row, tag in enumerate(hole_tags):
        holes[row, np.asarray(tag.ints, dtype=np.int64)] = True
    p = _Polygons(
        corners,
        sizes,
        np.arange(sizes.size, dtype=np.int64),
        holes,
        np.arange(n_input, dtype=np.int64),
        np.arange(corners.size, dtype=np.int64),
    )
    notes = _Notes()

    p, repeating = _cut_repeats(p)
    notes.add("repeated", repeating[np.isin(repeating, p.source)])
    notes.add("polygons", p.source[np.isin(p.source, repeating)])
    notes.add("dropped", repeating[~np.isin(repeating, p.source)])
    if not p.sizes.size:
        raise DegenerateFaceError(
            f"no face is left after the repairs ({', '.join(_phrases(notes))})"
        )
    for _ in range(SHEET_PASSES):
        p, changed = _sheets(p, notes)
        if not changed:
            break
    p = _dissolve(p, notes)
    if not p.sizes.size:
        raise ValenceError(f"no face is left after the repairs ({', '.join(_phrases(notes))})")

    used_before = np.zeros(n_input, dtype=bool)
    used_before[corners] = True
    used = np.bincount(p.corners, minlength=p.origin.size) > 0
    keep = used | ~used_before[p.origin]
    notes.add("orphans", np.setdiff1d(p.origin[~keep], notes.get("dissolved")))
    index = np.cumsum(keep) - 1
    p = p._replace(corners=index[p.corners], origin=p.origin[keep])
    carried = _carry_tags(tags, p, corners, sizes, n_input, notes)
    return Repaired(
        points[p.origin],
        p.corners,
        p.sizes,
        carried,
        _phrases(notes),
        p.corner_source,
        bool(notes.get("dissolved").size),
        p.source,
    )
