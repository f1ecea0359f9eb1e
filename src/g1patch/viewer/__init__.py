"""An interactive viewer: one self-contained HTML file per network (``g1patch view``,
``Surface.view``).

The page draws the surface with WebGL (three.js, vendored: see ``vendor/README.md``) and needs no
network when opened: three.js and the data are inlined (an import map of ``data:`` URLs for the
modules, base64 ``Float32Array`` data in ``<script type="application/octet-stream">`` blocks).
Drag to orbit, right-drag or shift-drag to pan, wheel to zoom; keys 1/2/3 or the buttons switch the
mode, the URL hash (``#shaded``, ``#zebra``, ``#deviation``) chooses the first one:

* ``shaded``: ambient light, a key and a fill light and a soft highlight, as :mod:`g1patch.render`;
  back faces (the inside of an open surface) in a warm grey;
* ``zebra``: reflection lines, computed per pixel from the exact normals: the view ray reflected
  about the normal meets an environment of :data:`~g1patch.render.DEFAULT_STRIPES` stripe pairs
  around the screen's vertical tilted by 20°; they flow across G1 edges and break at creases;
* ``deviation``: every patch edge drawn as a band about 3 pixels wide in the colour of its G1
  angle (:func:`g1patch.continuity.check`'s per-edge measure, the colour scale of
  :func:`g1patch.render.render`: plasma, logarithmic when the angles span decades), with a legend;
  a patch smaller than 8 pixels on the screen is filled with its worst edge's colour instead;
* ``uv`` (key 4; only for a network with texture coordinates, :attr:`PatchNetwork.uv`, the mesh's
  ``vt``): a procedural checker of the UVs, 8 × 8 squares a unit, no image needed. The page holds
  each patch's corner UVs (float32) and gives the geometry a ``texcoord`` attribute, bilinear
  over the patch's grid.

Intended seams (``network.seam``) are drawn apart as green lines in every mode; the continuity
summary (G1 angles, G0 gap, folds, seams) sits in a corner.

Every patch is sampled on its own ``r × r`` grid with its own exact normals ``p_u × p_v`` (as
the render does: the two sides of a crease are not averaged), positions centred on the surface's
box, as float32. The resolution follows :func:`g1patch.tessellate.choose_resolution` (about
:data:`~g1patch.tessellate.TRIANGLE_BUDGET` = 2 M triangles, the export's budget), and a page of
more triangles (an explicit resolution, or more than a million patches) is refused with a
:class:`ViewTooLargeError` unless ``force``: beyond that a browser draws slowly and the file
passes ~70 MB. Triangle indices and per-vertex parameters are rebuilt in the page from ``r``, so
the file holds 32 bytes of base64 per sample and 22 per patch.

The camera looks at the front three-quarter of the surface about its up axis, chosen from the
data as the render does (:func:`g1patch.render.auto_camera`), and is framed to
its silhouette in the page.
"""

from __future__ import annotations

import base64
import json
import math
import os
import re
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..continuity import DEGENERATE_RTOL, ContinuityReport
from ..errors import InputError
from ..io.atomic import atomic_path
from ..network import PatchNetwork, display_frame
from ..tessellate import TRIANGLE_BUDGET, _size_text, samples_per_side, triangle_count

__all__ = [
    "MODES",
    "VENDORED_THREE_VERSION",
    "ViewTooLargeError",
    "page_size",
    "view_html",
    "write_view",
]

#: three.js release inlined into every page (vendor/README.md says how to refresh it)
VENDORED_THREE_VERSION = "0.170.0"
MODES = ("shaded", "zebra", "deviation")
# : bytes of the page per grid sample (float32 position and normal, base64) and per patch (4 side
# values)
BYTES_PER_SAMPLE = 32
BYTES_PER_PATCH = 22
#: samples per block of patch evaluation
_BLOCK_SAMPLES = 1 << 18
#: entries of the colour table of the deviation mode
_LUT_SIZE = 64
#: side values of the deviation mode for sides that have no G1 angle
_SEAM_SIDE, _OPEN_SIDE = -1.0, -2.0


