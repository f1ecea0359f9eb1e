"""Pictures a person can judge: shaded surfaces, zebra stripes and maps of the G1 angle.

Three modes, one camera, chosen from the surface unless asked for (:func:`auto_camera`: y-up as
in OBJ files unless the surface is a slab lying in the xy plane, seen from the front three-quarter
when it has a long horizontal axis, framed to its silhouette):

* ``shaded``: ambient light plus a key and a fill light and a soft highlight.
* ``zebra``: reflection lines. The viewer looks along ``d``; a point with unit normal n reflects
  it to ``r = d − 2 (d·n) n``, and the environment is a cylinder of black and white stripes
  around an axis c (the screen's vertical, tilted by 20° so that no cube edge is parallel to
  it). The stripe phase is ``φ = stripes · atan2(r·b, r·a)`` (a, b ⊥ c); a point is white
  where ``sin φ ≥ 0``. φ depends on the normal only, so stripes flow smoothly across a
  G1-continuous edge and jump where the normals of the two sides differ: reflection lines double
  the normal's angle, a 1° crease moves them by about ``stripes · 2° / 360°`` of a period.
* ``deviation``: the patch boundary curves, drawn as thin bands along every patch edge and
  coloured by the G1 angle of their edge (from :func:`g1patch.continuity.check`'s edge measure),
  over a light grey surface, with a colour bar in degrees (logarithmic when the angles span
  decades). Seams (edges sharp on purpose, ``network.seam``) are drawn in a colour of their own,
  outside the colour map, named in a legend; their angles do not enter the colour scale. Bands are
  drawn only where they can be told apart: a patch whose opposite edges lie less than
  :data:`EDGE_SPACING_PX` pixels apart at the picture's scale (in 3-D: a patch seen edge-on at
  the silhouette keeps its bands) is filled instead with the colour of its
  worst edge (a seam colour if one of its sides is a seam), so a network of a million patches
  becomes a map of its G1 angles instead of a moiré of bands. Without a report only the edge
  angles are measured (not check's folds and fairness), at 33 samples per edge (check's default)
  or, for networks of many edges, fewer: at most :data:`EDGE_SAMPLES_PER_PIXEL` samples per
  pixel of the picture, at least :data:`MIN_EDGE_SAMPLES` per edge (the caption says how many).

Every patch is sampled on its own grid and its normals come from its own exact derivatives
(``p_u × p_v``), so the two sides of a crease are not averaged into one normal: the picture shows
the jump the surface has, no wider and no narrower. A degenerate normal (a collapsed edge) takes
the mean of its grid neighbours.

Drawing uses an orthographic camera and the painter's algorithm on 2-D triangles: on a closed,
consistently oriented network the triangles facing away are dropped first (exact for closed
surfaces), the rest are sorted back to front and drawn by one call to Agg's Gouraud triangles
(colours given at the three corners and interpolated inside), without antialiased edges, so
neither cracks nor a wireframe show. Lighting is computed at the sample points (smooth shading);
zebra stripes are a ramp of ``sin φ`` at the points, so their edges follow the interpolated
contour instead of stepping from triangle to triangle. The sampling density follows the
pixels, not the patch count: without a resolution, every patch gets one sample about every
:data:`SAMPLE_SPACING_PX` pixels of its projected size (at least 2 per side, at most
:data:`MAX_SAMPLES` points in all), so the triangles drawn scale with the picture and a
million-patch network costs about one triangle pair per patch. The figure is an Agg
canvas of its own (no pyplot, no change to the caller's backend) saved at exactly the requested
pixel size. Every write is atomic. pyvista is not used: matplotlib alone draws every mode.

:func:`stripe_jumps` measures what the zebra picture shows: per shared edge, the largest jump of
the stripe phase across it, in stripe periods.
"""

from __future__ import annotations

import math
import os
import textwrap
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .continuity import DEGENERATE_RTOL, ContinuityReport
from .errors import InputError, MissingDependencyError, as_float_array, check_choice
from .io.atomic import atomic_path
from .network import Patches, PatchNetwork, edge_parameters
from .patches import CORNER_PARAMETERS
from .tessellate import TriangleMesh

__all__ = [
    "AUTO",
    "AUTO_AXIS_TOLERANCE_DEG",
    "AUTO_CORRELATION",
    "AUTO_ELEVATION",
    "AUTO_LONG_RATIO",
    "AUTO_SLAB_RATIO",
    "AUTO_TURN_DEG",
    "DEFAULT_STRIPES",
    "DEFAULT_VIEW",
    "EDGE_SAMPLES_PER_PIXEL",
    "EDGE_SPACING_PX",
    "EXACT_G1_DEG",
    "FILL",
    "MIN_EDGE_SAMPLES",
    "MODES",
    "SAMPLE_SPACING_PX",
    "TRIANGLE_BUDGET",
    "UP_AXES",
    "auto_camera",
    "choose_resolution",
    "render",
    "render_side_by_side",
    "render_surfaces",
    "stripe_jumps",
    "stripe_phase",
]

Mode = Literal["shaded", "zebra", "deviation"]
MODES: tuple[Mode, ...] = ("shaded", "zebra", "deviation")
#: the world axis drawn upwards: z for the shapes here and CAD data, y for most OBJ files
UP_AXES = ("z", "y", "x")

#: (elevation, azimuth) in degrees, matplotlib's convention: the camera looks at the centre from
#: azimuth ``azim`` about +z and ``elev`` above the xy plane (about the up axis, azimuth 0 along the
#: next axis: y up, from +z towards +x; x up, from +y towards +z). This one shows three cube faces;
#: :func:`auto_camera` takes it for surfaces without a front.
DEFAULT_VIEW = (25.0, -60.0)
#: the surface's box on the screen (the box of its silhouette) fills this fraction of its panel's
#: width or height, whichever binds
FILL = 0.9
#: black/white stripe pairs per full turn of the reflected direction about the stripe axis
DEFAULT_STRIPES = 12
#: triangles per picture for :func:`choose_resolution` (a closed surface samples twice as many:
#: the half facing away is dropped before drawing); matplotlib's Agg draws about 2·10^5 triangles
#: a second. :func:`render` chooses by pixels instead (:data:`SAMPLE_SPACING_PX`)
TRIANGLE_BUDGET = 200_000
#: resolutions chosen for you lie in this range (samples per patch side)
RESOLUTION_RANGE = (2, 129)
# : a resolution chosen for you samples at most this many points per network (unless 2 per side is
# more)
MAX_SAMPLES = 4_000_000
#: a resolution chosen for you puts a sample about every this many pixels along a patch (the
#: 90th percentile of the patches' projected sizes sets it)
SAMPLE_SPACING_PX = 3.0
#: the deviation mode draws a patch's edges as bands when its opposite edges lie at least this
#: many pixels apart on the screen (a band is about 2 pixels on each side of its edge); a smaller
#: patch is filled with the colour of its worst edge
EDGE_SPACING_PX = 8.0
#: the deviation mode without a report samples each edge at 33 parameters while that makes at
#: most this many samples per pixel of the picture, fewer (down to :data:`MIN_EDGE_SAMPLES`) for
#: networks with more edges
EDGE_SAMPLES_PER_PIXEL = 4
# : the fewest samples per edge of the deviation mode without a report (the ends, the middle, the
# quarters)
MIN_EDGE_SAMPLES = 5
#: check's samples per edge
_CHECK_SAMPLES = 33
#: patches whose curves :func:`_band_width` measures (evenly spaced through the network)
_BAND_WIDTH_PATCHES = 4096
#: the project's bar for "exactly G1", degrees (marked on the colour bar of the deviation mode)
EXACT_G1_DEG = 1e-9
#: tilt of the stripe axis from the screen's vertical, degrees
STRIPE_TILT_DEG = 20.0

