"""The picture functions: :func:`render` (one network), :func:`render_side_by_side` (several,
one camera) and :func:`render_surfaces` (triangle meshes)."""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import replace

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..compare import mesh_distance
from ..continuity import ContinuityReport, _box
from ..errors import InputError, as_float_array, check_choice
from ..network import PatchNetwork, display_frame, unit_frame
from ..tessellate import TriangleMesh
from .camera import AUTO, UP_AXES, _camera, _check_view
from .checks import (
    _check_angle_range,
    _check_network,
    _check_path,
    _check_report,
    _check_resolution,
    _check_size,
    _check_title,
    _check_titles,
    _check_zoom,
    _matplotlib,
)
from .deviation import (
    _SEAM_COLOUR,
    _SEAM_LABEL,
    EDGE_SPACING_PX,
    _angle_scale,
    _band_angles,
    _deviation_caption,
    _distance_scale,
    _edge_angles,
    _edge_samples,
    _EdgeAngles,
)
from .draw import _draw
from .panel import MODES, Mode, _panel
from .sampling import _band_width, _footprint, _pixel_resolution, _sample, _Surface
from .stripes import DEFAULT_STRIPES, _check_stripes


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
    scan: tuple[ArrayLike, ArrayLike] | None = None,
) -> None:
    """Write a PNG of exactly ``size`` = (width, height) pixels showing ``network``.

    ``mode``: ``"shaded"``, ``"zebra"`` (reflection lines, ``stripes`` black/white pairs per turn)
    or ``"deviation"`` (patch edges coloured by their G1 angle from ``report``, which is computed
    when None; ``angle_range`` = (low, high) in degrees fixes the colour scale; the title gets the
    largest angle; without a report only the edge angles are measured, see the module docstring;
    patches too small on the screen for their edge bands are filled with their worst edge's
    colour) or ``"distance"`` (every sample coloured by its exact distance to the triangles of
    ``scan`` = (points, triangles), of the scan's bounding-box diagonal: what ``g1patch fit``
    was fitted to). ``resolution``: samples per patch side, None to choose it from the pixels (one
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
        scan=scan,
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
    scan: tuple[ArrayLike, ArrayLike] | None = None,
) -> None:
    """Write one PNG with ``networks`` side by side, each under its title, seen from the same
    camera; the triangle budget is shared. In ``deviation`` and ``distance`` modes all panels
    share one colour scale and one colour bar. Arguments as for :func:`render`; ``reports`` holds
    one report (or None) per network."""
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
    _check_titles(titles, len(networks), "network")
    for index, title in enumerate(titles):
        _check_title(f"titles[{index}]" if len(titles) > 1 else "title", title)
    scan_points, scan_triangles = _check_scan(scan, mode)
    frame = display_frame(networks)  # a surface 1e-25 or 1e25 in size: drawn in its unit box
    if frame is not None and scan_points is not None:
        scan_points = frame.to_local(scan_points)
    if frame is not None:
        networks = [network.local_to(frame) for network in networks]
        target_point = None if target_point is None else frame.to_local(target_point)
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
        for i, (r, n) in enumerate(zip(reports, networks, strict=True))
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
            [len(n.shared_edges()[0]) for r, n in zip(checked, networks, strict=True) if r is None],
            size,
        )
        full: list[ContinuityReport | _EdgeAngles] = [
            r if r is not None else _edge_angles(n, samples)
            for r, n in zip(checked, networks, strict=True)
        ]
        sides = [_band_angles(n, r) for n, r in zip(networks, full, strict=True)]
        scale = _angle_scale([r.edge_angle_deg[~r.edge_seam] for r in full], angle_range)
        shown_titles = [
            "\n".join(filter(None, [t, _deviation_caption(r)]))
            for t, r in zip(titles, full, strict=True)
        ]
        if any(r.seam_edges for r in full):
            legend.append((_SEAM_LABEL, _SEAM_COLOUR))
    surfaces = []
    for network in networks:
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
        surfaces.append(_sample(network, r, band, filled))
    values: list[NDArray[np.float64] | None] = [None] * count
    label = "G1 angle across the edge (degrees" + (
        ", log scale)" if scale is not None and scale.log else ")"
    )
    if mode == "distance":
        assert scan_points is not None and scan_triangles is not None
        diagonal = float(np.linalg.norm(scan_points.max(axis=0) - scan_points.min(axis=0)))
        distances = [
            mesh_distance(surface.points, scan_points, scan_triangles) / diagonal
            for surface in surfaces
        ]
        scale = _distance_scale(max(float(d.max(initial=0.0)) for d in distances))
        shown_titles = [
            "\n".join(filter(None, [t, f"distance to the scan: max {float(d.max()):.2e}"]))
            for t, d in zip(titles, distances, strict=True)
        ]
        values = list(distances)
        label = "distance to scan (of diag.)"
    panels = [
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
            values=value,
        )
        for surface, title, network_sides, value in zip(
            surfaces, shown_titles, sides, values, strict=True
        )
    ]
    _draw(out_path, panels, size, scale, label, legend)


def _check_scan(
    scan: tuple[ArrayLike, ArrayLike] | None, mode: str
) -> tuple[NDArray[np.float64] | None, NDArray[np.int64] | None]:
    """The distance mode's scan as (points (V, 3), triangles (T, 3)); None for other modes."""
    if mode != "distance":
        if scan is not None:
            raise InputError(f"scan: only the distance mode draws one, not {mode!r}")
        return None, None
    if scan is None:
        raise InputError("mode 'distance': give the scan as scan=(points, triangles)")
    points = as_float_array("scan points", scan[0], (3,))
    triangles = np.asarray(scan[1], dtype=np.int64)
    if (
        points.ndim != 2
        or not len(points)
        or triangles.ndim != 2
        or triangles.shape[1] != 3
        or not len(triangles)
        or triangles.min() < 0
        or triangles.max() >= len(points)
    ):
        raise InputError(
            f"scan: expected points (V, 3) and triangles (T, 3) indexing them, got "
            f"{points.shape} and {triangles.shape}"
        )
    if not np.ptp(points, axis=0).any():
        raise InputError("scan: its points all coincide (no extent to measure against)")
    return points, triangles


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
    _check_titles(titles, len(meshes), "mesh")
    for index, (mesh, title) in enumerate(zip(meshes, titles, strict=True)):
        if not isinstance(mesh, TriangleMesh):
            raise InputError(f"meshes[{index}]: expected a TriangleMesh, got {type(mesh).__name__}")
        _check_title(f"titles[{index}]", title)
    _matplotlib()
    points = [np.asarray(mesh.points, dtype=np.float64).reshape(-1, 3) for mesh in meshes]
    frame = unit_frame(*_box(np.concatenate(points)))
    if frame is not None:  # meshes 1e-25 or 1e25 in size: drawn in their unit box
        meshes = [replace(mesh, points=frame.to_local(mesh.points)) for mesh in meshes]
    camera = _camera(view, up, meshes)
    panels = []
    for mesh, title in zip(meshes, titles, strict=True):
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
