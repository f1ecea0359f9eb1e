"""STEP and IGES export through OpenCASCADE (OCP, the extra ``cad``), and reading them back.

Every patch becomes one face on a bicubic B-spline surface (``Geom_BSplineSurface``):

* polynomial patches (:class:`PatchSet` in any form) exactly, as their Bézier control net with
  the knots ``[0, 0, 0, 0, 1, 1, 1, 1]`` (``PatchSet.convert("bezier").world_control()``);
* a Gregory network, by default (``method="auto"``), as the split4 re-assembly of its targets
  (:mod:`g1patch.construct.polynomial`): polynomial, so exact, and G1 in OCC; the reported
  deviation is its distance to the Gregory surface; seams stay seams. ``method="fit"``, networks
  split4 cannot re-assemble, and any other patches: :func:`fit_bspline_surfaces`, a least-squares
  fit on dyadic knots, refined until the deviation is below the tolerance (OCC sees kinks).

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
B-spline, is evaluated by OCC at every point (:func:`_shape_normals`).

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
"""

from __future__ import annotations

import importlib
import os
import re
import time
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from contextvars import ContextVar
from dataclasses import dataclass, field, replace
from pathlib import Path
from types import SimpleNamespace
from typing import Any, Literal, NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import (
    ConstructionError,
    FormatError,
    G1PatchError,
    InputError,
    MeshError,
    MissingDependencyError,
    check_choice,
)
from ..frame import Frame
from ..geometry import grid_row_chunks
from ..network import Patches, PatchNetwork, edge_parameters, network_from_patch_points
from ..patches import CORNER_PARAMETERS, PatchSet
from .atomic import atomic_path

__all__ = [
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
]

PathLike = str | os.PathLike[str]
CadFormat = Literal["step", "iges"]
CadMethod = Literal["auto", "split4", "fit"]
#: how a rational (Gregory) network reaches CAD: ``split4`` its targets re-assembled polynomially
#: (exact G1 in CAD, :mod:`g1patch.construct.polynomial`), ``fit`` its patches fitted one by one
#: (close, kinked), ``auto`` split4, or fit where split4 cannot re-assemble the network
CAD_METHODS: tuple[CadMethod, ...] = ("auto", "split4", "fit")
#: file extensions of each format
CAD_FORMATS: dict[CadFormat, tuple[str, ...]] = {
    "step": (".step", ".stp"),
    "iges": (".iges", ".igs"),
}
# : ``progress(stage, done, total)``; stages: split4, deviation, fit, faces, sew, solid, check, g1,
# write
Progress = Callable[[str, int, int], None]

#: default fit tolerance, relative to the bounding-box diagonal
FIT_RTOL = 1e-6
#: default largest distance of a split4 re-assembly from its Gregory surface, relative to the
#: bounding-box diagonal: above it each patch is re-assembled as n × n cells (n from
#: :data:`REFINE_STEPS`; :func:`~g1patch.construct.polynomial.split4_of_gregory`)
DEVIATION_RTOL = 1e-3
#: the cuts of a patch the re-assembly tries, in order (the distance falls about as 1/n), and the
#: most quads a cut may make
REFINE_STEPS = (1, 2, 3, 4, 6, 8)
REFINE_QUADS = 20_000
#: sewing tolerance, relative to the bounding-box diagonal: shared boundaries coincide to rounding
#: (exact export, ~1e-16) or bit for bit (fitted export); mesh edges are many orders longer.
SEWING_RTOL = 1e-7
#: least-squares samples per knot span and direction; the deviation is measured on twice as many
SAMPLES_PER_SPAN = 4
#: points per shared edge at which the exported surfaces' G1 angle is measured (as the check)
G1_SAMPLES = 33
#: largest |coordinate| (world units) handed to OpenCASCADE: the network file's bound
MAX_COORDINATE = 1e30
#: smallest extent (control-net bounding-box diagonal, model units) of a face handed to
#: OpenCASCADE: 100 × its fixed ``Precision::Confusion()`` (1e-7); smaller faces are sewn away
MIN_FACE_EXTENT = 1e-5
#: smallest extent of a face relative to the sewing tolerance (which would sew it away)
MIN_FACE_SEWING = 10.0


class OpenCascadeError(ConstructionError):
    """OpenCASCADE failed on the geometry: an exception raised inside OCP, or a face its sewing
    dropped."""


# ----------------------------------------------------------------------------------- fitting


class BSplineFit(NamedTuple):
    """Bicubic B-spline surfaces with common knot vectors (full, end knots of multiplicity 4)."""

    control: NDArray[np.float64]  # (N, nu, nv, 3)
    knots_u: NDArray[np.float64]  # (nu + 4,)
    knots_v: NDArray[np.float64]  # (nv + 4,)
    #: max |fit − patch| over a grid twice as fine as the samples, in model units
    deviation: float


def bezier_knots(spans: int = 1) -> NDArray[np.float64]:
    """Clamped uniform cubic knot vector on [0, 1]: ``[0, 0, 0, 0, 1/s, …, 1, 1, 1, 1]``."""
    return np.concatenate([np.zeros(3), np.linspace(0.0, 1.0, spans + 1), np.ones(3)])


def _design_matrix(x: NDArray[np.float64], knots: NDArray[np.float64]) -> NDArray[np.float64]:
    from scipy.interpolate import BSpline

    return BSpline.design_matrix(x, knots, 3).toarray()


@dataclass(frozen=True)
class _Sharing:
    """Which patch corners and edges are the same: ids per ``(patch, k)`` and a representative."""

    corner_ids: NDArray[np.int64]  # (N, 4)
    edge_reversed: NDArray[np.bool_]  # (N, 4)
    edge_rep: NDArray[np.int64]  # (E,) flat index 4 p + k of the side each edge is sampled on
    edge_of: NDArray[np.int64]  # (4 N,) edge number of every patch edge


def _sharing(network: PatchNetwork | None, count: int) -> _Sharing:
    if network is None:  # every patch on its own
        ids = np.arange(4 * count, dtype=np.int64)
        return _Sharing(ids.reshape(count, 4), np.zeros((count, 4), bool), ids, ids)
    _, rep, edge_of = np.unique(
        network.edge_ids.reshape(-1), return_index=True, return_inverse=True
    )
    return _Sharing(network.corner_ids, network.edge_reversed, rep, edge_of.reshape(-1))


def _boundary_control(
    patches: Patches,
    x: NDArray[np.float64],
    basis: NDArray[np.float64],
    inner_pinv: NDArray[np.float64],
    corner_points: NDArray[np.float64],
    share: _Sharing,
) -> NDArray[np.float64]:
    """Control nets ``(N, c, c, 3)`` whose boundary rows are the fitted edge curves (interior 0).

    Each shared edge is fitted once, on its representative side, with its ends fixed to the
    shared corner points: ``inner = B_I⁺ (s − B_0 a − B_last b)``; both sides then copy the same
    numbers (reversed where they run against it), so neighbours' boundaries are identical.
    """
    count = len(patches)
    along_u = patches.evaluate_grid(x, np.array([0.0, 1.0]))  # (N, m, 2, 3)
    along_v = patches.evaluate_grid(np.array([0.0, 1.0]), x)  # (N, 2, m, 3)
    # counter-clockwise edge samples; edges 2 and 3 run backwards, at parameters 1 − x[::-1] = x
    # (the samples are symmetric), so one basis fits all four
    samples = np.stack(
        [along_u[:, :, 0], along_v[:, 1], along_u[:, ::-1, 1], along_v[:, 0, ::-1]], axis=1
    )
    rep = share.edge_rep
    start = corner_points[share.corner_ids.reshape(-1)[rep]]
    end = corner_points[np.roll(share.corner_ids, -1, axis=1).reshape(-1)[rep]]
    residual = (
        samples.reshape(4 * count, -1, 3)[rep]
        - basis[:, 0, None] * start[:, None]
        - basis[:, -1, None] * end[:, None]
    )
    curves = np.concatenate(
        [start[:, None], np.einsum("im,emd->eid", inner_pinv, residual), end[:, None]], axis=1
    )
    flip = share.edge_reversed.reshape(-1)
    canonical = np.where(flip[rep, None, None], curves[:, ::-1], curves)
    ccw = canonical[share.edge_of]
    ccw = np.where(flip[:, None, None], ccw[:, ::-1], ccw).reshape(count, 4, -1, 3)
    size = basis.shape[1]
    control = np.zeros((count, size, size, 3))
    control[:, :, 0], control[:, -1, :] = ccw[:, 0], ccw[:, 1]
    control[:, :, -1], control[:, 0, :] = ccw[:, 2, ::-1], ccw[:, 3, ::-1]
    return control


def _span_samples(breaks: NDArray[np.float64], per_span: int) -> NDArray[np.float64]:
    """``per_span`` equal steps in every span between consecutive ``breaks``, ends included once."""
    steps = np.linspace(0.0, 1.0, per_span + 1)[:-1]
    inner = (breaks[:-1, None] + np.diff(breaks)[:, None] * steps).reshape(-1)
    return np.append(inner, breaks[-1])


