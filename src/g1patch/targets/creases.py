"""Sharp features in the targets: sectors, crease curves and each sector's own tangent plane.

A *seam* is an interior edge the surface crosses with a crease on purpose (a tagged sharp edge);
the seams and the boundary cut the ring of a vertex into *sectors*, the runs of faces reached
without crossing one. A vertex with one sector (no seam, or a single seam ending there: a
*dart*) keeps the smooth rule's targets and is G1 at its corner. At a vertex with several:

* **crease** (two seams, not tagged as a corner, turning by less than 90°): the crease curve
  is tangent-continuous through it. Its direction is the tangent of the circle through the
  vertex and its two crease neighbours A, B, ``d ∥ |c_A|² c_B − |c_B|² c_A`` with
  ``c = neighbour − vertex``; each crease slot gets the circle-aware length
  ``2|c| / (1 + ĉ·d)`` along ±d. Each sector's plane contains d and fits the sector's own faces:
  ``N_s ∥ m_s − (m_s·d) d``, m_s the area-weighted fan normal of the sector's faces;
* **corner** (three or more cuts, or tagged, or a crease turning by 90° or more): each sector is
  the plane of its two bounding tangents, ``N_s ∥ ±(t_a × t_b)`` oriented with m_s (the fan
  normal stands in, made perpendicular to t_a, where the two are parallel). A crease slot at
  a corner mirrors the tangent at its far end about the chord (the symmetric arc through both
  ends, ``u = 2(ĉ·g) ĉ − g`` with g the far end's travel direction) or, when the far end is a
  corner too, runs along the chord (so the edges of a box with all edges sharp are straight).
  A corner sector whose two tangents span no plane along its faces takes its fan normal
  instead (:func:`ridge_corners` with two seams under the limit rule, :func:`loose_corners`
  with more under both).

The smooth slots of such a vertex are the chord projected onto their sector's plane, circle-aware
length; a sector whose slots would not turn counter-clockwise inside it gets them spread evenly
(counted as a fallback). The interior targets of such corners take the bilinear twist, since a
shape operator fitted across the crease means nothing there.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ..mesh import INFINITE_SHARPNESS, QuadMesh, QuadTopology, Sectors, sectors
from .local import cross
from .value import halfedge_slots

__all__ = [
    "INTERPOLATE_SHARPNESS",
    "crease_tangents",
    "loose_corners",
    "ridge_corners",
    "sector_fan_normals",
    "seam_edges",
    "sharp_vertices",
    "spread_sectors",
]

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]
BoolArray = NDArray[np.bool_]

#: in ``interpolate`` mode a semi-sharp edge or vertex of sharpness ≥ this is sharp, below it
#: smooth (an interpolating surface has no subdivision levels to spend the sharpness on)
INTERPOLATE_SHARPNESS = 1.0
#: bounding tangents closer to parallel than this (|t̂_a × t̂_b|) do not define a sector plane
_PARALLEL = 0.02
#: a two-seam corner whose sector plane (spanned by its crease tangents) has a cosine below this
#: with some sector's own fan normal (more than ~37° off its faces) is taken as a crease
_ACROSS = 0.8
#: a limit corner whose two seam tangents span a plane with a cosine below this (25°) with a
#: sector's fan normal is taken as a crease (:func:`ridge_corners`): a sector of three faces
#: whose seam chords span a plane 34° off its faces had its inner slots squeezed into it nearly
#: parallel to the seams, and the Gregory corner split failed
_RIDGE = 0.9
#: the largest turn between consecutive slots of a creased sector (radians, a little under π)
_HALF_TURN = 0.95 * np.pi
#: two loose sectors' planes (:func:`loose_corners`) meeting at a sine of at least this (11°) share
#: their seam's line; below it the line is ill-defined and the seam is moved into one plane
_SHARED_LINE = 0.2
#: a far-end tangent this close to perpendicular to the chord (ĉ·g) is not mirrored
_MIRROR_MIN = 0.1


def _dot(a: FloatArray, b: FloatArray) -> FloatArray:
    return np.einsum("...d,...d->...", a, b)


def _unit(v: FloatArray) -> FloatArray:
    length = np.linalg.norm(v, axis=-1, keepdims=True)
    return v / np.where(length > 0, length, 1.0)


def seam_edges(mesh: QuadMesh, threshold: float = INFINITE_SHARPNESS) -> BoolArray:
    """Interior edges whose sharpness is at least ``threshold`` (E,): the surface creases there."""
    return (mesh.features.edge_sharpness >= threshold) & ~mesh.topology.is_boundary_edge


def sharp_vertices(mesh: QuadMesh, threshold: float = INFINITE_SHARPNESS) -> BoolArray:
    """Vertices tagged as corners with a sharpness of at least ``threshold`` (V,)."""
    return mesh.features.vertex_sharpness >= threshold


def sector_fan_normals(mesh: QuadMesh, found: Sectors) -> FloatArray:
    """Area-weighted fan normal of each sector's face corners, ``Σ (x_next − x) × (x_prev − x)``
    (not unit)."""
    topology = mesh.topology
    x = mesh.vertices
    here = x[topology.faces]
    corner = cross(np.roll(here, -1, axis=1) - here, np.roll(here, 1, axis=1) - here).reshape(-1, 3)
    per_position = corner[topology.ring_halfedges]
    n_sectors = found.vertex.size
    return np.stack(
        [np.bincount(found.label, per_position[:, d], minlength=n_sectors) for d in range(3)],
        axis=1,
    )


def _loose_sectors(
    found: Sectors, tangents: FloatArray, fan: FloatArray, at: BoolArray, least_faces: int = 1
) -> tuple[IntArray, FloatArray, FloatArray, FloatArray, BoolArray, BoolArray]:
    """The sectors bounded by two slots at the vertices ``at`` (V,) that have a *loose* one —
    of at least ``least_faces`` faces, whose bounding tangents ``t_a``, ``t_b`` span no plane
    along its faces: nearly parallel (``|t̂_a × t̂_b| <`` :data:`_PARALLEL`) or across (the
    plane's cosine with the sector's unit ``fan`` normal below :data:`_RIDGE`) — with their
    ``t_a``, ``t_b``, unit fan normals and which are loose; and those vertices (V,)."""
    mine = np.flatnonzero(at[found.vertex] & (found.start >= 0))
    t_a, t_b = tangents[found.start[mine]], tangents[found.end[mine]]
    plane = cross(_unit(t_a), _unit(t_b))
    m = _unit(fan[mine])
    loose = (np.linalg.norm(plane, axis=1) < _PARALLEL) | (np.abs(_dot(_unit(plane), m)) < _RIDGE)
    loose &= np.bincount(found.label, minlength=found.vertex.size)[mine] >= least_faces
    hit = np.zeros(at.size, dtype=bool)
    hit[found.vertex[mine[loose]]] = True
    chosen = hit[found.vertex[mine]]
    return mine[chosen], t_a[chosen], t_b[chosen], m[chosen], loose[chosen], hit


def ridge_corners(
    topology: QuadTopology,
    found: Sectors,
    tangents: FloatArray,
    fan: FloatArray,
    corner_vertices: BoolArray,
) -> tuple[FloatArray, FloatArray, BoolArray]:
    """Interior corners with two seams whose seam tangents ``t_a``, ``t_b`` span no plane along
    their sectors — nearly parallel (``|t̂_a × t̂_b| <`` :data:`_PARALLEL`) or across (the plane's
    cosine with a sector's fan normal below :data:`_RIDGE`: a ridge's apex, where a plane
    holding both stands on edge) — taken as crease vertices, as the interpolating rule does:
    the seam slots become ``±|t| d`` along ``d ∥ t̂_a − t̂_b`` and each sector's normal its
    ``fan`` normal (per sector, :func:`sector_fan_normals`) made perpendicular to d, so that
    both sectors hold the shared seam tangents and their own faces. Returns the ``tangents``
    (slots) changed there, the sectors' unit normals (zero elsewhere) and which vertices."""
    two = corner_vertices & ~topology.is_boundary_vertex & (found.cuts == 2)
    mine, t_a, t_b, m, _, ridge = _loose_sectors(found, tangents, fan, two)
    out, normals = tangents.copy(), np.zeros_like(fan)
    d = _unit(_unit(t_a) - _unit(t_b))
    out[found.start[mine]] = np.linalg.norm(t_a, axis=1)[:, None] * d
    out[found.end[mine]] = -np.linalg.norm(t_b, axis=1)[:, None] * d
    normals[mine] = _unit(m - _dot(m, d)[:, None] * d)
    return out, normals, ridge


