"""The PLY header, parsed and checked line by line (:func:`_ply_header`), the room its element
counts need checked against the bytes after it (:func:`_check_room`), and the common layout
g1patch reads itself (:func:`_ply_layout`)."""

from __future__ import annotations

from pathlib import Path
from typing import NamedTuple

import numpy as np

from ...errors import FormatError
from .source import MAX_COUNT_DIGITS, room_error

#: PLY scalar types as NumPy codes without the byte order: the PLY names and their sized aliases
#: (``int64`` / ``uint64``: meshio's)
PLY_TYPES = {
    "char": "i1",
    "int8": "i1",
    "uchar": "u1",
    "uint8": "u1",
    "short": "i2",
    "int16": "i2",
    "ushort": "u2",
    "uint16": "u2",
    "int": "i4",
    "int32": "i4",
    "uint": "u4",
    "uint32": "u4",
    "float": "f4",
    "float32": "f4",
    "double": "f8",
    "float64": "f8",
    "int64": "i8",
    "uint64": "u8",
}
PLY_FORMATS = ("ascii", "binary_little_endian", "binary_big_endian")
#: the names of a face's list of vertex indices
FACE_LISTS = ("vertex_indices", "vertex_index")
#: the fewest corners a face may have: what the header check counts per face
MIN_CORNERS = 3
#: per-vertex texture coordinate properties, the first pair a vertex has wins
UV_PROPERTIES = (("s", "t"), ("u", "v"), ("texture_u", "texture_v"), ("texture_s", "texture_t"))
#: the per-face list of texture coordinates (u₁ v₁ … uₙ vₙ, one pair per corner)
TEXCOORD = "texcoord"


class _Property(NamedTuple):
    """A scalar property (``length`` None) or a list (``length``: the type of its length)."""

    name: str
    type: str
    length: str | None = None


class _Element(NamedTuple):
    name: str
    size: int
    line: int  # the header line announcing it
    properties: tuple[_Property, ...]


class _PlyHeader(NamedTuple):
    format: str  # one of PLY_FORMATS
    elements: tuple[_Element, ...]
    lines: int  # lines of the header, ``end_header`` included
    start: int  # the first byte after the header

    @property
    def ascii(self) -> bool:
        return self.format == "ascii"

    def total(self, name: str) -> int:
        return sum(element.size for element in self.elements if element.name == name)


def _ply_header(path: Path, data: bytes) -> _PlyHeader:
    """The header of a PLY file, every line checked: ``ply``, one ``format``, ``element NAME
    COUNT`` (a count ≥ 0), ``property TYPE NAME`` or ``property list COUNT_TYPE TYPE NAME`` of
    known types, ``comment`` / ``obj_info``, ``end_header``; else :class:`FormatError` naming the
    line."""
    end = data.find(b"end_header")
    if not data.startswith(b"ply") or end < 0:
        raise FormatError(path, "expected a PLY header: 'ply' ... 'end_header'", 1)
    try:
        lines = data[:end].decode("ascii").splitlines()
    except UnicodeDecodeError:
        raise FormatError(path, "the PLY header is not ASCII text") from None
    if lines[0].strip() != "ply":
        raise FormatError(path, "expected a PLY header: 'ply' ... 'end_header'", 1)
    newline = data.find(b"\n", end)
    start = len(data) if newline < 0 else newline + 1
    form: str | None = None
    elements: list[_Element] = []
    for number, line in enumerate(lines[1:], start=2):
        parts = line.split()
        keyword = parts[0] if parts else ""
        if keyword in ("", "comment", "obj_info"):
            continue
        if keyword == "format" and form is None and not elements:
            if len(parts) != 3 or parts[1] not in PLY_FORMATS or parts[2] != "1.0":
                raise FormatError(
                    path,
                    f"unsupported PLY format {line.strip()[:60]!r}; expected 'format ascii 1.0', "
                    "'format binary_little_endian 1.0' or 'format binary_big_endian 1.0'",
                    number,
                )
            form = parts[1]
        elif keyword == "element" and form is not None:
            if len(parts) != 3 or not parts[2].isdigit() or len(parts[2]) > MAX_COUNT_DIGITS:
                raise FormatError(
                    path,
                    f"expected 'element name count' (a count of at most {MAX_COUNT_DIGITS} "
                    f"digits), got {line.strip()[:60]!r}",
                    number,
                )
            elements.append(_Element(parts[1], int(parts[2]), number, ()))
        elif keyword == "property" and elements:
            count, values = None, parts[1:]
            if values[:1] == ["list"] and len(values) == 4:
                count, values = values[1], values[2:]
            if len(values) != 2 or values[0] not in PLY_TYPES or (count or "int") not in PLY_TYPES:
                raise FormatError(
                    path,
                    "expected 'property TYPE NAME' or 'property list COUNT_TYPE TYPE NAME' of "
                    f"the PLY types ({', '.join(PLY_TYPES)}), got {line.strip()[:60]!r}",
                    number,
                )
            if count is not None and PLY_TYPES[count][0] == "f":
                raise FormatError(path, f"a list's length must be an integer type: {count}", number)
            property_ = _Property(values[1], values[0], count)
            last = elements[-1]
            elements[-1] = last._replace(properties=(*last.properties, property_))
        else:
            raise FormatError(
                path,
                f"unexpected PLY header line {line.strip()[:60]!r} (expected "
                f"{'format' if form is None else 'element, property, comment'} or end_header)",
                number,
            )
    if form is None:
        raise FormatError(path, "the PLY header has no 'format' line", len(lines) + 1)
    return _PlyHeader(form, tuple(elements), len(lines) + 1, start)


