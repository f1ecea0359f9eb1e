"""How close is a patch network to the surface it should be? Distances, normal errors and fairness.

Three kinds of comparison, all vectorised over grids of samples per patch:

* against an exact surface (sphere, ellipsoid, torus; closest points from :mod:`g1patch.shapes`):
  max and mean distance and max normal error (:func:`deviation`, :func:`distance_to_sphere`, …);
* against a triangulated reference such as the Catmull–Clark limit in
  ``../shared/data/reference/NAME.limit.npz`` (:func:`load_reference`): the exact distance from
  samples to the triangles (:func:`mesh_distance`);
* fairness, DESIGN §4: the normal turn between neighbouring samples, of the network
  (:func:`network_normal_turns`) and of the reference (:func:`reference_normal_turns`), compared
  like with like by :func:`compare_fairness`.

Grid density follows the mesh faces: :func:`patch_samples` gives the samples per patch edge for
a number of grid steps per mesh face, halving them for ``split4`` networks (4 sub-patches per face).
"""

from __future__ import annotations

import zipfile
from collections.abc import Callable
from dataclasses import dataclass
from itertools import chain
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial import cKDTree

from . import continuity
from .continuity import angle_between
from .errors import FormatError, InputError, as_float_array, as_index_array
from .network import PatchNetwork
from .shapes import ellipsoid_project, sphere_project, torus_project

__all__ = [
    "Deviation",
    "Reference",
    "FairnessComparison",
    "patch_samples",
    "surface_samples",
    "deviation",
    "distance_to_sphere",
    "distance_to_ellipsoid",
    "distance_to_torus",
    "load_reference",
    "reference_path",
    "mesh_distance",
    "closest_points_on_triangles",
    "reference_vertex_normals",
    "reference_normal_turns",
    "network_normal_turns",
    "turn_percentiles",
    "compare_fairness",
]

FloatArray = NDArray[np.float64]
Projection = Callable[[FloatArray], tuple[FloatArray, FloatArray]]

#: (sample, candidate) pairs per block of :func:`mesh_distance` (bounds its memory to ~200 MB)
_PAIR_BUDGET = 1 << 20
#: samples in the first block of :func:`mesh_distance`, before the candidates per sample are known
_FIRST_BLOCK = 1024


def _check_samples(samples: int, least: int = 2) -> int:
    if isinstance(samples, bool) or not isinstance(samples, (int, np.integer)) or samples < least:
        raise InputError(f"samples: expected an integer ≥ {least}, got {samples!r}")
    return int(samples)


def patch_samples(network: PatchNetwork, face_steps: int) -> int:
    """Samples per patch edge that give ``face_steps`` grid steps across every mesh face.

    ``face_steps + 1`` for one patch per face; ``face_steps / 2 + 1`` for a ``split4`` network
    (provenance method ``split4``: 4 sub-patches per face), so both grids have the same step.
    """
    steps = _check_samples(face_steps, 1)
    if network.provenance.get("method") != "split4":
        return steps + 1
    if steps % 2:
        raise InputError(
            f"face_steps: a split4 network needs an even number of steps per face, got {steps}"
        )
    return steps // 2 + 1


def surface_samples(network: PatchNetwork, samples: int) -> tuple[FloatArray, FloatArray]:
    """Positions and unit normals on a uniform ``samples × samples`` grid per patch, both ``(N, S,
    S, 3)``.

    Normals are ``p_u × p_v`` normalised (works for :class:`PatchSet` and :class:`GregoryPatchSet`);
    the zero vector where that cross product is exactly zero.
    """
    grid = np.linspace(0.0, 1.0, _check_samples(samples))
    patches = network.patches
    positions = patches.evaluate_grid(grid, grid)
    normals = np.cross(
        patches.evaluate_grid(grid, grid, 1, 0), patches.evaluate_grid(grid, grid, 0, 1)
    )
    length = np.linalg.norm(normals, axis=-1, keepdims=True)
    np.divide(normals, length, out=normals, where=length > 0)
    return positions, normals


# -- against an exact surface ----------------------------------------------------------------------


@dataclass(frozen=True)
class Deviation:
    """Distance of a network's samples from an exact surface, and the angle of its normals from the
    surface's."""

    max_distance: float
    mean_distance: float
    max_normal_error_deg: float
    samples: int


