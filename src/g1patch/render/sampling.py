"""What to draw: how finely to sample the patches for the picture's pixels, and every patch
sampled on its own grid with its exact normals (with the deviation mode's edge bands)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ..continuity import DEGENERATE_RTOL
from ..network import Patches, PatchNetwork
from ..patches import CORNER_PARAMETERS
from .camera import _Camera

#: the surface's box on the screen (the box of its silhouette) fills this fraction of its panel's
#: width or height, whichever binds
FILL = 0.9
#: triangles per picture for :func:`choose_resolution` (a closed surface samples twice as many:
#: the half facing away is dropped before drawing); matplotlib's Agg draws about 2·10^5 triangles
#: a second. :func:`render` chooses by pixels instead (:data:`SAMPLE_SPACING_PX`)
TRIANGLE_BUDGET = 200_000
#: resolutions chosen for you lie in this range (samples per patch side)
RESOLUTION_RANGE = (2, 129)
#: a resolution chosen for you samples at most this many points per network (unless 2 per side is
#: more)
MAX_SAMPLES = 4_000_000
#: a resolution chosen for you puts a sample about every this many pixels along a patch (the
#: 90th percentile of the patches' projected sizes sets it)
SAMPLE_SPACING_PX = 3.0
#: patches whose curves :func:`_band_width` measures (evenly spaced through the network)
_BAND_WIDTH_PATCHES = 4096


def choose_resolution(
    n_patches: int, panels: int = 1, budget: int = TRIANGLE_BUDGET, closed: bool = True
) -> int:
    """Samples per patch side r so that ``panels`` pictures of ``n_patches`` draw about ``budget``
    triangles.

    ``2 (r − 1)² n_patches · panels ≤ budget`` (twice the budget for a ``closed`` surface, whose
    back half is not drawn), clamped to :data:`RESOLUTION_RANGE`. Closed, one panel: the cube
    (6 patches) gets 129, the 96-patch sphere 46, the 2928-patch Spot cow 9 samples per side.
    """
    low, high = RESOLUTION_RANGE
    cells = budget * (2.0 if closed else 1.0) / (2.0 * max(n_patches, 1) * max(panels, 1))
    return int(np.clip(math.floor(math.sqrt(cells)) + 1, low, high))


@dataclass(frozen=True)
class _Footprint:
    """How big a network's patches come out in its panel, from their corner quads: the panel's
    pixels per model unit, every patch's largest side in pixels (3-D chords, at most what a side
    can cover on the screen), and the distance in pixels between its opposite edges (the smaller
    of the two pairs) at the panel's scale in 3-D, without foreshortening: a patch seen edge-on at
    the silhouette is as far across as the same patch facing the camera. (Projected, such patches
    measured ~0 and a coarse sphere's rim filled with their colour: crescents, not edges.)"""

    pixels_per_unit: float
    side_px: NDArray[np.float64]
    spacing_px: NDArray[np.float64]


def _footprint(
    network: PatchNetwork, camera: _Camera, size: tuple[int, int], panels: int, zoom: float
) -> _Footprint:
    corners = network.patches.evaluate(CORNER_PARAMETERS)  # (N, 4, 3)
    screen, _ = camera.project(corners)  # (N, 4, 2)
    flat = screen.reshape(-1, 2)
    extent = np.maximum(flat.max(axis=0) - flat.min(axis=0), 1e-300) / FILL
    pixels_per_unit = float(zoom * min(size[0] / panels / extent[0], size[1] / extent[1]))
    side = np.linalg.norm(
        np.roll(corners, -1, axis=1) - corners, axis=-1
    )  # side k: corner k to k + 1
    # the quad's area, half the cross product of its diagonals; the sides 0, 2 run along u, 1, 3
    # along v: the distance between sides 1 and 3 is the area over their mean length, and so on
    area = 0.5 * np.linalg.norm(
        np.cross(corners[:, 2] - corners[:, 0], corners[:, 3] - corners[:, 1]), axis=-1
    )
    across_u = area / np.maximum(0.5 * (side[:, 1] + side[:, 3]), 1e-300)
    across_v = area / np.maximum(0.5 * (side[:, 0] + side[:, 2]), 1e-300)
    return _Footprint(
        pixels_per_unit,
        side.max(axis=1) * pixels_per_unit,
        np.minimum(across_u, across_v) * pixels_per_unit,
    )


def _pixel_resolution(footprint: _Footprint) -> int:
    """Samples per patch side for one sample about every :data:`SAMPLE_SPACING_PX` pixels along the
    patches (the 90th percentile of their sizes), in :data:`RESOLUTION_RANGE` and at most
    :data:`MAX_SAMPLES` points in all (but 2 per side at least)."""
    low, high = RESOLUTION_RANGE
    count = len(footprint.side_px)
    size = float(np.quantile(footprint.side_px, 0.9)) if count else 0.0
    r = int(np.clip(math.ceil(size / SAMPLE_SPACING_PX) + 1, low, high))
    return max(low, min(r, math.isqrt(MAX_SAMPLES // max(count, 1))))


def _band_width(patches: Patches, pixels_per_unit: float) -> tuple[float, float]:
    """Parameter widths (w_u, w_v) of the edge bands: about 2 pixels on each side of an edge line,
    at most a tenth of the patch (the mean length of the u- and v-curves of ``patches``, at most
    :data:`_BAND_WIDTH_PATCHES` of them evenly spaced, in pixels of the picture, sets the scale)."""
    if len(patches) > _BAND_WIDTH_PATCHES:
        patches = patches.take(
            np.linspace(0, len(patches) - 1, _BAND_WIDTH_PATCHES).round().astype(np.int64)
        )
    params = np.linspace(0.0, 1.0, 5)
    coarse = patches.evaluate_grid(params, params)
    widths = []
    for axis in (1, 2):  # the u-curves, then the v-curves
        length = float(np.linalg.norm(np.diff(coarse, axis=axis), axis=-1).sum(axis=axis).mean())
        widths.append(float(np.clip(2.0 / max(length * pixels_per_unit, 1e-9), 0.003, 0.1)))
    return widths[0], widths[1]


@dataclass(frozen=True)
class _Surface:
    """Triangles to draw: points (P, 3), unit normals (P, 3), triangles (T, 3); for the deviation
    mode, per triangle its patch and the mask of the patch sides whose band it lies in."""

    points: NDArray[np.float64]
    normals: NDArray[np.float64]
    triangles: NDArray[np.int64]
    closed: bool
    band_patch: NDArray[np.int64] | None = None
    band_mask: NDArray[np.int64] | None = None


def _grid_triangles(
    count: int, ru: int, rv: int
) -> tuple[NDArray[np.int64], NDArray[np.int64], NDArray[np.int64]]:
    """Triangles of ``count`` separate ru × rv grids (counter-clockwise about p_u × p_v), with the
    grid cell (a, b) of every triangle."""
    cells_a, cells_b = np.meshgrid(np.arange(ru - 1), np.arange(rv - 1), indexing="ij")
    a, b = cells_a.reshape(-1), cells_b.reshape(-1)
    base = (np.arange(count) * ru * rv)[:, None]
    p00, p10 = base + a * rv + b, base + (a + 1) * rv + b
    p11, p01 = p10 + 1, p00 + 1
    triangles = np.concatenate(
        [
            np.stack([p00, p10, p11], axis=-1).reshape(-1, 3),
            np.stack([p00, p11, p01], axis=-1).reshape(-1, 3),
        ]
    )
    cell_a = np.tile(np.broadcast_to(a, (count, a.size)).reshape(-1), 2)
    cell_b = np.tile(np.broadcast_to(b, (count, b.size)).reshape(-1), 2)
    return triangles, cell_a, cell_b


def _fill_degenerate(
    normals: NDArray[np.float64], usable: NDArray[np.bool_]
) -> NDArray[np.float64]:
    """Replace unusable normals on (N, ru, rv) grids by the mean of their usable grid neighbours."""
    for _ in range(3):
        if usable.all():
            break
        padded = np.pad(np.where(usable[..., None], normals, 0.0), ((0, 0), (1, 1), (1, 1), (0, 0)))
        total = sum(
            padded[:, 1 + di : padded.shape[1] - 1 + di, 1 + dj : padded.shape[2] - 1 + dj]
            for di in (-1, 0, 1)
            for dj in (-1, 0, 1)
            if di or dj
        )
        length = np.linalg.norm(total, axis=-1)
        fixed = ~usable & (length > 0)
        normals = np.where(
            fixed[..., None], total / np.where(length > 0, length, 1.0)[..., None], normals
        )
        usable = usable | fixed
    return normals


#: band mask bit of a triangle of a filled patch (deviation mode): coloured by its worst side
_FILLED = 16


def _sample(
    network: PatchNetwork,
    resolution: int,
    band: tuple[float, float] | None,
    filled: NDArray[np.bool_] | None = None,
) -> _Surface:
    """Every patch on its own grid; with ``band`` = (w_u, w_v) the first and last cells in u (in
    v) have the parameter width w_u (w_v): the bands along the patch edges that the deviation
    mode colours. ``filled`` (N,) bool, with a band: those patches are sampled on the plain grid
    instead and their triangles marked to take the colour of their worst side.

    Points of the banded patches come first (in patch order), then those of the filled ones."""
    patches = network.patches
    count = len(patches)
    closed = len(network.open_edges()[0]) == 0 and not network.same_direction.any()
    r = resolution
    plain = np.linspace(0.0, 1.0, r)
    if band is None:
        groups = [(np.arange(count), r, plain, plain, False)]
    else:
        rb = max(r, 4)
        u, v = (np.concatenate([[0.0], np.linspace(w, 1.0 - w, rb - 2), [1.0]]) for w in band)
        fill = np.zeros(count, dtype=bool) if filled is None else np.asarray(filled, dtype=bool)
        groups = [
            (np.flatnonzero(~fill), rb, u, v, False),
            (np.flatnonzero(fill), r, plain, plain, True),
        ]
    samples = []
    for ids, _, gu, gv, _ in groups:
        part = patches if len(ids) == count else patches.take(ids)
        if not len(ids):
            samples.append((np.zeros((0, len(gu), len(gv), 3)), np.zeros((0, len(gu), len(gv), 3))))
            continue
        points = part.evaluate_grid(gu, gv)
        samples.append(
            (points, np.cross(part.evaluate_grid(gu, gv, 1, 0), part.evaluate_grid(gu, gv, 0, 1)))
        )
    every = np.concatenate([points.reshape(-1, 3) for points, _ in samples])
    diagonal = float(np.linalg.norm(every.max(axis=0) - every.min(axis=0))) if len(every) else 0.0
    diagonal = diagonal or 1.0
    normal_parts, triangle_parts, patch_parts, mask_parts = [], [], [], []
    offset = 0
    for (ids, rg, _, _, is_filled), (_, normals) in zip(groups, samples, strict=True):
        length = np.linalg.norm(normals, axis=-1)
        usable = length > DEGENERATE_RTOL * diagonal**2
        normal_parts.append(
            _fill_degenerate(normals / np.where(usable, length, 1.0)[..., None], usable).reshape(
                -1, 3
            )
        )
        triangles, cell_a, cell_b = _grid_triangles(len(ids), rg, rg)
        triangle_parts.append(triangles + offset)
        offset += len(ids) * rg * rg
        if band is None:
            continue
        patch_parts.append(ids[triangles[:, 0] // (rg * rg)])
        if is_filled:  # every triangle of a filled patch takes the colour of its worst side
            mask_parts.append(np.full(len(triangles), _FILLED | 0b1111, dtype=np.int64))
        else:
            # the patch sides each triangle's cell lies on, as a 4-bit mask (0: interior):
            # bit 0 edge 0 (v = 0), bit 1 edge 1 (u = 1), bit 2 edge 2 (v = 1), bit 3 edge 3 (u = 0)
            sides = np.stack(
                [cell_b == 0, cell_a == rg - 2, cell_b == rg - 2, cell_a == 0], axis=-1
            )
            mask_parts.append((sides * (1 << np.arange(4))).sum(axis=-1).astype(np.int64))
    triangles = np.concatenate(triangle_parts)
    normals = np.concatenate(normal_parts)
    if band is None:
        return _Surface(every, normals, triangles, closed)
    return _Surface(
        every, normals, triangles, closed, np.concatenate(patch_parts), np.concatenate(mask_parts)
    )
