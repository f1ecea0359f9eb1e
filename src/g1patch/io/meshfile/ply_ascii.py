"""ASCII PLY of the common layout (:class:`~.ply_header._PlyLayout`): one line per vertex, then
one per face, as many as the header announces and nothing after them.

Read by the vectorised fast path (:func:`_ply_text`: double coordinates first, faces of a list
alone) or, where it declines, line by line (:func:`_read_ply_lines`, the reference: every error
names its line). A face's list must hold exactly the corners its count announces; ``float``
coordinates are rounded to float32, as the file declares them.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from ...errors import FormatError
from .parsed import (
    _content,
    _convert,
    _faces_in_range,
    _finite_vertices,
    _Parsed,
    _polygon_list,
    _rows_announced,
)
from .ply_header import MIN_CORNERS, PLY_TYPES, _PlyHeader, _PlyLayout
from .text import _numbers, _scan


def _ply_text(
    data: bytes, header: _PlyHeader, layout: _PlyLayout
) -> tuple[NDArray[np.float64], NDArray[np.int64], NDArray[np.int64]] | None:
    """Points, corners and sizes of an ASCII PLY file of the common layout with x, y, z first and
    every vertex property ``double``, faces of their list alone, one line per vertex then per face
    with exactly its numbers, no blank line or comment among them and nothing after them: parsed
    as the OBJ and OFF text is; None for any other file (:func:`_read_ply_lines` reads it)."""
    properties = layout.vertex.properties
    if (
        not header.ascii
        or [p.name for p in properties[:3]] != ["x", "y", "z"]
        or any(PLY_TYPES[p.type] != "f8" for p in properties)
        or len(layout.face.properties) != 1
    ):
        return None
    body = data[header.start :]
    lines = None if b"#" in body or b"\r" in body else _scan(body)
    n_vertices, n_faces, width = layout.vertex.size, layout.face.size, len(properties)
    if lines is None or lines.tokens.size < n_vertices + n_faces:
        return None
    vertex_tokens, face_tokens = (
        lines.tokens[:n_vertices],
        lines.tokens[n_vertices : n_vertices + n_faces],
    )
    if (
        (vertex_tokens != width).any()
        or (face_tokens == 0).any()
        or lines.tokens[n_vertices + n_faces :].any()
    ):
        return None
    values = _numbers(lines.chunk(np.arange(n_vertices)), b"", width * n_vertices, np.float64)
    if values is None or not np.isfinite(points := values.reshape(-1, width)[:, :3]).all():
        return None
    numbers = _numbers(
        lines.chunk(np.arange(n_vertices, n_vertices + n_faces)),
        b"",
        int(face_tokens.sum()),
        np.int64,
    )
    offsets = np.cumsum(face_tokens) - face_tokens
    if numbers is None or (numbers[offsets] != face_tokens - 1).any():
        return None
    sizes, corners = numbers[offsets], np.delete(numbers, offsets)
    if (sizes < MIN_CORNERS).any() or corners.min() < 0 or corners.max() >= n_vertices:
        return None
    return np.ascontiguousarray(points), corners, sizes


def _read_ply_lines(path: Path, data: bytes, header: _PlyHeader, layout: _PlyLayout) -> _Parsed:
    """The line-by-line ASCII PLY reader of the common layout, the reference: as many lines as the
    header announces, each vertex line with one number per property (x, y, z read, the others
    counted), each face line with its scalars and a list of exactly as many indices as its count
    (≥ 3) says; every error names its line."""
    rows = _content(path, data[header.start :], header.lines + 1)
    n_vertices, n_faces = layout.vertex.size, layout.face.size
    _rows_announced(path, rows, n_vertices, n_faces, header.lines)
    points = _ply_points(path, rows[:n_vertices], layout)
    face_rows = rows[n_vertices:]
    properties = layout.face.properties
    before, after = layout.corners, len(properties) - layout.corners - 1
    names = [p.name for p in properties]
    shape = " ".join([*names[:before], "n i_1 ... i_n", *names[before + 1 :]])
    sizes: list[int] = []
    tokens: list[str] = []
    for number, parts in face_rows:
        try:
            size = int(parts[before]) if len(parts) > before else -1
        except ValueError:
            size = -1
        if size < MIN_CORNERS or len(parts) != before + 1 + size + after:
            raise FormatError(
                path,
                f"expected a face '{shape}' with n ≥ {MIN_CORNERS} and exactly n indices, got "
                f"{' '.join(parts)[:80]!r}",
                number,
            )
        sizes.append(size)
        tokens.extend(parts[before + 1 : before + 1 + size])
    face_sizes = np.array(sizes, dtype=np.int64)
    face_lines = np.array([number for number, _ in face_rows], dtype=np.int64)
    corners = _convert(
        path, tokens, np.int64, "integer vertex indices", np.repeat(face_lines, face_sizes)
    )
    _faces_in_range(path, corners, face_sizes, n_vertices, face_lines)
    return _Parsed(points, _polygon_list(corners, face_sizes))


def _ply_points(
    path: Path, rows: list[tuple[int, list[str]]], layout: _PlyLayout
) -> NDArray[np.float64]:
    """The x, y, z of the vertex lines ``rows``, each with one number per vertex property; a
    ``float`` coordinate rounded to float32."""
    properties = layout.vertex.properties
    names = [p.name for p in properties]
    for number, parts in rows:
        if len(parts) != len(names):
            raise FormatError(
                path,
                f"expected a vertex of {len(names)} numbers ({' '.join(names)[:60]}), got "
                f"{' '.join(parts)[:80]!r}",
                number,
            )
    columns = [names.index(axis) for axis in "xyz"]
    lines = np.array([number for number, _ in rows], dtype=np.int64)
    points = _convert(
        path,
        [[parts[k] for k in columns] for _, parts in rows],
        np.float64,
        "a vertex of numbers",
        lines,
    ).reshape(-1, 3)
    for axis, k in enumerate(columns):
        if PLY_TYPES[properties[k].type] == "f4":
            with np.errstate(over="ignore", invalid="ignore"):  # inf or NaN: named below
                points[:, axis] = points[:, axis].astype(np.float32)
    _finite_vertices(path, points, lines)
    return points
