"""What the check samples, and the size it measures against: argument checks, the patches in their
local coordinates, their corner points and bounding-box diagonals (local and world), blocks of
work, and the points and normals along patch edges."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ..errors import InputError
from ..gregory import GregoryPatchSet
from ..memory import memory_budget
from ..network import Patches, PatchNetwork, edge_parameters
from ..patches import CORNER_PARAMETERS, PatchSet
from .vectors import _cross3, _planar


def _check_count(name: str, value: object, least: int) -> None:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < least:
        raise InputError(f"{name}: expected an integer ≥ {least}, got {value!r}")


#: bytes the check holds per sample of one edge (both sides' points, derivatives, normals and
#: their temporaries), and per sample of one patch's grid
SAMPLE_BYTES = 512


def _check_sample_memory(samples: int, fold_samples: int, edges: int, chunk: int) -> None:
    """Refuse (:class:`InputError`) ``samples`` per edge whose block of ``min(edges, chunk)``
    edges, or a ``fold_samples²`` grid of one patch, would need more than the memory budget."""
    budget = memory_budget()
    lanes = max(1, min(edges, chunk))
    most = max(2, budget // (lanes * SAMPLE_BYTES))
    if samples > most:
        raise InputError(
            f"samples: expected 2 to {most:,} samples per edge ({lanes:,} edges at a time within "
            f"the memory budget of {budget / 1e9:.3g} GB, half the RAM), got {samples:,}"
        )
    most = max(2, int((budget // SAMPLE_BYTES) ** 0.5))
    if fold_samples > most:
        raise InputError(
            f"fold_samples: expected 2 to {most:,} samples per patch side (within the memory "
            f"budget of {budget / 1e9:.3g} GB, half the RAM), got {fold_samples:,}"
        )


def _local(patches: Patches) -> Patches:
    """The patches in their local coordinates (frame-free), or the patches when they have no
    frame."""
    return patches.local() if hasattr(patches, "local") else patches


def _box(points: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Lowest and highest coordinates of ``points`` (..., 3), zeros for no points (each
    coordinate's extremes over its strided column: NumPy reduces ``axis=0`` of ``(M, 3)`` 3 values
    at a time, 20× slower)."""
    flat = points.reshape(-1, 3)
    if not len(flat):
        return np.zeros(3), np.zeros(3)
    return (
        np.array([flat[:, d].min() for d in range(3)]),
        np.array([flat[:, d].max() for d in range(3)]),
    )


def _diagonal(points: NDArray[np.float64]) -> float:
    """Length of the diagonal of the bounding box of ``points`` (..., 3), ``|max − min|``."""
    low, high = _box(points)
    return float(np.linalg.norm(high - low))


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


def position_entries(form: str, count: int) -> NDArray[np.bool_]:
    """Which of a patch's ``count`` points in ``form`` are positions, which a translation moves:
    all but a Hermite patch's derivative and twist entries (its control ``[:2, :2]``, flat
    entries 0, 1, 4, 5, are its corners)."""
    entry = np.arange(count)
    if form == "hermite":
        return (entry % 4 < 2) & (entry // 4 < 2)
    return np.ones(count, dtype=bool)


def anchors(patches: Patches, patch_ids: NDArray[np.int64]) -> NDArray[np.float64]:
    """The first control point of each given patch (E, 3): a point of the patch's own size, which
    the edge measures subtract from both sides' points (:func:`translated`) so that the
    derivatives keep the patch's own precision (taken from coordinates of the model's size, a
    patch 1/7000 of its diagonal and 2° skew measured 1e-8° off G1 where it is exact)."""
    if isinstance(patches, GregoryPatchSet):
        return np.asarray(patches.points[patch_ids, 0], dtype=np.float64)
    assert isinstance(patches, PatchSet)
    return np.asarray(patches.control[patch_ids, 0, 0], dtype=np.float64)


def translated(patches: Patches, offset: NDArray[np.float64]) -> Patches:
    """Frame-free ``patches`` with each one's positions (:func:`position_entries`) less its row
    of ``offset`` (N, 3)."""
    if isinstance(patches, GregoryPatchSet):
        return GregoryPatchSet(patches.points - offset[:, None])
    assert isinstance(patches, PatchSet)
    moved = position_entries(patches.form, 16).reshape(4, 4)
    control = patches.control - np.where(moved[..., None], offset[:, None, None], 0.0)
    return PatchSet(control, patches.form)


def _edge_samples(
    patches: Patches,
    patch_ids: NDArray[np.int64],
    edges: NDArray[np.int64],
    backwards: NDArray[np.bool_],
    t: NDArray[np.float64],
    origin: NDArray[np.float64],
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Points less ``origin`` (one point per edge, (E, 3)) and normals ``p_u × p_v`` at ``t``
    along the given patch edges, each planar ``(3, E, K)``.

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
                group = translated(patches.take(patch_ids[rows]), origin[rows])
                points[:, rows] = np.moveaxis(group.evaluate(uv), -1, 0)
                normals[:, rows] = _cross3(
                    _planar(group.evaluate(uv, 1, 0)), _planar(group.evaluate(uv, 0, 1))
                )
    return points, normals
