"""Semi-sharp meshes: the limit masks hold once no sharpness is fractional, so the limit at the
vertices a semi-sharp feature reaches is taken on the decayed refinement of their neighbourhood
(:mod:`g1patch.subdivision`): which vertices, which faces, that neighbourhood as a level of its
own, and its refinement until the sharpness has decayed.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ..errors import MeshError
from ..mesh import INFINITE_SHARPNESS, QuadTopology
from .features import _effective, _Level
from .refine import _step

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]
BoolArray = NDArray[np.bool_]


def _affected(level: _Level) -> BoolArray:
    """Vertices whose limit sees a semi-sharp feature: a semi-sharp vertex, or an incident
    semi-sharp edge."""
    semi_edge = (level.edge > 0) & (level.edge < INFINITE_SHARPNESS)
    out = (level.vertex > 0) & (level.vertex < INFINITE_SHARPNESS)
    out[level.topology.edges[semi_edge].ravel()] = True
    return out


def _sublevel(level: _Level, faces: BoolArray) -> tuple[_Level, IntArray]:
    """The faces as a level of their own (vertices renumbered in order), and the new index of every
    vertex (-1 outside)."""
    topology = level.topology
    kept = topology.faces[faces]
    used = np.zeros(topology.n_vertices, dtype=bool)
    used[kept] = True
    index = np.cumsum(used) - 1
    index[~used] = -1
    sub = QuadTopology.from_faces(index[kept], int(used.sum()))
    original = np.flatnonzero(used)
    keys = topology.edges[:, 0] * topology.n_vertices + topology.edges[:, 1]
    sub_keys = original[sub.edges[:, 0]] * topology.n_vertices + original[sub.edges[:, 1]]
    edge, vertex = _effective(
        sub, level.edge[np.searchsorted(keys, sub_keys)], level.vertex[original], level.mode
    )
    return _Level(
        level.x[original], sub, edge, vertex, level.holes[faces], level.mode, level.chaikin
    ), index


def _neighbourhood(level: _Level, vertices: BoolArray, rings: int) -> BoolArray:
    """Faces within ``rings`` vertex rings of ``vertices`` (1: the faces at them)."""
    faces = level.topology.faces
    touched = vertices.copy()
    keep = np.any(touched[faces], axis=1)
    for _ in range(rings - 1):
        touched = np.zeros_like(touched)
        touched[faces[keep]] = True
        keep = np.any(touched[faces], axis=1)
    return keep


def _decayed(level: _Level) -> tuple[_Level, int]:
    """Refined until no fractional sharpness is left (at most ⌈max s⌉ ≤ 10 steps), and the steps
    taken."""
    steps = 0
    while level.semi_sharp:
        level = _step(level)
        steps += 1
    return level, steps


def _decayed_neighbourhood(level: _Level) -> tuple[_Level, IntArray, int, IntArray]:
    """The decayed refinement of the neighbourhood of the vertices a semi-sharp feature reaches
    (:func:`_affected`), the index in it of every vertex of ``level`` (-1 outside), the steps
    taken, and those vertices. Where cutting the neighbourhood out leaves a vertex with two fans,
    a ring more is taken, at last the whole level."""
    affected = _affected(level)
    # the limit of v reads its 1-ring and the sharpness at v; with Chaikin also that at its
    # neighbours
    rings = 2 if level.chaikin else 1
    sub, index = level, np.arange(level.topology.n_vertices)
    for extra in range(3):
        faces = _neighbourhood(level, affected, rings + extra)
        if faces.all():
            break
        try:
            sub, index = _sublevel(level, faces)
            break
        except MeshError:  # the cut leaves a vertex with two fans: take a ring more, at last all
            sub, index = level, np.arange(level.topology.n_vertices)
    fine, steps = _decayed(sub)
    return fine, index, steps, np.flatnonzero(affected)
