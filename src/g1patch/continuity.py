"""How smooth is a patch network? G0 gaps and G1 angles on every shared edge and corner, folds,
fairness.

For every interior edge shared by patches L and R the edge is sampled at K ≥ 33 parameters,
both ends included, from both sides; exact first derivatives give the normals
``n = p_u × p_v`` and the G1 angle is ``atan2(|n_L × n_R|, n_L · n_R)`` (accurate near 0, where
arccos floors at ~1e-6°). The G0 gap is ``|p_L − p_R|``, reported relative to the bounding-box
diagonal. Corners: the angle between the normals of every pair of patches meeting at a point
within one sector (:meth:`PatchNetwork.corner_sectors`: the patches a walk around the point
reaches without crossing a seam).

**Seams** (``network.seam``: edges sharp on purpose) are only meant to be G0. They are measured
like every shared edge but reported apart: their number, their largest G0 gap and the range
(min, max over all their samples) of the angle between the two sides' normals. They never count
as G1 failures or folds; a G0 gap above :data:`SEAM_G0_RTOL` on a seam still fails the check.

On a ``G × G`` grid of every patch (``G = fold_samples``, both borders included):

* degenerate normals: ``|p_u × p_v| ≤ degenerate_rtol · diag²`` (collapsed edges);
* folds (intrinsic, DESIGN §4): a patch is folded where two neighbouring samples (along u or v)
  have normals more than 90° apart (``n_a · n_b < 0``), or where a sample of a corner's grid cell
  has its normal against the normal at that corner; both patches of a shared edge are folded
  where their normals at one point of the edge are more than 90° apart (G1 angle > 90°: the
  surface turns back across the edge), unless the edge is a seam. Degenerate normals are skipped;
* fairness: the normal turn ``θ = 2 asin(|n̂_a − n̂_b| / 2)`` between neighbouring samples (median,
  p99, max over all pairs of all patches) and the thin-plate energy
  ``∫∫ |p_uu|² + 2|p_uv|² + |p_vv|² du dv = ∫∫ |∇p_u|² + |∇p_v|² du dv`` (``p_uv = p_vu``), summed
  over the patches and divided by diag².

**Evaluation.** From :data:`KERNEL_PATCHES` patches on (``compiled=None``, the default; ``True``
always) numba kernels do the work, compiled on first use and cached on disk (see "Compiled
kernels" below): one parallel pass over the shared edges (both
sides of each), one over the corner sectors and one over the patches' grids, several patches at a
time. ``compiled=False`` runs the NumPy reference, block by block. The two agree exactly on
counts, folds, their locations, the turn figures, and within a few ULP on angles, gaps and energy
(tests/test_check_kernels.py states and tests the bounds).

Everything is measured in the patches' local coordinates (``patches.local()`` when the patch set
has a frame): angles do not depend on the frame, gaps and deviations are relative to the diagonal,
so the figures are the same wherever the model sits and whatever its size.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import cache
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ._grid import BLOCK_POINTS
from .basis import basis_values
from .errors import InputError
from .gregory import BEZIER_INDEX, INTERIOR_INDEX, GregoryPatchSet, gregory_weights
from .network import Patches, PatchNetwork, edge_parameters, network_of
from .patches import CORNER_PARAMETERS, PatchSet

__all__ = [
    "SEAM_G0_RTOL",
    "ContinuityReport",
    "check",
    "fairness",
    "folded_patches",
    "angle_between",
    "format_reports",
]

DEGENERATE_RTOL = 1e-13
"""|p_u × p_v| ≤ DEGENERATE_RTOL · diag² is a degenerate normal. At a collapsed edge the
derivative is a sum of equal points with weights summing to zero, ~1e-16 · diag, so the cross
product there is ~1e-16 · diag²; a real patch of a 1 M-quad mesh has |p_u × p_v| ~ 1e-6 · diag²."""

FOLD_SAMPLES = 17
"""Grid samples per patch side for folds, degenerate normals and fairness. Newell's teapot, the
tightest legitimate curls in the shared data, turns its normal by 115° between neighbouring
samples of a 9 × 9 grid (at the spout, patch 18), which the 90° rule would call a fold;
on the 17 × 17 grid its largest turn between neighbours is 69°."""

MAX_FOLD_LOCATIONS = 10
"""The report locates the first this many folded patches."""

SEAM_G0_RTOL = 1e-12
"""The largest G0 gap (relative to the bounding-box diagonal) a seam may have and pass: its two
sides share one boundary curve, equal up to rounding."""

# Histogram of the turns, in bounded memory: the squared chord ``s = |n̂_a − n̂_b|² = 4 sin²(θ/2)``
# (monotone in θ) as float32, whose bit pattern read as an integer is monotone too; its top
# 8 exponent + 8 mantissa bits make 256 bins per octave of s (bins 0.27 % wide in s, 0.14 % in θ
# for small θ), from θ = 1e-12° to 180°, and a bin 0 for smaller turns.
_SHIFT = 23 - 8
_MIN_TURN_DEG = 1e-12


def _chord_codes(chord2: NDArray[np.floating[Any]]) -> NDArray[np.int32]:
    return np.asarray(chord2, dtype=np.float32).view(np.int32) >> _SHIFT


_CODE_MIN = int(_chord_codes(np.array([4.0 * np.sin(np.radians(_MIN_TURN_DEG) / 2.0) ** 2]))[0])
_CODE_MAX = int(_chord_codes(np.array([4.0]))[0])
_BINS = _CODE_MAX - _CODE_MIN + 2
#: bin b holds squared chords in [_EDGES[b], _EDGES[b + 1])
_EDGES = np.r_[
    0.0, (np.arange(_CODE_MIN, _CODE_MAX + 2, dtype=np.int32) << _SHIFT).view(np.float32)
].astype(np.float64)


def angle_between(a: NDArray[np.float64], b: NDArray[np.float64]) -> NDArray[np.float64]:
    """Angle in degrees between vectors along the last axis: ``atan2(|a × b|, a · b)``."""
    a, b = np.broadcast_arrays(np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64))
    shape = a.shape[:-1]
    return _angle3(_planar(a.reshape(-1, 3)), _planar(b.reshape(-1, 3))).reshape(shape)[()]


@dataclass(frozen=True)
class ContinuityReport:
    """The measured smoothness of a network (angles in degrees, gaps relative to the bbox
    diagonal)."""

    patches: int
    shared_edges: int
    open_edges: int
    collapsed_edges: int
    collapsed_patch_edges: int
    samples_per_edge: int
    max_edge_angle_deg: float
    mean_edge_angle_deg: float
    max_corner_angle_deg: float
    max_g0_gap: float
    degenerate_normals: int
    folds: int
    inconsistent_orientation_edges: int
    bounding_box_diagonal: float
    max_vertex_deviation: float | None
    #: grid samples per patch side of the fold, degenerate-normal and fairness measures
    fold_samples: int
    #: (patch, u, v) of the first offending sample of the first folded patches (at most 10)
    fold_locations: tuple[tuple[int, float, float], ...]
    turn_median_deg: float
    turn_p99_deg: float
    turn_max_deg: float
    thin_plate: float
    #: shared edges that are seams (sharp on purpose, G0 only), their largest G0 gap (relative)
    #: and the smallest and largest angle between the sides' normals on them (None without seams);
    #: the edge and corner figures above leave them out
    seam_edges: int
    seam_g0_max: float
    seam_angle_min_deg: float | None
    seam_angle_max_deg: float | None
    #: per shared edge: (patch, edge) of both sides, max G1 angle (deg), max G0 gap (relative), seam
    edge_patches: NDArray[np.int64] = field(repr=False)
    edge_sides: NDArray[np.int64] = field(repr=False)
    edge_angle_deg: NDArray[np.float64] = field(repr=False)
    edge_gap: NDArray[np.float64] = field(repr=False)
    edge_seam: NDArray[np.bool_] = field(repr=False)

    @property
    def worst_edge(self) -> dict[str, Any] | None:
        """The smooth (non-seam) shared edge with the largest G1 angle: its patches, edges, angle
        and gap."""
        if self.shared_edges == self.seam_edges:
            return None
        index = int(np.argmax(np.where(self.edge_seam, -np.inf, self.edge_angle_deg)))
        return {
            "patches": [int(p) for p in self.edge_patches[index]],
            "edges": [int(k) for k in self.edge_sides[index]],
            "angle_deg": float(self.edge_angle_deg[index]),
            "g0_gap": float(self.edge_gap[index]),
        }

    def is_g1(self, max_angle_deg: float = 1e-9) -> bool:
        """True when every smooth edge and every corner sector's angle is within ``max_angle_deg``
        (folds and seams aside)."""
        return max(self.max_edge_angle_deg, self.max_corner_angle_deg) <= max_angle_deg

    def seams_closed(self, max_gap: float = SEAM_G0_RTOL) -> bool:
        """True when every seam's G0 gap (relative to the bbox diagonal) is within ``max_gap``."""
        return self.seam_g0_max <= max_gap

    def passes(self, max_angle_deg: float = 1e-9, max_seam_gap: float = SEAM_G0_RTOL) -> bool:
        """The check verdict: :meth:`is_g1`, no patch folds and :meth:`seams_closed`."""
        return self.is_g1(max_angle_deg) and self.folds == 0 and self.seams_closed(max_seam_gap)

    @property
    def seams(self) -> dict[str, Any]:
        """The seam figures: ``count``, ``g0_max``, ``angle_min_deg``, ``angle_max_deg``."""
        return {
            "count": self.seam_edges,
            "g0_max": self.seam_g0_max,
            "angle_min_deg": self.seam_angle_min_deg,
            "angle_max_deg": self.seam_angle_max_deg,
        }

    @property
    def fold_location_dicts(self) -> list[dict[str, Any]]:
        """:attr:`fold_locations` as ``{"patch", "u", "v"}`` dicts."""
        return [{"patch": patch, "u": u, "v": v} for patch, u, v in self.fold_locations]

    @property
    def fairness(self) -> dict[str, float]:
        """The fairness figures, keyed as :func:`fairness` returns them."""
        return {
            "turn_median_deg": self.turn_median_deg,
            "turn_p99_deg": self.turn_p99_deg,
            "turn_max_deg": self.turn_max_deg,
            "thin_plate": self.thin_plate,
        }

    def to_dict(self) -> dict[str, Any]:
        """The scalar figures and the worst edge, JSON-ready."""
        return {
            "patches": self.patches,
            "shared_edges": self.shared_edges,
            "open_edges": self.open_edges,
            "collapsed_edges": self.collapsed_edges,
            "collapsed_patch_edges": self.collapsed_patch_edges,
            "samples_per_edge": self.samples_per_edge,
            "max_edge_angle_deg": self.max_edge_angle_deg,
            "mean_edge_angle_deg": self.mean_edge_angle_deg,
            "max_corner_angle_deg": self.max_corner_angle_deg,
            "max_g0_gap": self.max_g0_gap,
            "degenerate_normals": self.degenerate_normals,
            "folds": self.folds,
            "inconsistent_orientation_edges": self.inconsistent_orientation_edges,
            "bounding_box_diagonal": self.bounding_box_diagonal,
            "max_vertex_deviation": self.max_vertex_deviation,
            "worst_edge": self.worst_edge,
            "seams": self.seams,
            "fold_samples": self.fold_samples,
            "fold_locations": self.fold_location_dicts,
            **self.fairness,
        }

    def rows(self) -> list[tuple[str, str]]:
        """(label, value) pairs of the figures, as :meth:`summary` prints them."""
        rows = [
            ("patches", f"{self.patches}"),
            ("shared / open edges", f"{self.shared_edges} / {self.open_edges}"),
            ("max G1 angle on edges", f"{self.max_edge_angle_deg:.3e}°"),
            ("mean G1 angle on edges", f"{self.mean_edge_angle_deg:.3e}°"),
            ("max G1 angle at corners", f"{self.max_corner_angle_deg:.3e}°"),
            ("max G0 gap (of bbox diag)", f"{self.max_g0_gap:.3e}"),
            ("degenerate normals", f"{self.degenerate_normals}"),
            ("folds", f"{self.folds}"),
            (
                "normal turn median / p99 / max",
                f"{self.turn_median_deg:.3g}° / {self.turn_p99_deg:.3g}° / "
                f"{self.turn_max_deg:.3g}°",
            ),
            ("thin-plate energy (of diag²)", f"{self.thin_plate:.4g}"),
        ]
        if self.fold_locations:
            patch, u, v = self.fold_locations[0]
            rows.insert(
                rows.index(("folds", f"{self.folds}")) + 1,
                ("first fold", f"patch {patch} at (u, v) = ({u:.4g}, {v:.4g})"),
            )
        if self.seam_edges:
            rows[2:2] = [
                ("seams (sharp on purpose)", f"{self.seam_edges}"),
                (
                    "seam angle min / max",
                    f"{self.seam_angle_min_deg:.4g}° / {self.seam_angle_max_deg:.4g}°",
                ),
                ("seam max G0 gap (of bbox diag)", f"{self.seam_g0_max:.3e}"),
            ]
        if self.collapsed_edges:
            rows.insert(
                2,
                (
                    "collapsed edges",
                    f"{self.collapsed_edges} ({self.collapsed_patch_edges} patch edges)",
                ),
            )
        if self.inconsistent_orientation_edges:
            rows.append(
                ("edges with flipped orientation", f"{self.inconsistent_orientation_edges}")
            )
        if self.max_vertex_deviation is not None:
            rows.append(("max vertex deviation (of diag)", f"{self.max_vertex_deviation:.3e}"))
        worst = self.worst_edge
        if worst is not None:
            rows.append(
                (
                    "worst edge",
                    f"patch {worst['patches'][0]} edge {worst['edges'][0]} / "
                    f"patch {worst['patches'][1]} edge {worst['edges'][1]}",
                )
            )
        return rows

    def summary(self) -> str:
        """A short human-readable table."""
        return format_reports([self])

    def verdict(self, max_angle_deg: float = 1e-9) -> str:
        """One phrase: ``"exact G1 (max angle 3.1e-12°), no folds"``, or what fails."""
        angle = max(self.max_edge_angle_deg, self.max_corner_angle_deg)
        g1 = (
            f"exact G1 (max angle {angle:.2g}°)"
            if self.is_g1(max_angle_deg)
            else f"not G1 (max angle {angle:.3g}°)"
        )
        folds = f"{self.folds} folded patches" if self.folds else "no folds"
        seams = (
            f", {self.seam_edges} seams"
            + ("" if self.seams_closed() else f" open by {self.seam_g0_max:.2g}")
            if self.seam_edges
            else ""
        )
        return f"{g1}, {folds}{seams}"

    def __repr__(self) -> str:
        edges = f"{self.shared_edges} shared edges"
        return f"<ContinuityReport {self.patches} patches, {edges}: {self.verdict()}>"

    def __str__(self) -> str:
        return self.summary()

    def _repr_html_(self) -> str:
        """The :meth:`rows` as an HTML table under the verdict, for Jupyter."""
        from html import escape

        verdict = "passes" if self.passes() else "fails"
        cells = "".join(
            f"<tr><td style='text-align:left'>{escape(label)}</td><td "
            f"style='text-align:left'>{escape(value)}</td></tr>"
            for label, value in self.rows()
        )
        return (
            f"<div><b>ContinuityReport</b>: {escape(self.verdict())} (the check {verdict} at 1e-9°)"
            f"<table>{cells}</table></div>"
        )


