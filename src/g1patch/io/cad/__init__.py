"""STEP and IGES export through OpenCASCADE (OCP, the extra ``cad``), and reading them back.

Every patch becomes one face on a bicubic B-spline surface (``Geom_BSplineSurface``):

* polynomial patches (:class:`PatchSet` in any form) exactly, as their Bézier control net with
  the knots ``[0, 0, 0, 0, 1, 1, 1, 1]`` (``PatchSet.convert("bezier").world_control()``);
* a Gregory network, by default (``method="auto"``), as the split4 re-assembly of its targets
  (:mod:`g1patch.construct.polynomial`): polynomial, so exact, and G1 in OCC; the reported
  deviation is its distance to the Gregory surface; seams stay seams. ``method="fit"``, networks
  split4 cannot re-assemble, and any other patches: :func:`fit_bspline_surfaces`, a least-squares
  fit on dyadic knots, refined until the deviation is below ``fit_tolerance`` (OCC sees kinks).

A split4 network (four C1 sub-patches per quad, :mod:`g1patch.construct.split4`) becomes one face
per quad instead (:func:`split4_quad_faces`), exactly: a quad whose pieces are one bicubic
subdivided at ½ (a regular region of a limit surface) is that bicubic, knots ``[0,0,0,0,1,1,1,1]``;
any other quad is its two-span B-spline, knots ``[0,0,0,0,½,½,1,1,1,1]``. Its STEP edges carry no
pcurves (each face is a whole surface, its edges its boundary iso-lines, rebuilt by any reader). In
STEP every face is named after its index (``'face 12'``: the patch, or the quad, it was made from),
and the file is compacted (:func:`compact_step`): equal points written once, poles with 15
significant digits instead of OCC's 12.

The faces are sewn into shells (``BRepBuilderAPI_Sewing``, tolerance ``SEWING_RTOL`` × the
bounding-box diagonal); a closed shell becomes a solid (``BRepBuilderAPI_MakeSolid``), reversed
where its volume (``BRepGProp::VolumeProperties``, signed) is negative: oriented outwards. The
exported surfaces' G1 angles are measured on the surfaces OCC holds, at K points of every shared
edge: ``n = ±(S_u × S_v)`` with the sign of the face's orientation, angle
``atan2(|n_L × n_R|, n_L · n_R)``. Each sewn face's poles, knots and orientation are read back from
OCC and its B-spline evaluated vectorised along the edges; one point per face is evaluated by OCC
itself (``BRepAdaptor_Surface::D1``) as a check, and any face that disagrees, or is not a plain
B-spline, is evaluated by OCC at every point (:mod:`~g1patch.io.cad.measure`).

Seams (``network.seam``: edges sharp on purpose) are sewn like every shared edge: one B-rep edge
between two faces that meet at an angle, which is all a sharp edge is. Nothing here smooths or
merges faces across any edge; the G1 figures leave seams out and report their angle range apart.

OCP is imported only inside these functions; without it they raise
:class:`MissingDependencyError` naming the extra, before anything is written. Writes go through
:func:`atomic_path`: an error never leaves a partial file.

Nothing reaches OpenCASCADE unchecked. OCC segfaults (it does not raise) on some inputs that look
harmless — a face sewn away because it is smaller than the sewing tolerance or OCC's fixed
``Precision::Confusion()`` (1e-7) leaves a null face, and evaluating it crashes; infinite or huge
coordinates make infinite tolerances — so before any OCC call: the patches' world coordinates are
finite and at most :data:`MAX_COORDINATE` (1e30, the bound of :mod:`g1patch.io.network_file`; past
1e40 the G1 measurement's eighth powers overflow), the model has a positive bounding box, the poles
handed over are finite and bounded, both knot vectors are clamped cubic ones (finite,
non-decreasing, end multiplicity 4, interior multiplicity ≤ 3, spans at least 1e-12 of the range,
as many knots as poles + 4), and every face's control net spans at least :data:`MIN_FACE_EXTENT`
(1e-5, 100 × ``Precision::Confusion``) and 10 × the sewing tolerance. Each violation is an
:class:`InputError` naming the output file and the patch. After sewing, a face OCC dropped anyway
is an :class:`OpenCascadeError`, and so is any exception raised inside OCP (``Standard_Failure``,
``Standard_ConstructionError``, …): never a traceback, never a crash.

The modules, bottom to top: :mod:`~g1patch.io.cad.bspline` (knots, fitting, split4 quad faces),
:mod:`~g1patch.io.cad.opencascade` (OCP, faces, sewing, solids, writing),
:mod:`~g1patch.io.cad.guards` (the checks above), :mod:`~g1patch.io.cad.measure` (G1 angles in
OCC), :mod:`~g1patch.io.cad.step_text` (:func:`compact_step`), :mod:`~g1patch.io.cad.method`
(exact, split4 or fit), :mod:`~g1patch.io.cad.export` (:func:`export_cad`) and
:mod:`~g1patch.io.cad.read` (reading files back).
"""

from .bspline import (
    FIT_RTOL,
    BSplineFit,
    QuadFaces,
    bezier_knots,
    fit_bspline_surfaces,
    split4_quad_faces,
)
from .export import (
    SEWING_RTOL,
    CadSurfaces,
    ExportOptions,
    ExportResult,
    cad_surfaces,
    export_cad,
    export_iges,
    export_step,
)
from .guards import MAX_COORDINATE, MIN_FACE_EXTENT
from .measure import G1_SAMPLES
from .method import CAD_METHODS, DEVIATION_RTOL, REFINE_QUADS, REFINE_STEPS, CadMethod
from .opencascade import CAD_FORMATS, CadFormat, OpenCascadeError, PathLike, Progress
from .read import (
    CadFace,
    CadModel,
    file_g1_angles,
    read_cad_faces,
    read_iges_faces,
    read_step_faces,
)
from .rhino import RhinoResult, export_3dm
from .step_text import STEP_DIGITS, compact_step

__all__ = [
    "CadSurfaces",
    "RhinoResult",
    "cad_surfaces",
    "export_3dm",
    "CAD_FORMATS",
    "CAD_METHODS",
    "DEVIATION_RTOL",
    "BSplineFit",
    "ExportResult",
    "CadFace",
    "CadModel",
    "export_cad",
    "export_step",
    "export_iges",
    "fit_bspline_surfaces",
    "bezier_knots",
    "read_cad_faces",
    "file_g1_angles",
    "compact_step",
    "read_step_faces",
    "read_iges_faces",
    "OpenCascadeError",
    "MAX_COORDINATE",
    "MIN_FACE_EXTENT",
    "ExportOptions",
    "QuadFaces",
    "split4_quad_faces",
    "CadFormat",
    "CadMethod",
    "PathLike",
    "Progress",
    "FIT_RTOL",
    "G1_SAMPLES",
    "REFINE_QUADS",
    "REFINE_STEPS",
    "SEWING_RTOL",
    "STEP_DIGITS",
]
