"""How far a network built from a control cage lies from the cage's exact Catmull–Clark limit.

The limit is sampled exactly: the cage refined ``levels`` times (:func:`g1patch.subdivision.
refine_grids`, OpenSubdiv's rules, creases and semi-sharp tags included) and every refined
vertex pushed to its limit position by the limit masks (:func:`g1patch.subdivision.
limit_points`), so face f of the cage gets the ``(m + 1)²`` limit points at parameters ``(i/m,
j/m)``, ``m = 2^levels``. Each one is projected onto the network: Gauss–Newton on
``|S(u, v) − L|²`` in the patch that holds the same parameter of the same face (one patch per face,
or the quarter of a ``split4`` face), walking into the neighbouring patch where a step leaves the
unit square, so the foot is found even where the network's parameterisation differs from the
limit's (around extraordinary vertices). The largest foot distance is the figure a build prints
and ``--tolerance`` bounds: the one-sided distance from the limit to the network at dense exact
samples (on the shared OpenSubdiv meshes it agrees with the two-way distance to OpenSubdiv's own
limit within a few per cent, and it is exactly 0 where the network is the limit's bicubic
B-spline).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from .mesh import QuadMesh
from .network import PatchNetwork, edge_parameters
from .subdivision import limit_points, refine_grids

__all__ = ["LimitDistance", "limit_distance", "limit_sample_levels", "project_to_network"]

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

#: refined faces sampled at most (levels drop below :data:`LIMIT_LEVELS` on cages of more than
#: 1,024 faces, never below 1): ≤ ~300 k exact limit points, about a second on Spot (2,928 faces,
#: 9 × 9 points each) where its build takes half that
LIMIT_SAMPLE_FACES = 1 << 18
#: refinement levels of the samples on small cages: 17 × 17 limit points per face
LIMIT_LEVELS = 4
#: Gauss–Newton steps of the projection (quadratic convergence: 2–3 suffice from the same
#: parameter; the rest are for the samples that walk into a neighbour)
PROJECTION_STEPS = 10
#: a parameter step below this ends a sample's projection (the foot is then exact to rounding)
CONVERGED = 1e-12
#: samples projected at once (bounds the per-sample copies of patch points to ~100 MB)
_BLOCK = 1 << 16


@dataclass(frozen=True)
class LimitDistance:
    """The distance from a cage's exact Catmull–Clark limit to a network: ``max`` in model units
    and ``relative`` to the network's bounding-box diagonal, over ``samples`` limit points of
    ``levels`` refinement levels; ``per_face`` the largest per face of the cage it was measured on
    (NaN on hole faces), ``worst_face`` where it is largest."""

    max: float
    relative: float
    samples: int
    levels: int
    per_face: FloatArray
    worst_face: int


def limit_sample_levels(n_faces: int) -> int:
    """Levels of the exact samples: :data:`LIMIT_LEVELS` where the cage is small, fewer so that
    at most about :data:`LIMIT_SAMPLE_FACES` refined faces are sampled, at least 1."""
    levels = LIMIT_LEVELS
    while levels > 1 and n_faces * 4**levels > LIMIT_SAMPLE_FACES:
        levels -= 1
    return levels


def _face_patches(
    n_faces: int, holes: NDArray[np.bool_], patches_per_face: int, network: PatchNetwork
) -> IntArray:
    """The first patch of every face (−1 on hole faces, which have none): faces in order, hole
    faces dropped, ``patches_per_face`` each."""
    if network.n_patches not in (n_faces * patches_per_face, (~holes).sum() * patches_per_face):
        raise ValueError(
            f"the network has {network.n_patches} patches, not {patches_per_face} per face of a "
            f"{n_faces}-face mesh"
        )
    first = np.full(n_faces, -1, dtype=np.int64)
    kept = ~holes if network.n_patches != n_faces * patches_per_face else np.ones(n_faces, bool)
    first[kept] = np.arange(int(kept.sum())) * patches_per_face
    return first


def _start(first: IntArray, uv: FloatArray, patches_per_face: int) -> tuple[IntArray, FloatArray]:
    """The patch holding face parameter ``uv`` and its own parameter there: the face's patch, or
    for ``split4`` the sub-patch k of the quarter at face corner k, which runs the face's
    directions at twice their speed (its corner k at the face's)."""
    if patches_per_face == 1:
        return first, uv
    half = uv >= 0.5
    quarter = np.array([[0, 3], [1, 2]])[half[:, 0].astype(int), half[:, 1].astype(int)]
    local = 2.0 * uv - half
    return first + quarter, local


def project_to_network(
    network: PatchNetwork, points: FloatArray, patch: IntArray, uv: FloatArray
) -> FloatArray:
    """Distance from each point to the network, by Gauss–Newton from parameter ``uv`` of patch
    ``patch``: ``δ = (JᵀJ)⁻¹ Jᵀ (p − S)``, ``J = [S_u S_v]``, shortened to at most one patch (a
    near-singular J at a degenerate corner proposes far jumps); a step that leaves the unit
    square across a shared edge continues from the same place on that edge of the neighbour, one
    that leaves across an open edge stops on it. Returns the smallest distance to a point the
    iteration visited (an upper bound of the true distance, equal to it where the last foot is
    the nearest point; a step that strays, e.g. round a pole of hundreds of slim patches, cannot
    make the figure worse than the start's)."""
    out = np.empty(len(points))
    for start in range(0, len(points), _BLOCK):
        rows = slice(start, min(start + _BLOCK, len(points)))
        out[rows] = _project_block(network, points[rows], patch[rows].copy(), uv[rows].copy())
    return out


def _project_block(
    network: PatchNetwork, points: FloatArray, patch: IntArray, uv: FloatArray
) -> FloatArray:
    patches = network.patches
    active = np.arange(len(points))
    best = np.full(len(points), np.inf)  # every point visited is on the network: keep the nearest
    for _ in range(PROJECTION_STEPS):
        these = patches.take(patch[active])
        at = uv[active, None, :]
        value = these.evaluate(at)[:, 0]
        su, sv = these.evaluate(at, 1, 0)[:, 0], these.evaluate(at, 0, 1)[:, 0]
        r = points[active] - value
        best[active] = np.minimum(best[active], np.linalg.norm(r, axis=1))
        a, b, c = (su * su).sum(1), (su * sv).sum(1), (sv * sv).sum(1)
        gu, gv = (su * r).sum(1), (sv * r).sum(1)
        det = a * c - b * b
        det = np.where(det > 0, det, np.inf)  # a degenerate corner: stay
        step = np.stack([(c * gu - b * gv) / det, (a * gv - b * gu) / det], axis=1)
        longest = np.abs(step).max(axis=1)
        moved = uv[active] + step / np.maximum(longest, 1.0)[:, None]  # ≤ one patch per step
        patch[active], uv[active] = _walk(network, patch[active], moved)
        active = active[longest > CONVERGED]
        if not active.size:
            break
    last = np.linalg.norm(points - patches.take(patch).evaluate(uv[:, None, :])[:, 0], axis=1)
    return np.minimum(best, last)


def _walk(network: PatchNetwork, patch: IntArray, uv: FloatArray) -> tuple[IntArray, FloatArray]:
    """Parameters outside the unit square: onto the neighbour across the edge they left by (the
    farthest-out side), at the same point of that edge; clamped where there is none."""
    below, above = -uv, uv - 1.0
    out = np.maximum(below, above)  # (N, 2): how far out along u and v
    leaving = out.max(axis=1) > 0
    if not leaving.any():
        return patch, uv
    rows = np.flatnonzero(leaving)
    along_u = out[rows, 0] >= out[rows, 1]
    # edge 0: v = 0 (t = u), 1: u = 1 (t = v), 2: v = 1 (t = 1 − u), 3: u = 0 (t = 1 − v)
    edge = np.where(
        along_u,
        np.where(above[rows, 0] > 0, 1, 3),
        np.where(above[rows, 1] > 0, 2, 0),
    )
    clamped = np.clip(uv[rows], 0.0, 1.0)
    t = np.choose(edge, [clamped[:, 0], clamped[:, 1], 1 - clamped[:, 0], 1 - clamped[:, 1]])
    across = network.neighbor[patch[rows], edge]
    patch, uv = patch.copy(), np.clip(uv, 0.0, 1.0)
    moves = across >= 0
    if moves.any():
        source = rows[moves]
        there = network.neighbor_edge[patch[source], edge[moves]]
        same = network.same_direction[patch[source], edge[moves]]
        t_there = np.where(same, t[moves], 1.0 - t[moves])
        patch[source] = across[moves]
        uv[source] = edge_parameters(there, t_there)
    return patch, uv


def limit_distance(
    network: PatchNetwork,
    cage: QuadMesh,
    patches_per_face: int,
    levels: int | None = None,
    only: NDArray[np.bool_] | None = None,
) -> LimitDistance:
    """The distance from the exact Catmull–Clark limit of ``cage`` (world coordinates, the quad
    mesh the network's patches were built on, ``patches_per_face`` each, hole faces without) to
    the network (module docstring); with ``only`` (F,), on those faces alone (NaN elsewhere)."""
    levels = limit_sample_levels(cage.n_faces) if levels is None else int(levels)
    holes = cage.features.holes
    first = _face_patches(cage.n_faces, holes, patches_per_face, network)
    refined, grid = refine_grids(cage, levels)
    limit = limit_points(refined)
    m = grid.shape[1]
    t = np.linspace(0.0, 1.0, m)
    face_uv = np.stack(np.meshgrid(t, t, indexing="ij"), axis=-1).reshape(-1, 2)
    faces = np.flatnonzero((first >= 0) if only is None else (first >= 0) & only)
    face = np.repeat(faces, m * m)
    uv = np.tile(face_uv, (len(faces), 1))
    patch, local = _start(first[face], uv, patches_per_face)
    distance = project_to_network(network, limit[grid[faces].reshape(-1)], patch, local)
    per_face = np.full(cage.n_faces, np.nan)
    per_face[faces] = distance.reshape(len(faces), m * m).max(axis=1)
    worst = int(np.nanargmax(per_face)) if len(faces) else -1
    largest = float(distance.max()) if distance.size else 0.0
    diagonal = network.bounding_box_diagonal()
    return LimitDistance(
        largest,
        largest / diagonal if diagonal > 0 else 0.0,
        int(distance.size),
        levels,
        per_face,
        worst,
    )