def loose_corners(
    topology: QuadTopology,
    found: Sectors,
    tangents: FloatArray,
    fan: FloatArray,
    corner_vertices: BoolArray,
) -> tuple[FloatArray, FloatArray, BoolArray]:
    """Interior corners with three or more seams where a sector of two or more faces has seam
    tangents that span no plane along its faces (nearly parallel or across, as in
    :func:`ridge_corners`: the straight bar of a T where a third crease ends on it, whose chords
    span a plane standing on edge; a one-face sector's plane is its two tangents', however its
    face is bent, as on a cube with a rounded edge). Such a
    *loose* sector takes its ``fan`` normal made perpendicular to ``d ∥ t̂_a − t̂_b`` and its seam
    tangents are moved into that plane (length kept; a seam between two loose sectors onto the
    line both planes share, ``∥ N_L × N_R``, where they meet at 11° or more); every other sector
    there takes the plane its (moved) seam tangents span, oriented with its fan normal. Returns
    the ``tangents`` (slots) changed there, the sectors' unit normals (zero elsewhere) and which
    vertices."""
    many = corner_vertices & ~topology.is_boundary_vertex & (found.cuts > 2)
    mine, t_a, t_b, m, loose, hit = _loose_sectors(found, tangents, fan, many, least_faces=2)
    out, normals = tangents.copy(), np.zeros_like(fan)
    if not mine.size:
        return out, normals, hit
    d = _unit(_unit(t_a) - _unit(t_b))
    flat = _unit(m - _dot(m, d)[:, None] * d)
    is_loose = np.zeros(found.vertex.size, dtype=bool)
    is_loose[mine] = loose
    normals[mine] = flat
    after = np.full(len(tangents), -1, dtype=np.int64)  # the sector a seam slot starts
    after[found.start[mine]] = mine
    seam, left = found.end[mine], mine  # each seam slot once, with the sector it ends
    right = after[seam]
    t = tangents[seam]
    one = np.where(is_loose[left], left, right)
    into = t - _dot(t, normals[one])[:, None] * normals[one]
    line = cross(normals[left], normals[right])
    onto = _unit(line) * _dot(t, _unit(line))[:, None]
    both = is_loose[left] & is_loose[right] & (np.linalg.norm(line, axis=1) >= _SHARED_LINE)
    moved = np.where(both[:, None], onto, into)
    moved = _unit(moved) * np.linalg.norm(t, axis=1)[:, None]
    out[seam] = np.where((is_loose[left] | is_loose[right])[:, None], moved, t)
    own = cross(out[found.start[mine]], out[found.end[mine]])
    own *= np.sign(_dot(own, m))[:, None]
    normals[mine] = np.where(loose[:, None], flat, _unit(own))
    return out, normals, hit