def _fit_level(
    patches: Patches,
    breaks: NDArray[np.float64],
    corner_points: NDArray[np.float64],
    share: _Sharing,
) -> tuple[NDArray[np.float64], NDArray[np.float64], float, NDArray[np.float64]]:
    """Fit with the given knot ``breaks``: control ``(N, s+3, s+3, 3)``, knots, deviation, per-span
    deviation.

    Interior points by separable least squares with the boundary fixed, ``X = B_I⁺ R B_I⁺ᵀ`` with
    ``R = S − B C_boundary Bᵀ``, accumulated over row blocks of the sample grid. The deviation is
    measured on a grid with twice as many points per span; a span's deviation is the largest on
    the strips ``u ∈ span`` and ``v ∈ span`` (u and v share the knots).
    """
    spans = len(breaks) - 1
    knots = np.concatenate([np.zeros(3), breaks, np.ones(3)])
    x = _span_samples(breaks, SAMPLES_PER_SPAN)
    basis = _design_matrix(x, knots)
    inner_pinv = np.linalg.pinv(basis[:, 1:-1])
    control = _boundary_control(patches, x, basis, inner_pinv, corner_points, share)
    interior = np.zeros((len(patches), spans + 1, spans + 1, 3))
    for rows in grid_row_chunks(len(patches), len(x), len(x)):
        residual = patches.evaluate_grid(x[rows], x) - np.einsum(
            "ai,nijd,bj->nabd", basis[rows], control, basis, optimize=True
        )
        interior += np.einsum(
            "ia,nabd,jb->nijd", inner_pinv[:, rows], residual, inner_pinv, optimize=True
        )
    control[:, 1:-1, 1:-1] = interior

    check = _span_samples(breaks, 2 * SAMPLES_PER_SPAN)
    check_basis = _design_matrix(check, knots)
    error = np.zeros((len(check), len(check)))  # max over patches
    for rows in grid_row_chunks(len(patches), len(check), len(check)):
        difference = patches.evaluate_grid(check[rows], check) - np.einsum(
            "ai,nijd,bj->nabd", check_basis[rows], control, check_basis, optimize=True
        )
        error[rows] = np.sqrt(np.einsum("...d,...d->...", difference, difference).max(axis=0))
    # point k of the check grid lies in span k // (2 S) (the last point in the last span)
    span_of = np.minimum(np.arange(len(check)) // (2 * SAMPLES_PER_SPAN), spans - 1)
    strip = np.maximum(error.max(axis=1), error.max(axis=0))
    per_span = np.zeros(spans)
    np.maximum.at(per_span, span_of, strip)
    return control, knots, float(error.max()), per_span


def _corner_points(patches: Patches, corner_ids: NDArray[np.int64]) -> NDArray[np.float64]:
    """One position per corner id (the last patch listing it wins: all patches then share it)."""
    corners = patches.evaluate(CORNER_PARAMETERS)  # (N, 4, 3)
    points = np.zeros((int(corner_ids.max()) + 1 if corner_ids.size else 0, 3))
    points[corner_ids.reshape(-1)] = corners.reshape(-1, 3)
    return points


def _diagonal(points: NDArray[np.float64]) -> float:
    flat = points.reshape(-1, 3)
    return float(np.linalg.norm(flat.max(axis=0) - flat.min(axis=0))) if flat.size else 0.0


def fit_bspline_surfaces(
    patches: PatchNetwork | Patches,
    tolerance: float | None = None,
    *,
    refine: Literal["adaptive", "uniform"] = "adaptive",
    max_spans: int = 64,
) -> BSplineFit:
    """Bicubic B-splines within ``tolerance`` of arbitrary patches (``evaluate``/``evaluate_grid``).

    All patches share one knot vector, the same in u and v, symmetric under t → 1 − t. Each span
    is sampled at 4 equal steps per direction. First the boundary: corners are interpolated, each
    edge curve is the least-squares fit of its samples with its ends fixed; then the interior
    control points, by least squares with the boundary fixed. The deviation ``max |fit − patch|`` is
    measured on a grid with twice the samples. While it exceeds ``tolerance`` (default ``1e-6`` ×
    the bounding-box diagonal) knots are inserted at span midpoints: with ``refine="uniform"`` in
    every span (s = 1, 2, 4, …), with ``"adaptive"`` only in spans whose strip ``u ∈ span`` or ``v ∈
    span`` (or its mirror image) exceeds the tolerance. Gregory patches are C¹ but not C² at their
    corners, so the fit converges there as O(h²) only: adaptive refinement grades the knots towards
    the patch ends and needs 46 spans where uniform needs 128 (cube, 1e-6). The first step, s = 1,
    is the Bézier knot vector, so bicubic patches are reproduced at once, up to rounding.

    Pass a :class:`PatchNetwork` to share boundaries: every shared edge is fitted once and copied to
    both sides (reversed where they run against each other: exact on symmetric dyadic knots), so
    neighbouring faces get bit-identical boundary control points. Bare patches are fitted each on
    its own (neighbours then agree to rounding). The arithmetic is batched over patches and chunked
    over grid rows. Raises :class:`ConstructionError` when ``max_spans`` spans do not reach the
    tolerance.

    Patches with a frame (:mod:`g1patch.frame`) are fitted in their local coordinates, with the
    tolerance ``tolerance / s``; the poles are then mapped to world, ``c + s X`` (identical local
    numbers stay identical), and the deviation reported in world units.
    """
    network = patches if isinstance(patches, PatchNetwork) else None
    surfaces = network.patches if network is not None else patches
    if not all(hasattr(surfaces, name) for name in ("evaluate", "evaluate_grid", "__len__")):
        raise InputError(
            "patches: expected patches with evaluate, evaluate_grid and len, got "
            f"{type(surfaces).__name__}"
        )
    check_choice("refine", refine, ("adaptive", "uniform"))
    if not (isinstance(max_spans, (int, np.integer)) and max_spans >= 1):
        raise InputError(f"max_spans: expected a positive integer, got {max_spans!r}")
    frame: Frame | None = getattr(surfaces, "frame", None)
    unit = 1.0
    if frame is not None:
        surfaces, unit = surfaces.local(), frame.scale  # type: ignore[attr-defined]
    share = _sharing(network, len(surfaces))
    corner_points = _corner_points(surfaces, share.corner_ids)
    local_tolerance = _tolerance(tolerance, _diagonal(corner_points) * unit) / unit
    breaks = np.array([0.0, 1.0])
    while True:
        control, knots, deviation, per_span = _fit_level(surfaces, breaks, corner_points, share)
        if deviation <= local_tolerance:
            poles = control if frame is None else frame.to_world(control, out=control)
            return BSplineFit(poles, knots, knots.copy(), deviation * unit)
        # split symmetrically: a reversed edge curve is its reversed control points only on knots
        # symmetric under t → 1 − t (dyadic breaks keep that exact)
        split = (
            np.maximum(per_span, per_span[::-1]) > local_tolerance
            if refine == "adaptive"
            else np.ones(len(per_span), bool)
        )
        split |= not split.any()  # the deviation may sit only on span ends: split all
        if len(breaks) - 1 + int(split.sum()) > max_spans:
            raise ConstructionError(
                f"fit_bspline_surfaces: {len(breaks) - 1} knot spans per direction leave a "
                "deviation of "
                f"{deviation * unit:.3e}, above the tolerance {local_tolerance * unit:.3e}; raise "
                f"max_spans (now {max_spans}) or the tolerance"
            )
        breaks = np.sort(np.concatenate([breaks, 0.5 * (breaks[:-1] + breaks[1:])[split]]))


def _tolerance(tolerance: float | None, diagonal: float) -> float:
    if tolerance is None:
        return FIT_RTOL * diagonal if diagonal > 0 else FIT_RTOL
    if not (
        isinstance(tolerance, (int, float, np.floating))
        and tolerance > 0
        and np.isfinite(tolerance)
    ):
        raise InputError(f"tolerance: expected a positive distance, got {tolerance!r}")
    return float(tolerance)


# --------------------------------------------------------------------------------- OCC access


#: the OCP classes export and reading use, by module
_OCC_NAMES: dict[str, tuple[str, ...]] = {
    "BRep": ("BRep_Builder", "BRep_Tool"),
    "BRepAdaptor": ("BRepAdaptor_Surface",),
    "BRepBuilderAPI": (
        "BRepBuilderAPI_MakeFace",
        "BRepBuilderAPI_MakeSolid",
        "BRepBuilderAPI_Sewing",
    ),
    "BRepCheck": ("BRepCheck_Analyzer",),
    "BRepGProp": ("BRepGProp",),
    "collections": ("Array1_double", "Array1_int", "Array2_gp_Pnt"),
    "Geom": ("Geom_BSplineSurface",),
    "GeomAbs": ("GeomAbs_SurfaceType",),
    "gp": ("gp_Pnt", "gp_Vec"),
    "GProp": ("GProp_GProps",),
    "IFSelect": ("IFSelect_ReturnStatus",),
    "IGESControl": ("IGESControl_Reader", "IGESControl_Writer"),
    "Interface": ("Interface_Static",),
    "Message": ("Message", "Message_Gravity"),
    "STEPConstruct": ("STEPConstruct",),
    "STEPControl": ("STEPControl_AsIs", "STEPControl_Reader", "STEPControl_Writer"),
    "TCollection": ("TCollection_HAsciiString",),
    "TopAbs": ("TopAbs_FACE", "TopAbs_REVERSED", "TopAbs_SHELL"),
    "TopExp": ("TopExp_Explorer",),
    "TopoDS": ("TopoDS", "TopoDS_Compound"),
}


def _occ() -> SimpleNamespace:
    """The OCP classes of ``_OCC_NAMES``, or :class:`MissingDependencyError` naming the extra."""
    try:
        importlib.import_module("OCP")  # first: a missing (or blocked) OCP fails here
        modules = {name: importlib.import_module(f"OCP.{name}") for name in _OCC_NAMES}
    except ImportError:
        raise MissingDependencyError(
            "cadquery-ocp-novtk", "cad", "STEP/IGES export and import"
        ) from None
    return SimpleNamespace(
        **{n: getattr(modules[m], n) for m, names in _OCC_NAMES.items() for n in names}
    )


@contextmanager
def _quiet(occ: SimpleNamespace) -> Iterator[None]:
    """Silence OCC's transfer statistics on stdout for the duration (failures still print)."""
    printers = list(occ.Message.DefaultMessenger_s().Printers())
    levels = [printer.GetTraceLevel() for printer in printers]
    for printer in printers:
        printer.SetTraceLevel(occ.Message_Gravity.Message_Fail)
    try:
        yield
    finally:
        for printer, level in zip(printers, levels):
            printer.SetTraceLevel(level)


def _faces_of(occ: SimpleNamespace, shape: Any) -> list[Any]:
    explorer, faces = occ.TopExp_Explorer(shape, occ.TopAbs_FACE), []
    while explorer.More():
        faces.append(occ.TopoDS.Face(explorer.Current()))
        explorer.Next()
    return faces


def _knot_arrays(occ: SimpleNamespace, knots: NDArray[np.float64]) -> tuple[Any, Any]:
    values, counts = np.unique(knots, return_counts=True)
    array, mults = occ.Array1_double(1, len(values)), occ.Array1_int(1, len(values))
    for i, (value, count) in enumerate(zip(values.tolist(), counts.tolist()), start=1):
        array.SetValue(i, value)
        mults.SetValue(i, count)
    return array, mults


def _make_faces(
    occ: SimpleNamespace, fit: BSplineFit, tolerance: float, progress: Progress | None
) -> list[Any]:
    """One face per control net on ``Geom_BSplineSurface(poles, knots, mults, 3, 3)``."""
    knots_u, mults_u = _knot_arrays(occ, fit.knots_u)
    knots_v, mults_v = _knot_arrays(occ, fit.knots_v)
    count, size_u, size_v = fit.control.shape[:3]
    gp_Pnt, make_face, surface = occ.gp_Pnt, occ.BRepBuilderAPI_MakeFace, occ.Geom_BSplineSurface
    faces = []
    for n, net in enumerate(fit.control.tolist()):
        poles = occ.Array2_gp_Pnt(1, size_u, 1, size_v)
        for i, row in enumerate(net, start=1):
            for j, (x, y, z) in enumerate(row, start=1):
                poles.SetValue(i, j, gp_Pnt(x, y, z))
        faces.append(
            make_face(surface(poles, knots_u, knots_v, mults_u, mults_v, 3, 3), tolerance).Face()
        )
        if progress is not None and (n + 1) % 256 == 0:
            progress("faces", n + 1, count)
    return faces


# ----------------------------------------------------------------------------------- split4 quads

#: a split4 quad whose four sub-patches are one bicubic subdivided at ½, to within this share of
#: the control nets' bounding-box diagonal, is written as that bicubic: a single-span face
SINGLE_SPAN_RTOL = 1e-12
#: split4's sub-patches join C1 inside each quad (row and column 3 of its 7×7 net are the
#: midpoints of their neighbours) to within this share of the diagonal, or the network is written
#: one face per patch
_C1_RTOL = 1e-10
# a cubic's Bézier points from its two halves' seven: b0, 2 h1 − b0, 2 h5 − b3, b3
_EXTRACT = np.array(
    [[1.0, 0, 0, 0, 0, 0, 0], [-1, 2, 0, 0, 0, 0, 0], [0, 0, 0, 0, 0, 2, -1], [0, 0, 0, 0, 0, 0, 1]]
)
# de Casteljau at ½: the two halves' seven points from a cubic's four
_HALVE = (
    np.array(
        [
            [8.0, 0, 0, 0],
            [4, 4, 0, 0],
            [2, 4, 2, 0],
            [1, 3, 3, 1],
            [0, 2, 4, 2],
            [0, 0, 4, 4],
            [0, 0, 0, 8],
        ]
    )
    / 8.0
)
# sub-patch 4f + k covers (uv + _QUARTER[k]) / 2 of quad f
_QUARTER = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])


