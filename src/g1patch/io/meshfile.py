"""Quad mesh files: read OBJ / PLY / OFF into a :class:`QuadMesh`; write triangles or quads as OBJ /
PLY / STL.

* OBJ is read by a small parser of its own (``v``, ``f``, OpenSubdiv ``t`` tag lines; other OBJ
  statements are skipped, unknown ones are errors) so that every error names its line and mixed
  polygon lists keep their order.
* PLY: binary files of the common layout (x, y, z and other scalars per vertex, one list of
  vertex indices per face, every face with as many corners) are read as NumPy records, any other
  by meshio (``meshio.ply``), after checking the header here: meshio silently returns fewer faces
  from a truncated binary file.
* OFF is read by a parser of its own: meshio's OFF reader only accepts triangles.

OBJ and OFF text is parsed in bulk by NumPy over the whole file, and from :data:`KERNEL_BYTES` on
by numba kernels (OBJ in one scan; the coordinates of OFF and ASCII PLY); only where a fast path
declines (anything unusual, any error) is the file read again line by line, by the reference
parser whose results and line-numbered messages the fast paths reproduce exactly.

Every problem with a file raises :class:`FormatError` (file, line where known, what was expected);
problems with the mesh it describes raise the :class:`MeshError` family, prefixed with the file
name. Writes go through :func:`atomic_path`: an error never leaves a partial file. OBJ and STL are
written here, a block of rows at a time (several times faster than meshio and in bounded
memory), binary PLY by meshio.
"""

from __future__ import annotations

import os
import re
import warnings
from collections.abc import Callable, Sequence
from functools import cache
from pathlib import Path
from typing import NamedTuple

import meshio
import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import FormatError, InputError, as_float_array, as_index_array
from ..mesh import QuadMesh, Tag
from .atomic import atomic_path

__all__ = ["read_mesh", "write_triangles", "write_quads", "READ_FORMATS", "WRITE_FORMATS"]

READ_FORMATS = (".obj", ".ply", ".off")
WRITE_FORMATS = (".obj", ".ply", ".stl")

#: OBJ statements that carry nothing a quad mesh needs (normals, texture, grouping, materials,
#: free-form geometry); they are skipped. Any other keyword is an error.
OBJ_SKIPPED = frozenset(
    "vt vn vp g o s usemtl mtllib l p lod bevel c_interp d_interp shadow_obj trace_obj maplib "
    "usemap "
    "cstype deg bmat step curv curv2 surf parm trim hole scrv sp end con mg ctech stech call "
    "csh".split()
)

PathLike = str | os.PathLike[str]


def read_mesh(
    path: PathLike,
    *,
    split: bool = True,
    sharp_angle: float | None = None,
    strict: bool | None = None,
) -> QuadMesh:
    """Read an OBJ, PLY or OFF file into a validated :class:`QuadMesh` (tags from OBJ ``t`` lines).

    With ``split`` a mesh with non-quad faces is refined once into quads (see
    :meth:`QuadMesh.from_arrays`); without, such a mesh raises :class:`MeshError`.
    ``sharp_angle`` (degrees): tag the edges whose faces' normals differ by more than that as
    infinitely sharp, and vertices with three such edges as corners, before splitting
    (:func:`g1patch.sharpen.sharp_angle_tags`); the file's own tags are kept. ``strict``: refuse
    a mesh that needs repair instead of repairing it (:meth:`QuadMesh.from_arrays`).
    """
    path = Path(path)
    suffix = path.suffix.lower()
    readers = {".obj": _read_obj, ".ply": _read_ply, ".off": _read_off}
    if suffix not in readers:
        raise FormatError(
            path,
            f"unsupported extension {path.suffix!r}; expected one of {', '.join(READ_FORMATS)}",
        )
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise FormatError(path, f"cannot read the file ({exc.strerror or exc})") from None
    if not data or data.isspace():
        raise FormatError(path, "the file is empty")
    parsed = readers[suffix](path, data)
    tags = parsed.tags
    if sharp_angle is not None:
        tags = tags + _sharp_angle_tags(path, parsed, sharp_angle)
    return QuadMesh.from_arrays(
        parsed.vertices, parsed.faces, split=split, source=str(path), tags=tags, strict=strict
    )


def _sharp_angle_tags(path: Path, parsed: _Parsed, degrees: float) -> tuple[Tag, ...]:
    """The ``--sharp-angle`` tags of a parsed file, on its own polygons (index errors are left to
    the mesh checks)."""
    from ..mesh import _as_polygons
    from ..sharpen import sharp_angle_tags

    corners, sizes = _as_polygons(parsed.faces)
    vertices = np.asarray(parsed.vertices, dtype=np.float64)
    if (
        sizes.size == 0
        or corners.size == 0
        or corners.min() < 0
        or corners.max() >= len(vertices)
        or not np.isfinite(vertices).all()
    ):
        return ()
    return sharp_angle_tags(vertices, corners, sizes, degrees)


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


# -- vectorised text parsing -------------------------------------------------------------------
#
# The text readers first try a fast path: the whole file is normalised by bytes operations (comments
# cut, CR LF and tabs made LF and spaces, runs of spaces made one, no space at a line's ends), its
# lines located and their tokens counted with NumPy, and each kind of line (``v``, ``f``, an OFF
# vertex or face) converted in bulk. It never raises: on anything it does not handle exactly as the
# line-by-line parser does (non-ASCII text, a token it does not convert the same way, any error in
# the file) it returns None, and the line-by-line parser reads the file again, so every result and
# every message is that parser's.

# : bytes ``str.splitlines`` or ``str.split`` treat as line breaks or spaces; the fast path declines
# a file with one
_ODD_BYTES = (b"\x0b", b"\x0c", b"\x1c", b"\x1d", b"\x1e", b"\x1f")
_SPACES = re.compile(rb" {2,}")
_EDGE_SPACE = re.compile(rb"(?m)^ | $")
_SLASHED = re.compile(rb"/[^ \n]*")


