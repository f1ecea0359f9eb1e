"""The export entry point: :func:`export_cad` (and :func:`export_step`, :func:`export_iges`) runs
the stages (method, faces, sewing, solid, check, G1 angles, write) and reports them in an
:class:`ExportResult`."""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, NamedTuple, TypedDict, Unpack

import numpy as np
from numpy.typing import NDArray

from ...errors import InputError
from ...mesh.groups import FaceGroups
from ...network import PatchNetwork, network_from_patch_points
from ...patches import PatchSet
from ..atomic import atomic_path
from .bspline import (
    BSplineFit,
    QuadFaces,
    _fit_tolerance,
    _quad_groups,
    bezier_knots,
    fit_bspline_surfaces,
    split4_quad_faces,
)
from .guards import _check_diagonal, _check_fit, _check_patch_coordinates, _check_sewn
from .measure import G1_SAMPLES, _occ_g1_angles
from .method import (
    DEVIATION_RTOL,
    CadMethod,
    _as_bicubics,
    _bicubic,
    _cad_method,
    _split4_within,
)
from .opencascade import (
    CadFormat,
    PathLike,
    Progress,
    _format_of,
    _make_faces,
    _make_quad_faces,
    _occ,
    _occ_failures,
    _sew,
    _solids,
    _step_options,
    _volume,
    _write,
)
from .read import CadModel, _model_g1_angles, read_cad_faces
from .step_text import STEP_MATCH_RTOL, _face_nets, compact_step
from .step_write import QuadBrep, quad_brep, write_quad_step

#: sewing tolerance, relative to the bounding-box diagonal: shared boundaries coincide to rounding
#: (exact export, ~1e-16) or bit for bit (fitted export); mesh edges are many orders longer.
SEWING_RTOL = 1e-7

#: faces up to which a STEP file written directly (:mod:`~g1patch.io.cad.step_write`) is read back
#: by OpenCASCADE to check it and measure its G1 angles (~2.5 ms and ~150 kB a face: 8,192 faces
#: 20 s, 1.2 GB; Spot's 17,568 quads 60–75 s); above, the file's poles are the network's own and
#: nothing is measured unless asked
VERIFY_FACES = 10_000
#: the confusion accuracy a directly written STEP file states (OCC's default, 1e-7 model units)
STEP_UNCERTAINTY = 1e-7

#: the stage export_cad enters after each lap, for a failure's message
_NEXT_STAGE = {
    "brep": "writing the file",
    "read": "checking the shape",
    "split4": "measuring the deviation",
    "deviation": "fitting the surfaces",
    "fit": "making the faces",
    "faces": "sewing",
    "sew": "making solids",
    "solid": "checking the shape",
    "check": "measuring G1 angles",
    "g1": "writing the file",
}


@dataclass(frozen=True, repr=False)
class ExportResult:
    """What was written and how good it is (distances in model units, angles in degrees)."""

    path: Path
    format: CadFormat
    faces: int
    #: every sewn shell closed and made a solid
    solid: bool
    #: BRepCheck_Analyzer's verdict on the written shape (a directly written STEP file: on the
    #: file read back; not read back above :data:`VERIFY_FACES` faces: True, and ``g1_note`` says
    #: so)
    valid: bool
    free_edges: int
    #: polynomial patches written exactly (their Bézier control nets)
    exact: bool
    #: how the faces were made: ``exact`` (polynomial patches, or Gregory patches that are
    #: bicubics), ``split4`` (a Gregory network's targets re-assembled polynomially, then exact) or
    #: ``fit`` (fitted B-splines)
    method: str
    #: why ``auto`` fitted a Gregory network without seams (split4 failed on it), else ""
    method_note: str
    #: knot spans per direction (1 for exact export; 2 where split4 quads keep their two spans)
    spans: int
    #: cells per patch side of the split4 re-assembly (1: one quad per patch; n: n × n, face
    #: ``r = f n² + a n + b`` covers cell (a, b) of patch f), 0 for other methods
    refine: int
    #: max |surface − patch| of the fit, measured on a grid twice as fine as its samples; 0.0 when
    #: exact
    fit_deviation: float
    #: the fit's bound on that (``fit_tolerance`` of :func:`export_cad`, model units); 0.0 when
    #: exact
    fit_tolerance: float
    sewing_tolerance: float
    #: G1 angles of the exported surfaces on shared edges but seams, measured by OCC (max and mean
    #: of per-edge max)
    max_g1_angle_deg: float
    mean_g1_angle_deg: float
    #: seams (edges sharp on purpose), each one sharp B-rep edge, and the range of the angle
    #: between their faces' OCC normals over all samples (None without seams or measurements)
    seam_edges: int
    seam_angle_min_deg: float | None
    seam_angle_max_deg: float | None
    #: OCC's volume of the solid (BRepGProp::VolumeProperties), None when no solid was made or a
    #: directly written file was not read back
    volume: float | None
    #: max distance of the written surface from the network's own surface (model units): 0 when
    #: exact, the fit deviation when fitted, the foot-point distance to the Gregory surface for
    #: split4
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