_DPI = 100
_SIZE_RANGE = (32, 8192)
_BACKGROUND = (1.0, 1.0, 1.0)
_SURFACE_COLOUR = np.array([0.60, 0.72, 0.88])
_DEVIATION_SURFACE = np.array([0.86, 0.86, 0.86])
_OPEN_EDGE_COLOUR = np.array([0.35, 0.35, 0.35])
#: seams in the deviation mode: a green that plasma (blue, purple, orange, yellow) never reaches
_SEAM_COLOUR = np.array([0.0, 0.62, 0.42])
_SEAM_LABEL = "seam (sharp on purpose)"
_STRIPE_DARK = 0.05
_DEVIATION_CMAP = "plasma"
_CMAP_RANGE = (0.0, 0.88)  # plasma without its palest yellow, which vanishes on light grey


# --------------------------------------------------------------------------- camera and stripes
@dataclass(frozen=True)
class _Camera:
    """Orthographic camera: ``eye`` points from the scene towards the viewer; ``right``, ``up`` span
    the screen."""

    eye: NDArray[np.float64]
    right: NDArray[np.float64]
    up: NDArray[np.float64]

    @classmethod
    def from_view(cls, view: tuple[float, float], up: str = "z") -> _Camera:
        """The camera of ``view`` = (elevation, azimuth) about the world axis ``up``."""
        elev, azim = np.radians(view[0]), np.radians(view[1])
        eye = np.array([np.cos(elev) * np.cos(azim), np.cos(elev) * np.sin(azim), np.sin(elev)])
        right = np.array([-np.sin(azim), np.cos(azim), 0.0])
        # a cyclic permutation of the axes (a rotation) takes the z-up frame's (a, b, c) to the
        # world's (b, c, a) when y is up and to (c, a, b) when x is up
        shift = {"z": 0, "y": 1, "x": 2}[up]
        eye, right = np.roll(eye, -shift), np.roll(right, -shift)
        return cls(eye, right, np.cross(eye, right))

    def project(
        self, points: NDArray[np.float64]
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Screen coordinates (…, 2) and depth (…,) (larger = nearer the viewer)."""
        return np.stack([points @ self.right, points @ self.up], axis=-1), points @ self.eye

    def stripe_frame(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """The vectors a, b spanning the plane ⊥ the stripe axis: a = eye, b = axis × eye."""
        tilt = np.radians(STRIPE_TILT_DEG)
        axis = np.cos(tilt) * self.up + np.sin(tilt) * self.right
        return self.eye, np.cross(axis, self.eye)


def stripe_phase(
    normals: NDArray[np.float64],
    view: tuple[float, float] = DEFAULT_VIEW,
    stripes: int = DEFAULT_STRIPES,
    up: str = "z",
) -> NDArray[np.float64]:
    """Zebra stripe phase φ (radians) at unit ``normals`` (…, 3); white where ``sin φ ≥ 0``.

    ``r = d − 2 (d·n) n`` with d the viewing direction of ``view``; ``φ = stripes · atan2(r·b,
    r·a)`` about the stripe axis (see the module docstring). A function of the normal alone.
    """
    view, stripes, up = (
        _check_view(view, auto=False),
        _check_stripes(stripes),
        check_choice("up", up, UP_AXES),
    )
    camera = _Camera.from_view(view, up)  # type: ignore[arg-type]
    return _phase(np.asarray(normals, dtype=np.float64), camera, stripes)


def _phase(normals: NDArray[np.float64], camera: _Camera, stripes: int) -> NDArray[np.float64]:
    d = -camera.eye
    reflected = d - 2.0 * (normals @ d)[..., None] * normals
    a, b = camera.stripe_frame()
    return stripes * np.arctan2(reflected @ b, reflected @ a)


# --------------------------------------------------------------------------- the automatic camera
#: ``up`` / ``view`` value asking :func:`render` to choose from the data (:func:`auto_camera`)
AUTO = "auto"
#: z is up when the surface's spread along its thinnest principal axis is at most this fraction of
#: the next one's (a slab: the teapot's is 0.86, a flat torus 0.24, the cube 1)
AUTO_SLAB_RATIO = 0.9
#: a principal axis "is" a coordinate axis when they are at most this many degrees apart
AUTO_AXIS_TOLERANCE_DEG = 25.0
# : the horizontal footprint has a long axis when its shorter spread is at most this fraction of its
# longer
AUTO_LONG_RATIO = 0.9
# : height and position along the long axis are uncorrelated below this correlation (the front is
# then +axis)
AUTO_CORRELATION = 0.05
#: the camera's elevation in degrees: the first for a surface as tall as it is wide, rising to the
#: second for a flat one (so that a flat surface is not seen edge-on)
AUTO_ELEVATION = (25.0, 45.0)
# : front three-quarter: the camera is turned this many degrees from the front towards the model's
# left
AUTO_TURN_DEG = 35.0
#: patches sampled by :func:`auto_camera` on a network (evenly spaced through it), 4 × 4 points each
_AUTO_PATCHES = 65_536
_AUTO_GRID = 4


def _area_samples(
    surface: PatchNetwork | TriangleMesh,
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Points (N, 3) on ``surface`` and the area each stands for (N,): a network's patches at the
    midpoints of a 4 × 4 grid of cells, weighted by ``|p_u × p_v|`` (at most :data:`_AUTO_PATCHES`
    patches, evenly spaced), a triangle mesh's triangle centroids weighted by their areas."""
    if isinstance(surface, TriangleMesh):
        corners = np.asarray(surface.points, dtype=np.float64)[
            np.asarray(surface.triangles, dtype=np.int64)
        ]
        area = 0.5 * np.linalg.norm(
            np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]), axis=-1
        )
        return corners.mean(axis=1), area
    patches = surface.patches
    if len(patches) > _AUTO_PATCHES:
        patches = patches.take(
            np.linspace(0, len(patches) - 1, _AUTO_PATCHES).round().astype(np.int64)
        )
    t = (np.arange(_AUTO_GRID) + 0.5) / _AUTO_GRID
    area = np.linalg.norm(
        np.cross(patches.evaluate_grid(t, t, 1, 0), patches.evaluate_grid(t, t, 0, 1)), axis=-1
    )
    return patches.evaluate_grid(t, t).reshape(-1, 3), area.reshape(-1)