class _Lines(NamedTuple):
    """A normalised text and its lines: line ``i`` is ``text[starts[i]:ends[i]]``, line ``i + 1`` of
    the file."""

    text: bytes
    array: NDArray[np.uint8]
    starts: NDArray[np.int64]
    ends: NDArray[np.int64]
    tokens: NDArray[np.int64]

    def byte(self, column: int) -> NDArray[np.uint8]:
        """Byte ``column`` of every line (0 where the line is shorter)."""
        if self.array.size == 0:
            return np.zeros(self.starts.size, dtype=np.uint8)
        at = np.minimum(self.starts + column, self.array.size - 1)
        return np.where(self.ends - self.starts > column, self.array[at], 0).astype(np.uint8)

    def chunk(self, rows: NDArray[np.int64]) -> bytes:
        """The text of lines ``rows`` (increasing), one per line: consecutive lines are sliced at
        once."""
        if rows.size == 0:
            return b""
        breaks = np.flatnonzero(np.diff(rows) != 1) + 1
        first, last = rows[np.r_[0, breaks]], rows[np.r_[breaks - 1, rows.size - 1]]
        text = self.text
        return b"\n".join(
            [text[s:e] for s, e in zip(self.starts[first].tolist(), self.ends[last].tolist())]
        )


def _scan(data: bytes) -> _Lines | None:
    """``data`` normalised and split into lines, or None if it is not plain ASCII text."""
    if not data.isascii() or any(odd in data for odd in _ODD_BYTES):
        return None
    text = data
    if b"\r" in text:  # CR LF or a lone CR ends a line, as for str.splitlines
        text = text.replace(b"\r\n", b"\n").replace(b"\r", b"\n")
    if b"#" in text:
        text = _uncommented(text)
    if b"\t" in text:
        text = text.replace(b"\t", b" ")
    separators = _separators(text)
    if separators is None:
        return None
    # a run of spaces, or a space at either end of a line (two-byte searches are slow: found here)
    adjacent = np.flatnonzero(np.diff(separators) == 1)
    array = np.frombuffer(text, dtype=np.uint8)
    messy = (array[separators[adjacent]] == ord(" ")) | (
        array[separators[adjacent + 1]] == ord(" ")
    )
    if messy.any() or text.startswith(b" ") or text.endswith(b" "):
        text = _EDGE_SPACE.sub(b"", _SPACES.sub(b" ", text))
        array, separators = np.frombuffer(text, dtype=np.uint8), _separators(text)
    newlines = np.flatnonzero(array[separators] == ord("\n"))
    ends = separators[newlines]
    if text and not text.endswith(b"\n"):
        ends, newlines = np.append(ends, len(text)), np.append(newlines, separators.size)
    starts = np.concatenate(([0], ends[:-1] + 1)).astype(np.int64)
    spaces = (
        np.diff(newlines, prepend=-1) - 1
    )  # separators between a line's end and the previous one's
    return _Lines(
        text, array, starts, ends.astype(np.int64), np.where(ends > starts, spaces + 1, 0)
    )


def _separators(text: bytes) -> NDArray[np.int64] | None:
    """Where ``text`` (no tab or CR) has a space or LF; None if it has another control byte, which
    ``str.split`` does not split at."""
    array = np.frombuffer(text, dtype=np.uint8)
    separators = np.flatnonzero(array <= ord(" "))
    kinds = array[separators]
    return None if ((kinds != ord(" ")) & (kinds != ord("\n"))).any() else separators


def _uncommented(text: bytes) -> bytes:
    """``text`` with each ``#`` and the rest of its line cut (lines end in LF)."""
    parts, at = [], 0
    while (mark := text.find(b"#", at)) >= 0:
        parts.append(text[at:mark])
        at = text.find(b"\n", mark)
        if at < 0:
            return b"".join(parts)
    parts.append(text[at:])
    return b"".join(parts)


def _gather_floats(
    text: bytes, counts: NDArray[np.int64], columns: Sequence[int]
) -> NDArray[np.float64] | None:
    """Tokens ``columns`` of each line of ``text`` (``counts`` tokens each) as floats, converted as
    ``float`` converts them; None if one is not a number."""
    tokens = np.array(text.split(), dtype=object)
    if tokens.size != counts.sum():
        return None
    offsets = np.cumsum(counts) - counts
    try:
        return tokens[offsets[:, None] + np.asarray(columns)].astype(np.float64)
    except (ValueError, OverflowError, TypeError):
        return None


#: the bytes a line of numbers may hold besides its keyword, and those that may follow a sign
_NUMBER_BYTES = {
    np.int64: (b"0123456789+- \n", b"0123456789"),
    np.float64: (b"0123456789.eE+- \n", b"0123456789."),
}


def _numbers(
    text: bytes, keyword: bytes, count: int, dtype: type[np.int64] | type[np.float64]
) -> NDArray | None:
    """The ``count`` numbers of ``text`` (lines of ``keyword`` then numbers), each token converted
    as ``int`` or ``float`` converts it, by one ``np.fromstring`` (floats from :data:`KERNEL_BYTES`
    on, without a keyword: :func:`_floats_compiled`); None where ``text`` holds anything else, or a
    token that ``np.fromstring`` might read otherwise."""
    if dtype is np.float64 and not keyword and len(text) >= KERNEL_BYTES:
        return _floats_compiled(text, count)
    allowed, after_sign = _NUMBER_BYTES[dtype]
    if text.translate(None, allowed).replace(keyword, b"") != b"":
        return None
    if (
        b"-" in text or b"+" in text
    ):  # numpy reads a lone sign at the end as 0; int and float refuse it
        array = np.frombuffer(text, dtype=np.uint8)
        signs = np.flatnonzero((array == ord("-")) | (array == ord("+")))
        if (
            signs[-1] + 1 == array.size
            or not np.isin(array[signs + 1], np.frombuffer(after_sign, dtype=np.uint8)).all()
        ):
            return None
    try:
        values = np.fromstring(
            text.replace(keyword, b" ") if keyword else text, dtype=dtype, sep=" "
        )
    except ValueError:  # a token it cannot read; a token it reads as two numbers changes the count
        return None
    return values if values.size == count else None


