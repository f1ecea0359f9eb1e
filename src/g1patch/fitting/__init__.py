"""The fit stage: a dense triangle mesh (a scan, a tessellation) → a quad layout → a cage whose
Catmull–Clark limit passes nearest the scan (:mod:`g1patch.fitting.solve`) → the limit targets and
an exact-G1 assembly (split4 by default: polynomial, so the CAD file is the fitted surface).

:func:`fit_network` runs it and measures the result against the scan both ways
(:class:`FitReport`): scan points to the surface and surface samples to the scan's triangles.
Without a given layout or face count it starts from :data:`START_FACES` (or the scan's size) and,
while the tolerance is not met, asks for the face count the measured error calls for
(:func:`next_faces`: the error's rate over the face count observed between layouts), up to
:data:`MAX_ROUNDS` layouts and at most :func:`face_budget` quads; a layout the
cage cannot be built from (what :func:`~g1patch.fitting.layout.clean_layout` leaves still
refused) is skipped for the next face count. The scan's coincident vertices are welded first
(:func:`welded`): an unwelded scan's cracks make the remesher's layout ragged and, on some inputs,
not reproducible.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..build import build_network, check_tolerance
from ..compare import mesh_distance
from ..errors import ConstructionError, InputError, MeshError
from ..mesh import QuadMesh
from ..network import PatchNetwork
from ..tessellate import tessellate
from .features import (
    boundary_corners,
    layout_corners,
    layout_creases,
    sharp_corners,
    sharp_segments,
    snap_to_features,
)
from .layout import quad_layout
from .solve import FitCage, fit_cage, vertex_normals

__all__ = [
    "DEFAULT_TOLERANCE",
    "FIT_SHARP_ANGLE",
    "MAX_FACES",
    "MAX_ROUNDS",
    "START_FACES",
    "FitReport",
    "Scan",
    "face_budget",
    "fit_network",
    "next_faces",
    "quad_layout",
    "scan_from_polygons",
    "scan_of",
    "welded",
]

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

#: the default tolerance: two-way distance, a fraction of the scan's bounding-box diagonal
DEFAULT_TOLERANCE = 1e-3
#: the default ``sharp_angle`` of the fit, degrees: a CAD part's 90° edges (and 60° or more) are
#: kept; on the shared organic triangle meshes (Spot, the teapot) no layout edge runs along a scan
#: edge this sharp (at 40° a few short chains on Spot would)
FIT_SHARP_ANGLE = 60.0
#: quads of the first layout when neither a layout nor a face count is given
START_FACES = 1024
#: layouts tried at most (the faces growing each time, :func:`next_faces`) to meet the tolerance
MAX_ROUNDS = 4
#: quads of an adaptive fit at most: a CAD file of more faces is not a reduction of the scan (nor
#: are more quads than half its triangles, :func:`face_budget`)
MAX_FACES = 20_000
#: the share of :func:`face_budget` left for the remesher's excess over the count asked for
BUDGET_MARGIN = 0.05
#: the error's order in the face count assumed before two layouts measured it: max distance ∝
#: faces^−1, i.e. ∝ h², h the quad size (a smooth surface fitted where its curvature dominates)
ASSUMED_RATE = 1.0
#: the observed rate is kept within these (a feature the layout misses barely improves; a noisy
#: measurement can claim any rate)
RATE_RANGE = (0.5, 2.0)
#: the next count aims at this fraction of the tolerance (the maximum is a noisy figure)
AIM = 0.8
#: the next count grows by at least and at most these factors
GROWTH_RANGE = (1.25, 4.0)
#: samples per patch side of the surface when it is measured against the scan (split4: a
#: sub-patch is a quarter face, so 9 a face side)
MEASURE_SAMPLES = 5


@dataclass(frozen=True)
class Scan:
    """A dense triangle mesh to fit: ``points`` (N, 3), ``triangles`` (T, 3), its name and what
    was repaired in it (:func:`welded`)."""

    points: FloatArray
    triangles: IntArray
    source: str | None = None
    repairs: tuple[str, ...] = ()

    @property
    def diagonal(self) -> float:
        return float(np.linalg.norm(self.points.max(axis=0) - self.points.min(axis=0)))


def scan_from_polygons(
    points: FloatArray, corners: IntArray, sizes: IntArray, source: str | None = None
) -> Scan:
    """Polygons (flat ``corners``, ``sizes``) fanned into triangles from their first corner."""
    first = np.repeat(np.cumsum(sizes) - sizes, sizes - 2)
    fan = sizes - 2
    step = np.arange(int(fan.sum())) - np.repeat(np.cumsum(fan) - fan, fan)
    triangles = np.stack(
        [corners[first], corners[first + step + 1], corners[first + step + 2]], axis=1
    )
    return Scan(np.asarray(points, dtype=np.float64), triangles.astype(np.int64), source)


def welded(scan: Scan) -> Scan:
    """``scan`` with the vertices at one position merged into one (the first's index order
    kept) and the triangles that then repeat a corner dropped; ``repairs`` says how many."""
    _, first, inverse = np.unique(scan.points, axis=0, return_index=True, return_inverse=True)
    duplicated = len(scan.points) - len(first)
    if not duplicated:
        return scan
    keep = np.sort(first)
    renumber = np.empty(len(first), dtype=np.int64)
    renumber[np.argsort(first)] = np.arange(len(first))  # unique rows → first-occurrence order
    triangles = renumber[inverse.reshape(-1)][scan.triangles]
    ordered = np.sort(triangles, axis=1)
    triangles = triangles[(ordered[:, 1:] != ordered[:, :-1]).all(axis=1)]
    note = f"welded {duplicated} duplicated vertices"
    return Scan(scan.points[keep], triangles, scan.source, (*scan.repairs, note))


def scan_of(mesh: QuadMesh) -> Scan:
    """The triangles of a mesh: the polygons it was split from (:attr:`QuadMesh.cage`) fanned
    into triangles, else its quads cut along the diagonal 0–2."""
    if mesh.cage is not None:
        cage = mesh.cage
        return scan_from_polygons(cage.points, cage.corners, cage.sizes, mesh.source)
    quads = mesh.faces
    triangles = np.concatenate([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]])
    return Scan(np.asarray(mesh.vertices, dtype=np.float64), triangles, mesh.source)


@dataclass(frozen=True)
class FitReport:
    """How near the fitted surface is to the scan, in model units and of the diagonal.

    ``to_surface``: scan points → surface; ``to_scan``: surface samples → scan triangles; each
    ``(max, p99, rms)``. ``faces``: cage quads; ``rounds``: layouts tried; ``rms``: the model's
    RMS per solve of the last round; ``seconds``: wall time; ``creases``: cage edges kept sharp
    (the scan's features, ``sharp_angle``); ``repairs``: what was repaired in the scan."""

    diagonal: float
    tolerance: float
    to_surface: tuple[float, float, float]
    to_scan: tuple[float, float, float]
    faces: int
    patches: int
    rounds: int
    rms: tuple[float, ...]
    seconds: float
    creases: int = 0
    repairs: tuple[str, ...] = ()

    @property
    def worst(self) -> float:
        """The two-way maximum distance, of the diagonal."""
        return max(self.to_surface[0], self.to_scan[0]) / self.diagonal

    @property
    def met(self) -> bool:
        return self.worst <= self.tolerance

    def summary(self) -> str:
        """The report as a table (distances also of the diagonal)."""

        def row(name: str, figures: tuple[float, float, float]) -> str:
            relative = " / ".join(f"{value / self.diagonal:.2e}" for value in figures)
            absolute = " / ".join(f"{value:.3g}" for value in figures)
            return f"{name:<32}{relative}  ({absolute})"

        verdict = "within" if self.met else "NOT within"
        return "\n".join(
            [
                f"{'cage quads / patches':<32}{self.faces} / {self.patches} "
                f"({self.rounds} layouts)",
                f"{'crease edges (features)':<32}{self.creases}",
                f"{'distance, of diagonal':<32}max / p99 / rms  (model units)",
                row("scan → surface", self.to_surface),
                row("surface → scan", self.to_scan),
                f"{'tolerance':<32}{self.tolerance:g} of the diagonal: {verdict} "
                f"({self.worst:.2e})",
                f"{'time':<32}{self.seconds:.1f} s",
            ]
        )

    def to_dict(self) -> dict[str, Any]:
        """The figures, JSON-ready."""
        names = ("max", "p99", "rms")
        return {
            "diagonal": self.diagonal,
            "tolerance": self.tolerance,
            "within_tolerance": self.met,
            "worst_of_diagonal": self.worst,
            "scan_to_surface": dict(zip(names, self.to_surface, strict=True)),
            "surface_to_scan": dict(zip(names, self.to_scan, strict=True)),
            "faces": self.faces,
            "patches": self.patches,
            "rounds": self.rounds,
            "seconds": self.seconds,
            "creases": self.creases,
            "repairs": list(self.repairs),
        }


def _figures(distances: FloatArray) -> tuple[float, float, float]:
    return (
        float(distances.max()),
        float(np.percentile(distances, 99)),
        float(np.sqrt(np.mean(distances**2))),
    )


def measure(network: PatchNetwork, scan: Scan) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """Two-way distances between the surface (sampled :data:`MEASURE_SAMPLES` per patch side,
    triangulated) and the scan: ``(to_surface, to_scan)`` figures (max, p99, rms)."""
    mesh = tessellate(network, MEASURE_SAMPLES)
    to_surface = mesh_distance(scan.points, mesh.points, mesh.triangles)
    to_scan = mesh_distance(mesh.points, scan.points, scan.triangles)
    return _figures(to_surface), _figures(to_scan)


def fit_network(
    scan: Scan,
    *,
    tolerance: float = DEFAULT_TOLERANCE,
    faces: int | None = None,
    layout: QuadMesh | None = None,
    method: str = "split4",
    sharp_angle: float | None = FIT_SHARP_ANGLE,
) -> tuple[PatchNetwork, FitReport]:
    """The fitted exact-G1 network of ``scan`` and its :class:`FitReport` (module docstring).

    ``layout``: the user's quad mesh near the scan (its topology is the cage's; no remeshing);
    ``faces``: the layout's quad count (about), else from :data:`START_FACES` doubling up to
    :data:`MAX_ROUNDS` times while the two-way distance exceeds ``tolerance`` (of the diagonal).
    ``sharp_angle`` (degrees): the scan's edges whose triangles turn by more than that are
    features; the layout edges along them become infinitely sharp creases
    (:mod:`~g1patch.fitting.features`), seams of the network and edges of its STEP solid.
    """
    tolerance = check_tolerance(tolerance)
    started = time.perf_counter()
    scan = welded(scan)
    diagonal = scan.diagonal
    if not diagonal > 0:
        raise InputError(f"{scan.source or 'scan'}: the scan has no extent")
    count = faces if faces is not None else min(START_FACES, max(64, len(scan.triangles) // 8))
    adaptive = layout is None and faces is None
    normals = vertex_normals(scan.points, scan.triangles)
    features = (
        np.zeros((0, 2, 3))
        if sharp_angle is None
        else sharp_segments(scan.points, scan.triangles, sharp_angle)
    )
    feature_corners = (
        np.zeros((0, 3))
        if sharp_angle is None
        else sharp_corners(scan.points, scan.triangles, sharp_angle)
    )
    corners = boundary_corners(
        scan.points, scan.triangles, FIT_SHARP_ANGLE if sharp_angle is None else sharp_angle
    )
    rounds, best, failure, tried = 0, None, "", []
    budget = face_budget(len(scan.triangles))
    if adaptive:
        count = min(count, budget)
    while True:
        rounds += 1
        try:
            cage_layout = layout if layout is not None else _layout(scan, count)
        except (ConstructionError, MeshError) as error:  # unusable: the next face count
            if not adaptive:
                raise
            failure = str(error)
            tried.append((count, np.inf))
        else:
            snapped = snap_to_features(cage_layout, features, feature_corners)
            creased = layout_creases(snapped, features, feature_corners)
            cage_layout = layout_corners(creased, corners)
            fitted: FitCage = fit_cage(scan.points, normals, cage_layout, scan.triangles)
            # the scan, not the cage's limit, is what the fit is measured against (below)
            network = build_network(fitted.cage, method, "limit", tolerance=None)
            to_surface, to_scan = measure(network, scan)
            worst = max(to_surface[0], to_scan[0]) / diagonal
            tried.append((cage_layout.n_faces, worst))
            if best is None or worst < best[-1]:  # a finer layout is not always nearer
                best = (cage_layout, fitted, network, to_surface, to_scan, worst)
            if not adaptive or worst <= tolerance:
                break
        if rounds >= MAX_ROUNDS or count >= budget:
            break
        count = min(next_faces(tried, tolerance, count), budget)
    if best is None:
        raise ConstructionError(f"no usable quad layout in {rounds} tries (last: {failure})")
    cage_layout, fitted, network, to_surface, to_scan, worst = best
    network.provenance.update({"fit_tolerance": f"{tolerance:g}", "fit_distance": f"{worst:.3e}"})
    report = FitReport(
        diagonal,
        tolerance,
        to_surface,  # type: ignore[arg-type]
        to_scan,  # type: ignore[arg-type]
        fitted.cage.n_faces,
        network.n_patches,
        rounds,
        fitted.rms,
        time.perf_counter() - started,
        int(cage_layout.features.edge_sharpness.astype(bool).sum()),
        scan.repairs,
    )
    return network, report


def face_budget(triangles: int) -> int:
    """The most quads an adaptive fit of a scan of ``triangles`` asks for: :data:`MAX_FACES`, and
    half the triangles (a quad is two triangles' worth of data), less :data:`BUDGET_MARGIN` (the
    remesher's count is the request's within a few per cent)."""
    return max(16, int((1.0 - BUDGET_MARGIN) * min(MAX_FACES, triangles // 2)))


def next_faces(tried: list[tuple[int, float]], tolerance: float, count: int) -> int:
    """The face count the measured errors call for: ``tried`` holds (faces, worst distance of
    the diagonal) per layout so far (∞: unusable), ``count`` the last count asked for. The error
    is modelled as ``e ∝ faces^−r``, r from the last two usable layouts (:data:`ASSUMED_RATE`
    before there are two; kept in :data:`RATE_RANGE`), and the count that brings it to
    :data:`AIM` × ``tolerance`` is asked for, growing by a factor in :data:`GROWTH_RANGE`."""
    usable = [(faces, error) for faces, error in tried if np.isfinite(error) and error > 0]
    if not usable:
        return int(count * GROWTH_RANGE[0] ** 2)
    rate = ASSUMED_RATE
    if len(usable) >= 2 and usable[-1][0] != usable[-2][0]:
        (f0, e0), (f1, e1) = usable[-2], usable[-1]
        rate = float(np.clip(np.log(e0 / e1) / np.log(f1 / f0), *RATE_RANGE))
    faces, error = usable[-1]
    growth = (error / (AIM * tolerance)) ** (1.0 / rate)
    return int(np.ceil(max(faces, count) * float(np.clip(growth, *GROWTH_RANGE))))


def _layout(scan: Scan, faces: int) -> QuadMesh:
    """The remesher's quads as a validated (and where needed repaired) quad mesh."""
    vertices, quads = quad_layout(scan.points, scan.triangles, int(faces))
    return QuadMesh.from_arrays(vertices, quads, source=f"layout of {scan.source or 'the scan'}")