def auto_camera(
    surface: PatchNetwork | TriangleMesh | ArrayLike,
    weights: ArrayLike | None = None,
    *,
    up: str = AUTO,
) -> tuple[str, tuple[float, float]]:
    """The up axis and ``(elevation, azimuth)`` that :func:`render` uses for ``up`` / ``view`` =
    ``"auto"``.

    ``surface``: a :class:`~g1patch.network.PatchNetwork` or a
    :class:`~g1patch.tessellate.TriangleMesh` (sampled for you, area-weighted), or points (N, 3)
    on the surface with the area each stands for in ``weights`` (N,) (equal when None). ``up``: an
    axis to keep (``"x"``, ``"y"``, ``"z"``), or ``"auto"`` to choose it. The view is in the
    convention of :func:`render`'s ``view`` about that axis.

    The rule, on the weighted mean and covariance of the samples, whose principal axes have
    spreads (standard deviations) σ₀ ≤ σ₁ ≤ σ₂:

    * **up** is **z** when the surface is a slab lying in the xy plane: its thinnest principal
      axis is within :data:`AUTO_AXIS_TOLERANCE_DEG` of z, σ₀ ≤ :data:`AUTO_SLAB_RATIO` σ₁, and it
      has no long axis along y (σ₁ ≤ :data:`AUTO_LONG_RATIO` σ₂ with the longest axis within the
      tolerance of y: a tall thing thin from front to back stands in y). CAD data and the
      Utah teapot (spread 0.86 of the next along z) are like that. Otherwise **y**, the convention
      of OBJ (and glTF, Maya, Blender's OBJ export): the Spot cow (thinnest along x, its width) is
      y-up. x is never chosen: pass ``up="x"``.
    * **view**: elevation ``25° + 20° · (1 − min(1, σ_up / σ_wide))`` above the horizontal plane
      (:data:`AUTO_ELEVATION`; σ_up the spread along the up axis, σ_wide the footprint's longer
      principal spread): 25° for Spot and the cube, 32° for the teapot, 45° for a flat sheet.
      Azimuth: when the footprint (the samples projected on the horizontal plane) has a long axis
      (its shorter principal spread at most :data:`AUTO_LONG_RATIO` of its longer), the front is
      the end of the long axis where the surface stands higher (the end towards which height and
      position along the axis correlate: an animal holds its head up; the axis's + end when the
      correlation is below :data:`AUTO_CORRELATION` in size), and the camera looks from
      :data:`AUTO_TURN_DEG` off the front towards the model's left (front three-quarter: the
      front points to the left of the picture). A footprint without a long axis (the cube, a sphere,
      a flat torus) has no front: the azimuth of :data:`DEFAULT_VIEW`.

    A heuristic on the shape alone, right on the shared Spot and teapot and on the generated
    shapes; it misreads e.g. a z-up animal (thin along x, so taken as y-up: it lies on its side), a
    square y-up relief (thin along z: taken as a z-up slab) and a car whose rear stands higher
    than its bonnet (seen from behind). Pass ``up`` / ``view`` for those.
    """
    up = check_choice("up", up, (AUTO, *UP_AXES))
    if isinstance(surface, (PatchNetwork, TriangleMesh)):
        if weights is not None:
            raise InputError(
                "weights: a network or mesh is weighted by its own area; pass weights with points "
                "only"
            )
        points, area = _area_samples(surface)
    else:
        points = as_float_array("points", surface, (3,))
        if points.ndim != 2:
            raise InputError(f"points: expected an (N, 3) array, got shape {points.shape}")
        area = (
            np.ones(len(points))
            if weights is None
            else as_float_array("weights", weights, (len(points),))
        )
        if area.shape != (len(points),) or (area < 0).any():
            raise InputError(
                f"weights: expected {len(points)} non-negative areas, got shape {area.shape}"
            )
    total = float(area.sum())
    mean = area @ points / max(total, 1e-300)
    offset = points - mean
    covariance = (offset * area[:, None]).T @ offset / max(total, 1e-300)
    if not np.trace(covariance) > 0.0:  # no area, or all in one point: nothing to choose by
        return ("y" if up == AUTO else up), DEFAULT_VIEW
    spread2, axes = np.linalg.eigh(covariance)  # ascending
    cos_tol = math.cos(math.radians(AUTO_AXIS_TOLERANCE_DEG))
    if up == AUTO:
        slab = spread2[0] <= AUTO_SLAB_RATIO**2 * spread2[1] and abs(axes[2, 0]) >= cos_tol
        standing = spread2[1] <= AUTO_LONG_RATIO**2 * spread2[2] and abs(axes[1, 2]) >= cos_tol
        up = "z" if slab and not standing else "y"
    k = {"x": 0, "y": 1, "z": 2}[up]
    first, second = (k + 1) % 3, (k + 2) % 3  # the horizontal axes azimuth 0° and 90° point along
    flat = covariance[np.ix_([first, second], [first, second])]
    spread2, axes = np.linalg.eigh(flat)
    low, high = AUTO_ELEVATION
    flatness = 1.0 - min(1.0, math.sqrt(covariance[k, k] / spread2[1])) if spread2[1] > 0.0 else 0.0
    elevation = low + (high - low) * flatness
    if spread2[0] > AUTO_LONG_RATIO**2 * spread2[1]:
        return up, (elevation, DEFAULT_VIEW[1])
    front = axes[:, 1] * np.sign(
        axes[np.argmax(np.abs(axes[:, 1])), 1]
    )  # +axis unless the data says otherwise
    height = (
        covariance[k, [first, second]] @ front
    )  # covariance of height and position along the long axis
    if height < -AUTO_CORRELATION * math.sqrt(
        covariance[k, k] * spread2[1]
    ):  # the front stands higher
        front = -front
    turn = math.radians(AUTO_TURN_DEG)
    left = np.array([-front[1], front[0]])  # up × front in the horizontal frame (first, second)
    eye = math.cos(turn) * front + math.sin(turn) * left
    return up, (elevation, math.degrees(math.atan2(eye[1], eye[0])))


