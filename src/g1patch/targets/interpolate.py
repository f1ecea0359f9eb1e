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
      than ``ε = min(2°, ¼ · 360°/n, ½ · ω_A)`` and less than ``180° − ε``, and go once around
      (interior) or less than once (boundary); ``ω_A`` is the narrowest corner the mesh's own
      faces have at A, ``min(θ, 180° − θ)``, between its chords or between their projections onto
      A's plane, whichever is narrower (:func:`~g1patch.targets.fans.mesh_gaps`): the thin
      kites round a 360-valent pole turn 2° and 178° at their spoke vertices, and are kept; so do
      those round a sphere's pole, 0.87° in the plane at valence 360 but 7.5° apart in space.
      Where they do not, ``t = (1 − μ) t_raw + μ t_star`` with the smallest
      ``μ ∈ {1/8, …, 1}`` that passes, t_star the regular star fitted to the raw fan; if
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

The parts live beside this module: :mod:`~g1patch.targets.frames` (normals and shape operators),
:mod:`~g1patch.targets.tangents` (projected tangents, smooth lines, rims),
:mod:`~g1patch.targets.fans` (the safeguard and the regular stars) and
:mod:`~g1patch.targets.interior` (twists, the circle-section fit of coarse faces); this module
composes them.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ..mesh import QuadMesh
from .creases import INTERPOLATE_SHARPNESS, crease_tangents, seam_edges, sharp_vertices
from .fans import fit_regular_star, mesh_gaps, safeguarded_fans, spread_fan, tangent_stars
from .frames import vertex_frames
from .interior import _interior_targets, _round_coarse_faces
from .local import dot, fan_normals, in_vertex_planes, slot_vertices, unit_rows
from .tangents import _along_smooth_lines, _projected_tangents, _smooth_boundary_tangents
from .value import TangentRule, Targets

__all__ = [
    "interpolate_targets",
    "legacy_targets",
    "retreat",
    "retreat_to_star",
    # the fan's parts, importable from here as before (g1patch.targets.fans)
    "fit_regular_star",
    "safeguarded_fans",
    "slot_vertices",
    "spread_fan",
    "tangent_stars",
]

IntArray = NDArray[np.int64]


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


def interpolate_targets(mesh: QuadMesh, *, tangents: TangentRule = "arc") -> Targets:
    """The default interpolating rule (module docstring). ``tangents`` is ignored (the signature of
    a :class:`~g1patch.targets.value.ShapeFunction`): the lengths are always circle-aware."""
    frames = vertex_frames(mesh)
    topology = mesh.topology
    normals = frames.normals
    raw, chord, parallel = _projected_tangents(mesh, normals)
    raw = _along_smooth_lines(mesh, normals, raw, out=raw)
    raw = _smooth_boundary_tangents(mesh, normals, raw)
    slots, guarded = safeguarded_fans(topology, normals, raw, chord, mesh_gaps(mesh, normals))
    slots = in_vertex_planes(slots, normals, topology.neighbor_offsets, out=slots)
    fallback = guarded | frames.repaired | parallel
    seams = seam_edges(mesh, INTERPOLATE_SHARPNESS)
    corner_normals = normals[topology.faces]
    # Targets.interior: the same target for both edges at a corner
    both = np.empty((topology.n_faces, 4, 2, 3))
    first = both[:, :, 0]
    interior = _interior_targets(
        topology, mesh.vertices, slots, normals, frames.shape_operator, out=first
    )
    if seams.any():
        slots, sector_normals, creased, spread = crease_tangents(
            mesh, seams, slots, sharp_vertices(mesh, INTERPOLATE_SHARPNESS)
        )
        at_crease = creased[topology.faces]
        corner_normals = np.where(at_crease[..., None], sector_normals, corner_normals)
        # the bilinear twist: a shape operator fitted across the crease means nothing, and on an
        # extruded side (a box's fillet) it keeps the cross derivative exactly along the extrusion
        bilinear = _interior_targets(topology, mesh.vertices, slots, normals, None)
        interior = np.where(at_crease[..., None], bilinear, interior)
        fallback = (fallback & ~creased) | spread
    rounded = _round_coarse_faces(mesh, slots, corner_normals, interior)
    if seams.any():
        # the circle sections model one sphere through a face's corners: not across a crease
        rounded = np.where(np.any(at_crease, axis=1)[:, None, None], interior, rounded)
    if rounded is not first:
        first[:] = rounded
    both[:, :, 1] = first
    return Targets(
        topology,
        mesh.vertices,
        normals,
        slots,
        both,
        seams,
        fallback,
        "interpolate",
        corner_normals,
    )


