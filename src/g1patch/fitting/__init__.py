"""The fit stage: a dense triangle mesh (a scan, a tessellation) → a quad layout → a cage whose
Catmull–Clark limit passes nearest the scan, both ways (:mod:`g1patch.fitting.solve`) → the limit
targets and an exact-G1 assembly (split4 by default: polynomial, so the CAD file is the fitted
surface).

:func:`fit_network` runs it and measures the result against the scan both ways (:class:`FitReport`):
scan points to the surface and surface samples to the scan's triangles. Without a given layout or
face count it starts from :data:`START_FACES` (or the scan's size) and, while the tolerance is not
met, refines the layout locally where it is off (:func:`_locally_refined`: the off faces and two
rings about them split into four, the mesh closed into quads round them,
:mod:`g1patch.mesh.conforming`) when few faces are off and the fit has no fold and is the nearest so
far, else asks the remesher for the face count the measured error calls for (:func:`next_faces`: the
error's rate over the face count observed between the remesher's layouts; half the budget before
all of it, :func:`next_count`), up to :data:`MAX_ROUNDS`
layouts (:data:`ROUND_POINTS`) and at most :func:`face_budget` quads; the layout kept is the one
with the fewest folds, then the nearest. A fit that folds is first fitted again on its own layout,
fairer round the folds (:func:`_stiffened`, :data:`FOLD_REFITS` times at most). A layout the cage
cannot be built from (what :func:`~g1patch.fitting.layout.clean_layout` leaves still refused) is
skipped for the next face count; the faces of a remesher's layout that span a hole of the scan are
cut out (:func:`~g1patch.fitting.layout.bridging_faces`). The tolerance bounds the scan → surface
99.9th percentile and the surface → scan maximum (:class:`FitReport`). The scan is cleaned first:
vertices no triangle uses dropped (:func:`used_only`), coincident ones welded (:func:`welded`: an
unwelded scan's cracks make the remesher's layout ragged and, on some inputs, not reproducible), two
triangles at most kept at an edge (:func:`manifold`), triangles turned over to agree with their
neighbours (:func:`oriented`), islands dropped (:func:`without_islands`), holes narrower than the
first layout's edge filled (:func:`holes_filled`); its points are its vertices and, where its
triangles are large beside the layout face nearest them, samples inside them
(:meth:`Scan.facet_samples`).
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy.spatial import cKDTree

from ..build import build_network, check_tolerance
from ..compare import mesh_distance
from ..continuity import (
    EXACT_G1_DEG,
    FOLD_SAMPLES,
    ContinuityReport,
    check,
    folded_patches,
)
from ..errors import ConstructionError, InputError, MeshError
from ..mesh import QuadMesh
from ..mesh.neighbourhood import grow
from ..network import PatchNetwork
from ..tessellate import tessellate
from .features import (
    boundary_corners,
    boundary_reach,
    crease_gaps,
    layout_corners,
    layout_creases,
    median_edge,
    quad_areas,
    sharp_corners,
    sharp_segments,
    snap_to_features,
    without_lonely_creases,
)
from .layout import bridging_faces, quad_layout, refined_layout
from .scan_topology import (
    boundary_edges,
    boundary_loops,
    orientation_flips,
    side_edges,
    triangle_parts,
)
from .solve import FitCage, _Triangles, fit_cage, vertex_normals

__all__ = [
    "DEFAULT_TOLERANCE",
    "FIT_SHARP_ANGLE",
    "MAX_FACES",
    "MAX_ROUNDS",
    "MIN_ROUNDS",
    "ROUND_POINTS",
    "START_FACES",
    "FitReport",
    "Scan",
    "face_budget",
    "fit_network",
    "holes_filled",
    "layout_rank",
    "manifold",
    "next_count",
    "next_faces",
    "oriented",
    "quad_layout",
    "scan_from_polygons",
    "scan_of",
    "used_only",
    "welded",
    "without_islands",
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
#: layouts tried (the faces growing each time, :func:`next_faces`) to meet the tolerance: at
#: least ``MIN_ROUNDS``, and past that while the scan points fitted in all of them so far are
#: fewer than ``ROUND_POINTS``, ``MAX_ROUNDS`` at most — a small scan's layout takes a second or
#: two (an airplane's 10,796 triangles: its fourth layout, 2,495 quads, was 2.3e-3 off, its
#: fifth, 4,740, within 2e-3), a 100 k-triangle scan's 25 s
MIN_ROUNDS = 4
MAX_ROUNDS = 8
ROUND_POINTS = 250_000
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
#: a layout farther than this many tolerances is coarser than the features it misses: the rate
#: measured from it to the next is the features coming into view, slower than the rate near
#: the tolerance, and is taken as :data:`ASSUMED_RATE` at least (a face scan: 1,048 → 4,226
#: quads at a rate of 0.64, 4,226 → 14,397 at 1.30; the 14,397 asked for at 0.64 were within
#: 2e-3 by 2.8×, a 47 MB STEP file)
FAR = 4.0
#: the next count aims at this fraction of the tolerance (the maximum is a noisy figure)
AIM = 0.8
#: the next count grows by at least and at most these factors
GROWTH_RANGE = (1.25, 4.0)
#: samples per patch side of the surface when it is measured against the scan (split4: a
#: sub-patch is a quarter face, so 9 a face side)
MEASURE_SAMPLES = 5
#: a layout is refined locally (:func:`~g1patch.fitting.layout.refined_layout`) rather than
#: remade finer when at most this share of its faces are off the tolerance
LOCAL_SHARE = 0.25
#: ... and when the refined layout has at most this many times its faces: a refinement of most
#: of it is a finer layout, which the remesher makes better (the Stanford bunny scan's 1,034
#: quads refined to 3,893 folded 104 patches at the transitions, 1.4e-2 off; its next remeshed
#: layout, 4,185 quads, no fold after a refit and 3.6e-3; the airplane's 976 → 1,847, 2.3e-3,
#: is kept)
LOCAL_GROWTH = 2.0
#: rings of faces about the off ones refined with them (a bump on a sphere scan, one face off:
#: with one ring the fit folded 3 patches on the bump's flank, where the transition quads met
#: it; with two, 1,027 → 1,116 quads within the tolerance, no fold, where a finer layout took
#: 1,406 quads in two layouts; after the one-ring attempt, 2,890 in three)
REFINE_RINGS = 2
#: scan points a face needs to be refined (about 4 per quad it becomes), its vertices and the
#: samples its large facets would get (:func:`_refined_points`): finer than the scan's own
#: sampling, the fit has too few points per cage vertex and the cage tangles (Spot's 5,856
#: triangles: folded slivers at its horns)
REFINE_POINTS = 16
#: the share of the feature lines that may lie in gaps of the crease chains
#: (:func:`~g1patch.fitting.features.crease_gaps`): the remesher never follows every line to the
#: end (0.3 % and 0.5 % of a washer's and a cylinder's rims in gaps at 2,429 and 2,138 quads,
#: the fitted surfaces' largest turn between neighbouring samples 0.3°); at 2.6 % a washer's
#: rim had two gaps a quad long where the fitted surface turned by 12°
FEATURE_GAPS = 0.01
#: a triangle of at least this share of the area of the layout face nearest it is sampled inside
#: (:meth:`Scan.facet_samples`), to one point per ``1/SAMPLES_PER_FACE`` of that area: where a
#: face holds few scan vertices (a low-poly model, a CAD part's large flat facets). Smaller ones
#: are not: a facet's points lie on its chord, a sag inside a curved surface (a 96 × 48 torus
#: scan's triangle centroids are 2.6e-4 of the diagonal inside the torus; fitted to them too, its
#: surface sat 1.7× farther from the torus on average)
SPARSE_FACET = 0.25
#: ... and no layout face counts as smaller than this share of the mean (a face refined twice is
#: a sixteenth of its parent)
SMALLEST_FACE = 1.0 / 16.0
SAMPLES_PER_FACE = 16
#: a triangle is cut into at most this many squared samples (a sliver of a huge scan triangle)
MAX_FACET_SPLIT = 32
#: a connected part of a scan narrower than this (its bounding box's diagonal, of the scan's) is
#: an island, dropped (:func:`without_islands`)
ISLAND_SIZE = 0.05
#: a fit that folds is fitted again, at most this many times, fairer where it folds (the
#: Stanford bunny scan's 4,276-quad layout, its base holes cut open: 15, 13, 7 and 5 folded
#: patches; a fourth try is cheaper than the finer layout the fold would otherwise call for)
FOLD_REFITS = 3
#: by this factor on the fairness weight of the folded faces' vertices and a ring round them
FOLD_STIFFNESS = 30.0
#: a layout refined from its fitted cage that came out this many times farther than its parent
#: missed a feature the parent's cage does not resolve: the parent is refined again from its own
#: vertices (a narrow bump on a sphere: 2.2e-3 → 4.3e-3 refined from the cage, within from the
#: vertices); one less far is remade (a face scan's 3.5e-3 → 3.7e-3: refined from its vertices
#: too, 6.8e-3, a round that its finer layout's refinement, within, then lacked)
RETRY_FARTHER = 1.5
#: scan points beyond the tolerance that make a face off (one alone is a stray point or noise,
#: which the tolerance's 99.9th percentile lets be)
STRAY_POINTS = 2


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

    @property
    def centroids(self) -> FloatArray:
        """Per triangle its centroid ``(a + b + c) / 3``."""
        return self.points[self.triangles].mean(axis=1)

    @property
    def areas(self) -> FloatArray:
        """Per triangle its area ``|(b − a) × (c − a)| / 2``."""
        a, b, c = (self.points[self.triangles[:, k]] for k in range(3))
        return 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1)

    def facet_splits(self, area: FloatArray | float, least: FloatArray | float = 0.0) -> IntArray:
        """Per triangle the samples per side ``m = ⌊√(A / area)⌋`` (:data:`MAX_FACET_SPLIT` at
        most) of :meth:`facet_samples`, 0 where its area ``A`` is under ``least``; ``area`` and
        ``least`` are one figure or one per triangle."""
        areas = self.areas
        split = np.minimum(np.floor(np.sqrt(areas / area)), MAX_FACET_SPLIT).astype(np.int64)
        split[areas < least] = 0
        return split

    def facet_samples(
        self, area: FloatArray | float, least: FloatArray | float = 0.0
    ) -> tuple[FloatArray, FloatArray]:
        """Points inside the triangles of area at least ``least`` and ``area``, one per ``area``
        or so (one figure, or one per triangle), and their triangles' unit normals: a triangle
        of area A is cut into ``m² = ⌊√(A / area)⌋²`` equal triangles (m per side,
        :meth:`facet_splits`), sampled at their centroids ``p = b₀ a + b₁ b + b₂ c``,
        ``(b₁, b₂) = ((i + 1/3)/m, (j + 1/3)/m)`` for ``i + j ≤ m − 1`` and ``((i + 2/3)/m,
        (j + 2/3)/m)`` for ``i + j ≤ m − 2``. A scan's vertices alone leave a large facet
        unsampled: a low-poly model's surface bulges between them (a 12-triangle cube fitted to
        its 8 corners bowed out 4 % of its diagonal)."""
        areas = self.areas
        split = self.facet_splits(area, least)
        corners = self.points[self.triangles]  # (T, 3, 3)
        cross = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
        points, normals = [np.zeros((0, 3))], [np.zeros((0, 3))]
        for m in np.unique(split[split > 0]):  # a few sizes, each a batch of triangles
            mine = np.flatnonzero(split == m)
            i, j = np.meshgrid(np.arange(m), np.arange(m), indexing="ij")
            up, down = i + j <= m - 1, i + j <= m - 2
            second = np.concatenate([i[up] + 1 / 3, i[down] + 2 / 3]) / m
            third = np.concatenate([j[up] + 1 / 3, j[down] + 2 / 3]) / m
            weights = np.stack([1.0 - second - third, second, third], axis=1)  # (m², 3)
            points.append(np.einsum("sk,tkd->tsd", weights, corners[mine]).reshape(-1, 3))
            unit = cross[mine] / (2.0 * areas[mine, None])
            normals.append(np.repeat(unit, len(weights), axis=0))
        return np.concatenate(points), np.concatenate(normals)


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


def used_only(scan: Scan) -> Scan:
    """``scan`` without the vertices no triangle uses (PLY and OBJ files carry them: 359 of the
    1,872 vertices of a bone model, a quarter of an airplane's; fitted as points they pull the
    surface off the triangles); ``repairs`` says how many."""
    used = np.zeros(len(scan.points), dtype=bool)
    used[scan.triangles.reshape(-1)] = True
    unused = int((~used).sum())
    if not unused:
        return scan
    renumber = np.cumsum(used) - 1
    note = f"dropped {unused} vertices no triangle uses"
    return Scan(scan.points[used], renumber[scan.triangles], scan.source, (*scan.repairs, note))


def without_islands(scan: Scan) -> Scan:
    """``scan`` without its islands: connected parts (triangles sharing edges,
    :func:`~g1patch.fitting.scan_topology.triangle_parts`) whose bounding box's diagonal is under
    :data:`ISLAND_SIZE` of the whole scan's, the specks a range scan leaves (pymeshlab's sample
    face scan: 20 of its 22 parts, 485 of 166,259 triangles, each 0.3–4.9 % of the diagonal
    across; laid out and fitted they folded). ``repairs`` says how many; a scan of islands
    only is kept whole."""
    part = triangle_parts(scan.triangles, len(scan.points))
    count = int(part.max()) + 1 if len(part) else 0
    if count < 2:
        return scan
    corners = scan.points[scan.triangles]  # (T, 3, 3)
    low = np.full((count, 3), np.inf)
    high = np.full((count, 3), -np.inf)
    np.minimum.at(low, part, corners.min(axis=1))
    np.maximum.at(high, part, corners.max(axis=1))
    small = np.linalg.norm(high - low, axis=1) < ISLAND_SIZE * scan.diagonal
    if not small.any() or small.all():
        return scan
    keep = ~small[part]
    islands = int(small.sum())
    note = (
        f"dropped {islands} island{'s' if islands > 1 else ''} under {ISLAND_SIZE:.0%} of the "
        f"diagonal across ({int((~keep).sum())} triangles)"
    )
    kept = used_only(Scan(scan.points, scan.triangles[keep], scan.source))
    return Scan(kept.points, kept.triangles, scan.source, (*scan.repairs, note))


def welded(scan: Scan) -> Scan:
    """``scan`` with the vertices at one position merged into one (the first's index order
    kept) and the triangles that then repeat a corner dropped (a triangle ``(a, b, b)`` has an
    open edge ``b → b`` and a side run both ways); ``repairs`` says how many of each."""
    _, first, inverse = np.unique(scan.points, axis=0, return_index=True, return_inverse=True)
    duplicated = len(scan.points) - len(first)
    keep = np.sort(first)
    renumber = np.empty(len(first), dtype=np.int64)
    renumber[np.argsort(first)] = np.arange(len(first))  # unique rows → first-occurrence order
    triangles = renumber[inverse.reshape(-1)][scan.triangles]
    ordered = np.sort(triangles, axis=1)
    distinct = (ordered[:, 1:] != ordered[:, :-1]).all(axis=1)
    repeats = int((~distinct).sum())
    if not duplicated and not repeats:
        return scan
    notes = [f"welded {duplicated} duplicated vertices"] if duplicated else []
    if repeats:
        notes.append(f"dropped {repeats} triangles that repeat a corner")
    kept = Scan(scan.points[keep], triangles[distinct], scan.source, (*scan.repairs, *notes))
    return used_only(kept) if repeats else kept


def manifold(scan: Scan) -> Scan:
    """``scan`` with two triangles at most at every edge: at an edge of more, the two joined
    to the rest best are kept (the most of their other edges shared with one more triangle,
    then the larger), the others dropped (a fin on a sphere scan's edge: the fit was 6.8e-2 of
    the diagonal off, and the remesher's layout is made of a manifold scan); ``repairs`` says
    how many."""
    triangles = scan.triangles
    _, edge_of, counts = side_edges(triangles)
    at = counts[edge_of]  # per triangle side (T, 3): the triangles at its edge
    if not (at > 2).any():
        return scan
    joined = (at == 2).sum(axis=1)
    side = np.flatnonzero(at.reshape(-1) > 2)
    owner = side // 3
    order = np.lexsort((-scan.areas[owner], -joined[owner], edge_of.reshape(-1)[side]))
    edge = edge_of.reshape(-1)[side][order]
    start = np.searchsorted(edge, edge)  # the first side of each edge's run
    rank = np.arange(len(order)) - start
    drop = np.zeros(len(triangles), dtype=bool)
    drop[owner[order][rank >= 2]] = True
    note = f"dropped {int(drop.sum())} triangles at edges of more than two"
    return used_only(Scan(scan.points, triangles[~drop], scan.source, (*scan.repairs, note)))


def oriented(scan: Scan) -> Scan:
    """``scan`` with its triangles turned so that neighbours agree (an STL file's winding may
    not: with every other triangle reversed, a sphere scan's normals cancelled, every edge
    looked sharp and the fit folded 35 patches, G1 18°), in each part the fewer turned
    (:func:`~g1patch.fitting.scan_topology.orientation_flips`); ``repairs`` says how many."""
    flip = orientation_flips(scan.triangles, len(scan.points))
    if not flip.any():
        return scan
    triangles = np.where(flip[:, None], scan.triangles[:, ::-1], scan.triangles)
    note = f"turned {int(flip.sum())} triangles over to agree with their neighbours"
    return Scan(scan.points, triangles, scan.source, (*scan.repairs, note))


def holes_filled(scan: Scan, across: float) -> Scan:
    """``scan`` with its holes under ``across`` closed: a boundary loop (every vertex on it with
    one open edge in and one out) shorter than ``π · across`` gets a vertex at its vertices'
    mean and a fan of triangles ``(w, v, c)`` for its open edges ``v → w`` (wound as its
    neighbours). The layout closes a hole under a layout edge anyway
    (:func:`~g1patch.fitting.layout.bridging_faces` cuts only larger ones), and its surface
    then lies up to the hole's radius from the scan's triangles (a sphere scan with 20
    one-triangle holes: 5.7e-3 of the diagonal); over the fan it lies within the fan's sag.
    ``repairs`` says how many."""
    edges = boundary_edges(scan.triangles)
    if not len(edges) or not across > 0:
        return scan
    count = len(scan.points)
    loop = boundary_loops(edges, count)[edges[:, 0]]
    loops = int(loop.max()) + 1
    simple = (np.bincount(edges[:, 0], minlength=count) == 1) & (
        np.bincount(edges[:, 1], minlength=count) == 1
    )
    pinched = np.bincount(loop, weights=~simple[edges[:, 0]], minlength=loops) > 0
    length = np.linalg.norm(scan.points[edges[:, 1]] - scan.points[edges[:, 0]], axis=1)
    perimeter = np.bincount(loop, weights=length, minlength=loops)
    sides = np.bincount(loop, minlength=loops)
    small = (sides >= 3) & ~pinched & (perimeter < np.pi * across)
    if not small.any():
        return scan
    chosen = np.flatnonzero(small)
    centre_of = np.full(loops, -1, dtype=np.int64)
    centre_of[chosen] = count + np.arange(chosen.size)
    sums = np.zeros((loops, 3))
    np.add.at(sums, loop, scan.points[edges[:, 0]])
    fill = small[loop]
    fan = np.stack([edges[fill, 1], edges[fill, 0], centre_of[loop[fill]]], axis=1)
    note = f"filled {chosen.size} holes under a layout edge ({across:.3g}) across"
    return Scan(
        np.concatenate([scan.points, sums[chosen] / sides[chosen, None]]),
        np.concatenate([scan.triangles, fan]),
        scan.source,
        (*scan.repairs, f"{note} with {len(fan)} triangles"),
    )


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
    ``(max, p99.9, rms)``. The tolerance bounds the scan → surface 99.9th percentile (a scan's
    noise and stray points are not chased) and the surface → scan maximum (the surface leaves
    the scan nowhere). ``faces``: cage quads; ``rounds``: layouts tried; ``rms``: the model's
    RMS per solve of the last round; ``seconds``: wall time; ``creases``: cage edges kept sharp
    (the scan's features, ``sharp_angle``); ``repairs``: what was repaired in the scan;
    ``feature_gaps``: the share of the scan's feature lines no crease follows
    (:func:`~g1patch.fitting.features.crease_gaps`), where the surface rounds a sharp edge;
    ``folds``: folded patches (as :func:`~g1patch.continuity.check` counts them); ``g1``: the
    largest angle between the patches' normals across a smooth edge or at a corner, degrees (as
    ``check`` measures it); ``skipped``: the layouts that could not be used, each with why."""

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
    feature_gaps: float = 0.0
    folds: int = 0
    g1: float = 0.0
    skipped: tuple[str, ...] = ()

    @property
    def worst(self) -> float:
        """The distance the tolerance bounds, of the diagonal: the larger of the scan → surface
        99.9th percentile and the surface → scan maximum."""
        return _bounded(self.to_surface, self.to_scan) / self.diagonal

    @property
    def met(self) -> bool:
        """Within the tolerance, no fold, the feature lines creases (but :data:`FEATURE_GAPS`
        of them), exactly G1 (:data:`~g1patch.continuity.EXACT_G1_DEG`)."""
        return (
            self.worst <= self.tolerance
            and self.folds == 0
            and self.feature_gaps <= FEATURE_GAPS
            and self.g1 <= EXACT_G1_DEG
        )

    def summary(self) -> str:
        """The report as a table (distances also of the diagonal)."""

        def row(name: str, figures: tuple[float, float, float]) -> str:
            relative = " / ".join(f"{value / self.diagonal:.2e}" for value in figures)
            absolute = " / ".join(f"{value:.3g}" for value in figures)
            return f"{name:<32}{relative}  ({absolute})"

        verdict = "within" if self.worst <= self.tolerance else "NOT within"
        return "\n".join(
            [
                f"{'cage quads / patches':<32}{self.faces} / {self.patches} "
                f"({self.rounds} layouts)",
                f"{'crease edges (features)':<32}{self.creases}"
                + (
                    f" ({self.feature_gaps:.1%} of the feature lines in gaps: rounded there)"
                    if self.feature_gaps > FEATURE_GAPS
                    else ""
                ),
                f"{'folded patches':<32}{self.folds}",
                f"{'G1: largest angle':<32}{self.g1:.1e}°"
                + ("" if self.g1 <= EXACT_G1_DEG else f" (NOT within {EXACT_G1_DEG:g}°)"),
                f"{'distance, of diagonal':<32}max / p99.9 / rms  (model units)",
                row("scan → surface", self.to_surface),
                row("surface → scan", self.to_scan),
                f"{'tolerance':<32}{self.tolerance:g} of the diagonal: {verdict} "
                f"({self.worst:.2e})",
                f"{'time':<32}{self.seconds:.1f} s",
            ]
            + [f"{'skipped layout':<32}{reason}" for reason in self.skipped]
        )

    def to_dict(self) -> dict[str, Any]:
        """The figures, JSON-ready."""
        names = ("max", "p99.9", "rms")
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
            "feature_gaps": self.feature_gaps,
            "folds": self.folds,
            "g1_deg": self.g1,
            "repairs": list(self.repairs),
            "skipped_layouts": list(self.skipped),
        }