# -- OBJ ---------------------------------------------------------------------------------------


def _read_obj(path: Path, data: bytes) -> _Parsed:
    """OBJ: ``v x y z [w]``; ``f a b c …`` with ``a`` = ``v``, ``v/vt``, ``v//vn`` or ``v/vt/vn``.

    Indices are 1-based; negative ones count back from the last vertex defined so far. Read by
    :func:`_obj_compiled` (from :data:`KERNEL_BYTES` on) or :func:`_obj_fast`, or line by line
    (:func:`_read_obj_lines`) where it declines.
    """
    parsed = _obj_compiled(data) if len(data) >= KERNEL_BYTES else _obj_fast(data)
    return parsed if parsed is not None else _read_obj_lines(path, data)


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
        line = face_lines[
            int(
                np.searchsorted(
                    np.cumsum(face_sizes), np.flatnonzero(written == 0)[0], side="right"
                )
            )
        ]
        raise FormatError(path, "vertex index 0 in a face; OBJ indices start at 1", line)
    # 1-based; negative indices count back from the last vertex defined before the face
    corners = np.where(
        written > 0, written - 1, np.repeat(vertices_before_face, face_sizes) + written
    )
    _faces_in_range(path, corners, face_sizes, points.shape[0], np.array(face_lines))
    return _Parsed(points, _polygon_list(corners, face_sizes), tuple(tags))


def _convert(
    path: Path, tokens: list, dtype: type, expected: str, lines: Sequence[int] | NDArray[np.int64]
) -> NDArray:
    """``np.array(tokens, dtype)``; on a bad token, a :class:`FormatError` naming its line
    (``lines`` per row)."""
    try:
        return np.array(tokens, dtype=dtype)
    except (ValueError, OverflowError):
        for row, line in zip(tokens, lines):
            try:
                np.array(row, dtype=dtype)
            except (ValueError, OverflowError):
                text = row if isinstance(row, str) else " ".join(row)
                raise FormatError(path, f"expected {expected}, got {text!r}", int(line)) from None
        raise


def _parse_tag(path: Path, parts: Sequence[str], line: int) -> Tag:
    """OpenSubdiv ``t name nints/nfloats/nstrings ints… floats… strings…`` (integers 0-based)."""
    usage = "expected 't name nints/nfloats/nstrings ints... floats... strings...'"
    if len(parts) < 3:
        raise FormatError(path, usage, line)
    counts = parts[2].split("/")
    if len(counts) != 3 or not all(c.isdigit() for c in counts):
        raise FormatError(path, f"{usage}; got counts {parts[2]!r}", line)
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
    except ValueError:
        raise FormatError(
            path, f"tag {parts[1]!r}: expected {n_ints} integers then {n_floats} numbers", line
        ) from None
    return Tag(parts[1], ints, floats, tuple(values[n_ints + n_floats :]))


# -- compiled readers --------------------------------------------------------------------------
#
# From KERNEL_BYTES on, OBJ text is read by one numba kernel that scans the bytes once: ``v`` lines'
# first three numbers are converted as they are met (Eisel–Lemire: correctly rounded, as float();
# a number it cannot settle, or spelt otherwise, is left to float()), ``f`` lines' indices (the
# part before a '/') resolved, ``vt`` / ``vn`` / ``vp`` skipped, and every other statement handed
# back as a span for Python to read (tags, skipped statements, unknown keywords). The coordinates
# of OFF and ASCII PLY (``_numbers``) are converted by the same code. As the NumPy fast paths,
# they never raise: on anything else they decline and the line-by-line parser reads the file.

#: OBJ files, and OFF / ASCII PLY coordinates, of at least this many bytes are read by the kernels
#: (their first use, on a fresh install, compiles them: see benchmarks/bench_readers.py)
KERNEL_BYTES = 2 << 20
#: helpers the kernels call, compiled (and rebound) with the first kernel
_KERNEL_HELPERS = ("_product", "_decimal", "_number")
#: the sign bit of a float64, as int64
_SIGN_BIT = -(2**63)


@cache
def _powers_of_five() -> NDArray[np.uint64]:
    """``5^q`` for q in -342..308 as 128-bit significands (high, low word), the top bit set:
    truncated for q ≥ 0, rounded up for q < 0 (the table of Lemire's fast_float)."""
    words = []
    for q in range(-342, 309):
        if q >= 0:
            value = 5**q
            value <<= max(0, 128 - value.bit_length())
            value >>= max(0, value.bit_length() - 128)
        else:
            power = 5**-q
            z = power.bit_length()
            value = (1 << (z + 127 if q >= -27 else 2 * z + 128)) // power + 1
            value >>= max(0, value.bit_length() - 128)
        words += [value >> 64, value & (2**64 - 1)]
    return np.array(words, dtype=np.uint64)


def _product(a: np.uint64, b: np.uint64) -> tuple[np.uint64, np.uint64]:
    """The 128-bit product ``a b`` as (high, low) 64-bit words."""
    low32, shift = np.uint64(0xFFFFFFFF), np.uint64(32)
    a0, a1, b0, b1 = a & low32, a >> shift, b & low32, b >> shift
    p00, p01, p10, p11 = a0 * b0, a0 * b1, a1 * b0, a1 * b1
    middle = p10 + (p00 >> shift) + (p01 & low32)
    return p11 + (middle >> shift) + (p01 >> shift), (middle << shift) | (p00 & low32)