def _least_bytes(element: _Element, ascii: bool) -> int:
    """The fewest bytes one ``element`` takes in the body: binary, its scalars' sizes and each
    list's count (with :data:`MIN_CORNERS` indices for a face's vertex list); ASCII, two bytes (a
    digit, then a space or a line break) a number."""
    numbers = size = 0
    for property_ in element.properties:
        corners = MIN_CORNERS if element.name == "face" and property_.name in FACE_LISTS else 0
        item = np.dtype(PLY_TYPES[property_.type]).itemsize
        if property_.length is None:
            numbers, size = numbers + 1, size + item
        else:
            count = np.dtype(PLY_TYPES[property_.length]).itemsize
            numbers, size = numbers + 1 + corners, size + count + corners * item
    return 2 * numbers if ascii else size


def _check_room(path: Path, header: _PlyHeader, data: bytes) -> None:
    """Refuse a header whose elements cannot fit in the bytes after it (:func:`_least_bytes`
    each), before anything is allocated by their counts. ASCII: the last line may lack its line
    break."""
    have, slack = len(data) - header.start, 1 if header.ascii else 0
    need = 0
    for element in header.elements:
        each = _least_bytes(element, header.ascii)
        before, need = need, need + element.size * each
        if need > have + slack:
            after = f" (after {before} for the elements before them)" if before else ""
            what = f"'{element.name}' elements"
            raise room_error(path, element.line, element.size, what, each, need, have, after)


class _PlyLayout(NamedTuple):
    """A PLY file of the common layout: one vertex element of scalar properties with x, y, z, then
    one face element of scalars and one list of vertex indices (:data:`FACE_LISTS`), and maybe a
    float list :data:`TEXCOORD` after it. ``uv``: the vertex properties of the texture
    coordinates (:data:`UV_PROPERTIES`), None without."""

    vertex: _Element
    face: _Element
    corners: int  # the position of the list among the face's properties
    uv: tuple[int, int] | None = None
    texcoord: int | None = None  # the position of the texcoord list


def _ply_layout(header: _PlyHeader) -> _PlyLayout | None:
    """The common layout of ``header``, None for any other."""
    if [element.name for element in header.elements] != ["vertex", "face"]:
        return None
    vertex, face = header.elements
    names = [p.name for p in vertex.properties]
    lists = [k for k, p in enumerate(face.properties) if p.length is not None]
    texcoord = None
    if len(lists) == 2 and face.properties[lists[1]].name == TEXCOORD:
        texcoord = lists.pop()
    if (
        any(p.length is not None for p in vertex.properties)
        or len(set(names)) != len(names)
        or not {"x", "y", "z"} <= set(names)
        or len(lists) != 1
        or face.properties[lists[0]].name not in FACE_LISTS
        or PLY_TYPES[face.properties[lists[0]].type][0] == "f"
        or (texcoord is not None and PLY_TYPES[face.properties[texcoord].type][0] != "f")
    ):
        return None
    pair = next((pair for pair in UV_PROPERTIES if set(pair) <= set(names)), None)
    uv = None if pair is None else (names.index(pair[0]), names.index(pair[1]))
    return _PlyLayout(vertex, face, lists[0], uv, texcoord)
