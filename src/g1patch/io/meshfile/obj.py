"""OBJ: ``v``, ``f`` and OpenSubdiv ``t`` tag lines, other statements skipped or refused; read
by the compiled kernel, the vectorised fast path or, where they decline, line by line; ``vt`` by
a pass of its own, only in files that have them (:func:`_obj_uvs`), and so are the face groups
(``usemtl``, ``g``, ``o``: :mod:`.obj_groups`)."""

from __future__ import annotations

import re
from collections.abc import Sequence
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from ...errors import FormatError
from ...kernels import use_kernels
from ...mesh import Tag
from .compiled import _BYTE_CLASSES, KERNEL_BYTES, _compiled, _obj_kernel, _powers_of_five
from .obj_groups import _mentions_groups, _obj_groups
from .parsed import (
    _INT64_END,
    _convert,
    _decode,
    _faces_in_range,
    _finite_vertices,
    _Parsed,
    _polygon_list,
)
from .source import MAX_COUNT_DIGITS
from .text import _gather_floats, _numbers, _scan

#: OBJ statements the face reader skips: those that carry nothing a quad mesh needs (normals,
#: free-form geometry) and those read by passes of their own (``vt``, ``g``, ``o``, ``usemtl``,
#: ``mtllib``). Any other keyword is an error.
OBJ_SKIPPED = frozenset(
    "vt vn vp g o s usemtl mtllib l p lod bevel c_interp d_interp shadow_obj trace_obj maplib "
    "usemap "
    "cstype deg bmat step curv curv2 surf parm trim hole scrv sp end con mg ctech stech call "
    "csh".split()
)
_SLASHED = re.compile(rb"/[^ \n]*")


def _read_obj(path: Path, data: bytes) -> _Parsed:
    """OBJ: ``v x y z [w]``; ``f a b c …`` with ``a`` = ``v``, ``v/vt``, ``v//vn`` or ``v/vt/vn``.

    Indices are 1-based; negative ones count back from the last vertex defined so far. Read by
    :func:`_obj_compiled` (from :data:`KERNEL_BYTES` on) or :func:`_obj_fast`, or line by line
    (:func:`_read_obj_lines`) where it declines.
    """
    parsed = _obj_compiled(data) if use_kernels(len(data) >= KERNEL_BYTES) else _obj_fast(data)
    parsed = parsed if parsed is not None else _read_obj_lines(path, data)
    if _mentions_groups(data):  # the one cost to files without groups
        parsed = parsed._replace(groups=_obj_groups(path, data, len(parsed.faces)))
    if not _mentions_uvs(data):  # the one cost to files without texture coordinates
        return parsed
    return parsed._replace(uv=_obj_uvs(path, data, parsed))


def _mentions_uvs(data: bytes) -> bool:
    """Whether some ``t`` of ``data`` ends a ``vt`` at the start of a token: a ``memchr`` for the
    byte ``t``, which numbers never hold (a search for ``vt`` stops at every ``v``: 7× slower)."""
    at = data.find(b"t")
    while at >= 0:
        if at and data[at - 1] == ord("v") and (at == 1 or data[at - 2] in b" \t\r\n"):
            return True
        at = data.find(b"t", at + 1)
    return False


#: a face corner ``v/vt…`` as its ``vt`` index (``v//vn`` as an empty token)
_VT_OF_CORNER = re.compile(rb"[^ \n/]*/([^ \n/]*)[^ \n]*")


