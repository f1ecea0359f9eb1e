"""What the check samples, and the size it measures against: argument checks, the patches in their
local coordinates, their corner points and bounding-box diagonals (local and world), blocks of
work, and the points and normals along patch edges."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ..errors import InputError
from ..gregory import GregoryPatchSet
from ..network import Patches, PatchNetwork, edge_parameters
from ..patches import CORNER_PARAMETERS
from .vectors import _cross3, _planar


def _check_count(name: str, value: object, least: int) -> None:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < least:
        raise InputError(f"{name}: expected an integer ≥ {least}, got {value!r}")


def _local(patches: Patches) -> Patches:
    """The patches in their local coordinates (frame-free), or the patches when they have no
    frame."""
    return patches.local() if hasattr(patches, "local") else patches


def _diagonal(points: NDArray[np.float64]) -> float:
    """Length of the diagonal of the bounding box of ``points`` (..., 3) (each coordinate's extremes
    over its strided column: NumPy reduces ``axis=0`` of ``(M, 3)`` 3 values at a time, 20×
    slower)."""
    flat = points.reshape(-1, 3)
    if not len(flat):
        return 0.0
    extent = np.array([flat[:, d].max() - flat[:, d].min() for d in range(3)])
    return float(np.linalg.norm(extent))


def _corner_points(patches: Patches) -> NDArray[np.float64]:
    """``patches.evaluate(CORNER_PARAMETERS)``, ``(N, 4, 3)``: a Gregory patch's corners are its
    points 0–3 (weights 1 and 0, so the evaluation returns them exactly)."""
    if isinstance(patches, GregoryPatchSet) and patches.frame is None:
        return np.ascontiguousarray(patches.points[:, :4])
    return patches.evaluate(CORNER_PARAMETERS)


def _world_diagonal(network: PatchNetwork, corners: NDArray[np.float64]) -> float:
    """:meth:`PatchNetwork.bounding_box_diagonal` from the local ``corners`` of its patches (the
    same ``c + s x`` that the patches' world evaluation applies)."""
    patches = network.patches
    if isinstance(patches, GregoryPatchSet) and patches.frame is not None:
        return _diagonal(patches.frame.to_world(corners))
    return network.bounding_box_diagonal()


def _world_extent_diagonal(
    network: PatchNetwork, low: NDArray[np.float64], high: NDArray[np.float64]
) -> float:
    """:func:`_world_diagonal` from the local corners' box ``low``, ``high``: ``c + s x`` is
    monotone in each coordinate (both roundings are), so the world corners' extremes are the images
    of the local ones, exactly."""
    patches = network.patches
    if isinstance(patches, GregoryPatchSet) and patches.frame is not None:
        ends = patches.frame.to_world(np.stack([low, high]))
        return float(np.linalg.norm(ends.max(axis=0) - ends.min(axis=0)))
    return network.bounding_box_diagonal()


def _blocks(count: int, size: int) -> list[slice]:
    return [slice(start, min(start + size, count)) for start in range(0, count, size)]


def _edge_samples(
    patches: Patches,
    patch_ids: NDArray[np.int64],
    edges: NDArray[np.int64],
    backwards: NDArray[np.bool_],
    t: NDArray[np.float64],
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Points and normals ``p_u × p_v`` at ``t`` along the given patch edges, each planar ``(3, E,
    K)``.

    Edge k is run counter-clockwise, or from its far end where ``backwards``. The eight
    (edge, direction) groups share their parameters, so each group is one batched product.
    """
    points = np.empty((3, len(patch_ids), len(t)))
    normals = np.empty_like(points)
    for edge in range(4):
        for reverse in (False, True):
            rows = np.flatnonzero((edges == edge) & (backwards == reverse))
            if len(rows):
                uv = edge_parameters(np.asarray(edge, dtype=np.int64), t[::-1] if reverse else t)
                group = patches.take(patch_ids[rows])
                points[:, rows] = np.moveaxis(group.evaluate(uv), -1, 0)
                normals[:, rows] = _cross3(
                    _planar(group.evaluate(uv, 1, 0)), _planar(group.evaluate(uv, 0, 1))
                )
    return points, normals
