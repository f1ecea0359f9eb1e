"""The macro net of a quad: its four bicubic sub-patches as one 7×7 net, and what split4's
assembly takes over from it.

Sub-patch ``4 f + k`` sits at corner k of face f, its own 4×4 Bézier net in the frame of corner k
(:data:`_LOCAL`); the four join C1, so the macro net minus its row and column 3 is one bicubic
B-spline patch (knots :data:`BSPLINE_KNOTS`, :func:`bspline_nets`). :func:`target_nets` is the
targets' own bicubic per face, and :func:`_own_quantities` reads off a face's macro net the detail
the free choices follow (:data:`_QUANTITIES`; :mod:`g1patch.construct.split4`, "Shape").
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ...errors import InputError
from ...gregory import INTERIOR_INDEX
from ...network import PatchNetwork
from ...patches import PatchSet
from ...targets import Targets, halfedge_slots

__all__ = ["BSPLINE_KNOTS", "bspline_nets", "macro_nets", "target_nets"]

#: knots of each quad's B-spline patch, in u and in v
BSPLINE_KNOTS = np.array([0.0, 0.0, 0.0, 0.0, 0.5, 0.5, 1.0, 1.0, 1.0, 1.0])

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

# Frame of corner k: point (p, q) of the 7×7 macro net, p along edge k, q back along edge k − 1.
# _LOCAL[k, p, q] = (i, j) in sub-patch k's own 4×4 Bézier net, for p, q ∈ 0..3.
_P, _Q = np.meshgrid(np.arange(4), np.arange(4), indexing="ij")
_LOCAL = np.stack(
    [
        np.stack([_P, _Q], -1),
        np.stack([3 - _Q, _P], -1),
        np.stack([3 - _P, 3 - _Q], -1),
        np.stack([_Q, 3 - _P], -1),
    ]
)
#: (s, t)·3: where sub-patch k sits in the 7×7 net
_SUB_ORIGIN = np.array([[0, 0], [3, 0], [3, 3], [0, 3]])


# de Casteljau halving of a cubic at ½: the 7 × 4 matrix from Bézier points to the two halves'
_HALVE = (
    np.array(
        [
            [8.0, 0, 0, 0],
            [4, 4, 0, 0],
            [2, 4, 2, 0],
            [1, 3, 3, 1],
            [0, 2, 4, 2],
            [0, 0, 4, 4],
            [0, 0, 0, 8],
        ]
    )
    / 8.0
)
# What the assembly takes over from a face's macro net (the targets' bicubic subdivided at ½, or a
# guide), per half-edge h = 4f + k in the frame of corner k (points (p, q) of :func:`_macro_index`),
# each as the net's detail over what its own boundary predicts, so that where G1 moves a curve
# point the interior moves with it:
# * the centre over the bilinear Coons centre ``ΣM/2 − ΣV/4``: ``(3,3) − 2 (3,0) + (0,0)`` (its mean
# over k);
# * the cross arm ``b_k − C`` over ``(M_k − M_{k+2})/6``: ``(3,2) − (3,0)/3`` (taken as ``(a_k −
# a_{k+2})/2``);
# * the seam tangent ``3 (e − M)`` at M_k into the face over ``C − M``: ``3 (3,1) − 2 (3,0) −
# (3,3)``;
# * the twist offsets, each twist point minus the parallelogram of its three neighbours, at
#   MID[k] (2,1), MID[k−1] (1,2), C (2,2) and V (1,1).
_CENTRE, _CROSS, _SEAM, _TWIST_MID, _TWIST_PREV, _TWIST_CENTRE, _TWIST_VERTEX = range(7)
_QUANTITIES: tuple[dict[tuple[int, int], float], ...] = (
    {(3, 3): 1.0, (3, 0): -2.0, (0, 0): 1.0},
    {(3, 2): 1.0, (3, 0): -1.0 / 3.0},
    {(3, 1): 3.0, (3, 0): -2.0, (3, 3): -1.0},
    {(2, 1): 1.0, (2, 0): -1.0, (3, 1): -1.0, (3, 0): 1.0},
    {(1, 2): 1.0, (0, 2): -1.0, (1, 3): -1.0, (0, 3): 1.0},
    {(2, 2): 1.0, (3, 2): -1.0, (2, 3): -1.0, (3, 3): 1.0},
    {(1, 1): 1.0, (1, 0): -1.0, (0, 1): -1.0, (0, 0): 1.0},
)


def _macro_index(k: int, p: int, q: int) -> tuple[int, int]:
    """Index (i, j) in the 7×7 macro net of point (p, q) in the frame of corner k (as
    :data:`_LOCAL`, on 0..6)."""
    return [(p, q), (6 - q, p), (6 - p, 6 - q), (q, 6 - p)][k]


def _quantity_weights() -> FloatArray:
    """[k, quantity, 7 i + j]: weights of :data:`_QUANTITIES` over the 7×7 macro net, frame of
    corner k."""
    weights = np.zeros((4, len(_QUANTITIES), 49))
    for k in range(4):
        for c, terms in enumerate(_QUANTITIES):
            for (p, q), weight in terms.items():
                i, j = _macro_index(k, p, q)
                weights[k, c, 7 * i + j] += weight
    return weights


#: [k, quantity, 7 i + j] over the macro net and [k, quantity, 4 i + j] over a bicubic's 4×4 net
#: (its de Casteljau halves at ½ in u and v)
_MACRO_WEIGHTS = _quantity_weights()
_NET_WEIGHTS = _MACRO_WEIGHTS @ np.kron(_HALVE, _HALVE)


def target_nets(targets: Targets) -> FloatArray:
    """The (F, 4, 4, 3) Bézier nets of the targets' own bicubic per face: corners, edge points
    ``x + t/3`` from the slot tangents, interior points :attr:`Targets.corner_interior`
    (``net[i, j]``, i along edge 0, j along edge 3 reversed)."""
    topology = targets.topology
    slot_out, slot_in = halfedge_slots(topology)
    h = 4 * np.arange(topology.n_faces)[:, None] + np.arange(4)
    corner = targets.positions[topology.faces]
    net = np.empty((topology.n_faces, 4, 4, 3))
    net[:, [0, 3, 3, 0], [0, 0, 3, 3]] = corner
    net[:, [1, 3, 2, 0], [0, 1, 3, 2]] = (
        corner + targets.tangents[slot_out[h]] / 3.0
    )  # edge k, next to corner k
    net[:, [2, 3, 1, 0], [0, 2, 3, 1]] = (
        np.roll(corner, -1, axis=1) + targets.tangents[slot_in[h]] / 3.0
    )  # next to k + 1
    net[:, INTERIOR_INDEX[:, 0], INTERIOR_INDEX[:, 1]] = targets.corner_interior
    return net


def _own_quantities(targets: Targets, guide: FloatArray | None) -> FloatArray:
    """Per half-edge h = 4f + k the (4F, 7, 3) :data:`_QUANTITIES` of face f's macro net: the
    ``guide`` (F, 7, 7, 3), or the targets' bicubic (:func:`target_nets`) subdivided at ½."""
    nets, weights = (
        (target_nets(targets).reshape(-1, 16, 3), _NET_WEIGHTS)
        if guide is None
        else (guide.reshape(-1, 49, 3), _MACRO_WEIGHTS)
    )
    return np.matmul(weights.reshape(-1, weights.shape[-1]), nets).reshape(
        -1, len(_QUANTITIES), 3
    )  # (F, 4·7, 3)


