"""How smooth is a patch network? G0 gaps and G1 angles on every shared edge and corner.

For every interior edge shared by patches L and R the edge is sampled at K ≥ 33 parameters,
both ends included, from both sides; exact first derivatives give the normals
``n = p_u × p_v`` and the G1 angle is ``atan2(|n_L × n_R|, n_L · n_R)`` (accurate near 0, where
arccos floors at ~1e-6°). The G0 gap is ``|p_L − p_R|``, reported relative to the bounding-box
diagonal. Corners: the angle between the normals of every pair of patches meeting at a point.
Folds: a patch normal pointing against the mesh's fan normals (blended over the quad), or, for
patch files without a mesh, a normal that flips between neighbouring samples. Degenerate normals: ``|p_u × p_v| ≤ degenerate_rtol · diag²`` (collapsed edges), counted on a
regular grid of samples per patch.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .errors import InputError
from .network import PatchNetwork, Patches, edge_parameters
from .patches import CORNER_PARAMETERS

__all__ = ["ContinuityReport", "check", "angle_between", "format_reports"]

DEGENERATE_RTOL = 1e-13
"""|p_u × p_v| ≤ DEGENERATE_RTOL · diag² is a degenerate normal. At a collapsed edge the
derivative is a sum of equal points with weights summing to zero, ~1e-16 · diag, so the cross
product there is ~1e-16 · diag²; a real patch of a 1 M-quad mesh has |p_u × p_v| ~ 1e-6 · diag²."""


_FOLD_COSINE = np.cos(np.radians(150.0))


def angle_between(a: NDArray[np.float64], b: NDArray[np.float64]) -> NDArray[np.float64]:
    """Angle in degrees between vectors along the last axis: ``atan2(|a × b|, a · b)``."""
    a, b = np.broadcast_arrays(np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64))
    shape = a.shape[:-1]
    return _angle3(_planar(a.reshape(-1, 3)), _planar(b.reshape(-1, 3))).reshape(shape)[()]


@dataclass(frozen=True)
class ContinuityReport:
    """The measured smoothness of a network (angles in degrees, gaps relative to the bbox diagonal)."""

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
    #: per shared edge: (patch, edge) of both sides, max G1 angle (deg), max G0 gap (relative)
    edge_patches: NDArray[np.int64] = field(repr=False)
    edge_sides: NDArray[np.int64] = field(repr=False)
    edge_angle_deg: NDArray[np.float64] = field(repr=False)
    edge_gap: NDArray[np.float64] = field(repr=False)

    @property
    def worst_edge(self) -> dict[str, Any] | None:
        """The shared edge with the largest G1 angle: its patches, edges, angle and gap."""
        if not self.shared_edges:
            return None
        index = int(np.argmax(self.edge_angle_deg))
        return {
            "patches": [int(p) for p in self.edge_patches[index]],
            "edges": [int(k) for k in self.edge_sides[index]],
            "angle_deg": float(self.edge_angle_deg[index]),
            "g0_gap": float(self.edge_gap[index]),
        }

    def is_g1(self, max_angle_deg: float = 1e-9) -> bool:
        """True when every edge and corner angle is within ``max_angle_deg``."""
        return max(self.max_edge_angle_deg, self.max_corner_angle_deg) <= max_angle_deg

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
        ]
        if self.collapsed_edges:
            rows.insert(2, ("collapsed edges", f"{self.collapsed_edges} ({self.collapsed_patch_edges} patch edges)"))
        if self.inconsistent_orientation_edges:
            rows.append(("edges with flipped orientation", f"{self.inconsistent_orientation_edges}"))
        if self.max_vertex_deviation is not None:
            rows.append(("max vertex deviation (of diag)", f"{self.max_vertex_deviation:.3e}"))
        worst = self.worst_edge
        if worst is not None:
            rows.append(
                ("worst edge", f"patch {worst['patches'][0]} edge {worst['edges'][0]} / "
                 f"patch {worst['patches'][1]} edge {worst['edges'][1]}")
            )
        return rows

    def summary(self) -> str:
        """A short human-readable table."""
        return format_reports([self])


def format_reports(reports: list[ContinuityReport], titles: list[str] | None = None) -> str:
    """The reports' figures as a table, one column per report (rows missing from one are blank)."""
    columns = [dict(report.rows()) for report in reports]
    labels = list(dict.fromkeys(label for report in reports for label, _ in report.rows()))
    table = [[label, *(column.get(label, "") for column in columns)] for label in labels]
    if titles is not None:
        table = [["", *titles], ["", *("-" * len(title) for title in titles)], *table]
    widths = [max(len(row[i]) for row in table) for i in range(len(table[0]))]
    return "\n".join("  ".join(cell.ljust(width) for cell, width in zip(row, widths, strict=True)).rstrip() for row in table)


