"""STL, what scanners and CAD systems write: triangles with their own copies of the corners, in
binary (80-byte header, a little-endian ``uint32`` count, 50 bytes per triangle: normal, three
corners as ``float32``, a 2-byte attribute) or ASCII (``solid`` … ``facet normal`` … ``outer loop``
``vertex x y z`` × 3 ``endloop endfacet`` … ``endsolid``). A file is binary when its size is exactly
what its count announces (an ASCII file whose header happens to say so is not), else it must be
ASCII. Corners with the same coordinates become one vertex (STL repeats them bit for bit), so the
triangles share edges as the surface does; the stored normals are not used (the triangles'
winding is)."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from ...errors import FormatError
from .parsed import _Parsed

#: bytes of the binary header and count, and of one triangle record
_HEADER, _RECORD = 84, 50
_TRIANGLE = np.dtype([("normal", "<f4", (3,)), ("corners", "<f4", (3, 3)), ("attribute", "<u2")])
_VERTEX = re.compile(rb"vertex[ \t]+(\S+)[ \t]+(\S+)[ \t]+(\S+)")


def _read_stl(path: Path, data: bytes) -> _Parsed:
    """The triangles of a binary or ASCII STL file, corners welded (module docstring)."""
    if len(data) >= _HEADER:
        count = int(np.frombuffer(data, "<u4", 1, 80)[0])
        if len(data) == _HEADER + _RECORD * count:
            if not count:
                raise FormatError(path, "no faces: the binary STL announces 0 triangles")
            records = np.frombuffer(data, _TRIANGLE, count, _HEADER)
            return _welded(records["corners"].astype(np.float64).reshape(-1, 3))
    if not data.lstrip().startswith(b"solid"):
        announced = (
            f"; as binary STL its count announces {count:,} triangles "
            f"({_HEADER + _RECORD * count:,} bytes), the file has {len(data):,}"
            if len(data) >= _HEADER
            else ""
        )
        raise FormatError(path, f"neither binary STL nor ASCII STL ('solid …'){announced}")
    found = _VERTEX.findall(data)
    if not found:
        raise FormatError(path, "no faces: the ASCII STL has no 'vertex' lines")
    if len(found) % 3:
        raise FormatError(
            path, f"{len(found):,} 'vertex' lines: not three per facet (the last facet is cut)"
        )
    try:
        corners = np.array(found, dtype=np.float64)
    except ValueError:
        match = next(m for m in _VERTEX.finditer(data) if not _numbers(m.groups()))
        line = data.count(b"\n", 0, match.start()) + 1
        text = match.group(0).decode("ascii", "replace")
        raise FormatError(path, f"a vertex is not three numbers: {text!r}", line) from None
    return _welded(corners)


def _numbers(row: tuple[bytes, ...]) -> bool:
    try:
        [float(value) for value in row]
    except ValueError:
        return False
    return True


def _welded(corners: np.ndarray) -> _Parsed:
    """Triangles from their corners (3 T, 3): equal coordinates become one vertex."""
    vertices, triangles = np.unique(corners, axis=0, return_inverse=True)
    return _Parsed(vertices, triangles.reshape(-1, 3).astype(np.int64))
