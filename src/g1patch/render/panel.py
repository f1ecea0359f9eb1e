"""One panel of a picture: the visible triangles of a sampled surface, coloured for the mode
and sorted back to front (the painter's algorithm), in screen coordinates."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import NDArray

from .camera import _Camera
from .deviation import _DEVIATION_SURFACE, _AngleScale, _deviation_colours
from .sampling import FILL, _Surface
from .shading import _STRIPE_DARK, _SURFACE_COLOUR, _diffuse, _shaded_colours, _zebra_values
from .stripes import DEFAULT_STRIPES, _phase

Mode = Literal["shaded", "zebra", "deviation", "distance"]
MODES: tuple[Mode, ...] = ("shaded", "zebra", "deviation", "distance")


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
    values: NDArray[np.float64] | None = None,
) -> _Panel:
    """Colour every point of ``surface`` for ``mode`` and sort the visible triangles back to front.
    ``sides``: the deviation mode's G1 angle and seam flag of every patch side
    (:func:`_band_angles`); ``values``: the distance mode's value at every point, coloured by
    ``scale`` and lit.

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
    elif mode == "distance":
        assert values is not None and scale is not None
        diffuse, _ = _diffuse(facing, camera)
        rgb = scale.cmap(scale.norm(values))[:, :3] * (0.45 + 0.55 * diffuse)[:, None]
        colours = np.clip(rgb, 0.0, 1.0)[surface.triangles[keep]]
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
