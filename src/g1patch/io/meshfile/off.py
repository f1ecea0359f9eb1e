"""OFF: a header, counts, vertex lines and face lines (0-based, any polygon), ``#`` comments;
read by the vectorised fast path or, where it declines, line by line (meshio's OFF reader only
accepts triangles)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from ...errors import FormatError
from .parsed import (
    _INT64_END,
    _content,
    _faces_in_range,
    _finite_vertices,
    _Parsed,
    _polygon_list,
    _rows_announced,
)
from .text import _gather_floats, _numbers, _scan

OFF_HEADERS = frozenset({"OFF", "COFF", "NOFF", "CNOFF", "STOFF", "STCOFF", "STNOFF", "STCNOFF"})


def _read_off(path: Path, data: bytes) -> _Parsed:
    """``OFF``, ``nv nf ne``, nv lines ``x y z …``, nf lines ``n i_1 … i_n …`` (0-based); ``#``
    comments.

    Read by :func:`_off_fast`, or line by line (:func:`_read_off_lines`) where it declines.
    """
    parsed = _off_fast(data)
    return parsed if parsed is not None else _read_off_lines(path, data)


def _off_fast(data: bytes) -> _Parsed | None:
    """The vectorised OFF reader (see above); None where the line-by-line one must read the file."""
    lines = _scan(data)
    if lines is None:
        return None
    content = np.flatnonzero(lines.tokens > 0)
    head = [
        lines.text[lines.starts[row] : lines.ends[row]].decode("ascii").split()
        for row in content[:2].tolist()
    ]
    if not head or head[0][0] not in OFF_HEADERS:
        return None
    counts, body = (
        (head[0][1:], content[1:]) if len(head[0]) > 1 or len(head) == 1 else (head[1], content[2:])
    )
    try:
        n_vertices, n_faces = int(counts[0]), int(counts[1])
    except (IndexError, ValueError):
        return None
    if n_vertices < 0 or n_faces <= 0 or body.size != n_vertices + n_faces:
        return None  # too few or too many lines: the reference names the line
    vertex_rows, face_rows = body[:n_vertices], body[n_vertices : n_vertices + n_faces]
    vertex_tokens, face_tokens = lines.tokens[vertex_rows], lines.tokens[face_rows]
    if (vertex_tokens < 3).any():
        return None
    text = lines.chunk(vertex_rows)
    points: NDArray[np.float64] | None
    if (vertex_tokens == 3).all() and (
        values := _numbers(text, b"", 3 * n_vertices, np.float64)
    ) is not None:
        points = values.reshape(-1, 3)
    else:  # more than x y z (colours), or tokens np.fromstring does not read as float does
        points = _gather_floats(text, vertex_tokens, (0, 1, 2))
    if points is None or not np.isfinite(points).all():
        return None
    text = lines.chunk(face_rows)
    offsets = np.cumsum(face_tokens) - face_tokens
    values = _numbers(text, b"", int(face_tokens.sum()), np.int64)
    if values is not None and (values[offsets] == face_tokens - 1).all():  # 'n i_1 ... i_n' only
        sizes, corners = values[offsets], np.delete(values, offsets)
    else:  # more after the indices (colours): convert the indices only
        tokens = np.array(text.split(), dtype=object)
        try:
            sizes = tokens[offsets].astype(np.int64)
            if (sizes < 3).any() or (face_tokens < sizes + 1).any():
                return None
            starts = np.repeat(offsets + 1 - (np.cumsum(sizes) - sizes), sizes)
            corners = tokens[starts + np.arange(int(sizes.sum()))].astype(np.int64)
        except (ValueError, OverflowError, TypeError):
            return None
    if (sizes < 3).any() or corners.min() < 0 or corners.max() >= n_vertices:
        return None
    return _Parsed(points, _polygon_list(corners, sizes))


def _read_off_lines(path: Path, data: bytes) -> _Parsed:
    """The line-by-line OFF reader, the reference: every error names its line."""
    content = _content(path, data)
    if not content or content[0][1][0] not in OFF_HEADERS:
        raise FormatError(
            path, "expected the header 'OFF' on the first line", content[0][0] if content else 1
        )
    (counts_line, header), body = content[0], content[1:]
    counts = header[1:]  # the counts may follow the header on its line
    if not counts and body:
        (counts_line, counts), body = body[0], body[1:]
    try:
        n_vertices, n_faces = int(counts[0]), int(counts[1])
        if n_vertices < 0 or n_faces < 0:
            raise ValueError
    except (IndexError, ValueError):
        raise FormatError(
            path,
            "expected the counts 'n_vertices n_faces n_edges' (integers ≥ 0), got "
            f"{' '.join(counts)[:60]!r}",
            counts_line,
        ) from None
    _rows_announced(path, body, n_vertices, n_faces, counts_line)

    vertex_rows, face_rows = body[:n_vertices], body[n_vertices : n_vertices + n_faces]
    points = np.empty((n_vertices, 3))
    for row, (number, parts) in enumerate(vertex_rows):
        try:
            points[row] = [float(x) for x in parts[:3]]
        except ValueError:
            raise FormatError(
                path, f"expected a vertex 'x y z', got {' '.join(parts)!r}", number
            ) from None
    vertex_lines = np.array([number for number, _ in vertex_rows], dtype=np.int64)
    _finite_vertices(path, points, vertex_lines)

    faces = []
    for number, parts in face_rows:
        try:
            size = int(parts[0])
            indices = [int(x) for x in parts[1 : 1 + size]]
            if size < 3 or len(indices) != size or max(map(abs, indices)) >= _INT64_END:
                raise ValueError  # an index beyond int64 is no vertex either
        except ValueError:
            expected = "expected a face 'n i_1 ... i_n' with n >= 3"
            raise FormatError(path, f"{expected}, got {' '.join(parts)!r}", number) from None
        faces.append(indices)
    sizes = np.fromiter(map(len, faces), dtype=np.int64, count=len(faces))
    if sizes.size == 0:
        raise FormatError(path, "no faces: the header announces 0 faces", counts_line)
    corners = np.fromiter(
        (i for face in faces for i in face), dtype=np.int64, count=int(sizes.sum())
    )
    _faces_in_range(path, corners, sizes, n_vertices, np.array([number for number, _ in face_rows]))
    return _Parsed(points, _polygon_list(corners, sizes))