def deviation(network: PatchNetwork, project: Projection, samples: int = 21) -> Deviation:
    """Compare the network's ``samples²`` grid per patch with the surface whose ``project(points)``
    returns (closest points, outward unit normals) — e.g. :func:`g1patch.shapes.ellipsoid_project`.

    Distance: to the closest point. Normal error: ``atan2`` angle between the patch normal and
    the surface normal at that closest point (a reversed normal counts 180°).
    """
    positions, normals = surface_samples(network, samples)
    closest, surface_normals = project(positions)
    distance = np.linalg.norm(positions - closest, axis=-1)
    return Deviation(
        max_distance=float(distance.max()),
        mean_distance=float(distance.mean()),
        max_normal_error_deg=float(np.max(angle_between(normals, surface_normals))),
        samples=samples,
    )


def distance_to_sphere(network: PatchNetwork, radius: float = 1.0, samples: int = 21) -> Deviation:
    """:func:`deviation` from the sphere of ``radius`` about the origin (the radial deviation)."""
    return deviation(network, lambda points: sphere_project(points, radius), samples)


def distance_to_ellipsoid(
    network: PatchNetwork, axes: tuple[float, float, float] = (1.0, 0.7, 0.5), samples: int = 21
) -> Deviation:
    """:func:`deviation` from the ellipsoid with semi-axes ``axes`` (exact closest points)."""
    return deviation(network, lambda points: ellipsoid_project(points, axes), samples)


def distance_to_torus(
    network: PatchNetwork, R: float = 2.0, r: float = 0.7, samples: int = 21
) -> Deviation:
    """:func:`deviation` from the torus of :func:`g1patch.shapes.torus` with radii ``R``, ``r``."""
    return deviation(network, lambda points: torus_project(points, R, r), samples)


# -- against a triangulated reference --------------------------------------------------------------


@dataclass(frozen=True)
class Reference:
    """A reference surface as a quad mesh: ``points`` (M, 3), ``faces`` (K, 4) and the refinement
    ``levels`` that made it from the cage (so its edges are 2^-levels of a cage edge)."""

    points: FloatArray
    faces: NDArray[np.int64]
    levels: int
    path: Path

    @property
    def bounding_box_diagonal(self) -> float:
        return float(np.linalg.norm(self.points.max(axis=0) - self.points.min(axis=0)))


def reference_path(mesh_file: str | Path) -> Path:
    """Where the Catmull–Clark reference of a shared mesh file lives: ``reference/NAME.limit.npz``
    beside it."""
    mesh_file = Path(mesh_file)
    return mesh_file.parent / "reference" / f"{mesh_file.stem}.limit.npz"


def load_reference(path: str | Path) -> Reference:
    """Read a ``NAME.limit.npz`` reference: arrays ``points`` (M, 3), ``faces`` (K, 4), ``levels``
    (scalar).

    Points are returned as float64, faces as int64. Raises :class:`FormatError` naming the file
    when it cannot be read, is not an ``.npz`` archive, lacks an array, or has wrong shapes,
    non-finite points, face indices outside ``0..M-1`` or a negative ``levels``.
    """
    path = Path(path)
    try:
        archive = np.load(path, allow_pickle=False)
    except OSError as exc:
        raise FormatError(path, f"cannot read the file ({exc.strerror or exc})") from None
    except (ValueError, EOFError, zipfile.BadZipFile) as exc:
        raise FormatError(path, f"not a readable .npz archive ({exc})") from None
    if not isinstance(archive, np.lib.npyio.NpzFile):
        raise FormatError(
            path,
            "expected an .npz archive with arrays points, faces and levels, got a single array",
        )
    with archive:
        missing = [name for name in ("points", "faces", "levels") if name not in archive.files]
        if missing:
            raise FormatError(
                path,
                f"missing array(s) {', '.join(missing)}; the archive has "
                f"{', '.join(archive.files) or 'none'}",
            )
        try:
            raw = {name: archive[name] for name in ("points", "faces", "levels")}
        except (OSError, ValueError, EOFError, zipfile.BadZipFile) as exc:
            raise FormatError(path, f"an array cannot be read ({exc})") from None
    points, faces, levels = raw["points"], raw["faces"], raw["levels"]
    if points.ndim != 2 or points.shape[1] != 3 or points.dtype.kind != "f":
        raise FormatError(
            path,
            f"points: expected a float array of shape (M, 3), got {points.dtype} {points.shape}",
        )
    if not np.isfinite(points).all():
        raise FormatError(
            path, f"points: {int((~np.isfinite(points).all(axis=1)).sum())} point(s) are not finite"
        )
    if faces.ndim != 2 or faces.shape[1] != 4 or faces.dtype.kind not in "iu" or not len(faces):
        raise FormatError(
            path,
            f"faces: expected an integer array of shape (K, 4), K ≥ 1, got {faces.dtype} "
            f"{faces.shape}",
        )
    if faces.min() < 0 or faces.max() >= len(points):
        raise FormatError(
            path,
            f"faces: indices must lie in 0..{len(points) - 1}, found {faces.min()}..{faces.max()}",
        )
    if levels.shape != () or levels.dtype.kind not in "iu" or int(levels) < 0:
        raise FormatError(
            path,
            f"levels: expected a non-negative integer scalar, got {levels.dtype} {levels.shape} "
            f"{levels!r}",
        )
    return Reference(points.astype(np.float64), faces.astype(np.int64), int(levels), path)