#: the options of :func:`view_html` when not given
_DEFAULTS: dict[str, Any] = {
    "resolution": None,
    "force": False,
    "report": None,
    "title": None,
    "up": "auto",
    "view": "auto",
    "scan": None,
}


class ViewTooLargeError(InputError):
    """A page would hold more than :data:`~g1patch.tessellate.TRIANGLE_BUDGET` triangles and was not
    forced."""


@dataclass(frozen=True)
class _Samples:
    """Every patch on its own grid: centred float32 positions and unit normals (N, r, r, 3), and
    the area elements |p_u × p_v| (N, r, r)."""

    positions: NDArray[np.float32]
    normals: NDArray[np.float32]
    area: NDArray[np.float32]
    centre: NDArray[np.float64]
    radius: float


def _check_camera(up: str, view: object) -> tuple[str, tuple[float, float] | str]:
    from ..errors import check_choice
    from ..render import AUTO, UP_AXES, _check_view

    return check_choice("up", up, (AUTO, *UP_AXES)), _check_view(view)


def _eye(samples: _Samples, up: str, view: tuple[float, float] | str) -> tuple[str, list[float]]:
    """The world's up axis and the unit vector from the surface towards the camera of checked
    ``up`` and ``view``; ``"auto"`` in either: :func:`g1patch.render.auto_camera` of the samples,
    each weighted by its area element |p_u × p_v|."""
    from ..render import AUTO, _Camera, auto_camera

    if up == AUTO or view == AUTO:
        chosen_up, chosen_view = auto_camera(
            samples.positions.reshape(-1, 3), samples.area.reshape(-1), up=up
        )
        up, view = chosen_up, chosen_view if view == AUTO else view
    return up, _Camera.from_view(view, up).eye.tolist()  # type: ignore[arg-type]


def _check_network(network: object) -> PatchNetwork:
    if not isinstance(network, PatchNetwork):
        raise InputError(f"network: expected a PatchNetwork, got {type(network).__name__}")
    if network.n_patches == 0:
        raise InputError("network: has no patches; there is nothing to view")
    return network


def page_size(n_patches: int, resolution: int) -> int:
    """Bytes of the data in a page of ``n_patches`` at ``resolution``, about (three.js adds ~0.95
    MB)."""
    return BYTES_PER_SAMPLE * n_patches * resolution * resolution + BYTES_PER_PATCH * n_patches


def _resolution(n_patches: int, resolution: object, force: bool) -> int:
    """The samples per patch side: ``resolution`` or :func:`choose_resolution`; above the budget
    without ``force`` a :class:`ViewTooLargeError` with the sizes."""
    r = samples_per_side(resolution, n_patches)
    triangles = triangle_count(n_patches, r)
    if triangles > TRIANGLE_BUDGET and not force:
        raise ViewTooLargeError(
            f"{n_patches} patches at {r} samples a side would make a page of "
            f"{_size_text(triangles)} triangles "
            f"(~{_size_text(page_size(n_patches, r), 'B')}), above the viewer's budget of "
            f"{_size_text(TRIANGLE_BUDGET)} triangles; pass force=True (--force)"
            + (" or a lower resolution" if r > 2 else " (2 samples a side is the coarsest)")
        )
    return r


