"""split4's stars at the mesh vertices: per ring slot a tangent ``t_j`` and the half ``c_j`` of
its star coefficient, ``t_{j−1} + t_{j+1} = 2 c_j t_j`` (:func:`split4_star`).

The regular star fitted to each target fan (:func:`_star_kernel` vertex by vertex from
:data:`~g1patch.construct.split4.threshold.KERNEL_FACES` faces on), at boundary vertices fitted to
the turn of their own fan (:func:`_rim_stars`), optionally the nearest fan of equal sectors on the
boundary and at odd valence (:func:`_equal_area_fans`); everywhere the length safeguard
(:data:`STAR_LENGTH_LIMIT`, :func:`_length_shrink`).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from ...kernels import in_chunks, jit_kernel
from ...mesh import QuadTopology
from ...targets import Targets, halfedge_slots
from ...targets.fans import fit_regular_star, spread_fan
from ...targets.local import slot_vertices
from .threshold import use_kernels

__all__ = [
    "EQUAL_AREA_RTOL",
    "EQUAL_AREA_SINE",
    "EQUAL_AREA_STEPS",
    "STAR_LENGTH_LIMIT",
    "FanWalk",
    "SplitStar",
    "edge_end_cosines",
    "fan_walk",
    "split4_star",
]

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]


def _unit(v: FloatArray) -> FloatArray:
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def _dot(a: FloatArray, b: FloatArray) -> FloatArray:
    return np.einsum("...d,...d->...", a, b)


#: no star tangent may exceed this multiple of its own target tangent's length: a regular star
#: fitted to an irregular fan gives a short edge opposite a long one a tangent several times its
#: length, and its boundary cubic then overshoots the neighbour (shape-diagnosis.md cause 1); nor
#: of the circle-aware length of its edge: a target fan that is itself a regular star (the legacy
#: rule) gives the short edge at a box corner a tangent several chords long, and the cubic loops
STAR_LENGTH_LIMIT = 1.5


class SplitStar(NamedTuple):
    """The stars of :func:`split4_star`: tangents per ring slot (S, 3); per slot j the half ``c_j``
    of its star coefficient, ``t_{j−1} + t_{j+1} = 2 c_j t_j`` (S,) (a regular star's slots all have
    the cosine of its angle step); the vertices whose fan was refitted to spread directions
    (``refitted``: a real fallback), those whose star the length safeguard scaled down (``shrunk``)
    and the scale factor (≤ 1) per vertex."""

    star: FloatArray
    cosine: FloatArray
    refitted: NDArray[np.bool_]
    shrunk: NDArray[np.bool_]
    factor: FloatArray


def _per_slot(topology: QuadTopology, values: FloatArray) -> FloatArray:
    """A value per vertex repeated on each of its ring slots (S,)."""
    return np.repeat(values, np.diff(topology.neighbor_offsets))


def edge_end_cosines(topology: QuadTopology, cosine: FloatArray) -> FloatArray:
    """(E, 2): the star's ``c`` (:class:`SplitStar`, per slot) of each edge at X and at Y (its first
    half-edge X → Y)."""
    slot_out, slot_in = halfedge_slots(topology)
    h = topology.edge_halfedges[:, 0]
    return np.stack([cosine[slot_out[h]], cosine[slot_in[h]]], axis=1)


def split4_star(
    targets: Targets, *, compiled: bool | None = None, equal_sectors: bool = False
) -> SplitStar:
    """The stars split4 needs, fitted to the target fans: the regular star (at even interior
    valence the twist systems are solvable only for affine-regular stars) ``t_j = a cos θ_j + b sin
    θ_j``, ``c_v = cos`` of the angle step. With ``equal_sectors``, on the boundary and at odd
    valence the nearest fan of equal sectors instead (:func:`_equal_area_fans`): for reproducing a
    surface whose fans are given (a Gregory network's, :mod:`~g1patch.construct.polynomial`); a
    build keeps the regular stars, which are fairer where the targets' angles are uneven (a genus-2
    cage's odd vertices: turn p99 5.2° against 6.4°) and closer to the Catmull–Clark limit (Spot,
    limit: 3.8e-4 of the diagonal against 5.0e-4). A star that does not turn counter-clockwise is
    refitted to evenly spread target directions (a fallback). Length safeguard: each vertex's star
    is scaled down uniformly (it stays regular) until no tangent is longer than
    :data:`STAR_LENGTH_LIMIT` × the shorter of its target's and the circle-aware Hermite length of
    its edge (``2|d|²/(|d| + |P d|)``, P the projection onto the tangent plane: what the interpolate
    rule's tangents are). ``compiled``: vertex by vertex in :func:`_star_kernel` (ranges side by
    side), default from :data:`~g1patch.construct.split4.threshold.KERNEL_FACES` faces on; where a
    fan needs the refit, the NumPy reference.
    """
    topology = targets.topology
    wanted = targets.tangents
    if use_kernels(topology.n_faces, compiled):
        star = np.empty(wanted.shape)
        valid = np.empty(topology.n_vertices, dtype=bool)
        factor = np.empty(topology.n_vertices)
        kernel = jit_kernel(_star_kernel)
        arrays = [
            np.ascontiguousarray(a, dtype=np.float64)
            for a in (targets.normals, wanted, targets.positions)
        ]
        in_chunks(
            lambda lo, hi: kernel(
                *arrays,
                topology.neighbor_offsets,
                topology.neighbors,
                topology.face_count,
                topology.valence,
                topology.is_boundary_vertex,
                STAR_LENGTH_LIMIT,
                star,
                valid,
                factor,
                lo,
                hi,
            ),
            topology.n_vertices,
        )
        if valid.all():
            step = np.where(
                topology.is_boundary_vertex,
                np.pi / topology.face_count,
                2.0 * np.pi / topology.valence,
            )
            stars = _rim_stars(
                targets,
                SplitStar(star, _per_slot(topology, np.cos(step)), ~valid, factor < 1.0, factor),
            )
            return _equal_area_fans(targets, stars) if equal_sectors else stars
    star, cosine, valid = fit_regular_star(topology, targets.normals, wanted)
    if not valid.all():
        chord = np.linalg.norm(wanted, axis=1)
        wanted = spread_fan(topology, targets.normals, wanted, chord, np.flatnonzero(~valid))
        star, cosine, _ = fit_regular_star(topology, targets.normals, wanted)
    slot_vertex = slot_vertices(topology)
    shrink = _length_shrink(
        targets, star, wanted, np.arange(len(star)), slot_vertex, slot_vertex, topology.n_vertices
    )
    star *= shrink[slot_vertex, None]
    stars = _rim_stars(targets, SplitStar(star, cosine[slot_vertex], ~valid, shrink < 1.0, shrink))
    return _equal_area_fans(targets, stars) if equal_sectors else stars


def _length_shrink(
    targets: Targets,
    star: FloatArray,
    wanted: FloatArray,
    slots: IntArray,
    vertex: IntArray,
    owner: IntArray,
    count: int,
) -> FloatArray:
    """:func:`split4_star`'s length safeguard: per owner (``count`` of them) ``min(1, 1 / max_j
    |t_j| / allowed_j)`` over its ``slots`` at their ``vertex`` (star rows ``t_j``, target rows
    ``wanted``), ``allowed = limit · min(|s|, 2|d|²/(|d| + |P d|))``."""
    topology = targets.topology
    edge = targets.positions[topology.neighbors[slots]] - targets.positions[vertex]
    normal = targets.normals[vertex]
    chord = np.linalg.norm(edge, axis=1)
    in_plane = np.linalg.norm(edge - _dot(edge, normal)[:, None] * normal, axis=1)
    arc = (
        2.0 * chord**2 / np.where(chord > 0, chord + in_plane, 1.0)
    )  # the circle-aware Hermite length
    allowed = STAR_LENGTH_LIMIT * np.minimum(np.linalg.norm(wanted, axis=1), arc)
    ratio = np.linalg.norm(star, axis=1) / np.where(allowed > 0, allowed, np.inf)
    worst = np.zeros(count)
    np.maximum.at(worst, owner, ratio)
    return np.minimum(1.0, 1.0 / np.where(worst > 0, worst, 1.0))


class FanWalk(NamedTuple):
    """The k + 1 slots of each of some boundary fans in ring order: per slot its fan (``owner``),
    its place in the fan (``j``), its slot index, its target tangent; per fan the total turn ``Φ``
    from the first slot to the last about the vertex normal (the sum of the turns between
    consecutive slots, ``atan2(n·(t_{j−1} × t_j), t_{j−1}·t_j)``)."""

    owner: IntArray
    j: IntArray
    slot: IntArray
    tangent: FloatArray
    turn: FloatArray


def fan_walk(targets: Targets, vertices: IntArray) -> FanWalk:
    """:class:`FanWalk` of the fans of ``vertices`` (boundary vertices, k = face count slots +
    1)."""
    topology = targets.topology
    k = topology.face_count[vertices]
    owner = np.repeat(np.arange(vertices.size), k + 1)
    j = np.arange(owner.size) - np.repeat(np.cumsum(k + 1) - (k + 1), k + 1)
    slot = topology.neighbor_offsets[vertices][owner] + j
    t = targets.tangents[slot]
    previous = targets.tangents[np.where(j > 0, slot - 1, slot)]
    normal = targets.normals[vertices][owner]
    turn = np.arctan2(_dot(np.cross(previous, t), normal), _dot(previous, t))
    total = np.asarray(np.bincount(owner, turn, minlength=vertices.size), dtype=np.float64)
    return FanWalk(owner, j, slot, t, total)


#: a boundary fan turning by at least this (and at most 2π minus it) gets a star of its own turn
#: (:func:`_rim_stars`); below :data:`_RIM_TURN_NONE` one straight through, blended between
_RIM_TURN_FULL = np.radians(60.0)
_RIM_TURN_NONE = np.radians(30.0)


def _rim_stars(targets: Targets, base: SplitStar) -> SplitStar:
    """``base`` with the stars of the boundary vertices with k ≥ 2 faces fitted to the turn of their
    own fan: ``Φ`` the fan's turn from its first rim slot to its last about the normal (the sum of
    the turns between consecutive slots), step ``θ = Φ/k`` (π/k in ``base``: the rim straight
    through), ``[a b]`` by least squares over the k + 1 slots, ``t_j = a cos jθ + b sin jθ`` (the
    2 × 2 Gram matrix, no longer diagonal), ``c_v = cos θ``, the same length safeguard. A rim that
    turns at the vertex (a boundary corner of a coarse cage: the interpolate rule keeps it) keeps
    its direction: fitted to a straight star its rim tangents turned by up to 30°, and the CAD
    surface of catmark_xord_boundary lay 1.3e-2 of the diagonal off the Gregory one (now 1.8e-3).
    A fan turning by less than :data:`_RIM_TURN_FULL` (or more than 2π minus it) fits a turn
    blended towards π, ``w Φ + (1 − w) π``, w the smoothstep of ``min(Φ, 2π − Φ)`` from
    :data:`_RIM_TURN_NONE` to :data:`_RIM_TURN_FULL`: the sliver faces of a zigzag rim (the flat
    360-valent fan's spokes, Φ ≈ 1°) folded with a star that thin. Where Φ is π this is ``base``'s
    fit; a fan that does not turn once forward (Φ ∉ (0, 2π)), a refitted one, or a star that would
    not turn counter-clockwise keeps ``base``."""
    topology = targets.topology
    rims = np.flatnonzero(topology.is_boundary_vertex & (topology.face_count >= 2) & ~base.refitted)
    if not rims.size:
        return base
    k = topology.face_count[rims]
    owner, j, slot, t, own = fan_walk(targets, rims)
    narrow = np.clip(
        (np.minimum(own, 2.0 * np.pi - own) - _RIM_TURN_NONE) / (_RIM_TURN_FULL - _RIM_TURN_NONE),
        0.0,
        1.0,
    )
    weight = narrow * narrow * (3.0 - 2.0 * narrow)
    total = weight * own + (1.0 - weight) * np.pi
    theta = j * (total / k)[owner]
    c, s = np.cos(theta), np.sin(theta)
    cc, cs, ss = (np.bincount(owner, w, minlength=rims.size) for w in (c * c, c * s, s * s))
    moment_c = np.stack(
        [np.bincount(owner, c * t[:, d], minlength=rims.size) for d in range(3)], axis=1
    )
    moment_s = np.stack(
        [np.bincount(owner, s * t[:, d], minlength=rims.size) for d in range(3)], axis=1
    )
    det = cc * ss - cs * cs
    safe = np.where(det > 0, det, 1.0)[:, None]
    a = (ss[:, None] * moment_c - cs[:, None] * moment_s) / safe
    b = (cc[:, None] * moment_s - cs[:, None] * moment_c) / safe
    area = _dot(np.cross(a, b), targets.normals[rims])
    good = (own > 0) & (own < 2.0 * np.pi) & (det > 0) & (area > 1e-12 * (_dot(a, a) + _dot(b, b)))
    fitted = c[:, None] * a[owner] + s[:, None] * b[owner]
    shrink = _length_shrink(targets, fitted, t, slot, rims[owner], owner, rims.size)
    keep = good[owner]
    star, cosine, factor = base.star.copy(), base.cosine.copy(), base.factor.copy()
    star[slot[keep]] = fitted[keep] * shrink[owner[keep], None]
    cosine[slot[keep]] = np.cos(total / k)[owner[keep]]
    factor[rims[good]] = shrink[good]
    return SplitStar(star, cosine, base.refitted, factor < 1.0, factor)


#: Gauss–Newton steps of :func:`_equal_area_fans`' projection, and the largest relative difference
#: of its sectors' areas that is taken as equal (to rounding: G1 depends on it)
EQUAL_AREA_STEPS = 12
EQUAL_AREA_RTOL = 1e-13
#: :func:`_equal_area_fans` keeps ``base`` where a sector of its fan turns by less than this (sine)
EQUAL_AREA_SINE = 0.05


def _sector_areas(fan: FloatArray, j: IntArray, nxt: IntArray) -> FloatArray:
    """(g, sectors): ``t_j × t_{j+1}`` of plane fans (g, m, 2), sector j from slot ``j`` to slot
    ``nxt``."""
    return fan[:, j, 0] * fan[:, nxt, 1] - fan[:, j, 1] * fan[:, nxt, 0]


def _equal_area_fans(targets: Targets, base: SplitStar) -> SplitStar:
    """``base`` with the fans of boundary vertices (k ≥ 2 faces) and of interior vertices of odd
    valence replaced by the nearest fan (least squares over its tangents, in the tangent plane)
    whose sectors all have the same area ``t_j × t_{j+1}``: then ``t_{j−1} + t_{j+1} = λ_j t_j`` at
    every slot (cross both sides with t_j), ``λ_j = (t_{j−1} + t_{j+1})·t_j / |t_j|²``, which is all
    split4's G1 needs there, their twist systems having no compatibility condition (a path, an odd
    cycle). Regular stars are such fans too, but most target fans are not regular (a coarse cage's
    boundary corner, a valence-3 or 5 vertex with unequal angles), and a regular star turned their
    tangents by degrees. The nearest fan is the projection onto ``A_j − A_{j+1} = 0`` by
    Gauss–Newton from the targets (:data:`EQUAL_AREA_STEPS` steps ``δ = r − Jᵀ (J Jᵀ)⁻¹ (J r + h)``,
    r the way back to the targets). The same length safeguard as the regular stars. ``base`` is kept
    where the areas do not agree to :data:`EQUAL_AREA_RTOL`, a sector of the target fan or of the
    result turns by less than :data:`EQUAL_AREA_SINE` (sine), or the vertex was refitted."""
    topology = targets.topology
    boundary = topology.is_boundary_vertex
    eligible = ~base.refitted & np.where(
        boundary, topology.face_count >= 2, topology.valence % 2 == 1
    )
    star, cosine, factor = base.star.copy(), base.cosine.copy(), base.factor.copy()
    size = topology.face_count + boundary  # slots in the fan: k + 1 on the boundary, n inside
    keys = np.unique(2 * size[eligible] + boundary[eligible])  # one group per (fan size, boundary)
    for m, is_open in zip((keys // 2).tolist(), (keys % 2 == 1).tolist(), strict=True):
        vs = np.flatnonzero(eligible & (boundary == is_open) & (size == m))
        slots = topology.neighbor_offsets[vs][:, None] + np.arange(m)  # (g, m)
        normal = targets.normals[vs]
        first = targets.tangents[slots[:, 0]]
        e1 = _unit(first - _dot(first, normal)[:, None] * normal)
        e2 = np.cross(normal, e1)
        wanted = targets.tangents[slots]
        goal = np.stack(
            [_dot(wanted, e1[:, None]), _dot(wanted, e2[:, None])], axis=-1
        )  # (g, m, 2) in the plane
        sectors = m - 1 if is_open else m
        j = np.arange(sectors)
        nxt = (j + 1) % m

        start_area = _sector_areas(goal, j, nxt)
        start_length = np.linalg.norm(goal, axis=-1)
        posed = (start_area >= EQUAL_AREA_SINE * start_length[:, j] * start_length[:, nxt]).all(
            axis=1
        )
        posed &= (start_length > 0).all(
            axis=1
        )  # every sector turns forward: the projection is well posed
        vs, slots, wanted, goal, e1, e2 = (
            vs[posed],
            slots[posed],
            wanted[posed],
            goal[posed],
            e1[posed],
            e2[posed],
        )
        if not vs.size:
            continue
        fan = goal.copy()
        for _ in range(EQUAL_AREA_STEPS):
            u, w = fan[..., 0], fan[..., 1]
            area = _sector_areas(fan, j, nxt)
            grad = np.zeros((len(vs), sectors, m, 2))  # ∂A_j / ∂(u, w)
            grad[:, j, j, 0], grad[:, j, j, 1] = w[:, nxt], -u[:, nxt]
            grad[:, j, nxt, 0], grad[:, j, nxt, 1] = -w[:, j], u[:, j]
            jac = (grad[:, :-1] - grad[:, 1:]).reshape(
                len(vs), sectors - 1, 2 * m
            )  # rows: A_j − A_{j+1}
            gap = area[:, :-1] - area[:, 1:]
            back = (goal - fan).reshape(len(vs), 2 * m)
            normal_matrix = jac @ jac.transpose(0, 2, 1)
            normal_matrix += (
                1e-14
                * np.trace(normal_matrix, axis1=1, axis2=2)[:, None, None]
                * np.eye(sectors - 1)
            )
            rhs = np.einsum("gcz,gz->gc", jac, back) + gap
            multiplier = np.linalg.solve(normal_matrix, rhs[..., None])[..., 0]
            fan = fan + (back - np.einsum("gcz,gc->gz", jac, multiplier)).reshape(len(vs), m, 2)
        area = _sector_areas(fan, j, nxt)
        length = np.linalg.norm(fan, axis=-1)
        turn = area / np.maximum(length[:, j] * length[:, nxt], 1e-300)
        good = (
            np.abs(area - area.mean(axis=1, keepdims=True))
            <= EQUAL_AREA_RTOL * np.abs(area).mean(axis=1, keepdims=True)
        ).all(axis=1) & (turn >= EQUAL_AREA_SINE).all(axis=1)
        tangents = fan[..., :1] * e1[:, None] + fan[..., 1:] * e2[:, None]  # (g, m, 3)
        lam = _dot(np.roll(tangents, 1, axis=1) + np.roll(tangents, -1, axis=1), tangents) / _dot(
            tangents, tangents
        )
        shrink = _length_shrink(
            targets,
            tangents.reshape(-1, 3),
            wanted.reshape(-1, 3),
            slots.reshape(-1),
            np.repeat(vs, m),
            np.repeat(np.arange(len(vs)), m),
            len(vs),
        )
        keep = np.flatnonzero(good)
        star[slots[keep]] = tangents[keep] * shrink[keep, None, None]
        inner = (
            slice(1, m - 1) if is_open else slice(0, m)
        )  # a boundary fan's rim slots have no relation
        cosine[slots[keep, inner]] = 0.5 * lam[keep, inner]
        factor[vs[keep]] = shrink[keep]
    return SplitStar(star, cosine, base.refitted, factor < 1.0, factor)


def _star_kernel(
    normals: FloatArray,
    wanted: FloatArray,
    positions: FloatArray,
    offsets: IntArray,
    neighbors: IntArray,
    face_count: IntArray,
    valence: IntArray,
    boundary: NDArray[np.bool_],
    limit: float,
    star: FloatArray,
    valid: NDArray[np.bool_],
    factor: FloatArray,
    lo: int,
    hi: int,
) -> None:
    """:func:`~g1patch.targets.interpolate.fit_regular_star` and :func:`split4_star`'s length
    safeguard for vertices ``lo:hi``: ``[a b] = Σ_j s_j [cos θ_j, sin θ_j] G⁻¹``, ``t_j = a cos θ_j
    + b sin θ_j`` (a boundary corner keeps ``s``), valid where ``(a × b)·n > 1e-12 (|a|² + |b|²)``;
    then the star scaled by ``min(1, 1 / max_j |t_j| / allowed_j)``, ``allowed = limit · min(|s|,
    2|d|²/(|d| + |P d|))``."""
    width = 1
    for v in range(lo, hi):
        width = max(width, offsets[v + 1] - offsets[v])
    cos, sin = np.empty(width), np.empty(width)
    a, b = np.empty(3), np.empty(3)
    for v in range(lo, hi):
        start, stop = offsets[v], offsets[v + 1]
        step = np.pi / face_count[v] if boundary[v] else 2.0 * np.pi / valence[v]
        corner = boundary[v] and face_count[v] == 1
        a[:] = 0.0
        b[:] = 0.0
        for s in range(start, stop):
            theta = (s - start) * step
            cos[s - start], sin[s - start] = np.cos(theta), np.sin(theta)
            for d in range(3):
                a[d] += cos[s - start] * wanted[s, d]
                b[d] += sin[s - start] * wanted[s, d]
        half = 0.5 * (face_count[v] if boundary[v] else valence[v])
        a /= half + 1.0 if boundary[v] else half
        b /= 1.0 if corner else half
        n = normals[v]
        area = (
            (a[1] * b[2] - a[2] * b[1]) * n[0]
            + (a[2] * b[0] - a[0] * b[2]) * n[1]
            + (a[0] * b[1] - a[1] * b[0]) * n[2]
        )
        valid[v] = corner or area > 1e-12 * (
            (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]) + (b[0] * b[0] + b[1] * b[1] + b[2] * b[2])
        )
        worst = 0.0
        for s in range(start, stop):
            for d in range(3):
                star[s, d] = (
                    wanted[s, d] if corner else a[d] * cos[s - start] + b[d] * sin[s - start]
                )
            e = positions[neighbors[s]] - positions[v]
            chord = np.sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2])
            along = e[0] * n[0] + e[1] * n[1] + e[2] * n[2]
            p0, p1, p2 = e[0] - along * n[0], e[1] - along * n[1], e[2] - along * n[2]
            in_plane = np.sqrt(p0 * p0 + p1 * p1 + p2 * p2)
            arc = 2.0 * chord**2 / (chord + in_plane if chord > 0 else 1.0)
            length = np.sqrt(
                wanted[s, 0] * wanted[s, 0]
                + wanted[s, 1] * wanted[s, 1]
                + wanted[s, 2] * wanted[s, 2]
            )
            allowed = limit * min(length, arc)
            ratio = np.sqrt(
                star[s, 0] * star[s, 0] + star[s, 1] * star[s, 1] + star[s, 2] * star[s, 2]
            ) / (allowed if allowed > 0 else np.inf)
            if ratio > worst or np.isnan(ratio):
                worst = ratio
        shrink = min(1.0, 1.0 / (worst if worst > 0 else 1.0))
        factor[v] = shrink
        for s in range(start, stop):
            for d in range(3):
                star[s, d] *= shrink