def _decimal(w: np.uint64, q: int, powers: NDArray[np.uint64]) -> int:
    """The float64 bits of ``w · 10^q`` (``0 < w < 10^19``), correctly rounded (Eisel–Lemire,
    as fast_float), or -1 where it cannot tell, the result is subnormal or infinite."""
    if q < -342 or q > 308:
        return -1
    one, ones = np.uint64(1), np.uint64(0xFFFFFFFFFFFFFFFF)
    lz = 0
    for shift in (32, 16, 8, 4, 2, 1):  # normalise: the top bit set
        if w < one << np.uint64(64 - shift):
            w <<= np.uint64(shift)
            lz += shift
    index = 2 * (q + 342)
    high, low = _product(w, powers[index])
    if high & np.uint64(0x1FF) == np.uint64(
        0x1FF
    ):  # the 55 bits needed may carry: the next 64 bits of 5^q
        high2, _ = _product(w, powers[index + 1])
        low += high2
        if high2 > low:
            high += one
    if low == ones and (q < -27 or q > 55):
        return -1
    upper = np.int64(high >> np.uint64(63))
    mantissa = high >> np.uint64(upper + 9)
    power2 = ((217706 * q) >> 16) + 63 + upper - lz + 1023
    if power2 <= 0:
        return -1
    if (
        low <= one
        and -4 <= q <= 23
        and mantissa & np.uint64(3) == one
        and (mantissa << np.uint64(upper + 9)) == high
    ):
        mantissa &= ~one  # exactly halfway: to even
    mantissa += mantissa & one
    mantissa >>= one
    if mantissa >= np.uint64(2) << np.uint64(52):
        mantissa = one << np.uint64(52)
        power2 += 1
    if power2 >= 0x7FF:
        return -1
    return np.int64(
        (mantissa & ~(one << np.uint64(52))) | (np.uint64(power2) << np.uint64(52))
    )  # int64 as every return


def _number(
    data: NDArray[np.uint8], classes: NDArray[np.uint8], first: int, powers: NDArray[np.uint64]
) -> tuple[int, int]:
    """The float64 bits (as int64) of the token at ``first`` and where it ends, read in one pass: a
    token spelt ``[+-]digits[.digits][(e|E)[+-]digits]`` (or ``.digits``) correctly rounded as
    ``float`` rounds it; -1 for any other spelling, more than 19 significant digits, or a number
    :func:`_decimal` cannot settle: ``float`` must convert it."""
    n, at, negative = data.size, first, False
    if data[at] == 43 or data[at] == 45:
        negative = data[at] == 45
        at += 1
    w, digits, fraction, seen = np.uint64(0), 0, 0, False
    while at < n and 48 <= data[at] <= 57:
        seen = True
        if w != np.uint64(0) or data[at] != 48:  # leading zeros are not significant
            w = w * np.uint64(10) + np.uint64(data[at] - 48)
            digits += 1
        at += 1
    if at < n and data[at] == 46:
        at += 1
        while at < n and 48 <= data[at] <= 57:
            seen = True
            fraction += 1
            if w != np.uint64(0) or data[at] != 48:
                w = w * np.uint64(10) + np.uint64(data[at] - 48)
                digits += 1
            at += 1
    exponent = 0
    if seen and at < n and (data[at] == 101 or data[at] == 69):
        at += 1
        sign = 1
        if at < n and (data[at] == 43 or data[at] == 45):
            sign = -1 if data[at] == 45 else 1
            at += 1
        seen = at < n and 48 <= data[at] <= 57
        while at < n and 48 <= data[at] <= 57:
            exponent = min(exponent * 10 + data[at] - 48, 100_000)
            at += 1
        exponent *= sign
    if at < n and classes[data[at]] == _TOKEN:  # more of the token: another spelling
        seen = False
        while at < n and classes[data[at]] == _TOKEN:
            at += 1
    if not seen or digits > 19:
        return -1, at
    bits = 0 if w == np.uint64(0) else _decimal(w, exponent - fraction, powers)
    return (
        -1 if bits < 0 else bits | (_SIGN_BIT if negative else 0)
    ), at  # -1: a NaN's bits, never a number's


#: byte classes of the OBJ kernel: 0 a token's, 1 space or tab, 2 LF or CR, 3 '#', 4 any other (not
#: ASCII, a control byte, or one ``str.splitlines`` breaks at): the kernel declines the file
_TOKEN, _SPACE, _BREAK, _HASH, _ODD = range(5)
_BYTE_CLASSES = np.full(256, _ODD, dtype=np.uint8)
_BYTE_CLASSES[33:128] = _TOKEN
_BYTE_CLASSES[[ord(" "), ord("\t")]] = _SPACE
_BYTE_CLASSES[[ord("\n"), ord("\r")]] = _BREAK
_BYTE_CLASSES[ord("#")] = _HASH


