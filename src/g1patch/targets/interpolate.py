"""Interpolating targets: a surface through the mesh vertices, shaped by local rules.

Two rules, both returning :class:`~g1patch.targets.Targets` on the mesh's own positions:

``interpolate`` (the default; shape-quality.md §3.1–3.3)
    * normal: :func:`~g1patch.targets.frames.vertex_frames` where its local fit is trusted, the
      area-weighted fan normal elsewhere;
    * tangents: every mesh edge projected onto the tangent plane, ``s = P_A (B − A)``, with the
      circle-aware length ``L = |B − A| / cos²(θ/4)``, ``sin(θ/2) = |N·(B − A)|/|B − A|``: the
      Hermite tangent that reproduces the circular arc through B tangent to the plane at A
      (``= 2|d|²/(|d| + |s|)``, :func:`~g1patch.targets.local.corner_tangents`). A flexible fan:
      no regular-star fit, so a short edge opposite a long one keeps its own length. Where a mesh
      line runs on smoothly through an interior vertex of valence 4 (B' → A → B, opposite
      neighbours, turning at A in its tangent plane as it does at B and B'), both slots turn along
      the tangent at A of the circle through B', A, B, ``|a|² b − |b|² a`` (a = B' − A, b = B − A):
      the projected chords of a curved line make a V (147° on the coarse torus cage), the line's
      own tangent is straight through, the fan a parallelogram where lengths agree, as the C1
      B-spline's and split4's stars (split4 moved the V by 28 %, its CAD surface lay 1.3e-2 of the
      diagonal off). Where the line kinks at A (a projected cube's or icosahedron's edges) the
      chords stay: they keep the sphere's edge curves on great circles. At a boundary
      vertex with two or more faces the two rim slots point along ±the rim's central difference,
      so the boundary curve does not kink there (a corner with one face keeps its edges);
    * fan safeguard: in A's tangent plane consecutive slots must turn counter-clockwise by more
      than ``ε = min(2°, ¼ · 360°/n)`` and less than ``180° − ε``, and go once around (interior)
      or less than once (boundary). Where they do not, ``t = (1 − μ) t_raw + μ t_star`` with the
      smallest ``μ ∈ {1/8, …, 1}`` that passes, t_star the regular star fitted to the raw fan; if
      even the star fails, evenly spread directions with the raw lengths. A corner with one face
      turning by ``180° − ε`` or more (nearly straight: every corner of a split polygon of 180 or
      more sides) is its own regular star, so no blend helps: its two tangents turn towards each
      other, about the normal, until they are ``180° − 3ε/2`` apart, instead of being spread to
      90°, which folded the polygon's thin faces. Such vertices are counted in ``Targets.fallback``;
    * interior points: at corner A of face (A, B, C, D) with B next and D previous,
      ``Ft = A + (t_AB + t_AD)/3 + [P_A w + II_A(t_AB, t_AD) N_A]/9``, ``w = A − B + C − D``: the
      bilinear twist with its normal part replaced by the estimated second fundamental form,
      ``N·p_uv = II(p_u, p_v)`` for any parameterisation.

``legacy`` (the release before this one, kept as the benchmarks' baseline)
    fan normal, the affine-regular star ``t_j = a cos θ_j + b sin θ_j`` fitted to the projected
    edges (θ_j = 2πj/n inside, πj/k over the k + 1 edges of a boundary vertex), bilinear twist.
"""

from __future__ import annotations

from typing import Literal

import numpy as np
from numpy.typing import NDArray

from ..errors import ConstructionError, check_choice
from ..kernels import in_chunks, jit_kernel
from ..mesh import QuadMesh, QuadTopology
from . import Targets
from .creases import INTERPOLATE_SHARPNESS, crease_tangents, seam_edges, sharp_vertices
from .local import (
    TANGENTS,
    TangentRule,
    corner_tangents,
    cross,
    fan_normals,
    in_vertex_planes,
    slot_tables,
)

__all__ = [
    "SHAPES",
    "ShapeRule",
    "fit_regular_star",
    "interpolate_targets",
    "legacy_targets",
    "safeguarded_fans",
    "shape_targets",
    "retreat",
    "slot_vertices",
    "spread_fan",
    "tangent_stars",
]

ShapeRule = Literal["interpolate", "limit", "limit-interpolate", "legacy"]
SHAPES: tuple[ShapeRule, ...] = ("interpolate", "limit", "limit-interpolate", "legacy")

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

_NEXT = np.array([1, 2, 3, 0])
_PREV = np.array([3, 0, 1, 2])
#: the safeguard's largest minimum turn between consecutive slots, and its share of 360°/n: small,
#: because a thin wedge of the mesh is a thin wedge of its fan (the flat 360-valent disk turns 1°
#: per face, the boundary vertices of its zigzag rim 4.5°); only fans the mesh does not have
#: (turned over by the normal, or collapsed) are replaced
_MIN_GAP = np.radians(2.0)
_MIN_GAP_SHARE = 0.25
#: blend weights towards the regular star tried by the safeguard, smallest first
_BLENDS = np.arange(1, 9) / 8.0
#: a boundary vertex's rim turn up to which its rim is made smooth, and from which it is a corner
_RIM_SMOOTH = np.radians(45.0)
_RIM_CORNER = np.radians(90.0)
#: a mesh line B' → A → B through a regular vertex runs on smoothly (its slots at A turn along it)
# : when its turn at A is within this share of the mean of its turns at B and B', plus the slack
# (rad)
_LINE_SHARE = 0.25
_LINE_SLACK = np.radians(0.1)
#: an edge whose projection onto the tangent plane is shorter than this share of its length is
#: treated as parallel to the normal: its direction is undefined and the safeguard replaces it
_PARALLEL = 1e-6


def slot_vertices(topology: QuadTopology) -> IntArray:
    """The vertex of every ring slot, (S,)."""
    return np.repeat(np.arange(topology.n_vertices), np.diff(topology.neighbor_offsets))


def _dot(a: FloatArray, b: FloatArray) -> FloatArray:
    return np.einsum("...d,...d->...", a, b)


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
    area = _dot(cross(a, b), normals)
    valid = corner | (area > 1e-12 * (_dot(a, a) + _dot(b, b)))
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