def _chosen_uncreased(
    targets: Targets, vertices: IntArray
) -> tuple[NDArray[np.bool_], NDArray[np.bool_]]:
    """``vertices`` as a (V,) mask without the creased ones (more than one sector: they keep
    their sectors' planes), and the creased ones."""
    topology = targets.topology
    chosen = np.zeros(topology.n_vertices, dtype=bool)
    chosen[vertices] = True
    sectored = np.zeros(topology.n_vertices, dtype=bool)
    sectored[
        topology.faces[(targets.corner_normals != targets.normals[topology.faces]).any(axis=2)]
    ] = True
    return chosen & ~sectored, sectored


def retreat(
    targets: Targets,
    fair: Targets,
    vertices: IntArray,
    anchored: NDArray[np.bool_] | None = None,
) -> Targets:
    """``targets`` with ``fair``'s (the same topology) at ``vertices``: their positions, normals,
    slot tangents and the interior targets of every face corner at them. The build's fold guard
    uses it where a patch turns back on itself, with ``fair`` the faired limit-interpolating
    targets there (:func:`~g1patch.targets.limit_interpolate.limit_interpolate_near`): a shape
    rule's choice, not a fallback. ``anchored`` (V,) bool: vertices that keep their positions (take
    the rest). Creased vertices (more than one sector) keep their targets."""
    topology = targets.topology
    chosen, sectored = _chosen_uncreased(targets, vertices)
    moved = chosen if anchored is None else chosen & ~anchored
    positions = np.where(moved[:, None], fair.positions, targets.positions)
    normals = np.where(chosen[:, None], fair.normals, targets.normals)
    rows = chosen[slot_vertices(topology)]
    tangents = np.where(rows[:, None], fair.tangents, targets.tangents)
    corners = chosen[topology.faces]
    interior = np.where(corners[..., None, None], fair.interior, targets.interior)
    corner_normals = _corner_normals(targets, sectored, normals)
    return targets.with_changes(
        positions=positions,
        normals=normals,
        tangents=tangents,
        interior=interior,
        corner_normals=corner_normals,
    )


def _corner_normals(
    targets: Targets, sectored: NDArray[np.bool_], normals: NDArray[np.float64]
) -> NDArray[np.float64]:
    """Each face corner's normal after a retreat: its vertex's new normal, but a creased
    (``sectored``) vertex's corners keep their own sector normals."""
    topology = targets.topology
    return np.where(
        sectored[topology.faces][..., None], targets.corner_normals, normals[topology.faces]
    )


def retreat_to_star(targets: Targets, vertices: IntArray, weight: float) -> Targets:
    """``targets`` moved by ``weight`` ∈ [0, 1] towards the previous release's rule at ``vertices``:
    their normals towards the fan normal, their slot tangents (re-projected) towards the regular
    star fitted to that fan, and the interior targets of every face corner at them towards the
    bilinear twist (no curvature term, no section fit). The build's fold guard uses it where a
    patch still turns back on itself with the faired targets (:func:`retreat`: a pole of many
    thin triangles, whose faired fan folds too); those vertices join ``fallback``. Creased
    vertices (more than one sector) keep their targets."""
    topology = targets.topology
    chosen, sectored = _chosen_uncreased(targets, vertices)
    fan = fan_normals(QuadMesh(targets.positions, topology))
    normals = targets.normals.copy()
    normals[chosen] = unit_rows((1.0 - weight) * normals[chosen] + weight * fan[chosen])
    slot_vertex = slot_vertices(topology)
    n = normals[slot_vertex]
    projected = targets.tangents - dot(targets.tangents, n)[:, None] * n
    star, _, valid = fit_regular_star(topology, normals, projected)
    chosen &= valid
    rows = chosen[slot_vertex]
    tangents = targets.tangents.copy()
    tangents[rows] = (1.0 - weight) * projected[rows] + weight * star[rows]
    bilinear = _interior_targets(topology, targets.positions, tangents, normals, None)
    corners = chosen[topology.faces]
    interior = targets.interior.copy()
    interior[corners] = (1.0 - weight) * interior[corners] + weight * bilinear[corners][:, None, :]
    corner_normals = _corner_normals(targets, sectored, normals)
    return targets.with_changes(
        normals=normals,
        tangents=tangents,
        interior=interior,
        fallback=targets.fallback | chosen,
        corner_normals=corner_normals,
    )