def macro_nets(control: FloatArray) -> FloatArray:
    """The (F, 7, 7, 3) macro nets of sub-patch controls (4F, 4, 4, 3) (sub-patch 4f+k at corner
    k)."""
    sub = control.reshape(-1, 4, 4, 4, 3)
    nets = np.empty((sub.shape[0], 7, 7, 3))
    for k, (a, b) in enumerate(_SUB_ORIGIN):
        nets[:, a : a + 4, b : b + 4] = sub[:, k]
    return nets


def bspline_nets(source: PatchNetwork | PatchSet) -> FloatArray:
    """Per-quad bicubic B-spline nets (F, 6, 6, 3), knots :data:`BSPLINE_KNOTS` in u and v.

    The macro net minus its row and column 3: those hold exact midpoints of their neighbours
    (the pieces join C1), which is what a double knot at ½ encodes.
    """
    patches = source.patches if isinstance(source, PatchNetwork) else source
    if not isinstance(patches, PatchSet) or patches.form != "bezier" or len(patches) % 4:
        raise InputError(
            "bspline_nets: expected the Bézier sub-patches of a split4 network (4 per quad)"
        )
    keep = np.array([0, 1, 2, 4, 5, 6])
    return np.ascontiguousarray(macro_nets(patches.world_control())[:, keep][:, :, keep])