def _as_network(network: PatchNetwork | PatchSet) -> PatchNetwork:
    if isinstance(network, PatchNetwork):
        return network
    if isinstance(network, PatchSet):
        return network_from_patch_points(network)
    raise InputError(
        f"network: expected a PatchNetwork or a PatchSet, got {type(network).__name__}"
    )


class CadSurfaces(NamedTuple):
    """The B-spline surfaces a network is written as (:func:`cad_surfaces`): ``fit`` one face per
    patch, or ``quads`` one per split4 quad (then ``fit`` is their finest group), in world
    coordinates; the network they come from, the ``method`` taken and its note, the distance to
    the network (model units), the re-assembly's cells per side and the fit tolerance."""

    network: PatchNetwork
    method: str
    method_note: str
    fit: BSplineFit
    quads: QuadFaces | None
    diagonal: float
    deviation: float
    exact: bool
    refine: int
    fit_tolerance: float

    def nets(self) -> list[NDArray[np.float64]]:
        """The world control net of every face, in face order."""
        return _face_nets(self.fit if self.quads is None else self.quads)

    @property
    def groups(self) -> FaceGroups | None:
        """Each face's group (:attr:`PatchNetwork.groups`: of its patch, or of a split4 quad's
        first sub-patch), None where the network has none."""
        groups = self.network.groups
        if groups is None or self.quads is None:
            return groups
        return groups.take(np.arange(0, len(groups), 4))

    def labels(self) -> tuple[list[str], NDArray[np.float64]] | None:
        """Each face's name, ``'NAME n'`` in a group and ``'face n'`` without, and colour (F, 3),
        NaN without; None where the network has no groups (every face ``'face n'``)."""
        groups = self.groups
        if groups is None:
            return None
        names = [groups.label(n, "face") for n in range(len(groups))]
        colours = np.where(groups.ids[:, None] >= 0, groups.colours[groups.ids], np.nan)
        return names, colours

    def knots(self) -> list[tuple[NDArray[np.float64], NDArray[np.float64]]]:
        """The (u, v) knot vectors of every face, in face order."""
        if self.quads is None:
            return [(self.fit.knots_u, self.fit.knots_v)] * len(self.fit.control)
        one, two = self.quads.bezier, self.quads.two_span
        return [
            (one.knots_u, one.knots_v) if single else (two.knots_u, two.knots_v)
            for single in self.quads.single.tolist()
        ]


def cad_surfaces(
    target: Path,
    network: PatchNetwork,
    *,
    method: CadMethod = "auto",
    max_deviation: float = DEVIATION_RTOL,
    fit_tolerance: float | None = None,
    lap: Callable[[str], None] = lambda stage: None,
) -> CadSurfaces:
    """The surfaces of :func:`export_cad` (its docstring says how ``method`` chooses), the same for
    every CAD format; ``lap(stage)`` after the ``split4``, ``deviation`` and ``fit`` stages."""
    if not (isinstance(max_deviation, (int, float, np.floating)) and 0.0 < max_deviation < np.inf):
        raise InputError(
            f"max_deviation: expected a positive number (relative to the bounding-box diagonal), "
            f"got {max_deviation!r}"
        )
    chosen = _cad_method(target, network, method)
    if chosen != "fit" and not isinstance(network.patches, PatchSet) and _bicubic(network.patches):
        network, chosen = replace(network, patches=_as_bicubics(network.patches)), "exact"
    diagonal = network.bounding_box_diagonal()
    _check_diagonal(target, diagonal)
    deviation, method_note, refine = 0.0, "", 0
    hanging = network.hanging
    if method == "auto" and hanging is not None and len(hanging):
        method_note = (
            f"refined locally ({len(hanging)} hanging edges), which split4 cannot re-assemble: "
            "fitted (build with --method split4 for an exact polynomial file)"
        )
    if chosen == "split4":
        converted = _split4_within(network, max_deviation, diagonal, method == "auto", lap)
        if isinstance(converted, str):
            chosen, method_note = "fit", converted
        else:
            network, deviation, refine, method_note = converted
    exact = isinstance(network.patches, PatchSet)
    fit_tolerance = _fit_tolerance(fit_tolerance, diagonal)
    quads = split4_quad_faces(network) if exact else None
    if quads is not None:  # one face per quad; `fit` is the finest group, for `spans`
        fit = _quad_groups(quads)[-1]
    elif isinstance(network.patches, PatchSet):  # exact
        knots = bezier_knots(1)
        fit = BSplineFit(network.patches.convert("bezier").world_control(), knots, knots, 0.0)
    else:
        fit = fit_bspline_surfaces(network, fit_tolerance)
        deviation = fit.deviation
    lap("fit")
    return CadSurfaces(
        network, chosen, method_note, fit, quads, diagonal, deviation, exact, refine, fit_tolerance
    )


