"""What every reader returns (:class:`_Parsed`: vertices, faces, tags) and the checks they
share: UTF-8 text, its lines of content, as many as a header announces, numbers converted in bulk,
finite coordinates, face indices in range, the polygon list."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from ...errors import FormatError
from ...mesh import Tag
from ...mesh.groups import FaceGroups

#: the first integer int64 cannot hold: no index or count in a file may reach it
_INT64_END = 2**63


class _Parsed(NamedTuple):
    vertices: NDArray[np.float64]
    faces: NDArray[np.int64] | list[NDArray[np.int64]]
    tags: tuple[Tag, ...] = ()
    #: texture coordinates per face corner (C, 2), in the faces' order (OBJ ``vt``); None without
    uv: NDArray[np.float64] | None = None
    #: each face's group (OBJ ``usemtl``, ``g``, ``o``: :mod:`.obj_groups`); None without
    groups: FaceGroups | None = None


def _decode(path: Path, data: bytes) -> list[str]:
    try:
        return data.decode("utf-8").splitlines()
    except UnicodeDecodeError as exc:
        raise FormatError(path, f"not a text file (byte {exc.start} is not UTF-8)") from None


def _content(path: Path, data: bytes, first: int = 1) -> list[tuple[int, list[str]]]:
    """The lines of ``data`` (UTF-8 text; line ``first`` first) that hold more than a ``#``
    comment: (line number, tokens)."""
    return [
        (number, parts)
        for number, line in enumerate(_decode(path, data), start=first)
        if (parts := line.split("#", 1)[0].split())
    ]


def _rows_announced(
    path: Path, rows: Sequence[tuple[int, list[str]]], n_vertices: int, n_faces: int, last: int
) -> None:
    """Refuse fewer or more ``rows`` than the ``n_vertices + n_faces`` a header announced (``last``:
    the header's last line, where a file without rows ends)."""
    expected = n_vertices + n_faces
    if len(rows) < expected:
        raise FormatError(
            path,
            f"truncated: the header announces {n_vertices} vertices and {n_faces} faces, the file "
            f"ends first ({len(rows)} of their {expected} lines)",
            rows[-1][0] if rows else last,
        )
    if len(rows) > expected:
        number, parts = rows[expected]
        raise FormatError(
            path,
            f"unexpected content after the {n_vertices} vertices and {n_faces} faces the header "
            f"announces: {' '.join(parts)[:60]!r}",
            number,
        )


def _convert(
    path: Path, tokens: list, dtype: type, expected: str, lines: Sequence[int] | NDArray[np.int64]
) -> NDArray:
    """``np.array(tokens, dtype)``; on a bad token, a :class:`FormatError` naming its line
    (``lines`` per row)."""
    try:
        return np.array(tokens, dtype=dtype)
    except (ValueError, OverflowError):
        for row, line in zip(tokens, lines, strict=True):
            try:
                np.array(row, dtype=dtype)
            except (ValueError, OverflowError):
                text = row if isinstance(row, str) else " ".join(row)
                raise FormatError(path, f"expected {expected}, got {text!r}", int(line)) from None
        raise


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
    """An (nf, n) table when all faces have n ≥ 1 corners, else one index array per face (faces
    without corners are then empty arrays, which the mesh checks refuse by name)."""
    if sizes[0] > 0 and (sizes == sizes[0]).all():
        return corners.reshape(-1, int(sizes[0]))
    return np.split(corners, np.cumsum(sizes)[:-1])
