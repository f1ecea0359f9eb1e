"""Argument checks of the picture functions (sizes, paths, titles, reports, zoom, colour range)
and the optional matplotlib import: each raises :class:`~g1patch.errors.InputError` (or
:class:`~g1patch.errors.MissingDependencyError`) with the argument's name."""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from ..continuity import ContinuityReport
from ..errors import InputError, MissingDependencyError
from ..network import PatchNetwork

_SIZE_RANGE = (32, 8192)


def _check_network(network: object) -> PatchNetwork:
    if not isinstance(network, PatchNetwork):
        raise InputError(f"network: expected a PatchNetwork, got {type(network).__name__}")
    if network.n_patches == 0:
        raise InputError("network: has no patches; there is nothing to draw")
    return network


def _check_size(size: Any) -> tuple[int, int]:
    low, high = _SIZE_RANGE
    try:
        width, height = size
    except (TypeError, ValueError):
        raise InputError(f"size: expected (width, height) in pixels, got {size!r}") from None
    for value in (width, height):
        if (
            isinstance(value, bool)
            or not isinstance(value, (int, np.integer))
            or not low <= value <= high
        ):
            raise InputError(
                f"size: expected two integers from {low} to {high} pixels, got {size!r}"
            )
    return int(width), int(height)


def _check_resolution(resolution: object) -> int | None:
    if resolution is None:
        return None
    if (
        isinstance(resolution, bool)
        or not isinstance(resolution, (int, np.integer))
        or not 2 <= resolution <= 1025
    ):
        raise InputError(
            f"resolution: expected None or an integer from 2 to 1025, got {resolution!r}"
        )
    return int(resolution)


def _check_title(name: str, title: object) -> str | None:
    if title is not None and not isinstance(title, str):
        raise InputError(f"{name}: expected a string, got {type(title).__name__}")
    return title


def _check_titles(titles: object, count: int, per: str) -> None:
    """``titles``: a sequence (not a string) of ``count`` titles, one per ``per``."""
    if isinstance(titles, str) or not isinstance(titles, Sequence) or len(titles) != count:
        got = (
            len(titles)
            if isinstance(titles, Sequence) and not isinstance(titles, str)
            else type(titles).__name__
        )
        raise InputError(f"titles: expected one title per {per} ({count}), got {got}")


def _check_path(path: object) -> Path:
    if not isinstance(path, (str, os.PathLike)):
        raise InputError(f"path: expected a file name, got {type(path).__name__}")
    target = Path(path)
    if target.suffix.lower() != ".png":
        raise InputError(
            "path: pictures are written as PNG; expected a name ending in .png, got "
            f"{str(target)!r}"
        )
    return target


def _check_report(
    report: object, network: PatchNetwork, name: str = "report"
) -> ContinuityReport | None:
    if report is None:
        return None
    if not isinstance(report, ContinuityReport):
        raise InputError(
            f"{name}: expected a ContinuityReport or None, got {type(report).__name__}"
        )
    if report.patches != network.n_patches or (
        report.edge_patches.size and int(report.edge_patches.max()) >= network.n_patches
    ):
        raise InputError(
            f"{name}: was made for {report.patches} patches, the network has {network.n_patches}"
        )
    return report


def _check_zoom(zoom: Any) -> float:
    if (
        isinstance(zoom, bool)
        or not isinstance(zoom, (int, float, np.integer, np.floating))
        or not 0.1 <= zoom <= 1000.0
    ):
        raise InputError(f"zoom: expected a number from 0.1 to 1000, got {zoom!r}")
    return float(zoom)


def _check_angle_range(angle_range: Any) -> tuple[float, float] | None:
    if angle_range is None:
        return None
    try:
        low, high = (float(x) for x in angle_range)
    except (TypeError, ValueError):
        raise InputError(
            f"angle_range: expected (low, high) in degrees, got {angle_range!r}"
        ) from None
    if not (math.isfinite(low) and math.isfinite(high) and 0.0 <= low < high):
        raise InputError(f"angle_range: expected 0 ≤ low < high, finite, got {angle_range!r}")
    return low, high


def _matplotlib() -> Any:
    try:
        import matplotlib  # noqa: F401
        from matplotlib.figure import Figure
    except ImportError:
        raise MissingDependencyError("matplotlib", "viz", "rendering pictures") from None
    return Figure