def _camera(
    view: tuple[float, float] | str, up: str, surfaces: Sequence[PatchNetwork | TriangleMesh]
) -> _Camera:
    """The camera of checked ``view`` and ``up``; ``"auto"`` in either: :func:`auto_camera` of all
    ``surfaces`` together (one camera for side-by-side panels)."""
    if view != AUTO and up != AUTO:
        return _Camera.from_view(view, up)  # type: ignore[arg-type]
    samples = [_area_samples(surface) for surface in surfaces]
    chosen_up, chosen_view = auto_camera(
        np.concatenate([p for p, _ in samples]), np.concatenate([w for _, w in samples]), up=up
    )
    return _Camera.from_view(chosen_view if view == AUTO else view, chosen_up)  # type: ignore[arg-type]


def stripe_jumps(
    network: PatchNetwork,
    *,
    view: tuple[float, float] | str = AUTO,
    stripes: int = DEFAULT_STRIPES,
    samples: int = 33,
    up: str = AUTO,
) -> NDArray[np.float64]:
    """Per shared edge, the largest jump of the zebra stripe phase across it, in stripe periods.

    Edges in the order of :meth:`PatchNetwork.shared_edges` (the order of a ContinuityReport's
    edge arrays). Both sides are sampled at ``samples`` parameters (ends included) with their
    exact normals, as :func:`g1patch.continuity.check` does; the difference of the reflected
    directions' angle about the stripe axis (wrapped to (−π, π]) times ``stripes`` / 2π is the
    jump. 0 on an exactly G1 edge (up to rounding); about ``stripes · 2 θ / 360°`` on a crease of
    θ degrees whose normals turn about the stripe axis. Degenerate normals are left out. The camera
    is :func:`render`'s: ``view`` and ``up`` ``"auto"`` choose it as the picture does
    (:func:`auto_camera`).
    """
    _check_network(network)
    view, stripes, up = (
        _check_view(view),
        _check_stripes(stripes),
        check_choice("up", up, (AUTO, *UP_AXES)),
    )
    if not isinstance(samples, (int, np.integer)) or isinstance(samples, bool) or samples < 2:
        raise InputError(f"samples: expected an integer ≥ 2, got {samples!r}")
    camera = _camera(view, up, [network])
    patches = network.patches
    count = len(patches)
    t = np.linspace(0.0, 1.0, int(samples))
    uv = edge_parameters(np.arange(4)[:, None], t[None, :]).reshape(-1, 2)
    normals = np.cross(patches.evaluate(uv, 1, 0), patches.evaluate(uv, 0, 1)).reshape(
        count, 4, samples, 3
    )
    length = np.linalg.norm(normals, axis=-1)
    diagonal = network.bounding_box_diagonal() or 1.0
    usable = length > DEGENERATE_RTOL * diagonal**2
    normals = normals / np.where(usable, length, 1.0)[..., None]

    left_patch, left_edge = network.shared_edges()
    right_patch = network.neighbor[left_patch, left_edge]
    right_edge = network.neighbor_edge[left_patch, left_edge]
    same = network.same_direction[left_patch, left_edge]
    order = np.where(same[:, None], np.arange(samples), np.arange(samples)[::-1])
    left = normals[left_patch, left_edge]
    right = normals[right_patch[:, None], right_edge[:, None], order]
    right = np.where(same[:, None, None], -right, right)
    valid = usable[left_patch, left_edge] & usable[right_patch[:, None], right_edge[:, None], order]
    difference = (_phase(left, camera, 1) - _phase(right, camera, 1) + np.pi) % (
        2.0 * np.pi
    ) - np.pi
    jumps = np.where(valid, np.abs(difference) * stripes / (2.0 * np.pi), 0.0)
    return jumps.max(axis=1) if len(jumps) else np.zeros(0)


# --------------------------------------------------------------------------- argument checks
def _check_network(network: object) -> PatchNetwork:
    if not isinstance(network, PatchNetwork):
        raise InputError(f"network: expected a PatchNetwork, got {type(network).__name__}")
    if network.n_patches == 0:
        raise InputError("network: has no patches; there is nothing to draw")
    return network


def _check_size(size: Any) -> tuple[int, int]:
    low, high = _SIZE_RANGE
    try:
        width, height = size
    except (TypeError, ValueError):
        raise InputError(f"size: expected (width, height) in pixels, got {size!r}") from None
    for value in (width, height):
        if (
            isinstance(value, bool)
            or not isinstance(value, (int, np.integer))
            or not low <= value <= high
        ):
            raise InputError(
                f"size: expected two integers from {low} to {high} pixels, got {size!r}"
            )
    return int(width), int(height)


def _check_view(view: Any, auto: bool = True) -> tuple[float, float] | str:
    if isinstance(view, str):
        if auto and view == AUTO:
            return AUTO
        raise InputError(
            f"view: expected (elevation, azimuth) in degrees{' or auto' if auto else ''}, got "
            f"{view!r}"
        )
    try:
        elev, azim = (float(x) for x in view)
    except (TypeError, ValueError):
        raise InputError(
            f"view: expected (elevation, azimuth) in degrees{' or auto' if auto else ''}, got "
            f"{view!r}"
        ) from None
    if not (math.isfinite(elev) and math.isfinite(azim)):
        raise InputError(f"view: expected finite angles, got {view!r}")
    if abs(elev) >= 90.0:
        raise InputError(
            f"view: elevation must lie strictly between -90 and 90 degrees, got {elev}"
        )
    return elev, azim


def _check_stripes(stripes: object) -> int:
    if (
        isinstance(stripes, bool)
        or not isinstance(stripes, (int, np.integer))
        or not 1 <= stripes <= 1000
    ):
        raise InputError(f"stripes: expected an integer from 1 to 1000, got {stripes!r}")
    return int(stripes)


def _check_resolution(resolution: object) -> int | None:
    if resolution is None:
        return None
    if (
        isinstance(resolution, bool)
        or not isinstance(resolution, (int, np.integer))
        or not 2 <= resolution <= 1025
    ):
        raise InputError(
            f"resolution: expected None or an integer from 2 to 1025, got {resolution!r}"
        )
    return int(resolution)