def _figures(distances: FloatArray) -> tuple[float, float, float]:
    return (
        float(distances.max()),
        float(np.percentile(distances, 99.9)),
        float(np.sqrt(np.mean(distances**2))),
    )


def _bounded(to_surface: tuple[float, ...], to_scan: tuple[float, ...]) -> float:
    """What the tolerance bounds (model units): scan → surface p99.9, surface → scan max."""
    return float(np.max([to_surface[1], to_scan[0]]))  # NaN stays NaN: never "within"


def measure(
    network: PatchNetwork,
    scan: Scan,
    faces: int | None = None,
    tolerance: float = np.inf,
    samples: FloatArray | None = None,
) -> tuple[tuple[float, ...], tuple[float, ...], FloatArray | None]:
    """Two-way distances between the surface (sampled :data:`MEASURE_SAMPLES` per patch side,
    triangulated) and the scan (its vertices and the ``samples`` inside its facets): ``(to_surface,
    to_scan)`` figures (max, p99.9, rms), and with the cage's face count ``faces`` (its patches
    face after face) per face (F, 2): the largest distance of its surface samples to the scan, and
    how many scan points whose nearest surface sample is on it are farther than ``tolerance``
    (model units)."""
    mesh = tessellate(network, MEASURE_SAMPLES)
    points = scan.points if samples is None else np.concatenate([scan.points, samples])
    to_surface = mesh_distance(points, mesh.points, mesh.triangles)
    to_scan = mesh_distance(mesh.points, scan.points, scan.triangles)
    per_face = None
    if faces is not None:
        grid = np.linspace(0.0, 1.0, MEASURE_SAMPLES)
        samples = network.patches.evaluate_grid(grid, grid).reshape(-1, 3)
        tree = cKDTree(samples)
        face_of_sample = np.arange(len(samples)) // (
            MEASURE_SAMPLES**2 * network.n_patches // faces
        )
        per_face = np.zeros((faces, 2))
        np.maximum.at(per_face[:, 0], face_of_sample[tree.query(mesh.points)[1]], to_scan)
        nearest = face_of_sample[tree.query(points)[1]]
        per_face[:, 1] = np.bincount(nearest[to_surface > tolerance], minlength=faces)
    return _figures(to_surface), _figures(to_scan), per_face


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
    ``faces``: the layout's quad count (about), else from :data:`START_FACES`, refined locally
    or remade finer up to :data:`MAX_ROUNDS` times (:data:`ROUND_POINTS`) while the distance
    exceeds ``tolerance`` (of the diagonal; :class:`FitReport`).
    ``sharp_angle`` (degrees): the scan's edges whose triangles turn by more than that are
    features; the layout edges along them become infinitely sharp creases
    (:mod:`~g1patch.fitting.features`), seams of the network and edges of its STEP solid.
    """
    tolerance = check_tolerance(tolerance)
    started = time.perf_counter()
    scan = without_islands(oriented(manifold(welded(used_only(scan)))))
    diagonal = scan.diagonal
    if not diagonal > 0:
        raise InputError(f"{scan.source or 'scan'}: the scan has no extent")
    count = faces if faces is not None else min(START_FACES, max(64, len(scan.triangles) // 8))
    scan = holes_filled(scan, _layout_edge(scan, layout, count))
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
    corner_angle = FIT_SHARP_ANGLE if sharp_angle is None else sharp_angle
    rounds, best, tried, fitted_points = 0, None, [], 0
    skipped: list[str] = []
    budget = face_budget(len(scan.triangles))
    if adaptive:
        count = min(count, budget)
    refine: QuadMesh | None = None  # the next layout, when it is the last one refined locally
    # the layout last refined from its fitted cage, its off faces and distance
    parent: tuple[QuadMesh, FloatArray, float] | None = None
    while True:
        rounds += 1
        try:
            if layout is not None:
                cage_layout = layout
            elif refine is not None:
                cage_layout = refine
            else:
                cage_layout = _layout(scan, count)
            if refine is None:  # a refined layout keeps the features its parent was given
                snapped = snap_to_features(cage_layout, features, feature_corners)
                creased = layout_creases(snapped, features, feature_corners)
                reach = boundary_reach(creased)
                corners = boundary_corners(scan.points, scan.triangles, corner_angle, reach)
                cage_layout = layout_corners(creased, corners)
                if method == "split4":  # as split4 builds it
                    cage_layout = without_lonely_creases(cage_layout)
            face_area = _sampled_areas(cage_layout, scan)
            samples, sample_normals = scan.facet_samples(
                face_area / SAMPLES_PER_FACE, SPARSE_FACET * face_area
            )
            points = np.concatenate([scan.points, samples])
            fitted_points += len(points)
            point_normals = np.concatenate([normals, sample_normals])
            fitted, network, folded = _fitted(
                points, point_normals, cage_layout, scan.triangles, method
            )
        except (ConstructionError, MeshError) as error:  # unusable: the next face count
            if not adaptive:
                raise
            which = "the refined layout" if refine is not None else f"{count:,} quads asked"
            skipped.append(f"{which}: {error}")
            tried.append((count, np.inf))
            off, folds = None, 0
        else:
            to_surface, to_scan, off = measure(
                network, scan, cage_layout.n_faces, tolerance * diagonal, samples
            )
            worst = _bounded(to_surface, to_scan) / diagonal
            if refine is None:  # the error model is the remesher's: refined layouts stay out
                tried.append((cage_layout.n_faces, worst))
            gaps = crease_gaps(cage_layout, features)
            folds = int(folded.sum())
            rank = layout_rank(folds, worst, tolerance, gaps)  # as if exactly G1: check later
            if best is None or rank < best[0]:
                angle = _largest_angle(check(network))  # only for a layout that may be kept
                rank = layout_rank(folds, worst, tolerance, gaps, angle)
                if best is None or rank < best[0]:
                    best = (rank, gaps, cage_layout, fitted, network, to_surface, to_scan, angle)
            if not adaptive or rank == (False, 0, False, False, worst):
                break
        if rounds >= MAX_ROUNDS or (rounds >= MIN_ROUNDS and fitted_points >= ROUND_POINTS):
            break
        # a folded fit is remade, not refined (its folds spread: Spot's horns), nor is one that
        # ranks below a layout before it (a refinement that made the fit worse)
        kept = off is not None and not folds and best is not None and best[2] is cage_layout
        refine = None
        if kept and off is not None:  # refined from its fitted cage first …
            refine = _locally_refined(
                cage_layout, fitted.cage, off, tolerance * diagonal, budget, scan
            )
            parent = (cage_layout, off, worst) if refine is not None else None
        elif parent is not None and (off is None or worst > RETRY_FARTHER * parent[2]):
            # … and where that came out far worse, from its vertices
            refine = _locally_refined(
                parent[0], None, parent[1], tolerance * diagonal, budget, scan
            )
            parent = None
        else:
            parent = None
        if refine is None:
            if count >= budget:
                break
            count = next_count(tried, tolerance, count, budget)
    if best is None:
        raise ConstructionError(f"no usable quad layout in {rounds} tries (last: {skipped[-1]})")
    (_, folds, _, _, worst), gaps, cage_layout, fitted, network, to_surface, to_scan, angle = best
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
        gaps,
        folds,
        angle,
        tuple(skipped),
    )
    return network, report


def _fitted(
    points: FloatArray,
    point_normals: FloatArray,
    layout: QuadMesh,
    triangles: IntArray,
    method: str,
) -> tuple[FitCage, PatchNetwork, NDArray[np.bool_]]:
    """The cage fitted to the ``points`` on ``layout``, its network and folded patches: where it
    folds, fitted again stiffer round the folds (:func:`_stiffened`, :data:`FOLD_REFITS` times at
    most), the attempt with the fewest folds kept. A refit whose cage pinches a face to nothing
    ends the refits; a first fit that does raises (the layout is unusable: a cycloidal gear's
    2,842-quad layout, a thin tooth's face fitted to zero area)."""
    stiffness: FloatArray | None = None
    attempts: list[tuple[int, int, FitCage, PatchNetwork, NDArray[np.bool_]]] = []
    for _ in range(FOLD_REFITS + 1):
        try:
            attempt = fit_cage(points, point_normals, layout, triangles, stiffness=stiffness)
        except MeshError:
            if not attempts:
                raise
            break
        # the scan, not the cage's limit, is what the fit is measured against (by the caller)
        made = build_network(attempt.cage, method, "limit", tolerance=None)
        bent = folded_patches(made.patches, FOLD_SAMPLES)  # as check counts
        attempts.append((int(bent.sum()), len(attempts), attempt, made, bent))
        if not bent.any():
            break
        stiffness = _stiffened(layout, made, bent, stiffness)
    _, _, fitted, network, folded = min(attempts, key=lambda a: a[:2])
    return fitted, network, folded


def _largest_angle(checked: ContinuityReport) -> float:
    """The largest G1 angle ``check`` measured, across smooth edges and at corners (degrees)."""
    return max(checked.max_edge_angle_deg, checked.max_corner_angle_deg)


def layout_rank(
    folds: int, worst: float, tolerance: float, gaps: float, angle: float = 0.0
) -> tuple[bool, int, bool, bool, float]:
    """How a fitted layout ranks (the least is kept): exactly G1 (its largest G1 ``angle`` as
    ``check`` measures it, degrees, within :data:`~g1patch.continuity.EXACT_G1_DEG`: a trimesh
    CAD model's layout, its crease chains meeting three at a vertex, came out 1.1° off G1 along
    one smooth edge, and was kept over an exactly G1 one), then fewer folds, then within the
    ``tolerance``, then (within it) the feature lines followed (``gaps`` ≤ :data:`FEATURE_GAPS`),
    then the ``worst`` distance. A finer layout is not always nearer, and where none is within,
    gaps in stray feature lines (a decimated bunny's chains of steep facets) do not outrank
    distance: its 1,034-quad layout at 1.5e-2 was kept over a 4,126-quad one at 3.2e-3."""
    within = worst <= tolerance
    return (angle > EXACT_G1_DEG, folds, not within, within and gaps > FEATURE_GAPS, worst)


def face_budget(triangles: int) -> int:
    """The most quads an adaptive fit of a scan of ``triangles`` asks for: :data:`MAX_FACES`, and
    half the triangles (a quad is two triangles' worth of data), less :data:`BUDGET_MARGIN` (the
    remesher's count is the request's within a few per cent)."""
    return max(16, int((1.0 - BUDGET_MARGIN) * min(MAX_FACES, triangles // 2)))


def next_faces(tried: list[tuple[int, float]], tolerance: float, count: int) -> int:
    """The face count the measured errors call for: ``tried`` holds (faces, worst distance of
    the diagonal) per layout so far (∞: unusable), ``count`` the last count asked for. The error
    is modelled as ``e ∝ faces^−r``, r from the last two usable layouts (:data:`ASSUMED_RATE`
    before there are two; kept in :data:`RATE_RANGE`, at least :data:`ASSUMED_RATE` from a layout
    :data:`FAR` off), and the count that brings it to
    :data:`AIM` × ``tolerance`` is asked for, growing by a factor in :data:`GROWTH_RANGE`."""
    usable = [(faces, error) for faces, error in tried if np.isfinite(error) and error > 0]
    if not usable:
        return int(count * GROWTH_RANGE[0] ** 2)
    rate = ASSUMED_RATE
    if len(usable) >= 2 and usable[-1][0] != usable[-2][0]:
        (f0, e0), (f1, e1) = usable[-2], usable[-1]
        rate = float(np.clip(np.log(e0 / e1) / np.log(f1 / f0), *RATE_RANGE))
        if e0 > FAR * tolerance:  # from a layout that missed features: no slower than assumed
            rate = max(rate, ASSUMED_RATE)
    faces, error = usable[-1]
    growth = (error / (AIM * tolerance)) ** (1.0 / rate)
    return int(np.ceil(max(faces, count) * float(np.clip(growth, *GROWTH_RANGE))))


def next_count(tried: list[tuple[int, float]], tolerance: float, count: int, budget: int) -> int:
    """The next remesher's face count: :func:`next_faces`, at most ``budget``; where that asks for
    the budget and no layout so far had half of it, half (``budget`` / :data:`LOCAL_GROWTH`), so
    that the layout can still be refined locally within the budget where it is off, rather
    than uniformly finer everywhere (fandisk, 5,750 triangles: 734 quads, then 2,810 at its
    budget, 3.9e-3 off; now 734, then 1,318 refined round its off faces to 2,504, 2.7e-3)."""
    wanted = next_faces(tried, tolerance, count)
    half = int(budget / LOCAL_GROWTH)
    largest = max([count, *(faces for faces, _ in tried)])
    if wanted >= budget and largest * GROWTH_RANGE[0] <= half:
        return half
    return min(wanted, budget)


def _locally_refined(
    layout: QuadMesh,
    cage: QuadMesh | None,
    per_face: FloatArray,
    tolerance: float,
    budget: int,
    scan: Scan,
) -> QuadMesh | None:
    """``layout`` refined round its faces off the ``tolerance`` (model units; ``per_face`` as
    :func:`measure` gives it: a surface sample farther, or :data:`STRAY_POINTS` scan points)
    that would hold :data:`REFINE_POINTS` scan points refined (:func:`_refined_points`;
    :func:`~g1patch.fitting.layout.refined_layout`): at the positions of the ``cage`` fitted on
    it split the same way, so that the refit starts from the surface it refines, or (``cage``
    None) at the layout's own, the new vertices moved onto the scan as the remesher's are. From
    the cage, the Stanford bunny scan's 4,185-quad layout refined twice was within at 4,686
    quads, where refined from its vertices it came out farther and the fit ended at 9,732; but
    a narrow bump on a sphere, which the parent's cage does not resolve, is only within when
    refined from the vertices (the fit's feet on the start surface miss its tip); so both are
    tried (:func:`fit_network`). None where the off faces are more
    than :data:`LOCAL_SHARE` of all (a finer layout is the cheaper cure), none can be refined,
    or the refined layout would exceed ``budget`` quads or :data:`LOCAL_GROWTH` times the
    layout's. Faces on a feature line are refined too (a CAD part's are off there: fandisk's
    1,318 quads, 45 off, refined to 2,504 went from 4.9e-3 to 2.7e-3, where its next remeshed
    layouts, 2,724 and 2,810 quads, stayed at 3.5e-3 and 3.9e-3); a split edge on a crease
    stays one."""
    off: NDArray[np.bool_] = (per_face[:, 0] > tolerance) | (per_face[:, 1] >= STRAY_POINTS)
    marked: NDArray[np.bool_] = off & (_refined_points(layout, scan) >= REFINE_POINTS)
    if not marked.any() or off.mean() > LOCAL_SHARE:
        return None
    refined = refined_layout(
        layout if cage is None else cage, grow(layout.topology, marked, REFINE_RINGS)
    )
    if refined.n_faces > min(budget, LOCAL_GROWTH * layout.n_faces):
        return None
    if cage is not None:
        return refined
    vertices = refined.vertices.copy()
    new = np.arange(layout.n_vertices, refined.n_vertices)
    quads = refined.faces
    normals = vertex_normals(vertices, np.concatenate([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]]))
    triangle, weights = _Triangles(scan.points, scan.triangles).feet(vertices[new], normals[new])
    vertices[new] = np.einsum("nk,nkd->nd", weights, scan.points[scan.triangles[triangle]])
    try:
        return refined.with_vertices(vertices)
    except MeshError:  # two new vertices on one scan point: keep them where the split made them
        return refined


def _nearest_faces(layout: QuadMesh, points: FloatArray) -> IntArray:
    """Per point the layout face whose centre is nearest."""
    centres = layout.vertices[layout.faces].mean(axis=1)
    return cKDTree(centres).query(points)[1].astype(np.int64)


def _sampled_areas(layout: QuadMesh, scan: Scan, nearest: IntArray | None = None) -> FloatArray:
    """Per scan triangle the area its facet samples are taken at: that of the layout face
    nearest it (``nearest``, else found), at least :data:`SMALLEST_FACE` of the layout's mean
    (a flattened sphere's layout had faces of almost no area, and a million samples)."""
    areas = quad_areas(layout.vertices, layout.faces)
    if nearest is None:
        nearest = _nearest_faces(layout, scan.centroids)
    return np.maximum(areas[nearest], SMALLEST_FACE * float(scan.areas.sum()) / layout.n_faces)


def _refined_points(layout: QuadMesh, scan: Scan) -> IntArray:
    """Per layout face the scan points it would hold split into four: the scan's vertices
    nearest it and the samples the fit would take inside the triangles nearest it at a quarter
    of its area (:meth:`Scan.facet_samples`) — a low-poly scan's facets are points too."""
    nearest = _nearest_faces(layout, scan.centroids)
    quarter = 0.25 * _sampled_areas(layout, scan, nearest)
    split = scan.facet_splits(quarter / SAMPLES_PER_FACE, SPARSE_FACET * quarter)
    vertices = np.bincount(_nearest_faces(layout, scan.points), minlength=layout.n_faces)
    samples = np.bincount(nearest, weights=split**2, minlength=layout.n_faces)
    return vertices + samples.astype(np.int64)


def _layout_edge(scan: Scan, layout: QuadMesh | None, faces: int) -> float:
    """The first layout's edge length: the median of a given ``layout``'s, else that of
    ``faces`` squares covering the scan's area."""
    if layout is not None:
        return median_edge(layout)
    return float(np.sqrt(scan.areas.sum() / max(faces, 1)))


def _stiffened(
    layout: QuadMesh, network: PatchNetwork, folded: NDArray[np.bool_], stiffness: FloatArray | None
) -> FloatArray:
    """Per cage vertex the fairness weight of the next fit: :data:`FOLD_STIFFNESS` times the last
    at the vertices of the faces whose patches fold and a ring round them."""
    faces = np.zeros(layout.n_faces, dtype=bool)
    faces[np.flatnonzero(folded) * layout.n_faces // network.n_patches] = True
    around = grow(layout.topology, faces, 1)
    out = np.ones(layout.n_vertices) if stiffness is None else stiffness.copy()
    out[np.unique(layout.faces[around])] *= FOLD_STIFFNESS
    return out


def _layout(scan: Scan, faces: int) -> QuadMesh:
    """The remesher's quads as a validated (and where needed repaired) quad mesh, without the
    faces that span the scan's holes (:func:`~g1patch.fitting.layout.bridging_faces`: the
    surface keeps the holes, its rim tied to theirs)."""
    vertices, quads = quad_layout(scan.points, scan.triangles, int(faces))
    source = f"layout of {scan.source or 'the scan'}"
    layout = QuadMesh.from_arrays(vertices, quads, source=source)
    bridges = bridging_faces(layout, scan.points, scan.triangles)
    if not bridges.any() or bridges.all():
        return layout
    return QuadMesh.from_arrays(layout.vertices, layout.faces[~bridges], source=source)
