"""Binary PLY of the common layout (:class:`~.ply._PlyLayout`), read as NumPy records.

Faces with as many corners each are one structured ``np.frombuffer`` (:func:`_ply_records`).
Otherwise the faces are walked (:func:`_face_walk`): each face's corner count says where the next
one starts, so the walk is sequential, but it is taken a run at a time: where a face has ``c``
corners, the counts of the next ``k`` faces of ``c`` corners are read at once through a strided
view and compared, ``k`` doubling while they agree. Meshes of few corner counts in long runs
(meshio writes one block per count) take a few dozen NumPy calls; alternating counts cost one
Python step a face, as meshio's own walk does.

Every count is checked before it is used: a negative one, one below 3, one whose indices run past
the end of the file, and bytes after the last face are errors naming the face, the byte and the
limit.
"""

from __future__ import annotations

from pathlib import Path
from typing import Literal, NamedTuple

import numpy as np
from numpy.typing import NDArray

from ...errors import FormatError
from .ply_header import MIN_CORNERS, PLY_TYPES, _PlyHeader, _PlyLayout

#: the most faces one strided comparison of the walk reads
_MAX_RUN = 1 << 22


class _FaceRecord(NamedTuple):
    """The byte layout of one face: ``prefix`` bytes of scalars, the count, the indices,
    ``suffix`` bytes of scalars; with a texcoord list (``uv``: its count and value types),
    ``middle`` bytes of scalars, its count and 2 values a corner come before the suffix."""

    prefix: int
    length: np.dtype
    item: np.dtype
    suffix: int
    length_name: str
    item_name: str
    order: Literal["little", "big"]
    uv: tuple[np.dtype, np.dtype] | None = None
    middle: int = 0

    def size(self, corners: int) -> int:
        uv = 0 if self.uv is None else self.uv[0].itemsize + 2 * corners * self.uv[1].itemsize
        own = self.prefix + self.length.itemsize + corners * self.item.itemsize + self.suffix
        return own + self.middle + uv


def _face_record(layout: _PlyLayout, order: str) -> _FaceRecord:
    properties = layout.face.properties
    sizes = [np.dtype(PLY_TYPES[p.type]).itemsize for p in properties]
    corners = properties[layout.corners]
    assert corners.length is not None  # the layout's list
    end, uv, middle = len(properties), None, 0
    if layout.texcoord is not None:  # after the corners' list (the layout's rule)
        texcoord = properties[layout.texcoord]
        assert texcoord.length is not None
        count_type = np.dtype(order + PLY_TYPES[texcoord.length])
        uv = (count_type, np.dtype(order + PLY_TYPES[texcoord.type]))
        middle, end = sum(sizes[layout.corners + 1 : layout.texcoord]), layout.texcoord
    return _FaceRecord(
        sum(sizes[: layout.corners]),
        np.dtype(order + PLY_TYPES[corners.length]),
        np.dtype(order + PLY_TYPES[corners.type]),
        sum(sizes[layout.corners + 1 : end]) if uv is None else sum(sizes[end + 1 :]),
        corners.length,
        corners.type,
        "little" if order == "<" else "big",
        uv,
        middle,
    )


#: points, corners, sizes and texture coordinates (per vertex (V, 2), or per face corner with a
#: ``texcoord`` list (C, 2); None without)
_Records = tuple[
    NDArray[np.float64], NDArray[np.int64], NDArray[np.int64], NDArray[np.float64] | None
]


def _ply_binary(path: Path, data: bytes, header: _PlyHeader, layout: _PlyLayout) -> _Records:
    """Points, corners, sizes and UVs of a binary PLY file of the common layout whose element
    counts :func:`~.ply._check_room` found room for: :func:`_ply_records`, else the walk (which
    does not read a ``texcoord`` list: a file with one whose faces differ in size is refused)."""
    records = _ply_records(data, header, layout)
    if records is not None:
        return records
    order = "<" if header.format == "binary_little_endian" else ">"
    face = _face_record(layout, order)
    if face.uv is not None:
        raise FormatError(
            path,
            "a binary 'texcoord' face list is read only where every face has as many corners "
            "and 2 texture coordinates a corner (use per-vertex s, t, or an ASCII file)",
        )
    points, uv, start = _vertices(data, header, layout, order)
    sizes, starts = _face_walk(path, data, start, layout.face.size, face)
    return points, _gather(data, start, sizes, starts, face), sizes, uv


def _vertices(
    data: bytes, header: _PlyHeader, layout: _PlyLayout, order: str
) -> tuple[NDArray[np.float64], NDArray[np.float64] | None, int]:
    """The vertices' x, y, z as float64, their texture coordinates (V, 2) (None without) and the
    byte after the last vertex."""
    vertex_type = np.dtype([(p.name, order + PLY_TYPES[p.type]) for p in layout.vertex.properties])
    vertices = np.frombuffer(data, vertex_type, layout.vertex.size, header.start)
    with np.errstate(invalid="ignore"):  # a signalling NaN: the finite-coordinate check names it
        points = np.stack([vertices[axis].astype(np.float64) for axis in "xyz"], axis=1)
        names = [] if layout.uv is None else [layout.vertex.properties[k].name for k in layout.uv]
        uv = np.stack([vertices[n].astype(np.float64) for n in names], 1) if names else None
    return points, uv, header.start + layout.vertex.size * vertex_type.itemsize