def _obj_kernel(
    data: NDArray[np.uint8],
    classes: NDArray[np.uint8],
    powers: NDArray[np.uint64],
    points: NDArray[np.uint64],
    corners: NDArray[np.int64],
    sizes: NDArray[np.int64],
    hard: NDArray[np.int64],
    others: NDArray[np.int64],
) -> tuple[bool, int, int, int, int, int]:
    """Scan OBJ bytes once into the arrays given; returns ``valid`` and the items found:
    coordinates, faces, corners, hard numbers, other lines (those beyond an array's length are
    counted, not written). ``points``: float64 bits, x y z per vertex (0 where hard); ``corners``
    (0-based, resolved) and ``sizes`` of the faces; ``hard``: (start, end, slot in points) of each
    number left to ``float``; ``others``: (start, end) of each line of another statement, comment
    cut. Not ``valid`` (a byte of class 4, or anything the line-by-line parser reports): that parser
    reads the file."""
    n = data.size
    n_points = n_faces = n_corners = n_hard = n_others = 0
    i, valid = 0, True
    while i < n and valid:
        while i < n and classes[data[i]] == _SPACE:
            i += 1
        start = i
        while i < n and classes[data[i]] == _TOKEN:  # the keyword
            i += 1
        keyword = i - start
        kind = 0  # 1: v, 2: f, 3: vt/vn/vp, 4: other
        if keyword == 1 and data[start] == 118:
            kind = 1
        elif keyword == 1 and data[start] == 102:
            kind = 2
        elif (
            keyword == 2
            and data[start] == 118
            and (data[start + 1] == 116 or data[start + 1] == 110 or data[start + 1] == 112)
        ):
            kind = 3
        elif keyword > 0:
            kind = 4
        tokens = 0
        while True:  # the tokens after the keyword, up to a comment or the end of the line
            while i < n and classes[data[i]] == _SPACE:
                i += 1
            if i >= n or classes[data[i]] != _TOKEN:
                break
            first = i
            tokens += 1
            if kind == 1 and tokens <= 3:
                bits, i = _number(data, classes, first, powers)
                if bits == -1:
                    if n_hard < hard.shape[0]:
                        hard[n_hard, 0], hard[n_hard, 1], hard[n_hard, 2] = (
                            first,
                            i,
                            n_points + tokens - 1,
                        )
                    n_hard += 1
                    bits = 0
                if n_points + 3 <= points.size:
                    points[n_points + tokens - 1] = np.uint64(bits)
                continue
            while i < n and classes[data[i]] == _TOKEN:
                i += 1
            if kind == 2:
                at, negative, value = first, False, 0
                if data[at] == 43 or data[at] == 45:
                    negative = data[at] == 45
                    at += 1
                end = at
                while end < i and data[end] != 47:  # the index: up to a '/'
                    end += 1
                valid = at < end <= at + 18
                while valid and at < end:
                    valid = 48 <= data[at] <= 57
                    value = value * 10 + data[at] - 48
                    at += 1
                if not valid or value == 0:
                    valid = False
                    break
                if n_corners < corners.size:
                    corners[n_corners] = n_points // 3 - value if negative else value - 1
                n_corners += 1
        if i < n and classes[data[i]] == _HASH:  # a comment
            while i < n and classes[data[i]] != _BREAK:
                valid = valid and classes[data[i]] != _ODD
                i += 1
        if i < n and classes[data[i]] == _ODD:
            valid = False
        if kind == 1:
            valid = valid and 4 <= tokens + 1 <= 8
            n_points += 3
        elif kind == 2:
            valid = valid and tokens >= 3
            if n_faces < sizes.size:
                sizes[n_faces] = tokens
            n_faces += 1
        elif kind == 4:
            if n_others < others.shape[0]:
                others[n_others, 0], others[n_others, 1] = start, i
            n_others += 1
        i += 1  # the line break (CR LF: the LF ends an empty line)
    return valid, n_points, n_faces, n_corners, n_hard, n_others


def _floats_kernel(
    data: NDArray[np.uint8],
    classes: NDArray[np.uint8],
    powers: NDArray[np.uint64],
    out: NDArray[np.uint64],
    hard: NDArray[np.int64],
) -> tuple[bool, int, int]:
    """The numbers of a text of numbers separated by spaces and line breaks, by :func:`_number`,
    into ``out`` (float64 bits; 0 where hard): returns ``valid`` (no byte but a number's, a space or
    a line break), the numbers and the hard ones found (those beyond ``out`` or ``hard`` counted,
    not written); ``hard``: (start, end, slot in out) of each number left to ``float``."""
    n, count, n_hard, i = data.size, 0, 0, 0
    while i < n:
        kind = classes[data[i]]
        if kind == _SPACE or kind == _BREAK:
            i += 1
            continue
        if kind != _TOKEN:
            return False, count, n_hard
        first = i
        bits, i = _number(data, classes, first, powers)
        if bits == -1:
            if n_hard < hard.shape[0]:
                hard[n_hard, 0], hard[n_hard, 1], hard[n_hard, 2] = first, i, count
            n_hard += 1
            bits = 0
        if count < out.size:
            out[count] = np.uint64(bits)
        count += 1
    return True, count, n_hard


@cache
def _compiled(kernel: Callable[..., tuple]) -> Callable[..., tuple]:
    """``kernel`` compiled by :func:`~g1patch.kernels.jit_kernel`, the helpers first."""
    from ..kernels import jit_kernel  # numba, imported on first use

    for name in _KERNEL_HELPERS:
        if not hasattr(globals()[name], "py_func"):
            globals()[name] = jit_kernel(globals()[name])
    return jit_kernel(kernel)  # type: ignore[return-value]


def _floats_compiled(text: bytes, count: int) -> NDArray[np.float64] | None:
    """The ``count`` numbers of ``text`` (numbers, spaces, line breaks) converted as ``float``
    converts them, by :func:`_floats_kernel`; None if it holds anything else or another count. As
    :func:`_numbers`, a token of other bytes than ``0-9 . e E + -`` is refused, not given to
    ``float``."""
    buffer, kernel, n_hard = np.frombuffer(text, dtype=np.uint8), _compiled(_floats_kernel), 1024
    out = np.empty(count, dtype=np.uint64)
    while True:
        hard = np.empty((n_hard, 3), dtype=np.int64)
        valid, found, n_hard = kernel(buffer, _BYTE_CLASSES, _powers_of_five(), out, hard)
        if not valid or found != count or n_hard <= len(hard):
            break
    if not valid or found != count:
        return None
    values = out.view(np.float64)
    for start, end, slot in hard[:n_hard].tolist():
        token = text[start:end]
        if token.translate(None, b"0123456789.eE+-"):
            return None
        try:
            values[slot] = float(token)
        except ValueError:
            return None
    return values


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
        if not valid or all(count <= len(array) for count, array in zip(found, arrays)):
            break
    if not valid or found[2] == 0:
        return None
    points, corners, sizes, hard, others = (array[:count] for array, count in zip(arrays, found))
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