def legacy_targets(mesh: QuadMesh, tangents: TangentRule = "arc") -> Targets:
    """The previous release's rule: fan normal, fitted regular star, bilinear twist (module
    docstring)."""
    topology = mesh.topology
    normals = fan_normals(mesh)
    star, _ = tangent_stars(mesh, normals, tangents)
    interior = _interior_targets(topology, mesh.vertices, star, normals, None)
    return Targets(
        topology,
        mesh.vertices,
        normals,
        star,
        np.stack([interior, interior], axis=2),
        rule="legacy",
    )


def _projected_tangents(
    mesh: QuadMesh, normals: FloatArray, *, compiled: bool = True
) -> tuple[FloatArray, FloatArray, NDArray[np.bool_]]:
    """Circle-aware projected edge tangents per slot, the chord lengths, and per vertex whether a
    slot is (near) parallel to the normal (its tangent is set to 0). ``compiled``: slot by slot in
    :func:`_projected_kernel`, else NumPy."""
    topology = mesh.topology
    x = mesh.vertices
    if compiled:
        out, chord = np.empty((len(topology.neighbors), 3)), np.empty(len(topology.neighbors))
        parallel = np.empty(topology.n_vertices, dtype=bool)
        jit_kernel(_projected_kernel)(
            x,
            normals,
            topology.neighbor_offsets,
            topology.neighbors,
            _PARALLEL,
            out,
            chord,
            parallel,
        )
        return out, chord, parallel
    slot_vertex = slot_vertices(topology)
    d = x[topology.neighbors] - x[slot_vertex]
    n = normals[slot_vertex]
    s = d - _dot(d, n)[:, None] * n
    in_plane = np.linalg.norm(s, axis=1)
    chord = np.linalg.norm(d, axis=1)
    parallel = ~(in_plane > _PARALLEL * chord)
    length = 2.0 * chord**2 / (chord + in_plane)
    scale = np.where(parallel, 0.0, length / np.where(parallel, 1.0, in_plane))
    return (
        s * scale[:, None],
        chord,
        np.bincount(slot_vertex, parallel, minlength=topology.n_vertices) > 0,
    )


def _projected_kernel(
    x: FloatArray,
    normals: FloatArray,
    offsets: IntArray,
    neighbors: IntArray,
    parallel_share: float,
    out: FloatArray,
    chord: FloatArray,
    parallel: NDArray[np.bool_],
) -> None:
    """:func:`_projected_tangents` vertex by vertex: ``s = d − (N·d) N``, ``s · 2|d|²/(|d| +
    |s|)/|s|``."""
    for v in range(offsets.size - 1):
        n0, n1, n2 = normals[v, 0], normals[v, 1], normals[v, 2]
        parallel[v] = False
        for slot in range(offsets[v], offsets[v + 1]):
            b = neighbors[slot]
            d0, d1, d2 = x[b, 0] - x[v, 0], x[b, 1] - x[v, 1], x[b, 2] - x[v, 2]
            height = d0 * n0 + d1 * n1 + d2 * n2
            s0, s1, s2 = d0 - height * n0, d1 - height * n1, d2 - height * n2
            in_plane = np.sqrt(s0 * s0 + s1 * s1 + s2 * s2)
            length = np.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
            chord[slot] = length
            if in_plane > parallel_share * length:
                scale = 2.0 * (length * length) / (length + in_plane) / in_plane
            else:
                scale = 0.0
                parallel[v] = True
            out[slot, 0], out[slot, 1], out[slot, 2] = s0 * scale, s1 * scale, s2 * scale


def _turn(p: FloatArray, a: FloatArray, q: FloatArray, n: FloatArray) -> FloatArray:
    """Signed turn of the polyline p → a → q at a, in a's tangent plane about ``n``:
    ``atan2(n·(u × w), u·w)``, u = P(a − p), w = P(q − a) (P removes the component along n)."""
    u, w = a - p, q - a
    u = u - _dot(u, n)[:, None] * n
    w = w - _dot(w, n)[:, None] * n
    return np.arctan2(_dot(cross(u, w), n), _dot(u, w))


def _along_smooth_lines(
    mesh: QuadMesh,
    normals: FloatArray,
    raw: FloatArray,
    *,
    compiled: bool = True,
    out: FloatArray | None = None,
) -> FloatArray:
    """``raw`` with the slots of mesh lines that run on smoothly through a regular vertex turned
    along the line (module docstring): at an interior vertex A of valence 4, the line B' → A → B of
    opposite neighbours is *smooth* when its signed turn at A (:func:`_turn`) is within
    :data:`_LINE_SHARE` of the larger magnitude, plus :data:`_LINE_SLACK`, of the mean of its turns
    at B and B' (continued through each that is regular too; at least one is). Both slots then
    point along the tangent at A of the circle through B', A, B, ``|a|² b − |b|² a`` with
    ``a = B' − A``, ``b = B − A``, in A's plane, with their own lengths. ``compiled``: vertex by
    vertex in :func:`_lines_kernel` (ranges side by side), else NumPy; into ``out`` (``raw``
    itself may be given: a slot is read only before it is written), by default a copy of ``raw``."""
    topology = mesh.topology
    out = raw.copy() if out is None else out
    if compiled:
        kernel = jit_kernel(_lines_kernel)
        in_chunks(
            lambda lo, hi: kernel(
                mesh.vertices,
                normals,
                topology.neighbor_offsets,
                topology.neighbors,
                topology.face_count,
                topology.is_boundary_vertex,
                _LINE_SHARE,
                _LINE_SLACK,
                raw,
                out,
                lo,
                hi,
            ),
            topology.n_vertices,
        )
        return out
    x, offsets, neighbors = mesh.vertices, topology.neighbor_offsets, topology.neighbors
    regular = ~topology.is_boundary_vertex & (topology.face_count == 4)
    vertices = np.flatnonzero(regular)
    lengths = np.linalg.norm(raw, axis=1)

    def beyond(b: IntArray, a: IntArray) -> IntArray:
        """The neighbour of regular b opposite a."""
        ring = neighbors[offsets[b][:, None] + np.arange(4)]
        at = np.argmax(ring == a[:, None], axis=1)
        return ring[np.arange(len(b)), (at + 2) % 4]

    for line in range(2):
        s_fore, s_back = offsets[vertices] + line, offsets[vertices] + line + 2
        a, fore, back = vertices, neighbors[s_fore], neighbors[s_back]
        total, count = np.zeros(len(a)), np.zeros(len(a))
        for ok, turn in (
            (
                regular[fore],
                lambda i: _turn(x[a[i]], x[fore[i]], x[beyond(fore[i], a[i])], normals[fore[i]]),
            ),
            (
                regular[back],
                lambda i: _turn(x[beyond(back[i], a[i])], x[back[i]], x[a[i]], normals[back[i]]),
            ),
        ):
            total[ok] += turn(np.flatnonzero(ok))
            count += ok
        at_a = _turn(x[back], x[a], x[fore], normals[a])
        mean = total / np.maximum(count, 1)
        d_back, d_fore = x[back] - x[a], x[fore] - x[a]
        along = _dot(d_back, d_back)[:, None] * d_fore - _dot(d_fore, d_fore)[:, None] * d_back
        along -= _dot(along, normals[a])[:, None] * normals[a]
        size = np.linalg.norm(along, axis=1)
        smooth = (count > 0) & (
            np.abs(at_a - mean)
            <= _LINE_SHARE * np.maximum(np.abs(at_a), np.abs(mean)) + _LINE_SLACK
        )
        smooth &= (size > 0) & (lengths[s_fore] > 0) & (lengths[s_back] > 0)
        direction = along[smooth] / size[smooth, None]
        out[s_fore[smooth]] = direction * lengths[s_fore[smooth], None]
        out[s_back[smooth]] = -direction * lengths[s_back[smooth], None]
    return out