def _ply_records(data: bytes, header: _PlyHeader, layout: _PlyLayout) -> _Records | None:
    """Points, corners, sizes and UVs of a binary PLY file of the common layout with every face of
    as many corners (and, with a ``texcoord`` list, 2 values a corner) and nothing after them,
    read as NumPy records; None for any other file."""
    if header.ascii:
        return None
    order = "<" if header.format == "binary_little_endian" else ">"
    face = _face_record(layout, order)
    vertex_bytes = sum(np.dtype(PLY_TYPES[p.type]).itemsize for p in layout.vertex.properties)
    faces_start = header.start + layout.vertex.size * vertex_bytes
    n_faces, first = layout.face.size, faces_start + face.prefix
    if len(data) < first + face.length.itemsize:
        return None
    corners = int(np.frombuffer(data, face.length, 1, first)[0])
    if corners < MIN_CORNERS or len(data) != faces_start + n_faces * face.size(corners):
        return None  # checked against the file's size first: no record of 4e9 corners is made
    fields: list[tuple[str, np.dtype] | tuple[str, np.dtype, tuple[int]]] = [
        ("n", face.length),
        ("i", face.item, (corners,)),
    ]
    if face.prefix:
        fields.insert(0, ("p", np.dtype(f"V{face.prefix}")))
    if face.middle:
        fields.append(("m", np.dtype(f"V{face.middle}")))
    if face.uv is not None:
        fields += [("tn", face.uv[0]), ("t", face.uv[1], (2 * corners,))]
    if face.suffix:
        fields.append(("s", np.dtype(f"V{face.suffix}")))
    faces = np.frombuffer(data, np.dtype(fields), n_faces, faces_start)
    if (faces["n"] != corners).any():
        return None
    if face.uv is not None and (faces["tn"] != 2 * corners).any():
        return None
    points, uv, _ = _vertices(data, header, layout, order)
    if face.uv is not None:
        uv = faces["t"].astype(np.float64).reshape(-1, 2)
    return (
        points,
        faces["i"].astype(np.int64).ravel(),
        np.full(n_faces, corners, dtype=np.int64),
        uv,
    )


def _face_walk(
    path: Path, data: bytes, at: int, n_faces: int, face: _FaceRecord
) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
    """The corner count and the first byte of each of the ``n_faces`` faces from byte ``at``
    (module docstring); :class:`FormatError` on a count that is negative, below 3 or runs past the
    end, or on bytes after the last face."""
    sizes = np.empty(n_faces, dtype=np.int64)
    starts = np.empty(n_faces, dtype=np.int64)
    end, done, probe = len(data), 0, 1
    signed = face.length.kind == "i"
    width = face.length.itemsize
    while done < n_faces:
        where = at + face.prefix
        if where + width > end:
            raise FormatError(
                path,
                f"truncated: face {done} of the {n_faces} the header announces starts at byte "
                f"{at}, the file ends at byte {end}",
            )
        corners = int.from_bytes(data[where : where + width], face.order, signed=signed)
        step = face.size(corners)
        if corners < MIN_CORNERS or at + step > end:
            raise _count_error(path, done, corners, where, step, end - at, face)
        run = min(probe, n_faces - done, (end - at) // step)
        if run > 1:
            counts = np.ndarray((run,), face.length, data, where, (step,))
            different = np.flatnonzero(counts != corners)
            run, probe = (int(different[0]), 1) if different.size else (run, min(2 * run, _MAX_RUN))
        else:
            probe = 2
        sizes[done : done + run] = corners
        starts[done : done + run] = at + step * np.arange(run)
        done, at = done + run, at + step * run
    if at != end:
        raise FormatError(
            path,
            f"{end - at} bytes after the last of the {n_faces} faces the header announces (from "
            f"byte {at} on); the file must end there",
        )
    return sizes, starts


def _count_error(
    path: Path, face: int, corners: int, where: int, step: int, left: int, record: _FaceRecord
) -> FormatError:
    """The error of face ``face``'s corner count ``corners`` (read at byte ``where``)."""
    if corners < 0:
        return FormatError(
            path, f"face {face} has a negative corner count {corners} (at byte {where})"
        )
    if corners < MIN_CORNERS:
        return FormatError(
            path,
            f"face {face} has {corners} corners (at byte {where}); a face needs at least "
            f"{MIN_CORNERS}",
        )
    return FormatError(
        path,
        f"truncated: face {face} announces {corners} corners (its {record.length_name} count at "
        f"byte {where}), {step} bytes with its {record.item_name} indices, but only {left} bytes "
        "remain",
    )


def _gather(
    data: bytes,
    start: int,
    sizes: NDArray[np.int64],
    starts: NDArray[np.int64],
    face: _FaceRecord,
) -> NDArray[np.int64]:
    """The faces' indices in order, as int64: every byte of the faces' region that is no index
    (the scalars before and after the list, its count) cut out, the rest read as indices."""
    size = int(starts[-1] - start) + face.size(int(sizes[-1]))
    region = np.frombuffer(data, np.uint8, size, start)
    keep = np.ones(size, dtype=bool)
    head = face.prefix + face.length.itemsize
    keep[((starts - start)[:, None] + np.arange(head)).ravel()] = False
    if face.suffix:
        ends = starts - start + head + sizes * face.item.itemsize
        keep[(ends[:, None] + np.arange(face.suffix)).ravel()] = False
    return region[keep].view(face.item).astype(np.int64)