class QuadFaces(NamedTuple):
    """A split4 network written one face per quad, in quad order: ``single`` (F,) marks the quads
    that are one bicubic, written as it (``bezier``: 4×4 nets, knots :func:`bezier_knots`); the
    others are their two-span B-spline (``two_span``: 6×6 nets, knots ``[0,0,0,0,½,½,1,1,1,1]``).
    Poles in world coordinates."""

    single: NDArray[np.bool_]
    bezier: BSplineFit
    two_span: BSplineFit


def split4_quad_faces(network: PatchNetwork) -> QuadFaces | None:
    """The quads of a split4 network (sub-patch ``4f + k`` at corner k of quad f, its seams to
    ``4f + k ± 1`` joined C1: :mod:`g1patch.construct.split4`), or None for any other network.

    A quad is single-span when its 7×7 macro net is, to :data:`SINGLE_SPAN_RTOL` of the diagonal,
    the de Casteljau subdivision at ½ of the bicubic read off its corners (the Bézier points of each
    corner's 2×2 block, ``b1 = 2 h1 − b0``): then the four pieces are that bicubic and nothing is
    lost. The tests run in the patches' working coordinates (their frame), the poles are mapped to
    world.
    """
    from ..construct.split4 import BSPLINE_KNOTS, macro_nets

    patches = network.patches
    if not isinstance(patches, PatchSet) or not len(patches) or len(patches) % 4:
        return None
    p = np.arange(len(patches))
    k = p % 4
    seams = (network.neighbor[p, (k + 1) % 4] == p - k + (k + 1) % 4) & (
        network.neighbor[p, (k + 2) % 4] == p - k + (k + 3) % 4
    )
    if not seams.all():
        return None
    bezier = patches.convert("bezier")
    nets = macro_nets(bezier.control)
    flat = nets.reshape(-1, 3)
    diagonal = float(np.linalg.norm(flat.max(axis=0) - flat.min(axis=0)))
    if not (np.isfinite(diagonal) and diagonal > 0):
        return None
    c1_gap = max(
        float(np.abs(nets[:, 3] - 0.5 * (nets[:, 2] + nets[:, 4])).max()),
        float(np.abs(nets[:, :, 3] - 0.5 * (nets[:, :, 2] + nets[:, :, 4])).max()),
    )
    if not c1_gap <= _C1_RTOL * diagonal:
        return None
    cubic = np.einsum("ai,fijd,bj->fabd", _EXTRACT, nets, _EXTRACT)
    again = np.einsum("ai,fijd,bj->fabd", _HALVE, cubic, _HALVE)
    single = np.abs(again - nets).max(axis=(1, 2, 3)) <= SINGLE_SPAN_RTOL * diagonal
    keep = np.array([0, 1, 2, 4, 5, 6])  # row and column 3 are midpoints: the double knot at ½
    two_span = np.ascontiguousarray(nets[~single][:, keep][:, :, keep])
    one = np.ascontiguousarray(cubic[single])
    if bezier.frame is not None:
        one, two_span = (
            bezier.frame.to_world(one, out=one),
            bezier.frame.to_world(two_span, out=two_span),
        )
    knots = bezier_knots(1)
    return QuadFaces(
        single,
        BSplineFit(one, knots, knots.copy(), 0.0),
        BSplineFit(two_span, BSPLINE_KNOTS.copy(), BSPLINE_KNOTS.copy(), 0.0),
    )


def _quad_groups(quads: QuadFaces) -> list[BSplineFit]:
    """The non-empty groups of faces with one knot vector each, single-span first."""
    return [group for group in (quads.bezier, quads.two_span) if len(group.control)]


def _make_quad_faces(
    occ: SimpleNamespace, quads: QuadFaces, tolerance: float, progress: Progress | None
) -> list[Any]:
    """One face per quad, in quad order: single-span ones from ``quads.bezier``, the rest
    two-span."""
    faces: list[Any] = [None] * len(quads.single)
    for rows, group in (
        (np.flatnonzero(quads.single), quads.bezier),
        (np.flatnonzero(~quads.single), quads.two_span),
    ):
        if rows.size:
            for row, face in zip(rows.tolist(), _make_faces(occ, group, tolerance, progress)):
                faces[row] = face
    return faces


def _sew(
    occ: SimpleNamespace, faces: Sequence[Any], tolerance: float
) -> tuple[Any, list[Any], int]:
    """Sewn shape, the sewn face of every input face, number of free edges."""
    sewing = occ.BRepBuilderAPI_Sewing(tolerance)
    for face in faces:
        sewing.Add(face)
    sewing.Perform()
    sewn = [occ.TopoDS.Face(sewing.Modified(face)) for face in faces]
    return sewing.SewedShape(), sewn, int(sewing.NbFreeEdges())


def _solids(occ: SimpleNamespace, shape: Any) -> tuple[Any, float | None]:
    """Each closed shell made a solid oriented outwards; ``(shape, volume)``, the volume None
    unless every shell closed.

    A solid's orientation is the sign of its volume (``BRepGProp::VolumeProperties``, signed by
    the faces' orientation: negative inside out), so the volume reported is measured once and no
    point classification (``BRepLib::OrientClosedSolid``) is needed."""
    shells, explorer = [], occ.TopExp_Explorer(shape, occ.TopAbs_SHELL)
    while explorer.More():
        shells.append(occ.TopoDS.Shell(explorer.Current()))
        explorer.Next()
    if not shells or not all(occ.BRep_Tool.IsClosed_s(shell) for shell in shells):
        return shape, None
    solids, volume = [], 0.0
    for shell in shells:
        solid = occ.BRepBuilderAPI_MakeSolid(shell).Solid()
        signed = _volume(occ, solid)
        if signed < 0:
            solid.Reverse()
        solids.append(solid)
        volume += abs(signed)
    if len(solids) == 1:
        return solids[0], volume
    compound, builder = occ.TopoDS_Compound(), occ.BRep_Builder()
    builder.MakeCompound(compound)
    for solid in solids:
        builder.Add(compound, solid)
    return compound, volume


def _volume(occ: SimpleNamespace, shape: Any) -> float:
    """OCC's (signed) volume of a shape (``BRepGProp::VolumeProperties``)."""
    props = occ.GProp_GProps()
    occ.BRepGProp.VolumeProperties_s(shape, props)
    return float(props.Mass())


def _face_normals(occ: SimpleNamespace, face: Any, uv: NDArray[np.float64]) -> NDArray[np.float64]:
    """``±(S_u × S_v)`` (not normalised) by ``BRepAdaptor_Surface::D1``, sign of the face
    orientation."""
    surface = occ.BRepAdaptor_Surface(face, False)
    point, d_u, d_v = occ.gp_Pnt(), occ.gp_Vec(), occ.gp_Vec()
    out = []
    for u, v in uv.tolist():
        surface.D1(u, v, point, d_u, d_v)
        out.append(d_u.Crossed(d_v).Coord())
    normals = np.array(out, dtype=np.float64).reshape(-1, 3)
    return -normals if face.Orientation() == occ.TopAbs_REVERSED else normals


class _OccBSpline(NamedTuple):
    """A face's surface as OCC holds it (``BRep_Tool::Surface``, location applied): a non-rational,
    non-periodic B-spline's poles (nu, nv, 3), full knot sequences and degrees; ``sign`` −1 for a
    reversed face."""

    poles: NDArray[np.float64]
    knots_u: tuple[float, ...]
    knots_v: tuple[float, ...]
    degree_u: int
    degree_v: int
    sign: float