def format_reports(reports: list[ContinuityReport], titles: list[str] | None = None) -> str:
    """The reports' figures as a table, one column per report (rows missing from one are blank)."""
    columns = [dict(report.rows()) for report in reports]
    labels = list(dict.fromkeys(label for report in reports for label, _ in report.rows()))
    table = [[label, *(column.get(label, "") for column in columns)] for label in labels]
    if titles is not None:
        table = [["", *titles], ["", *("-" * len(title) for title in titles)], *table]
    widths = [max(len(row[i]) for row in table) for i in range(len(table[0]))]
    return "\n".join(
        "  ".join(cell.ljust(width) for cell, width in zip(row, widths, strict=True)).rstrip()
        for row in table
    )


#: networks of at least this many patches are measured by the kernels by default: below it the
#: NumPy reference takes seconds at most (Spot's 2,928 patches: 0.5–0.7 s), while the kernels'
#: one-time compile takes about a minute (57 s measured from an empty cache, against 0.8 s for
#: the reference's whole check of the cube), which a first ``make demo`` should not pay
KERNEL_PATCHES = 20_000


def _kernels_wanted(compiled: bool | None, count: int) -> bool:
    """Whether to use the kernels: ``compiled`` when given, else from :data:`KERNEL_PATCHES` patches
    on."""
    return count >= KERNEL_PATCHES if compiled is None else compiled


def check(
    network: PatchNetwork | PatchSet | GregoryPatchSet,
    samples: int = 33,
    fold_samples: int = FOLD_SAMPLES,
    degenerate_rtol: float = DEGENERATE_RTOL,
    chunk: int = 4096,
    progress: Callable[[int, int], None] | None = None,
    *,
    compiled: bool | None = None,
) -> ContinuityReport:
    """Measure G0 and G1 continuity, folds and fairness of ``network`` (see the module docstring).

    Work is done in blocks of ``chunk`` edges, and of at most ``chunk`` patches, so memory stays
    bounded on networks of millions of patches (the default keeps a block's sample arrays near
    the size of a core's L2 cache, the fastest setting measured); ``progress(done, total)`` is
    called after each block. Degenerate normals, folds and fairness share the
    ``fold_samples²`` grid of every patch. A :class:`~g1patch.patches.PatchSet` or
    :class:`~g1patch.gregory.GregoryPatchSet` is measured as the network of its matching boundary
    curves (:func:`g1patch.network.network_of`). ``compiled``: the numba kernels (see below), all edges
    and all patches in one pass each (``progress`` after each); False: the NumPy reference; None
    (default): the kernels from :data:`KERNEL_PATCHES` patches on.
    """
    for name, value, least in (
        ("samples", samples, 2),
        ("fold_samples", fold_samples, 2),
        ("chunk", chunk, 1),
    ):
        _check_count(name, value, least)
    network = network_of(network, "network")  # a PatchSet or GregoryPatchSet: its shared edges
    patches = network.patches
    local = _local(patches)
    form = _evaluation_form(local) if _kernels_wanted(compiled, len(local)) else None
    frame = getattr(patches, "frame", None)
    vertices = None
    if network.vertices is not None:
        vertices = network.vertices if frame is None else frame.to_local(network.vertices)
    if form is None:
        corners = _corner_points(local)
        diagonal = _diagonal(corners) or 1.0
    else:  # the same figures from one pass over the corners in place (4 M corners: 0.5 s -> 0.03 s)
        corner_points = (
            form[0]
            if isinstance(local, GregoryPatchSet)
            else np.ascontiguousarray(_corner_points(local))
        )
        low, high, farthest = _corner_extent_compiled(
            corner_points, vertices, np.ascontiguousarray(network.corner_ids, dtype=np.int64)
        )
        diagonal = (float(np.linalg.norm(high - low)) if len(local) else 0.0) or 1.0
    degenerate_level = degenerate_rtol * diagonal**2

    left_patch, left_edge = network.shared_edges()
    right_patch = network.neighbor[left_patch, left_edge]
    right_edge = network.neighbor_edge[left_patch, left_edge]
    same = network.same_direction[left_patch, left_edge]
    seam = network.seam[left_patch, left_edge]
    edge_angle = np.zeros(len(left_patch))
    edge_angle_min = np.zeros(len(left_patch))
    edge_gap = np.zeros(len(left_patch))
    edge_worst = np.zeros(len(left_patch), dtype=np.int64)
    patch_block = min(chunk, _patch_block(fold_samples))
    total = len(left_patch) + len(local)
    grid = _GridMeasures(len(local), fold_samples, degenerate_level)
    if form is not None:
        sides = (left_patch, left_edge, right_patch, right_edge, same)
        edge_angle, edge_angle_min, edge_worst, edge_gap = _edge_measures_compiled(
            *form, sides, samples, degenerate_level
        )
        if progress is not None:
            progress(len(left_patch), total)
        corner_angle = _max_corner_angle_compiled(
            network, _corner_normals_compiled(*form), degenerate_level, not same.any()
        )
        grid.add_compiled(*form, patch_block)
        if progress is not None:
            progress(total, total)
    else:
        for block in _blocks(len(left_patch), chunk):
            edge_angle[block], edge_angle_min[block], edge_worst[block], edge_gap[block] = (
                _edge_measures(
                    local,
                    left_patch[block],
                    left_edge[block],
                    right_patch[block],
                    right_edge[block],
                    same[block],
                    samples,
                    degenerate_level,
                )
            )
            if progress is not None:
                progress(block.stop, total)
        corner_angle = _max_corner_angle(network, local, degenerate_level, oriented=not same.any())
        for block in _blocks(len(local), patch_block):
            grid.add(local, block)
            if progress is not None:
                progress(len(left_patch) + block.stop, total)
    edge_gap /= diagonal
    figures = grid.fairness(diagonal)
    folded_edges = np.flatnonzero((edge_angle > 90.0) & ~seam)
    folded = grid.folded.copy()
    folded[left_patch[folded_edges]] = folded[right_patch[folded_edges]] = True
    edge_sides = (left_patch, left_edge, right_patch, right_edge, same)
    locations = _first_per_patch(
        grid.locations + _edge_fold_locations(edge_sides, folded_edges, edge_worst, samples)
    )

    max_vertex_deviation = None
    if vertices is not None and form is not None:
        max_vertex_deviation = float(np.sqrt(farthest) / diagonal) if len(local) else 0.0
    elif vertices is not None:
        deviation = np.linalg.norm(corners - vertices[network.corner_ids], axis=-1)
        max_vertex_deviation = float(deviation.max() / diagonal) if deviation.size else 0.0

    open_patch, _ = network.open_edges()
    smooth_angle = edge_angle[~seam]
    seam_range: tuple[float, float] | tuple[None, None] = (None, None)
    if seam.any():  # degenerate samples count as 0°, as in the maxima
        least = float(edge_angle_min[seam].min())
        seam_range = (least if np.isfinite(least) else 0.0, float(edge_angle[seam].max()))
    return ContinuityReport(
        patches=len(local),
        shared_edges=int(len(left_patch)),
        open_edges=int(len(open_patch)),
        collapsed_edges=int(network.edge_collapsed.sum()),
        collapsed_patch_edges=int(network.edge_collapsed[network.edge_ids].sum()),
        samples_per_edge=samples,
        max_edge_angle_deg=float(smooth_angle.max(initial=0.0)),
        mean_edge_angle_deg=float(smooth_angle.mean()) if len(smooth_angle) else 0.0,
        max_corner_angle_deg=corner_angle,
        max_g0_gap=float(edge_gap.max(initial=0.0)),
        degenerate_normals=grid.degenerate,
        folds=int(folded.sum()),
        inconsistent_orientation_edges=int(same.sum()),
        bounding_box_diagonal=float(
            diagonal
            if local is patches
            else _world_diagonal(network, corners)
            if form is None
            else _world_extent_diagonal(network, low, high)
        ),
        max_vertex_deviation=max_vertex_deviation,
        fold_samples=fold_samples,
        fold_locations=tuple(locations),
        turn_median_deg=figures["turn_median_deg"],
        turn_p99_deg=figures["turn_p99_deg"],
        turn_max_deg=figures["turn_max_deg"],
        thin_plate=figures["thin_plate"],
        seam_edges=int(seam.sum()),
        seam_g0_max=float(edge_gap[seam].max(initial=0.0)),
        seam_angle_min_deg=seam_range[0],
        seam_angle_max_deg=seam_range[1],
        edge_patches=np.stack([left_patch, right_patch], axis=1),
        edge_sides=np.stack([left_edge, right_edge], axis=1),
        edge_angle_deg=edge_angle,
        edge_gap=edge_gap,
        edge_seam=seam,
    )


def fairness(
    network: PatchNetwork,
    samples: int = FOLD_SAMPLES,
    degenerate_rtol: float = DEGENERATE_RTOL,
    *,
    compiled: bool | None = None,
) -> dict[str, float]:
    """The fairness figures of :func:`check` on a ``samples²`` grid per patch.

    Keys: ``turn_median_deg``, ``turn_p99_deg``, ``turn_max_deg`` (the normal turn between
    neighbouring grid samples along u and v, over all pairs of all patches) and ``thin_plate``
    (``Σ ∫∫ |p_uu|² + 2|p_uv|² + |p_vv|² du dv / diag²``).
    """
    grid, diagonal = _grid_measures(network.patches, samples, degenerate_rtol, compiled=compiled)
    return grid.fairness(diagonal)


