"""Quad mesh files: read OBJ / PLY / OFF into a :class:`QuadMesh`; write triangles or quads as OBJ /
PLY / STL.

* OBJ is read by a small parser of its own (``v``, ``f``, OpenSubdiv ``t`` tag lines; other OBJ
  statements are skipped, unknown ones are errors) so that every error names its line and mixed
  polygon lists keep their order. Texture coordinates (``vt``, with faces ``v/vt`` or
  ``v/vt/vn``) are read by a pass of their own that runs only on files that have them
  (:func:`~g1patch.io.meshfile.obj._obj_uvs`), as one UV per face corner; so are the face groups
  (``usemtl`` materials, else ``g``/``o`` names; colours from the ``mtllib`` files' ``Kd``:
  :mod:`~g1patch.io.meshfile.obj_groups`).
* PLY: files of the common layout (x, y, z and other scalars per vertex, scalars and one list of
  vertex indices per face) are read here, binary as NumPy records, ASCII as OBJ and OFF text is;
  any other by meshio (``meshio.ply``), after checking the header here: meshio silently returns
  fewer faces from a truncated binary file.
* OFF is read by a parser of its own: meshio's OFF reader only accepts triangles.

OBJ and OFF text is parsed in bulk by NumPy over the whole file, and from :data:`KERNEL_BYTES` on
by numba kernels (OBJ in one scan; the coordinates of OFF and ASCII PLY); only where a fast path
declines (anything unusual, any error) is the file read again line by line, by the reference
parser whose results and line-numbered messages the fast paths reproduce exactly.

Nothing a file says is trusted (:mod:`~g1patch.io.meshfile.source`): only a regular file is read
(links resolved: never ``/dev/zero`` or a FIFO), of at most :data:`MAX_INPUT_BYTES` (2 GB) or the
caller's ``max_input_size``; every count in a header is checked against the bytes that follow it
before anything is allocated by it, and lines or bytes beyond a header's counts are an error
naming the line. A UTF-8 byte-order mark before the text is skipped.

Every problem with a file raises :class:`FormatError` (file, line where known, what was expected);
problems with the mesh it describes raise the :class:`MeshError` family, prefixed with the file
name. Writes go through :func:`atomic_path`: an error never leaves a partial file. OBJ and STL are
written here, a block of rows at a time (several times faster than meshio and in bounded
memory), binary PLY by meshio.

The package's modules: :mod:`~g1patch.io.meshfile.obj`, :mod:`~g1patch.io.meshfile.ply` and
:mod:`~g1patch.io.meshfile.off` read one format each, on the shared fast paths of
:mod:`~g1patch.io.meshfile.text` (NumPy) and :mod:`~g1patch.io.meshfile.compiled` (numba) and the
checks of :mod:`~g1patch.io.meshfile.parsed` (PLY in :mod:`~g1patch.io.meshfile.ply_header`,
:mod:`~g1patch.io.meshfile.ply_binary` and :mod:`~g1patch.io.meshfile.ply_ascii` too);
:mod:`~g1patch.io.meshfile.source` reads the bytes; :mod:`~g1patch.io.meshfile.write` writes.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from ...errors import FormatError
from ...mesh import QuadMesh, Tag
from .compiled import KERNEL_BYTES as KERNEL_BYTES
from .compiled import _floats_compiled as _floats_compiled
from .obj import OBJ_SKIPPED as OBJ_SKIPPED
from .obj import _obj_compiled as _obj_compiled
from .obj import _obj_fast as _obj_fast
from .obj import _read_obj
from .obj import _read_obj_lines as _read_obj_lines
from .off import OFF_HEADERS as OFF_HEADERS
from .off import _off_fast as _off_fast
from .off import _read_off
from .off import _read_off_lines as _read_off_lines
from .parsed import _Parsed
from .ply import _ply_meshio as _ply_meshio
from .ply import _read_ply
from .ply_ascii import _ply_text as _ply_text
from .ply_ascii import _read_ply_lines as _read_ply_lines
from .ply_binary import _ply_records as _ply_records
from .ply_header import _ply_header as _ply_header
from .ply_header import _ply_layout as _ply_layout
from .source import BOM, read_input
from .source import MAX_INPUT_BYTES as MAX_INPUT_BYTES
from .source import check_input as check_input
from .stl import _read_stl
from .text import _numbers as _numbers
from .write import WRITE_FORMATS, PathLike, write_quads, write_triangles

__all__ = [
    "read_mesh",
    "read_polygons",
    "read_tagged_polygons",
    "write_triangles",
    "write_quads",
    "check_input",
    "READ_FORMATS",
    "WRITE_FORMATS",
    "MAX_INPUT_BYTES",
]

READ_FORMATS = (".obj", ".ply", ".off", ".stl")


def read_mesh(
    path: PathLike,
    *,
    split: bool = True,
    sharp_angle: float | None = None,
    strict: bool | None = None,
    max_input_size: int | None = None,
) -> QuadMesh:
    """Read an OBJ, PLY or OFF file into a validated :class:`QuadMesh` (tags from OBJ ``t`` lines).

    With ``split`` a mesh with non-quad faces is refined once into quads (see
    :meth:`QuadMesh.from_arrays`); without, such a mesh raises :class:`MeshError`.
    ``sharp_angle`` (degrees): tag the edges whose faces' normals differ by more than that as
    infinitely sharp, and vertices with three such edges as corners, before splitting
    (:func:`g1patch.sharpen.sharp_angle_tags`); the file's own tags are kept. ``strict``: refuse
    a mesh that needs repair instead of repairing it (:meth:`QuadMesh.from_arrays`).
    ``max_input_size`` (bytes; default :data:`MAX_INPUT_BYTES`, 2 GB): a larger file is refused
    before it is read, as is anything but a regular file (:func:`check_input`).
    """
    path = Path(path)
    parsed = _parse(path, max_input_size)
    tags = parsed.tags
    if sharp_angle is not None:
        tags = tags + _sharp_angle_tags(path, parsed, sharp_angle)
    return QuadMesh.from_arrays(
        parsed.vertices,
        parsed.faces,
        split=split,
        source=str(path),
        tags=tags,
        strict=strict,
        uv=parsed.uv,
        groups=parsed.groups,
    )


def _parse(path: Path, max_input_size: int | None) -> _Parsed:
    """The file's vertices, faces and tags as its reader parses them (by its extension)."""
    suffix = path.suffix.lower()
    readers = {".obj": _read_obj, ".ply": _read_ply, ".off": _read_off, ".stl": _read_stl}
    if suffix not in readers:
        raise FormatError(
            path,
            f"unsupported extension {path.suffix!r}; expected one of {', '.join(READ_FORMATS)}",
        )
    data = read_input(path, max_input_size).removeprefix(BOM)
    if not data or data.isspace():
        raise FormatError(path, "the file is empty")
    return readers[suffix](path, data)