def _circle_lengths(chord: FloatArray, direction: FloatArray) -> FloatArray:
    """Hermite tangent length of the circular arc leaving along unit ``direction`` through the
    chord's end: ``2|c| / (1 + ĉ·d)``."""
    length = np.linalg.norm(chord, axis=-1)
    cosine = _dot(chord, direction) / np.where(length > 0, length, 1.0)
    return 2.0 * length / (1.0 + np.maximum(cosine, _MIRROR_MIN))


def crease_tangents(
    mesh: QuadMesh, seams: BoolArray, tangents: FloatArray, corner_vertices: BoolArray
) -> tuple[FloatArray, FloatArray, BoolArray, BoolArray]:
    """The slot tangents and corner normals of the creased vertices (module docstring).

    ``tangents`` (S, 3) are the smooth rule's; ``corner_vertices`` (V,) are tagged corners.
    Returns ``(tangents, corner_normals (F, 4, 3) or zeros where the vertex is not creased,
    creased (V,), spread (V,): vertices whose sector fans had to be spread)``.
    """
    topology = mesh.topology
    x = mesh.vertices
    found = sectors(topology, seams)
    creased = found.creased
    out = tangents.copy()
    offsets = topology.neighbor_offsets
    slot_vertex = np.repeat(np.arange(topology.n_vertices), np.diff(offsets))
    chord = x[topology.neighbors] - x[slot_vertex]
    slot_cut = np.zeros(offsets[-1], dtype=bool)
    slot_cut[found.start[found.start >= 0]] = True
    slot_cut[found.end[found.end >= 0]] = True
    slot_cut &= creased[slot_vertex]
    fan = sector_fan_normals(mesh, found)

    # two-seam vertices: the crease curve runs through, tangent to the circle through both
    # neighbours
    seam_slot = slot_cut & ~_boundary_slots(topology)
    two_seams = creased & ~topology.is_boundary_vertex & (found.cuts == 2)
    two = np.flatnonzero(seam_slot & two_seams[slot_vertex]).reshape(-1, 2)  # slots in vertex order
    two_vertex = slot_vertex[two[:, 0]]
    c_a, c_b = chord[two[:, 0]], chord[two[:, 1]]
    d = _unit(_dot(c_a, c_a)[:, None] * c_b - _dot(c_b, c_b)[:, None] * c_a)
    crease_direction = np.zeros((topology.n_vertices, 3))
    crease_direction[two_vertex] = d
    # a corner where tagged or where the crease turns by 90° or more (a sector of one face between
    # two creases then gets a straight corner: the crease curve runs through, as in OpenSubdiv)
    corner = creased.copy()
    corner[two_vertex] = corner_vertices[two_vertex] | (_dot(_unit(c_a), _unit(c_b)) > 0.0)
    out[two[:, 1]] = _circle_lengths(c_b, d)[:, None] * d
    out[two[:, 0]] = -_circle_lengths(c_a, -d)[:, None] * d

    # corners: seam slots mirror their far end's tangent, or follow the chord between two corners
    mirror = np.flatnonzero(seam_slot & corner[slot_vertex])
    far = _reverse_slots(topology)[mirror]
    far_vertex = slot_vertex[far]
    unit_chord = _unit(chord[mirror])
    g = -_unit(out[far])
    along = _dot(unit_chord, g)
    mirrored = ~corner[far_vertex] & (along > _MIRROR_MIN)
    u = np.where(mirrored[:, None], 2.0 * along[:, None] * unit_chord - g, unit_chord)
    corner_tangents = out.copy()
    corner_tangents[mirror] = _circle_lengths(chord[mirror], u)[:, None] * u

    # corner sector planes: the span of the bounding tangents, oriented with the sector's faces
    t_a, t_b = _unit(corner_tangents[found.start]), _unit(corner_tangents[found.end])
    plane = cross(t_a, t_b)
    m = _unit(fan)
    unit_plane = _unit(plane)
    flat = np.linalg.norm(plane, axis=1) < _PARALLEL
    n_corner = _unit(
        np.where(
            flat[:, None],
            m - _dot(m, t_a)[:, None] * t_a,
            np.where(_dot(plane, m)[:, None] < 0, -unit_plane, unit_plane),
        )
    )
    # a two-seam corner whose tangents span a plane across its sectors (a ridge's apex) is a crease
    across = np.zeros(topology.n_vertices, dtype=bool)
    across[found.vertex[(found.start >= 0) & (np.abs(_dot(n_corner, m)) < _ACROSS)]] = True
    corner[two_vertex] &= ~across[two_vertex]
    crease = creased & ~corner
    at_corner_slot = corner[slot_vertex]
    out[at_corner_slot] = corner_tangents[at_corner_slot]

    n_sector = np.zeros_like(fan)
    at_crease = crease[found.vertex]
    dc = crease_direction[found.vertex[at_crease]]
    n_sector[at_crease] = _unit(fan[at_crease] - _dot(fan[at_crease], dc)[:, None] * dc)
    at_corner = corner[found.vertex]
    n_sector[at_corner] = n_corner[at_corner]
    # three or more seams, a sector spanning no plane along its faces (a T's bar): its fan's
    out, loose_normals, loose = loose_corners(topology, found, out, fan, corner)
    n_sector[loose[found.vertex]] = loose_normals[loose[found.vertex]]

    # smooth slots of creased vertices: the chord in the sector's plane, circle-aware
    inner_position = np.flatnonzero(
        creased[np.repeat(np.arange(topology.n_vertices), topology.face_count)]
    )
    ring_vertex = np.repeat(np.arange(topology.n_vertices), topology.face_count)
    inner_slot = (
        offsets[ring_vertex[inner_position]]
        + inner_position
        - topology.ring_offsets[ring_vertex[inner_position]]
    )
    keep = ~slot_cut[inner_slot]
    inner_slot, inner_position = inner_slot[keep], inner_position[keep]
    n = n_sector[found.label[inner_position]]
    c = chord[inner_slot]
    s = c - _dot(c, n)[:, None] * n
    in_plane = np.linalg.norm(s, axis=1)
    length = np.linalg.norm(c, axis=1)
    scale = 2.0 * length**2 / ((length + in_plane) * np.where(in_plane > 0, in_plane, 1.0))
    out[inner_slot] = s * scale[:, None]
    spread = spread_sectors(topology, found, out, n_sector, creased, chord)

    corner_normals = np.zeros((topology.n_faces * 4, 3))
    corner_positions = np.flatnonzero(creased[ring_vertex])
    corner_normals[topology.ring_halfedges[corner_positions]] = n_sector[
        found.label[corner_positions]
    ]
    return out, corner_normals.reshape(-1, 4, 3), creased, spread