def _obj_uvs(path: Path, data: bytes, parsed: _Parsed) -> NDArray[np.float64] | None:
    """Texture coordinates per face corner (C, 2), in the readers' face order: ``vt u [v [w]]``
    (v = 0 when absent), named by the faces' ``v/vt`` or ``v/vt/vn`` corners (1-based; negative
    ones count back from the last ``vt`` defined so far). None where the file has no ``vt`` or
    some corner names none (``v``, ``v//vn``): UVs are all or nothing. Vectorised; where it
    declines, :func:`_obj_uvs_lines` reads them (and names the line of a bad one)."""
    sizes = _face_sizes(parsed.faces)
    lines = _scan(data)
    if lines is None:
        return _obj_uvs_lines(path, data, sizes)
    first, second, third = lines.byte(0), lines.byte(1), lines.byte(2)
    is_uv = (first == ord("v")) & (second == ord("t")) & (third == ord(" "))
    if not is_uv.any():
        return None
    uv_rows = np.flatnonzero(is_uv)
    face_rows = np.flatnonzero((first == ord("f")) & (second == ord(" ")))
    uv_tokens = lines.tokens[uv_rows]
    if (
        (uv_tokens < 3).any()
        or (uv_tokens > 4).any()
        or not np.array_equal(lines.tokens[face_rows] - 1, sizes)
    ):
        return _obj_uvs_lines(path, data, sizes)
    text, count = _VT_OF_CORNER.subn(rb"\1", lines.chunk(face_rows))
    if count != sizes.sum():
        return None  # a corner without '/': no UVs
    uv_text = lines.chunk(uv_rows)
    values: NDArray[np.float64] | None = None
    if (uv_tokens == 3).all() and (
        numbers := _numbers(uv_text, b"vt", 2 * uv_rows.size, np.float64)
    ) is not None:
        values = numbers.reshape(-1, 2)
    else:  # 'vt u v w', or tokens np.fromstring does not read as float does
        values = _gather_floats(uv_text, uv_tokens, (1, 2))
    written = _numbers(text, b"f", int(sizes.sum()), np.int64)
    if values is None or written is None or (written == 0).any():
        return _obj_uvs_lines(path, data, sizes)
    before = np.repeat(np.cumsum(is_uv)[face_rows], sizes)
    corners = np.where(written > 0, written - 1, before + written)
    if corners.min() < 0 or corners.max() >= len(values) or not np.isfinite(values).all():
        return _obj_uvs_lines(path, data, sizes)
    return values[corners]


def _face_sizes(faces: NDArray[np.int64] | list[NDArray[np.int64]]) -> NDArray[np.int64]:
    if isinstance(faces, np.ndarray):
        return np.full(faces.shape[0], faces.shape[1], dtype=np.int64)
    return np.array([len(face) for face in faces], dtype=np.int64)


def _obj_uvs_lines(path: Path, data: bytes, sizes: NDArray[np.int64]) -> NDArray[np.float64] | None:
    """:func:`_obj_uvs` line by line, the reference: a bad ``vt`` or ``vt`` index names its line."""
    values: list[tuple[float, float]] = []
    corners: list[int] = []
    for number, line in enumerate(_decode(path, data), start=1):
        parts = line.split("#", 1)[0].split()
        if not parts:
            continue
        if parts[0] == "vt":
            try:
                u, v = float(parts[1]), float(parts[2]) if len(parts) > 2 else 0.0
                if len(parts) > 4 or not (np.isfinite(u) and np.isfinite(v)):
                    raise ValueError
            except (ValueError, IndexError):
                expected = "expected 'vt u [v [w]]' with finite numbers"
                raise FormatError(path, f"{expected}, got {line.strip()!r}", number) from None
            values.append((u, v))
        elif parts[0] == "f":
            for token in parts[1:]:
                vt = token.split("/")[1] if "/" in token else ""
                if not vt:
                    return None  # a corner without a texture coordinate: no UVs
                try:
                    index = int(vt)
                except ValueError:
                    raise FormatError(
                        path, f"expected an integer texture index in {token!r}", number
                    ) from None
                at = index - 1 if index > 0 else len(values) + index
                if index == 0 or not 0 <= at < len(values):
                    raise FormatError(
                        path,
                        f"face corner {token!r} names texture coordinate {index}, but "
                        f"{len(values)} are defined (1-based)",
                        number,
                    )
                corners.append(at)
    if not values or len(corners) != int(sizes.sum()):
        return None
    return np.array(values, dtype=np.float64).reshape(-1, 2)[corners]