def _occ_bspline(occ: SimpleNamespace, face: Any) -> _OccBSpline | None:
    """The B-spline data OCC holds for ``face`` (:class:`_OccBSpline`), None for any other
    surface."""
    surface = occ.BRep_Tool.Surface_s(face)
    if (
        not isinstance(surface, occ.Geom_BSplineSurface)
        or surface.IsURational()
        or surface.IsVRational()
        or surface.IsUPeriodic()
        or surface.IsVPeriodic()
    ):
        return None
    pole, count_u, count_v = surface.Pole, surface.NbUPoles(), surface.NbVPoles()
    net = np.array(
        [pole(i, j).Coord() for i in range(1, count_u + 1) for j in range(1, count_v + 1)],
        dtype=np.float64,
    ).reshape(count_u, count_v, 3)
    knots = [
        tuple(sequence.Value(i) for i in range(sequence.Lower(), sequence.Upper() + 1))
        for sequence in (surface.UKnotSequence(), surface.VKnotSequence())
    ]
    sign = -1.0 if face.Orientation() == occ.TopAbs_REVERSED else 1.0
    return _OccBSpline(net, knots[0], knots[1], surface.UDegree(), surface.VDegree(), sign)


def _basis_d1(
    knots: NDArray[np.float64], degree: int, x: NDArray[np.float64]
) -> tuple[NDArray[np.int64], NDArray[np.float64], NDArray[np.float64]]:
    """The ``degree + 1`` B-spline basis functions that are nonzero at each ``x`` and their first
    derivatives (Cox–de Boor, The NURBS Book A2.2/A2.3, over all x at once): the index of the
    first one (n,), values (n, p+1), derivatives (n, p+1). ``x`` is clamped into the knots'
    range."""
    p = degree
    x = np.clip(x, knots[p], knots[-p - 1])
    span = np.clip(np.searchsorted(knots, x, side="right") - 1, p, len(knots) - p - 2)
    steps = np.arange(1, p + 1)[:, None]
    left = x - knots[span + 1 - steps]  # left[j-1] = x − t[span + 1 − j], (p, n)
    right = knots[span + steps] - x  # right[j-1] = t[span + j] − x
    level = [np.ones_like(x)]
    for j in range(1, p + 1):
        lower, saved, level = level, np.zeros_like(x), []
        for r in range(j):
            temp = lower[r] / (right[r] + left[j - 1 - r])
            level.append(saved + right[r] * temp)
            saved = left[j - 1 - r] * temp
        level.append(saved)
    # N'_{i,p} = p N_{i,p-1} / (t[i+p] − t[i]) − p N_{i+1,p-1} / (t[i+p+1] − t[i+1]), i = span − p +
    # k
    below = np.stack(
        [np.zeros_like(x), *lower, np.zeros_like(x)], axis=1
    )  # N_{span-p+k, p-1}, k = 0 … p+1
    k = np.arange(p + 2)
    width = knots[span[:, None] + k] - knots[span[:, None] + k - p]
    scaled = np.divide(p * below, width, out=np.zeros_like(below), where=width > 0)
    return span - p, np.stack(level, axis=1), scaled[:, :-1] - scaled[:, 1:]


