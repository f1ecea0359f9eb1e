"""The fan of a vertex's slot tangents: regular stars fitted to it, and the safeguard that keeps it
turning once around the normal.

* :func:`fit_regular_star`: the affine-regular star ``t_j = a cos θ_j + b sin θ_j`` closest to the
  slots (θ_j = 2πj/n inside, πj/k over the k + 1 slots of a boundary vertex), and the previous
  release's star of the projected edges (:func:`tangent_stars`);
* :func:`safeguarded_fans`: in A's tangent plane consecutive slots must turn counter-clockwise by
  more than ``ε = min(2°, ¼ · 360°/n, ½ · ω_A)`` and less than ``180° − ε``, and go once around
  (interior) or less than once (boundary); where they do not, the smallest blend towards the
  fitted star that passes, else evenly spread directions (:func:`spread_fan`). ``ω_A``
  (:func:`mesh_gaps`) is the mesh's own narrowest face corner at A, ``min(θ, 180° − θ)``, in
  space or in A's tangent plane, whichever is narrower: a thin wedge the mesh has (the kites
  round a 360-valent pole turn 0.87° in the plane at their spoke vertices) is no reason to replace
  a fan. The rule is told in full in
  :mod:`g1patch.targets.interpolate`.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ..errors import ConstructionError, check_choice
from ..kernels import jit_kernel, use_kernels
from ..mesh import QuadMesh, QuadTopology
from .local import corner_tangents, cross, dot, slot_vertices
from .value import TANGENTS, TangentRule

__all__ = [
    "fit_regular_star",
    "mesh_gaps",
    "safeguarded_fans",
    "spread_fan",
    "tangent_stars",
]

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

#: the safeguard's largest minimum turn between consecutive slots, and its share of 360°/n: small,
#: because a thin wedge of the mesh is a thin wedge of its fan (the flat 360-valent disk turns 1°
#: per face, the boundary vertices of its zigzag rim 4.5°); only fans the mesh does not have
#: (turned over by the normal, or collapsed) are replaced
_MIN_GAP = np.radians(2.0)
_MIN_GAP_SHARE = 0.25
#: blend weights towards the regular star tried by the safeguard, smallest first
_BLENDS = np.arange(1, 9) / 8.0


def _star_angles(
    topology: QuadTopology, slot_vertex: IntArray
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """θ_j of every slot (2πj/n inside, πj/k at a boundary vertex with k faces) and the
    per-vertex angle step."""
    offsets = topology.neighbor_offsets
    boundary = topology.is_boundary_vertex
    step = np.where(boundary, np.pi / topology.face_count, 2.0 * np.pi / topology.valence)
    theta = (np.arange(len(slot_vertex)) - offsets[slot_vertex]) * step[slot_vertex]
    return np.cos(theta), np.sin(theta), step


def fit_regular_star(
    topology: QuadTopology, normals: FloatArray, s: FloatArray
) -> tuple[FloatArray, FloatArray, NDArray[np.bool_]]:
    """The affine-regular star ``t_j = a cos θ_j + b sin θ_j`` closest to the slot tangents ``s``.

    Least squares ``[a b] = (Σ_j s_j [cos θ_j, sin θ_j]) G⁻¹``; the Gram matrix is diagonal:
    ``diag(n/2, n/2)`` inside, ``diag((k + 2)/2, k/2)`` at a boundary vertex with k ≥ 2 faces. A
    boundary corner (k = 1) keeps ``s``. Returns the star (S, 3), ``c_v`` = cos of the angle step
    (V,), and per vertex whether the star turns counter-clockwise about its normal.
    """
    offsets = topology.neighbor_offsets
    slot_vertex = slot_vertices(topology)
    cos, sin, step = _star_angles(topology, slot_vertex)
    boundary = topology.is_boundary_vertex
    corner = boundary & (topology.face_count == 1)
    moments = np.add.reduceat(
        np.concatenate([cos[:, None] * s, sin[:, None] * s], axis=1), offsets[:-1]
    )
    half = 0.5 * np.where(boundary, topology.face_count, topology.valence)
    a = moments[:, :3] / np.where(boundary, half + 1.0, half)[:, None]
    b = moments[:, 3:] / np.where(corner, 1.0, half)[:, None]
    area = dot(cross(a, b), normals)
    valid = corner | (area > 1e-12 * (dot(a, a) + dot(b, b)))
    star = a[slot_vertex] * cos[:, None] + b[slot_vertex] * sin[:, None]
    free = corner[slot_vertex]
    star[free] = s[free]
    return star, np.cos(step), valid


def tangent_stars(
    mesh: QuadMesh, normals: FloatArray, tangents: TangentRule = "arc"
) -> tuple[FloatArray, FloatArray]:
    """The previous release's star: the regular star fitted to the projected edge tangents
    (:func:`~g1patch.targets.local.corner_tangents`, ``tangents`` lengths), and ``c_v``.

    Raises :class:`ConstructionError` where a fitted star is degenerate or folded, as that release
    did.
    """
    check_choice("tangents", tangents, TANGENTS)
    topology = mesh.topology
    slot_vertex = slot_vertices(topology)
    s = corner_tangents(
        mesh.vertices[slot_vertex],
        mesh.vertices[topology.neighbors],
        normals[slot_vertex],
        tangents,
        np.stack([slot_vertex, topology.neighbors], axis=1),
    )
    star, cosine, valid = fit_regular_star(topology, normals, s)
    if not valid.all():
        v = int(np.flatnonzero(~valid)[0])
        raise ConstructionError(
            f"tangent star: the regular star fitted to the ring of vertex {v} "
            f"({'boundary' if topology.is_boundary_vertex[v] else 'interior'}, valence "
            f"{topology.valence[v]}) "
            "is degenerate or folded; its ring edges do not turn once around the normal"
        )
    return star, cosine


def _fan_gaps(
    topology: QuadTopology, normals: FloatArray, t: FloatArray
) -> tuple[FloatArray, IntArray, IntArray]:
    """Signed turn from every face's first slot to its second about the normal, (G,), with the
    vertex of each gap. Gap j of vertex v runs from slot j to slot j + 1 (cyclically inside);
    a boundary vertex with k faces has k gaps, an interior one n."""
    offsets = topology.neighbor_offsets
    counts = topology.face_count
    gap_vertex = np.repeat(np.arange(topology.n_vertices), counts)
    local = np.arange(len(gap_vertex)) - np.repeat(np.cumsum(counts) - counts, counts)
    first = offsets[gap_vertex] + local
    size = np.diff(offsets)[gap_vertex]
    second = offsets[gap_vertex] + (local + 1) % size
    n = normals[gap_vertex]
    a, b = t[first], t[second]
    gaps = np.arctan2(dot(cross(a, b), n), dot(a, b))
    return gaps, gap_vertex, first


def mesh_gaps(mesh: QuadMesh, normals: FloatArray | None = None) -> FloatArray:
    """Per vertex A the narrowest corner its faces have there, ``ω_A = min_j min(θ_j, π − θ_j)``
    (radians), ``θ_j = atan2(|d_j × d_{j+1}|, d_j · d_{j+1})`` between the chords ``d_j = B_j − A``
    of the face's two edges at A: the wedge the mesh itself allows a fan (:func:`gap_floors`).

    With the vertex ``normals`` (V, 3) the corner is also measured as the fan turns, between the
    chords projected onto A's tangent plane, and the smaller of the two is taken. On a curved
    surface chords of unequal length dip below the plane by unequal angles: next to a 360-valent
    pole of a sphere the kite's corner at a spoke vertex turns 0.87° in the plane (it narrows
    like 360°/n, as the pole's sector does) but its chords are 7.5° apart in space, so the 3D
    corner alone kept ε at 2°, the fan was blended towards a regular star and its edge curves
    left their sectors."""
    topology = mesh.topology
    offsets = topology.neighbor_offsets
    counts = topology.face_count
    gap_vertex = np.repeat(np.arange(topology.n_vertices), counts)
    starts = np.cumsum(counts) - counts
    local = np.arange(len(gap_vertex)) - starts[gap_vertex]
    size = np.diff(offsets)[gap_vertex]
    x = mesh.vertices
    a = x[topology.neighbors[offsets[gap_vertex] + local]] - x[gap_vertex]
    b = x[topology.neighbors[offsets[gap_vertex] + (local + 1) % size]] - x[gap_vertex]
    theta = np.arctan2(np.linalg.norm(cross(a, b), axis=1), dot(a, b))
    gap = np.minimum(theta, np.pi - theta)
    if normals is not None:
        n = normals[gap_vertex]
        a -= dot(a, n)[:, None] * n
        b -= dot(b, n)[:, None] * n
        theta = np.arctan2(np.linalg.norm(cross(a, b), axis=1), dot(a, b))
        gap = np.minimum(gap, np.minimum(theta, np.pi - theta))
    return np.minimum.reduceat(gap, starts)


def gap_floors(topology: QuadTopology, own: FloatArray | None = None) -> FloatArray:
    """Per vertex the safeguard's ε: ``min(2°, ¼ · 360°/n, ½ · ω)`` with ``ω`` the mesh's own
    narrowest corner there (:func:`mesh_gaps`; None: no such bound). A boundary corner with one
    face keeps ``min(2°, ¼ · 360°/n)``: its nearly straight corner is narrowed on purpose
    (:func:`_narrowed_straight_corners`)."""
    eps = np.minimum(_MIN_GAP, _MIN_GAP_SHARE * 2.0 * np.pi / np.maximum(topology.valence, 3))
    if own is None:
        return eps
    corner = topology.is_boundary_vertex & (topology.face_count == 1)
    return np.where(corner, eps, np.minimum(eps, 0.5 * own))


def _valid_fans(
    topology: QuadTopology,
    normals: FloatArray,
    t: FloatArray,
    eps: FloatArray | None = None,
    *,
    compiled: bool = True,
) -> NDArray[np.bool_]:
    """Per vertex: every consecutive turn in (ε, 180° − ε), once around inside, less than once at a
    boundary (``eps`` per vertex, default :func:`gap_floors` without the mesh's own bound;
    ``compiled``: vertex by vertex in :func:`_valid_fans_kernel`)."""
    compiled = use_kernels(compiled)  # NumPy where kernels cannot be cached
    eps = gap_floors(topology) if eps is None else eps
    if compiled:
        valid = np.empty(topology.n_vertices, dtype=bool)
        jit_kernel(_valid_fans_kernel)(
            normals,
            t,
            topology.neighbor_offsets,
            topology.face_count,
            topology.is_boundary_vertex,
            eps,
            _MIN_GAP,
            valid,
        )
        return valid
    gaps, gap_vertex, first = _fan_gaps(topology, normals, t)
    floor = eps[gap_vertex]
    length = np.linalg.norm(t, axis=1)
    ok_gap = (gaps > floor) & (gaps < np.pi - floor) & (length[first] > 0)
    valid = np.bincount(gap_vertex, weights=~ok_gap, minlength=topology.n_vertices) == 0
    total = np.bincount(gap_vertex, weights=gaps, minlength=topology.n_vertices)
    once = np.where(
        topology.is_boundary_vertex,
        total < 2.0 * np.pi - _MIN_GAP,
        np.abs(total - 2.0 * np.pi) < 1e-6,
    )
    last = (
        topology.neighbor_offsets[1:] - 1
    )  # a boundary vertex's last slot ends no gap: check its length too
    return valid & once & (length[last] > 0)


def _valid_fans_kernel(
    normals: FloatArray,
    t: FloatArray,
    offsets: IntArray,
    face_count: IntArray,
    boundary: NDArray[np.bool_],
    floors: FloatArray,
    min_gap: float,
    valid: NDArray[np.bool_],
) -> None:
    """:func:`_valid_fans` vertex by vertex: the turns ``atan2((a × b)·N, a·b)`` of the gaps
    (:func:`_fan_gaps`), each above ``floors[v]`` and below ``π − floors[v]``."""
    for v in range(offsets.size - 1):
        n0, n1, n2 = normals[v, 0], normals[v, 1], normals[v, 2]
        first, size = offsets[v], offsets[v + 1] - offsets[v]
        eps = floors[v]
        ok = True
        total = 0.0
        for j in range(face_count[v]):
            a, b = first + j, first + (j + 1) % size
            a0, a1, a2 = t[a, 0], t[a, 1], t[a, 2]
            b0, b1, b2 = t[b, 0], t[b, 1], t[b, 2]
            gap = np.arctan2(
                (a1 * b2 - a2 * b1) * n0 + (a2 * b0 - a0 * b2) * n1 + (a0 * b1 - a1 * b0) * n2,
                a0 * b0 + a1 * b1 + a2 * b2,
            )
            ok &= gap > eps and gap < np.pi - eps and np.sqrt(a0 * a0 + a1 * a1 + a2 * a2) > 0
            total += gap
        last = first + size - 1
        once = total < 2.0 * np.pi - min_gap if boundary[v] else abs(total - 2.0 * np.pi) < 1e-6
        valid[v] = ok and once and np.sqrt(t[last, 0] ** 2 + t[last, 1] ** 2 + t[last, 2] ** 2) > 0


def spread_fan(
    topology: QuadTopology,
    normals: FloatArray,
    t: FloatArray,
    chord: FloatArray,
    vertices: IntArray,
) -> FloatArray:
    """Evenly spread slot directions at ``vertices`` (2π/n apart inside, π/max(k, 2) at a
    boundary), starting from the first slot's direction, with the slots' own lengths (their
    chords where a slot has none)."""
    offsets = topology.neighbor_offsets
    counts = np.diff(offsets)[vertices]
    slots = np.repeat(offsets[vertices] - np.cumsum(counts) + counts, counts) + np.arange(
        counts.sum()
    )
    owner = np.repeat(vertices, counts)
    local = slots - offsets[owner]
    n = normals[owner]
    first = t[offsets[owner]]
    first = first - dot(first, n)[:, None] * n
    reference = np.where(
        np.linalg.norm(first, axis=1, keepdims=True) > 0, first, _any_perpendicular(n)
    )
    e1 = reference / np.linalg.norm(reference, axis=1, keepdims=True)
    e2 = np.cross(n, e1)
    boundary = topology.is_boundary_vertex[owner]
    step = np.where(
        boundary,
        np.pi / np.maximum(topology.face_count[owner], 2),
        2.0 * np.pi / topology.valence[owner],
    )
    angle = local * step
    length = np.linalg.norm(t[slots], axis=1)
    length = np.where(length > 0, length, chord[slots])
    out = t.copy()
    out[slots] = (np.cos(angle)[:, None] * e1 + np.sin(angle)[:, None] * e2) * length[:, None]
    return out


def _any_perpendicular(n: FloatArray) -> FloatArray:
    """A vector ⊥ each unit ``n``: n × (the coordinate axis least aligned with n)."""
    axis = np.eye(3)[np.argmin(np.abs(n), axis=1)]
    return np.cross(n, axis)


def _narrowed_straight_corners(
    topology: QuadTopology, normals: FloatArray, t: FloatArray, corners: IntArray
) -> FloatArray:
    """At one-face ``corners`` whose two tangents turn by ``θ ≥ 180° − ε`` about the normal, both
    rotated in the tangent plane by ``δ = (θ − 180° + 3ε/2)/2`` towards each other (the first slot
    counter-clockwise, the second clockwise); the other corners unchanged."""
    out = t.copy()
    if not corners.size:
        return out
    first = topology.neighbor_offsets[corners]
    a, b, n = t[first], t[first + 1], normals[corners]
    a_plane = a - dot(a, n)[:, None] * n
    b_plane = b - dot(b, n)[:, None] * n
    turn = np.arctan2(dot(cross(a_plane, b_plane), n), dot(a_plane, b_plane))
    eps = np.minimum(
        _MIN_GAP, _MIN_GAP_SHARE * 2.0 * np.pi / np.maximum(topology.valence[corners], 3)
    )
    delta = np.where(turn >= np.pi - eps, 0.5 * (turn - np.pi + 1.5 * eps), 0.0)[:, None]
    out[first] = a - a_plane + np.cos(delta) * a_plane + np.sin(delta) * cross(n, a_plane)
    out[first + 1] = b - b_plane + np.cos(delta) * b_plane - np.sin(delta) * cross(n, b_plane)
    return out


def safeguarded_fans(
    topology: QuadTopology,
    normals: FloatArray,
    raw: FloatArray,
    chord: FloatArray,
    own: FloatArray | None = None,
) -> tuple[FloatArray, NDArray[np.bool_]]:
    """The raw slot tangents where their fan is valid, else the smallest blend towards the
    regular star that is, else evenly spread directions (:mod:`g1patch.targets.interpolate`).
    ``own``: the mesh's narrowest corner per vertex (:func:`mesh_gaps`), which lowers the minimum
    turn ε to half of it (:func:`gap_floors`). Returns the tangents and the vertices that needed
    the safeguard."""
    eps = gap_floors(topology, own)
    valid = _valid_fans(topology, normals, raw, eps)
    needs = ~valid
    if not needs.any():
        return raw, needs
    t = _narrowed_straight_corners(
        topology, normals, raw, np.flatnonzero(needs & (topology.face_count == 1))
    )
    pending = needs & ~_valid_fans(topology, normals, t, eps)
    if not pending.any():
        return t, needs
    raw = t
    star, _, _ = fit_regular_star(topology, normals, raw)
    slot_vertex = slot_vertices(topology)
    t = raw.copy()
    for mu in _BLENDS:
        rows = pending[slot_vertex]
        trial = t.copy()
        trial[rows] = (1.0 - mu) * raw[rows] + mu * star[rows]
        passed = pending & _valid_fans(topology, normals, trial, eps)
        accept = passed[slot_vertex]
        t[accept] = trial[accept]
        pending &= ~passed
        if not pending.any():
            break
    if pending.any():
        t = spread_fan(topology, normals, t, chord, np.flatnonzero(pending))
    return t, needs