def export_cad(
    path: PathLike,
    network: PatchNetwork | PatchSet,
    *,
    format: CadFormat | None = None,
    fit_tolerance: float | None = None,
    progress: Progress | None = None,
    g1_samples: int = G1_SAMPLES,
    method: CadMethod = "auto",
    max_deviation: float = DEVIATION_RTOL,
    verify: bool | None = None,
) -> ExportResult:
    """Write a network as a STEP or IGES B-rep, chosen by the extension (``.step .stp .iges .igs``).

    One B-spline face per patch, or per quad of a split4 network, sewn, a solid where the shells
    close; seams stay sharp edges. Polynomial patches are written exactly. A Gregory network goes
    by ``method`` (:data:`CAD_METHODS`): ``split4`` writes the polynomial re-assembly of its targets
    (exact G1 in CAD; its distance to the Gregory surface is the reported deviation), ``fit`` fits
    each patch within ``fit_tolerance`` (model units, default 1e-6 × the bounding-box diagonal; OCC
    then sees kinks), ``auto`` is split4 (seams kept: the network is cut open along them, both
    sides share each seam curve), or fit where split4 raises. The re-assembly lies within
    ``max_deviation`` × the bounding-box diagonal of the Gregory surface, by cutting each patch
    into n × n cells where needed (:func:`~g1patch.io.cad.method._split4_within`). The G1 angles
    of the written surfaces are measured by OCC on ``g1_samples`` points per shared edge (0: skip),
    seams apart. The extension and OCP are checked before anything is computed or written.

    The quads of a split4 network go to STEP without OCC's modelling (:mod:`~g1patch.io.cad.
    step_write`: the B-rep read off the network, seconds for a million quads); OCC then reads the
    file back to check it and measure its angles when ``verify`` (default: up to
    :data:`VERIFY_FACES` faces).
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

    made = cad_surfaces(
        target,
        network,
        method=method,
        max_deviation=max_deviation,
        fit_tolerance=fit_tolerance,
        lap=lap,
    )
    network, fit, quads, diagonal = made.network, made.fit, made.quads, made.diagonal
    sewing_tolerance = SEWING_RTOL * diagonal if diagonal > 0 else SEWING_RTOL
    for group in [fit] if quads is None else _quad_groups(quads):
        _check_fit(target, group, sewing_tolerance)
    brep = quad_brep(quads, network) if kind == "step" and quads is not None else None
    if brep is not None:
        lap("brep")
        return _direct_step(target, made, brep, sewing_tolerance, g1_samples, verify, lap, seconds)
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
        with (
            atomic_path(target) as temporary,
            _step_options(sewn_faces, pcurves=quads is None, groups=made.labels()),
        ):
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
    return _result(
        made,
        target=target,
        kind=kind,
        faces=len(faces),
        solid=solid,
        valid=valid,
        free_edges=free_edges,
        volume=volume,
        file_bytes=file_bytes,
        sewing_tolerance=sewing_tolerance,
        angles=angles,
        measured="measured on the surfaces OpenCASCADE holds (its poles and knots, each face "
        "checked against its own evaluator)",
        unmeasured="",
        g1_samples=g1_samples,
        seconds=seconds,
    )


def _result(
    made: CadSurfaces,
    *,
    target: Path,
    kind: CadFormat,
    faces: int,
    solid: bool,
    valid: bool,
    free_edges: int,
    volume: float | None,
    file_bytes: int,
    sewing_tolerance: float,
    angles: NDArray[np.float64],
    measured: str,
    unmeasured: str,
    g1_samples: int,
    seconds: dict[str, float],
) -> ExportResult:
    """The :class:`ExportResult` of the surfaces ``made`` written as ``faces`` faces: the G1
    figures from ``angles`` ((E, K) along every shared edge of the network, seams apart), said
    ``measured`` or, with none, why not (``unmeasured``, else from ``g1_samples``)."""
    network, fit = made.network, made.fit
    shared_patch, shared_edge = network.shared_edges()
    seam = network.seam[shared_patch, shared_edge]
    smooth = angles[~seam].max(axis=1) if angles.size else np.zeros(0)
    seam_angles = angles[seam] if angles.size else np.zeros(0)
    note = (
        measured
        if smooth.size
        else unmeasured
        or (
            "not measured: g1_samples=0"
            if not g1_samples
            else "not measured: no shared edges but seams"
        )
    )
    return ExportResult(
        path=target,
        format=kind,
        faces=faces,
        solid=solid,
        valid=valid,
        free_edges=free_edges,
        exact=made.exact,
        method=made.method,
        method_note=made.method_note,
        spans=len(np.unique(fit.knots_u)) - 1,
        refine=made.refine,
        fit_deviation=fit.deviation,
        fit_tolerance=0.0 if made.exact else made.fit_tolerance,
        sewing_tolerance=sewing_tolerance,
        max_g1_angle_deg=float(smooth.max()) if smooth.size else 0.0,
        mean_g1_angle_deg=float(smooth.mean()) if smooth.size else 0.0,
        seam_edges=int(seam.sum())
        // (2 if made.quads is not None else 1),  # a quad face's edge is two split4 halves
        seam_angle_min_deg=float(seam_angles.min()) if seam_angles.size else None,
        seam_angle_max_deg=float(seam_angles.max()) if seam_angles.size else None,
        volume=volume,
        deviation=made.deviation,
        relative_deviation=made.deviation / made.diagonal,
        file_bytes=file_bytes,
        g1_measured=bool(smooth.size),
        g1_note=note,
        seconds=seconds,
    )


def _direct_step(
    target: Path,
    made: CadSurfaces,
    brep: QuadBrep,
    sewing_tolerance: float,
    g1_samples: int,
    verify: bool | None,
    lap: Callable[[str], None],
    seconds: dict[str, float],
) -> ExportResult:
    """:func:`export_cad`'s STEP file of a split4 network's quads, written directly
    (:func:`~g1patch.io.cad.step_write.write_quad_step`) and, if ``verify`` (None: up to
    :data:`VERIFY_FACES` faces), read back by OCC: its validity, volume and G1 angles."""
    labels = made.labels()
    names, colours = (None, None) if labels is None else labels
    with atomic_path(target) as temporary:
        write_quad_step(
            temporary,
            brep,
            names,
            colours,
            STEP_UNCERTAINTY,
            target.stem,
            time.strftime("%Y-%m-%dT%H:%M:%S"),
        )
        file_bytes = temporary.stat().st_size
    lap("write")
    faces = len(brep.corners)
    checked = faces <= VERIFY_FACES if verify is None else bool(verify)
    solid = bool(brep.closed.all())
    valid, volume, angles = True, None, np.zeros((0, 0))
    if checked:
        occ = _occ()
        with _occ_failures(target, ["reading the file back"]):
            model: CadModel = read_cad_faces(target)
            lap("read")
            valid = bool(occ.BRepCheck_Analyzer(model.shape).IsValid())
            volume = _read_volume(occ, model.shape) if solid else None
            lap("check")
            if g1_samples:
                angles = _model_g1_angles(model, made.network, g1_samples)
            lap("g1")
    unmeasured = (
        "not measured: not read back (verify=False; the file's poles are the network's own)"
        if verify is False
        else f"not measured: {faces:,} faces, more than the {VERIFY_FACES:,} read back (the "
        "file's poles are the network's own; verify=True reads it)"
        if not checked
        else ""
    )
    return _result(
        made,
        target=target,
        kind="step",
        faces=faces,
        solid=solid,
        valid=valid,
        free_edges=brep.free_edges,
        volume=volume,
        file_bytes=file_bytes,
        sewing_tolerance=sewing_tolerance,
        angles=angles,
        measured="measured on the file read back by OpenCASCADE",
        unmeasured=unmeasured,
        g1_samples=g1_samples,
        seconds=seconds,
    )


def _read_volume(occ: Any, shape: Any) -> float:
    """The volume of the solids of a shape read back (each counted positive)."""
    total, explorer = 0.0, occ.TopExp_Explorer(shape, occ.TopAbs_SOLID)
    while explorer.More():
        total += abs(_volume(occ, explorer.Current()))
        explorer.Next()
    return total


class ExportOptions(TypedDict, total=False):
    """The keywords of :func:`export_cad` that :func:`export_step` and :func:`export_iges` pass on
    (all but ``format``), with its defaults."""

    fit_tolerance: float | None
    progress: Progress | None
    g1_samples: int
    method: CadMethod
    max_deviation: float
    verify: bool | None


def export_step(
    path: PathLike, network: PatchNetwork | PatchSet, **options: Unpack[ExportOptions]
) -> ExportResult:
    """Write a STEP file (``.step`` / ``.stp``, AP214); ``options`` (:class:`ExportOptions`) as
    for :func:`export_cad`."""
    return export_cad(path, network, format="step", **options)


def export_iges(
    path: PathLike, network: PatchNetwork | PatchSet, **options: Unpack[ExportOptions]
) -> ExportResult:
    """Write an IGES file (``.iges`` / ``.igs``, B-rep mode); ``options`` (:class:`ExportOptions`)
    as for :func:`export_cad`."""
    return export_cad(path, network, format="iges", **options)
