"""Which patches fold, and where: :func:`folded_patches` (the grid test alone, for a builder's fold
guard) and the check's fold locations: the worst sample of folded edges (G1 angle above 90°) and
the first location of each folded patch."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ..network import Patches, edge_parameters
from .grid import DEGENERATE_RTOL, FOLD_SAMPLES, MAX_FOLD_LOCATIONS, _grid_measures


def folded_patches(
    patches: Patches,
    samples: int = 9,
    degenerate_rtol: float = DEGENERATE_RTOL,
    *,
    compiled: bool | None = None,
) -> NDArray[np.bool_]:
    """Which patches fold (the intrinsic test of :func:`check`) on a ``samples²`` grid, (N,) bool.

    For a builder's fold guard: no network needed, patches in any coordinates. ``compiled``: the
    grid kernel (False: the NumPy reference; None: as :func:`check`).
    """
    return _grid_measures(patches, samples, degenerate_rtol, fairness=False, compiled=compiled)[
        0
    ].folded


def folds_and_bend(
    patches: Patches,
    samples: int = FOLD_SAMPLES,
    *,
    diagonal: float | None = None,
    compiled: bool | None = None,
) -> tuple[NDArray[np.bool_], int, float]:
    """Which patches fold, (N,) bool, how many grid samples have a degenerate normal, and the 99th
    percentile of the normal turn between neighbouring samples (degrees), on the ``samples²`` grid
    of :func:`check`: for a builder that compares attempts as the check would measure them.
    ``diagonal``: the whole network's bounding-box diagonal where ``patches`` are some of it (the
    degenerate normals' level is relative to it)."""
    grid, diagonal = _grid_measures(
        patches, samples, DEGENERATE_RTOL, compiled=compiled, diagonal=diagonal
    )
    return grid.folded, grid.degenerate, grid.fairness(diagonal)["turn_p99_deg"]


def _edge_fold_locations(
    sides: tuple[
        NDArray[np.int64],
        NDArray[np.int64],
        NDArray[np.int64],
        NDArray[np.int64],
        NDArray[np.bool_],
    ],
    folded_edges: NDArray[np.int64],
    worst: NDArray[np.int64],
    samples: int,
) -> list[tuple[int, float, float]]:
    """(patch, u, v) of the worst sample of the given folded edges on both sides, for the first
    :data:`MAX_FOLD_LOCATIONS` patches (side R is sampled at ``t[::-1]`` unless ``same``)."""
    left_patch, left_edge, right_patch, right_edge, same = (side[folded_edges] for side in sides)
    index = worst[folded_edges]
    t = np.linspace(0.0, 1.0, samples)
    patch = np.concatenate([left_patch, right_patch])
    edge = np.concatenate([left_edge, right_edge])
    parameter = np.concatenate([t[index], t[np.where(same, index, samples - 1 - index)]])
    _, first = np.unique(patch, return_index=True)
    first = first[:MAX_FOLD_LOCATIONS]
    uv = edge_parameters(edge[first], parameter[first])
    return [(int(p), float(u), float(v)) for p, (u, v) in zip(patch[first], uv, strict=True)]


def _first_per_patch(locations: list[tuple[int, float, float]]) -> list[tuple[int, float, float]]:
    """The lowest location of each patch, for the first :data:`MAX_FOLD_LOCATIONS` patches."""
    first: dict[int, tuple[int, float, float]] = {}
    for location in sorted(locations):
        first.setdefault(location[0], location)
    return list(first.values())[:MAX_FOLD_LOCATIONS]