def folded_patches(
    patches: Patches,
    samples: int = 9,
    degenerate_rtol: float = DEGENERATE_RTOL,
    *,
    compiled: bool | None = None,
) -> NDArray[np.bool_]:
    """Which patches fold (the intrinsic test of :func:`check`) on a ``samples²`` grid, (N,) bool.

    For a builder's fold guard: no network needed, patches in any coordinates. ``compiled``: the
    grid kernel (False: the NumPy reference; None: as :func:`check`).
    """
    return _grid_measures(patches, samples, degenerate_rtol, fairness=False, compiled=compiled)[
        0
    ].folded


def _grid_measures(
    patches: Patches,
    samples: int,
    degenerate_rtol: float,
    fairness: bool = True,
    *,
    compiled: bool | None = None,
) -> tuple[_GridMeasures, float]:
    """The grid measures of every patch (``fairness`` False: folds and degenerate normals only),
    in local coordinates, and the bounding-box diagonal."""
    _check_count("samples", samples, 2)
    local = _local(patches)
    diagonal = _diagonal(_corner_points(local)) or 1.0
    grid = _GridMeasures(len(local), samples, degenerate_rtol * diagonal**2, fairness)
    form = _evaluation_form(local) if _kernels_wanted(compiled, len(local)) else None
    if form is not None:
        grid.add_compiled(*form, _patch_block(samples))
    else:
        for block in _blocks(len(local), _patch_block(samples)):
            grid.add(local, block)
    return grid, diagonal