def _triangles(points: FloatArray, faces: NDArray[np.int64]) -> FloatArray:
    """The corner positions (T, 3, 3) of the triangles of ``faces``: triangles as given, quads split
    along 0–2."""
    if faces.shape[1] == 4:
        faces = np.concatenate([faces[:, [0, 1, 2]], faces[:, [0, 2, 3]]])
    return points[faces]


def _barycentric_closest(
    d1: FloatArray, d2: FloatArray, ab_ab: FloatArray, ab_ac: FloatArray, ac_ac: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """Coordinates (v, w) of the closest point ``a + v ab + w ac`` of triangle (a, b, c) to p.

    Inputs: ``d1 = ab·ap``, ``d2 = ac·ap`` and the Gram entries of ab, ac. Ericson's
    Voronoi-region test (Real-Time Collision Detection §5.1.5) in branch-free form: every
    region condition is evaluated and :func:`numpy.select` keeps the first that holds, in the
    order vertex a, vertex b, edge ab, vertex c, edge ac, edge bc, face.
    """
    d3, d4 = d1 - ab_ab, d2 - ab_ac  # ab·bp, ac·bp
    d5, d6 = d1 - ab_ac, d2 - ac_ac  # ab·cp, ac·cp
    vc, vb, va = d1 * d4 - d3 * d2, d5 * d2 - d1 * d6, d3 * d6 - d5 * d4
    with np.errstate(divide="ignore", invalid="ignore"):  # only in regions not selected
        along_ab = d1 / (d1 - d3)
        along_ac = d2 / (d2 - d6)
        along_bc = (d4 - d3) / ((d4 - d3) + (d5 - d6))
        total = va + vb + vc
        inside_v, inside_w = vb / total, vc / total
    zero, one = np.zeros_like(d1), np.ones_like(d1)
    conditions = [
        (d1 <= 0) & (d2 <= 0),
        (d3 >= 0) & (d4 <= d3),
        (vc <= 0) & (d1 >= 0) & (d3 <= 0),
        (d6 >= 0) & (d5 <= d6),
        (vb <= 0) & (d2 >= 0) & (d6 <= 0),
        (va <= 0) & (d4 - d3 >= 0) & (d5 - d6 >= 0),
    ]
    v = np.select(conditions, [zero, one, along_ab, zero, zero, 1.0 - along_bc], inside_v)
    w = np.select(conditions, [zero, zero, zero, one, along_ac, along_bc], inside_w)
    return v, w


def closest_points_on_triangles(
    points: ArrayLike, a: ArrayLike, b: ArrayLike, c: ArrayLike
) -> FloatArray:
    """The closest point to each of ``points`` on triangle (a, b, c); all (..., 3), broadcast
    together."""
    p, a, b, c = np.broadcast_arrays(
        *(
            as_float_array(name, value, (3,))
            for name, value in zip("pabc", (points, a, b, c), strict=True)
        )
    )
    ab, ac, ap = b - a, c - a, p - a
    v, w = _barycentric_closest(
        (ab * ap).sum(-1),
        (ac * ap).sum(-1),
        (ab * ab).sum(-1),
        (ab * ac).sum(-1),
        (ac * ac).sum(-1),
    )
    return a + v[..., None] * ab + w[..., None] * ac


@dataclass(frozen=True)
class _TriangleSearch:
    """Triangles prepared for :func:`mesh_distance`: corner a, edges ab, ac, their Gram entries,
    each triangle's reach (largest centroid-to-corner distance), and a k-d tree over the
    centroids."""

    a: FloatArray
    ab: FloatArray
    ac: FloatArray
    gram: FloatArray  # (T, 3): ab·ab, ab·ac, ac·ac
    reach: FloatArray
    tree: cKDTree

    @classmethod
    def build(cls, triangles: FloatArray, reach: FloatArray) -> _TriangleSearch:
        a, ab, ac = (
            triangles[:, 0],
            triangles[:, 1] - triangles[:, 0],
            triangles[:, 2] - triangles[:, 0],
        )
        gram = np.stack([(ab * ab).sum(-1), (ab * ac).sum(-1), (ac * ac).sum(-1)], axis=1)
        return cls(a, ab, ac, gram, reach, cKDTree(triangles.mean(axis=1)))

    def __len__(self) -> int:
        return len(self.a)

    def distance(self, points: FloatArray, triangle: NDArray[np.int64]) -> FloatArray:
        """Exact distance from each point to the triangle of the same row."""
        ab, ac = self.ab[triangle], self.ac[triangle]
        ap = points - self.a[triangle]
        gram = self.gram[triangle]
        v, w = _barycentric_closest(
            (ab * ap).sum(-1), (ac * ap).sum(-1), gram[:, 0], gram[:, 1], gram[:, 2]
        )
        return np.linalg.norm(v[:, None] * ab + w[:, None] * ac - ap, axis=-1)

    @staticmethod
    def _keep(
        best: FloatArray,
        which: NDArray[np.int64],
        query: NDArray[np.int64],
        triangle: NDArray[np.int64],
        distance: FloatArray,
    ) -> None:
        """Per query point the nearest of its candidate ``triangle``s at ``distance``, kept in
        ``best`` and ``which`` where it is no farther than the bound there."""
        order = np.lexsort((distance, query))
        first = order[np.r_[True, query[order][1:] != query[order][:-1]]] if len(order) else order
        query, triangle, distance = query[first], triangle[first], distance[first]
        nearer = distance <= best[query]
        best[query[nearer]] = distance[nearer]
        which[query[nearer]] = triangle[nearer]

    def lower(self, points: FloatArray, best: FloatArray, which: NDArray[np.int64]) -> None:
        """Lower ``best`` (finite upper bounds, in place) to the exact distance from each point to
        these triangles where that is no larger, and set ``which`` to the triangle found there.

        A triangle whose centroid is r away is at least ``r − reach`` away, so only triangles with
        their centroid within ``best`` (first lowered to the distance to the triangle with the
        nearest centroid) plus the largest reach can be closer: those come from one ball search
        per point, and the ones with ``r − reach < best`` are measured exactly.
        Points go in blocks sized so that a block has about ``_PAIR_BUDGET`` candidates.
        """
        centroids, largest_reach = self.tree.data, float(self.reach.max())
        nearest = self.tree.query(points, workers=-1)[1]
        self._keep(best, which, np.arange(len(points)), nearest, self.distance(points, nearest))
        start, block = 0, _FIRST_BLOCK
        while start < len(points):
            rows = slice(start, min(start + block, len(points)))
            found = self.tree.query_ball_point(
                points[rows], best[rows] + largest_reach, workers=-1, return_sorted=False
            )
            counts = np.fromiter(map(len, found), dtype=np.int64, count=len(found))
            triangle = np.fromiter(
                chain.from_iterable(found), dtype=np.int64, count=int(counts.sum())
            )
            query = np.repeat(np.arange(rows.start, rows.stop), counts)
            gap = np.linalg.norm(points[query] - centroids[triangle], axis=1) - self.reach[triangle]
            keep = gap <= best[query]
            query, triangle = query[keep], triangle[keep]
            self._keep(best, which, query, triangle, self.distance(points[query], triangle))
            start = rows.stop
            block = int(np.clip(_PAIR_BUDGET * len(found) / max(len(triangle), 1), 1, _PAIR_BUDGET))


def mesh_distance(samples: ArrayLike, points: ArrayLike, faces: ArrayLike) -> FloatArray:
    """Exact distance from each sample point (..., 3) to the triangulated mesh ``points``,
    ``faces`` (:func:`nearest_triangles`)."""
    return nearest_triangles(samples, points, faces)[0]


def nearest_triangles(
    samples: ArrayLike, points: ArrayLike, faces: ArrayLike
) -> tuple[FloatArray, NDArray[np.int64]]:
    """Exact distance from each sample point (..., 3) to the triangulated mesh ``points``,
    ``faces``, and the triangle where it is met (:class:`NearestTriangles`, built for one
    query)."""
    return NearestTriangles(points, faces).query(samples)


class NearestTriangles:
    """A triangulated mesh ``points``, ``faces`` prepared for exact nearest-point queries
    (build it once for many queries of the same mesh).

    ``faces`` (K, 3) triangles or (K, 4) quads (split along the diagonal 0–2). The distance to
    the nearest mesh vertex is an upper bound; a triangle whose centroid is r away is at least
    ``r − reach`` away (reach: its largest centroid-to-corner distance), so only triangles with
    centroids within the bound plus the reach are candidates (:class:`scipy.spatial.cKDTree`
    ball searches) and only those that can beat the best so far are measured exactly: the result
    equals the brute-force minimum over all triangles. Triangles are searched in classes of
    similar reach (within a factor 2), so a few large triangles do not widen the search around
    small ones. The cost per sample grows with (distance / edge length)²: fast near the mesh,
    slower for surfaces far apart relative to its edges.
    """

    def __init__(self, points: ArrayLike, faces: ArrayLike) -> None:
        vertices = as_float_array("points", points, (3,))
        polygons = as_index_array("faces", faces, (None,))
        if polygons.ndim != 2 or polygons.shape[1] not in (3, 4) or not len(polygons):
            raise InputError(
                "faces: expected a non-empty (K, 3) or (K, 4) index array, got shape "
                f"{polygons.shape}"
            )
        if polygons.min() < 0 or polygons.max() >= len(vertices):
            raise InputError(
                f"faces: indices must lie in 0..{len(vertices) - 1}, found "
                f"{polygons.min()}..{polygons.max()}"
            )
        triangles = _triangles(vertices, polygons)
        reach = np.linalg.norm(triangles - triangles.mean(axis=1, keepdims=True), axis=-1)
        reach = reach.max(axis=1)
        largest = max(float(reach.max()), np.finfo(float).tiny)
        size = np.floor(np.log2(largest / np.maximum(reach, largest * 2.0**-30))).astype(np.int64)
        classes = (np.flatnonzero(size == c) for c in np.unique(size))
        self.classes = [
            (members, _TriangleSearch.build(triangles[members], reach[members]))
            for members in sorted(classes, key=len, reverse=True)
        ]
        corners = polygons
        if polygons.shape[1] == 4:  # the halves, as _triangles cuts them
            corners = np.concatenate([polygons[:, [0, 1, 2]], polygons[:, [0, 2, 3]]])
        self.used = np.unique(polygons)
        self.vertices = cKDTree(vertices[self.used])
        self.incident = np.zeros(len(vertices), dtype=np.int64)
        self.incident[corners.reshape(-1)] = np.repeat(np.arange(len(corners)), 3)

    def query(self, samples: ArrayLike) -> tuple[FloatArray, NDArray[np.int64]]:
        """Per sample point (..., 3) its distance to the mesh and the triangle where it is met
        (an index into the faces' triangles: the triangles as given, quads as their halves,
        the 0–1–2 halves first); arrays of shape ``samples.shape[:-1]``."""
        queries = as_float_array("samples", samples, (3,))
        flat = queries.reshape(-1, 3)
        best, vertex = self.vertices.query(flat, workers=-1)  # a mesh vertex: a bound
        which = self.incident[self.used[vertex]]  # a triangle at that vertex: no farther
        for members, search in self.classes:
            found = np.full(len(flat), -1, dtype=np.int64)
            search.lower(flat, best, found)
            which[found >= 0] = members[found[found >= 0]]
        return best.reshape(queries.shape[:-1]), which.reshape(queries.shape[:-1])


# -- fairness: the normal turn between neighbouring samples ----------------------------------------


def reference_vertex_normals(points: ArrayLike, faces: ArrayLike) -> FloatArray:
    """Area-weighted unit vertex normals of a quad mesh, each quad split into triangles.

    Both splittings of a quad are used at half weight (the four corner triangles
    ``(v_{i-1}, v_i, v_{i+1})``), so the normals do not depend on the choice of diagonal.
    Each triangle adds its area vector to its three corners. Zero where the sum vanishes.
    """
    positions = as_float_array("points", points, (3,))
    quads = as_index_array("faces", faces, (4,))
    corner = positions[quads]  # (K, 4, 3)
    following, preceding = np.roll(corner, -1, axis=1), np.roll(corner, 1, axis=1)
    area = 0.25 * np.cross(
        following - corner, preceding - corner
    )  # half of each corner triangle's area vector
    # corner triangle i touches the corners i - 1, i, i + 1
    spread = area + np.roll(area, -1, axis=1) + np.roll(area, 1, axis=1)
    ids = quads.ravel()
    normals = np.stack(
        [
            np.bincount(ids, weights=spread[..., k].ravel(), minlength=len(positions))
            for k in range(3)
        ],
        axis=1,
    )
    length = np.linalg.norm(normals, axis=1, keepdims=True)
    np.divide(normals, length, out=normals, where=length > 0)
    return normals.astype(np.float64, copy=False)


def reference_normal_turns(points: ArrayLike, faces: ArrayLike) -> FloatArray:
    """The turn, in degrees, between the vertex normals (:func:`reference_vertex_normals`) at the
    two ends of every edge of the quad mesh, each edge once."""
    quads = as_index_array("faces", faces, (4,))
    normals = reference_vertex_normals(points, quads)
    ends = np.stack([quads, np.roll(quads, -1, axis=1)], axis=-1).reshape(-1, 2)
    edges = np.unique(np.sort(ends, axis=1), axis=0)
    return np.asarray(
        angle_between(normals[edges[:, 0]], normals[edges[:, 1]]), dtype=np.float64
    ).reshape(-1)


def network_normal_turns(network: PatchNetwork, samples: int) -> FloatArray:
    """The turn, in degrees, between the unit normals of neighbouring samples (along u and along v)
    of a ``samples × samples`` grid on every patch.

    Stand-in for the network side of :func:`g1patch.continuity.fairness` while that does not
    exist; :func:`compare_fairness` prefers it when it does.
    """
    _, normals = surface_samples(network, samples)
    along_u = angle_between(normals[:, 1:], normals[:, :-1])
    along_v = angle_between(normals[:, :, 1:], normals[:, :, :-1])
    return np.concatenate([np.ravel(along_u), np.ravel(along_v)])


def turn_percentiles(turns: ArrayLike) -> dict[str, float]:
    """``{"median", "p99", "max"}`` of the normal turns (degrees)."""
    values = np.asarray(turns, dtype=np.float64).ravel()
    if not values.size:
        raise InputError("turns: expected at least one normal turn, got none")
    median, p99 = np.percentile(values, [50.0, 99.0])
    return {"median": float(median), "p99": float(p99), "max": float(values.max())}


@dataclass(frozen=True)
class FairnessComparison:
    """Normal-turn percentiles (degrees) of a network and of its reference, on grids of the same
    step."""

    network: dict[str, float]
    reference: dict[str, float]
    samples: int

    @property
    def p99_ratio(self) -> float:
        """Network p99 / reference p99: the DESIGN §5 bar is ≤ 1.5 (interpolating), ≤ 1.1 (limit
        mode)."""
        return self.network["p99"] / self.reference["p99"]


def compare_fairness(network: PatchNetwork, reference: Reference) -> FairnessComparison:
    """The network's normal turns against the reference's, like with like.

    The reference is the cage refined ``levels`` times, so its edges are 2^-levels of a cage
    edge: the network is sampled with ``2^levels`` steps per face (:func:`patch_samples`). The
    network side uses :func:`g1patch.continuity.fairness` when the library has it, else
    :func:`network_normal_turns`.
    """
    samples = patch_samples(network, 2**reference.levels)
    fairness: Callable[..., dict[str, Any]] | None = getattr(continuity, "fairness", None)
    if fairness is None:
        ours = turn_percentiles(network_normal_turns(network, samples))
    else:
        figures = fairness(network, samples=samples)
        ours = {key: float(figures[f"turn_{key}_deg"]) for key in ("median", "p99", "max")}
    theirs = turn_percentiles(reference_normal_turns(reference.points, reference.faces))
    return FairnessComparison(ours, theirs, samples)
