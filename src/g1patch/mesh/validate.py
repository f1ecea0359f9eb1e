"""Checks of a mesh's input that no repair can mend, each naming the item at fault (0-based):
coordinates finite and within :data:`MAX_COORDINATE`, vertex indices in range, no face visiting
a vertex twice, no face of zero area (:data:`DEGENERATE_AREA_TOLERANCE`), tags naming existing
items; and the helpers that name a few of many items in an error message.

The face-area check runs a compiled kernel from :data:`KERNEL_FACES` faces on; the NumPy code is
the reference and names the face.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import DegenerateFaceError, InputError, MeshError, as_float_array
from .faces import _as_polygons
from .tags import FACE_TAGS, VERTEX_TAGS, Tag

__all__ = ["DEGENERATE_AREA_TOLERANCE", "KERNEL_FACES", "MAX_COORDINATE"]

IntArray = NDArray[np.int64]
FloatArray = NDArray[np.float64]

#: A face is degenerate when ``|d1 × d2| <= tol · max(|d1|, |d2|)²`` for its diagonals d1, d2
#: (twice its vector area against the square of its size).
DEGENERATE_AREA_TOLERANCE = 1e-12
#: the largest coordinate magnitude accepted (and stored in network files): products of two
#: coordinates and sums of many of them stay far from overflow, and 1e30 of any unit is larger
#: than anything a model describes
MAX_COORDINATE = 1e30


def _few(items: ArrayLike, limit: int = 5) -> str:
    """``"3, 7, 9 and 12 more"``: the first ``limit`` items of a list for an error message."""
    values = np.asarray(items).ravel().tolist()
    text = ", ".join(map(str, values[:limit]))
    return text + (f" and {len(values) - limit} more" if len(values) > limit else "")


def _all_of(items: ArrayLike, noun: str) -> str:
    """``" (3 such faces: 1, 4, 9)"``, or nothing when there is only one."""
    count = np.asarray(items).size
    return f" ({count} such {noun}: {_few(items)})" if count > 1 else ""


def _check_index_range(corners: IntArray, sizes: IntArray, n_vertices: int) -> None:
    bad = np.flatnonzero((corners < 0) | (corners >= n_vertices))
    if bad.size:
        face = np.repeat(np.arange(sizes.size), sizes)[bad]
        raise MeshError(
            f"face {face[0]} has vertex index {corners[bad[0]]} outside 0..{n_vertices - 1}"
            + _all_of(np.unique(face), "faces")
        )


#: faces of at most this many corners are checked for a repeated vertex pair by pair
#: (n (n - 1) / 2 pairs)
_PAIRWISE_SIZE = 8


def _check_repeated_vertices(corners: IntArray, sizes: IntArray, n_vertices: int) -> None:
    """A face may not visit a vertex twice: compare corner pairs (all faces of one small size, at
    most :data:`_PAIRWISE_SIZE` corners) or sort (face, vertex) keys (linear in memory for any
    size)."""
    if sizes[0] <= _PAIRWISE_SIZE and (sizes == sizes[0]).all():
        table = corners.reshape(-1, int(sizes[0]))
        repeats = np.zeros(table.shape[0], dtype=bool)
        for i, j in zip(*np.triu_indices(table.shape[1], 1), strict=True):
            repeats |= table[:, i] == table[:, j]
        faces = np.flatnonzero(repeats)
    else:
        face = np.repeat(np.arange(sizes.size, dtype=np.int64), sizes)
        keys = np.sort(face * n_vertices + corners)
        faces = np.unique(keys[1:][keys[1:] == keys[:-1]] // n_vertices)
    if faces.size:
        start = int(np.sum(sizes[: faces[0]]))
        face_corners = corners[start : start + sizes[faces[0]]]
        raise DegenerateFaceError(
            f"face {faces[0]} repeats a vertex: corners {tuple(face_corners.tolist())}"
            + _all_of(faces, "faces")
        )


def _check_finite(vertices: FloatArray) -> None:
    """Every coordinate finite and within :data:`MAX_COORDINATE` (two reductions, which NaN makes
    fail, before any search for the vertex to name)."""
    if vertices.size == 0 or (
        vertices.max() <= MAX_COORDINATE and vertices.min() >= -MAX_COORDINATE
    ):
        return
    bad = np.flatnonzero(~np.isfinite(vertices).all(axis=1))
    if bad.size:
        raise InputError(
            f"vertex {bad[0]} has a non-finite coordinate {tuple(vertices[bad[0]].tolist())}"
            + _all_of(bad, "vertices")
        )
    huge = np.flatnonzero((np.abs(vertices) > MAX_COORDINATE).any(axis=1))
    if huge.size:
        raise InputError(
            f"vertex {huge[0]} has a coordinate beyond ±{MAX_COORDINATE:g}: "
            f"{tuple(vertices[huge[0]].tolist())}" + _all_of(huge, "vertices")
        )


#: from this many faces on (``compiled=None``) :func:`_check_face_areas` first runs
#: :func:`_face_area_kernel`
KERNEL_FACES = 20_000
#: faces the kernel finds within this relative margin of the tolerance go to the NumPy check
_AREA_MARGIN = 1e-6


def _check_face_areas(
    vertices: FloatArray, faces: IntArray, *, compiled: bool | None = None
) -> None:
    """Zero area: ``|d1 × d2| <= tol · max(|d1|, |d2|)²`` for the diagonals d1 = p2 − p0, d2 = p3 −
    p1.

    ``compiled`` (default: from :data:`KERNEL_FACES` faces on): :func:`_face_area_kernel` passes
    the mesh when every face clears the tolerance by the margin :data:`_AREA_MARGIN` (far beyond
    any rounding of the two computations); otherwise the NumPy code below, the reference, decides.
    """
    from ..kernels import jit_kernel, use_kernels  # numba, imported on first use

    if use_kernels(faces.shape[0] >= KERNEL_FACES) if compiled is None else compiled:
        if jit_kernel(_face_area_kernel)(
            vertices, faces, DEGENERATE_AREA_TOLERANCE * (1.0 + _AREA_MARGIN)
        ):
            return
    corners = vertices[faces]
    d1 = corners[:, 2] - corners[:, 0]
    d2 = corners[:, 3] - corners[:, 1]
    double_area = np.linalg.norm(np.cross(d1, d2), axis=1)
    size = np.maximum(np.einsum("ij,ij->i", d1, d1), np.einsum("ij,ij->i", d2, d2))
    bad = np.flatnonzero(double_area <= DEGENERATE_AREA_TOLERANCE * size)
    if bad.size:
        f = bad[0]
        raise DegenerateFaceError(
            f"face {f} {tuple(faces[f].tolist())} has zero area (|d1 x d2| = {double_area[f]:.3g})"
            + _all_of(bad, "faces")
        )


def _face_area_kernel(vertices: FloatArray, faces: IntArray, tolerance: float) -> bool:
    """Whether every face has ``|d1 × d2|² > (tolerance · max(|d1|², |d2|²))²`` (NaN fails), face
    by face; compiled by :func:`~g1patch.kernels.jit_kernel`."""
    for f in range(faces.shape[0]):
        a, b, c, d = faces[f, 0], faces[f, 1], faces[f, 2], faces[f, 3]
        u0, u1, u2 = (
            vertices[c, 0] - vertices[a, 0],
            vertices[c, 1] - vertices[a, 1],
            vertices[c, 2] - vertices[a, 2],
        )
        w0, w1, w2 = (
            vertices[d, 0] - vertices[b, 0],
            vertices[d, 1] - vertices[b, 1],
            vertices[d, 2] - vertices[b, 2],
        )
        n0, n1, n2 = u1 * w2 - u2 * w1, u2 * w0 - u0 * w2, u0 * w1 - u1 * w0
        size = tolerance * max(u0 * u0 + u1 * u1 + u2 * u2, w0 * w0 + w1 * w1 + w2 * w2)
        if not n0 * n0 + n1 * n1 + n2 * n2 > size * size:
            return False
    return True


def _check_tags(tags: Sequence[Tag], n_vertices: int, n_faces: int) -> None:
    """Vertex tags (crease pairs, corners) and face tags (holes) must name existing items."""
    for tag in tags:
        limit = (
            n_vertices if tag.name in VERTEX_TAGS else n_faces if tag.name in FACE_TAGS else None
        )
        if limit is None:
            continue
        ints = np.asarray(tag.ints, dtype=np.int64)
        if tag.name == "crease" and ints.size % 2:
            raise MeshError(f"tag 'crease' needs pairs of vertex indices, got {ints.size} integers")
        bad = ints[(ints < 0) | (ints >= limit)]
        if bad.size:
            item = "vertex" if tag.name in VERTEX_TAGS else "face"
            raise MeshError(f"tag {tag.name!r} names {item} {bad[0]}, outside 0..{limit - 1}")


def _checked_polygons(
    vertices: ArrayLike, faces: ArrayLike | Sequence[Sequence[int]], tags: tuple[Tag, ...]
) -> tuple[FloatArray, IntArray, IntArray]:
    """Positions (finite), faces as flat ``corners`` and ``sizes`` (≥ 3 corners, indices in range)
    and tags naming existing items: what no repair can mend."""
    points = as_float_array("vertices", vertices, (3,), finite=False)
    if points.ndim != 2:
        raise InputError(f"vertices: expected shape (nv, 3), got {points.shape}")
    _check_finite(points)
    corners, sizes = _as_polygons(faces)
    if sizes.size == 0:
        raise MeshError("the mesh has no faces")
    short = np.flatnonzero(sizes < 3)
    if short.size:
        raise DegenerateFaceError(
            f"face {short[0]} has {sizes[short[0]]} corners; a face needs at least 3"
            + _all_of(short, "faces")
        )
    _check_tags(tags, points.shape[0], sizes.size)
    _check_index_range(corners, sizes, points.shape[0])
    return points, corners, sizes