def _patch_block(resolution: int) -> int:
    """Patches per block of the grid measures: about :data:`g1patch._grid.BLOCK_POINTS` grid
    samples, so the block's arrays stay in the L2 cache and its GEMMs below the size at which
    OpenBLAS splits them over threads (measured: 33 µs per patch at 17² samples in blocks of 64
    patches, 83 µs in blocks of 467)."""
    return max(1, BLOCK_POINTS // resolution**2)


def _edge_fold_locations(
    sides: tuple[
        NDArray[np.int64],
        NDArray[np.int64],
        NDArray[np.int64],
        NDArray[np.int64],
        NDArray[np.bool_],
    ],
    folded_edges: NDArray[np.int64],
    worst: NDArray[np.int64],
    samples: int,
) -> list[tuple[int, float, float]]:
    """(patch, u, v) of the worst sample of the given folded edges on both sides, for the first
    :data:`MAX_FOLD_LOCATIONS` patches (side R is sampled at ``t[::-1]`` unless ``same``)."""
    left_patch, left_edge, right_patch, right_edge, same = (side[folded_edges] for side in sides)
    index = worst[folded_edges]
    t = np.linspace(0.0, 1.0, samples)
    patch = np.concatenate([left_patch, right_patch])
    edge = np.concatenate([left_edge, right_edge])
    parameter = np.concatenate([t[index], t[np.where(same, index, samples - 1 - index)]])
    _, first = np.unique(patch, return_index=True)
    first = first[:MAX_FOLD_LOCATIONS]
    uv = edge_parameters(edge[first], parameter[first])
    return [(int(p), float(u), float(v)) for p, (u, v) in zip(patch[first], uv, strict=True)]


def _first_per_patch(locations: list[tuple[int, float, float]]) -> list[tuple[int, float, float]]:
    """The lowest location of each patch, for the first :data:`MAX_FOLD_LOCATIONS` patches."""
    first: dict[int, tuple[int, float, float]] = {}
    for location in sorted(locations):
        first.setdefault(location[0], location)
    return list(first.values())[:MAX_FOLD_LOCATIONS]


def _check_count(name: str, value: object, least: int) -> None:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < least:
        raise InputError(f"{name}: expected an integer ≥ {least}, got {value!r}")


def _local(patches: Patches) -> Patches:
    """The patches in their local coordinates (frame-free), or the patches when they have no
    frame."""
    return patches.local() if hasattr(patches, "local") else patches  # type: ignore[no-any-return]


def _diagonal(points: NDArray[np.float64]) -> float:
    """Length of the diagonal of the bounding box of ``points`` (..., 3) (each coordinate's extremes
    over its strided column: NumPy reduces ``axis=0`` of ``(M, 3)`` 3 values at a time, 20×
    slower)."""
    flat = points.reshape(-1, 3)
    if not len(flat):
        return 0.0
    extent = np.array([flat[:, d].max() - flat[:, d].min() for d in range(3)])
    return float(np.linalg.norm(extent))


def _corner_points(patches: Patches) -> NDArray[np.float64]:
    """``patches.evaluate(CORNER_PARAMETERS)``, ``(N, 4, 3)``: a Gregory patch's corners are its
    points 0–3 (weights 1 and 0, so the evaluation returns them exactly)."""
    if isinstance(patches, GregoryPatchSet) and patches.frame is None:
        return np.ascontiguousarray(patches.points[:, :4])
    return patches.evaluate(CORNER_PARAMETERS)


def _world_diagonal(network: PatchNetwork, corners: NDArray[np.float64]) -> float:
    """:meth:`PatchNetwork.bounding_box_diagonal` from the local ``corners`` of its patches (the
    same ``c + s x`` that the patches' world evaluation applies)."""
    patches = network.patches
    if isinstance(patches, GregoryPatchSet) and patches.frame is not None:
        return _diagonal(patches.frame.to_world(corners))
    return network.bounding_box_diagonal()


def _world_extent_diagonal(
    network: PatchNetwork, low: NDArray[np.float64], high: NDArray[np.float64]
) -> float:
    """:func:`_world_diagonal` from the local corners' box ``low``, ``high``: ``c + s x`` is
    monotone in each coordinate (both roundings are), so the world corners' extremes are the images
    of the local ones, exactly."""
    patches = network.patches
    if isinstance(patches, GregoryPatchSet) and patches.frame is not None:
        ends = patches.frame.to_world(np.stack([low, high]))
        return float(np.linalg.norm(ends.max(axis=0) - ends.min(axis=0)))
    return network.bounding_box_diagonal()


def _blocks(count: int, size: int) -> list[slice]:
    return [slice(start, min(start + size, count)) for start in range(0, count, size)]


# Vector algebra on planar arrays ``(3, ...)`` (component first, each component contiguous): the
# edge and fold measures touch tens of millions of 3-vectors, and component-wise products on
# interleaved ``(..., 3)`` arrays run on stride-3 views. Each helper performs exactly the
# floating-point operations, in the same order, of the interleaved NumPy formulation it replaces
# (``np.cross``, ``np.linalg.norm(axis=-1)``, ``np.einsum("...d,...d->...")``), so the reported
# figures do not depend on the layout.


def _planar(values: NDArray[np.float64]) -> NDArray[np.float64]:
    """``(..., 3)`` vectors as a ``(3, ...)`` view (no copy: the helpers below read strided
    components several times faster than NumPy transposes them into contiguous ones, and they
    write contiguous planar results)."""
    return np.moveaxis(values, -1, 0)


def _cross3(a: NDArray[np.float64], b: NDArray[np.float64]) -> NDArray[np.float64]:
    """``a × b`` of planar ``(3, ...)`` arrays, planar."""
    out = np.empty(np.broadcast_shapes(a.shape, b.shape))
    scratch = np.empty(out.shape[1:])
    for i, j, k in ((0, 1, 2), (1, 2, 0), (2, 0, 1)):
        np.multiply(a[j], b[k], out=out[i])
        np.multiply(a[k], b[j], out=scratch)
        out[i] -= scratch
    return out


def _dot3(a: NDArray[np.float64], b: NDArray[np.float64]) -> NDArray[np.float64]:
    """``a · b`` of planar arrays, summed as ``(a₀b₀ + a₂b₂) + a₁b₁`` like ``np.einsum``."""
    out = a[0] * b[0]
    scratch = a[2] * b[2]
    out += scratch
    np.multiply(a[1], b[1], out=scratch)
    out += scratch
    return out


def _norm3(a: NDArray[np.float64]) -> NDArray[np.float64]:
    """``|a|`` of a planar array, summed as ``(a₀² + a₁²) + a₂²`` like ``np.linalg.norm``."""
    out = a[0] * a[0]
    scratch = a[1] * a[1]
    out += scratch
    np.multiply(a[2], a[2], out=scratch)
    out += scratch
    return np.sqrt(out, out=out)


def _angle3(a: NDArray[np.float64], b: NDArray[np.float64]) -> NDArray[np.float64]:
    """:func:`angle_between` of planar arrays."""
    angle = np.arctan2(_norm3(_cross3(a, b)), _dot3(a, b))
    return np.degrees(angle, out=angle)


def _edge_samples(
    patches: Patches,
    patch_ids: NDArray[np.int64],
    edges: NDArray[np.int64],
    backwards: NDArray[np.bool_],
    t: NDArray[np.float64],
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Points and normals ``p_u × p_v`` at ``t`` along the given patch edges, each planar ``(3, E,
    K)``.

    Edge k is run counter-clockwise, or from its far end where ``backwards``. The eight
    (edge, direction) groups share their parameters, so each group is one batched product.
    """
    points = np.empty((3, len(patch_ids), len(t)))
    normals = np.empty_like(points)
    for edge in range(4):
        for reverse in (False, True):
            rows = np.flatnonzero((edges == edge) & (backwards == reverse))
            if len(rows):
                uv = edge_parameters(np.int64(edge), t[::-1] if reverse else t)
                group = patches.take(patch_ids[rows])
                points[:, rows] = np.moveaxis(group.evaluate(uv), -1, 0)
                normals[:, rows] = _cross3(
                    _planar(group.evaluate(uv, 1, 0)), _planar(group.evaluate(uv, 0, 1))
                )
    return points, normals


def _edge_measures(
    patches: Patches,
    left_patch: NDArray[np.int64],
    left_edge: NDArray[np.int64],
    right_patch: NDArray[np.int64],
    right_edge: NDArray[np.int64],
    same: NDArray[np.bool_],
    samples: int,
    degenerate_level: float,
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.int64], NDArray[np.float64]]:
    """Max and min G1 angle (deg; the min over non-degenerate samples, inf without any), the
    sample index where the max is reached, and max G0 gap (absolute) along each given shared edge.

    Side R runs along the edge in its own counter-clockwise direction, so it is sampled at the
    reversed parameters (exactly ``t[::-1]``) unless both sides run the same way; then its
    normal is flipped, as its patch is oriented the other way.
    """
    t = np.linspace(0.0, 1.0, samples)
    point_left, normal_left = _edge_samples(
        patches, left_patch, left_edge, np.zeros(len(same), dtype=bool), t
    )
    point_right, normal_right = _edge_samples(patches, right_patch, right_edge, ~same, t)
    if same.any():
        normal_right[:, same] *= -1.0
    usable = (_norm3(normal_left) > degenerate_level) & (_norm3(normal_right) > degenerate_level)
    angles = np.where(usable, _angle3(normal_left, normal_right), 0.0)
    point_left -= point_right
    gaps = _norm3(point_left)
    worst = angles.argmax(axis=1)
    least = np.where(usable, angles, np.inf).min(axis=1, initial=np.inf)
    return (
        np.take_along_axis(angles, worst[:, None], axis=1)[:, 0],
        least,
        worst,
        gaps.max(axis=1, initial=0.0),
    )


def _max_corner_angle(
    network: PatchNetwork, patches: Patches, degenerate_level: float, oriented: bool
) -> float:
    """Largest angle between the corner normals of any two patches meeting at one point in one
    sector (:meth:`PatchNetwork.corner_sectors`: patches across a seam may differ).

    Corners are grouped by their sector and the groups by size; the pairwise angles of the
    sectors with m corners are computed in (groups, rows, m) blocks of at most
    :data:`_CORNER_PAIR_BLOCK` pairs (a block of rows of one sector when m² is larger), so memory
    stays linear in the valence: a 10 000-valent vertex's 10⁸ pairs asked for 6 GB in one array.
    Every pair's angle is the same operations on the same two normals as in one array.
    """
    normals = _cross3(
        _planar(patches.evaluate(CORNER_PARAMETERS, 1, 0)),
        _planar(patches.evaluate(CORNER_PARAMETERS, 0, 1)),
    )
    normals = normals.reshape(3, -1)
    usable = _norm3(normals) > degenerate_level
    ids = network.corner_sectors().reshape(-1)[usable]
    normals = normals[:, usable].T
    if not len(ids):
        return 0.0
    order = np.argsort(ids, kind="stable")
    ids, normals = ids[order], normals[order]
    starts = np.flatnonzero(np.r_[True, ids[1:] != ids[:-1]])
    sizes = np.diff(np.r_[starts, len(ids)])
    worst = 0.0
    for size in np.unique(sizes[sizes > 1]):
        group_starts = starts[sizes == size]
        groups_per_block = max(1, _CORNER_PAIR_BLOCK // (size * size))
        rows_per_block = size if groups_per_block > 1 else max(1, _CORNER_PAIR_BLOCK // size)
        for first in range(0, len(group_starts), groups_per_block):
            group = normals[
                group_starts[first : first + groups_per_block, None] + np.arange(size)
            ]  # (g, m, 3)
            for row in range(0, size, rows_per_block):
                rows = np.ascontiguousarray(group[:, row : row + rows_per_block])  # (g, rows, 3)
                cross = np.linalg.norm(np.cross(rows[:, :, None], group[:, None, :]), axis=-1)
                dot = np.einsum("gid,gjd->gij", rows, group)
                if not oriented:
                    dot = np.abs(dot)
                worst = max(worst, float(np.degrees(np.arctan2(cross, dot)).max()))
    return worst


#: corner pairs per block of :func:`_max_corner_angle` (a block's arrays: about 100 bytes a pair)
_CORNER_PAIR_BLOCK = 1 << 18


def _turn_deg(chord2: float) -> float:
    """The angle θ of unit vectors a chord ``√chord2 = |a − b| = 2 sin(θ/2)`` apart, in degrees."""
    return float(np.degrees(2.0 * np.arcsin(min(1.0, np.sqrt(chord2) / 2.0))))


class _GridMeasures:
    """Degenerate normals, folds and fairness on a ``resolution²`` grid per patch, accumulated block
    by block.

    Folds are flagged per patch, located at the first offending sample (row-major, u first). The
    turns go into a histogram (see ``_EDGES``), their maximum is exact (``atan2`` of the worst
    pair), and the thin-plate energy is summed once over per-patch energies, so the figures do not
    depend on the blocks.
    """

    def __init__(
        self, count: int, resolution: int, degenerate_level: float, fairness: bool = True
    ) -> None:
        self.grid = np.linspace(0.0, 1.0, resolution)
        self.fairness_wanted = fairness
        self.degenerate_level = degenerate_level
        self.degenerate = 0
        self.folded = np.zeros(count, dtype=bool)
        self.locations: list[tuple[int, float, float]] = []
        self.histogram = np.zeros(_BINS, dtype=np.int64)
        self.max_turn_deg = 0.0
        self.energy = np.zeros(count)
        # trapezoid weights across the differences: ∫∫|∂_u f|² ≈ Σ_ij w_j |f_(i+1)j − f_ij|²
        # (midpoint rule
        # along u, the h = 1/(G − 1) of the difference quotient and of both rules cancel)
        self.weights = np.ones(resolution)
        self.weights[[0, -1]] = 0.5
        self.gregory_weights: list[NDArray[np.float64]] | None = None

    def add(self, patches: Patches, block: slice) -> None:
        """Measure the patches ``block`` of ``patches``."""
        p_u, p_v = self._tangents(
            patches.take(np.arange(block.start, block.stop))
        )  # (3, B, G, G) each
        normal = _cross3(p_u, p_v)
        length = _norm3(normal)  # (B, G, G)
        usable = length > self.degenerate_level
        self.degenerate += int(usable.size - np.count_nonzero(usable))
        unit = normal * (1.0 / np.maximum(length, np.finfo(float).tiny))

        offending = np.zeros(length.shape, dtype=bool)
        last = len(self.grid) - 1
        for corner_u, corner_v in ((0, 0), (last, 0), (last, last), (0, last)):
            # the corner's grid cell: a patch turned over at its corner
            step_u, step_v = (1 if corner_u == 0 else -1), (1 if corner_v == 0 else -1)
            corner = normal[:, :, corner_u, corner_v]
            for i, j in (
                (corner_u + step_u, corner_v),
                (corner_u, corner_v + step_v),
                (corner_u + step_u, corner_v + step_v),
            ):
                against = _dot3(normal[:, :, i, j], corner) < 0
                offending[:, i, j] |= against & usable[:, i, j] & usable[:, corner_u, corner_v]
        worst_chord2, worst_pair = -1.0, None
        for axis in (1, 2):  # neighbours along u, along v
            ahead = tuple(slice(1, None) if a == axis else slice(None) for a in range(3))
            behind = tuple(slice(None, -1) if a == axis else slice(None) for a in range(3))
            chord = unit[(slice(None), *ahead)] - unit[(slice(None), *behind)]
            chord2 = _dot3(chord, chord)  # |n̂_a − n̂_b|² = 4 sin²(θ/2): > 2 where θ > 90°
            paired = usable[ahead] & usable[behind]
            offending[behind] |= (chord2 > 2.0) & paired
            if not self.fairness_wanted:
                continue
            bins = _chord_codes(chord2) - (_CODE_MIN - 1)
            np.clip(bins, 0, _BINS - 1, out=bins)
            if paired.all():
                self.histogram += np.bincount(bins.reshape(-1), minlength=_BINS)
            else:
                self.histogram += np.bincount(bins[paired], minlength=_BINS)
                chord2[~paired] = -1.0
            index = int(np.argmax(chord2))
            if chord2.reshape(-1)[index] > worst_chord2:
                worst_chord2 = float(chord2.reshape(-1)[index])
                position = np.unravel_index(index, chord2.shape)
                following = tuple(p + (a == axis) for a, p in enumerate(position))
                worst_pair = (
                    normal[(slice(None), *position)][:, None],
                    normal[(slice(None), *following)][:, None],
                )
        if worst_pair is not None:
            self.max_turn_deg = max(self.max_turn_deg, float(_angle3(*worst_pair)[0]))

        folded = offending.any(axis=(1, 2))
        self.folded[block] = folded
        for patch in np.flatnonzero(folded)[: MAX_FOLD_LOCATIONS - len(self.locations)]:
            i, j = np.unravel_index(int(np.argmax(offending[patch])), offending.shape[1:])
            self.locations.append(
                (block.start + int(patch), float(self.grid[i]), float(self.grid[j]))
            )

        if not self.fairness_wanted:
            return
        energy = self.energy[block]
        for derivative in (p_u, p_v):
            along_u = derivative[:, :, 1:] - derivative[:, :, :-1]
            along_v = derivative[:, :, :, 1:] - derivative[:, :, :, :-1]
            energy += _dot3(along_u, along_u).sum(axis=1) @ self.weights
            energy += _dot3(along_v, along_v).sum(axis=2) @ self.weights

    def add_compiled(self, points: NDArray[np.float64], form: str, block: int) -> None:
        """Measure all patches ``points`` (:func:`_evaluation_form`) in :func:`_grid_kernel`.

        The kernel keeps each patch's largest squared chord along u and along v with the angle of
        its pair; the reference's maximum turn (per ``block`` of patches: the first largest chord
        along u, replaced by the first along v if larger) is picked from those, so it is the angle
        of the same pair of normals as :meth:`add` over blocks of ``block`` patches finds.
        """
        count, resolution = len(points), len(self.grid)
        if not count:
            return
        chunks = _chunks(count)
        location = np.empty(count, dtype=np.int64)
        degenerate = np.zeros(chunks, dtype=np.int64)
        histogram = np.zeros((chunks if self.fairness_wanted else 1, _BINS), dtype=np.int64)
        best = np.empty((count if self.fairness_wanted else 0, 4))
        _compiled(_grid_kernel)(
            points,
            *_grid_tables(form, self.grid),
            self.weights,
            self.degenerate_level,
            self.fairness_wanted,
            _CODE_MIN,
            _LANES,
            chunks,
            location,
            degenerate,
            histogram,
            best,
            self.energy,
        )
        self.degenerate += int(degenerate.sum())
        self.folded = location >= 0
        for patch in np.flatnonzero(self.folded)[: MAX_FOLD_LOCATIONS - len(self.locations)]:
            i, j = divmod(int(location[patch]), resolution)
            self.locations.append((int(patch), float(self.grid[i]), float(self.grid[j])))
        if not self.fairness_wanted:
            return
        self.histogram += histogram.sum(axis=0)
        if form == "gregory":
            self._exact_turns(points, best)
        blocks = -(-count // block)
        padded = np.full((blocks * block, 4), -1.0)
        padded[:count] = best
        padded = padded.reshape(blocks, block, 4)
        rows = np.arange(blocks)
        along_u = padded[rows, np.argmax(padded[:, :, 0], axis=1), :2]
        along_v = padded[rows, np.argmax(padded[:, :, 2], axis=1), 2:]
        use_v = along_v[:, 0] > along_u[:, 0]
        chord2 = np.where(use_v, along_v[:, 0], along_u[:, 0])
        angle = np.where(use_v, along_v[:, 1], along_u[:, 1])[chord2 > -1.0]
        self.max_turn_deg = max(self.max_turn_deg, float(angle.max(initial=0.0)))

    def _exact_turns(self, points: NDArray[np.float64], best: NDArray[np.float64]) -> None:
        """Replace the largest chords of Gregory patches (tensor sums in the kernel) by the
        reference's (:func:`_turn_kernel`) where a patch's could decide the maximum turn: its chord
        ``√chord²`` within :data:`_TURN_CANDIDATE_ATOL` of the largest of all patches (the two
        evaluations' chords differ by rounding, ~1e-15). The other patches' are set to −1: their
        blocks' pairs turn less than the largest either way, and a patch that wins its block
        among the candidates is its block's winner whenever that block can hold the maximum. (A
        threshold per block, as before, recomputed nearly every patch of a regular mesh, whose
        patches tie within rounding: 29 s of a 1 M-patch check.) Where more than
        :data:`EXACT_TURN_CANDIDATES` patches are candidates along an axis, their tensor chords and
        angles stand for that axis."""
        largest = np.sqrt(max(float(best[:, [0, 2]].max(initial=0.0)), 0.0))
        for axis in (0, 1):
            chord = np.sqrt(np.maximum(best[:, 2 * axis], 0.0))
            candidate = (best[:, 2 * axis] > -1.0) & (chord >= largest - _TURN_CANDIDATE_ATOL)
            if np.count_nonzero(candidate) > EXACT_TURN_CANDIDATES:
                continue
            patches = np.flatnonzero(candidate)
            chord2, angle = np.empty(len(patches)), np.empty(len(patches))
            if len(patches):
                exact = np.ascontiguousarray(
                    np.swapaxes(_gregory_grid_weights(self.grid), 1, 2)
                )  # (2, 20, G²)
                _compiled(_turn_kernel)(
                    points,
                    exact,
                    self.degenerate_level,
                    patches,
                    np.full(len(patches), axis),
                    _chunks(len(patches)),
                    chord2,
                    angle,
                )
            best[:, 2 * axis] = -1.0
            best[patches, 2 * axis], best[patches, 2 * axis + 1] = chord2, angle

    def _tangents(self, group: Patches) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """``p_u`` and ``p_v`` of ``group`` on the grid, planar ``(3, B, G, G)``.

        Gregory patches without a frame: ``p[d, n] = P[d, n] @ W``, the points ``(20,)`` of every
        coordinate and patch times the weights ``W`` ``(20, G²)``, a planar result (their
        ``evaluate_grid`` multiplies interleaved values by a Kronecker factor of two thirds zeros).
        """
        if not (isinstance(group, GregoryPatchSet) and getattr(group, "frame", None) is None):
            return _planar(group.evaluate_grid(self.grid, self.grid, 1, 0)), _planar(
                group.evaluate_grid(self.grid, self.grid, 0, 1)
            )
        if self.gregory_weights is None:
            u, v = self.grid[:, None], self.grid[None, :]
            self.gregory_weights = [
                gregory_weights(u, v, du, dv).reshape(-1, 20).T.copy()
                for du, dv in ((1, 0), (0, 1))
            ]
        points = np.ascontiguousarray(np.moveaxis(group.points, -1, 0))  # (3, B, 20)
        shape = (3, len(group), len(self.grid), len(self.grid))
        p_u, p_v = (np.matmul(points, weights).reshape(shape) for weights in self.gregory_weights)
        return p_u, p_v

    def fairness(self, diagonal: float) -> dict[str, float]:
        """Median, p99 and max turn (degrees) and the thin-plate energy divided by ``diagonal²``."""
        return {
            "turn_median_deg": self._percentile(0.5),
            "turn_p99_deg": self._percentile(0.99),
            "turn_max_deg": self.max_turn_deg,
            "thin_plate": float(self.energy.sum() / diagonal**2),
        }

    def _percentile(self, q: float) -> float:
        """The turn of rank ``q (M − 1)`` of the M pairs, interpolated linearly in s inside its bin
        (capped by the exact maximum); 0 without pairs."""
        total = int(self.histogram.sum())
        if not total:
            return 0.0
        rank = q * (total - 1)
        cumulative = np.cumsum(self.histogram)
        b = int(np.searchsorted(cumulative, rank, side="right"))
        fraction = (rank - (cumulative[b] - self.histogram[b]) + 0.5) / self.histogram[b]
        chord2 = _EDGES[b] + fraction * (_EDGES[b + 1] - _EDGES[b])
        return min(_turn_deg(chord2), self.max_turn_deg)


# ---------------------------------------------------------------------------------------------
# Compiled kernels (``compiled=True``, the default of :func:`check`, :func:`fairness` and
# :func:`folded_patches` from KERNEL_PATCHES patches on); the NumPy code above is their reference
# (``compiled=False``), and
# tests/test_check_kernels.py holds the two to one report.
#
# Patches enter the kernels as ``points (N, M, 3)`` and weight tables: Gregory patches their 20
# points, a PatchSet its 16 control points ``4 i + j`` (any basis form). Edge samples and corner
# normals are formed as the reference's matrix products form them: a sequential fused
# multiply-add over the points, ``acc = fma(P_m, W_m, acc)`` for m = 0, 1, …, the order of
# OpenBLAS's dgemm micro-kernel, skipping the weights that are exactly 0 (they add exactly
# nothing); they equal the reference's bit for bit except on the rows OpenBLAS gives its tail
# kernels. The grid measures use the tensor structure instead: a Gregory patch is the bicubic
# Bézier patch of its net with Fp_k inside plus ``Σ_k S_k (Fn_k − Fp_k)`` (``S_k``: the weight of
# Fn_k in :func:`~g1patch.gregory.gregory_weights`, as ``w_α + w_β = 1``), so a grid row of
# tangents costs one u contraction of the net, then 8 products and 4 blends per point and
# derivative, against 20 weights.

_TINY = float(np.finfo(np.float64).tiny)

_CANDIDATE_RTOL = 1e-12
"""An edge's extreme angles are computed (``atan2``) only at the samples whose pseudo-angle
``y / (y + x)`` (``2 − y / (y + |x|)`` where x < 0; y = |n_L × n_R|, x = n_L · n_R; strictly
increasing in the angle) is within this relative distance of the extreme one. Its rounding
(≤ 2 ULP) and atan2's (≤ 1 ULP), scaled by the pseudo-angle's slope (between ½ and 1 per radian),
stay below 10 ULP: this margin is 400× that."""

_TURN_CANDIDATE_ATOL = 1e-10
"""Patches whose largest chord between neighbouring unit normals (tensor evaluation) is within
this distance of their block's largest have it recomputed as the reference computes it (see
:meth:`_GridMeasures._exact_turns`): 10⁵ times the rounding of a unit normal (~1e-15)."""

EXACT_TURN_CANDIDATES = 100_000
"""At most this many candidates per axis are recomputed as the reference computes them (~4 µs
each). Above it the patches tie within rounding by the hundred thousand, as every patch of a
large regular torus does along its tube (4 M patches: 16 s recomputing, twice the rest of the
check), and the turn maximum is the tensor evaluation's: the angle of a pair of normals that tie
with the reference's within their rounding, so within :data:`TENSOR_TURN_ATOL` of its value."""

