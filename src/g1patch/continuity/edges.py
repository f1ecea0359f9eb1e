"""G0 and G1 along shared edges and at corners, the NumPy reference (``compiled=False``): per
shared edge its largest and smallest G1 angle, where the largest is, and its largest G0 gap; the
largest angle between corner normals within a corner sector. :mod:`.edge_kernels` and
:mod:`.corner_kernels` compute the same in numba kernels."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ..network import HangingEdges, Patches, PatchNetwork, edge_parameters
from ..patches import CORNER_PARAMETERS
from .sampling import _edge_samples, anchors, translated
from .vectors import _angle3, _cross3, _norm3, _planar

#: corner pairs per block of :func:`_max_corner_angle` (a block's arrays: about 100 bytes a pair)
_CORNER_PAIR_BLOCK = 1 << 18


def _edge_measures(
    patches: Patches,
    left_patch: NDArray[np.int64],
    left_edge: NDArray[np.int64],
    right_patch: NDArray[np.int64],
    right_edge: NDArray[np.int64],
    same: NDArray[np.bool_],
    samples: int,
    degenerate_level: float,
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.int64], NDArray[np.float64]]:
    """Max and min G1 angle (deg; the min over non-degenerate samples, inf without any), the
    sample index where the max is reached, and max G0 gap (absolute) along each given shared edge.

    Side R runs along the edge in its own counter-clockwise direction, so it is sampled at the
    reversed parameters (exactly ``t[::-1]``) unless both sides run the same way; then its
    normal is flipped, as its patch is oriented the other way.
    """
    t = np.linspace(0.0, 1.0, samples)
    origin = anchors(patches, left_patch)
    point_left, normal_left = _edge_samples(
        patches, left_patch, left_edge, np.zeros(len(same), dtype=bool), t, origin
    )
    point_right, normal_right = _edge_samples(patches, right_patch, right_edge, ~same, t, origin)
    if same.any():
        normal_right[:, same] *= -1.0
    return _side_figures(point_left, normal_left, point_right, normal_right, degenerate_level)


def _side_figures(
    point_left: NDArray[np.float64],
    normal_left: NDArray[np.float64],
    point_right: NDArray[np.float64],
    normal_right: NDArray[np.float64],
    degenerate_level: float,
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.int64], NDArray[np.float64]]:
    """Per edge, from both sides' points and normals at the same samples (planar (3, E, K)):
    max and min G1 angle, where the max is, and max G0 gap (``point_left`` is overwritten)."""
    usable = (_norm3(normal_left) > degenerate_level) & (_norm3(normal_right) > degenerate_level)
    angles = np.where(usable, _angle3(normal_left, normal_right), 0.0)
    point_left -= point_right
    gaps = _norm3(point_left)
    worst = angles.argmax(axis=1) if angles.size else np.zeros(angles.shape[0], dtype=np.int64)
    least = np.where(usable, angles, np.inf).min(axis=1, initial=np.inf)
    return (
        np.take_along_axis(angles, worst[:, None], axis=1)[:, 0],
        least,
        worst,
        gaps.max(axis=1, initial=0.0),
    )


def _max_corner_angle(
    network: PatchNetwork, patches: Patches, degenerate_level: float, oriented: bool
) -> float:
    """Largest angle between the corner normals of any two patches meeting at one point in one
    sector (:meth:`PatchNetwork.corner_sectors`: patches across a seam may differ).

    Corners are grouped by their sector and the groups by size; the pairwise angles of the
    sectors with m corners are computed in (groups, rows, m) blocks of at most
    :data:`_CORNER_PAIR_BLOCK` pairs (a block of rows of one sector when m² is larger), so memory
    stays linear in the valence: a 10 000-valent vertex's 10⁸ pairs asked for 6 GB in one array.
    Every pair's angle is the same operations on the same two normals as in one array. The
    normals are taken with each patch's points less its first (:func:`.sampling.anchors`).
    """
    own = translated(patches, anchors(patches, np.arange(len(patches))))  # own precision
    normals = _cross3(
        _planar(own.evaluate(CORNER_PARAMETERS, 1, 0)),
        _planar(own.evaluate(CORNER_PARAMETERS, 0, 1)),
    )
    normals = normals.reshape(3, -1)
    usable = _norm3(normals) > degenerate_level
    ids = network.corner_sectors().reshape(-1)[usable]
    normals = normals[:, usable].T
    if not len(ids):
        return 0.0
    order = np.argsort(ids, kind="stable")
    ids, normals = ids[order], normals[order]
    starts = np.flatnonzero(np.r_[True, ids[1:] != ids[:-1]])
    sizes = np.diff(np.r_[starts, len(ids)])
    worst = 0.0
    for size in np.unique(sizes[sizes > 1]):
        group_starts = starts[sizes == size]
        groups_per_block = max(1, _CORNER_PAIR_BLOCK // (size * size))
        rows_per_block = size if groups_per_block > 1 else max(1, _CORNER_PAIR_BLOCK // size)
        for first in range(0, len(group_starts), groups_per_block):
            group = normals[
                group_starts[first : first + groups_per_block, None] + np.arange(size)
            ]  # (g, m, 3)
            for row in range(0, size, rows_per_block):
                rows = np.ascontiguousarray(group[:, row : row + rows_per_block])  # (g, rows, 3)
                cross = np.linalg.norm(np.cross(rows[:, :, None], group[:, None, :]), axis=-1)
                dot = np.einsum("gid,gjd->gij", rows, group)
                if not oriented:
                    dot = np.abs(dot)
                worst = max(worst, float(np.degrees(np.arctan2(cross, dot)).max()))
    return worst


def _hanging_measures(
    patches: Patches,
    hanging: HangingEdges,
    samples: int,
    degenerate_level: float,
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.int64], NDArray[np.float64]]:
    """:func:`_edge_measures` along hanging edges: each fine edge at ``samples`` fractions against
    the coarse edge at the same points (:meth:`HangingEdges.coarse_parameters`)."""
    t = np.linspace(0.0, 1.0, samples)
    fine_patch, fine_edge, coarse_patch, coarse_edge = hanging.sides.T
    origin = anchors(patches, fine_patch)
    point_fine, normal_fine = _edge_samples(
        patches, fine_patch, fine_edge, np.zeros(len(hanging), dtype=bool), t, origin
    )
    uv = edge_parameters(coarse_edge[:, None], hanging.coarse_parameters(t))  # (H, K, 2)
    coarse = translated(patches.take(coarse_patch), origin)
    point_coarse = _planar(coarse.evaluate(uv))  # each patch at its own parameters
    normal_coarse = _cross3(_planar(coarse.evaluate(uv, 1, 0)), _planar(coarse.evaluate(uv, 0, 1)))
    return _side_figures(point_fine, normal_fine, point_coarse, normal_coarse, degenerate_level)
