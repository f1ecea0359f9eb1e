"""OpenCASCADE's side of CAD export and import: loading OCP, making faces, sewing, solids, writing.

OCP is imported only inside :func:`_occ`; without it the caller gets :class:`MissingDependencyError`
naming the extra. Exceptions raised inside OCP become :class:`OpenCascadeError`
(:func:`_occ_failures`). In STEP every face is named after its index (``'face 12'``), or after its
group and index (``'body 12'``), coloured by its group's colour through an XCAF document (AP214
styled items) and, for faces that are whole surfaces, written without parameter-space curves
(:func:`_step_options`).
"""

from __future__ import annotations

import importlib
import os
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from contextvars import ContextVar
from pathlib import Path
from types import SimpleNamespace
from typing import Any, Literal, NamedTuple

import numpy as np
from numpy.typing import NDArray

from ...errors import ConstructionError, FormatError, G1PatchError, MissingDependencyError
from .bspline import BSplineFit, QuadFaces

PathLike = str | os.PathLike[str]
CadFormat = Literal["step", "iges"]
#: file extensions of each format
CAD_FORMATS: dict[CadFormat, tuple[str, ...]] = {
    "step": (".step", ".stp"),
    "iges": (".iges", ".igs"),
}
#: ``progress(stage, done, total)``; stages: split4, deviation, fit, faces, sew, solid, check, g1,
#: write
Progress = Callable[[str, int, int], None]


class OpenCascadeError(ConstructionError):
    """OpenCASCADE failed on the geometry: an exception raised inside OCP, or a face its sewing
    dropped."""


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
    "Quantity": ("Quantity_Color", "Quantity_TypeOfColor"),
    "STEPCAFControl": ("STEPCAFControl_Writer",),
    "STEPConstruct": ("STEPConstruct",),
    "STEPControl": ("STEPControl_AsIs", "STEPControl_Reader", "STEPControl_Writer"),
    "TCollection": ("TCollection_ExtendedString", "TCollection_HAsciiString"),
    "TDocStd": ("TDocStd_Document",),
    "TopAbs": ("TopAbs_FACE", "TopAbs_REVERSED", "TopAbs_SHELL", "TopAbs_SOLID"),
    "TopExp": ("TopExp_Explorer",),
    "TopoDS": ("TopoDS", "TopoDS_Compound"),
    "XCAFDoc": ("XCAFDoc_ColorType", "XCAFDoc_DocumentTool"),
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
        for printer, level in zip(printers, levels, strict=True):
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
    for i, (value, count) in enumerate(zip(values.tolist(), counts.tolist(), strict=True), 1):
        array.SetValue(i, value)
        mults.SetValue(i, count)
    return array, mults


def _make_faces(
    occ: SimpleNamespace, fit: BSplineFit, face_tolerance: float, progress: Progress | None
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
            make_face(
                surface(poles, knots_u, knots_v, mults_u, mults_v, 3, 3), face_tolerance
            ).Face()
        )
        if progress is not None and (n + 1) % 256 == 0:
            progress("faces", n + 1, count)
    return faces


def _make_quad_faces(
    occ: SimpleNamespace, quads: QuadFaces, face_tolerance: float, progress: Progress | None
) -> list[Any]:
    """One face per quad, in quad order: single-span ones from ``quads.bezier``, the rest
    two-span."""
    faces: list[Any] = [None] * len(quads.single)
    for rows, group in (
        (np.flatnonzero(quads.single), quads.bezier),
        (np.flatnonzero(~quads.single), quads.two_span),
    ):
        if rows.size:
            made = _make_faces(occ, group, face_tolerance, progress)
            for row, face in zip(rows.tolist(), made, strict=True):
                faces[row] = face
    return faces


def _sew(
    occ: SimpleNamespace, faces: Sequence[Any], sewing_tolerance: float
) -> tuple[Any, list[Any], int]:
    """Sewn shape, the sewn face of every input face, number of free edges."""
    sewing = occ.BRepBuilderAPI_Sewing(sewing_tolerance)
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


def _format_of(path: Path, wanted: CadFormat | None) -> CadFormat:
    suffix = path.suffix.lower()
    for name, suffixes in CAD_FORMATS.items():
        if suffix in suffixes and wanted in (None, name):
            return name
    allowed = CAD_FORMATS[wanted] if wanted else sum(CAD_FORMATS.values(), ())
    raise FormatError(
        path, f"unsupported extension {path.suffix!r}; expected one of {', '.join(allowed)}"
    )


def _name_step_faces(
    occ: SimpleNamespace, writer: Any, faces: Sequence[Any], names: Sequence[str]
) -> None:
    """Name the ``ADVANCED_FACE`` of each of ``faces`` by ``names`` (``'face 12'``, ``'body 12'``:
    the patch, or the quad of a split4 network, it was made from)."""
    process = writer.WS().TransferWriter().FinderProcess()
    for face, name in zip(faces, names, strict=True):
        entity = occ.STEPConstruct.FindEntity_s(process, face)
        if entity is not None and hasattr(entity, "SetName"):
            entity.SetName(occ.TCollection_HAsciiString(name))