TENSOR_TURN_ATOL = 2048 * float(np.finfo(np.float64).eps) * 180.0 / np.pi
"""Degrees: how far a turn maximum taken from the tensor evaluation may be from the reference's,
two normals each a few hundred ULP off the reference's (the tensor sums round differently:
measured ≤ 454 ε on the shared meshes' edge angles), so their angle by 2 × 1024 ε radians."""

_PAIRWISE_SECTOR = 64
"""Sectors of at most this many corners compare all pairs of corner normals; larger ones only the
pairs of the vertices of their gnomonic convex hull (see :func:`_corner_kernel`)."""

prange = range  # numba.prange once a kernel is compiled

#: patches the grid kernel measures side by side, its vector lanes (a run-time argument: a
#: constant trip count is unrolled before the loop vectoriser sees it, and left scalar); 64 rather
#: than 16: each inner loop runs 8 AVX-512 steps instead of 2 for the same loop overhead (the
#: scratch, ~0.7 MB, stays in a core's L2)
_LANES = 64

# : shared edges the edge kernel measures side by side (its vector lanes; a run-time argument, as
# _LANES)
_EDGE_LANES = 32

#: functions the kernels call, compiled (and rebound) with the first kernel
_KERNEL_HELPERS = ("_pair_angle", "_hull_corners")


def _fma(a: float, b: float, c: float) -> float:
    """``a b + c`` rounded once; bound to an LLVM intrinsic by :func:`_compiled` (numba has no
    math.fma)."""
    raise NotImplementedError("_fma runs compiled only")


@cache
def _compiled(kernel: Callable[..., Any]) -> Callable[..., Any]:
    """``kernel`` compiled by numba, cached on disk, with float64 IEEE arithmetic as NumPy's (no
    fastmath) and ``parallel=True`` (its ``prange`` loop runs on every core), which
    :func:`g1patch.kernels.jit_kernel` does not offer. numba is imported here, so that
    ``import g1patch`` stays fast."""
    global _fma, prange
    import numba
    from numba.extending import intrinsic

    if prange is range:

        @intrinsic  # type: ignore[misc]
        def fused(typingctx: Any, a: Any, b: Any, c: Any) -> Any:
            signature = numba.types.float64(
                numba.types.float64, numba.types.float64, numba.types.float64
            )
            return signature, lambda context, builder, sig, args: builder.fma(*args)

        _fma, prange = fused, numba.prange
        for name in _KERNEL_HELPERS:
            globals()[name] = numba.njit(cache=True, error_model="numpy")(globals()[name])
    return numba.njit(cache=True, error_model="numpy", parallel=True)(kernel)  # type: ignore[no-any-return]


@cache
def _serial(kernel: Callable[..., Any]) -> Callable[..., Any]:
    """A kernel without a parallel loop, compiled once per process
    (:func:`g1patch.kernels.jit_kernel`)."""
    from .kernels import jit_kernel

    return jit_kernel(kernel)  # type: ignore[return-value]


def _chunks(count: int) -> int:
    """Chunks of a kernel's parallel loop: a few per core (the cores share the machine)."""
    import numba

    return max(1, min(count, 4 * numba.get_num_threads()))


def _evaluation_form(patches: Patches) -> tuple[NDArray[np.float64], str] | None:
    """``(points (N, M, 3), form)``: Gregory patches' points (M = 20, form "gregory") or a
    PatchSet's control points (M = 16, its basis form); None for other patch types."""
    if isinstance(patches, GregoryPatchSet):
        return patches.points, "gregory"
    if isinstance(patches, PatchSet):
        return patches.control.reshape(len(patches), 16, 3), str(patches.form)
    return None


def _weights(form: str, uv: NDArray[np.float64], du: int, dv: int) -> NDArray[np.float64]:
    """Weights ``(..., M)`` of the points in ``∂^(du+dv) p`` at ``uv (..., 2)``, formed as the
    reference forms them (:func:`gregory_weights`, or the tensor of ``PatchSet.evaluate``)."""
    if form == "gregory":
        return gregory_weights(uv[..., 0], uv[..., 1], du, dv)
    weights_u = basis_values(form, uv[..., 0], du)  # type: ignore[arg-type]
    weights_v = basis_values(form, uv[..., 1], dv)  # type: ignore[arg-type]
    return (weights_u[..., :, None] * weights_v[..., None, :]).reshape(*uv.shape[:-1], 16)


def _sparse(
    weights: NDArray[np.float64],
) -> tuple[NDArray[np.float64], NDArray[np.int64], NDArray[np.int64]]:
    """``weights (..., K, M)`` as ``(W (..., M, K), index (..., M), count (...))``: the points with
    a nonzero weight at some sample are ``index[..., :count]``, ascending."""
    nonzero = (weights != 0.0).any(axis=-2)
    index = np.argsort(~nonzero, axis=-1, kind="stable").astype(np.int64)
    return (
        np.ascontiguousarray(np.swapaxes(weights, -1, -2)),
        index,
        nonzero.sum(axis=-1).astype(np.int64),
    )


def _edge_measures_compiled(
    points: NDArray[np.float64],
    form: str,
    sides: tuple[NDArray[Any], ...],
    samples: int,
    degenerate_level: float,
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.int64], NDArray[np.float64]]:
    """:func:`_edge_measures` of all the given edges, both sides of each in one kernel pass."""
    left_patch, left_edge, right_patch, right_edge, same = sides
    t = np.linspace(0.0, 1.0, samples)
    uv = np.stack(
        [
            np.stack(
                [
                    edge_parameters(np.int64(edge), t[::-1] if reverse else t)
                    for reverse in (False, True)
                ]
            )
            for edge in range(4)
        ]
    )  # (edge, reversed, K, 2)
    table = np.stack([_weights(form, uv, du, dv) for du, dv in ((0, 0), (1, 0), (0, 1))], axis=2)
    weights, index, count = _sparse(table)  # (edge, reversed, derivative, M, K)
    blocks = (count + 3) // 4
    padded = np.full(
        (*index.shape[:-1], 4 * max(int(blocks.max()), 1)), index.shape[-1], dtype=np.int64
    )
    for key in np.ndindex(count.shape):
        padded[key][: count[key]] = index[key][: count[key]]
    weights = np.concatenate(
        [weights, np.zeros((*weights.shape[:-2], 1, samples))], axis=-2
    )  # point M: weight +0
    edges = len(left_patch)
    angle, least, gap = np.empty(edges), np.empty(edges), np.empty(edges)
    worst = np.empty(edges, dtype=np.int64)
    if edges:
        # the sides' edges and directions (the weights an edge takes), 32 classes: a stable sort of
        # 8-bit keys is NumPy's radix sort (2 M edges: 0.1 s -> 0.02 s for the sort and the classes)
        key = ((left_edge * 4 + right_edge) * 2 + same).astype(np.int8)
        order = np.argsort(key, kind="stable")
        bounds = np.r_[0, np.cumsum(np.bincount(key, minlength=32))]
        groups = np.unique(
            np.concatenate(
                [np.arange(a, b, _EDGE_LANES) for a, b in itertools.pairwise(bounds)] + [[edges]]
            )
        )
        _compiled(_edge_kernel)(
            points,
            left_patch,
            left_edge,
            right_patch,
            right_edge,
            same,
            order,
            groups,
            weights,
            padded,
            blocks,
            degenerate_level,
            _CANDIDATE_RTOL,
            _EDGE_LANES,
            _chunks(len(groups) - 1),
            angle,
            least,
            worst,
            gap,
        )
    return angle, least, worst, gap


