"""Writing triangle and quad meshes as OBJ, PLY or STL: OBJ and STL written here, a block of
rows at a time (several times faster than meshio and in bounded memory), binary PLY by meshio;
every write through :func:`~g1patch.io.atomic.atomic_path`."""

from __future__ import annotations

import os
from pathlib import Path

import meshio
import numpy as np
from numpy.typing import ArrayLike, NDArray

from ...errors import FormatError, InputError, as_float_array, as_index_array
from ...mesh.groups import FaceGroups
from ..atomic import atomic_path

WRITE_FORMATS = (".obj", ".ply", ".stl")

PathLike = str | os.PathLike[str]


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


def _write_obj(
    path: Path,
    points: NDArray[np.float64],
    cells: NDArray[np.int64],
    uv: NDArray[np.float64] | None = None,
    uv_cells: NDArray[np.int64] | None = None,
    groups: FaceGroups | None = None,
) -> None:
    """OBJ text as meshio writes it (``v x y z`` with the shortest round-trip digits, ``f`` with
    1-based indices), formatted a block of rows at a time by one C-level ``%`` per block: several
    times faster than meshio's line-by-line loop, and in bounded memory. With ``uv`` and
    ``uv_cells``: ``vt u v`` lines too, and faces ``f a/x b/y c/z``. With ``groups`` (one per
    cell): the cells sorted by group (stably), those without one first, each group's led by
    ``g NAME`` and ``usemtl NAME`` (no ``mtllib``: the materials are names only)."""
    vertex_row = "v %r %r %r\n"
    with_uv = uv is not None and uv_cells is not None
    face_row = "f" + (" %d/%d" if with_uv else " %d") * cells.shape[1] + "\n"
    with open(path, "w", encoding="ascii", newline="\n") as handle:
        handle.write("# written by g1patch\n")
        for start in range(0, len(points), _OBJ_ROWS):
            block = points[start : start + _OBJ_ROWS]
            handle.write((vertex_row * len(block)) % tuple(block.ravel().tolist()))
        if uv is not None and uv_cells is not None:
            for start in range(0, len(uv), _OBJ_ROWS):
                block = uv[start : start + _OBJ_ROWS]
                handle.write(("vt %r %r\n" * len(block)) % tuple(block.ravel().tolist()))
        runs = [(0, len(cells), "")]
        if groups is not None:
            order = np.argsort(groups.ids, kind="stable")
            cells = cells[order]
            uv_cells = None if uv_cells is None else uv_cells[order]
            ids = groups.ids[order]
            starts = np.flatnonzero(np.r_[True, ids[1:] != ids[:-1]])
            ends = np.r_[starts[1:], len(ids)]
            names = [groups.names[i] if i >= 0 else "" for i in ids[starts].tolist()]
            runs = [
                (a, b, f"g {name}\nusemtl {name}\n" if name else "")
                for a, b, name in zip(starts.tolist(), ends.tolist(), names, strict=True)
            ]
        for first, last, header in runs:
            handle.write(header)
            for start in range(first, last, _OBJ_ROWS):
                stop = min(start + _OBJ_ROWS, last)
                rows = cells[start:stop] + 1
                if uv_cells is not None and with_uv:
                    rows = np.stack([rows, uv_cells[start:stop] + 1], axis=-1)
                handle.write((face_row * len(rows)) % tuple(rows.ravel().tolist()))


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
    mesh = meshio.Mesh(points, [(cell_type, cells.astype(_index_type(cells)))])
    with atomic_path(path) as temporary:
        meshio.ply.write(str(temporary), mesh, binary=True)


def _index_type(cells: NDArray[np.int64]) -> type:
    """int32 where the indices fit (PLY wants 32-bit indices), else int64."""
    return np.int32 if cells.size == 0 or cells.max() < 2**31 else np.int64


def write_triangles(
    path: PathLike,
    points: ArrayLike,
    triangles: ArrayLike,
    *,
    uv: ArrayLike | None = None,
    uv_triangles: ArrayLike | None = None,
    groups: FaceGroups | None = None,
) -> None:
    """Write a triangle mesh, ``points`` (n, 3) and ``triangles`` (m, 3), as OBJ, PLY or STL (by
    extension).

    Texture coordinates, face-varying: ``uv`` (k, 2) and ``uv_triangles`` (m, 3), the UV vertex
    of every triangle corner. OBJ writes them as ``vt`` with faces ``f a/x b/y c/z`` (the points
    stay welded); PLY as vertex properties ``s``, ``t``, one vertex per distinct (point, UV) pair
    of the corners (split where UVs differ: at seams in UV space); STL has no place for them.
    Face groups, ``groups`` (one per triangle): OBJ writes ``g``/``usemtl`` per group
    (:func:`_write_obj`); PLY and STL have no place for them.
    """
    path = Path(path)
    suffix = _write_format(path)
    points = _checked_points("points", points)
    cells = _checked_cells("triangles", triangles, 3, points.shape[0])
    if groups is not None and len(groups) != len(cells):
        raise InputError(f"groups: expected one per triangle ({len(cells)}), got {len(groups)}")
    obj_groups = groups if suffix == ".obj" else None
    if (uv is None or uv_triangles is None or suffix == ".stl") and obj_groups is None:
        _write(path, suffix, points, "triangle", cells)
        return
    if uv is None or uv_triangles is None:
        with atomic_path(path) as temporary:
            _write_obj(temporary, points, cells, groups=obj_groups)
        return
    uv = as_float_array("uv", uv, (2,))
    uv_cells = _checked_cells("uv_triangles", uv_triangles, 3, uv.shape[0])
    if uv_cells.shape != cells.shape:
        raise InputError(
            f"uv_triangles: expected shape {cells.shape} (one per triangle corner), got "
            f"{uv_cells.shape}"
        )
    if suffix == ".obj":
        with atomic_path(path) as temporary:
            _write_obj(temporary, points, cells, uv, uv_cells, obj_groups)
        return
    # PLY: one vertex per distinct (point, UV vertex) pair
    pairs = cells.reshape(-1) * np.int64(uv.shape[0]) + uv_cells.reshape(-1)
    keys, first, inverse = np.unique(pairs, return_index=True, return_inverse=True)
    del keys
    point_of, uv_of = cells.reshape(-1)[first], uv_cells.reshape(-1)[first]
    mesh = meshio.Mesh(
        points[point_of],
        [("triangle", inverse.reshape(-1, 3).astype(_index_type(inverse)))],
        point_data={"s": uv[uv_of, 0], "t": uv[uv_of, 1]},
    )
    with atomic_path(path) as temporary:
        meshio.ply.write(str(temporary), mesh, binary=True)


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