def _step_text(name: str) -> str:
    """``name`` as a STEP string OCC writes verbatim: printable ASCII without quote or
    backslash, anything else ``_``."""
    return "".join(c if " " <= c <= "~" and c not in "'\\" else "_" for c in name)


def _coloured_step_writer(
    occ: SimpleNamespace, shape: Any, faces: Sequence[Any], colours: NDArray[np.float64]
) -> Any:
    """A ``STEPCAFControl_Writer`` and the XCAF document it writes: ``shape`` with each of
    ``faces`` whose row of ``colours`` (F, 3) is not NaN given that surface colour (sRGB, the
    numbers of the file's ``COLOUR_RGB``)."""
    document = occ.TDocStd_Document(occ.TCollection_ExtendedString("XmlOcaf"))
    shapes = occ.XCAFDoc_DocumentTool.ShapeTool_s(document.Main())
    palette = occ.XCAFDoc_DocumentTool.ColorTool_s(document.Main())
    label = shapes.AddShape(shape, False)
    srgb = occ.Quantity_TypeOfColor.Quantity_TOC_sRGB
    surface = occ.XCAFDoc_ColorType.XCAFDoc_ColorSurf
    for n in np.flatnonzero(~np.isnan(colours).any(axis=1)).tolist():
        sub = shapes.AddSubShape(label, faces[n])
        if not sub.IsNull():
            palette.SetColor(sub, occ.Quantity_Color(*colours[n].tolist(), srgb), surface)
    return occ.STEPCAFControl_Writer(), document


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
    """What export_cad asks of the STEP writer beyond the shape (:func:`_step_options`): the
    faces, their names and colours ((F, 3) sRGB, NaN rows uncoloured; None: none), pcurves."""

    faces: Sequence[Any]
    pcurves: bool
    names: Sequence[str] = ()
    colours: NDArray[np.float64] | None = None


#: outside :func:`_step_options`: no faces named, edges with pcurves
_PLAIN_STEP = _StepOptions((), True)
_STEP_OPTIONS: ContextVar[_StepOptions] = ContextVar("_STEP_OPTIONS")


@contextmanager
def _step_options(
    faces: Sequence[Any],
    pcurves: bool,
    groups: tuple[Sequence[str], NDArray[np.float64]] | None = None,
) -> Iterator[None]:
    """For the :func:`_write` calls inside: name ``faces`` after their index (``'face N'``), or by
    ``groups`` (names (F,) and colours (F, 3), NaN rows uncoloured; :func:`_step_text` makes the
    names STEP text) and colour them; with ``pcurves`` False, write the edges without
    parameter-space curves."""
    if groups is None:
        names: Sequence[str] = [f"face {n}" for n in range(len(faces))]
        colours = None
    else:
        names = [_step_text(name) for name in groups[0]]
        colours = groups[1] if not np.isnan(groups[1]).all() else None
    token = _STEP_OPTIONS.set(_StepOptions(faces, pcurves, names, colours))
    try:
        yield
    finally:
        _STEP_OPTIONS.reset(token)


def _write(occ: SimpleNamespace, shape: Any, path: Path, kind: CadFormat) -> None:
    """Write ``shape``. In STEP the faces of :func:`_step_options` are named (IGES faces carry no
    names here) and, where it gives colours, coloured (an XCAF document written by
    ``STEPCAFControl_Writer``); without its ``pcurves`` the edges carry no parameter-space
    curves (``write.surfacecurve.mode`` 0): every face written here is a whole B-spline surface, its
    edges the iso-lines u, v ∈ {0, 1}, which a reader rebuilds exactly."""
    options = _STEP_OPTIONS.get(_PLAIN_STEP)
    done = occ.IFSelect_ReturnStatus.IFSelect_RetDone
    with _quiet(occ):
        if kind == "step":
            # the writer is made before the setting: the first writer of a process initialises
            # the STEP settings to their defaults (so a file written first had its pcurves back)
            if options.colours is None:
                writer = step = occ.STEPControl_Writer()
            else:
                writer, document = _coloured_step_writer(occ, shape, options.faces, options.colours)
                step = writer.ChangeWriter()
            with _static(occ, "write.surfacecurve.mode", 1 if options.pcurves else 0):
                if options.colours is None:
                    ok = writer.Transfer(shape, occ.STEPControl_AsIs) == done
                else:
                    ok = bool(writer.Transfer(document, occ.STEPControl_AsIs))
            if ok:
                _name_step_faces(occ, step, options.faces, options.names)
                ok = writer.Write(str(path)) == done
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