# -- OFF ---------------------------------------------------------------------------------------

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
    if n_vertices < 0 or n_faces <= 0 or body.size < n_vertices + n_faces:
        return None
    vertex_rows, face_rows = body[:n_vertices], body[n_vertices : n_vertices + n_faces]
    vertex_tokens, face_tokens = lines.tokens[vertex_rows], lines.tokens[face_rows]
    if (vertex_tokens < 3).any():
        return None
    text = lines.chunk(vertex_rows)
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
    content = [
        (number, parts)
        for number, line in enumerate(_decode(path, data), start=1)
        if (parts := line.split("#", 1)[0].split())
    ]
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
            path, "expected the counts 'n_vertices n_faces n_edges'", counts_line
        ) from None
    if len(body) < n_vertices + n_faces:
        last = content[-1][0]
        raise FormatError(
            path,
            f"truncated: the header announces {n_vertices} vertices and {n_faces} faces, the file "
            "ends first",
            last,
        )

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
            corners = [int(x) for x in parts[1 : 1 + size]]
            if size < 3 or len(corners) != size:
                raise ValueError
        except ValueError:
            expected = "expected a face 'n i_1 ... i_n' with n >= 3"
            raise FormatError(path, f"{expected}, got {' '.join(parts)!r}", number) from None
        faces.append(corners)
    sizes = np.fromiter(map(len, faces), dtype=np.int64, count=len(faces))
    if sizes.size == 0:
        raise FormatError(path, "no faces: the header announces 0 faces", counts_line)
    corners = np.fromiter(
        (i for face in faces for i in face), dtype=np.int64, count=int(sizes.sum())
    )
    _faces_in_range(path, corners, sizes, n_vertices, np.array([number for number, _ in face_rows]))
    return _Parsed(points, _polygon_list(corners, sizes))


# -- PLY ---------------------------------------------------------------------------------------


class _PlyHeader(NamedTuple):
    ascii: bool
    elements: list[tuple[str, int]]
    lines: int


def _ply_header(path: Path, data: bytes) -> _PlyHeader:
    end = data.find(b"end_header")
    if not data.startswith(b"ply") or end < 0:
        raise FormatError(path, "expected a PLY header: 'ply' ... 'end_header'", 1)
    try:
        header = data[:end].decode("ascii").splitlines()
    except UnicodeDecodeError:
        raise FormatError(path, "the PLY header is not ASCII text") from None
    elements = []
    for number, line in enumerate(header, start=1):
        parts = line.split()
        if parts[:1] == ["element"]:
            if len(parts) != 3 or not parts[2].isdigit():
                raise FormatError(
                    path, f"expected 'element name count', got {line.strip()!r}", number
                )
            elements.append((parts[1], int(parts[2])))
    return _PlyHeader("format ascii" in data[:end].decode("ascii"), elements, len(header) + 1)


def _read_ply(path: Path, data: bytes) -> _Parsed:
    """PLY of the common layout as NumPy records (binary, :func:`_ply_records`) or parsed as OBJ
    and OFF are (ASCII, :func:`_ply_text`), any other through ``meshio.ply``, the vertex and face
    counts checked against the header."""
    header = _ply_header(path, data)
    counts = dict(header.elements)
    if counts.get("face", 0) == 0:
        raise FormatError(path, "no faces: the header declares no 'element face'")
    records = _ply_text(data) if header.ascii else _ply_records(data)
    if records is not None:
        points, corners, sizes = records
        vertex_lines = face_lines = None
    else:
        points, corners, sizes, vertex_lines, face_lines = _ply_meshio(path, header)
    _finite_vertices(path, points, vertex_lines)
    _faces_in_range(path, corners, sizes, points.shape[0], face_lines)
    return _Parsed(points, _polygon_list(corners, sizes))


#: PLY scalar types as NumPy codes (without the byte order), those of meshio's binary reader as it
#: maps them (``uchar`` signed), so that a file reads the same by either path
_PLY_TYPES = {
    "uchar": "i1",
    "uint": "u4",
    "uint8": "u1",
    "uint16": "u2",
    "uint32": "u4",
    "uint64": "u8",
    "int": "i4",
    "int8": "i1",
    "int32": "i4",
    "int64": "i8",
    "float": "f4",
    "float32": "f4",
    "double": "f8",
}
_PLY_ORDER = {"format binary_little_endian 1.0": "<", "format binary_big_endian 1.0": ">"}


class _PlyLayout(NamedTuple):
    """A PLY file of the common layout: one vertex element of scalar properties with x, y, z, then
    one face element of one list ``vertex_indices``; ``start``: the first byte after the header."""

    format: str
    n_vertices: int
    vertex_properties: list[tuple[str, str]]  # (type, name)
    n_faces: int
    count_type: str
    index_type: str
    start: int


def _ply_layout(data: bytes) -> _PlyLayout | None:
    """The layout of a PLY file whose header :func:`_ply_header` accepted, None if it is not the
    common one."""
    end = data.find(b"end_header")  # the header is ASCII before it
    lines = [line.strip() for line in data[:end].decode("ascii").splitlines()]
    if data[end : end + 11] != b"end_header\n" or len(lines) < 2 or lines[0] != "ply":
        return None
    elements: list[tuple[str, int, list[list[str]]]] = []
    for line in lines[2:]:
        parts = line.split()
        if parts[:1] == ["element"]:
            elements.append((parts[1], int(parts[2]), []))
        elif parts[:1] == ["property"] and elements:
            elements[-1][2].append(parts[1:])
        elif parts[:1] not in (["comment"], ["obj_info"]):
            return None
    if [name for name, _, _ in elements] != ["vertex", "face"]:
        return None
    (_, n_vertices, vertex_properties), (_, n_faces, face_properties) = elements
    names = [p[-1] for p in vertex_properties]
    if (
        any(len(p) != 2 for p in vertex_properties)
        or len(set(names)) != len(names)
        or not {"x", "y", "z"} <= set(names)
        or len(face_properties) != 1
        or len(face_properties[0]) != 4
        or face_properties[0][0] != "list"
        or face_properties[0][3] != "vertex_indices"
    ):
        return None
    count_type, index_type = face_properties[0][1:3]
    return _PlyLayout(
        lines[1],
        n_vertices,
        [(p[0], p[1]) for p in vertex_properties],
        n_faces,
        count_type,
        index_type,
        end + 11,
    )


