"""Interior targets of the face corners: the twist, and the circle-section fit of coarse faces.

* :func:`_interior_targets`: at corner A of face (A, B, C, D) with B next and D previous,
  ``Ft = A + (t_AB + t_AD)/3 + [P_A w + II_A(t_AB, t_AD) N_A]/9``, ``w = A − B + C − D``: the
  bilinear twist with its normal part replaced by the estimated second fundamental form (without
  a shape operator, the bilinear twist alone);
* :func:`_round_coarse_faces`: faces whose corner normals turn far take interior points fitted to
  circle sections across the face, where a sphere models the face's corners.

Parts of the ``interpolate`` rule (:mod:`g1patch.targets.interpolate`); ``legacy`` uses the
bilinear twist.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ..kernels import in_chunks, jit_kernel, use_kernels
from ..mesh import QuadMesh, QuadTopology
from .local import dot, slot_tables, unit_rows
from .value import halfedge_slots

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

_NEXT = np.array([1, 2, 3, 0])
_PREV = np.array([3, 0, 1, 2])

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
    compiled = use_kernels(compiled)  # NumPy where kernels cannot be cached
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
        normal = dot(w, n)
        planar = np.sqrt(np.maximum(dot(w, w) - normal**2, 0.0))
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


def _normal_along(tangent: FloatArray, n0: FloatArray, n1: FloatArray, t: FloatArray) -> FloatArray:
    """The normal ``(1 − t) n0 + t n1`` made ⊥ the unit ``tangent`` and unit."""
    n = (1.0 - t)[..., None] * n0 + t[..., None] * n1
    tangent = unit_rows(tangent)
    return unit_rows(n - dot(n, tangent)[..., None] * tangent)


def _circle_section(
    p: FloatArray, q: FloatArray, n_p: FloatArray, n_q: FloatArray, s: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """Point and normal at ``s`` of the circle-aware Hermite cubic from p to q (tangents: q − p
    projected onto each end's plane, length ``2|d|²/(|d| + |s|)``), the normal blended along it."""
    d = q - p
    chord = np.linalg.norm(d, axis=-1)

    def tangent(direction: FloatArray, n: FloatArray) -> FloatArray:
        projected = direction - dot(direction, n)[..., None] * n
        length = np.linalg.norm(projected, axis=-1)
        return (
            projected
            * (2.0 * chord**2 / (chord + length) / np.where(length > 0, length, 1.0))[..., None]
        )

    net = (p, p + tangent(d, n_p) / 3.0, q + tangent(-d, n_q) / 3.0, q)
    b, db = _bernstein(s), _bernstein(s, True)
    point = along = np.zeros(())  # Σ_i from 0, in the order i = 0..3
    for i in range(4):
        point = point + b[..., i, None] * net[i]
        along = along + db[..., i, None] * net[i]
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
    rhs = dot(normals, targets - np.concatenate([known, known], axis=1))
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
    normal = unit_rows(np.cross(p_u, p_v))
    u, v = g[:, None, None], g[None, :, None]
    n = corner_normals[:, :, None, None, :]
    blend = unit_rows(
        (1 - u) * (1 - v) * n[:, 0]
        + u * (1 - v) * n[:, 1]
        + u * v * n[:, 2]
        + (1 - u) * v * n[:, 3]
    )
    return (dot(normal, blend) >= np.cos(_ROUND_MAX_TURN)).all(axis=(1, 2))


def _sphere_misfit(x: FloatArray, n: FloatArray) -> FloatArray:
    """How far a face's corners (F, 4, 3) and normals are from one sphere: ``x_i ≈ c + R n_i`` by
    least squares (``R = Σ (x_i − x̄)·(n_i − n̄) / Σ |n_i − n̄|²``), the RMS residual over the mean
    edge length. 0 on any sphere; 0.05–0.1 with 8 % noise; 0.2–0.4 on a coarse ellipsoid, 0.4–0.8
    on coarse tori, one-ring disks and Spot's legs."""
    xc = x - x.mean(axis=1, keepdims=True)
    nc = n - n.mean(axis=1, keepdims=True)
    spread = dot(nc, nc).sum(axis=1)
    radius = dot(xc, nc).sum(axis=1) / np.where(spread > 0, spread, 1.0)
    residual = xc - radius[:, None, None] * nc
    size = np.linalg.norm(x - x[:, _NEXT], axis=2).mean(axis=1)
    return np.sqrt(dot(residual, residual).mean(axis=1)) / np.where(size > 0, size, 1.0)


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
    turn = edge_turns(n)
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


def edge_turns(corner_normals: FloatArray) -> FloatArray:
    """Per face the largest angle between the corner normals at the ends of an edge,
    ``max_k arccos(clip(n_k·n_{k+1}, −1, 1))``: :func:`_turn_kernel`, or
    its NumPy twin where kernels cannot be cached."""
    if use_kernels(True):
        turn = np.empty(len(corner_normals))
        jit_kernel(_turn_kernel)(corner_normals, turn)
        return turn
    a, b = corner_normals, np.roll(corner_normals, -1, axis=1)
    cosine = a[..., 0] * b[..., 0] + a[..., 1] * b[..., 1] + a[..., 2] * b[..., 2]
    return np.asarray(np.arccos(np.clip(cosine, -1.0, 1.0)).max(axis=1, initial=0.0))


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