def _lines_kernel(
    x: FloatArray,
    normals: FloatArray,
    offsets: IntArray,
    neighbors: IntArray,
    face_count: IntArray,
    boundary: NDArray[np.bool_],
    share: float,
    slack: float,
    raw: FloatArray,
    out: FloatArray,
    lo: int,
    hi: int,
) -> None:
    """:func:`_along_smooth_lines` for vertices ``lo`` to ``hi``: the same formulas, in the same
    order."""
    turn = np.empty(3)
    for v in range(lo, hi):
        if boundary[v] or face_count[v] != 4:
            continue
        for line in range(2):
            ends = (
                neighbors[offsets[v] + line + 2],
                neighbors[offsets[v] + line],
            )  # back B', fore B
            total, count = 0.0, 0
            for side in range(
                3
            ):  # 0: at B (A → B → beyond), 1: at B' (beyond → B' → A), 2: at A (B' → A → B)
                if side < 2:
                    b = ends[1 - side]
                    if boundary[b] or face_count[b] != 4:
                        continue
                    at = 0
                    for k in range(4):
                        if neighbors[offsets[b] + k] == v:
                            at = k
                    far = neighbors[offsets[b] + (at + 2) % 4]
                    p, a, q = (v, b, far) if side == 0 else (far, b, v)
                else:
                    p, a, q = ends[0], v, ends[1]
                n0, n1, n2 = normals[a, 0], normals[a, 1], normals[a, 2]
                u0, u1, u2 = x[a, 0] - x[p, 0], x[a, 1] - x[p, 1], x[a, 2] - x[p, 2]
                w0, w1, w2 = x[q, 0] - x[a, 0], x[q, 1] - x[a, 1], x[q, 2] - x[a, 2]
                h = (u0 * n0 + u1 * n1) + u2 * n2
                u0, u1, u2 = u0 - h * n0, u1 - h * n1, u2 - h * n2
                h = (w0 * n0 + w1 * n1) + w2 * n2
                w0, w1, w2 = w0 - h * n0, w1 - h * n1, w2 - h * n2
                c0, c1, c2 = u1 * w2 - u2 * w1, u2 * w0 - u0 * w2, u0 * w1 - u1 * w0
                turn[side] = np.arctan2(
                    (c0 * n0 + c1 * n1) + c2 * n2, (u0 * w0 + u1 * w1) + u2 * w2
                )
                if side < 2:
                    total += turn[side]
                    count += 1
            if count == 0:
                continue
            mean = total / count
            if not abs(turn[2] - mean) <= share * max(abs(turn[2]), abs(mean)) + slack:
                continue
            s_back, s_fore = offsets[v] + line + 2, offsets[v] + line
            back, fore = ends
            b0, b1, b2 = x[back, 0] - x[v, 0], x[back, 1] - x[v, 1], x[back, 2] - x[v, 2]
            f0, f1, f2 = x[fore, 0] - x[v, 0], x[fore, 1] - x[v, 1], x[fore, 2] - x[v, 2]
            bb, ff = (b0 * b0 + b1 * b1) + b2 * b2, (f0 * f0 + f1 * f1) + f2 * f2
            a0, a1, a2 = bb * f0 - ff * b0, bb * f1 - ff * b1, bb * f2 - ff * b2
            n0, n1, n2 = normals[v, 0], normals[v, 1], normals[v, 2]
            h = (a0 * n0 + a1 * n1) + a2 * n2
            a0, a1, a2 = a0 - h * n0, a1 - h * n1, a2 - h * n2
            size = np.sqrt((a0 * a0 + a1 * a1) + a2 * a2)
            fore_length = np.sqrt(
                (raw[s_fore, 0] * raw[s_fore, 0] + raw[s_fore, 1] * raw[s_fore, 1])
                + raw[s_fore, 2] * raw[s_fore, 2]
            )
            back_length = np.sqrt(
                (raw[s_back, 0] * raw[s_back, 0] + raw[s_back, 1] * raw[s_back, 1])
                + raw[s_back, 2] * raw[s_back, 2]
            )
            if not (size > 0.0 and fore_length > 0.0 and back_length > 0.0):
                continue
            out[s_fore, 0], out[s_fore, 1], out[s_fore, 2] = (
                a0 / size * fore_length,
                a1 / size * fore_length,
                a2 / size * fore_length,
            )
            out[s_back, 0], out[s_back, 1], out[s_back, 2] = (
                -(a0 / size) * back_length,
                -(a1 / size) * back_length,
                -(a2 / size) * back_length,
            )


