"""The deviation mode: the G1 angle of every shared edge (from a report, or measured as
:func:`g1patch.continuity.check` does), its colour scale and caption, and the colours of the edge
bands."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..continuity import (
    DEGENERATE_RTOL,
    EXACT_G1_DEG,
    ContinuityReport,
    _blocks,
    _diagonal,
    _edge_measures,
    _hanging_measures,
    _local,
)
from ..network import PatchNetwork
from ..patches import CORNER_PARAMETERS
from .camera import _Camera
from .sampling import _FILLED, _Surface
from .shading import _diffuse

#: the deviation mode draws a patch's edges as bands when its opposite edges lie at least this
#: many pixels apart on the screen (a band is about 2 pixels on each side of its edge); a smaller
#: patch is filled with the colour of its worst edge
EDGE_SPACING_PX = 8.0
#: the deviation mode without a report samples each edge at 33 parameters while that makes at
#: most this many samples per pixel of the picture, fewer (down to :data:`MIN_EDGE_SAMPLES`) for
#: networks with more edges
EDGE_SAMPLES_PER_PIXEL = 4
#: the fewest samples per edge of the deviation mode without a report (the ends, the middle, the
#: quarters)
MIN_EDGE_SAMPLES = 5
#: check's samples per edge
_CHECK_SAMPLES = 33
_DEVIATION_SURFACE = np.array([0.86, 0.86, 0.86])
_OPEN_EDGE_COLOUR = np.array([0.35, 0.35, 0.35])
#: seams in the deviation mode: a green that plasma (blue, purple, orange, yellow) never reaches
_SEAM_COLOUR = np.array([0.0, 0.62, 0.42])
_SEAM_LABEL = "seam (sharp on purpose)"
_DEVIATION_CMAP = "plasma"
_CMAP_RANGE = (0.0, 0.88)  # plasma without its palest yellow, which vanishes on light grey


@dataclass(frozen=True)
class _EdgeAngles:
    """What the deviation mode needs of a :class:`ContinuityReport`: per shared edge its patches,
    sides, G1 angle and seam flag, and the caption's figures."""

    edge_patches: NDArray[np.int64]
    edge_sides: NDArray[np.int64]
    edge_angle_deg: NDArray[np.float64]
    edge_seam: NDArray[np.bool_]
    samples_per_edge: int

    @property
    def shared_edges(self) -> int:
        return len(self.edge_angle_deg)

    @property
    def seam_edges(self) -> int:
        return int(self.edge_seam.sum())

    @property
    def max_edge_angle_deg(self) -> float:
        return float(self.edge_angle_deg[~self.edge_seam].max(initial=0.0))


def _edge_angles(network: PatchNetwork, samples: int) -> _EdgeAngles:
    """The G1 angle of every shared edge as :func:`g1patch.continuity.check` measures it (the same
    function on the same blocks: equal figures at ``samples`` = 33), without check's corner, fold
    and fairness measures."""
    local = _local(network.patches)
    diagonal = _diagonal(local.evaluate(CORNER_PARAMETERS)) or 1.0
    left_patch, left_edge = network.shared_edges()
    right_patch = network.neighbor[left_patch, left_edge]
    right_edge = network.neighbor_edge[left_patch, left_edge]
    same = network.same_direction[left_patch, left_edge]
    angle = np.zeros(len(left_patch))
    seam = network.seam[left_patch, left_edge]
    level = DEGENERATE_RTOL * diagonal**2
    for block in _blocks(len(left_patch), 4096):
        left, right = (left_patch[block], left_edge[block]), (right_patch[block], right_edge[block])
        angle[block] = _edge_measures(local, *left, *right, same[block], samples, level)[0]
    hanging = network.hanging
    if hanging is not None and len(hanging):  # after the shared edges, as check orders them
        fine_patch, fine_edge, coarse_patch, coarse_edge = hanging.sides.T
        left_patch, left_edge = np.r_[left_patch, fine_patch], np.r_[left_edge, fine_edge]
        right_patch, right_edge = np.r_[right_patch, coarse_patch], np.r_[right_edge, coarse_edge]
        angle = np.r_[angle, _hanging_measures(local, hanging, samples, level)[0]]
        seam = np.r_[seam, np.zeros(len(hanging), dtype=bool)]
    return _EdgeAngles(
        np.stack([left_patch, right_patch], axis=1),
        np.stack([left_edge, right_edge], axis=1),
        angle,
        seam,
        samples,
    )


