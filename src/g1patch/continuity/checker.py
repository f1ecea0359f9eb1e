"""The check: G0 and G1 on every shared edge and corner, folds and fairness of a network, measured
by the NumPy reference or the kernels, as one :class:`~.report.ContinuityReport` (see
:mod:`g1patch.continuity`)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace

import numpy as np

from ..gregory import GregoryPatchSet
from ..network import PatchNetwork, network_of, unit_frame
from ..patches import PatchSet
from .corner_kernels import (
    _corner_extent_compiled,
    _corner_normals_compiled,
    _max_corner_angle_compiled,
)
from .edge_kernels import _edge_measures_compiled
from .edges import _edge_measures, _hanging_measures, _max_corner_angle
from .folds import _edge_fold_locations, _first_per_patch
from .grid import DEGENERATE_RTOL, FOLD_SAMPLES, _GridMeasures, _patch_block
from .jit import _kernel_form
from .report import ContinuityReport
from .sampling import (
    _blocks,
    _box,
    _check_count,
    _check_sample_memory,
    _corner_points,
    _local,
    _world_diagonal,
    _world_extent_diagonal,
)


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
    """Measure G0 and G1 continuity, folds and fairness of ``network`` (see
    :mod:`g1patch.continuity`).

    Work is done in blocks of ``chunk`` edges, and of at most ``chunk`` patches, so memory stays
    bounded on networks of millions of patches (the default keeps a block's sample arrays near
    the size of a core's L2 cache, the fastest setting measured); ``progress(done, total)`` is
    called after each block. Degenerate normals, folds and fairness share the
    ``fold_samples²`` grid of every patch. A :class:`~g1patch.patches.PatchSet` or
    :class:`~g1patch.gregory.GregoryPatchSet` is measured as the network of its matching boundary
    curves (:func:`g1patch.network.network_of`). ``compiled``: the numba kernels (:mod:`.jit`),
    all edges and all patches in one pass each (``progress`` after each); False: the NumPy
    reference; None (default): the kernels from :data:`~.jit.KERNEL_PATCHES` patches on. Frame-free
    patches far from size 1 are measured in the frame of their corners' box
    (:func:`~g1patch.network.unit_frame`).
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
    form = _kernel_form(local, compiled)
    frame = getattr(patches, "frame", None)
    vertices = None
    if network.vertices is not None:
        vertices = network.vertices if frame is None else frame.to_local(network.vertices)
    if form is None:
        corners = _corner_points(local)
        low, high = _box(corners)
        diagonal = float(np.linalg.norm(high - low)) or 1.0
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
    if local is patches and isinstance(patches, (PatchSet, GregoryPatchSet)) and len(local):
        measuring = unit_frame(low, high)  # frame-free, far from size 1 or the origin:
        if measuring is not None:  # measured in its unit box
            framed = replace(network, patches=patches.local_to(measuring).with_frame(measuring))
            return check(
                framed, samples, fold_samples, degenerate_rtol, chunk, progress, compiled=compiled
            )
    degenerate_level = degenerate_rtol * diagonal**2

    left_patch, left_edge = network.shared_edges()
    _check_sample_memory(samples, fold_samples, len(left_patch), chunk)
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
    hanging = network.hanging
    if hanging is not None and len(hanging):  # T-junctions: each fine edge against its coarse part
        measured = _hanging_measures(local, hanging, samples, degenerate_level)
        fine_patch, fine_edge, coarse_patch, coarse_edge = hanging.sides.T
        left_patch, left_edge = np.r_[left_patch, fine_patch], np.r_[left_edge, fine_edge]
        right_patch, right_edge = np.r_[right_patch, coarse_patch], np.r_[right_edge, coarse_edge]
        same = np.r_[same, np.zeros(len(hanging), dtype=bool)]
        seam = np.r_[seam, np.zeros(len(hanging), dtype=bool)]
        edge_angle, edge_angle_min, edge_worst, edge_gap = (
            np.r_[old, new]
            for old, new in zip(
                (edge_angle, edge_angle_min, edge_worst, edge_gap), measured, strict=True
            )
        )
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

    collapsed = network.edge_collapsed[network.edge_ids]  # (N, 4): a triangle's pole, …
    collapsed_patch_edges = int(np.count_nonzero(collapsed))
    degenerate = grid.zero_area  # … and patches with no area or more than one such edge
    if collapsed_patch_edges > 1:
        degenerate = degenerate | (np.count_nonzero(collapsed, axis=1) > 1)
    degenerate_ids = np.flatnonzero(degenerate)
    open_patch, _ = network.open_edges()
    smooth_angle = edge_angle[~seam]
    seam_range: tuple[float, float] | tuple[None, None] = (None, None)
    if seam.any():  # degenerate samples count as 0°, as in the maxima
        lowest = float(edge_angle_min[seam].min())
        seam_range = (lowest if np.isfinite(lowest) else 0.0, float(edge_angle[seam].max()))
    return ContinuityReport(
        patches=len(local),
        shared_edges=int(len(left_patch)),
        hanging_edges=0 if hanging is None else len(hanging),
        open_edges=int(len(open_patch)),
        collapsed_edges=int(network.edge_collapsed.sum()),
        collapsed_patch_edges=collapsed_patch_edges,
        samples_per_edge=samples,
        max_edge_angle_deg=float(smooth_angle.max(initial=0.0)),
        mean_edge_angle_deg=float(smooth_angle.mean()) if len(smooth_angle) else 0.0,
        max_corner_angle_deg=corner_angle,
        max_g0_gap=float(edge_gap.max(initial=0.0)),
        degenerate_normals=grid.degenerate,
        degenerate_patches=int(degenerate_ids.size),
        degenerate_patch_ids=tuple(int(i) for i in degenerate_ids[:10]),
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
