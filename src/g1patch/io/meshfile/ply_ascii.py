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
) -> (
    tuple[NDArray[np.float64], NDArray[np.int64], NDArray[np.int64], NDArray[np.float64] | None]
    | None
):
    """Points, corners, sizes and per-vertex UVs (None without) of an ASCII PLY file of the common
    layout with x, y, z first and every vertex property ``double``, faces of their list alone,
    one line per vertex then per face with exactly its numbers, no blank line or comment among
    them and nothing after them: parsed as the OBJ and OFF text is; None for any other file
    (:func:`_read_ply_lines` reads it)."""
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
    uv = None if layout.uv is None else values.reshape(-1, width)[:, list(layout.uv)]
    if uv is not None and not np.isfinite(uv).all():
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
    return np.ascontiguousarray(points), corners, sizes, uv


def _read_ply_lines(path: Path, data: bytes, header: _PlyHeader, layout: _PlyLayout) -> _Parsed:
    """The line-by-line ASCII PLY reader of the common layout, the reference: as many lines as the
    header announces, each vertex line with one number per property (x, y, z and the texture
    coordinates read, the others counted), each face line with its scalars and a list of exactly
    as many indices as its count (≥ 3) says, and where the header has one, a ``texcoord`` list of
    2 finite numbers a corner; every error names its line."""
    rows = _content(path, data[header.start :], header.lines + 1)
    n_vertices, n_faces = layout.vertex.size, layout.face.size
    _rows_announced(path, rows, n_vertices, n_faces, header.lines)
    points, vertex_uv = _ply_points(path, rows[:n_vertices], layout)
    face_rows = rows[n_vertices:]
    properties = layout.face.properties
    texcoord = len(properties) if layout.texcoord is None else layout.texcoord
    before, middle = layout.corners, texcoord - layout.corners - 1
    after = len(properties) - texcoord - (0 if layout.texcoord is None else 1)
    names = [p.name for p in properties]
    shape = " ".join(
        [*names[:before], "n i_1 ... i_n", *names[before + 1 : texcoord]]
        + ([] if layout.texcoord is None else ["2n u_1 v_1 ... u_n v_n", *names[texcoord + 1 :]])
    )
    uv_count = 0 if layout.texcoord is None else 1
    sizes: list[int] = []
    tokens: list[str] = []
    uv_tokens: list[str] = []
    for number, parts in face_rows:
        try:
            size = int(parts[before]) if len(parts) > before else -1
            pairs = int(parts[before + 1 + size + middle]) if uv_count and size > 0 else 0
        except (ValueError, IndexError):
            size = -1
        uv_size = 2 * size * uv_count
        if (
            size < MIN_CORNERS
            or len(parts) != before + 1 + size + middle + uv_count + uv_size + after
            or pairs != uv_size
        ):
            raise FormatError(
                path,
                f"expected a face '{shape}' with n ≥ {MIN_CORNERS} and exactly n indices, got "
                f"{' '.join(parts)[:80]!r}",
                number,
            )
        sizes.append(size)
        tokens.extend(parts[before + 1 : before + 1 + size])
        if uv_count:
            start = before + 1 + size + middle + 1
            uv_tokens.extend(parts[start : start + uv_size])
    face_sizes = np.array(sizes, dtype=np.int64)
    face_lines = np.array([number for number, _ in face_rows], dtype=np.int64)
    corner_lines = np.repeat(face_lines, face_sizes)
    corners = _convert(path, tokens, np.int64, "integer vertex indices", corner_lines)
    _faces_in_range(path, corners, face_sizes, n_vertices, face_lines)
    uv: NDArray[np.float64] | None = None
    if uv_count:
        uv = _convert(
            path, uv_tokens, np.float64, "texture coordinates", np.repeat(corner_lines, 2)
        ).reshape(-1, 2)
        _finite_uvs(path, uv, corner_lines, "face")
    elif vertex_uv is not None:
        uv = vertex_uv[corners]
    return _Parsed(points, _polygon_list(corners, face_sizes), uv=uv)


def _finite_uvs(
    path: Path, uv: NDArray[np.float64], lines: NDArray[np.int64] | None, what: str
) -> None:
    """Refuse a texture coordinate that is not finite, naming its line (or its ``what`` item)."""
    bad = np.flatnonzero(~np.isfinite(uv).all(axis=1))
    if bad.size:
        at = int(bad[0])
        where = (None, f"{what} corner {at}") if lines is None else (int(lines[at]), what)
        raise FormatError(
            path,
            f"{where[1]}: texture coordinates {uv[at].tolist()} are not finite numbers",
            where[0],
        )


def _ply_points(
    path: Path, rows: list[tuple[int, list[str]]], layout: _PlyLayout
) -> tuple[NDArray[np.float64], NDArray[np.float64] | None]:
    """The x, y, z of the vertex lines ``rows``, each with one number per vertex property; a
    ``float`` coordinate rounded to float32; and the texture coordinates (V, 2), None without."""
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
    if layout.uv is None:
        return points, None
    uv = _convert(
        path,
        [[parts[k] for k in layout.uv] for _, parts in rows],
        np.float64,
        "texture coordinates",
        lines,
    ).reshape(-1, 2)
    _finite_uvs(path, uv, lines, "vertex")
    return points, uv