def _dense_basis(
    knots: tuple[float, ...], degree: int, count: int, x: NDArray[np.float64]
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """All ``count`` basis functions and their derivatives at ``x`` (any shape): (…, count) each."""
    first, values, derivatives = _basis_d1(np.asarray(knots), degree, x.reshape(-1))
    rows, columns = np.arange(x.size)[:, None], first[:, None] + np.arange(degree + 1)
    dense_values, dense_derivatives = np.zeros((x.size, count)), np.zeros((x.size, count))
    dense_values[rows, columns], dense_derivatives[rows, columns] = values, derivatives
    return dense_values.reshape(*x.shape, count), dense_derivatives.reshape(*x.shape, count)


def _distinct_rows(rows: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """The distinct rows of a 2-D array (first seen first) and each row's index among them."""
    rows = np.ascontiguousarray(rows)
    seen: dict[bytes, int] = {}
    which = np.array([seen.setdefault(row.tobytes(), len(seen)) for row in rows], dtype=np.int64)
    first = np.zeros(len(seen), dtype=np.int64)
    first[which[::-1]] = np.arange(len(rows) - 1, -1, -1)
    return rows[first], which


def _cross(a: NDArray[np.float64], b: NDArray[np.float64]) -> NDArray[np.float64]:
    """``a × b`` for coordinates on axis 1, (n, 3, …)."""
    return np.stack(
        [
            a[:, 1] * b[:, 2] - a[:, 2] * b[:, 1],
            a[:, 2] * b[:, 0] - a[:, 0] * b[:, 2],
            a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0],
        ],
        axis=1,
    )


#: a normal ``S_u × S_v`` shorter than this share of ``|S_u| |S_v|`` is rounding (its tangents are
#: parallel: a degenerate point) and counts as zero, as OCC's exact cancellation there gives
DEGENERATE_NORMAL_RTOL = 64 * float(np.finfo(np.float64).eps)
#: rows (iso-line samples) :func:`_bspline_iso_normals` evaluates at once
_ROW_CHUNK = 1 << 14


def _bspline_iso_normals(
    surfaces: Sequence[_OccBSpline],
    face_of: NDArray[np.int64],
    uv: NDArray[np.float64],
    iso_u: NDArray[np.bool_],
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """``±(S_u × S_v)`` of ``surfaces[face_of[r]]`` at ``uv[r, k]``, (R, K, 3), and ``|S_u| |S_v|``
    (the scale of its rounding), (R, K), for rows on iso-lines: u constant along row r where
    ``iso_u[r]``, else v. Vectorised over rows of faces with equal knots, degrees and pole counts:
    each row's curve ``C(s) = Σ_a N_a(s) Σ_c N_c(c) P_ac`` and cross-derivative curve (``N'_c``)
    in one product with the constant parameter's basis, then both evaluated at the row's samples."""
    normals, scale = np.empty(uv.shape[:2] + (3,)), np.empty(uv.shape[:2])
    groups: dict[tuple[Any, ...], list[int]] = {}
    for f, s in enumerate(surfaces):
        groups.setdefault((s.knots_u, s.knots_v, s.degree_u, s.degree_v, s.poles.shape), []).append(
            f
        )
    for (knots_u, knots_v, p, q, _), members in groups.items():
        nets = np.stack([surfaces[f].poles for f in members])  # (F, nu, nv, 3)
        signs = np.array([surfaces[f].sign for f in members])
        slot = np.full(len(surfaces), -1)
        slot[members] = np.arange(len(members))
        for constant_u in (True, False):
            # along the row runs v (u constant: poles transposed to (along, cross)) or u
            poles = nets.transpose(0, 2, 1, 3) if constant_u else nets
            along, cross = (1, 0) if constant_u else (0, 1)
            (knots_a, p_a), (knots_c, p_c) = (
                ((knots_v, q), (knots_u, p)) if constant_u else ((knots_u, p), (knots_v, q))
            )
            rows = np.flatnonzero((slot[face_of] >= 0) & (iso_u == constant_u))
            for chunk in np.array_split(rows, -(-len(rows) // _ROW_CHUNK)) if rows.size else ():
                member = slot[face_of[chunk]]
                n_c, d_c = _dense_basis(knots_c, p_c, poles.shape[2], uv[chunk, 0, cross])
                curve = np.einsum("rc,racd->rda", n_c, poles[member])  # (rows, 3, along poles)
                cross_curve = np.einsum("rc,racd->rda", d_c, poles[member])
                samples, which = _distinct_rows(uv[chunk, :, along])
                n_a, d_a = _dense_basis(knots_a, p_a, poles.shape[1], samples)
                # (rows, 3, K): coordinates first, so that the cross product runs on contiguous rows
                s_along = np.matmul(curve, d_a.transpose(0, 2, 1)[which])
                s_cross = np.matmul(cross_curve, n_a.transpose(0, 2, 1)[which])
                normal = _cross(s_cross, s_along) if constant_u else _cross(s_along, s_cross)
                size = np.sqrt(
                    np.einsum("rdk,rdk->rk", s_along, s_along)
                    * np.einsum("rdk,rdk->rk", s_cross, s_cross)
                )
                # a degenerate point (tangents parallel to rounding): no direction, the zero normal
                degenerate = (
                    np.sqrt(np.einsum("rdk,rdk->rk", normal, normal))
                    <= DEGENERATE_NORMAL_RTOL * size
                )
                normal = np.where(
                    degenerate[:, None], 0.0, normal * signs[member, None, None]
                )  # +0: angle 0 to any normal
                normals[chunk] = normal.transpose(0, 2, 1)
                scale[chunk] = size
    return normals, scale


#: vectorised and OCC's own normals agree to this share of ``|S_u| |S_v|`` (:func:`_shape_normals`)
NORMAL_AGREEMENT_RTOL = 1e-9


def _shape_normals(
    occ: SimpleNamespace,
    faces: Sequence[Any],
    face_of: NDArray[np.int64],
    uv: NDArray[np.float64],
    progress: Progress | None,
) -> NDArray[np.float64]:
    """``±(S_u × S_v)`` of ``faces[face_of[r]]`` at ``uv[r, k]`` (R rows of K points), (R, K, 3), on
    the surfaces OCC holds.

    Rows on iso-lines (u or v constant along the row, as every edge is) of B-spline faces: the
    faces' poles, knots and orientation are read from OCC (:func:`_occ_bspline`) and evaluated
    vectorised (:func:`_bspline_iso_normals`); on every such face one point (the middle of its first
    row) is evaluated by OCC too
    (``BRepAdaptor_Surface::D1``, :func:`_face_normals`). A face where the two disagree beyond
    :data:`NORMAL_AGREEMENT_RTOL` of ``|S_u| |S_v|``, a face on another kind of surface, and any
    other row are evaluated by OCC at every point."""
    used = np.unique(face_of)
    surfaces = [_occ_bspline(occ, faces[f]) for f in used.tolist()]
    index = np.full(len(faces), -1)
    index[used] = np.arange(len(used))
    known = np.array([s is not None for s in surfaces], dtype=bool)
    iso_u = (uv[:, :, 0] == uv[:, :1, 0]).all(axis=1)
    fast = known[index[face_of]] & (iso_u | (uv[:, :, 1] == uv[:, :1, 1]).all(axis=1))
    normals = np.empty(uv.shape[:2] + (3,))
    if fast.any():
        rows = np.flatnonzero(fast)
        kept = [s for s in surfaces if s is not None]
        local = np.cumsum(known) - 1  # index among the kept surfaces
        normals[rows], scale = _bspline_iso_normals(
            kept, local[index[face_of[rows]]], uv[rows], iso_u[rows]
        )
        checked, first = np.unique(
            face_of[rows], return_index=True
        )  # one row per face: its middle point
        middle = uv.shape[1] // 2
        by_occ = np.concatenate(
            [
                _face_normals(occ, faces[f], uv[rows[r], middle : middle + 1])
                for f, r in zip(checked.tolist(), first.tolist())
            ]
        )
        off = (
            np.linalg.norm(by_occ - normals[rows[first], middle], axis=-1)
            > NORMAL_AGREEMENT_RTOL * scale[first, middle]
        )
        fast &= ~np.isin(face_of, checked[off])
    slow = np.flatnonzero(~fast)
    order = slow[np.argsort(face_of[slow], kind="stable")]
    starts = np.flatnonzero(np.diff(face_of[order], prepend=-1))
    for n, (start, end) in enumerate(zip(starts.tolist(), [*starts[1:].tolist(), len(order)])):
        chosen = order[start:end]
        face = faces[int(face_of[chosen[0]])]
        normals[chosen] = _face_normals(occ, face, uv[chosen].reshape(-1, 2)).reshape(
            len(chosen), -1, 3
        )
        if progress is not None and n % 256 == 0:
            progress("g1", n, len(starts))
    return normals


def _occ_g1_angles(
    occ: SimpleNamespace,
    faces: Sequence[Any],
    network: PatchNetwork,
    samples: int,
    progress: Progress | None,
    quads: bool = False,
) -> NDArray[np.float64]:
    """(E, samples) angles (degrees) between the two sewn faces' OCC normals along every shared
    edge. With ``quads`` the faces are a split4 network's quads (:func:`split4_quad_faces`):
    sub-patch ``4f + k`` is evaluated on its quarter of face f, so the seams inside a quad compare
    the one surface with itself (0), and every mesh edge compares the two quads' surfaces."""
    from ..continuity import angle_between

    patch, edge = network.shared_edges()
    other, other_edge = network.neighbor[patch, edge], network.neighbor_edge[patch, edge]
    t = np.linspace(0.0, 1.0, samples)
    t_other = np.where(network.same_direction[patch, edge][:, None], t, 1.0 - t)
    uv_a = edge_parameters(edge[:, None], t)  # (E, K, 2)
    uv_b = edge_parameters(other_edge[:, None], t_other)
    face_a, face_b = patch, other
    if quads:
        uv_a, uv_b = (
            0.5 * (uv_a + _QUARTER[patch % 4, None]),
            0.5 * (uv_b + _QUARTER[other % 4, None]),
        )
        face_a, face_b = patch // 4, other // 4
    normals = _shape_normals(
        occ, faces, np.concatenate([face_a, face_b]), np.concatenate([uv_a, uv_b]), progress
    )
    return angle_between(normals[: len(patch)], normals[len(patch) :])


# ----------------------------------------------------------------------------------- guards
#: the stage export_cad enters after each lap, for a failure's message
_NEXT_STAGE = {
    "split4": "measuring the deviation",
    "deviation": "fitting the surfaces",
    "fit": "making the faces",
    "faces": "sewing",
    "sew": "making solids",
    "solid": "checking the shape",
    "check": "measuring G1 angles",
    "g1": "writing the file",
}


def _raised_by_occ(error: BaseException) -> bool:
    """An exception from inside OCP: its classes live in ``OCP.*``, or pybind11's translation of a
    C++ exception it does not know (``RuntimeError``)."""
    return type(error) is RuntimeError or any(
        cls.__module__.startswith("OCP") for cls in type(error).__mro__
    )


@contextmanager
def _occ_failures(target: Path, doing: list[str]) -> Iterator[None]:
    """Turn an exception raised inside OCP into :class:`OpenCascadeError` naming ``target`` and the
    stage."""
    try:
        yield
    except G1PatchError:
        raise
    except Exception as error:
        if not _raised_by_occ(error):
            raise
        text = str(error).strip()
        detail = text.splitlines()[0] if text else "no message"
        raise OpenCascadeError(
            f"{target}: OpenCASCADE failed while {doing[0]} ({type(error).__name__}: {detail})"
        ) from error


def _bound_message(value: float) -> str:
    what = (
        "is not a number"
        if np.isnan(value)
        else "is infinite"
        if np.isinf(value)
        else f"reaches magnitude {abs(value):.3g}"
    )
    limit = f"finite coordinates of magnitude at most {MAX_COORDINATE:g}"
    return f"{what}; OpenCASCADE export needs {limit}"


def _check_patch_coordinates(target: Path, patches: object) -> None:
    """Polynomial and Gregory patches: world coordinates finite and within :data:`MAX_COORDINATE`
    (``|c| + s·max|x|`` with a frame, in Python floats: no overflow warning); other patches are
    checked on their fitted poles."""
    data = patches.control if isinstance(patches, PatchSet) else getattr(patches, "points", None)
    if not isinstance(data, np.ndarray) or data.dtype.kind != "f" or not data.size:
        return
    low, high = float(data.min()), float(data.max())
    largest = max(-low, high) if low == low and high == high else float("nan")
    frame = getattr(patches, "frame", None)
    if isinstance(frame, Frame):
        largest = float(np.abs(frame.centre).max()) + frame.scale * largest
    if not largest <= MAX_COORDINATE:
        raise InputError(
            f"{target}: cannot export: the largest of the patches' coordinates "
            f"{_bound_message(largest)}"
        )


def _check_diagonal(target: Path, diagonal: float) -> None:
    if not (np.isfinite(diagonal) and diagonal > 0):
        what = "0: all patch corners coincide" if diagonal == 0 else f"{diagonal!r}"
        raise InputError(
            f"{target}: cannot export: the bounding-box diagonal of the patch corners is {what}"
        )


def _check_knots(target: Path, name: str, knots: NDArray[np.float64], poles: int) -> None:
    """A clamped cubic knot vector for ``poles`` poles, as ``Geom_BSplineSurface`` takes it."""
    knots = np.asarray(knots, dtype=np.float64)
    problem = None
    if knots.ndim != 1 or len(knots) != poles + 4:
        problem = f"has {knots.size} knots for {poles} poles (needs poles + 4)"
    elif not np.isfinite(knots).all():
        problem = "is not finite"
    elif np.any(np.diff(knots) < 0):
        problem = "decreases"
    else:
        values, counts = np.unique(knots, return_counts=True)
        span = values[-1] - values[0]
        if len(values) < 2 or not span > 0:
            problem = "spans nothing"
        elif counts[0] != 4 or counts[-1] != 4:
            problem = (
                f"has end multiplicities {counts[0]} and {counts[-1]} (a clamped cubic needs 4)"
            )
        elif len(counts) > 2 and counts[1:-1].max() > 3:
            problem = (
                f"has an interior knot of multiplicity {counts[1:-1].max()} (at most 3 for cubics)"
            )
        elif np.diff(values).min() < 1e-12 * span:
            problem = f"has a span of {np.diff(values).min():.3g}, below 1e-12 of its range"
    if problem is not None:
        raise InputError(f"{target}: cannot export: the B-spline knot vector in {name} {problem}")


def _check_fit(target: Path, fit: BSplineFit, sewing_tolerance: float) -> None:
    """The poles and knots handed to ``Geom_BSplineSurface``: finite, bounded, clamped cubic knots,
    no face smaller than OCC can sew (module docstring)."""
    control = np.asarray(fit.control)
    if control.ndim != 4 or control.shape[-1] != 3 or not control.shape[0]:
        raise InputError(
            f"{target}: cannot export: expected control nets (N, nu, nv, 3), got {control.shape}"
        )
    low, high = float(control.min()), float(control.max())
    if not (low >= -MAX_COORDINATE and high <= MAX_COORDINATE):
        bad = np.argwhere(~(np.abs(control) <= MAX_COORDINATE))[0]
        raise InputError(
            f"{target}: cannot export: patch {bad[0]}: a B-spline pole "
            f"{_bound_message(float(control[tuple(bad)]))}"
        )
    _check_knots(target, "u", fit.knots_u, control.shape[1])
    _check_knots(target, "v", fit.knots_v, control.shape[2])
    if not (np.isfinite(sewing_tolerance) and sewing_tolerance > 0):
        raise InputError(f"{target}: cannot export: the sewing tolerance is {sewing_tolerance!r}")
    extent = np.linalg.norm(control.max(axis=(1, 2)) - control.min(axis=(1, 2)), axis=-1)
    smallest = max(MIN_FACE_EXTENT, MIN_FACE_SEWING * sewing_tolerance)
    small = np.flatnonzero(extent < smallest)
    if small.size:
        first = int(small[0])
        others = f" (and {small.size - 1} more)" if small.size > 1 else ""
        raise InputError(
            f"{target}: cannot export: patch {first}{others} spans {extent[first]:.3g} (its "
            "control net's diagonal), "
            f"below {smallest:.3g}, the least OpenCASCADE can sew (100 × its fixed precision "
            "1e-7, at least "
            f"10 × the sewing tolerance): a degenerate or too small patch"
        )


def _check_sewn(target: Path, faces: Sequence[Any]) -> None:
    """Every input face has a sewn face: OCC segfaults evaluating the null face of one it
    dropped."""
    dropped = [n for n, face in enumerate(faces) if face.IsNull()]
    if dropped:
        raise OpenCascadeError(
            f"{target}: OpenCASCADE's sewing dropped the face of patch {dropped[0]}"
            f"{f' (and {len(dropped) - 1} more)' if len(dropped) > 1 else ''}: a degenerate face"
        )


# ----------------------------------------------------------------------------------- export


@dataclass(frozen=True, repr=False)
class ExportResult:
    """What was written and how good it is (distances in model units, angles in degrees)."""

    path: Path
    format: CadFormat
    faces: int
    #: every sewn shell closed and made a solid
    solid: bool
    #: BRepCheck_Analyzer's verdict on the written shape
    valid: bool
    free_edges: int
    #: polynomial patches written exactly (their Bézier control nets)
    exact: bool
    # : how the faces were made: ``exact`` (polynomial patches, or Gregory patches that are
    # bicubics), ``split4`` (a Gregory network's
    #: targets re-assembled polynomially, then exact) or ``fit`` (fitted B-splines)
    method: str
    #: why ``auto`` fitted a Gregory network without seams (split4 failed on it), else ""
    method_note: str
    #: knot spans per direction (1 for exact export; 2 where split4 quads keep their two spans)
    spans: int
    #: cells per patch side of the split4 re-assembly (1: one quad per patch; n: n × n, face
    #: ``r = f n² + a n + b`` covers cell (a, b) of patch f), 0 for other methods
    refine: int
    # : max |surface − patch| of the fit, measured on a grid twice as fine as its samples; 0.0 when
    # exact
    fit_deviation: float
    fit_tolerance: float
    sewing_tolerance: float
    # : G1 angles of the exported surfaces on shared edges but seams, measured by OCC (max and mean
    # of per-edge max)
    max_g1_angle_deg: float
    mean_g1_angle_deg: float
    #: seams (edges sharp on purpose), each one sharp B-rep edge, and the range of the angle
    #: between their faces' OCC normals over all samples (None without seams or measurements)
    seam_edges: int
    seam_angle_min_deg: float | None
    seam_angle_max_deg: float | None
    #: OCC's volume of the solid (BRepGProp::VolumeProperties), None when no solid was made
    volume: float | None
    #: max distance of the written surface from the network's own surface (model units): 0 when
    # : exact, the fit deviation when fitted, the foot-point distance to the Gregory surface for
    # split4
    deviation: float
    #: :attr:`deviation` / the bounding-box diagonal
    relative_deviation: float
    #: bytes of the written file
    file_bytes: int
    #: whether OCC measured the G1 angles; if not, why (``g1_note``)
    g1_measured: bool
    g1_note: str
    #: seconds per stage: split4 (a Gregory network re-assembled) and deviation (its distance to the
    #: Gregory surface), fit (or the split4 quads read off), faces, sew, solid (with its volume),
    #: check, g1, write (with the STEP compaction)
    seconds: dict[str, float] = field(default_factory=dict)

    def __repr__(self) -> str:
        """One line: the file, its faces and verdicts, the method, OCC's G1 angle, the deviation."""
        shape = "solid" if self.solid else f"{self.free_edges} free edges"
        angle = f"OCC G1 ≤ {self.max_g1_angle_deg:.1e}°" if self.g1_measured else "G1 not measured"
        return (
            f"<ExportResult {self.path.name}: {self.format}, {self.faces} faces, {shape}, "
            f"{'valid' if self.valid else 'INVALID'}, {self.method}, {angle}, "
            f"deviation {self.relative_deviation:.1e} of diagonal, {self.file_bytes:,} bytes>"
        )

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready figures."""
        result = {name: getattr(self, name) for name in self.__dataclass_fields__}
        result["path"] = str(self.path)
        return result


def _format_of(path: Path, wanted: CadFormat | None) -> CadFormat:
    suffix = path.suffix.lower()
    for name, suffixes in CAD_FORMATS.items():
        if suffix in suffixes and wanted in (None, name):
            return name
    allowed = CAD_FORMATS[wanted] if wanted else sum(CAD_FORMATS.values(), ())
    raise FormatError(
        path, f"unsupported extension {path.suffix!r}; expected one of {', '.join(allowed)}"
    )


def _as_network(network: PatchNetwork | PatchSet) -> PatchNetwork:
    if isinstance(network, PatchNetwork):
        return network
    if isinstance(network, PatchSet):
        return network_from_patch_points(network)
    raise InputError(
        f"network: expected a PatchNetwork or a PatchSet, got {type(network).__name__}"
    )


def _name_step_faces(occ: SimpleNamespace, writer: Any, faces: Sequence[Any]) -> None:
    """Name the ``ADVANCED_FACE`` of each of ``faces`` after its index (``'face 12'``): the patch,
    or the quad of a split4 network, it was made from."""
    process = writer.WS().TransferWriter().FinderProcess()
    for n, face in enumerate(faces):
        entity = occ.STEPConstruct.FindEntity_s(process, face)
        if entity is not None and hasattr(entity, "SetName"):
            entity.SetName(occ.TCollection_HAsciiString(f"face {n}"))


@contextmanager
def _static(occ: SimpleNamespace, name: str, value: int) -> Iterator[None]:
    """OCC's process-wide integer setting ``name`` at ``value`` for the duration, then as it was."""
    before = occ.Interface_Static.IVal_s(name)
    occ.Interface_Static.SetIVal_s(name, value)
    try:
        yield
    finally:
        occ.Interface_Static.SetIVal_s(name, before)


class _StepOptions(NamedTuple):
    """What export_cad asks of the STEP writer beyond the shape (:func:`_step_options`)."""

    faces: Sequence[Any]
    pcurves: bool


_STEP_OPTIONS: ContextVar[_StepOptions] = ContextVar(
    "_STEP_OPTIONS", default=_StepOptions((), True)
)


@contextmanager
def _step_options(faces: Sequence[Any], pcurves: bool) -> Iterator[None]:
    """For the :func:`_write` calls inside: name ``faces`` after their index; with ``pcurves``
    False, write the edges without parameter-space curves."""
    token = _STEP_OPTIONS.set(_StepOptions(faces, pcurves))
    try:
        yield
    finally:
        _STEP_OPTIONS.reset(token)


def _write(occ: SimpleNamespace, shape: Any, path: Path, kind: CadFormat) -> None:
    """Write ``shape``. In STEP the faces of :func:`_step_options` are named after their index (IGES
    faces carry no names here), and without its ``pcurves`` the edges carry no parameter-space
    curves (``write.surfacecurve.mode`` 0): every face written here is a whole B-spline surface, its
    edges the iso-lines u, v ∈ {0, 1}, which a reader rebuilds exactly."""
    options = _STEP_OPTIONS.get()
    with _quiet(occ):
        if kind == "step":
            writer = occ.STEPControl_Writer()
            with _static(occ, "write.surfacecurve.mode", 1 if options.pcurves else 0):
                status = writer.Transfer(shape, occ.STEPControl_AsIs)
            if status == occ.IFSelect_ReturnStatus.IFSelect_RetDone:
                _name_step_faces(occ, writer, options.faces)
                status = writer.Write(str(path))
            ok = status == occ.IFSelect_ReturnStatus.IFSelect_RetDone
        else:
            writer = occ.IGESControl_Writer(
                "MM", 1
            )  # 1: B-rep entities (solids and shells), not trimmed faces
            ok = bool(writer.AddShape(shape))
            if ok:
                writer.ComputeModel()
                ok = bool(writer.Write(str(path)))
    if not ok:
        raise G1PatchError(f"{path}: OpenCASCADE could not write the {kind.upper()} file")


#: Gregory patches whose interior pairs agree to this share of the model's size are bicubics
BICUBIC_RTOL = 1e-12


def _bicubic(patches: Any) -> bool:
    """Whether Gregory patches are bicubics already (every pair ``Fn_k = Fp_k``, to
    :data:`BICUBIC_RTOL`)."""
    from ..gregory import GregoryPatchSet

    if not isinstance(patches, GregoryPatchSet):
        return False
    points = patches.points
    extent = float(np.abs(points).max())
    return bool(np.abs(points[:, 12::2] - points[:, 13::2]).max() <= BICUBIC_RTOL * extent)


def _as_bicubics(patches: Any) -> PatchSet:
    """Gregory patches that are bicubics (:func:`_bicubic`) as Bézier patches: the same surface,
    exactly."""
    return PatchSet(patches.to_bezier_control(), "bezier").with_frame(patches.frame)


def _cad_method(target: Path, network: PatchNetwork, method: CadMethod) -> str:
    """What ``method`` means for ``network``: ``exact``, ``split4`` or ``fit``."""
    from ..gregory import GregoryPatchSet

    check_choice("method", method, CAD_METHODS)
    if isinstance(network.patches, PatchSet):
        return "exact"
    if method == "fit" or not isinstance(network.patches, GregoryPatchSet):
        if method == "split4":
            raise InputError(
                f"{target}: method 'split4' re-assembles Gregory networks; these patches are "
                f"{type(network.patches).__name__} (use method 'fit')"
            )
        return "fit"
    return "split4"


_ENTITY_END = re.compile(rb";[ \t\r]*\n(?=#\d)")
_REFERENCE = re.compile(rb"#(\d+)")
_NAMED_FACE = re.compile(rb"ADVANCED_FACE\('face (\d+)',\([^)]*\),#(\d+),")
_POLE_GRID = re.compile(rb"B_SPLINE_SURFACE_WITH_KNOTS\('[^']*',\d+,\d+,\(\((.*?)\)\),")
_BLANKS = re.compile(rb"\n[ \t\r\n\f\v]*")
#: significant digits of the coordinates :func:`compact_step` writes (OCC's writer: 12)
STEP_DIGITS = 15


def _step_reals(values: NDArray[np.float64]) -> list[bytes]:
    """STEP reals with :data:`STEP_DIGITS` significant digits, each with its decimal point (``1.``,
    ``1.E+20``)."""
    texts = (f"%.{STEP_DIGITS}G," * values.size % tuple(values.tolist())).encode().split(b",")[:-1]
    return [
        text if b"." in text else text.replace(b"E", b".E") if b"E" in text else text + b"."
        for text in texts
    ]


# : a file's 12-digit pole and the exact one agree to this share of the model's size
# (:func:`compact_step`)
STEP_MATCH_RTOL = 1e-10


def _face_nets(faces: BSplineFit | QuadFaces) -> list[NDArray[np.float64]]:
    """The world control net of every face, in face order (split4 quads: 4×4 single-span or 6×6)."""
    if isinstance(faces, BSplineFit):
        return list(faces.control)
    single, two = iter(faces.bezier.control), iter(faces.two_span.control)
    return [next(single) if one else next(two) for one in faces.single.tolist()]


def compact_step(
    path: Path, nets: Sequence[NDArray[np.float64]] = (), tolerance: float = 0.0
) -> None:
    """Rewrite a STEP file written by OCC: equal ``CARTESIAN_POINT`` entities become one, surface
    poles get :data:`STEP_DIGITS` digits, entities are numbered densely, without line breaks.

    OCC's writer gives every surface pole, every edge curve's pole and every vertex its own point
    entity, so a pole on a mesh edge is written once per face, once per edge curve and once per
    vertex: points with the same text (blanks removed) become the first of them. OCC writes 12
    significant digits, which leaves OCC's normals across Spot's small faces 7e-8° apart on reading
    back: the poles of face ``'face N'`` (its ``B_SPLINE_SURFACE_WITH_KNOTS``) are written from
    ``nets[N]`` (world poles, (nu, nv, 3)) with 15, where the file's value agrees with it within
    ``tolerance`` (so a point is only ever made more precise). The same B-rep; a split4 network's
    file is a third smaller.
    """
    text = path.read_bytes()
    start = text.index(b"\nDATA;") + len(b"\nDATA;")
    end = text.index(b"\nENDSEC;", start)
    # one pass each over the whole section: entity ends marked, line breaks removed, split
    entities = _BLANKS.sub(b"", _ENTITY_END.sub(b"\0", text[start:end].strip())).split(b"\0")
    entities[-1] = entities[-1].rstrip(b";")
    heads = [entity.partition(b"=") for entity in entities]
    bodies = {name.strip()[1:]: body.strip() for name, _, body in heads}
    first: dict[bytes, bytes] = {}
    # point number → the number of the first equal point
    canonical = {
        number: first.setdefault(body, number)
        for number, body in bodies.items()
        if body.startswith(b"CARTESIAN_POINT(")
    }
    points: list[bytes] = []  # every surface pole of a named face, as its canonical point …
    poles: list[NDArray[np.float64]] = []  # … and the exact net it belongs to
    for face, surface in _NAMED_FACE.findall(
        b"".join(body for body in bodies.values() if b"ADVANCED_FACE" in body)
    ):
        grid = _POLE_GRID.match(bodies.get(surface, b""))
        if grid is None or int(face) >= len(nets):
            continue
        rows = [_REFERENCE.findall(row) for row in grid.group(1).split(b"),(")]
        net = nets[int(face)]
        if [len(row) for row in rows] != [net.shape[1]] * net.shape[0]:
            continue
        points.extend(canonical[number] for row in rows for number in row)
        poles.append(np.asarray(net, dtype=np.float64).reshape(-1, 3))
    exact: dict[bytes, bytes] = {}
    if points:
        distinct = list(dict.fromkeys(points))
        where = {point: n for n, point in enumerate(distinct)}
        written = np.array(
            b",".join(bodies[point].split(b"(")[-1].rstrip(b")") for point in distinct).split(b","),
            dtype=np.float64,
        ).reshape(len(distinct), 3)
        pole = np.concatenate(poles)
        close = np.abs(written[[where[point] for point in points]] - pole).max(axis=1) <= tolerance
        chosen = {
            points[k]: k for k in np.flatnonzero(close).tolist()
        }  # the last matching pole of each point
        reals = _step_reals(pole[list(chosen.values())].reshape(-1))
        exact = {
            point: b"CARTESIAN_POINT('',(" + b",".join(reals[3 * n : 3 * n + 3]) + b"))"
            for n, point in enumerate(chosen)
        }
    kept = [
        (number, exact.get(number, body))
        for number, body in bodies.items()
        if canonical.get(number, number) == number
    ]
    renumber = {number: str(n).encode() for n, (number, _) in enumerate(kept, start=1)}
    renumber.update({number: renumber[point] for number, point in canonical.items()})
    parts = _REFERENCE.split(
        b"".join(b"#" + number + b"=" + body + b";\n" for number, body in kept)
    )
    parts[1::2] = [
        b"#" + renumber[number] for number in parts[1::2]
    ]  # every reference (and entity number) renumbered
    data = b"".join(parts)
    path.write_bytes(text[:start] + b"\n" + data.rstrip(b"\n") + text[end:])


def _split4_within(
    network: PatchNetwork,
    max_deviation: float,
    diagonal: float,
    fallback: bool,
    lap: Callable[[str], None],
) -> tuple[PatchNetwork, float, int, str] | str:
    """The split4 re-assembly of a Gregory network
    (:func:`~g1patch.construct.polynomial.split4_of_gregory`) with n = 1, 2, 3, …
    (:data:`REFINE_STEPS`) cells per patch side until its distance to the Gregory surface is at most
    ``max_deviation × diagonal`` (split4's stars differ from the Gregory fans near the vertices,
    over a cell's size), or a cut would make more than :data:`REFINE_QUADS` quads: ``(network,
    deviation, n, note)``. A cut that folds more sub-patches than n = 1 (small cells of a coarse
    cage can) is not taken; of those tried the closest one that does not, and the note says when it
    is above the bound. A network split4 cannot re-assemble raises, or with ``fallback`` returns the
    note for a fit (where only its cells cannot be, the fewer cells are kept)."""
    from ..construct.polynomial import split4_of_gregory, surface_deviation
    from ..continuity import folded_patches

    tried: list[
        tuple[bool, float, int, PatchNetwork]
    ] = []  # (folds more than n = 1, deviation, n, result)
    base_folds, allowed = 0, max_deviation * diagonal
    for refine in REFINE_STEPS:
        if refine > 1 and refine * refine * network.n_patches > REFINE_QUADS:
            break
        try:
            converted = split4_of_gregory(network, refine=refine)
        except (ConstructionError, MeshError) as error:
            if tried:  # the cells failed where the whole patches did not: keep those
                break
            if not fallback:
                raise
            return f"split4 could not re-assemble it ({error}): fitted"
        lap("split4")
        deviation = surface_deviation(network, converted)[1]
        folds = int(folded_patches(converted.patches).sum())
        base_folds = folds if refine == 1 else base_folds
        lap("deviation")
        tried.append((folds > base_folds, deviation, refine, converted))
        if deviation <= allowed and not tried[-1][0]:
            break
    _, deviation, refine, converted = min(tried, key=lambda attempt: attempt[:2])
    note = (
        ""
        if deviation <= allowed
        else (
            f"the re-assembly stays {deviation / diagonal:.2e} of the diagonal from the Gregory "
            "surface, above "
            f"--max-deviation {max_deviation:g}, at {refine} × {refine} cells per patch"
            + (" (finer cells folded)" if any(attempt[0] for attempt in tried) else "")
        )
    )
    return converted, deviation, refine, note


def export_cad(
    path: PathLike,
    network: PatchNetwork | PatchSet,
    *,
    format: CadFormat | None = None,
    tolerance: float | None = None,
    progress: Progress | None = None,
    g1_samples: int = G1_SAMPLES,
    method: CadMethod = "auto",
    max_deviation: float = DEVIATION_RTOL,
) -> ExportResult:
    """Write a network as a STEP or IGES B-rep, chosen by the extension (``.step .stp .iges .igs``).

    One B-spline face per patch, or per quad of a split4 network, sewn, a solid where the shells
    close; seams stay sharp edges. Polynomial patches are written exactly. A Gregory network goes
    by ``method`` (:data:`CAD_METHODS`): ``split4`` writes the polynomial re-assembly of its targets
    (exact G1 in CAD; its distance to the Gregory surface is the reported deviation), ``fit`` fits
    each patch within ``tolerance`` (default 1e-6 × the bounding-box diagonal; OCC then sees kinks),
    ``auto`` is split4 (seams kept: the network is cut open along them, both sides share each seam
    curve), or fit where split4 raises. The re-assembly lies within ``max_deviation`` × the
    bounding-box diagonal of the Gregory surface, by cutting each patch into n × n cells where
    needed (:func:`_split4_within`). The G1 angles of the written surfaces are
    measured by OCC on ``g1_samples`` points per shared edge (0: skip), seams apart.
    The extension and OCP are checked before anything is computed or written.
    """
    target = Path(path)
    kind = _format_of(target, format)
    occ = _occ()
    _check_patch_coordinates(
        target, network.patches if isinstance(network, PatchNetwork) else network
    )
    network = _as_network(network)
    if not (isinstance(g1_samples, (int, np.integer)) and (g1_samples == 0 or g1_samples >= 2)):
        raise InputError(f"g1_samples: expected 0 or an integer ≥ 2, got {g1_samples!r}")
    if not (isinstance(max_deviation, (int, float, np.floating)) and 0.0 < max_deviation < np.inf):
        raise InputError(
            f"max_deviation: expected a positive number (relative to the bounding-box diagonal), "
            f"got {max_deviation!r}"
        )
    chosen = _cad_method(target, network, method)
    if chosen != "fit" and not isinstance(network.patches, PatchSet) and _bicubic(network.patches):
        network, chosen = replace(network, patches=_as_bicubics(network.patches)), "exact"
    seconds: dict[str, float] = {}
    clock = time.perf_counter()
    doing = ["fitting the surfaces"]  # what OCC was doing, for a failure's message

    def lap(stage: str) -> None:
        nonlocal clock
        now = time.perf_counter()
        seconds[stage] = (
            seconds.get(stage, 0.0) + now - clock
        )  # split4 and deviation: every n tried
        clock = now
        doing[0] = _NEXT_STAGE.get(stage, stage)
        if progress is not None:
            progress(stage, 1, 1)

    diagonal = network.bounding_box_diagonal()
    _check_diagonal(target, diagonal)
    deviation, method_note, refine = 0.0, "", 0
    if chosen == "split4":
        converted = _split4_within(network, max_deviation, diagonal, method == "auto", lap)
        if isinstance(converted, str):
            chosen, method_note = "fit", converted
        else:
            network, deviation, refine, method_note = converted
    exact = isinstance(network.patches, PatchSet)
    fit_tolerance = _tolerance(tolerance, diagonal)
    quads = split4_quad_faces(network) if exact else None
    if quads is not None:  # one face per quad; `fit` is the finest group, for `spans`
        fit = _quad_groups(quads)[-1]
    elif exact:
        knots = bezier_knots(1)
        fit = BSplineFit(network.patches.convert("bezier").world_control(), knots, knots, 0.0)
    else:
        fit = fit_bspline_surfaces(network, fit_tolerance)
        deviation = fit.deviation
    lap("fit")
    sewing_tolerance = SEWING_RTOL * diagonal if diagonal > 0 else SEWING_RTOL
    for group in [fit] if quads is None else _quad_groups(quads):
        _check_fit(target, group, sewing_tolerance)
    with _occ_failures(target, doing):
        if quads is None:
            faces = _make_faces(occ, fit, 0.01 * sewing_tolerance, progress)
        else:
            faces = _make_quad_faces(occ, quads, 0.01 * sewing_tolerance, progress)
        lap("faces")
        sewn, sewn_faces, free_edges = _sew(occ, faces, sewing_tolerance)
        _check_sewn(target, sewn_faces)
        lap("sew")
        shape, volume = _solids(occ, sewn)
        solid = volume is not None
        lap("solid")
        valid = bool(occ.BRepCheck_Analyzer(shape).IsValid())
        lap("check")
        angles = (
            _occ_g1_angles(occ, sewn_faces, network, g1_samples, progress, quads is not None)
            if g1_samples
            else np.zeros((0, 0))
        )
        lap("g1")
        shared_patch, shared_edge = network.shared_edges()
        seam = network.seam[shared_patch, shared_edge]
        smooth = angles[~seam].max(axis=1) if angles.size else np.zeros(0)
        seam_angles = angles[seam] if angles.size else np.zeros(0)
        with atomic_path(target) as temporary, _step_options(sewn_faces, pcurves=quads is None):
            _write(occ, shape, temporary, kind)
            if kind == "step":
                nets = _face_nets(fit if quads is None else quads)
                compact_step(
                    temporary,
                    nets,
                    STEP_MATCH_RTOL * max(diagonal, max(float(np.abs(net).max()) for net in nets)),
                )
            file_bytes = temporary.stat().st_size
        lap("write")
    note = (
        "measured on the surfaces OpenCASCADE holds (its poles and knots, each face checked "
        "against its own evaluator)"
        if smooth.size
        else "not measured: g1_samples=0"
        if not g1_samples
        else "not measured: no shared edges but seams"
    )
    return ExportResult(
        path=target,
        format=kind,
        faces=len(faces),
        solid=solid,
        valid=valid,
        free_edges=free_edges,
        exact=exact,
        method=chosen,
        method_note=method_note,
        spans=len(np.unique(fit.knots_u)) - 1,
        refine=refine,
        fit_deviation=fit.deviation,
        fit_tolerance=0.0 if exact else fit_tolerance,
        sewing_tolerance=sewing_tolerance,
        max_g1_angle_deg=float(smooth.max()) if smooth.size else 0.0,
        mean_g1_angle_deg=float(smooth.mean()) if smooth.size else 0.0,
        seam_edges=int(seam.sum())
        // (2 if quads is not None else 1),  # a quad face's edge is two split4 halves
        seam_angle_min_deg=float(seam_angles.min()) if seam_angles.size else None,
        seam_angle_max_deg=float(seam_angles.max()) if seam_angles.size else None,
        volume=volume,
        deviation=deviation,
        relative_deviation=deviation / diagonal,
        file_bytes=file_bytes,
        g1_measured=bool(smooth.size),
        g1_note=note,
        seconds=seconds,
    )


def export_step(
    path: PathLike,
    network: PatchNetwork | PatchSet,
    *,
    tolerance: float | None = None,
    progress: Progress | None = None,
    g1_samples: int = G1_SAMPLES,
    method: CadMethod = "auto",
    max_deviation: float = DEVIATION_RTOL,
) -> ExportResult:
    """Write a STEP file (``.step`` / ``.stp``, AP214); see :func:`export_cad`."""
    return export_cad(
        path,
        network,
        format="step",
        tolerance=tolerance,
        progress=progress,
        g1_samples=g1_samples,
        method=method,
        max_deviation=max_deviation,
    )


def export_iges(
    path: PathLike,
    network: PatchNetwork | PatchSet,
    *,
    tolerance: float | None = None,
    progress: Progress | None = None,
    g1_samples: int = G1_SAMPLES,
    method: CadMethod = "auto",
    max_deviation: float = DEVIATION_RTOL,
) -> ExportResult:
    """Write an IGES file (``.iges`` / ``.igs``, B-rep mode); see :func:`export_cad`."""
    return export_cad(
        path,
        network,
        format="iges",
        tolerance=tolerance,
        progress=progress,
        g1_samples=g1_samples,
        method=method,
        max_deviation=max_deviation,
    )


# ----------------------------------------------------------------------------------- reading


class CadFace:
    """One face of a read shape: evaluate its surface (``BRepAdaptor_Surface``) at (u, v)."""

    def __init__(self, occ: SimpleNamespace, face: Any) -> None:
        self._occ = occ
        self.face = face
        self.surface = occ.BRepAdaptor_Surface(face, False)
        #: (u_min, u_max, v_min, v_max) of the underlying surface (not trimmed to the face)
        self.bounds = (
            self.surface.FirstUParameter(),
            self.surface.LastUParameter(),
            self.surface.FirstVParameter(),
            self.surface.LastVParameter(),
        )

    def evaluate(self, uv: ArrayLike) -> NDArray[np.float64]:
        """Points ``S(u, v)`` for ``uv`` of shape (K, 2), returned (K, 3)."""
        value = self.surface.Value
        params = np.asarray(uv, dtype=np.float64).reshape(-1, 2).tolist()
        return np.array([value(u, v).Coord() for u, v in params], dtype=np.float64).reshape(-1, 3)

    def normals(self, uv: ArrayLike) -> NDArray[np.float64]:
        """Unit normals ``±(S_u × S_v)/|…|`` (outwards for a face of an oriented solid), (K, 3)."""
        normals = _face_normals(
            self._occ, self.face, np.asarray(uv, dtype=np.float64).reshape(-1, 2)
        )
        length = np.linalg.norm(normals, axis=-1, keepdims=True)
        return np.divide(normals, length, out=np.zeros_like(normals), where=length > 0)

    def poles(self) -> NDArray[np.float64] | None:
        """The control net ``(nu, nv, 3)`` of a B-spline or Bézier surface, else None."""
        kind = self.surface.GetType()
        types = self._occ.GeomAbs_SurfaceType
        if kind == types.GeomAbs_BSplineSurface:
            surface = self.surface.BSpline()
        elif kind == types.GeomAbs_BezierSurface:
            surface = self.surface.Bezier()
        else:
            return None
        return np.array(
            [
                [surface.Pole(i, j).Coord() for j in range(1, surface.NbVPoles() + 1)]
                for i in range(1, surface.NbUPoles() + 1)
            ]
        )


class CadModel(NamedTuple):
    """A shape read from a CAD file and an evaluator per face (in ``TopExp_Explorer`` order)."""

    shape: Any
    faces: list[CadFace]


def read_cad_faces(path: PathLike) -> CadModel:
    """Read a STEP or IGES file (by extension) with OCC's readers into a shape and face
    evaluators."""
    source = Path(path)
    kind = _format_of(source, None)
    occ = _occ()
    if not source.is_file():
        raise FormatError(source, "no such file")
    with _occ_failures(source, ["reading the file"]), _quiet(occ):
        reader = occ.STEPControl_Reader() if kind == "step" else occ.IGESControl_Reader()
        status = reader.ReadFile(str(source))
        if status != occ.IFSelect_ReturnStatus.IFSelect_RetDone:
            raise FormatError(
                source, f"OpenCASCADE cannot read it as {kind.upper()} ({status.name})"
            )
        reader.TransferRoots()
        shape = reader.OneShape()
        faces = [CadFace(occ, face) for face in _faces_of(occ, shape) if not face.IsNull()]
    if not faces:
        raise FormatError(source, f"the {kind.upper()} file holds no faces")
    return CadModel(shape, faces)


def read_step_faces(path: PathLike) -> CadModel:
    """Read a STEP file (``STEPControl_Reader``): the shape and one evaluator per face."""
    if _format_of(Path(path), None) != "step":
        raise FormatError(
            path,
            f"expected a STEP file ({', '.join(CAD_FORMATS['step'])}), got {Path(path).suffix!r}",
        )
    return read_cad_faces(path)


def read_iges_faces(path: PathLike) -> CadModel:
    """Read an IGES file (``IGESControl_Reader``): the shape and one evaluator per face."""
    if _format_of(Path(path), None) != "iges":
        raise FormatError(
            path,
            f"expected an IGES file ({', '.join(CAD_FORMATS['iges'])}), got {Path(path).suffix!r}",
        )
    return read_cad_faces(path)


def file_g1_angles(
    path: PathLike, network: PatchNetwork, samples: int = G1_SAMPLES
) -> NDArray[np.float64]:
    """(E, samples) angles (degrees) between the OCC normals of a *read-back* CAD file's faces
    along every shared edge of ``network``, the network that was written (for a Gregory network
    exported by split4, its :func:`~g1patch.construct.polynomial.split4_of_gregory`): what a CAD
    user's system sees. Faces are matched to patches (or split4 quads) by their middle points
    (nearest, each face once); seams are included (``network.seam`` tells them apart)."""
    from scipy.spatial import cKDTree

    model = read_cad_faces(path)
    quads = split4_quad_faces(network) is not None
    middles = np.concatenate(
        [
            face.evaluate(
                np.array(
                    [
                        [
                            0.5 * (face.bounds[0] + face.bounds[1]),
                            0.5 * (face.bounds[2] + face.bounds[3]),
                        ]
                    ]
                )
            )
            for face in model.faces
        ]
    )
    centres = (
        network.patches.evaluate(np.array([[1.0, 1.0]]))[::4, 0]
        if quads
        else network.patches.evaluate(np.array([[0.5, 0.5]]))[:, 0]
    )
    distance, order = cKDTree(middles).query(centres)
    if len(model.faces) != len(centres) or len(set(order.tolist())) != len(centres):
        raise FormatError(
            path,
            f"its {len(model.faces)} faces do not match the network's {len(centres)} "
            f"{'quads' if quads else 'patches'} one to one",
        )
    faces = [model.faces[i].face for i in order.tolist()]
    return _occ_g1_angles(_occ(), faces, network, samples, None, quads)