def _smooth_boundary_tangents(mesh: QuadMesh, normals: FloatArray, raw: FloatArray) -> FloatArray:
    """At a boundary vertex with k ≥ 2 faces the two rim slots turn towards opposite directions,
    so the boundary curve does not kink there: ``T = P_A(x_next − x_prev)/|…|`` (the central
    difference along the rim, in the tangent plane), lengths the circle-aware
    ``2|d|²/(|d| + |d·T|)`` of each rim edge (the circular arc through its far end tangent to T).
    Where the rim itself turns sharply it is a corner of the boundary, not a sampled smooth curve:
    the directions blend from ``±T`` (rim turn ≤ 45°) to the edges' own (≥ 90°). A corner with
    one face keeps its edges."""
    topology = mesh.topology
    smooth = np.flatnonzero(topology.is_boundary_vertex & (topology.face_count >= 2))
    if not smooth.size:
        return raw
    offsets = topology.neighbor_offsets
    first, last = offsets[smooth], offsets[smooth + 1] - 1
    x = mesh.vertices
    d_next = x[topology.neighbors[first]] - x[smooth]
    d_prev = x[topology.neighbors[last]] - x[smooth]
    n = normals[smooth]
    along = d_next - d_prev
    along -= _dot(along, n)[:, None] * n
    length = np.linalg.norm(along, axis=1)
    usable = length > _PARALLEL * (np.linalg.norm(d_next, axis=1) + np.linalg.norm(d_prev, axis=1))
    direction = along / np.where(usable, length, 1.0)[:, None]
    unit_next, unit_prev = _unit_rows(d_next), _unit_rows(d_prev)
    rim_turn = np.arccos(np.clip(-_dot(unit_next, unit_prev), -1.0, 1.0))
    weight = np.clip((_RIM_CORNER - rim_turn) / (_RIM_CORNER - _RIM_SMOOTH), 0.0, 1.0)[:, None]
    out = raw.copy()
    for slot, d, sign in ((first, d_next, 1.0), (last, d_prev, -1.0)):
        own = _unit_rows(raw[slot])
        blended = _unit_rows((1.0 - weight) * own + weight * sign * direction)
        chord = np.linalg.norm(d, axis=1)
        arc = 2.0 * chord**2 / (chord + np.abs(_dot(d, blended)))
        keep = usable & (np.linalg.norm(raw[slot], axis=1) > 0)
        out[slot[keep]] = (arc[:, None] * blended)[keep]
    return out


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
    gaps = np.arctan2(_dot(cross(a, b), n), _dot(a, b))
    return gaps, gap_vertex, first


def _valid_fans(
    topology: QuadTopology, normals: FloatArray, t: FloatArray, *, compiled: bool = True
) -> NDArray[np.bool_]:
    """Per vertex: every consecutive turn in (ε, 180° − ε), once around inside, less than once at a
    boundary (``compiled``: vertex by vertex in :func:`_valid_fans_kernel`)."""
    if compiled:
        valid = np.empty(topology.n_vertices, dtype=bool)
        jit_kernel(_valid_fans_kernel)(
            normals,
            t,
            topology.neighbor_offsets,
            topology.face_count,
            topology.valence,
            topology.is_boundary_vertex,
            _MIN_GAP,
            _MIN_GAP_SHARE,
            valid,
        )
        return valid
    gaps, gap_vertex, first = _fan_gaps(topology, normals, t)
    n = np.maximum(topology.valence, 3)
    eps = np.minimum(_MIN_GAP, _MIN_GAP_SHARE * 2.0 * np.pi / n)[gap_vertex]
    length = np.linalg.norm(t, axis=1)
    ok_gap = (gaps > eps) & (gaps < np.pi - eps) & (length[first] > 0)
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
    valence: IntArray,
    boundary: NDArray[np.bool_],
    min_gap: float,
    min_gap_share: float,
    valid: NDArray[np.bool_],
) -> None:
    """:func:`_valid_fans` vertex by vertex: the turns ``atan2((a × b)·N, a·b)`` of the gaps
    (:func:`_fan_gaps`)."""
    for v in range(offsets.size - 1):
        n0, n1, n2 = normals[v, 0], normals[v, 1], normals[v, 2]
        first, size = offsets[v], offsets[v + 1] - offsets[v]
        eps = min(min_gap, min_gap_share * 2.0 * np.pi / max(valence[v], 3))
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
    first = first - _dot(first, n)[:, None] * n
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
    a_plane = a - _dot(a, n)[:, None] * n
    b_plane = b - _dot(b, n)[:, None] * n
    turn = np.arctan2(_dot(cross(a_plane, b_plane), n), _dot(a_plane, b_plane))
    eps = np.minimum(
        _MIN_GAP, _MIN_GAP_SHARE * 2.0 * np.pi / np.maximum(topology.valence[corners], 3)
    )
    delta = np.where(turn >= np.pi - eps, 0.5 * (turn - np.pi + 1.5 * eps), 0.0)[:, None]
    out[first] = a - a_plane + np.cos(delta) * a_plane + np.sin(delta) * cross(n, a_plane)
    out[first + 1] = b - b_plane + np.cos(delta) * b_plane - np.sin(delta) * cross(n, b_plane)
    return out


def safeguarded_fans(
    topology: QuadTopology, normals: FloatArray, raw: FloatArray, chord: FloatArray
) -> tuple[FloatArray, NDArray[np.bool_]]:
    """The raw slot tangents where their fan is valid, else the smallest blend towards the
    regular star that is, else evenly spread directions (module docstring). Returns the tangents
    and the vertices that needed the safeguard."""
    valid = _valid_fans(topology, normals, raw)
    needs = ~valid
    if not needs.any():
        return raw, needs
    t = _narrowed_straight_corners(
        topology, normals, raw, np.flatnonzero(needs & (topology.face_count == 1))
    )
    pending = needs & ~_valid_fans(topology, normals, t)
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
        passed = pending & _valid_fans(topology, normals, trial)
        accept = passed[slot_vertex]
        t[accept] = trial[accept]
        pending &= ~passed
        if not pending.any():
            break
    if pending.any():
        t = spread_fan(topology, normals, t, chord, np.flatnonzero(pending))
    return t, needs