def _obj_fast(data: bytes) -> _Parsed | None:
    """The vectorised OBJ reader (see above); None where the line-by-line one must read the file."""
    lines = _scan(data)
    if lines is None:
        return None
    first, second, third = lines.byte(0), lines.byte(1), lines.byte(2)
    is_vertex = (first == ord("v")) & (second == ord(" "))
    is_face = (first == ord("f")) & (second == ord(" "))
    skipped = (
        (first == ord("v"))
        & np.isin(second, np.frombuffer(b"tnp", np.uint8))
        & ((third == ord(" ")) | (lines.ends - lines.starts == 2))
    )
    tags: list[Tag] = []
    for row in np.flatnonzero((lines.tokens > 0) & ~(is_vertex | is_face | skipped)).tolist():
        parts = lines.text[lines.starts[row] : lines.ends[row]].decode("ascii").split()
        if parts[0] == "t":
            try:
                tags.append(_parse_tag(Path(), parts, row + 1))
            except FormatError:
                return None
        elif parts[0] not in OBJ_SKIPPED:
            return None  # unknown, or 'v' / 'f' alone
    vertex_rows, face_rows = np.flatnonzero(is_vertex), np.flatnonzero(is_face)
    vertex_tokens, sizes = lines.tokens[vertex_rows], lines.tokens[face_rows] - 1
    if (
        face_rows.size == 0
        or (vertex_tokens < 4).any()
        or (vertex_tokens > 8).any()
        or (sizes < 3).any()
    ):
        return None
    text = lines.chunk(vertex_rows)
    points: NDArray[np.float64] | None
    if (vertex_tokens == 4).all() and (
        values := _numbers(text, b"v", 3 * vertex_rows.size, np.float64)
    ) is not None:
        points = values.reshape(-1, 3)
    else:  # 'v x y z w', or tokens np.fromstring does not read as float does
        points = _gather_floats(text, vertex_tokens, (1, 2, 3))
    if points is None or not np.isfinite(points).all():
        return None
    text = lines.chunk(face_rows)
    if b"/" in text:  # v/vt/vn: keep v
        text = _SLASHED.sub(b"", text)
    written = _numbers(text, b"f", int(sizes.sum()), np.int64)
    if written is None or (written == 0).any():
        return None
    # 1-based; negative indices count back from the last vertex defined before the face
    before = np.repeat(np.cumsum(is_vertex)[face_rows], sizes)
    corners = np.where(written > 0, written - 1, before + written)
    if corners.size and (corners.min() < 0 or corners.max() >= points.shape[0]):
        return None
    return _Parsed(points, _polygon_list(corners, sizes), tuple(tags))


def _read_obj_lines(path: Path, data: bytes) -> _Parsed:
    """The line-by-line OBJ reader, the reference: every error names its line.

    The loop over lines only sorts tokens; NumPy converts them in bulk, and only on a bad number
    are the lines searched again to name the one at fault.
    """
    vertex_tokens: list[list[str]] = []
    vertex_lines: list[int] = []
    face_tokens: list[str] = []
    sizes: list[int] = []
    face_lines: list[int] = []
    vertices_before_face: list[int] = []
    tags: list[Tag] = []
    for number, line in enumerate(_decode(path, data), start=1):
        if "#" in line:
            line = line.split("#", 1)[0]
        parts = line.split()
        if not parts:
            continue
        keyword = parts[0]
        if keyword == "v":
            if not 4 <= len(parts) <= 8:
                raise FormatError(
                    path, f"expected 'v x y z' with 3 numbers, got {line.strip()!r}", number
                )
            vertex_tokens.append(parts[1:4])
            vertex_lines.append(number)
        elif keyword == "f":
            if len(parts) < 4:
                raise FormatError(
                    path, f"a face needs at least 3 corners, got {len(parts) - 1}", number
                )
            indices = parts[1:]
            if "/" in line:  # v/vt/vn: keep v
                indices = [token.partition("/")[0] for token in indices]
            face_tokens.extend(indices)
            sizes.append(len(parts) - 1)
            face_lines.append(number)
            vertices_before_face.append(len(vertex_tokens))
        elif keyword == "t":
            tags.append(_parse_tag(path, parts, number))
        elif keyword not in OBJ_SKIPPED:
            raise FormatError(path, f"unknown OBJ statement {keyword[:40]!r}", number)
    if not sizes:
        raise FormatError(path, "no faces: expected 'f' lines")

    face_sizes = np.array(sizes, dtype=np.int64)
    points = _convert(
        path, vertex_tokens, np.float64, "'v x y z' with 3 numbers", vertex_lines
    ).reshape(-1, 3)
    _finite_vertices(path, points, np.array(vertex_lines))
    token_lines = np.repeat(face_lines, face_sizes)
    written = _convert(path, face_tokens, np.int64, "'f' with integer vertex indices", token_lines)
    if (written == 0).any():
        at = face_lines[
            int(
                np.searchsorted(
                    np.cumsum(face_sizes), np.flatnonzero(written == 0)[0], side="right"
                )
            )
        ]
        raise FormatError(path, "vertex index 0 in a face; OBJ indices start at 1", at)
    # 1-based; negative indices count back from the last vertex defined before the face
    corners = np.where(
        written > 0, written - 1, np.repeat(vertices_before_face, face_sizes) + written
    )
    _faces_in_range(path, corners, face_sizes, points.shape[0], np.array(face_lines))
    return _Parsed(points, _polygon_list(corners, face_sizes), tuple(tags))


