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

The package's modules, each with one job: :mod:`~g1patch.render.camera` (the camera and its
automatic choice), :mod:`~g1patch.render.stripes` (the zebra phase and its jumps),
:mod:`~g1patch.render.sampling` (the patches sampled for the pixels),
:mod:`~g1patch.render.shading` (shaded and zebra colours), :mod:`~g1patch.render.deviation` (the
G1-angle map), :mod:`~g1patch.render.panel` (visible triangles, back to front),
:mod:`~g1patch.render.draw` (the matplotlib figure and the PNG),
:mod:`~g1patch.render.pictures` (the entry points) and :mod:`~g1patch.render.checks` (argument
checks).
"""

from __future__ import annotations

from .camera import (
    AUTO,
    AUTO_AXIS_TOLERANCE_DEG,
    AUTO_CORRELATION,
    AUTO_ELEVATION,
    AUTO_LONG_RATIO,
    AUTO_SLAB_RATIO,
    AUTO_TURN_DEG,
    DEFAULT_VIEW,
    UP_AXES,
    auto_camera,
)
from .camera import STRIPE_TILT_DEG as STRIPE_TILT_DEG
from .camera import _Camera as _Camera
from .camera import _check_view as _check_view
from .deviation import _SEAM_COLOUR as _SEAM_COLOUR
from .deviation import (
    EDGE_SAMPLES_PER_PIXEL,
    EDGE_SPACING_PX,
    EXACT_G1_DEG,
    MIN_EDGE_SAMPLES,
)
from .deviation import _angle_scale as _angle_scale
from .deviation import _band_angles as _band_angles
from .deviation import _edge_angles as _edge_angles
from .deviation import _edge_samples as _edge_samples
from .panel import MODES
from .panel import Mode as Mode
from .pictures import render, render_side_by_side, render_surfaces
from .sampling import (
    FILL,
    SAMPLE_SPACING_PX,
    TRIANGLE_BUDGET,
    choose_resolution,
)
from .sampling import MAX_SAMPLES as MAX_SAMPLES
from .sampling import RESOLUTION_RANGE as RESOLUTION_RANGE
from .sampling import _fill_degenerate as _fill_degenerate
from .sampling import _sample as _sample
from .stripes import DEFAULT_STRIPES, stripe_jumps, stripe_phase
from .stripes import _phase as _phase

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