def _sample(network: PatchNetwork, r: int) -> _Samples:
    """Positions and exact unit normals of every patch on its ``r × r`` grid, a block of patches at
    a time; a degenerate normal (a collapsed edge) takes the mean of its grid neighbours."""
    from ..continuity import _cross3, _norm3, _planar
    from ..render import _fill_degenerate

    patches = network.patches
    count = len(patches)
    grid = np.linspace(0.0, 1.0, r)
    points = np.empty((count, r, r, 3), dtype=np.float64)
    normals = np.empty((count, r, r, 3), dtype=np.float32)
    area = np.empty((count, r, r), dtype=np.float32)
    step = max(1, _BLOCK_SAMPLES // (r * r))
    diagonal = network.bounding_box_diagonal() or 1.0
    for start in range(0, count, step):
        block = patches.take(np.arange(start, min(start + step, count)))
        points[start : start + step] = block.evaluate_grid(grid, grid)
        normal = _cross3(
            _planar(block.evaluate_grid(grid, grid, 1, 0)),
            _planar(block.evaluate_grid(grid, grid, 0, 1)),
        )
        length = area[start : start + step] = _norm3(normal)
        usable = length > DEGENERATE_RTOL * diagonal**2
        normal /= np.where(usable, length, 1.0)
        unit = np.moveaxis(normal, 0, -1)
        normals[start : start + step] = unit if usable.all() else _fill_degenerate(unit, usable)
    flat = points.reshape(-1, 3)
    centre = 0.5 * (flat.min(axis=0) + flat.max(axis=0))
    flat -= centre
    radius = float(_norm3(_planar(flat)).max(initial=0.0))
    return _Samples(
        flat.astype(np.float32).reshape(points.shape), normals, area, centre, radius or 1.0
    )


def _side_values(network: PatchNetwork, report: ContinuityReport) -> NDArray[np.float32]:
    """Per patch side (N, 4): its edge's G1 angle in degrees, -1 on a seam, -2 on an open or
    collapsed side."""
    from ..render import _band_angles

    angles, seams = _band_angles(network, report)
    return np.where(seams, _SEAM_SIDE, np.where(np.isnan(angles), _OPEN_SIDE, angles)).astype(
        np.float32
    )


def _seam_segments(samples: _Samples, report: ContinuityReport) -> NDArray[np.float32]:
    """Line segments (S, r − 1, 2, 3) along every seam, from one side's grid samples."""
    r = samples.positions.shape[1]
    t, last = np.arange(r), np.full(r, r - 1)
    rows = np.stack(
        [t, last, t[::-1], np.zeros(r, dtype=np.int64)]
    )  # side k's samples along i (u) …
    columns = np.stack(
        [np.zeros(r, dtype=np.int64), t, last, t[::-1]]
    )  # … and j (v), counter-clockwise
    seam = report.edge_seam
    patch, side = report.edge_patches[seam, 0], report.edge_sides[seam, 0]
    curves = samples.positions[patch[:, None], rows[side], columns[side]]  # (S, r, 3)
    return np.stack([curves[:, :-1], curves[:, 1:]], axis=2)


def _colour_scale(side_values: NDArray[np.float32]) -> dict[str, Any]:
    """The deviation mode's scale, as :func:`g1patch.render.render` draws it: its ends, whether
    logarithmic, a colour table and the ticks of the legend."""
    from ..render import EXACT_G1_DEG, _angle_scale

    angles = side_values[side_values >= 0].astype(np.float64)
    scale = _angle_scale([angles], None)
    low, high = float(scale.norm.vmin), float(scale.norm.vmax)
    lut = np.asarray(scale.cmap(np.linspace(0.0, 1.0, _LUT_SIZE)))[:, :3]
    if scale.log:
        decades = np.arange(math.ceil(math.log10(low)), math.floor(math.log10(high)) + 1)
        ticks = [10.0**k for k in decades[:: max(1, math.ceil(len(decades) / 6))]]
    else:
        ticks = list(np.linspace(0.0, high, 5))
    return {
        "low": low,
        "high": high,
        "log": scale.log,
        "lut": lut.round(4).reshape(-1).tolist(),
        "ticks": [float(t) for t in ticks],
        "exact": EXACT_G1_DEG,
    }


def _summary(report: ContinuityReport) -> list[list[str]]:
    """(label, value) rows of the corner summary."""
    rows = [
        ["max G1 angle, edges", f"{report.max_edge_angle_deg:.3g}°"],
        ["max G1 angle, corners", f"{report.max_corner_angle_deg:.3g}°"],
        ["max G0 gap (of diagonal)", f"{report.max_g0_gap:.2g}"],
        ["folds", f"{report.folds}"],
    ]
    if report.degenerate_patches:
        rows.append(["degenerate patches", f"{report.degenerate_patches}"])
    if report.seam_edges:
        rows.append(
            [
                "seams (sharp on purpose)",
                f"{report.seam_edges}, "
                f"{report.seam_angle_min_deg:.3g}°–{report.seam_angle_max_deg:.3g}°",
            ]
        )
    else:
        rows.append(["seams", "none"])
    return rows


def _verdict(report: ContinuityReport) -> str:
    if report.passes():
        return "exactly G1" + (" apart from the seams" if report.seam_edges else "") + ", no folds"
    parts = [f"{report.folds} folded patches"] if report.folds else []
    if report.degenerate_patches:
        parts.append(f"{report.degenerate_patches} degenerate patches")
    if not report.is_g1():
        parts.append(
            "not G1: kinks up to "
            f"{max(report.max_edge_angle_deg, report.max_corner_angle_deg):.3g}°"
        )
    if not report.seams_closed():
        parts.append(f"seams open by {report.seam_g0_max:.2g} of the diagonal")
    return ", ".join(parts)


def _base64(array: NDArray[Any]) -> bytes:
    return base64.b64encode(np.ascontiguousarray(array).data)


def _vendor(name: str) -> str:
    return (resources.files(__name__) / "vendor" / name).read_text(encoding="utf-8")


def _module_url(source: str) -> str:
    return "data:text/javascript;base64," + base64.b64encode(source.encode("utf-8")).decode("ascii")


def _script_json(value: object) -> str:
    """JSON safe inside a ``<script>`` element (no ``</`` to end it early)."""
    return json.dumps(value, ensure_ascii=False, separators=(",", ":")).replace("</", "<\\/")


def _page(
    network: PatchNetwork,
    *,
    resolution: int | None,
    force: bool,
    report: ContinuityReport | None,
    title: str | None,
    up: str,
    view: tuple[float, float] | str,
    scan: tuple[NDArray[np.float64], NDArray[np.int64]] | None,
) -> list[bytes]:
    """The page of :func:`view_html` in pieces of UTF-8 (the data are never one large string)."""
    from ..render import DEFAULT_STRIPES

    network = _check_network(network)
    frame = display_frame([network])  # a surface 1e-25 or 1e25 in size: shown in its unit box
    if frame is not None:
        network = network.local_to(frame)
    r = _resolution(network.n_patches, resolution, force)
    up, view = _check_camera(up, view)
    if report is None:
        from ..continuity import check

        report = check(network)
    samples = _sample(network, r)
    distance, distance_meta = _scan_distances(samples, scan, frame)
    up, eye = _eye(samples, up, view)
    sides = _side_values(network, report)
    seams = _seam_segments(samples, report)
    provenance = network.provenance
    name = (
        title
        or Path(provenance.get("source", "")).name
        or f"{provenance.get('method', 'patch')} network"
    )
    method = ", ".join(part for part in (provenance.get("method"), provenance.get("shape")) if part)
    meta = {
        "title": name,
        "method": method,
        "patches": network.n_patches,
        "resolution": r,
        "triangles": triangle_count(network.n_patches, r),
        "seamSegments": int(seams.shape[0] * seams.shape[1]),
        "centre": samples.centre.tolist(),
        "radius": samples.radius,
        "up": up,
        "eye": eye,
        "openSides": int((sides == _OPEN_SIDE).sum()),
        "summary": _summary(report),
        "verdict": _verdict(report),
        "exact": bool(report.passes()),
        "scale": _colour_scale(sides),
        "stripes": DEFAULT_STRIPES,
        "uv": network.uv is not None,
        "distance": distance_meta,
    }
    imports = {
        "three": _module_url(_vendor("three.module.min.js")),
        "three/addons/controls/OrbitControls.js": _module_url(_vendor("OrbitControls.js")),
    }
    fields = {
        b"@@TITLE@@": _html_text(name).encode(),
        b"@@IMPORTS@@": _script_json({"imports": imports}).encode(),
        b"@@META@@": _script_json(meta).encode(),
        b"@@POSITIONS@@": _base64(samples.positions),
        b"@@NORMALS@@": _base64(samples.normals),
        b"@@SIDES@@": _base64(sides),
        b"@@SEAMS@@": _base64(seams.astype(np.float32)),
        b"@@TEXCOORDS@@": _base64(
            np.zeros(0, np.float32) if network.uv is None else network.uv.astype(np.float32)
        ),
        b"@@DISTANCE@@": _base64(distance),
        b"@@VERSION@@": VENDORED_THREE_VERSION.encode(),
        b"@@LICENSE@@": _html_text(_vendor("LICENSE-three.txt")).encode(),
    }
    template = (resources.files(__name__) / "page.html").read_bytes()
    pieces = re.split(rb"(@@[A-Z]+@@)", template)  # the text, then a field's name and text again
    return [fields[piece] if index % 2 else piece for index, piece in enumerate(pieces)]


def _scan_distances(
    samples: _Samples,
    scan: tuple[NDArray[np.float64], NDArray[np.int64]] | None,
    frame: Any,
) -> tuple[NDArray[np.float32], dict[str, float] | None]:
    """The distance of every sample to the scan's triangles (``scan``: points (V, 3), triangles
    (T, 3); exact point–triangle distances, :func:`g1patch.compare.mesh_distance`), of the
    scan's bounding-box diagonal, float32 in the samples' order, and the distance mode's meta
    (``high``: the largest); empty and None without a scan."""
    if scan is None:
        return np.zeros(0, np.float32), None
    from ..compare import mesh_distance
    from ..errors import InputError, as_float_array, as_index_array

    points = as_float_array("scan points", scan[0], (3,))
    triangles = as_index_array("scan triangles", scan[1], (3,))
    if frame is not None:  # the samples are in the display frame: so is the scan
        points = frame.to_local(points)
    diagonal = float(np.linalg.norm(points.max(axis=0) - points.min(axis=0)))
    if not diagonal > 0:
        raise InputError("scan: the scan has no extent")
    where = samples.positions.reshape(-1, 3).astype(np.float64) + samples.centre
    distance = mesh_distance(where, points, triangles) / diagonal
    return distance.astype(np.float32), {"high": float(distance.max())}


def _html_text(text: str) -> str:
    return text.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;")


def view_html(
    network: PatchNetwork,
    *,
    resolution: int | None = None,
    force: bool = False,
    report: ContinuityReport | None = None,
    title: str | None = None,
    up: str = "auto",
    view: tuple[float, float] | str = "auto",
    scan: tuple[NDArray[np.float64], NDArray[np.int64]] | None = None,
) -> str:
    """The viewer page of ``network`` as one HTML string (see the module docstring).

    ``resolution``: samples per patch side (None: about 2 M triangles at most, 17 for small
    networks); more than :data:`~g1patch.tessellate.TRIANGLE_BUDGET` triangles raise
    :class:`ViewTooLargeError` unless ``force``. ``report``: the continuity report to show
    (computed when None). ``title``: the page's title (default: the network's source or method).
    ``up``, ``view``: the first camera, as for :func:`g1patch.render.render` (``"auto"``: by
    :func:`g1patch.render.auto_camera`); R in the page returns to it. ``scan``: a triangle
    mesh ``(points, triangles)`` the surface was fitted to; the page then offers a distance
    mode (every sample coloured by its distance to the scan, of the scan's diagonal).
    """
    pieces = _page(
        network,
        resolution=resolution,
        force=force,
        report=report,
        title=title,
        up=up,
        view=view,
        scan=scan,
    )
    return b"".join(pieces).decode("utf-8")


def write_view(path: str | os.PathLike[str], network: PatchNetwork, **options: Any) -> Path:
    """Write the page of ``network`` (``options`` as for :func:`view_html`) to ``path``
    (``.html``/``.htm``), atomically; returns the path."""
    target = Path(path)
    if target.suffix.lower() not in (".html", ".htm"):
        from ..errors import FormatError

        raise FormatError(
            target,
            f"the viewer writes an HTML page: expected a .html file name, got "
            f"{target.suffix or '(no extension)'!r}",
        )
    pieces = _page(network, **{**_DEFAULTS, **options})
    with atomic_path(target) as temporary, open(temporary, "wb") as file:
        file.writelines(pieces)
    return target