def _parse_tag(path: Path, parts: Sequence[str], line: int) -> Tag:
    """OpenSubdiv ``t name nints/nfloats/nstrings ints… floats… strings…`` (integers 0-based)."""
    usage = "expected 't name nints/nfloats/nstrings ints... floats... strings...'"
    if len(parts) < 3:
        raise FormatError(path, usage, line)
    counts = parts[2].split("/")
    if len(counts) != 3 or not all(c.isdigit() and len(c) <= MAX_COUNT_DIGITS for c in counts):
        raise FormatError(path, f"{usage}; got counts {parts[2][:60]!r}", line)
    n_ints, n_floats, n_strings = map(int, counts)
    values = parts[3:]
    if len(values) != n_ints + n_floats + n_strings:
        raise FormatError(
            path,
            f"tag {parts[1]!r} announces {n_ints}/{n_floats}/{n_strings} values but has "
            f"{len(values)}",
            line,
        )
    try:
        ints = tuple(int(x) for x in values[:n_ints])
        floats = tuple(float(x) for x in values[n_ints : n_ints + n_floats])
        if any(not -_INT64_END <= i < _INT64_END for i in ints):
            raise ValueError  # no index, no count
    except ValueError:
        raise FormatError(
            path,
            f"tag {parts[1]!r}: expected {n_ints} integers (within ±2^63) then {n_floats} numbers",
            line,
        ) from None
    return Tag(parts[1], ints, floats, tuple(values[n_ints + n_floats :]))


def _obj_compiled(data: bytes) -> _Parsed | None:
    """The compiled OBJ reader (see above); None where the line-by-line one must read the file."""
    buffer, kernel = np.frombuffer(data, dtype=np.uint8), _compiled(_obj_kernel)
    found = (
        3 * (len(data) // 24 + 64),
        len(data) // 6 + 64,
        len(data) // 24 + 64,
        1024,
        1024,
    )  # most files fit
    while True:
        n_points, n_corners, n_faces, n_hard, n_others = found
        arrays = (
            np.empty(n_points, dtype=np.uint64),
            np.empty(n_corners, dtype=np.int64),
            np.empty(n_faces, dtype=np.int64),
            np.empty((n_hard, 3), dtype=np.int64),
            np.empty((n_others, 2), dtype=np.int64),
        )
        valid, *counts = kernel(buffer, _BYTE_CLASSES, _powers_of_five(), *arrays)
        found = (counts[0], counts[2], counts[1], counts[3], counts[4])
        if not valid or all(
            count <= len(array) for count, array in zip(found, arrays, strict=True)
        ):
            break
    if not valid or found[2] == 0:
        return None
    points, corners, sizes, hard, others = (
        arrays[0][: found[0]],
        arrays[1][: found[1]],
        arrays[2][: found[2]],
        arrays[3][: found[3]],
        arrays[4][: found[4]],
    )
    vertices = points.view(np.float64).reshape(-1, 3)
    for start, end, slot in hard.tolist():  # spelt otherwise ('1_0', 'inf'), or hard to round
        try:
            vertices.flat[slot] = float(data[start:end])
        except ValueError:
            return None
    tags: list[Tag] = []
    for start, end in others.tolist():
        parts = data[start:end].decode("ascii").split()
        if parts[0] == "t":
            try:
                tags.append(_parse_tag(Path(), parts, 0))
            except FormatError:
                return None
        elif parts[0] not in OBJ_SKIPPED:
            return None
    if not np.isfinite(vertices).all() or corners.min() < 0 or corners.max() >= len(vertices):
        return None
    return _Parsed(vertices, _polygon_list(corners, sizes), tuple(tags))