def check(
    network: PatchNetwork,
    samples: int = 33,
    fold_samples: int = 9,
    degenerate_rtol: float = DEGENERATE_RTOL,
    chunk: int = 4096,
    progress: Callable[[int, int], None] | None = None,
) -> ContinuityReport:
    """Measure G0 and G1 continuity of ``network`` (see the module docstring for the measures).

    Work is done in blocks of ``chunk`` edges or patches, so memory stays bounded on networks of
    millions of patches (the default keeps a block's sample arrays near the size of a core's L2
    cache, the fastest setting measured); ``progress(done, total)`` is called after each block.
    Degenerate normals are counted on the ``fold_samples²`` grid of every patch.
    """
    for name, value, least in (("samples", samples, 2), ("fold_samples", fold_samples, 2), ("chunk", chunk, 1)):
        if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < least:
            raise InputError(f"{name}: expected an integer ≥ {least}, got {value!r}")
    patches = network.patches
    diagonal = network.bounding_box_diagonal() or 1.0
    degenerate_level = degenerate_rtol * diagonal**2

    left_patch, left_edge = network.shared_edges()
    right_patch = network.neighbor[left_patch, left_edge]
    right_edge = network.neighbor_edge[left_patch, left_edge]
    same = network.same_direction[left_patch, left_edge]
    edge_angle = np.zeros(len(left_patch))
    edge_gap = np.zeros(len(left_patch))
    edge_blocks, patch_blocks = _blocks(len(left_patch), chunk), _blocks(len(patches), chunk)
    total = len(left_patch) + len(patches)
    for block in edge_blocks:
        edge_angle[block], edge_gap[block] = _edge_measures(
            patches, left_patch[block], left_edge[block], right_patch[block], right_edge[block], same[block],
            samples, degenerate_level,
        )
        if progress is not None:
            progress(block.stop, total)
    edge_gap /= diagonal

    corner_angle = _max_corner_angle(network, patches, degenerate_level, oriented=not same.any())
    folds = degenerate = 0
    for block in patch_blocks:
        block_folds, block_degenerate = _folds(network, np.arange(block.start, block.stop), fold_samples, degenerate_level)
        folds += block_folds
        degenerate += block_degenerate
        if progress is not None:
            progress(len(left_patch) + block.stop, total)

    max_vertex_deviation = None
    if network.vertices is not None:
        corners = patches.evaluate(CORNER_PARAMETERS)
        deviation = np.linalg.norm(corners - network.vertices[network.corner_ids], axis=-1)
        max_vertex_deviation = float(deviation.max() / diagonal) if deviation.size else 0.0

    open_patch, _ = network.open_edges()
    return ContinuityReport(
        patches=len(patches),
        shared_edges=int(len(left_patch)),
        open_edges=int(len(open_patch)),
        collapsed_edges=int(network.edge_collapsed.sum()),
        collapsed_patch_edges=int(network.edge_collapsed[network.edge_ids].sum()),
        samples_per_edge=samples,
        max_edge_angle_deg=float(edge_angle.max(initial=0.0)),
        mean_edge_angle_deg=float(edge_angle.mean()) if len(edge_angle) else 0.0,
        max_corner_angle_deg=corner_angle,
        max_g0_gap=float(edge_gap.max(initial=0.0)),
        degenerate_normals=degenerate,
        folds=folds,
        inconsistent_orientation_edges=int(same.sum()),
        bounding_box_diagonal=float(diagonal),
        max_vertex_deviation=max_vertex_deviation,
        edge_patches=np.stack([left_patch, right_patch], axis=1),
        edge_sides=np.stack([left_edge, right_edge], axis=1),
        edge_angle_deg=edge_angle,
        edge_gap=edge_gap,
    )


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
    patches: Patches, patch_ids: NDArray[np.int64], edges: NDArray[np.int64], backwards: NDArray[np.bool_], t: NDArray[np.float64]
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Points and normals ``p_u × p_v`` at ``t`` along the given patch edges, each planar ``(3, E, K)``.

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
                normals[:, rows] = _cross3(_planar(group.evaluate(uv, 1, 0)), _planar(group.evaluate(uv, 0, 1)))
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
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Max G1 angle (deg) and max G0 gap (absolute) along each given shared edge.

    Side R runs along the edge in its own counter-clockwise direction, so it is sampled at the
    reversed parameters (exactly ``t[::-1]``) unless both sides run the same way; then its
    normal is flipped, as its patch is oriented the other way.
    """
    t = np.linspace(0.0, 1.0, samples)
    point_left, normal_left = _edge_samples(patches, left_patch, left_edge, np.zeros(len(same), dtype=bool), t)
    point_right, normal_right = _edge_samples(patches, right_patch, right_edge, ~same, t)
    if same.any():
        normal_right[:, same] *= -1.0
    usable = (_norm3(normal_left) > degenerate_level) & (_norm3(normal_right) > degenerate_level)
    angles = np.where(usable, _angle3(normal_left, normal_right), 0.0)
    point_left -= point_right
    gaps = _norm3(point_left)
    return angles.max(axis=1, initial=0.0), gaps.max(axis=1, initial=0.0)


def _max_corner_angle(network: PatchNetwork, patches: Patches, degenerate_level: float, oriented: bool) -> float:
    """Largest angle between the corner normals of any two patches meeting at one point.

    Corners are grouped by their point id and the groups by size, so the pairwise angles of all
    points with m corners form one (groups, m, m) array.
    """
    normals = _cross3(_planar(patches.evaluate(CORNER_PARAMETERS, 1, 0)), _planar(patches.evaluate(CORNER_PARAMETERS, 0, 1)))
    normals = normals.reshape(3, -1)
    usable = _norm3(normals) > degenerate_level
    ids = network.corner_ids.reshape(-1)[usable]
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
        group = normals[group_starts[:, None] + np.arange(size)]  # (g, m, 3)
        cross = np.linalg.norm(np.cross(group[:, :, None], group[:, None, :]), axis=-1)
        dot = np.einsum("gid,gjd->gij", group, group)
        if not oriented:
            dot = np.abs(dot)
        worst = max(worst, float(np.degrees(np.arctan2(cross, dot)).max()))
    return worst


def _folds(network: PatchNetwork, patch_ids: NDArray[np.int64], resolution: int, degenerate_level: float) -> tuple[int, int]:
    """Patches (of ``patch_ids``) that fold somewhere on a ``resolution²`` grid, and degenerate samples.

    With mesh vertex normals: a fold is a patch normal against the bilinear blend of the fan
    normals at its four corners. Without (patch files): a normal that turns by more than 150°
    between neighbouring grid samples: a fold reverses the normal, while a smooth patch turns
    far less over one sample step (Newell's teapot rim, the tightest curl in the shared data,
    turns 115° over 1/8 of its patch).
    """
    patches = network.patches.take(patch_ids)
    grid = np.linspace(0.0, 1.0, resolution)
    normals = _cross3(_planar(patches.evaluate_grid(grid, grid, 1, 0)), _planar(patches.evaluate_grid(grid, grid, 0, 1)))
    length = _norm3(normals)  # (N, G, G)
    usable = length > degenerate_level
    if network.vertex_normals is not None:
        n0, n1, n2, n3 = np.moveaxis(network.vertex_normals[network.corner_ids[patch_ids]], 1, 0)
        u = grid[:, None]
        v = grid[None, :]
        # the bilinear blend of the corner normals, summed term by term in place
        weights = ((1 - u) * (1 - v), u * (1 - v), u * v, (1 - u) * v)
        reference = weights[0] * _planar(n0)[:, :, None, None]
        term = np.empty_like(reference)
        for corner, weight in zip((n1, n2, n3), weights[1:], strict=True):
            reference += np.multiply(weight, _planar(corner)[:, :, None, None], out=term)
        folded = ((_dot3(normals, reference) < 0) & usable).any(axis=(1, 2))
    else:
        folded = np.zeros(len(patch_ids), dtype=bool)
        tiny = np.finfo(float).tiny
        for ahead, behind in ((np.s_[:, 1:], np.s_[:, :-1]), (np.s_[:, :, 1:], np.s_[:, :, :-1])):  # along u, along v
            cosine = _dot3(normals[(slice(None), *ahead)], normals[(slice(None), *behind)]) / np.maximum(
                length[ahead] * length[behind], tiny
            )
            folded |= ((cosine < _FOLD_COSINE) & usable[ahead] & usable[behind]).any(axis=(1, 2))
    return int(folded.sum()), int((~usable).sum())