def _ply_records(
    data: bytes,
) -> tuple[NDArray[np.float64], NDArray[np.int64], NDArray[np.int64]] | None:
    """Points, corners and sizes of a binary PLY file of the common layout (:func:`_ply_layout`),
    every face with as many corners and nothing after them, read as NumPy records; None for any
    other file."""
    layout = _ply_layout(data)
    if layout is None or layout.format not in _PLY_ORDER:
        return None
    order = _PLY_ORDER[layout.format]
    kinds = [kind for kind, _ in layout.vertex_properties] + [layout.count_type, layout.index_type]
    if not set(kinds) <= _PLY_TYPES.keys() or {
        _PLY_TYPES[layout.count_type][0],
        _PLY_TYPES[layout.index_type][0],
    } & {"f"}:
        return None
    vertex_type = np.dtype(
        [(name, order + _PLY_TYPES[kind]) for kind, name in layout.vertex_properties]
    )
    count_type, index_type = (
        np.dtype(order + _PLY_TYPES[kind]) for kind in (layout.count_type, layout.index_type)
    )
    faces_start = layout.start + layout.n_vertices * vertex_type.itemsize
    if len(data) < faces_start + count_type.itemsize:
        return None
    corners = int(np.frombuffer(data, count_type, 1, faces_start)[0])
    face_type = np.dtype([("n", count_type), ("i", index_type, (max(corners, 0),))])
    if corners < 3 or len(data) != faces_start + layout.n_faces * face_type.itemsize:
        return None
    faces = np.frombuffer(data, face_type, layout.n_faces, faces_start)
    if (faces["n"] != corners).any():
        return None
    vertices = np.frombuffer(data, vertex_type, layout.n_vertices, layout.start)
    points = np.stack([vertices[axis].astype(np.float64) for axis in "xyz"], axis=1)
    return (
        points,
        faces["i"].astype(np.int64).ravel(),
        np.full(layout.n_faces, corners, dtype=np.int64),
    )


#: the PLY types of an ASCII file's faces the fast path reads (meshio's integer ones)
_PLY_ASCII_INTEGERS = frozenset(
    {"uchar", "uint8", "uint16", "uint", "uint32", "int", "int8", "int32", "int64", "uint64"}
)


def _ply_text(
    data: bytes,
) -> tuple[NDArray[np.float64], NDArray[np.int64], NDArray[np.int64]] | None:
    """Points, corners and sizes of an ASCII PLY file of the common layout (:func:`_ply_layout`)
    with x, y, z first and every vertex property ``double``, one line per vertex then per face
    with exactly its numbers, no blank line or comment among them: parsed as the OBJ and OFF text
    is; None for any other file (meshio reads it)."""
    layout = _ply_layout(data)
    if (
        layout is None
        or layout.format != "format ascii 1.0"
        or [name for _, name in layout.vertex_properties[:3]] != ["x", "y", "z"]
        or any(kind not in ("double", "float64") for kind, _ in layout.vertex_properties)
        or not {layout.count_type, layout.index_type} <= _PLY_ASCII_INTEGERS
    ):
        return None
    body = data[layout.start :]
    lines = (
        None if b"#" in body or b"\r" in body else _scan(body)
    )  # meshio: '#' starts a comment, only LF ends a line
    n_vertices, n_faces, width = layout.n_vertices, layout.n_faces, len(layout.vertex_properties)
    if lines is None or lines.tokens.size < n_vertices + n_faces:
        return None
    vertex_tokens, face_tokens = (
        lines.tokens[:n_vertices],
        lines.tokens[n_vertices : n_vertices + n_faces],
    )
    if (vertex_tokens != width).any() or (face_tokens == 0).any():
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
    if (sizes < 3).any() or (sizes > 127).any() or corners.min() < 0 or corners.max() >= n_vertices:
        return None
    return np.ascontiguousarray(points), corners, sizes


def _ply_meshio(
    path: Path, header: _PlyHeader
) -> tuple[
    NDArray[np.float64],
    NDArray[np.int64],
    NDArray[np.int64],
    NDArray[np.int64] | None,
    NDArray[np.int64] | None,
]:
    """Points, corners, sizes and, for an ASCII file of vertices then faces, the vertices' and
    faces' lines, read by ``meshio.ply``."""
    counts = dict(header.elements)
    try:
        with (
            warnings.catch_warnings()
        ):  # numbers beyond the declared type: the finite-coordinate check names them
            warnings.simplefilter("ignore", RuntimeWarning)
            mesh = meshio.ply.read(str(path))
    except (
        meshio.ReadError,
        ValueError,
        OverflowError,
        IndexError,
        KeyError,
        TypeError,
        AssertionError,
        EOFError,
    ) as exc:
        # one line, whatever the library wrote
        reason = f"{type(exc).__name__}: {' '.join(str(exc).split())}"
        raise FormatError(
            path, f"cannot read the PLY data, truncated or malformed ({reason})"
        ) from None
    points = np.asarray(mesh.points, dtype=np.float64)
    polygon_types = ("triangle", "quad", "polygon")
    blocks = [
        np.asarray(block.data, dtype=np.int64)
        for block in mesh.cells
        if block.type in polygon_types
    ]
    sizes = np.repeat(
        [b.shape[1] if b.ndim == 2 else 0 for b in blocks], [len(b) for b in blocks]
    ).astype(np.int64)
    if points.shape != (counts.get("vertex", 0), 3) or sizes.size != counts["face"]:
        raise FormatError(
            path,
            f"truncated or malformed: the header announces {counts.get('vertex', 0)} vertices (x, "
            "y, z) and "
            f"{counts['face']} faces, meshio read {points.shape[0]} vertices and {sizes.size} "
            "faces",
        )
    # for an ASCII file with vertices then faces, one element per line after the header
    in_order = header.ascii and [name for name, _ in header.elements] == ["vertex", "face"]
    vertex_lines = header.lines + 1 + np.arange(points.shape[0]) if in_order else None
    face_lines = header.lines + 1 + points.shape[0] + np.arange(sizes.size) if in_order else None
    return points, np.concatenate([b.ravel() for b in blocks]), sizes, vertex_lines, face_lines


