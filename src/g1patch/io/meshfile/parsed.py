"""What every reader returns (:class:`_Parsed`: vertices, faces, tags) and the checks they
share: UTF-8 text, finite coordinates, face indices in range, the polygon list."""

from __future__ import annotations

from pathlib import Path
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from ...errors import FormatError
from ...mesh import Tag


class _Parsed(NamedTuple):
    vertices: NDArray[np.float64]
    faces: NDArray[np.int64] | list[NDArray[np.int64]]
    tags: tuple[Tag, ...] = ()


def _decode(path: Path, data: bytes) -> list[str]:
    try:
        return data.decode("utf-8").splitlines()
    except UnicodeDecodeError as exc:
        raise FormatError(path, f"not a text file (byte {exc.start} is not UTF-8)") from None


def _finite_vertices(
    path: Path, vertices: NDArray[np.float64], lines: NDArray[np.int64] | None
) -> None:
    bad = np.flatnonzero(~np.isfinite(vertices).all(axis=1))
    if bad.size:
        v = int(bad[0])
        raise FormatError(
            path,
            f"vertex {v} has a non-finite coordinate {tuple(vertices[v].tolist())}",
            None if lines is None else int(lines[v]),
        )


def _faces_in_range(
    path: Path,
    corners: NDArray[np.int64],
    sizes: NDArray[np.int64],
    n_vertices: int,
    lines: NDArray[np.int64] | None,
) -> None:
    bad = np.flatnonzero((corners < 0) | (corners >= n_vertices))
    if bad.size:
        face = int(np.searchsorted(np.cumsum(sizes), bad[0], side="right"))
        raise FormatError(
            path,
            f"face {face} names vertex {corners[bad[0]]} (0-based), but the file has {n_vertices} "
            "vertices",
            None if lines is None else int(lines[face]),
        )


def _polygon_list(
    corners: NDArray[np.int64], sizes: NDArray[np.int64]
) -> NDArray[np.int64] | list[NDArray[np.int64]]:
    """An (nf, n) table when all faces have n corners, else one index array per face."""
    if (sizes == sizes[0]).all():
        return corners.reshape(-1, int(sizes[0]))
    return np.split(corners, np.cumsum(sizes)[:-1])
