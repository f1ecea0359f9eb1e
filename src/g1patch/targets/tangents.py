"""Slot tangents read off the mesh edges, before the fan safeguard
(:mod:`g1patch.targets.fans`): the first steps of the ``interpolate`` rule
(:mod:`g1patch.targets.interpolate`, whose docstring tells them in full).

* :func:`_projected_tangents`: every mesh edge projected onto the tangent plane with the
  circle-aware length ``2|d|²/(|d| + |s|)``;
* :func:`_along_smooth_lines`: the two slots of a mesh line that runs on smoothly through a
  regular vertex turned along the circle through its three points;
* :func:`_smooth_boundary_tangents`: the rim slots of a boundary vertex along the rim's central
  difference, so the boundary curve does not kink.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ..kernels import in_chunks, jit_kernel, use_kernels
from ..mesh import QuadMesh
from .local import cross, dot, slot_vertices, unit_rows

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

#: a boundary vertex's rim turn up to which its rim is made smooth, and from which it is a corner
_RIM_SMOOTH = np.radians(45.0)
_RIM_CORNER = np.radians(90.0)
#: a mesh line B' → A → B through a regular vertex runs on smoothly (its slots at A turn along it)
#: when its turn at A is within this share of the mean of its turns at B and B', plus the slack
#: (rad)
_LINE_SHARE = 0.25
_LINE_SLACK = np.radians(0.1)
#: an edge whose projection onto the tangent plane is shorter than this share of its length is
#: treated as parallel to the normal: its direction is undefined and the safeguard replaces it
_PARALLEL = 1e-6


def _projected_tangents(
    mesh: QuadMesh, normals: FloatArray, *, compiled: bool = True
) -> tuple[FloatArray, FloatArray, NDArray[np.bool_]]:
    """Circle-aware projected edge tangents per slot, the chord lengths, and per vertex whether a
    slot is (near) parallel to the normal (its tangent is set to 0). ``compiled``: slot by slot in
    :func:`_projected_kernel`, else NumPy."""
    compiled = use_kernels(compiled)  # NumPy where kernels cannot be cached
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
    s = d - dot(d, n)[:, None] * n
    in_plane = np.linalg.norm(s, axis=1)
    chord = np.linalg.norm(d, axis=1)
    parallel = ~(in_plane > _PARALLEL * chord)
    across = chord + in_plane  # 0 only for a zero chord, a parallel slot: no length
    length = np.divide(2.0 * chord**2, across, out=np.zeros_like(chord), where=across > 0)
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
    u = u - dot(u, n)[:, None] * n
    w = w - dot(w, n)[:, None] * n
    return np.arctan2(dot(cross(u, w), n), dot(u, w))


def _along_smooth_lines(
    mesh: QuadMesh,
    normals: FloatArray,
    raw: FloatArray,
    *,
    compiled: bool = True,
    out: FloatArray | None = None,
) -> FloatArray:
    """``raw`` with the slots of mesh lines that run on smoothly through a regular vertex turned
    along the line (:mod:`g1patch.targets.interpolate`): at an interior vertex A of valence 4, the
    line B' → A → B of opposite neighbours is *smooth* when its signed turn at A (:func:`_turn`) is
    within :data:`_LINE_SHARE` of the larger magnitude, plus :data:`_LINE_SLACK`, of the mean of its
    turns at B and B' (continued through each that is regular too; at least one is). Both slots
    then point along the tangent at A of the circle through B', A, B, ``|a|² b − |b|² a`` with
    ``a = B' − A``, ``b = B − A``, in A's plane, with their own lengths. ``compiled``: vertex by
    vertex in :func:`_lines_kernel` (ranges side by side), else NumPy; into ``out`` (``raw``
    itself may be given: a slot is read only before it is written), by default a copy of ``raw``."""
    compiled = use_kernels(compiled)  # NumPy where kernels cannot be cached
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
        # the turns at B (A → B → beyond) and at B' (beyond → B' → A) where those are regular
        ok = regular[fore]
        i = np.flatnonzero(ok)
        total[ok] += _turn(x[a[i]], x[fore[i]], x[beyond(fore[i], a[i])], normals[fore[i]])
        count += ok
        ok = regular[back]
        i = np.flatnonzero(ok)
        total[ok] += _turn(x[beyond(back[i], a[i])], x[back[i]], x[a[i]], normals[back[i]])
        count += ok
        at_a = _turn(x[back], x[a], x[fore], normals[a])
        mean = total / np.maximum(count, 1)
        d_back, d_fore = x[back] - x[a], x[fore] - x[a]
        along = dot(d_back, d_back)[:, None] * d_fore - dot(d_fore, d_fore)[:, None] * d_back
        along -= dot(along, normals[a])[:, None] * normals[a]
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
    along -= dot(along, n)[:, None] * n
    length = np.linalg.norm(along, axis=1)
    usable = length > _PARALLEL * (np.linalg.norm(d_next, axis=1) + np.linalg.norm(d_prev, axis=1))
    direction = along / np.where(usable, length, 1.0)[:, None]
    unit_next, unit_prev = unit_rows(d_next), unit_rows(d_prev)
    rim_turn = np.arccos(np.clip(-dot(unit_next, unit_prev), -1.0, 1.0))
    weight = np.clip((_RIM_CORNER - rim_turn) / (_RIM_CORNER - _RIM_SMOOTH), 0.0, 1.0)[:, None]
    out = raw.copy()
    for slot, d, sign in ((first, d_next, 1.0), (last, d_prev, -1.0)):
        own = unit_rows(raw[slot])
        blended = unit_rows((1.0 - weight) * own + weight * sign * direction)
        chord = np.linalg.norm(d, axis=1)
        across = chord + np.abs(dot(d, blended))  # 0 only for a zero chord: no arc
        arc = np.divide(2.0 * chord**2, across, out=np.zeros_like(chord), where=across > 0)
        keep = usable & (np.linalg.norm(raw[slot], axis=1) > 0)
        out[slot[keep]] = (arc[:, None] * blended)[keep]
    return out