# -- writing -----------------------------------------------------------------------------------


def _write_format(path: Path) -> str:
    suffix = path.suffix.lower()
    if suffix not in WRITE_FORMATS:
        expected = ", ".join(WRITE_FORMATS)
        raise FormatError(
            path, f"unsupported extension {path.suffix!r} for writing; expected one of {expected}"
        )
    return suffix


def _checked_points(name: str, points: ArrayLike) -> NDArray[np.float64]:
    array = as_float_array(name, points, (3,))
    if array.ndim != 2:
        raise InputError(f"{name}: expected shape (n, 3), got {array.shape}")
    return array


def _checked_cells(name: str, cells: ArrayLike, corners: int, n_points: int) -> NDArray[np.int64]:
    table = as_index_array(name, cells, (corners,))
    if table.ndim != 2:
        raise InputError(f"{name}: expected shape (n, {corners}), got {table.shape}")
    bad = np.flatnonzero(((table < 0) | (table >= n_points)).any(axis=1))
    if bad.size:
        row = tuple(table[bad[0]].tolist())
        raise InputError(f"{name}: row {bad[0]} {row} names a point outside 0..{n_points - 1}")
    return table


#: rows formatted per string in OBJ output (bounds the text held in memory to a few MB)
_OBJ_ROWS = 1 << 15


def _write_obj(path: Path, points: NDArray[np.float64], cells: NDArray[np.int64]) -> None:
    """OBJ text as meshio writes it (``v x y z`` with the shortest round-trip digits, ``f`` with
    1-based indices), formatted a block of rows at a time by one C-level ``%`` per block: several
    times faster than meshio's line-by-line loop, and in bounded memory."""
    vertex_row = "v %r %r %r\n"
    face_row = "f" + " %d" * cells.shape[1] + "\n"
    with open(path, "w", encoding="ascii", newline="\n") as handle:
        handle.write("# written by g1patch\n")
        for start in range(0, len(points), _OBJ_ROWS):
            block = points[start : start + _OBJ_ROWS]
            handle.write((vertex_row * len(block)) % tuple(block.ravel().tolist()))
        for start in range(0, len(cells), _OBJ_ROWS):
            block = cells[start : start + _OBJ_ROWS] + 1
            handle.write((face_row * len(block)) % tuple(block.ravel().tolist()))


_STL_RECORD = np.dtype([("normal", "<f4", (3,)), ("points", "<f4", (3, 3)), ("attr", "<u2")])


def _write_stl(path: Path, points: NDArray[np.float64], triangles: NDArray[np.int64]) -> None:
    """Binary STL as meshio writes it (unit facet normals, float32), a block of triangles at a time
    so that memory does not grow by the 100 bytes a triangle of meshio's whole-array records; a
    triangle without area gets the normal 0 (meshio: NaN)."""
    header = b"binary STL written by g1patch"
    with open(path, "wb") as handle:
        handle.write(header + b" " * (80 - len(header)))
        handle.write(np.array(len(triangles), dtype="<u4").tobytes())
        for start in range(0, len(triangles), _OBJ_ROWS):
            corners = points[triangles[start : start + _OBJ_ROWS]]
            normals = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
            length = np.sqrt(np.einsum("ij,ij->i", normals, normals))[:, None]
            records = np.zeros(len(corners), dtype=_STL_RECORD)
            records["normal"] = np.divide(
                normals, length, out=np.zeros_like(normals), where=length > 0
            )
            records["points"] = corners
            handle.write(records.tobytes())


def _write(
    path: Path, suffix: str, points: NDArray[np.float64], cell_type: str, cells: NDArray[np.int64]
) -> None:
    if suffix in (".obj", ".stl"):
        writer = _write_obj if suffix == ".obj" else _write_stl
        with atomic_path(path) as temporary:
            writer(temporary, points, cells)
        return
    index_type = (
        np.int32 if cells.size == 0 or cells.max() < 2**31 else np.int64
    )  # PLY wants 32-bit indices
    mesh = meshio.Mesh(points, [(cell_type, cells.astype(index_type))])
    with atomic_path(path) as temporary:
        meshio.ply.write(str(temporary), mesh, binary=True)


def write_triangles(path: PathLike, points: ArrayLike, triangles: ArrayLike) -> None:
    """Write a triangle mesh, ``points`` (n, 3) and ``triangles`` (m, 3), as OBJ, PLY or STL (by
    extension)."""
    path = Path(path)
    suffix = _write_format(path)
    points = _checked_points("points", points)
    _write(
        path, suffix, points, "triangle", _checked_cells("triangles", triangles, 3, points.shape[0])
    )


def write_quads(path: PathLike, vertices: ArrayLike, faces: ArrayLike) -> None:
    """Write a quad mesh as OBJ or PLY, or as STL with each quad (a, b, c, d) split into (a, b, c),
    (a, c, d)."""
    path = Path(path)
    suffix = _write_format(path)
    vertices = _checked_points("vertices", vertices)
    quads = _checked_cells("faces", faces, 4, vertices.shape[0])
    if suffix == ".stl":
        _write(path, suffix, vertices, "triangle", quads[:, [0, 1, 2, 0, 2, 3]].reshape(-1, 3))
    else:
        _write(path, suffix, vertices, "quad", quads)
