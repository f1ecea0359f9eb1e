"""The check's result: :class:`ContinuityReport` (figures, verdict, summary table, JSON and
Jupyter views) and :func:`format_reports` (reports side by side)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..errors import InputError

#: the project's bar for "exactly G1", degrees (DESIGN §5): the defaults of :meth:`ContinuityReport.
#: is_g1`, :meth:`~ContinuityReport.passes` and :meth:`~ContinuityReport.verdict`
EXACT_G1_DEG = 1e-9
SEAM_G0_RTOL = 1e-12
"""The largest G0 gap (relative to the bounding-box diagonal) a seam may have and pass: its two
sides share one boundary curve, equal up to rounding."""


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
    #: patches with no surface to speak of: zero area everywhere on the fold grid, or more than
    #: one collapsed edge (one is an intended triangular patch, as the teapot's poles); their count
    #: and the first of them (at most 10)
    degenerate_patches: int = 0
    degenerate_patch_ids: tuple[int, ...] = ()
    #: of the shared edges, the hanging ones (a fine patch edge along part of a coarse one, last in
    #: the per-edge arrays: fine side first)
    hanging_edges: int = 0

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

    def is_g1(self, max_angle_deg: float = EXACT_G1_DEG) -> bool:
        """True when every smooth edge and every corner sector's angle is within ``max_angle_deg``
        (folds and seams aside); ``max_angle_deg`` must be finite, from 0 to 180
        (:class:`~g1patch.errors.InputError`: NaN would pass every check)."""
        if not (
            isinstance(max_angle_deg, (int, float, np.integer, np.floating))
            and not isinstance(max_angle_deg, bool)
            and 0.0 <= max_angle_deg <= 180.0
        ):
            raise InputError(
                f"max_angle: expected a finite number of degrees in [0, 180], got {max_angle_deg!r}"
            )
        return max(self.max_edge_angle_deg, self.max_corner_angle_deg) <= max_angle_deg

    def seams_closed(self, max_gap: float = SEAM_G0_RTOL) -> bool:
        """True when every seam's G0 gap (relative to the bbox diagonal) is within ``max_gap``."""
        return self.seam_g0_max <= max_gap

    def passes(
        self, max_angle_deg: float = EXACT_G1_DEG, max_seam_gap: float = SEAM_G0_RTOL
    ) -> bool:
        """The check verdict: :meth:`is_g1`, no patch folds, no degenerate patch and
        :meth:`seams_closed`."""
        return (
            self.is_g1(max_angle_deg)
            and self.folds == 0
            and self.degenerate_patches == 0
            and self.seams_closed(max_seam_gap)
        )

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
            "hanging_edges": self.hanging_edges,
            "open_edges": self.open_edges,
            "collapsed_edges": self.collapsed_edges,
            "collapsed_patch_edges": self.collapsed_patch_edges,
            "samples_per_edge": self.samples_per_edge,
            "max_edge_angle_deg": self.max_edge_angle_deg,
            "mean_edge_angle_deg": self.mean_edge_angle_deg,
            "max_corner_angle_deg": self.max_corner_angle_deg,
            "max_g0_gap": self.max_g0_gap,
            "degenerate_normals": self.degenerate_normals,
            "degenerate_patches": self.degenerate_patches,
            "degenerate_patch_ids": list(self.degenerate_patch_ids),
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

    def _degenerate_rows(self) -> list[tuple[str, str]]:
        if not self.degenerate_patches:
            return []
        first = ", ".join(str(i) for i in self.degenerate_patch_ids)
        more = ", …" if self.degenerate_patches > len(self.degenerate_patch_ids) else ""
        return [("degenerate patches", f"{self.degenerate_patches} ({first}{more})")]

    @property
    def _hanging_note(self) -> str:
        return f" ({self.hanging_edges} hanging)" if self.hanging_edges else ""

    def rows(self) -> list[tuple[str, str]]:
        """(label, value) pairs of the figures, as :meth:`summary` prints them."""
        rows = [
            ("patches", f"{self.patches}"),
            ("shared / open edges", f"{self.shared_edges} / {self.open_edges}{self._hanging_note}"),
            ("max G1 angle on edges", f"{self.max_edge_angle_deg:.3e}°"),
            ("mean G1 angle on edges", f"{self.mean_edge_angle_deg:.3e}°"),
            ("max G1 angle at corners", f"{self.max_corner_angle_deg:.3e}°"),
            ("max G0 gap (of bbox diag)", f"{self.max_g0_gap:.3e}"),
            ("degenerate normals", f"{self.degenerate_normals}"),
            *self._degenerate_rows(),
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

    def verdict(self, max_angle_deg: float = EXACT_G1_DEG) -> str:
        """One phrase: ``"exact G1 (max angle 3.1e-12°), no folds"``, or what fails."""
        angle = max(self.max_edge_angle_deg, self.max_corner_angle_deg)
        g1 = (
            f"exact G1 (max angle {angle:.2g}°)"
            if self.is_g1(max_angle_deg)
            else f"not G1 (max angle {angle:.3g}°)"
        )
        folds = f"{self.folds} folded patches" if self.folds else "no folds"
        if self.degenerate_patches:
            folds += f", {self.degenerate_patches} degenerate patches"
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
            f"<div><b>ContinuityReport</b>: {escape(self.verdict())} "
            f"(the check {verdict} at {EXACT_G1_DEG:g}°)"
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