def read_polygons(
    path: PathLike, *, max_input_size: int | None = None
) -> tuple[NDArray[np.float64], NDArray[np.int64], NDArray[np.int64]]:
    """A mesh file's polygons as they are, without splitting or repairing them: ``(points (V, 3),
    corners, sizes)`` (flat corner indices, corners per face), checked as :func:`read_mesh`
    checks what no repair mends (finite positions, indices in range, ≥ 3 corners): what a scan
    to fit is read as (:func:`g1patch.fit`), at a fraction of a quad mesh's memory."""
    from ...errors import named_errors
    from ...mesh.validate import _checked_polygons

    path = Path(path)
    parsed = _parse(path, max_input_size)
    with named_errors(str(path)):
        return _checked_polygons(parsed.vertices, parsed.faces, ())


def read_tagged_polygons(
    path: PathLike, *, max_input_size: int | None = None
) -> tuple[NDArray[np.float64], NDArray[np.int64], NDArray[np.int64], tuple[Tag, ...]]:
    """:func:`read_polygons` and the file's own tags (OBJ ``t`` lines: creases, corners, …),
    checked against its polygons: what a ``--layout`` file is read as."""
    from ...errors import named_errors
    from ...mesh.validate import _checked_polygons

    path = Path(path)
    parsed = _parse(path, max_input_size)
    with named_errors(str(path)):
        points, corners, sizes = _checked_polygons(parsed.vertices, parsed.faces, parsed.tags)
    return points, corners, sizes, tuple(parsed.tags)


def _sharp_angle_tags(path: Path, parsed: _Parsed, degrees: float) -> tuple[Tag, ...]:
    """The ``--sharp-angle`` tags of a parsed file, on its own polygons (index errors are left to
    the mesh checks)."""
    from ...mesh import _as_polygons
    from ...sharpen import sharp_angle_tags

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