#: a corner's twist ``w`` may reach this many times its edge tangents, ``|P_A w| ≤ k (|t_AB| +
#: |t_AD|)``, and keep the second fundamental form in full; from here to ``_TWIST_BILINEAR`` the
#: replacement fades out (smoothstep). Past it the face is not a patch about its corner A but
#: a sliver reaching far beyond A's edges (the outer corner of a large polygon's split, 180° −
#: 360°/n), where the height a tangent-plane estimate gives to a point that far off the edges
#: folded the face
_TWIST_LOCAL = 1.0
_TWIST_BILINEAR = 2.0


def _local_twist_weights(planar: FloatArray, reach: FloatArray) -> FloatArray:
    """The share of the second fundamental form in each corner's twist: 1 where ``planar ≤
    _TWIST_LOCAL · reach``, 0 from ``_TWIST_BILINEAR · reach`` on, smoothstep between (the
    kernel inlines the same formula)."""
    u = np.clip(
        (_TWIST_BILINEAR * reach - planar)
        / np.where(reach > 0, (_TWIST_BILINEAR - _TWIST_LOCAL) * reach, 1.0),
        0.0,
        1.0,
    )
    return np.where(reach > 0, u * u * (3.0 - 2.0 * u), planar == 0)


def _interior_targets(
    topology: QuadTopology,
    positions: FloatArray,
    tangents: FloatArray,
    normals: FloatArray,
    shape_operator: FloatArray | None,
    *,
    compiled: bool = True,
    out: FloatArray | None = None,
) -> FloatArray:
    """``Ft = A + (t_AB + t_AD)/3 + w/9`` per face corner, ``w = A − B + C − D``; with a shape
    operator S = dN (:class:`~g1patch.targets.frames.VertexFrames`) the normal part of w is replaced
    by the second fundamental form, ``N·p_uv = −t_ABᵀ S t_AD``: ``w ← P_A w − (t_ABᵀ S t_AD) N_A``,
    by the weight :func:`_local_twist_weights` of ``|P_A w| / (|t_AB| + |t_AD|)``. ``compiled``:
    corner by corner in :func:`_interior_kernel` (ranges of vertices side by side,
    :func:`~g1patch.kernels.in_chunks`), into ``out`` (F, 4, 3) if given; else NumPy."""
    from . import halfedge_slots

    faces = topology.faces
    count = topology.n_faces
    if compiled:
        out = np.empty((count, 4, 3)) if out is None else out
        curved = shape_operator is not None
        kernel = jit_kernel(_interior_kernel)
        operator = shape_operator if curved else np.zeros((1, 3, 3))
        in_chunks(
            lambda lo, hi: kernel(
                positions,
                faces,
                topology.ring_offsets,
                topology.ring_halfedges,
                topology.neighbor_offsets,
                tangents,
                normals,
                operator,
                curved,
                out,
                lo,
                hi,
            ),
            topology.n_vertices,
        )
        return out
    slot_out, slot_in = halfedge_slots(topology)
    x = positions[faces]  # (F, 4, 3): A at corner k
    t_next = tangents[slot_out].reshape(count, 4, 3)  # A → B
    prev = QuadTopology.prev(np.arange(4 * count))
    t_prev = tangents[slot_in[prev]].reshape(count, 4, 3)  # A → D (the reverse of D → A)
    w = x - x[:, _NEXT] + x[:, [2, 3, 0, 1]] - x[:, _PREV]
    if shape_operator is not None:
        n = normals[faces]
        s = shape_operator[faces]
        normal = _dot(w, n)
        planar = np.sqrt(np.maximum(_dot(w, w) - normal**2, 0.0))
        reach = np.linalg.norm(t_next, axis=-1) + np.linalg.norm(t_prev, axis=-1)
        weight = _local_twist_weights(planar, reach)
        w = (
            w
            - ((normal + np.einsum("fki,fkij,fkj->fk", t_next, s, t_prev)) * weight)[..., None] * n
        )
    return x + (t_next + t_prev) / 3.0 + w / 9.0


def _interior_kernel(
    x: FloatArray,
    faces: IntArray,
    ring_offsets: IntArray,
    ring_halfedges: IntArray,
    slot_offsets: IntArray,
    tangents: FloatArray,
    normals: FloatArray,
    shape_operator: FloatArray,
    curved: bool,
    out: FloatArray,
    first: int,
    stop: int,
) -> None:
    """:func:`_interior_targets` of the vertices ``first ≤ a < stop``, vertex by vertex, over its
    ring: the corner of ring face i is between slots i (A → B) and i + 1 (A → D, cyclic inside), so
    no slot table is needed."""
    w = np.empty(3)
    for a in range(first, stop):
        slots = slot_offsets[a + 1] - slot_offsets[a]
        for i in range(ring_offsets[a + 1] - ring_offsets[a]):
            h = ring_halfedges[ring_offsets[a] + i]
            f, k = h >> 2, h & 3
            b, c, d = faces[f, (k + 1) & 3], faces[f, (k + 2) & 3], faces[f, (k + 3) & 3]
            s_next, s_prev = slot_offsets[a] + i, slot_offsets[a] + (i + 1) % slots
            for j in range(3):
                w[j] = x[a, j] - x[b, j] + x[c, j] - x[d, j]
            if curved:
                n0, n1, n2 = normals[a, 0], normals[a, 1], normals[a, 2]
                bend = 0.0
                for r in range(3):
                    for j in range(3):
                        bend += tangents[s_next, r] * shape_operator[a, r, j] * tangents[s_prev, j]
                normal = w[0] * n0 + w[1] * n1 + w[2] * n2
                planar = np.sqrt(
                    max(w[0] * w[0] + w[1] * w[1] + w[2] * w[2] - normal * normal, 0.0)
                )
                reach = np.sqrt(
                    tangents[s_next, 0] ** 2 + tangents[s_next, 1] ** 2 + tangents[s_next, 2] ** 2
                )
                reach += np.sqrt(
                    tangents[s_prev, 0] ** 2 + tangents[s_prev, 1] ** 2 + tangents[s_prev, 2] ** 2
                )
                u = 1.0 if planar == 0 else 0.0
                if reach > 0:
                    u = min(
                        max(
                            (_TWIST_BILINEAR * reach - planar)
                            / ((_TWIST_BILINEAR - _TWIST_LOCAL) * reach),
                            0.0,
                        ),
                        1.0,
                    )
                along = (normal + bend) * u * u * (3.0 - 2.0 * u)
                w[0], w[1], w[2] = w[0] - along * n0, w[1] - along * n1, w[2] - along * n2
            for j in range(3):
                out[f, k, j] = (
                    x[a, j] + (tangents[s_next, j] + tangents[s_prev, j]) / 3.0 + w[j] / 9.0
                )


