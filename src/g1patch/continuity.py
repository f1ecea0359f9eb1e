"""How smooth is a patch network? G0 gaps and G1 angles on every shared edge and corner.

For every interior edge shared by patches L and R the edge is sampled at K ≥ 33 parameters,
both ends included, from both sides; exact first derivatives give the normals
``n = p_u × p_v`` and the G1 angle is ``atan2(|n_L × n_R|, n_L · n_R)`` (accurate near 0, where
arccos floors at ~1e-6°). The G0 gap is ``|p_L − p_R|``, reported relative to the bounding-box
diagonal. Corners: the angle between the normals of every pair of patches meeting at a point.
Folds: a patch normal pointing against the mesh's fan normals (blended over the quad), or, for
patch files without a mesh, a normal that flips between neighbouring samples. Degenerate normals: ``|p_u × p_v| ≤ degenerate_rtol · diag²`` (collapsed edges).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .errors import InputError
from .network import PatchNetwork, edge_parameters
from .patches import CORNER_PARAMETERS

__all__ = ["ContinuityReport", "check", "angle_between"]

DEGENERATE_RTOL = 1e-13
"""|p_u × p_v| ≤ DEGENERATE_RTOL · diag² is a degenerate normal. At a collapsed edge the
derivative is a sum of equal points with weights summing to zero, ~1e-16 · diag, so the cross
product there is ~1e-16 · diag²; a real patch of a 1 M-quad mesh has |p_u × p_v| ~ 1e-6 · diag²."""


def angle_between(a: NDArray[np.float64], b: NDArray[np.float64]) -> NDArray[np.float64]:
    """Angle in degrees between vectors along the last axis: ``atan2(|a × b|, a · b)``."""
    return np.degrees(np.arctan2(np.linalg.norm(np.cross(a, b), axis=-1), np.einsum("...d,...d->...", a, b)))


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

    def summary(self) -> str:
        """A short human-readable table."""
        rows = [
            ("patches", f"{self.patches}"),
            ("shared edges", f"{self.shared_edges}  (open {self.open_edges}, collapsed {self.collapsed_edges} "
             f"= {self.collapsed_patch_edges} patch edges)"),
            ("max G1 angle on edges", f"{self.max_edge_angle_deg:.3e}°"),
            ("mean G1 angle on edges", f"{self.mean_edge_angle_deg:.3e}°"),
            ("max G1 angle at corners", f"{self.max_corner_angle_deg:.3e}°"),
            ("max G0 gap (of bbox diag)", f"{self.max_g0_gap:.3e}"),
            ("degenerate normals", f"{self.degenerate_normals}"),
            ("folds", f"{self.folds}"),
        ]
        if self.inconsistent_orientation_edges:
            rows.append(("edges with flipped orientation", f"{self.inconsistent_orientation_edges}"))
        if self.max_vertex_deviation is not None:
            rows.append(("max vertex deviation (of diag)", f"{self.max_vertex_deviation:.3e}"))
        worst = self.worst_edge
        if worst is not None:
            rows.append(
                ("worst edge", f"patch {worst['patches'][0]} edge {worst['edges'][0]} / "
                 f"patch {worst['patches'][1]} edge {worst['edges'][1]}: {worst['angle_deg']:.3e}°")
            )
        width = max(len(name) for name, _ in rows)
        return "\n".join(f"{name:<{width}}  {value}" for name, value in rows)


def check(
    network: PatchNetwork,
    samples: int = 33,
    fold_samples: int = 17,
    degenerate_rtol: float = DEGENERATE_RTOL,
) -> ContinuityReport:
    """Measure G0 and G1 continuity of ``network`` (see the module docstring for the measures)."""
    if not isinstance(samples, (int, np.integer)) or samples < 2:
        raise InputError(f"samples: expected an integer ≥ 2, got {samples!r}")
    if not isinstance(fold_samples, (int, np.integer)) or fold_samples < 2:
        raise InputError(f"fold_samples: expected an integer ≥ 2, got {fold_samples!r}")
    patches = network.patches
    diagonal = network.bounding_box_diagonal() or 1.0
    degenerate_level = degenerate_rtol * diagonal**2

    # Every patch edge sampled counter-clockwise: (N, 4, K, 3).
    t = np.linspace(0.0, 1.0, samples)
    uv = edge_parameters(np.arange(4)[:, None], t[None, :]).reshape(-1, 2)
    count = len(patches)
    points = patches.evaluate(uv).reshape(count, 4, samples, 3)
    normals = np.cross(patches.evaluate(uv, 1, 0), patches.evaluate(uv, 0, 1)).reshape(count, 4, samples, 3)
    degenerate = np.linalg.norm(normals, axis=-1) <= degenerate_level

    # Shared edges: side R is sampled in its own direction, so reverse it unless both run the same way.
    left_patch, left_edge = network.shared_edges()
    right_patch = network.neighbor[left_patch, left_edge]
    right_edge = network.neighbor_edge[left_patch, left_edge]
    same = network.same_direction[left_patch, left_edge]
    order = np.where(same[:, None], np.arange(samples), np.arange(samples)[::-1])
    right_points = points[right_patch[:, None], right_edge[:, None], order]
    right_normals = normals[right_patch[:, None], right_edge[:, None], order]
    right_normals = np.where(same[:, None, None], -right_normals, right_normals)
    left_points = points[left_patch, left_edge]
    left_normals = normals[left_patch, left_edge]
    valid = ~(degenerate[left_patch, left_edge] | degenerate[right_patch[:, None], right_edge[:, None], order])
    angles = np.where(valid, angle_between(left_normals, right_normals), 0.0)
    gaps = np.linalg.norm(left_points - right_points, axis=-1) / diagonal
    edge_angle = angles.max(axis=1) if len(angles) else np.zeros(0)
    edge_gap = gaps.max(axis=1) if len(gaps) else np.zeros(0)

    corner_angle = _max_corner_angle(network, patches, degenerate_level, oriented=not same.any())
    folds, grid_degenerate = _folds(network, fold_samples, degenerate_level)

    max_vertex_deviation = None
    if network.vertices is not None:
        corners = patches.evaluate(CORNER_PARAMETERS)
        deviation = np.linalg.norm(corners - network.vertices[network.corner_ids], axis=-1)
        max_vertex_deviation = float(deviation.max() / diagonal) if deviation.size else 0.0

    open_patch, _ = network.open_edges()
    return ContinuityReport(
        patches=count,
        shared_edges=int(len(left_patch)),
        open_edges=int(len(open_patch)),
        collapsed_edges=int(network.edge_collapsed.sum()),
        collapsed_patch_edges=int(network.edge_collapsed[network.edge_ids].sum()),
        samples_per_edge=samples,
        max_edge_angle_deg=float(edge_angle.max(initial=0.0)),
        mean_edge_angle_deg=float(edge_angle.mean()) if len(edge_angle) else 0.0,
        max_corner_angle_deg=corner_angle,
        max_g0_gap=float(edge_gap.max(initial=0.0)),
        degenerate_normals=int(degenerate.sum() + grid_degenerate),
        folds=folds,
        inconsistent_orientation_edges=int(same.sum()),
        bounding_box_diagonal=float(diagonal),
        max_vertex_deviation=max_vertex_deviation,
        edge_patches=np.stack([left_patch, right_patch], axis=1),
        edge_sides=np.stack([left_edge, right_edge], axis=1),
        edge_angle_deg=edge_angle,
        edge_gap=edge_gap,
    )


def _max_corner_angle(network: PatchNetwork, patches: Any, degenerate_level: float, oriented: bool) -> float:
    """Largest angle between the corner normals of any two patches meeting at one point.

    Corners are grouped by their point id and the groups by size, so the pairwise angles of all
    points with m corners form one (groups, m, m) array.
    """
    normals = np.cross(patches.evaluate(CORNER_PARAMETERS, 1, 0), patches.evaluate(CORNER_PARAMETERS, 0, 1))
    normals = normals.reshape(-1, 3)
    usable = np.linalg.norm(normals, axis=-1) > degenerate_level
    ids = network.corner_ids.reshape(-1)[usable]
    normals = normals[usable]
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


def _folds(network: PatchNetwork, resolution: int, degenerate_level: float) -> tuple[int, int]:
    """Patches that fold somewhere on a ``resolution²`` grid, and the interior degenerate samples.

    With mesh vertex normals: a fold is a patch normal against the bilinear blend of the fan
    normals at its four corners. Without (patch files): a normal that turns by more than 90°
    between neighbouring grid samples, i.e. the surface turns over between them.
    """
    patches = network.patches
    grid = np.linspace(0.0, 1.0, resolution)
    normals = np.cross(patches.evaluate_grid(grid, grid, 1, 0), patches.evaluate_grid(grid, grid, 0, 1))
    usable = np.linalg.norm(normals, axis=-1) > degenerate_level
    if network.vertex_normals is not None:
        n0, n1, n2, n3 = np.moveaxis(network.vertex_normals[network.corner_ids], 1, 0)
        u = grid[None, :, None, None]
        v = grid[None, None, :, None]
        reference = (
            (1 - u) * (1 - v) * n0[:, None, None] + u * (1 - v) * n1[:, None, None]
            + u * v * n2[:, None, None] + (1 - u) * v * n3[:, None, None]
        )
        against = (np.einsum("nabd,nabd->nab", normals, reference) < 0) & usable
        folded = against.any(axis=(1, 2))
    else:
        flip_u = (np.einsum("nabd,nabd->nab", normals[:, 1:], normals[:, :-1]) < 0) & usable[:, 1:] & usable[:, :-1]
        flip_v = (np.einsum("nabd,nabd->nab", normals[:, :, 1:], normals[:, :, :-1]) < 0) & usable[:, :, 1:] & usable[:, :, :-1]
        folded = flip_u.any(axis=(1, 2)) | flip_v.any(axis=(1, 2))
    interior_degenerate = ~usable[:, 1:-1, 1:-1]  # the borders are counted with the edge samples
    return int(folded.sum()), int(interior_degenerate.sum())