def _edge_kernel(
    points: NDArray[np.float64],
    left_patch: NDArray[np.int64],
    left_edge: NDArray[np.int64],
    right_patch: NDArray[np.int64],
    right_edge: NDArray[np.int64],
    same: NDArray[np.bool_],
    order: NDArray[np.int64],
    groups: NDArray[np.int64],
    weights: NDArray[np.float64],
    index: NDArray[np.int64],
    blocks: NDArray[np.int64],
    level: float,
    rtol: float,
    lanes: int,
    chunks: int,
    angle: NDArray[np.float64],
    least: NDArray[np.float64],
    worst: NDArray[np.int64],
    gap: NDArray[np.float64],
) -> None:
    """Per edge: both sides' points and normals at the K samples, then the reference's max and min
    angle, worst sample and max gap; ``atan2`` only at the candidates (:data:`_CANDIDATE_RTOL`).

    ``lanes`` edges at a time, ``order[groups[i]:groups[i + 1]]`` for group i, whose edges share
    their sides' edge numbers and directions, so their weights: the lanes are the last axis of
    every scratch array, and the arithmetic vectorises across edges (the three coordinates of
    every lane in one loop, as the weights do not depend on them), sample by sample. A sum
    ``Σ_m P_m W_m`` runs over ``index[edge, backwards, q]`` four terms at a time (``blocks``
    of them), padded with the point ``M`` (−1 in every lane) of weight +0: ``fma(−1, +0, acc)``
    is ``acc`` exactly (``acc + (−0)``), so every value is the sequential sum of the edge-by-edge
    formulation, bit for bit."""
    samples, padded, group_count = weights.shape[-1], points.shape[1] + 1, groups.size - 1
    for chunk in prange(chunks):
        net = np.zeros((2, padded, 3 * lanes))  # side, point, (coordinate, lane)
        net[:, padded - 1] = -1.0
        values = np.empty((2, 3, 3, lanes))  # side, derivative (p, p_u, p_v), coordinate, lane
        sums = values.reshape((2, 3, 3 * lanes))
        normal, cross = np.empty((2, 3, lanes)), np.empty((3, lanes))
        distance, y, x = np.empty(lanes), np.empty((samples, lanes)), np.empty((samples, lanes))
        pseudo, usable = np.empty((samples, lanes)), np.empty((samples, lanes), dtype=np.bool_)
        candidate = np.empty((samples, lanes), dtype=np.bool_)
        top, bottom, gap2 = np.empty(lanes), np.empty(lanes), np.empty(lanes)
        for group in range(chunk * group_count // chunks, (chunk + 1) * group_count // chunks):
            first, stop = groups[group], groups[group + 1]
            lead = order[first]
            flip = -1.0 if same[lead] else 1.0
            for lane in range(stop - first):
                e = order[first + lane]
                for side in range(2):
                    patch = left_patch[e] if side == 0 else right_patch[e]
                    for m in range(padded - 1):
                        for d in range(3):
                            net[side, m, d * lanes + lane] = points[patch, m, d]
            top[:] = -1.0
            bottom[:] = np.inf
            gap2[:] = 0.0
            for k in range(samples):
                for side in range(2):
                    edge = left_edge[lead] if side == 0 else right_edge[lead]
                    back = 1 if side == 1 and not same[lead] else 0
                    p = net[side]
                    for q in range(
                        3
                    ):  # the three coordinates of every lane in one loop (the weights are the same)
                        out = sums[side, q]
                        if blocks[edge, back, q] == 0:
                            out[:] = 0.0
                        for block in range(blocks[edge, back, q]):
                            m0, m1 = (
                                index[edge, back, q, 4 * block],
                                index[edge, back, q, 4 * block + 1],
                            )
                            m2, m3 = (
                                index[edge, back, q, 4 * block + 2],
                                index[edge, back, q, 4 * block + 3],
                            )
                            w0, w1 = weights[edge, back, q, m0, k], weights[edge, back, q, m1, k]
                            w2, w3 = weights[edge, back, q, m2, k], weights[edge, back, q, m3, k]
                            p0, p1, p2, p3 = p[m0], p[m1], p[m2], p[m3]
                            if block == 0:
                                for t in range(3 * lanes):
                                    out[t] = _fma(
                                        p3[t],
                                        w3,
                                        _fma(p2[t], w2, _fma(p1[t], w1, _fma(p0[t], w0, 0.0))),
                                    )
                            else:
                                for t in range(3 * lanes):
                                    out[t] = _fma(
                                        p3[t],
                                        w3,
                                        _fma(p2[t], w2, _fma(p1[t], w1, _fma(p0[t], w0, out[t]))),
                                    )
                for side in range(
                    2
                ):  # normals p_u × p_v (side R's flipped where both sides run the same way)
                    u, v, n = values[side, 1], values[side, 2], normal[side]
                    sign = flip if side == 1 else 1.0
                    for lane in range(lanes):
                        n[0, lane] = (u[1, lane] * v[2, lane] - u[2, lane] * v[1, lane]) * sign
                    for lane in range(lanes):
                        n[1, lane] = (u[2, lane] * v[0, lane] - u[0, lane] * v[2, lane]) * sign
                    for lane in range(lanes):
                        n[2, lane] = (u[0, lane] * v[1, lane] - u[1, lane] * v[0, lane]) * sign
                a, b = normal[0], normal[1]
                for lane in range(lanes):
                    usable[k, lane] = (
                        np.sqrt(
                            (a[0, lane] * a[0, lane] + a[1, lane] * a[1, lane])
                            + a[2, lane] * a[2, lane]
                        )
                        > level
                    ) & (
                        np.sqrt(
                            (b[0, lane] * b[0, lane] + b[1, lane] * b[1, lane])
                            + b[2, lane] * b[2, lane]
                        )
                        > level
                    )
                for lane in range(lanes):
                    cross[0, lane] = a[1, lane] * b[2, lane] - a[2, lane] * b[1, lane]
                for lane in range(lanes):
                    cross[1, lane] = a[2, lane] * b[0, lane] - a[0, lane] * b[2, lane]
                for lane in range(lanes):
                    cross[2, lane] = a[0, lane] * b[1, lane] - a[1, lane] * b[0, lane]
                for lane in range(lanes):
                    y[k, lane] = np.sqrt(
                        (cross[0, lane] * cross[0, lane] + cross[1, lane] * cross[1, lane])
                        + cross[2, lane] * cross[2, lane]
                    )
                for lane in range(lanes):
                    x[k, lane] = (a[0, lane] * b[0, lane] + a[2, lane] * b[2, lane]) + a[
                        1, lane
                    ] * b[1, lane]
                for lane in range(lanes):
                    total = y[k, lane] + abs(x[k, lane])
                    ratio = y[k, lane] / total if total > 0.0 else 0.0
                    pseudo[k, lane] = ratio if x[k, lane] >= 0.0 else 2.0 - ratio
                q0, q1 = values[0, 0], values[1, 0]
                for lane in range(lanes):
                    g0, g1, g2 = (
                        q0[0, lane] - q1[0, lane],
                        q0[1, lane] - q1[1, lane],
                        q0[2, lane] - q1[2, lane],
                    )
                    distance[lane] = (g0 * g0 + g1 * g1) + g2 * g2
                for lane in range(lanes):
                    gap2[lane] = max(gap2[lane], distance[lane])
                for lane in range(lanes):
                    top[lane] = max(top[lane], pseudo[k, lane]) if usable[k, lane] else top[lane]
                for lane in range(lanes):
                    bottom[lane] = (
                        min(bottom[lane], pseudo[k, lane]) if usable[k, lane] else bottom[lane]
                    )
            for k in range(samples):
                for lane in range(lanes):
                    candidate[k, lane] = usable[k, lane] & (
                        (pseudo[k, lane] >= top[lane] * (1.0 - rtol))
                        | (pseudo[k, lane] <= bottom[lane] * (1.0 + rtol))
                    )
            for lane in range(stop - first):
                e = order[first + lane]
                best, best_at, low = 0.0, 0, np.inf
                for k in range(samples):
                    if candidate[k, lane]:
                        value = np.degrees(np.arctan2(y[k, lane], x[k, lane]))
                        if value > best:
                            best, best_at = value, k
                        low = min(low, value)
                angle[e], worst[e], least[e], gap[e] = best, best_at, low, np.sqrt(gap2[lane])


def _corner_extent_compiled(
    points: NDArray[np.float64], vertices: NDArray[np.float64] | None, corner_ids: NDArray[np.int64]
) -> tuple[NDArray[np.float64], NDArray[np.float64], float]:
    """The low and high corner of the box around the patch corners (the first four points of
    ``points (N, M, 3)``: a Gregory patch's corners, or evaluated corners ``(N, 4, 3)``), and the
    largest squared distance ``(d₀² + d₁²) + d₂²`` of a corner to its vertex
    ``vertices[corner_ids]`` (0 without vertices), in one pass over the corners without copying
    them: what :func:`_diagonal` and ``np.linalg.norm(corners - vertices[ids], axis=-1)`` read (each
    coordinate's extremes are exact; the norm is monotone in its square, so its maximum is the root
    of the largest square)."""
    chunks = _chunks(len(points))
    low, high, far = np.empty((chunks, 3)), np.empty((chunks, 3)), np.empty(chunks)
    _compiled(_corner_extent_kernel)(
        points,
        np.zeros((0, 3)) if vertices is None else np.ascontiguousarray(vertices, dtype=np.float64),
        corner_ids,
        chunks,
        low,
        high,
        far,
    )
    return low.min(axis=0), high.max(axis=0), float(far.max())


def _corner_extent_kernel(
    points: NDArray[np.float64],
    vertices: NDArray[np.float64],
    corner_ids: NDArray[np.int64],
    chunks: int,
    low: NDArray[np.float64],
    high: NDArray[np.float64],
    far: NDArray[np.float64],
) -> None:
    """Per chunk of patches: each coordinate's least and greatest corner value and the largest
    squared distance of a corner to its vertex (NaN where one is NaN, as NumPy's extremes)."""
    patches, measure = points.shape[0], vertices.shape[0] > 0
    for chunk in prange(chunks):
        least, most = np.full(3, np.inf), np.full(3, -np.inf)
        farthest = 0.0
        for n in range(chunk * patches // chunks, (chunk + 1) * patches // chunks):
            for k in range(4):
                for d in range(3):
                    x = points[n, k, d]
                    if not np.isnan(least[d]) and (x < least[d] or np.isnan(x)):
                        least[d] = x
                    if not np.isnan(most[d]) and (x > most[d] or np.isnan(x)):
                        most[d] = x
                if measure:
                    vertex = corner_ids[n, k]
                    d0, d1, d2 = (
                        points[n, k, 0] - vertices[vertex, 0],
                        points[n, k, 1] - vertices[vertex, 1],
                        points[n, k, 2] - vertices[vertex, 2],
                    )
                    square = (d0 * d0 + d1 * d1) + d2 * d2
                    if not np.isnan(farthest) and (square > farthest or np.isnan(square)):
                        farthest = square
        low[chunk], high[chunk], far[chunk] = least, most, farthest


def _corner_normals_compiled(points: NDArray[np.float64], form: str) -> NDArray[np.float64]:
    """``p_u × p_v`` at the four corners of every patch, ``(N, 4, 3)`` (the reference's
    ``_cross3`` of ``evaluate(CORNER_PARAMETERS, 1, 0)`` and ``(0, 1)``)."""
    table = np.stack(
        [_weights(form, CORNER_PARAMETERS[:, None], du, dv) for du, dv in ((1, 0), (0, 1))]
    )  # (2, 4, 1, M)
    weights, index, count = _sparse(table)  # (2, 4, M, 1)
    normals = np.empty((len(points), 4, 3))
    if len(points):
        _compiled(_corner_normal_kernel)(
            points, weights, index, count, _chunks(len(points)), normals
        )
    return normals


def _corner_normal_kernel(
    points: NDArray[np.float64],
    weights: NDArray[np.float64],
    index: NDArray[np.int64],
    count: NDArray[np.int64],
    chunks: int,
    normals: NDArray[np.float64],
) -> None:
    """Corner normals patch by patch (``weights (derivative, corner, M, 1)``)."""
    patches = points.shape[0]
    for chunk in prange(chunks):
        tangent = np.empty((2, 3))
        for n in range(chunk * patches // chunks, (chunk + 1) * patches // chunks):
            for corner in range(4):
                for q in range(2):
                    for d in range(3):
                        acc = 0.0
                        for r in range(count[q, corner]):
                            m = index[q, corner, r]
                            acc = _fma(points[n, m, d], weights[q, corner, m, 0], acc)
                        tangent[q, d] = acc
                a, b = tangent[0], tangent[1]
                normals[n, corner, 0] = a[1] * b[2] - a[2] * b[1]
                normals[n, corner, 1] = a[2] * b[0] - a[0] * b[2]
                normals[n, corner, 2] = a[0] * b[1] - a[1] * b[0]


def _max_corner_angle_compiled(
    network: PatchNetwork, normals: NDArray[np.float64], degenerate_level: float, oriented: bool
) -> float:
    """:func:`_max_corner_angle` from the corner normals ``(N, 4, 3)``, sector by sector in a
    kernel."""
    normals = normals.reshape(-1, 3)
    ids = network.corner_sectors().reshape(-1).astype(np.int64)
    if not len(ids):
        return 0.0
    # the corners by sector, in order within each (a counting sort: the stable argsort's
    # permutation; 4 M corners 0.1 s -> 0.03 s), and where each sector starts
    counts = np.bincount(ids)
    cursor = np.r_[0, np.cumsum(counts)[:-1]]
    starts = np.r_[cursor[counts > 0], len(ids)]
    order = np.empty(len(ids), dtype=np.int64)
    _serial(_counting_sort_kernel)(ids, cursor, order)
    worst = np.zeros(len(starts) - 1)
    _compiled(_corner_kernel)(
        normals,
        order,
        starts,
        degenerate_level,
        oriented,
        _PAIRWISE_SECTOR,
        _chunks(len(worst)),
        worst,
    )
    return float(worst.max(initial=0.0))


def _counting_sort_kernel(
    keys: NDArray[np.int64], cursor: NDArray[np.int64], order: NDArray[np.int64]
) -> None:
    """``order``: the items by key, in their order within a key (``cursor[k]``: where key k's first
    goes; advanced as items are placed). Serial: the placement is what makes it stable."""
    for item in range(keys.size):
        key = keys[item]
        order[cursor[key]] = item
        cursor[key] += 1


def _pair_angle(a: NDArray[np.float64], b: NDArray[np.float64], oriented: bool) -> float:
    """``atan2(|a × b|, a · b)`` in degrees (``|a · b|`` unless ``oriented``)."""
    c0, c1, c2 = a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]
    dot = (a[0] * b[0] + a[2] * b[2]) + a[1] * b[1]
    return float(
        np.degrees(
            np.arctan2(np.sqrt((c0 * c0 + c1 * c1) + c2 * c2), dot if oriented else abs(dot))
        )
    )


def _corner_kernel(
    normals: NDArray[np.float64],
    order: NDArray[np.int64],
    starts: NDArray[np.int64],
    level: float,
    oriented: bool,
    pairwise: int,
    chunks: int,
    worst: NDArray[np.float64],
) -> None:
    """Per sector (corners ``order[starts[s]:starts[s + 1]]``): the largest angle between two of its
    usable corner normals. Sectors of more than ``pairwise`` corners, oriented, whose normals lie in
    one open hemisphere around their mean m compare only the vertices of the convex hull of their
    gnomonic projections ``(n·e₁, n·e₂) / (n·m)`` (e₁, e₂ ⟂ m): great circles project to lines,
    and the angle to a point is quasi-convex along the arcs of a hemisphere, so the largest angle
    is between hull vertices (up to rounding). Work O(m log m + h²) for h hull vertices."""
    sectors = starts.size - 1
    for chunk in prange(chunks):
        for s in range(chunk * sectors // chunks, (chunk + 1) * sectors // chunks):
            members = order[starts[s] : starts[s + 1]]
            keep = np.empty(members.size, dtype=np.int64)
            kept = 0
            for corner in members:
                a = normals[corner]
                if np.sqrt((a[0] * a[0] + a[1] * a[1]) + a[2] * a[2]) > level:
                    keep[kept] = corner
                    kept += 1
            keep = keep[:kept]
            if kept > pairwise and oriented:
                keep = _hull_corners(normals, keep)
            best = 0.0
            for i in range(keep.size):
                for j in range(i + 1, keep.size):
                    best = max(best, _pair_angle(normals[keep[i]], normals[keep[j]], oriented))
            worst[s] = best


def _hull_corners(normals: NDArray[np.float64], corners: NDArray[np.int64]) -> NDArray[np.int64]:
    """The corners whose unit normals' gnomonic projections are vertices of their convex hull
    (Andrew's monotone chain), or all of them when some normal is not within 90° of the mean."""
    unit = np.empty((corners.size, 3))
    mean = np.zeros(3)
    for i in range(corners.size):
        a = normals[corners[i]]
        unit[i] = a / np.sqrt((a[0] * a[0] + a[1] * a[1]) + a[2] * a[2])
        mean += unit[i]
    mean /= np.sqrt((mean[0] * mean[0] + mean[1] * mean[1]) + mean[2] * mean[2])
    axis = np.zeros(3)
    axis[np.argmin(np.abs(mean))] = 1.0
    e1 = np.cross(mean, axis)
    e1 /= np.sqrt((e1[0] * e1[0] + e1[1] * e1[1]) + e1[2] * e1[2])
    e2 = np.cross(mean, e1)
    heights = unit @ mean
    if heights.min() <= 0.0:
        return corners
    px, py = (unit @ e1) / heights, (unit @ e2) / heights
    by_y = np.argsort(py, kind="mergesort")
    sort = by_y[np.argsort(px[by_y], kind="mergesort")]  # by x, then y
    hull = np.empty(2 * sort.size, dtype=np.int64)
    size = 0
    for sweep in range(2):
        base = size
        for step in range(sort.size):
            p = sort[step] if sweep == 0 else sort[sort.size - 1 - step]
            while size >= base + 2:
                a, b = hull[size - 2], hull[size - 1]
                if (px[b] - px[a]) * (py[p] - py[a]) - (py[b] - py[a]) * (px[p] - px[a]) > 0.0:
                    break
                size -= 1
            hull[size] = p
            size += 1
        size -= 1  # each chain's last point starts the other
    return corners[np.unique(hull[: max(size, 1)])]


def _grid_tables(form: str, grid: NDArray[np.float64]) -> tuple[NDArray[Any], ...]:
    """The grid kernel's tables: ``index (16,)`` (the point of net entry ``4 i + j``), the blend
    pairs ``fn, fp (B,)``, the bases ``bu, dbu (G, 4)`` and ``bv, dbv (4, G)``, the blend weights
    ``su, sv (B, G, G)`` (B = 4 for Gregory patches, 0 for a PatchSet)."""
    basis = "bezier" if form == "gregory" else form
    bu, dbu = basis_values(basis, grid), basis_values(basis, grid, 1)  # type: ignore[arg-type]
    tables_v = np.ascontiguousarray(bu.T), np.ascontiguousarray(dbu.T)
    if form != "gregory":
        empty = np.zeros((0, len(grid), len(grid)))
        none = np.zeros(0, dtype=np.int64)
        return np.arange(16), none, none, bu, dbu, *tables_v, empty, empty
    index = np.empty(16, dtype=np.int64)
    index[4 * BEZIER_INDEX[:, 0] + BEZIER_INDEX[:, 1]] = np.arange(12)
    index[4 * INTERIOR_INDEX[:, 0] + INTERIOR_INDEX[:, 1]] = 13 + 2 * np.arange(4)  # Fp_k
    su, sv = (
        np.ascontiguousarray(
            np.moveaxis(table.reshape(len(grid), len(grid), 20)[..., 12::2], -1, 0)
        )
        for table in _gregory_grid_weights(grid)
    )
    return index, 12 + 2 * np.arange(4), 13 + 2 * np.arange(4), bu, dbu, *tables_v, su, sv


def _gregory_grid_weights(grid: NDArray[np.float64]) -> NDArray[np.float64]:
    """The point weights of p_u and p_v on the grid, ``(2, G², 20)``, as
    :meth:`_GridMeasures._tangents` forms them."""
    u, v = grid[:, None], grid[None, :]
    return np.stack([gregory_weights(u, v, du, dv).reshape(-1, 20) for du, dv in ((1, 0), (0, 1))])


def _turn_kernel(
    points: NDArray[np.float64],
    exact: NDArray[np.float64],
    level: float,
    patches: NDArray[np.int64],
    axes: NDArray[np.int64],
    chunks: int,
    chord2: NDArray[np.float64],
    angle: NDArray[np.float64],
) -> None:
    """For Gregory patches ``patches[c]`` and ``axes[c]`` (0: along u): the first largest squared
    chord between neighbouring unit normals along that axis and the angle of its pair, from the
    tangents summed as the reference's matrix product sums them (``exact (2, 20, G²)``: the point
    weights of p_u and p_v, a sequential fused multiply-add over the points, each sample's sum in
    its own lane: the loops over the samples vectorise), so the reference's values (chord² −1
    without pairs)."""
    samples, candidates = exact.shape[2], patches.size
    g = int(round(np.sqrt(samples)))
    for chunk in prange(chunks):
        tangent, normal = np.empty((2, 3, samples)), np.empty((3, samples))
        unit, length = np.empty((3, samples)), np.empty(samples)
        usable = np.empty(samples, dtype=np.bool_)
        pair = np.empty((2, 3))
        for c in range(chunk * candidates // chunks, (chunk + 1) * candidates // chunks):
            n, axis = patches[c], axes[c]
            for q in range(2):
                for d in range(3):
                    acc = tangent[q, d]
                    for s in range(samples):
                        acc[s] = 0.0
                    for m in range(20):
                        p, w = points[n, m, d], exact[q, m]
                        for s in range(samples):
                            acc[s] = _fma(p, w[s], acc[s])
            a, b = tangent[0], tangent[1]
            for s in range(samples):
                normal[0, s] = a[1, s] * b[2, s] - a[2, s] * b[1, s]
            for s in range(samples):
                normal[1, s] = a[2, s] * b[0, s] - a[0, s] * b[2, s]
            for s in range(samples):
                normal[2, s] = a[0, s] * b[1, s] - a[1, s] * b[0, s]
            for s in range(samples):
                length[s] = np.sqrt(
                    (normal[0, s] * normal[0, s] + normal[1, s] * normal[1, s])
                    + normal[2, s] * normal[2, s]
                )
            for s in range(samples):
                usable[s] = length[s] > level
            for s in range(samples):
                length[s] = 1.0 / max(length[s], _TINY)
            for d in range(3):
                for s in range(samples):
                    unit[d, s] = normal[d, s] * length[s]
            top, top_at, step = -1.0, -1, g if axis == 0 else 1
            for i in range(g - 1 + axis):
                for j in range(g - axis):
                    s = i * g + j
                    if usable[s] and usable[s + step]:
                        c0, c1, c2 = (
                            unit[0, s + step] - unit[0, s],
                            unit[1, s + step] - unit[1, s],
                            unit[2, s + step] - unit[2, s],
                        )
                        value = (c0 * c0 + c2 * c2) + c1 * c1
                        if value > top:
                            top, top_at = value, s
            chord2[c] = top
            angle[c] = 0.0
            if top_at >= 0:
                for d in range(3):
                    pair[0, d], pair[1, d] = normal[d, top_at], normal[d, top_at + step]
                angle[c] = _pair_angle(pair[0], pair[1], True)


def _grid_kernel(
    points: NDArray[np.float64],
    index: NDArray[np.int64],
    fn: NDArray[np.int64],
    fp: NDArray[np.int64],
    bu: NDArray[np.float64],
    dbu: NDArray[np.float64],
    bv: NDArray[np.float64],
    dbv: NDArray[np.float64],
    su: NDArray[np.float64],
    sv: NDArray[np.float64],
    weights: NDArray[np.float64],
    level: float,
    fairness: bool,
    code_min: int,
    lanes: int,
    chunks: int,
    location: NDArray[np.int64],
    degenerate: NDArray[np.int64],
    histogram: NDArray[np.int64],
    best: NDArray[np.float64],
    energy: NDArray[np.float64],
) -> None:
    """:meth:`_GridMeasures.add` for ``lanes`` patches at a time (the lanes, last axis of
    every scratch array, so the arithmetic vectorises across patches), row by row of their grids:
    tangents (fused multiply-adds: one u contraction of the net per row, 4 products and 4 blends
    per point; rows a − 1 and a kept), normals (the whole grid), the corner-cell and 90° tests
    (``location``: the first offending sample ``G i + j``, −1 if none), degenerate normals and, if
    ``fairness``, the histogram of the turns (a row per chunk; a run of one bin along a patch's row
    is counted in a register and added once), the thin-plate energy, and per axis (u, v) the first
    largest squared chord with the angle of its pair (``best (N, 4)``: chord², angle, chord², angle;
    chord² −1 without pairs; kept per grid column row by row, then the columns' largest, the lowest
    ``G i + j`` among equals: the first in row-major order). Inner loops index one-dimensional views
    taken before the loop by the loop variable only: LLVM vectorises such loops (computed indices
    whose sign it cannot prove left the previous kernel scalar: 2× slower), also where they store
    to several arrays, as the normals' pass does (normal, unit normal and usable in one pass: 8–14 %
    less time than a pass per array). Outputs are bitwise those of the sample-major formulation
    (same operations in the same order per value)."""
    patches, g, blends, bins = points.shape[0], bu.shape[0], fn.size, histogram.shape[1]
    last, gl, run = g - 1, g * lanes, (g - 1) * lanes
    groups = (patches + lanes - 1) // lanes
    for chunk in prange(chunks):
        net, blend = np.zeros((3, 16, lanes)), np.zeros((3, 4, lanes))
        row_u, row_v = np.empty((4, lanes)), np.empty((4, lanes))
        tu, tv = (
            np.empty((2, 3, gl)),
            np.empty((2, 3, gl)),
        )  # p_u, p_v of rows a − 1, a (by parity), [row, xyz, g b + lane]
        tu4, tv4 = tu.reshape((2, 3, g, lanes)), tv.reshape((2, 3, g, lanes))
        tu_ahead, tv_ahead = tu[:, :, lanes:], tv[:, :, lanes:]  # the sample at b + 1
        normal, usable, offending = (
            np.empty((3, g, gl)),
            np.empty((g, gl), dtype=np.bool_),
            np.empty((g, gl), dtype=np.bool_),
        )
        unit = np.empty((2, 3, gl))
        unit_ahead, usable_ahead = unit[:, :, lanes:], usable[:, lanes:]
        chord, together = np.empty(gl), np.empty(gl, dtype=np.bool_)
        chord2, together2 = chord.reshape((g, lanes)), together.reshape((g, lanes))
        narrow, code = np.empty(gl, dtype=np.float32), np.empty(gl, dtype=np.int64)
        code2, bits = code.reshape((g, lanes)), narrow.view(np.int32)
        column_top, column_row = np.empty((2, gl)), np.empty((2, gl), dtype=np.int64)
        top, top_at = np.empty((2, lanes)), np.empty((2, lanes), dtype=np.int64)
        along_u, along_v = np.empty((2, gl)), np.empty((2, g, lanes))
        pair = np.empty((2, 3))
        folded = np.empty(gl, dtype=np.bool_)
        for group in range(chunk * groups // chunks, (chunk + 1) * groups // chunks):
            first = group * lanes
            count = min(lanes, patches - first)
            for lane in range(count):
                for d in range(3):
                    for m in range(16):
                        net[d, m, lane] = points[first + lane, index[m], d]
                    for k in range(blends):
                        blend[d, k, lane] = (
                            points[first + lane, fn[k], d] - points[first + lane, fp[k], d]
                        )
            column_top[:] = -1.0
            column_row[:] = -1
            along_u[:] = 0.0
            lost = 0
            for a in range(g):
                r, p = a & 1, 1 - (a & 1)
                for d in range(
                    3
                ):  # tangents: the u contraction of the net, then 4 products and 4 blends a point
                    w0, w1, w2, w3 = dbu[a, 0], dbu[a, 1], dbu[a, 2], dbu[a, 3]
                    x0, x1, x2, x3 = bu[a, 0], bu[a, 1], bu[a, 2], bu[a, 3]
                    for j in range(4):
                        for lane in range(lanes):
                            row_u[j, lane] = _fma(
                                w3,
                                net[d, 12 + j, lane],
                                _fma(
                                    w2,
                                    net[d, 8 + j, lane],
                                    _fma(w1, net[d, 4 + j, lane], w0 * net[d, j, lane]),
                                ),
                            )
                        for lane in range(lanes):
                            row_v[j, lane] = _fma(
                                x3,
                                net[d, 12 + j, lane],
                                _fma(
                                    x2,
                                    net[d, 8 + j, lane],
                                    _fma(x1, net[d, 4 + j, lane], x0 * net[d, j, lane]),
                                ),
                            )
                    for b in range(g):
                        y0, y1, y2, y3 = bv[0, b], bv[1, b], bv[2, b], bv[3, b]
                        z0, z1, z2, z3 = dbv[0, b], dbv[1, b], dbv[2, b], dbv[3, b]
                        if blends:
                            s0, s1, s2, s3 = su[0, a, b], su[1, a, b], su[2, a, b], su[3, a, b]
                            t0, t1, t2, t3 = sv[0, a, b], sv[1, a, b], sv[2, a, b], sv[3, a, b]
                            out_u, out_v = tu4[r, d, b], tv4[r, d, b]
                            e0, e1, e2, e3 = blend[d, 0], blend[d, 1], blend[d, 2], blend[d, 3]
                            ru0, ru1, ru2, ru3 = row_u[0], row_u[1], row_u[2], row_u[3]
                            rv0, rv1, rv2, rv3 = row_v[0], row_v[1], row_v[2], row_v[3]
                            for lane in range(lanes):
                                value = _fma(
                                    ru3[lane],
                                    y3,
                                    _fma(ru2[lane], y2, _fma(ru1[lane], y1, ru0[lane] * y0)),
                                )
                                out_u[lane] = _fma(
                                    s3,
                                    e3[lane],
                                    _fma(
                                        s2, e2[lane], _fma(s1, e1[lane], _fma(s0, e0[lane], value))
                                    ),
                                )
                            for lane in range(lanes):
                                value = _fma(
                                    rv3[lane],
                                    z3,
                                    _fma(rv2[lane], z2, _fma(rv1[lane], z1, rv0[lane] * z0)),
                                )
                                out_v[lane] = _fma(
                                    t3,
                                    e3[lane],
                                    _fma(
                                        t2, e2[lane], _fma(t1, e1[lane], _fma(t0, e0[lane], value))
                                    ),
                                )
                        else:
                            for lane in range(lanes):
                                tu4[r, d, b, lane] = _fma(
                                    row_u[3, lane],
                                    y3,
                                    _fma(
                                        row_u[2, lane],
                                        y2,
                                        _fma(row_u[1, lane], y1, row_u[0, lane] * y0),
                                    ),
                                )
                            for lane in range(lanes):
                                tv4[r, d, b, lane] = _fma(
                                    row_v[3, lane],
                                    z3,
                                    _fma(
                                        row_v[2, lane],
                                        z2,
                                        _fma(row_v[1, lane], z1, row_v[0, lane] * z0),
                                    ),
                                )
                # normals, unit normals, usable: one pass over the row's samples
                n0, n1, n2 = normal[0, a], normal[1, a], normal[2, a]
                u0, u1, u2 = unit[r, 0], unit[r, 1], unit[r, 2]
                ua = usable[a]
                a0, a1, a2 = tu[r, 0], tu[r, 1], tu[r, 2]
                b0, b1, b2 = tv[r, 0], tv[r, 1], tv[r, 2]
                for s in range(gl):
                    x = a1[s] * b2[s] - a2[s] * b1[s]
                    y = a2[s] * b0[s] - a0[s] * b2[s]
                    z = a0[s] * b1[s] - a1[s] * b0[s]
                    n0[s] = x
                    n1[s] = y
                    n2[s] = z
                    size = np.sqrt((x * x + y * y) + z * z)
                    inverse = 1.0 / max(size, _TINY)
                    u0[s] = x * inverse
                    u1[s] = y * inverse
                    u2[s] = z * inverse
                    ua[s] = size > level
                offending[a, :] = False
                if count == lanes:
                    for s in range(gl):
                        lost += 0 if usable[a, s] else 1
                else:
                    for b in range(g):
                        for lane in range(count):
                            lost += 0 if usable[a, b * lanes + lane] else 1
                for axis in range(
                    2
                ):  # neighbours along u: (a − 1, b), (a, b); along v: (a, b), (a, b + 1)
                    if axis == 0 and a == 0:
                        continue
                    behind, span = (a - 1, gl) if axis == 0 else (a, run)
                    if axis == 0:
                        for s in range(gl):
                            c0, c1, c2 = (
                                unit[r, 0, s] - unit[p, 0, s],
                                unit[r, 1, s] - unit[p, 1, s],
                                unit[r, 2, s] - unit[p, 2, s],
                            )
                            chord[s] = (
                                c0 * c0 + c2 * c2
                            ) + c1 * c1  # |n̂_a − n̂_b|² = 4 sin²(θ/2): > 2 where θ > 90°
                        for s in range(gl):
                            together[s] = usable[a - 1, s] & usable[a, s]
                    else:
                        for s in range(run):
                            c0, c1, c2 = (
                                unit_ahead[r, 0, s] - unit[r, 0, s],
                                unit_ahead[r, 1, s] - unit[r, 1, s],
                                unit_ahead[r, 2, s] - unit[r, 2, s],
                            )
                            chord[s] = (c0 * c0 + c2 * c2) + c1 * c1
                        for s in range(run):
                            together[s] = usable[a, s] & usable_ahead[a, s]
                    for s in range(span):
                        offending[behind, s] = offending[behind, s] | (
                            together[s] & (chord[s] > 2.0)
                        )
                    if not fairness:
                        continue
                    best_top, best_row = (
                        column_top[axis],
                        column_row[axis],
                    )  # per column: the first largest chord
                    for s in range(span):
                        best_row[s] = (
                            behind if together[s] & (chord[s] > best_top[s]) else best_row[s]
                        )
                    for s in range(span):
                        best_top[s] = (
                            chord[s] if together[s] & (chord[s] > best_top[s]) else best_top[s]
                        )
                    for s in range(span):
                        narrow[s] = chord[s]
                    for s in range(span):
                        code[s] = min(max((bits[s] >> _SHIFT) - (code_min - 1), 0), bins - 1)
                    for lane in range(
                        count
                    ):  # runs of one bin along the row, counted in a register
                        current, tally = 0, 0
                        for b in range(span // lanes):
                            if together2[b, lane]:
                                code_b = code2[b, lane]
                                if code_b != current:
                                    histogram[chunk, current] += tally
                                    current, tally = code_b, 0
                                tally += 1
                        histogram[chunk, current] += tally
                if not fairness:
                    continue
                for plane in range(
                    2
                    # thin plate: squared differences of p_u, p_v along u (per column), along v (per
                    # row)
                ):
                    t, ahead = (tu, tu_ahead) if plane == 0 else (tv, tv_ahead)
                    if a > 0:
                        for s in range(gl):
                            c0, c1, c2 = (
                                t[r, 0, s] - t[p, 0, s],
                                t[r, 1, s] - t[p, 1, s],
                                t[r, 2, s] - t[p, 2, s],
                            )
                            along_u[plane, s] += (c0 * c0 + c2 * c2) + c1 * c1
                    for s in range(run):
                        c0, c1, c2 = (
                            ahead[r, 0, s] - t[r, 0, s],
                            ahead[r, 1, s] - t[r, 1, s],
                            ahead[r, 2, s] - t[r, 2, s],
                        )
                        chord[s] = (c0 * c0 + c2 * c2) + c1 * c1
                    along_v[plane, a, :] = 0.0
                    for b in range(last):
                        for lane in range(lanes):
                            along_v[plane, a, lane] += chord2[b, lane]
            degenerate[chunk] += lost
            # per lane and axis the first largest chord in row-major order: the largest of the
            # columns', first
            if fairness:
                for axis in range(2):
                    for lane in range(lanes):
                        value, at = -1.0, -1
                        for b in range(g - axis):
                            row = column_row[axis, b * lanes + lane]
                            if row < 0:
                                continue
                            chord_b = column_top[axis, b * lanes + lane]
                            if chord_b > value or (chord_b == value and row * g + b < at):
                                value, at = chord_b, row * g + b
                        top[axis, lane], top_at[axis, lane] = value, at
            for lane in range(count):
                for corner in range(4):  # the corner's grid cell: a patch turned over at its corner
                    cu = 0 if corner == 0 or corner == 3 else last
                    cv = 0 if corner < 2 else last
                    o = cv * lanes + lane
                    if not usable[cu, o]:
                        continue
                    step_u, step_v = (1 if cu == 0 else -1), (lanes if cv == 0 else -lanes)
                    for cell in range(3):
                        i, s = cu + (0 if cell == 1 else step_u), o + (0 if cell == 0 else step_v)
                        dot = (
                            normal[0, i, s] * normal[0, cu, o] + normal[2, i, s] * normal[2, cu, o]
                        ) + normal[1, i, s] * normal[1, cu, o]
                        if usable[i, s] and dot < 0.0:
                            offending[i, s] = True
            folded[:] = False  # per lane: any offending sample? then the first, row by row
            for i in range(g):
                for s in range(gl):
                    folded[s] = folded[s] | offending[i, s]
            for lane in range(count):
                location[first + lane] = -1
                hit = False
                for b in range(g):
                    hit = hit | folded[b * lanes + lane]
                if not hit:
                    continue
                for i in range(g * g):
                    if offending[i // g, (i % g) * lanes + lane]:
                        location[first + lane] = i
                        break
            if not fairness:
                continue
            for lane in range(count):
                n = first + lane
                for axis in range(2):
                    best[n, 2 * axis], best[n, 2 * axis + 1] = top[axis, lane], 0.0
                    s = top_at[axis, lane]
                    if s >= 0:
                        i, j = s // g, s % g
                        k, l = (i + 1, j) if axis == 0 else (i, j + 1)
                        for d in range(3):
                            pair[0, d], pair[1, d] = (
                                normal[d, i, j * lanes + lane],
                                normal[d, k, l * lanes + lane],
                            )
                        best[n, 2 * axis + 1] = _pair_angle(pair[0], pair[1], True)
            for lane in range(count):
                total = 0.0
                for plane in range(2):
                    row = 0.0
                    for b in range(g):
                        row += weights[b] * along_u[plane, b * lanes + lane]
                    total += row
                    row = 0.0
                    for a in range(g):
                        row += weights[a] * along_v[plane, a, lane]
                    total += row
                energy[first + lane] = total