#: faces whose corner normals turn by less than this keep the local twist targets; from here to
#: ``_ROUND_FULL`` the cross-section fit is blended in (smoothstep), beyond it used alone
_ROUND_START = np.radians(10.0)
_ROUND_FULL = np.radians(40.0)
#: interior samples per direction of the cross-section fit, and its pull towards the twist targets
#: (relative to the mean diagonal of its normal equations: fixes the tangential freedom that
#: point-to-plane distances leave, small enough not to bias the normal direction)
_ROUND_SAMPLES = 5
_ROUND_PULL = 1e-3
#: sphere misfit (:func:`_sphere_misfit`) at which the circle-section fit is off
_ROUND_MISFIT = 0.15
_ROUND_BLOCK = 4096
#: Bézier indices of the interior points at corners 0..3
_INNER = np.array([[1, 1], [2, 1], [2, 2], [1, 2]])
#: the largest turn of a blended patch's normal away from its corners' that the fit may cause
_ROUND_MAX_TURN = np.radians(60.0)


def _bernstein(t: FloatArray, derivative: bool = False) -> FloatArray:
    """Cubic Bernstein values (or derivatives) at ``t``, shape ``t.shape + (4,)``."""
    s = 1.0 - t
    if derivative:
        return np.stack(
            [-3 * s * s, 3 * s * s - 6 * t * s, 6 * t * s - 3 * t * t, 3 * t * t], axis=-1
        )
    return np.stack([s**3, 3 * t * s * s, 3 * t * t * s, t**3], axis=-1)


def _unit_rows(v: FloatArray) -> FloatArray:
    length = np.linalg.norm(v, axis=-1, keepdims=True)
    return v / np.where(length > 0, length, 1.0)


def _normal_along(tangent: FloatArray, n0: FloatArray, n1: FloatArray, t: FloatArray) -> FloatArray:
    """The normal ``(1 − t) n0 + t n1`` made ⊥ the unit ``tangent`` and unit."""
    n = (1.0 - t)[..., None] * n0 + t[..., None] * n1
    tangent = _unit_rows(tangent)
    return _unit_rows(n - _dot(n, tangent)[..., None] * tangent)