def _check_title(name: str, title: object) -> str | None:
    if title is not None and not isinstance(title, str):
        raise InputError(f"{name}: expected a string, got {type(title).__name__}")
    return title


def _check_path(path: object) -> Path:
    if not isinstance(path, (str, os.PathLike)):
        raise InputError(f"path: expected a file name, got {type(path).__name__}")
    target = Path(path)
    if target.suffix.lower() != ".png":
        raise InputError(
            "path: pictures are written as PNG; expected a name ending in .png, got "
            f"{str(target)!r}"
        )
    return target


def _check_report(
    report: object, network: PatchNetwork, name: str = "report"
) -> ContinuityReport | None:
    if report is None:
        return None
    if not isinstance(report, ContinuityReport):
        raise InputError(
            f"{name}: expected a ContinuityReport or None, got {type(report).__name__}"
        )
    if report.patches != network.n_patches or (
        report.edge_patches.size and int(report.edge_patches.max()) >= network.n_patches
    ):
        raise InputError(
            f"{name}: was made for {report.patches} patches, the network has {network.n_patches}"
        )
    return report


def _check_zoom(zoom: Any) -> float:
    if (
        isinstance(zoom, bool)
        or not isinstance(zoom, (int, float, np.integer, np.floating))
        or not 0.1 <= zoom <= 1000.0
    ):
        raise InputError(f"zoom: expected a number from 0.1 to 1000, got {zoom!r}")
    return float(zoom)


def _check_angle_range(angle_range: Any) -> tuple[float, float] | None:
    if angle_range is None:
        return None
    try:
        low, high = (float(x) for x in angle_range)
    except (TypeError, ValueError):
        raise InputError(
            f"angle_range: expected (low, high) in degrees, got {angle_range!r}"
        ) from None
    if not (math.isfinite(low) and math.isfinite(high) and 0.0 <= low < high):
        raise InputError(f"angle_range: expected 0 ≤ low < high, finite, got {angle_range!r}")
    return low, high


def _matplotlib() -> Any:
    try:
        import matplotlib  # noqa: F401
        from matplotlib.figure import Figure
    except ImportError:
        raise MissingDependencyError("matplotlib", "viz", "rendering pictures") from None
    return Figure


# --------------------------------------------------------------------------- sampling
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
    for (ids, rg, _, _, is_filled), (points, normals) in zip(groups, samples):
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


