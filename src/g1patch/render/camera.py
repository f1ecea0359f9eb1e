"""The camera: an orthographic view (elevation, azimuth) about a world up axis, and the one
:func:`auto_camera` chooses from the surface's shape when ``up`` / ``view`` are ``"auto"``."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Literal, overload

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InputError, as_float_array, check_choice
from ..network import PatchNetwork
from ..tessellate import TriangleMesh

#: the world axis drawn upwards: z for the shapes here and CAD data, y for most OBJ files
UP_AXES = ("z", "y", "x")

#: (elevation, azimuth) in degrees, matplotlib's convention: the camera looks at the centre from
#: azimuth ``azim`` about +z and ``elev`` above the xy plane (about the up axis, azimuth 0 along the
#: next axis: y up, from +z towards +x; x up, from +y towards +z). This one shows three cube faces;
#: :func:`auto_camera` takes it for surfaces without a front.
DEFAULT_VIEW = (25.0, -60.0)
#: tilt of the stripe axis from the screen's vertical, degrees
STRIPE_TILT_DEG = 20.0


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


#: ``up`` / ``view`` value asking :func:`render` to choose from the data (:func:`auto_camera`)
AUTO = "auto"
#: z is up when the surface's spread along its thinnest principal axis is at most this fraction of
#: the next one's (a slab: the teapot's is 0.86, a flat torus 0.24, the cube 1)
AUTO_SLAB_RATIO = 0.9
#: a principal axis "is" a coordinate axis when they are at most this many degrees apart
AUTO_AXIS_TOLERANCE_DEG = 25.0
#: the horizontal footprint has a long axis when its shorter spread is at most this fraction of its
#: longer
AUTO_LONG_RATIO = 0.9
#: height and position along the long axis are uncorrelated below this correlation (the front is
#: then +axis)
AUTO_CORRELATION = 0.05
#: the camera's elevation in degrees: the first for a surface as tall as it is wide, rising to the
#: second for a flat one (so that a flat surface is not seen edge-on)
AUTO_ELEVATION = (25.0, 45.0)
#: front three-quarter: the camera is turned this many degrees from the front towards the model's
#: left
AUTO_TURN_DEG = 35.0
#: a convex hull facet faces down along an axis when its normal is within this many degrees of it
#: (:func:`resting_axis`)
AUTO_BASE_CONE_DEG = 10.0
#: a surface stands on the hull facets facing down along an axis when they hold at least this
#: fraction of the hull's area (Spot's hooves: 0.09, the teapot's bottom 0.11, the Stanford
#: bunny's 0.09; a sphere's within the cone: 0.008)
AUTO_BASE_FRACTION = 0.04
#: ... and the facets facing up along it hold less than this fraction of that (else it is a slab
#: with two equal sides, the cube, a flat torus: no base to tell)
AUTO_BASE_OPPOSITE = 0.8
#: samples the hull is taken of, at most (evenly spaced)
_AUTO_HULL_POINTS = 20_000
#: patches sampled by :func:`auto_camera` on a network (evenly spaced through it), 4 × 4 points each
_AUTO_PATCHES = 65_536
_AUTO_GRID = 4


@overload
def _check_view(view: Any, auto: Literal[False]) -> tuple[float, float]: ...
@overload
def _check_view(view: Any, auto: bool = True) -> tuple[float, float] | str: ...
def _check_view(view: Any, auto: bool = True) -> tuple[float, float] | str:
    """``view`` checked: (elevation, azimuth) in degrees, or ``"auto"`` where ``auto``."""
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


def resting_axis(points: NDArray[np.float64]) -> str | None:
    """``"y"`` or ``"z"``, the axis a surface stands upright on, or None. Its convex hull's
    facets that face down along ``−y`` or ``−z`` (within :data:`AUTO_BASE_CONE_DEG`) are its
    base there: the larger base is the one stood on when it holds at least
    :data:`AUTO_BASE_FRACTION` of the hull's area and the facets facing up along that axis hold
    less than :data:`AUTO_BASE_OPPOSITE` of it. A scan's base is flat only roughly (the Stanford
    bunny's: hull facets of many planes a few degrees apart), so the facets are gathered by their
    direction, not by their plane. x is never chosen, as by the slab rule."""
    from scipy.spatial import ConvexHull, QhullError

    sample = points[:: max(1, len(points) // _AUTO_HULL_POINTS)]
    try:
        hull = ConvexHull(sample)
    except (QhullError, ValueError):  # flat or too few points: no solid to stand
        return None
    corners = hull.points[hull.simplices]
    area = 0.5 * np.linalg.norm(
        np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]), axis=-1
    )
    normals = hull.equations[:, :3]
    within = math.cos(math.radians(AUTO_BASE_CONE_DEG))
    best, chosen = 0.0, None
    for axis in (1, 2):
        down = float(area[-normals[:, axis] >= within].sum())
        up = float(area[normals[:, axis] >= within].sum())
        if down > best and up < AUTO_BASE_OPPOSITE * down:
            best, chosen = down, "xyz"[axis]
    return chosen if best >= AUTO_BASE_FRACTION * area.sum() else None


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

    The rule: **up** is the axis the surface stands on (:func:`resting_axis`: the larger of its
    convex hull's bases, the facets facing down along −y or −z — Spot's hooves, the Stanford
    bunny's scanned base, in a y-up or a z-up file alike),
    where it stands on one; otherwise, on the weighted mean and covariance of the samples, whose
    principal axes have spreads (standard deviations) σ₀ ≤ σ₁ ≤ σ₂:

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
    shapes; without a base to stand on it misreads e.g. a square y-up relief (thin along z: taken
    as a z-up slab), and a car whose rear stands higher than its bonnet is seen from behind. Pass
    ``up`` / ``view`` for those.
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
        up = resting_axis(points) or AUTO
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
    if not isinstance(view, str) and up != AUTO:  # a checked view: (elevation, azimuth) or AUTO
        return _Camera.from_view(view, up)
    samples = [_area_samples(surface) for surface in surfaces]
    chosen_up, chosen_view = auto_camera(
        np.concatenate([p for p, _ in samples]), np.concatenate([w for _, w in samples]), up=up
    )
    return _Camera.from_view(chosen_view if isinstance(view, str) else view, chosen_up)
