"""Integral geometry of patch networks: the enclosed volume, by the divergence theorem.

For a closed, consistently oriented surface (normals ``p_u × p_v`` pointing outwards)

    V = 1/3 ∮ (p − c) · n dA = 1/3 Σ_patches ∫₀¹∫₀¹ (p − c) · (p_u × p_v) du dv

for any point ``c`` (``∮ n dA = 0`` on a closed surface); ``c`` is the centre of the bounding box,
which keeps the integrand free of cancellation for a model far from the origin. On an open
network the value is the signed volume of the cone from ``c`` over the surface.

The integral is Gauss–Legendre quadrature, G points per direction, exact for degree 2G − 1.
For a bicubic patch p has degree 3 and p_u × p_v degree 5 in each direction, so the integrand
has degree 8 ≤ 9 and G = 5 is exact. Patches with a frame ``(c_f, s)`` (:mod:`g1patch.frame`) are
integrated in their local coordinates and the volume scaled by ``s³`` (the world volume, without
the cancellation of world coordinates far from the origin). Other patches (rational Gregory patches,
any object with ``evaluate_grid`` and ``__len__``) double G from 8 until two estimates agree to
``rtol``.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from .errors import InputError
from .frame import Frame
from .network import Patches, PatchNetwork
from .patches import CORNER_PARAMETERS, PatchSet

__all__ = ["VolumeEstimate", "network_volume", "volume_estimate", "grid_row_chunks"]

#: Gauss–Legendre points per direction that integrate a bicubic patch's volume term exactly.
BICUBIC_POINTS = 5

#: Grid evaluations are split into row blocks of about this many points per patch set.
GRID_BUDGET = 1 << 22


@dataclass(frozen=True)
class VolumeEstimate:
    """An enclosed volume, the quadrature that gave it and how far it had settled."""

    volume: float
    #: Gauss–Legendre points per direction of the last estimate
    points: int
    #: |V_G − V_{G/2}| of the last doubling; 0.0 when the quadrature is exact (polynomial patches)
    change: float
    exact: bool

    def __float__(self) -> float:
        return self.volume


def grid_row_chunks(
    n_patches: int, n_rows: int, n_columns: int, budget: int = GRID_BUDGET
) -> Iterator[slice]:
    """Row slices such that ``n_patches × rows × n_columns`` stays near ``budget`` points."""
    rows = max(1, budget // max(1, n_patches * n_columns))
    for start in range(0, n_rows, rows):
        yield slice(start, min(start + rows, n_rows))


def _patches_of(surface: PatchNetwork | Patches) -> Patches:
    patches = surface.patches if isinstance(surface, PatchNetwork) else surface
    if not (hasattr(patches, "evaluate_grid") and hasattr(patches, "__len__")):
        raise InputError(
            "network: expected a PatchNetwork or patches with evaluate_grid, got "
            f"{type(surface).__name__}"
        )
    return patches


def _centre(patches: Patches) -> NDArray[np.float64]:
    corners = patches.evaluate(CORNER_PARAMETERS).reshape(-1, 3)
    return 0.5 * (corners.min(axis=0) + corners.max(axis=0))


def _quadrature(patches: Patches, points: int, centre: NDArray[np.float64]) -> float:
    """``1/3 Σ_ab w_a w_b (p − c) · (p_u × p_v)`` at ``points × points`` Gauss–Legendre nodes."""
    nodes, weights = np.polynomial.legendre.leggauss(points)
    nodes, weights = 0.5 * (nodes + 1.0), 0.5 * weights  # [−1, 1] → [0, 1]
    total = 0.0
    for rows in grid_row_chunks(len(patches), points, points):
        p = patches.evaluate_grid(nodes[rows], nodes) - centre
        flux = np.einsum(
            "nabd,nabd->ab",
            p,
            np.cross(
                patches.evaluate_grid(nodes[rows], nodes, 1, 0),
                patches.evaluate_grid(nodes[rows], nodes, 0, 1),
            ),
        )
        total += float(weights[rows] @ flux @ weights)
    return total / 3.0


def volume_estimate(
    network: PatchNetwork | Patches, *, rtol: float = 1e-12, max_points: int = 256
) -> VolumeEstimate:
    """The enclosed volume ``1/3 Σ ∫∫ (p − c) · (p_u × p_v) du dv`` and how it was obtained.

    Polynomial patches (:class:`PatchSet`): 5 × 5 Gauss–Legendre points, exact. Others: G = 8, 16, …
    until ``|V_G − V_{G/2}| ≤ rtol · |V_G|`` or G would pass ``max_points``; ``change`` reports the
    last difference, so a caller sees how well the estimate settled.
    """
    patches = _patches_of(network)
    if not (isinstance(rtol, (int, float)) and rtol > 0):
        raise InputError(f"rtol: expected a positive number, got {rtol!r}")
    if len(patches) == 0:
        return VolumeEstimate(0.0, 0, 0.0, True)
    frame: Frame | None = getattr(patches, "frame", None)
    cube = 1.0
    if frame is not None:
        patches, cube = patches.local(), frame.scale**3  # type: ignore[attr-defined]
    centre = _centre(patches)
    if isinstance(patches, PatchSet):
        return VolumeEstimate(
            _quadrature(patches, BICUBIC_POINTS, centre) * cube, BICUBIC_POINTS, 0.0, True
        )
    points = 8
    previous = _quadrature(patches, points, centre)
    while True:
        points *= 2
        volume = _quadrature(patches, points, centre)
        change = abs(volume - previous)
        if change <= rtol * abs(volume) or 2 * points > max_points:
            return VolumeEstimate(volume * cube, points, change * cube, False)
        previous = volume


def network_volume(
    network: PatchNetwork | Patches, *, rtol: float = 1e-12, max_points: int = 256
) -> float:
    """The volume enclosed by a closed network (see :func:`volume_estimate` for the quadrature)."""
    return volume_estimate(network, rtol=rtol, max_points=max_points).volume