# --------------------------------------------------------------------------- colours
def _lights(
    camera: _Camera,
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Key light (upper left, in front), fill light (right), and the highlight's half vector."""
    key = -0.45 * camera.right + 0.60 * camera.up + 0.66 * camera.eye
    fill = 0.70 * camera.right - 0.15 * camera.up + 0.70 * camera.eye
    key, fill = key / np.linalg.norm(key), fill / np.linalg.norm(fill)
    half = key + camera.eye
    return key, fill, half / np.linalg.norm(half)


def _diffuse(
    normals: NDArray[np.float64], camera: _Camera
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Diffuse light in [0, 1] (ambient + key + fill) and the highlight, for normals facing the
    viewer."""
    key, fill, half = _lights(camera)
    diffuse = (
        0.42 + 0.48 * np.clip(normals @ key, 0.0, 1.0) + 0.18 * np.clip(normals @ fill, 0.0, 1.0)
    )
    highlight = np.clip(normals @ half, 0.0, 1.0) ** 40
    return np.clip(diffuse, 0.0, 1.0), highlight


def _shaded_colours(
    normals: NDArray[np.float64], camera: _Camera, base: NDArray[np.float64], gloss: float
) -> NDArray[np.float64]:
    """RGB (…, 3) of ``base`` lit at unit ``normals`` (…, 3) that face the viewer."""
    diffuse, highlight = _diffuse(normals, camera)
    rgb = diffuse[..., None] * base + gloss * highlight[..., None]
    return np.clip(rgb, 0.0, 1.0)


def _zebra_values(phase: NDArray[np.float64], triangles: NDArray[np.int64]) -> NDArray[np.float64]:
    """Whiteness in [0, 1] of the stripes at every point, from its phase (P,).

    The step ``sin φ ≥ 0`` is softened to a ramp about one triangle wide (``sin φ / s`` clipped,
    s the phase change across the point's triangles), so that the linear colour interpolation
    inside the triangles draws a sharp, antialiased stripe edge along the interpolated contour.
    Where the stripes are finer than the triangles (near the poles of the stripe axis) the
    stripes fade to grey instead of aliasing into moiré.
    """
    corner = phase[triangles]
    corner = (
        corner[:, :1] + (corner - corner[:, :1] + np.pi) % (2.0 * np.pi) - np.pi
    )  # unwrapped about corner 0
    spread = np.zeros(len(phase))
    np.maximum.at(
        spread, triangles.reshape(-1), np.repeat(corner.max(axis=1) - corner.min(axis=1), 3)
    )
    softness = np.clip(0.5 * spread, 0.02, 1.0)
    value = np.clip(0.5 + 0.5 * np.sin(phase) / softness, 0.0, 1.0)
    blur = np.clip((spread - 0.5 * np.pi) / np.pi, 0.0, 1.0)
    return (1.0 - blur) * value + 0.5 * blur


@dataclass(frozen=True)
class _AngleScale:
    """How G1 angles become colours: a matplotlib norm and colour map, shared by all panels."""

    norm: Any
    cmap: Any
    log: bool


def _angle_scale(
    angles: Sequence[NDArray[np.float64]], angle_range: tuple[float, float] | None
) -> _AngleScale:
    from matplotlib import colormaps
    from matplotlib.colors import ListedColormap, LogNorm, Normalize

    base = colormaps[_DEVIATION_CMAP]
    cmap = ListedColormap(base(np.linspace(*_CMAP_RANGE, 256)), name="g1patch_deviation")
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
    for column in (0, 1):
        sides = report.edge_patches[:, column], report.edge_sides[:, column]
        angles[sides] = np.where(report.edge_seam, np.nan, report.edge_angle_deg)
        seams[sides] = report.edge_seam
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


# --------------------------------------------------------------------------- drawing
@dataclass(frozen=True)
class _Panel:
    """One picture's worth of 2-D triangles, back to front, with their colours."""

    polygons: NDArray[np.float64]  # (T, 3, 2)
    colours: NDArray[np.float64]  # (T, 3 corners, 3), interpolated linearly inside each triangle
    centre: NDArray[np.float64]  # (2,) screen point at the middle of the picture
    extent: NDArray[np.float64]  # (2,) screen width and height that must fit into the picture
    title: str | None


def _visible(
    surface: _Surface, camera: _Camera
) -> tuple[NDArray[np.bool_], NDArray[np.float64], NDArray[np.float64]]:
    """Which triangles to draw, their screen corners (T, 3, 2) and depths (T,)."""
    screen, depth = camera.project(surface.points)
    corners = screen[surface.triangles]
    edge1, edge2 = corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]
    area = edge1[:, 0] * edge2[:, 1] - edge1[:, 1] * edge2[:, 0]
    keep = area != 0.0
    if surface.closed:
        p = surface.points[surface.triangles]
        volume = float(np.einsum("td,td->", p[:, 0], np.cross(p[:, 1], p[:, 2])))
        keep &= area * np.sign(volume or 1.0) > 0.0
    return keep, corners, depth[surface.triangles].mean(axis=1)


def _facing(normals: NDArray[np.float64], camera: _Camera) -> NDArray[np.float64]:
    """Normals turned towards the viewer (two-sided lighting for open or mixed-orientation
    surfaces)."""
    return normals * np.where(normals @ camera.eye < 0.0, -1.0, 1.0)[..., None]


def _panel(
    surface: _Surface,
    camera: _Camera,
    mode: Mode,
    title: str | None,
    *,
    stripes: int = DEFAULT_STRIPES,
    sides: tuple[NDArray[np.float64], NDArray[np.bool_]] | None = None,
    scale: _AngleScale | None = None,
    zoom: float = 1.0,
    target: NDArray[np.float64] | None = None,
) -> _Panel:
    """Colour every point of ``surface`` for ``mode`` and sort the visible triangles back to front.
    ``sides``: the deviation mode's G1 angle and seam flag of every patch side
    (:func:`_band_angles`).

    The picture shows the whole surface (its screen box filling :data:`FILL` of the panel's width
    or height, whichever binds) magnified ``zoom`` times about the
    point ``target`` (default: the middle of the surface's screen box)."""
    keep, corners, depth = _visible(surface, camera)
    facing = _facing(surface.normals, camera)
    if mode == "shaded":
        colours = _shaded_colours(facing, camera, _SURFACE_COLOUR, 0.22)[surface.triangles[keep]]
    elif mode == "zebra":
        # r = d − 2 (d·n) n is the same for n and −n: no orientation needed
        white = _zebra_values(_phase(surface.normals, camera, stripes), surface.triangles[keep])
        diffuse, _ = _diffuse(facing, camera)
        light = 0.62 + 0.38 * diffuse
        value = _STRIPE_DARK + white * (light - _STRIPE_DARK)
        colours = np.repeat(value[:, None], 3, axis=1)[surface.triangles[keep]]
    else:
        assert sides is not None and scale is not None
        grey = _shaded_colours(facing, camera, _DEVIATION_SURFACE, 0.08)
        colours = _deviation_colours(surface, keep, grey, facing, camera, *sides, scale)
    order = np.argsort(depth[keep], kind="stable")
    screen, _ = camera.project(surface.points)
    lower, upper = screen.min(axis=0), screen.max(axis=0)
    centre = (lower + upper) / 2.0 if target is None else camera.project(target)[0]
    extent = np.maximum(upper - lower, 1e-12) / (FILL * zoom)
    return _Panel(corners[keep][order], colours[order], centre, extent, title)


def _draw(
    path: Path,
    panels: Sequence[_Panel],
    size: tuple[int, int],
    scale: _AngleScale | None = None,
    colorbar_label: str = "",
    legend: Sequence[tuple[str, NDArray[np.float64]]] = (),
) -> None:
    """Lay the panels out side by side (with a colour bar at the right when ``scale``, and the
    ``legend`` entries (label, colour) in a band of their own below) and write the PNG."""
    Figure = _matplotlib()

    width, height = size
    figure = Figure(figsize=(width / _DPI, height / _DPI), dpi=_DPI, facecolor=_BACKGROUND)
    bar_width = 0.0 if scale is None else min(0.22, 120.0 / width)
    panel_width = (1.0 - bar_width) / len(panels)
    title_size = float(np.clip(min(height, width * panel_width) / 30.0, 6.0, 15.0))
    # a glyph is about 0.6 of the font size wide: the font shrinks (to 6 pt) until the longest
    # line fits its panel, and lines still too long are wrapped
    longest = max(
        (len(line) for p in panels if p.title for line in p.title.splitlines()), default=0
    )
    if longest:
        title_size = max(
            6.0, min(title_size, 0.95 * width * panel_width / (0.6 * longest) * 72.0 / _DPI)
        )
    fits = max(8, int(0.95 * width * panel_width / (0.6 * title_size * _DPI / 72.0)))
    titles = [
        "\n".join(textwrap.fill(line, fits) for line in p.title.splitlines()) if p.title else None
        for p in panels
    ]
    lines = max((t.count("\n") + 1 for t in titles if t), default=0)
    title_band = (
        min(0.4, (0.9 + 1.3 * lines) * title_size * (_DPI / 72.0) / height) if lines else 0.0
    )
    legend_size = max(6.0, title_size * 0.8)
    legend_band = min(0.2, 2.2 * legend_size * (_DPI / 72.0) / height) if legend else 0.0
    for column, panel in enumerate(panels):
        axes = figure.add_axes(
            (column * panel_width, legend_band, panel_width, 1.0 - title_band - legend_band)
        )
        axes.set_axis_off()
        box_w, box_h = width * panel_width, height * (1.0 - title_band - legend_band)
        units_per_pixel = max(panel.extent[0] / box_w, panel.extent[1] / box_h)
        half = units_per_pixel * np.array([box_w, box_h]) / 2.0
        low, high = panel.centre - half, panel.centre + half
        axes.set_xlim(low[0], high[0])
        axes.set_ylim(low[1], high[1])
        # triangles wholly outside the picture (zoomed in) are not drawn
        inside = ((panel.polygons.max(axis=1) >= low) & (panel.polygons.min(axis=1) <= high)).all(
            axis=1
        )
        axes.add_artist(_gouraud_artist(panel.polygons[inside], panel.colours[inside]))
        if titles[column]:
            figure.text(
                (column + 0.5) * panel_width,
                1.0 - 0.5 * title_band,
                titles[column],
                ha="center",
                va="center",
                fontsize=title_size,
                color="0.15",
                linespacing=1.3,
            )
    if scale is not None:
        from matplotlib.cm import ScalarMappable

        bar = figure.add_axes((1.0 - 0.78 * bar_width, 0.1, 0.14 * bar_width, 0.8 - title_band))
        colorbar = figure.colorbar(ScalarMappable(norm=scale.norm, cmap=scale.cmap), cax=bar)
        colorbar.set_label(colorbar_label, fontsize=max(6.0, title_size * 0.8))
        bar.tick_params(labelsize=max(6.0, title_size * 0.7))
        if scale.norm.vmin < EXACT_G1_DEG < scale.norm.vmax:  # the project's bar for "exactly G1"
            bar.axhline(EXACT_G1_DEG, color="white", linewidth=1.2)
            bar.text(
                -0.25,
                EXACT_G1_DEG,
                "exact\nG1",
                transform=bar.get_yaxis_transform(),
                ha="right",
                va="center",
                fontsize=max(5.0, title_size * 0.6),
                color="0.25",
            )
    if legend:
        from matplotlib.patches import Patch

        figure.legend(
            handles=[Patch(facecolor=colour, label=text) for text, colour in legend],
            loc="lower left",
            frameon=False,
            fontsize=legend_size,
            ncols=len(legend),
        )
    with atomic_path(path) as temporary:
        figure.savefig(temporary, format="png", dpi=_DPI, facecolor=_BACKGROUND)


def _gouraud_artist(polygons: NDArray[np.float64], colours: NDArray[np.float64]) -> Any:
    """An artist drawing triangles in the given order (painter's algorithm) with colours
    interpolated linearly from their corners: Agg's Gouraud triangles, one C++ call for all of
    them, without antialiased edges, so neither cracks nor a wireframe show."""
    from matplotlib.artist import Artist

    rgba = np.concatenate([colours, np.ones(colours.shape[:2] + (1,))], axis=-1)

    class GouraudTriangles(Artist):
        def draw(self, renderer: Any) -> None:
            if not self.get_visible() or not len(polygons) or self.axes is None:
                return
            gc = renderer.new_gc()
            gc.set_antialiased(False)
            gc.set_clip_rectangle(self.axes.bbox)  # a zoomed panel stays inside its own box
            renderer.draw_gouraud_triangles(gc, polygons, rgba, self.axes.transData.frozen())
            gc.restore()

    return GouraudTriangles()


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
    from .continuity import _blocks, _diagonal, _edge_measures, _local

    local = _local(network.patches)
    diagonal = _diagonal(local.evaluate(CORNER_PARAMETERS)) or 1.0
    left_patch, left_edge = network.shared_edges()
    right_patch = network.neighbor[left_patch, left_edge]
    right_edge = network.neighbor_edge[left_patch, left_edge]
    same = network.same_direction[left_patch, left_edge]
    angle = np.zeros(len(left_patch))
    for block in _blocks(len(left_patch), 4096):
        angle[block] = _edge_measures(
            local,
            left_patch[block],
            left_edge[block],
            right_patch[block],
            right_edge[block],
            same[block],
            samples,
            DEGENERATE_RTOL * diagonal**2,
        )[0]
    return _EdgeAngles(
        np.stack([left_patch, right_patch], axis=1),
        np.stack([left_edge, right_edge], axis=1),
        angle,
        network.seam[left_patch, left_edge],
        samples,
    )


def _edge_samples(edge_counts: Sequence[int], size: tuple[int, int]) -> int:
    """Samples per edge of the deviation mode without a report: 33 while the picture's edges take
    at most :data:`EDGE_SAMPLES_PER_PIXEL` samples per pixel, fewer for more, at least
    :data:`MIN_EDGE_SAMPLES`."""
    budget = EDGE_SAMPLES_PER_PIXEL * size[0] * size[1]
    return int(np.clip(budget // max(sum(edge_counts), 1), MIN_EDGE_SAMPLES, _CHECK_SAMPLES))


# --------------------------------------------------------------------------- public
def render(
    path: str | os.PathLike[str],
    network: PatchNetwork,
    *,
    mode: Mode = "shaded",
    size: tuple[int, int] = (800, 800),
    resolution: int | None = None,
    view: tuple[float, float] | str = AUTO,
    up: str = AUTO,
    title: str | None = None,
    report: ContinuityReport | None = None,
    stripes: int = DEFAULT_STRIPES,
    angle_range: tuple[float, float] | None = None,
    zoom: float = 1.0,
    target: ArrayLike | None = None,
) -> None:
    """Write a PNG of exactly ``size`` = (width, height) pixels showing ``network``.

    ``mode``: ``"shaded"``, ``"zebra"`` (reflection lines, ``stripes`` black/white pairs per turn)
    or ``"deviation"`` (patch edges coloured by their G1 angle from ``report``, which is computed
    when None; ``angle_range`` = (low, high) in degrees fixes the colour scale; the title gets the
    largest angle; without a report only the edge angles are measured, see the module docstring;
    patches too small on the screen for their edge bands are filled with their worst edge's
    colour). ``resolution``: samples per patch side, None to choose it from the pixels (one
    sample about every :data:`SAMPLE_SPACING_PX` pixels along a patch). ``view`` = (elevation,
    azimuth) in degrees about the world axis ``up`` (``"z"``, ``"y"`` for most OBJ files, or
    ``"x"``); ``"auto"`` (the default of both) chooses them from the surface by the rule of
    :func:`auto_camera` (z-up for a slab lying in the xy plane, else y-up; a front three-quarter
    view when the footprint has a long axis). The surface's screen box fills :data:`FILL` of the
    picture. ``zoom`` magnifies the picture
    about the world point ``target`` (default: the middle of the surface); the resolution chosen
    for you then grows with the zoom (at most :data:`MAX_SAMPLES` points). Bad arguments raise
    :class:`InputError`; without matplotlib, :class:`MissingDependencyError`. The file appears
    complete or not at all.
    """
    render_side_by_side(
        path,
        [network],
        [title],
        mode=mode,
        size=size,
        resolution=resolution,
        view=view,
        up=up,
        reports=[report],
        stripes=stripes,
        angle_range=angle_range,
        zoom=zoom,
        target=target,
    )


def render_side_by_side(
    path: str | os.PathLike[str],
    networks: Sequence[PatchNetwork],
    titles: Sequence[str | None],
    *,
    mode: Mode = "shaded",
    size: tuple[int, int] = (1400, 700),
    resolution: int | None = None,
    view: tuple[float, float] | str = AUTO,
    up: str = AUTO,
    reports: Sequence[ContinuityReport | None] | None = None,
    stripes: int = DEFAULT_STRIPES,
    angle_range: tuple[float, float] | None = None,
    zoom: float = 1.0,
    target: ArrayLike | None = None,
) -> None:
    """Write one PNG with ``networks`` side by side, each under its title, seen from the same
    camera; the triangle budget is shared. In ``deviation`` mode all panels share one colour
    scale and one colour bar. Arguments as for :func:`render`; ``reports`` holds one report (or
    None) per network."""
    out_path = _check_path(path)
    check_choice("mode", mode, MODES)
    size = _check_size(size)
    view = _check_view(view)
    up = check_choice("up", up, (AUTO, *UP_AXES))
    stripes = _check_stripes(stripes)
    resolution = _check_resolution(resolution)
    angle_range = _check_angle_range(angle_range)
    zoom = _check_zoom(zoom)
    target_point = None if target is None else as_float_array("target", target, (3,))
    if target_point is not None and target_point.shape != (3,):
        raise InputError(f"target: expected one point (x, y, z), got shape {target_point.shape}")
    if isinstance(networks, PatchNetwork) or not isinstance(networks, Sequence) or not networks:
        raise InputError(
            "networks: expected a non-empty sequence of PatchNetwork, got "
            f"{type(networks).__name__}"
        )
    for index, network in enumerate(networks):
        if not isinstance(network, PatchNetwork):
            raise InputError(
                f"networks[{index}]: expected a PatchNetwork, got {type(network).__name__}"
            )
        _check_network(network)
    if isinstance(titles, str) or not isinstance(titles, Sequence) or len(titles) != len(networks):
        count = (
            len(titles)
            if isinstance(titles, Sequence) and not isinstance(titles, str)
            else type(titles).__name__
        )
        raise InputError(f"titles: expected one title per network ({len(networks)}), got {count}")
    for index, title in enumerate(titles):
        _check_title(f"titles[{index}]" if len(titles) > 1 else "title", title)
    if reports is None:
        reports = [None] * len(networks)
    if (
        isinstance(reports, ContinuityReport)
        or not isinstance(reports, Sequence)
        or len(reports) != len(networks)
    ):
        raise InputError(f"reports: expected one report (or None) per network ({len(networks)})")
    checked = [
        _check_report(r, n, f"reports[{i}]" if len(networks) > 1 else "report")
        for i, (r, n) in enumerate(zip(reports, networks))
    ]
    _matplotlib()

    camera = _camera(view, up, networks)
    count = len(networks)
    scale = None
    sides: list[tuple[NDArray[np.float64], NDArray[np.bool_]] | None] = [None] * count
    shown_titles = list(titles)
    legend: list[tuple[str, NDArray[np.float64]]] = []
    if mode == "deviation":
        samples = _edge_samples(
            [len(n.shared_edges()[0]) for r, n in zip(checked, networks) if r is None], size
        )
        full: list[ContinuityReport | _EdgeAngles] = [
            r if r is not None else _edge_angles(n, samples) for r, n in zip(checked, networks)
        ]
        sides = [_band_angles(n, r) for n, r in zip(networks, full)]
        scale = _angle_scale([r.edge_angle_deg[~r.edge_seam] for r in full], angle_range)
        shown_titles = [
            "\n".join(filter(None, [t, _deviation_caption(r)])) for t, r in zip(titles, full)
        ]
        if any(r.seam_edges for r in full):
            legend.append((_SEAM_LABEL, _SEAM_COLOUR))
    panels = []
    for network, title, network_sides in zip(networks, shown_titles, sides):
        footprint = _footprint(network, camera, size, count, zoom)
        r = resolution or _pixel_resolution(footprint)
        band, filled = None, None
        if mode == "deviation":
            filled = footprint.spacing_px < EDGE_SPACING_PX
            banded = (
                network.patches
                if not filled.any()
                else network.patches.take(np.flatnonzero(~filled))
            )
            band = _band_width(banded, footprint.pixels_per_unit) if len(banded) else (0.1, 0.1)
        surface = _sample(network, r, band, filled)
        panels.append(
            _panel(
                surface,
                camera,
                mode,
                title,
                stripes=stripes,
                sides=network_sides,
                scale=scale,
                zoom=zoom,
                target=target_point,
            )
        )
    label = "G1 angle across the edge (degrees" + (
        ", log scale)" if scale is not None and scale.log else ")"
    )
    _draw(out_path, panels, size, scale, label, legend)


def render_surfaces(
    path: str | os.PathLike[str],
    meshes: Sequence[TriangleMesh],
    titles: Sequence[str],
    *,
    size: tuple[int, int] = (1200, 600),
    view: tuple[float, float] | str = AUTO,
    up: str = AUTO,
) -> None:
    """Write a PNG with the shaded triangle ``meshes`` side by side, each under its title.

    The meshes' own (welded) normals light them; for pictures of patch networks prefer
    :func:`render` / :func:`render_side_by_side`, which keep each patch's exact normals.
    """
    target = _check_path(path)
    size, view, up = _check_size(size), _check_view(view), check_choice("up", up, (AUTO, *UP_AXES))
    if isinstance(meshes, TriangleMesh) or not isinstance(meshes, Sequence) or not meshes:
        raise InputError(
            f"meshes: expected a non-empty sequence of TriangleMesh, got {type(meshes).__name__}"
        )
    if isinstance(titles, str) or not isinstance(titles, Sequence) or len(titles) != len(meshes):
        count = (
            len(titles)
            if isinstance(titles, Sequence) and not isinstance(titles, str)
            else type(titles).__name__
        )
        raise InputError(f"titles: expected one title per mesh ({len(meshes)}), got {count}")
    for index, (mesh, title) in enumerate(zip(meshes, titles)):
        if not isinstance(mesh, TriangleMesh):
            raise InputError(f"meshes[{index}]: expected a TriangleMesh, got {type(mesh).__name__}")
        _check_title(f"titles[{index}]", title)
    _matplotlib()
    camera = _camera(view, up, meshes)
    panels = []
    for mesh, title in zip(meshes, titles):
        # a tessellation is welded: call it closed when every triangle edge has two triangles
        t = np.asarray(mesh.triangles, dtype=np.int64)
        undirected = np.sort(np.concatenate([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]]), axis=1)
        closed = bool(len(t)) and bool(
            (np.unique(undirected, axis=0, return_counts=True)[1] == 2).all()
        )
        surface = _Surface(
            np.asarray(mesh.points, dtype=np.float64),
            np.asarray(mesh.normals, dtype=np.float64),
            t,
            closed,
        )
        panels.append(_panel(surface, camera, "shaded", title))
    _draw(target, panels, size)