def _edge_samples(edge_counts: Sequence[int], size: tuple[int, int]) -> int:
    """Samples per edge of the deviation mode without a report: 33 while the picture's edges take
    at most :data:`EDGE_SAMPLES_PER_PIXEL` samples per pixel, fewer for more, at least
    :data:`MIN_EDGE_SAMPLES`."""
    budget = EDGE_SAMPLES_PER_PIXEL * size[0] * size[1]
    return int(np.clip(budget // max(sum(edge_counts), 1), MIN_EDGE_SAMPLES, _CHECK_SAMPLES))


@dataclass(frozen=True)
class _AngleScale:
    """How G1 angles (or distances) become colours: a matplotlib norm and colour map, shared by
    all panels; ``marks_g1``: the colour bar marks the bar for "exactly G1"."""

    norm: Any
    cmap: Any
    log: bool
    marks_g1: bool = True


def _colour_map() -> Any:
    """The deviation and distance modes' colour map: plasma without its palest yellow."""
    from matplotlib import colormaps
    from matplotlib.colors import ListedColormap

    base = colormaps[_DEVIATION_CMAP]
    return ListedColormap(base(np.linspace(*_CMAP_RANGE, 256)), name="g1patch_deviation")


def _distance_scale(high: float) -> _AngleScale:
    """Distances 0 … ``high`` (of the diagonal) on the deviation mode's colour map, linear."""
    from matplotlib.colors import Normalize

    return _AngleScale(Normalize(0.0, max(high, 1e-15), clip=True), _colour_map(), False, False)


def _angle_scale(
    angles: Sequence[NDArray[np.float64]], angle_range: tuple[float, float] | None
) -> _AngleScale:
    from matplotlib.colors import LogNorm, Normalize

    cmap = _colour_map()
    values = np.concatenate(
        [np.asarray(a, dtype=np.float64).reshape(-1) for a in angles] + [np.zeros(0)]
    )
    if angle_range is not None:
        low, high = angle_range
    else:
        # angles below the bar for "exactly G1" are rounding noise, not information: they all get
        # the bottom colour, and the scale reaches at least a decade above the bar, so an exactly
        # G1 surface is uniformly dark instead of its noise spread over the whole colour map
        high = max(float(values.max(initial=0.0)), 10.0 * EXACT_G1_DEG)
        positive = values[values > 0]
        low = max(float(positive.min()) if positive.size else 0.0, 0.1 * EXACT_G1_DEG)
    if low > 0 and high / low >= 20.0:
        return _AngleScale(LogNorm(low, high, clip=True), cmap, True)
    return _AngleScale(Normalize(0.0, high, clip=True), cmap, False)


def _deviation_caption(report: ContinuityReport | _EdgeAngles) -> str:
    """The deviation panel's figure line: the largest G1 angle on the smooth edges, and the seams
    (and the samples per edge when fewer than check's 33)."""
    smooth_edges = report.shared_edges - report.seam_edges
    caption = f"max G1 angle {report.max_edge_angle_deg:.3g}° on {smooth_edges} edges"
    if report.samples_per_edge < _CHECK_SAMPLES:
        caption += f" ({report.samples_per_edge} samples each)"
    return caption + (f", {report.seam_edges} seams" if report.seam_edges else "")


def _band_angles(
    network: PatchNetwork, report: ContinuityReport | _EdgeAngles
) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
    """G1 angle of every patch side (N, 4), NaN on open, collapsed and seam sides; and the seam
    sides (N, 4)."""
    angles = np.full((network.n_patches, 4), np.nan)
    seams = np.zeros((network.n_patches, 4), dtype=bool)
    smooth = np.where(report.edge_seam, -np.inf, report.edge_angle_deg)
    for column in (0, 1):  # a coarse side of hanging edges: its largest
        sides = report.edge_patches[:, column], report.edge_sides[:, column]
        np.fmax.at(angles, sides, smooth)
        seams[sides] = report.edge_seam
    angles[np.isinf(angles)] = np.nan
    return angles, seams


def _deviation_colours(
    surface: _Surface,
    keep: NDArray[np.bool_],
    vertex_colours: NDArray[np.float64],
    vertex_normals: NDArray[np.float64],
    camera: _Camera,
    side_angles: NDArray[np.float64],
    side_seams: NDArray[np.bool_],
    scale: _AngleScale,
) -> NDArray[np.float64]:
    """Per-corner colours (T, 3, 3): the lit grey surface, and the edge bands in one flat colour
    each, the colour of their edge's G1 angle (a corner cell lies on two sides: the larger), or
    the seam colour where a side is a seam (it wins at corner cells: seams stay unbroken lines).
    A filled patch's triangles lie on all four sides: the colour of its worst side, the seam
    colour if it has a seam side, and the grey surface if it has neither (open or collapsed
    sides)."""
    assert surface.band_patch is not None and surface.band_mask is not None
    triangles = surface.triangles[keep]
    colours = vertex_colours[triangles]
    mask = surface.band_mask[keep]
    patch = surface.band_patch[keep]
    in_band = mask > 0
    touched = (mask[in_band, None] >> np.arange(4)) & 1 == 1  # (B, 4) sides the triangle lies on
    values = np.where(touched, side_angles[patch[in_band]], np.nan)
    has_angle = np.asarray(~np.isnan(values).all(axis=1))
    angle = np.max(np.where(np.isnan(values), -np.inf, values), axis=1)[has_angle]
    # open (boundary) sides: a neutral dark line; shared sides: the colour of their angle
    band = np.tile(_OPEN_EDGE_COLOUR, (int(in_band.sum()), 1))
    mapped = np.asarray(scale.cmap(scale.norm(angle)))[:, :3]
    on_seam = (touched & side_seams[patch[in_band]]).any(axis=1)
    band[has_angle] = mapped
    band[on_seam] = _SEAM_COLOUR
    lit = has_angle | on_seam
    normal = vertex_normals[triangles[in_band][lit]].sum(axis=1)
    normal /= np.maximum(np.linalg.norm(normal, axis=-1, keepdims=True), 1e-300)
    diffuse, _ = _diffuse(normal, camera)
    band[lit] *= (0.82 + 0.18 * diffuse)[:, None]
    painted = lit | ((mask[in_band] & _FILLED) == 0)
    band_rows = np.flatnonzero(in_band)[painted]
    colours[band_rows] = band[painted][:, None, :]
    return colours