def _circle_section(
    p: FloatArray, q: FloatArray, n_p: FloatArray, n_q: FloatArray, s: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """Point and normal at ``s`` of the circle-aware Hermite cubic from p to q (tangents: q − p
    projected onto each end's plane, length ``2|d|²/(|d| + |s|)``), the normal blended along it."""
    d = q - p
    chord = np.linalg.norm(d, axis=-1)

    def tangent(direction: FloatArray, n: FloatArray) -> FloatArray:
        projected = direction - _dot(direction, n)[..., None] * n
        length = np.linalg.norm(projected, axis=-1)
        return (
            projected
            * (2.0 * chord**2 / (chord + length) / np.where(length > 0, length, 1.0))[..., None]
        )

    net = (p, p + tangent(d, n_p) / 3.0, q + tangent(-d, n_q) / 3.0, q)
    b, db = _bernstein(s), _bernstein(s, True)
    point = sum(b[..., i, None] * net[i] for i in range(4))
    along = sum(db[..., i, None] * net[i] for i in range(4))
    return point, _normal_along(along, n_p, n_q, s)


def _round_interior(
    boundary: FloatArray, corner_normals: FloatArray, start: FloatArray
) -> FloatArray:
    """Interior Bézier points (b11, b21, b22, b12) per face that best fit the circle sections.

    ``boundary`` (F, 4, 4, 3): the four boundary cubics, edge k from corner k to k + 1;
    ``corner_normals`` (F, 4, 3); ``start`` (F, 4, 3) the twist targets. On a grid of interior
    samples (u, v) the target is the circle-aware cubic across the face from the bottom to the
    top curve at u (and from the left to the right curve at v), both with normals blended from the
    corners; the four points minimise ``Σ (n·(p(u, v) − X))² + λ |b − start|²`` (point-to-plane:
    the sections fix the surface, not its parameterisation). On a sphere the sections are great
    circles, so the cube comes out round.
    """
    count = len(start)
    g = (np.arange(_ROUND_SAMPLES) + 1.0) / (_ROUND_SAMPLES + 1.0)
    u, v = (a.ravel() for a in np.meshgrid(g, g, indexing="ij"))

    def curve(k: int, t: FloatArray) -> tuple[FloatArray, FloatArray]:
        pos = np.einsum("sk,fkd->fsd", _bernstein(t), boundary[:, k])
        along = np.einsum("sk,fkd->fsd", _bernstein(t, True), boundary[:, k])
        return pos, _normal_along(
            along, corner_normals[:, k, None], corner_normals[:, (k + 1) % 4, None], t[None, :]
        )

    (bottom, n_bottom), (top, n_top) = curve(0, u), curve(2, 1.0 - u)
    (left, n_left), (right, n_right) = curve(3, 1.0 - v), curve(1, v)
    across_v = _circle_section(bottom, top, n_bottom, n_top, np.broadcast_to(v, bottom.shape[:2]))
    across_u = _circle_section(left, right, n_left, n_right, np.broadcast_to(u, left.shape[:2]))
    targets = np.concatenate([across_v[0], across_u[0]], axis=1)
    normals = np.concatenate([across_v[1], across_u[1]], axis=1)

    weights = _bernstein(u)[:, :, None] * _bernstein(v)[:, None, :]  # (S, 4, 4) tensor Bernstein
    known = np.einsum("sij,fijd->fsd", weights, _bezier_net(boundary, np.zeros((count, 4, 3))))
    inner_weights = np.tile(weights[:, _INNER[:, 0], _INNER[:, 1]], (2, 1))  # (2S, 4)
    rows = (inner_weights[None, :, :, None] * normals[:, :, None, :]).reshape(count, -1, 12)
    rhs = _dot(normals, targets - np.concatenate([known, known], axis=1))
    system = np.einsum("fri,frj->fij", rows, rows)
    right_side = np.einsum("fri,fr->fi", rows, rhs)
    pull = _ROUND_PULL * np.einsum("fii->f", system) / 12.0
    system += pull[:, None, None] * np.eye(12)
    right_side += pull[:, None] * start.reshape(count, 12)
    return np.linalg.solve(system, right_side[..., None])[..., 0].reshape(count, 4, 3)


def _bezier_net(boundary: FloatArray, interior: FloatArray) -> FloatArray:
    """The (F, 4, 4, 3) Bézier nets of four boundary cubics (F, 4, 4, 3), edge k from corner k to
    k + 1, and interior points (F, 4, 3) at corners 0..3 (b11, b21, b22, b12)."""
    net = np.empty((len(interior), 4, 4, 3))
    net[:, :, 0], net[:, 3, :] = boundary[:, 0], boundary[:, 1]
    net[:, ::-1, 3], net[:, 0, ::-1] = boundary[:, 2], boundary[:, 3]
    net[:, _INNER[:, 0], _INNER[:, 1]] = interior
    return net


def _turns_within(
    boundary: FloatArray, interior: FloatArray, corner_normals: FloatArray
) -> NDArray[np.bool_]:
    """Per face: does the bicubic with this boundary and interior keep its normal within
    ``_ROUND_MAX_TURN`` of the bilinear blend of its corner normals on a 5 × 5 grid?"""
    net = _bezier_net(boundary, interior)
    g = np.linspace(0.0, 1.0, 5)
    b, db = _bernstein(g), _bernstein(g, True)
    p_u = np.einsum("ai,bj,fijd->fabd", db, b, net)
    p_v = np.einsum("ai,bj,fijd->fabd", b, db, net)
    normal = _unit_rows(np.cross(p_u, p_v))
    u, v = g[:, None, None], g[None, :, None]
    n = corner_normals[:, :, None, None, :]
    blend = _unit_rows(
        (1 - u) * (1 - v) * n[:, 0]
        + u * (1 - v) * n[:, 1]
        + u * v * n[:, 2]
        + (1 - u) * v * n[:, 3]
    )
    return (_dot(normal, blend) >= np.cos(_ROUND_MAX_TURN)).all(axis=(1, 2))


def _sphere_misfit(x: FloatArray, n: FloatArray) -> FloatArray:
    """How far a face's corners (F, 4, 3) and normals are from one sphere: ``x_i ≈ c + R n_i`` by
    least squares (``R = Σ (x_i − x̄)·(n_i − n̄) / Σ |n_i − n̄|²``), the RMS residual over the mean
    edge length. 0 on any sphere; 0.05–0.1 with 8 % noise; 0.2–0.4 on a coarse ellipsoid, 0.4–0.8
    on coarse tori, one-ring disks and Spot's legs."""
    xc = x - x.mean(axis=1, keepdims=True)
    nc = n - n.mean(axis=1, keepdims=True)
    spread = _dot(nc, nc).sum(axis=1)
    radius = _dot(xc, nc).sum(axis=1) / np.where(spread > 0, spread, 1.0)
    residual = xc - radius[:, None, None] * nc
    size = np.linalg.norm(x - x[:, _NEXT], axis=2).mean(axis=1)
    return np.sqrt(_dot(residual, residual).mean(axis=1)) / np.where(size > 0, size, 1.0)


def _round_coarse_faces(
    mesh: QuadMesh, tangents: FloatArray, corner_normals: FloatArray, interior: FloatArray
) -> FloatArray:
    """Blend the circle-section fit (:func:`_round_interior`) into the twist targets of coarse
    faces: weight ``smoothstep((θ − 10°)/30°)`` of the largest angle θ between the normals at
    the ends of the face's edges, so fine meshes keep the local targets (and their order) and
    faces that turn the normal by 40° or more (the cube: 70.5°) take the fit alone; the weight
    falls linearly to 0 as the face's corners depart from one sphere (:func:`_sphere_misfit` up
    to ``_ROUND_MISFIT``): the sections are circles, so only where a sphere models the face's own
    data are they a better guess than the local targets (elsewhere they made coarse tori and
    one-ring disks lumpy). A face whose
    blended patch would turn its normal more than 60° away from its corners' (a thin wedge of a
    high-valence fan, where the sections are poorly posed) halves the weight, up to three times,
    then keeps its twist targets."""
    topology = mesh.topology
    faces = topology.faces
    n = corner_normals
    turn = np.empty(len(n))
    jit_kernel(_turn_kernel)(n, turn)
    weight = np.clip((turn - _ROUND_START) / (_ROUND_FULL - _ROUND_START), 0.0, 1.0)
    weight = weight * weight * (3.0 - 2.0 * weight)
    chosen = np.flatnonzero(weight > 0)
    if not chosen.size:
        return interior
    weight[chosen] *= np.clip(
        1.0 - _sphere_misfit(mesh.vertices[faces[chosen]], n[chosen]) / _ROUND_MISFIT, 0.0, 1.0
    )
    chosen = chosen[weight[chosen] > 0]
    if not chosen.size:
        return interior
    slot_out, slot_in = slot_tables(topology)
    x = mesh.vertices
    out = interior.copy()
    for low in range(0, chosen.size, _ROUND_BLOCK):
        block = chosen[low : low + _ROUND_BLOCK]
        h = (4 * block[:, None] + np.arange(4)).ravel()
        a, b = x[topology.origin(h)], x[topology.target(h)]
        boundary = np.stack(
            [a, a + tangents[slot_out[h]] / 3.0, b + tangents[slot_in[h]] / 3.0, b], axis=1
        ).reshape(-1, 4, 4, 3)
        change = _round_interior(boundary, n[block], interior[block]) - interior[block]
        scale = weight[block]
        pending = np.ones(len(block), dtype=bool)
        for _ in range(4):
            trial = interior[block] + scale[:, None, None] * change
            pending &= ~_turns_within(boundary, trial, n[block])
            if not pending.any():
                break
            scale = np.where(pending, 0.5 * scale, scale)
        scale[pending] = 0.0
        out[block] += scale[:, None, None] * change
    return out


def _turn_kernel(corner_normals: FloatArray, turn: FloatArray) -> None:
    """Per face the largest angle between the corner normals at the ends of an edge,
    ``max_k arccos(clip(n_k·n_{k+1}, −1, 1))``."""
    for f in range(corner_normals.shape[0]):
        largest = 0.0
        for k in range(4):
            a, b = corner_normals[f, k], corner_normals[f, (k + 1) & 3]
            angle = np.arccos(min(max(a[0] * b[0] + a[1] * b[1] + a[2] * b[2], -1.0), 1.0))
            if not angle <= largest:
                largest = angle
        turn[f] = largest


def interpolate_targets(mesh: QuadMesh) -> Targets:
    """The default interpolating rule (module docstring)."""
    from .frames import vertex_frames

    frames = vertex_frames(mesh)
    topology = mesh.topology
    normals = frames.normals
    raw, chord, parallel = _projected_tangents(mesh, normals)
    raw = _along_smooth_lines(mesh, normals, raw, out=raw)
    raw = _smooth_boundary_tangents(mesh, normals, raw)
    tangents, guarded = safeguarded_fans(topology, normals, raw, chord)
    tangents = in_vertex_planes(tangents, normals, topology.neighbor_offsets, out=tangents)
    fallback = guarded | frames.repaired | parallel
    seams = seam_edges(mesh, INTERPOLATE_SHARPNESS)
    corner_normals = normals[topology.faces]
    both = np.empty(
        (topology.n_faces, 4, 2, 3)
    )  # Targets.interior: the same target for both edges at a corner
    first = both[:, :, 0]
    interior = _interior_targets(
        topology, mesh.vertices, tangents, normals, frames.shape_operator, out=first
    )
    if seams.any():
        tangents, sector_normals, creased, spread = crease_tangents(
            mesh, seams, tangents, sharp_vertices(mesh, INTERPOLATE_SHARPNESS)
        )
        at_crease = creased[topology.faces]
        corner_normals = np.where(at_crease[..., None], sector_normals, corner_normals)
        # the bilinear twist: a shape operator fitted across the crease means nothing, and on an
        # extruded side (a box's fillet) it keeps the cross derivative exactly along the extrusion
        bilinear = _interior_targets(topology, mesh.vertices, tangents, normals, None)
        interior = np.where(at_crease[..., None], bilinear, interior)
        fallback = (fallback & ~creased) | spread
    rounded = _round_coarse_faces(mesh, tangents, corner_normals, interior)
    if (
        seams.any()
    ):  # the circle sections model one sphere through a face's corners: not across a crease
        rounded = np.where(at_crease.any(axis=1)[:, None, None], interior, rounded)
    if rounded is not first:
        first[:] = rounded
    both[:, :, 1] = first
    return Targets(
        topology,
        mesh.vertices,
        normals,
        tangents,
        both,
        seams,
        fallback,
        "interpolate",
        corner_normals,
    )


def retreat(targets: Targets, vertices: IntArray, weight: float) -> Targets:
    """``targets`` moved by ``weight`` ∈ [0, 1] towards the previous release's rule at ``vertices``:
    their normals towards the fan normal, their slot tangents (re-projected) towards the regular
    star fitted to that fan, and the interior targets of every face corner at them towards the
    bilinear twist (no curvature term, no section fit). The build's fold guard uses it where a
    patch turns back on itself; those vertices join ``fallback``. Creased vertices (more than one
    sector) keep their targets."""
    topology = targets.topology
    chosen = np.zeros(topology.n_vertices, dtype=bool)
    chosen[vertices] = True
    sectored = np.zeros(topology.n_vertices, dtype=bool)
    sectored[
        topology.faces[(targets.corner_normals != targets.normals[topology.faces]).any(axis=2)]
    ] = True
    chosen &= ~sectored  # a creased vertex keeps its sectors' planes
    fan = fan_normals(QuadMesh(targets.positions, topology))
    normals = targets.normals.copy()
    normals[chosen] = _unit_rows((1.0 - weight) * normals[chosen] + weight * fan[chosen])
    slot_vertex = slot_vertices(topology)
    n = normals[slot_vertex]
    projected = targets.tangents - _dot(targets.tangents, n)[:, None] * n
    star, _, valid = fit_regular_star(topology, normals, projected)
    chosen &= valid
    rows = chosen[slot_vertex]
    tangents = targets.tangents.copy()
    tangents[rows] = (1.0 - weight) * projected[rows] + weight * star[rows]
    bilinear = _interior_targets(topology, targets.positions, tangents, normals, None)
    corners = chosen[topology.faces]
    interior = targets.interior.copy()
    interior[corners] = (1.0 - weight) * interior[corners] + weight * bilinear[corners][:, None, :]
    corner_normals = np.where(
        sectored[topology.faces][..., None], targets.corner_normals, normals[topology.faces]
    )
    return targets.with_changes(
        normals=normals,
        tangents=tangents,
        interior=interior,
        fallback=targets.fallback | chosen,
        corner_normals=corner_normals,
    )


def shape_targets(
    mesh: QuadMesh, shape: ShapeRule = "interpolate", *, tangents: TangentRule = "arc"
) -> Targets:
    """The targets of ``mesh`` by the named rule: ``interpolate`` (this module), ``limit`` (the
    Catmull–Clark limit of the mesh as a control cage, :mod:`g1patch.targets.limit`) or
    ``legacy``."""
    check_choice("shape", shape, SHAPES)
    if shape == "legacy":
        return legacy_targets(mesh, tangents)
    if shape == "limit":
        from .limit import limit_targets

        return limit_targets(mesh)
    if shape == "limit-interpolate":
        from .limit_interpolate import limit_interpolate_targets

        return limit_interpolate_targets(mesh)
    return interpolate_targets(mesh)