def _boundary_slots(topology: QuadTopology) -> BoolArray:
    """The first and the last (virtual) slot of every boundary vertex."""
    out = np.zeros(int(topology.neighbor_offsets[-1]), dtype=bool)
    boundary = np.flatnonzero(topology.is_boundary_vertex)
    out[topology.neighbor_offsets[boundary]] = True
    out[topology.neighbor_offsets[boundary + 1] - 1] = True
    return out


def _reverse_slots(topology: QuadTopology) -> IntArray:
    """For every slot A → B the slot B → A."""
    slot_out, slot_in = halfedge_slots(topology)
    out = np.empty(int(topology.neighbor_offsets[-1]), dtype=np.int64)
    out[slot_out] = slot_in
    out[slot_in] = slot_out
    return out


def spread_sectors(
    topology: QuadTopology,
    found: Sectors,
    tangents: FloatArray,
    n_sector: FloatArray,
    creased: BoolArray,
    chord: FloatArray,
) -> BoolArray:
    """Check that each creased sector's slots turn counter-clockwise from its start to its end
    about its normal, each by less than :data:`_HALF_TURN` (a Gregory corner split needs a
    slot's neighbours on either side of it); where they do not, put the inner slots at even
    angles in between (length: the chord), in place. Returns the vertices that needed it."""
    ring_vertex = np.repeat(np.arange(topology.n_vertices), topology.face_count)
    positions = np.flatnonzero(creased[ring_vertex])
    if not positions.size:
        return np.zeros(topology.n_vertices, dtype=bool)
    offsets = topology.neighbor_offsets
    vertex = ring_vertex[positions]
    index = positions - topology.ring_offsets[vertex]  # position j in the ring = slot j
    label = found.label[positions]
    start = found.start[label]
    rank = (index - (start - offsets[vertex])) % topology.face_count[
        vertex
    ]  # 0 at the sector's first slot
    order = np.lexsort((rank, label))
    vertex, index, label, start, rank = (
        vertex[order],
        index[order],
        label[order],
        start[order],
        rank[order],
    )
    slots = offsets[vertex] + index
    n = n_sector[label]
    e1 = _unit(tangents[start])
    e2 = cross(n, e1)
    angle = np.mod(np.arctan2(_dot(tangents[slots], e2), _dot(tangents[slots], e1)), 2 * np.pi)
    end_t = tangents[found.end[label]]
    end_angle = np.mod(np.arctan2(_dot(end_t, e2), _dot(end_t, e1)), 2 * np.pi)
    end_angle = np.where(end_angle <= 0, 2 * np.pi, end_angle)
    inner = rank > 0
    previous = np.where(rank > 1, np.concatenate([[0.0], angle[:-1]]), 0.0)
    last = inner & (np.r_[label[1:] != label[:-1], True])
    ordered = ~inner | (
        (angle > previous)
        & (angle < end_angle)
        & (angle - previous < _HALF_TURN)
        & (~last | (end_angle - angle < _HALF_TURN))
    )
    bad_sector = np.zeros(found.vertex.size, dtype=bool)
    bad_sector[label[~ordered]] = True
    fix = inner & bad_sector[label]
    if fix.any():
        n_inner = np.bincount(label, inner, minlength=found.vertex.size)
        phi = end_angle[fix] * rank[fix] / (n_inner[label[fix]] + 1.0)
        direction = np.cos(phi)[:, None] * e1[fix] + np.sin(phi)[:, None] * e2[fix]
        tangents[slots[fix]] = np.linalg.norm(chord[slots[fix]], axis=1)[:, None] * direction
    spread = np.zeros(topology.n_vertices, dtype=bool)
    spread[found.vertex[bad_sector]] = True
    return spread
