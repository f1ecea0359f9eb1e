"""The command line's commands: each reads its arguments and calls the public API
(:mod:`g1patch.api`), prints what it made and returns the exit code."""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from ..errors import FormatError

EXIT_OK, EXIT_CHECK_FAILED, EXIT_ERROR = 0, 1, 2
#: 128 + the signal's number, as a shell reports a process the signal ended
EXIT_SIGNAL_BASE = 128
EXIT_BROKEN_PIPE = EXIT_SIGNAL_BASE + 13


def camera_options(args: argparse.Namespace) -> dict[str, Any]:
    """The ``view`` and ``up`` of :func:`g1patch.render.render` from ``--view`` and ``--up``."""
    from ..errors import InputError

    if args.view == ["auto"]:
        return {"view": "auto", "up": args.up}
    try:
        elevation, azimuth = (float(value) for value in args.view)
    except ValueError:
        raise InputError(
            f"--view: expected auto or two angles ELEV AZIM in degrees, got {' '.join(args.view)!r}"
        ) from None
    return {"view": (elevation, azimuth), "up": args.up}


@contextmanager
def _progress(label: str, quiet: bool) -> Iterator[Callable[[int, int], None]]:
    """A ``progress(done, total)`` callback drawing a bar on stderr; silent when quiet or not a
    terminal."""
    if quiet or not sys.stderr.isatty():
        yield lambda done, total: None
        return
    from tqdm import tqdm

    bar = tqdm(total=None, desc=label, unit="", leave=False, file=sys.stderr)
    try:

        def update(done: int, total: int) -> None:
            bar.total = total
            bar.n = done
            bar.refresh()

        yield update
    finally:
        bar.close()


def _build(args: argparse.Namespace) -> int:
    from ..api import smooth
    from ..io.network_file import MAX_PATCHES

    if args.output.suffix.lower() != ".npz":
        raise FormatError(args.output, "a network file must end in .npz")
    with _progress("build", args.quiet) as progress:
        progress(0, 2)
        surface = smooth(
            args.mesh,
            args.shape,
            args.method,
            refine=args.refine,
            sharp_angle=args.sharp_angle,
            strict=args.strict,
            split=not args.no_split,
            tangents=args.tangents,
            twist=args.twist,
            normals=args.normals,
            max_memory=args.max_memory,
            max_patches=MAX_PATCHES,
            max_input_size=args.max_input_size,
            tolerance=args.tolerance,
        )
        progress(1, 2)
        # the file is written while the folds (or the whole check) are measured
        saving = surface.export(args.output, background=True)
        report = None
        if args.check:
            with _progress("check", args.quiet) as checking:
                report = surface.check(progress=checking)
            folds = report.folds
        else:
            folded = surface.folded_patches()
            folds = len(folded)
        saving.result()
        progress(2, 2)
    if surface.repairs:
        note = surface.mesh.repair_note if surface.mesh is not None else ""
        print(f"g1patch: {args.mesh}: {note}", file=sys.stderr)
    fallback = int(surface.provenance.get("fallback_vertices", "0"))
    vertices = "1 vertex" if fallback == 1 else f"{fallback} vertices"
    note = f"; {vertices} needed a fallback (degenerate or folded fans)" if fallback else ""
    faired = int(surface.provenance.get("faired_vertices", "0"))
    if faired:
        note += (
            f"; {_count(faired, 'vertex', 'vertices')} shaped as the faired limit-interpolating "
            "surface (the local rule folded or bent more there)"
        )
    print(
        f"built {surface.n_patches} {args.method} patches from {args.mesh} -> {args.output}, "
        f"{_count(folds, 'folded patch', 'folded patches') if folds else 'no folds'}{note}"
    )
    if folds:
        first = report.fold_locations[0][0] if report is not None else int(folded[0])
        hint = _fold_hint(surface, folds, first, args)
        print(f"g1patch: warning: {args.output}: {hint}", file=sys.stderr)
    if report is not None:
        print(report.summary())
    return _limit_distance_line(surface.provenance, args.output)


def _limit_distance_line(provenance: dict[str, str], output: Path) -> int:
    """Print how far a limit shape is from the exact Catmull–Clark limit (when it was measured):
    :data:`EXIT_CHECK_FAILED` and a warning when above the tolerance, else :data:`EXIT_OK`."""
    if "limit_distance" not in provenance:
        return EXIT_OK
    distance, tolerance = float(provenance["limit_distance"]), float(provenance["tolerance"])
    steps = int(provenance.get("tolerance_steps", "0"))
    added = f"; {_count(steps, 'Catmull–Clark step', 'Catmull–Clark steps')} added" if steps else ""
    print(
        f"distance to the Catmull–Clark limit: {distance:.2e} of the diagonal "
        f"(tolerance {tolerance:g}{added})"
    )
    if distance <= tolerance:
        return EXIT_OK
    why = provenance.get("tolerance_stop", "a larger --tolerance lets it through")
    print(
        f"g1patch: warning: {output}: {distance:.2e} is above the tolerance {tolerance:g}: {why}",
        file=sys.stderr,
    )
    return EXIT_CHECK_FAILED


def _count(count: int, one: str, many: str) -> str:
    """``'1 folded patch'``, ``'3 folded patches'``."""
    return f"{count:,} {one if count == 1 else many}"


def _fold_hint(surface: Any, folds: int, patch: int, args: argparse.Namespace) -> str:
    """How many patches fold, where the first is (its centre, in model units) and what to try:
    the Catmull–Clark limit of the cage (approximating: it folds only where the limit does), or a
    finer cage (``--refine 1``: the vertices interpolated are then nearer the limit's)."""
    import numpy as np

    centre = surface.network.patches.take(np.array([patch])).evaluate(np.array([[0.5, 0.5]]))
    where = ", ".join(f"{value:.4g}" for value in np.ravel(centre)[:3])
    tries = []
    if surface.shape != "limit":
        tries.append("--shape limit (the Catmull–Clark limit of the cage)")
    if not args.refine:
        tries.append("--refine 1 (a finer cage)")
    advice = f"; try {' or '.join(tries)}" if tries else ""
    which = "it is" if folds == 1 else "the first is"
    return (
        f"{_count(folds, 'patch folds', 'patches fold')} ({which} patch {patch}, near ({where}))"
        f"{advice}; `g1patch render {args.output} --zebra` shows them"
    )


def _fit(args: argparse.Namespace) -> int:
    from ..api import EXPORT_SUFFIXES, fit

    suffix = args.output.suffix.lower()
    if suffix not in (*EXPORT_SUFFIXES, ".html"):
        raise FormatError(
            args.output,
            f"unsupported extension {suffix or '(none)'!r}; expected one of "
            f"{', '.join((*EXPORT_SUFFIXES, '.html'))}",
        )
    with _progress("fit", args.quiet) as progress:
        progress(0, 2)
        result = fit(
            args.scan,
            tolerance=args.tolerance,
            faces=args.faces,
            layout=args.layout,
            method=args.method,
            max_input_size=args.max_input_size,
            sharp_angle=args.sharp_angle,
        )
        progress(1, 2)
        written = None
        if suffix == ".html":  # the viewer, with the distance to the scan
            result.view(args.output)
        else:
            written = result.surface.export(args.output)
        progress(2, 2)
    report = result.report
    if report.repairs:
        print(f"g1patch: {args.scan}: {', '.join(report.repairs)}", file=sys.stderr)
    from ..io.cad import ExportResult, RhinoResult

    corner_only = args.method == "corner"
    cad = written if isinstance(written, (ExportResult, RhinoResult)) else None
    if args.json:
        extra = {} if cad is None else {"cad": cad.to_dict()}
        print(json.dumps({**report.to_dict(), "output": str(args.output), **extra}))
    else:
        print(f"fitted {args.scan} -> {args.output}")
        print(report.summary())
        if isinstance(cad, ExportResult):  # what OpenCASCADE measured on the file written
            print(_cad_export_text(cad, corner_only))
        elif isinstance(cad, RhinoResult):
            print(cad.summary())
    return EXIT_OK if report.met else EXIT_CHECK_FAILED


def _check(args: argparse.Namespace) -> int:
    from ..api import as_network, check
    from ..continuity import SEAM_G0_RTOL

    network = as_network(args.surface)
    with _progress("check", args.quiet) as progress:
        report = check(network, samples=args.samples, progress=progress)
    fitted = _fit_rows(network.provenance)
    if args.json:
        print(json.dumps({**report.to_dict(), **{key: value for key, _, value in fitted}}))
    else:
        print(f"{args.surface} ({network.provenance.get('method', 'file')})")
        print(report.summary())
        for _, label, value in fitted:
            print(f"{label:<32}{value:.3e}")
    if args.max_angle is None:
        return EXIT_OK
    failures = []
    if not report.is_g1(args.max_angle):
        angle = max(report.max_edge_angle_deg, report.max_corner_angle_deg)
        failures.append(f"G1 angle {angle:.3e}° above {args.max_angle}°")
    if report.folds:
        patch, u, v = report.fold_locations[0]
        failures.append(
            f"{report.folds} folded patches (first: patch {patch} at (u, v) = ({u:.4g}, {v:.4g}))"
        )
    if report.degenerate_patches:
        failures.append(
            f"{report.degenerate_patches} degenerate patches (zero area or more than one collapsed "
            f"edge; first: patch {report.degenerate_patch_ids[0]})"
        )
    if not report.seams_closed():
        failures.append(
            f"seam G0 gap {report.seam_g0_max:.3e} (of bbox diag) above {SEAM_G0_RTOL:g}"
        )
    if not args.json:
        if failures:
            print("FAILED: " + "; ".join(failures), file=sys.stderr)
        else:
            seams = (
                f"; {report.seam_edges} seams (sharp on purpose) closed within {SEAM_G0_RTOL:g}"
                if report.seam_edges
                else ""
            )
            print(f"passed: G1 angles within {args.max_angle}°, no folds{seams}")
    return EXIT_CHECK_FAILED if failures else EXIT_OK


def _fit_rows(provenance: dict[str, str]) -> list[tuple[str, str, float]]:
    """The distances a network carries, (JSON key, label, value): to the exact Catmull–Clark limit
    (a limit shape's build) and to the scan (``g1patch fit``)."""
    rows = []
    if "limit_distance" in provenance:
        rows.append(
            (
                "limit_distance",
                "distance to limit (of diag)",
                float(provenance["limit_distance"]),
            )
        )
        rows.append(("tolerance", "tolerance (of diag)", float(provenance["tolerance"])))
    if "fit_distance" in provenance:
        rows.append(
            ("fit_distance", "distance to the scan (of diag)", float(provenance["fit_distance"]))
        )
        rows.append(
            ("fit_tolerance", "fit tolerance (of diag)", float(provenance["fit_tolerance"]))
        )
    return rows


def _export(args: argparse.Namespace) -> int:
    from ..api import CAD_SUFFIXES, EXPORT_SUFFIXES, RHINO_SUFFIX, as_network, export
    from ..errors import InputError
    from ..io.cad import ExportResult, RhinoResult

    suffix = args.output.suffix.lower()
    if suffix not in EXPORT_SUFFIXES or suffix == ".npz":
        written = ", ".join(s for s in EXPORT_SUFFIXES if s != ".npz")
        raise FormatError(
            args.output,
            f"unsupported extension {suffix or '(none)'!r}; expected one of {written}",
        )
    if args.json and suffix not in CAD_SUFFIXES:
        raise InputError(
            f"--json: reports CAD exports ({', '.join(CAD_SUFFIXES)}); {args.output} is not one"
        )
    network = as_network(args.network)
    fit_tolerance = (  # CAD files: --fit-tolerance is of the diagonal, the exporter's in units
        None if args.fit_tolerance is None else args.fit_tolerance * network.bounding_box_diagonal()
    )
    if suffix in CAD_SUFFIXES:
        with _progress("export", args.quiet or args.json) as progress:
            result = export(
                network,
                args.output,
                fit_tolerance=fit_tolerance,
                method=args.cad_method,
                max_deviation=args.max_deviation,
                progress=lambda stage, done, total: progress(done, total),
                verify=args.verify,
            )
        corner_only = network.provenance.get("method") == "corner"
        assert isinstance(result, ExportResult)
        if args.json:
            print(json.dumps({**result.to_dict(), "g1_by_design": not corner_only}))
            return EXIT_OK
        print(_cad_export_text(result, corner_only))
        return EXIT_OK
    if suffix == RHINO_SUFFIX:
        rhino = export(
            network,
            args.output,
            fit_tolerance=fit_tolerance,
            method=args.cad_method,
            max_deviation=args.max_deviation,
        )
        assert isinstance(rhino, RhinoResult)
        print(rhino.summary())
        return EXIT_OK
    if suffix == ".bpt":
        export(network, args.output)
        print(f"wrote {network.n_patches} Bézier patches -> {args.output}")
        return EXIT_OK
    from ..tessellate import choose_resolution, triangle_count

    resolution = args.resolution or choose_resolution(network.n_patches)
    export(network, args.output, resolution=resolution, force=args.force or args.resolution is None)
    print(f"wrote {triangle_count(network.n_patches, resolution)} triangles -> {args.output}")
    return EXIT_OK


def _cad_export_text(result: Any, corner_only: bool) -> str:
    """The lines ``export`` prints for a CAD file: faces, size, deviation, OCC's G1 angle, seams."""
    from ..tessellate import _size_text

    cells = (
        f", each Gregory patch as {result.refine} × {result.refine} quads"
        if result.refine > 1
        else ""
    )
    kind = {
        "exact": "exact B-spline faces",
        "split4": f"exact B-spline faces of the split4 re-assembly (exact G1{cells})",
        "fit": "fitted B-spline faces",
    }[result.method]
    lines = [
        f"wrote {result.faces} {kind}{', a closed solid' if result.solid else ''}, "
        f"{_size_text(result.file_bytes, 'B')} -> {result.path}",
        f"max deviation from the network's surface: {result.deviation:.3e} "
        f"({result.relative_deviation:.2e} of the "
        f"bbox diagonal{', split4 vs Gregory' if result.method == 'split4' else ''})",
    ]
    if result.method_note:
        lines.append(result.method_note)
    if result.g1_measured:
        lines.append(
            "max G1 angle across shared edges, measured on OpenCASCADE's surfaces: "
            f"{result.max_g1_angle_deg:.3e}°"
        )
    else:
        lines.append(f"G1 angle across shared edges: {result.g1_note}")
    if corner_only:
        lines.append(
            "the network is G1 at its corners only (method corner): its edges kink by design"
        )
    if result.seam_edges:
        angles = (
            ""
            if result.seam_angle_min_deg is None
            else f", their faces meet at {result.seam_angle_min_deg:.4g}° to "
            f"{result.seam_angle_max_deg:.4g}°"
        )
        lines.append(f"{result.seam_edges} seams kept as sharp edges{angles}")
    return "\n".join(lines)


def _render(args: argparse.Namespace) -> int:
    from ..api import Surface, as_network

    if args.output.suffix.lower() != ".png":
        raise FormatError(args.output, "pictures are written as .png")
    mode = "zebra" if args.zebra else "deviation" if args.deviation else "shaded"
    extra: dict[str, Any] = {}
    if args.distance is not None:
        from ..api import read_scan

        scan = read_scan(args.distance)
        mode, extra = "distance", {"scan": (scan.points, scan.triangles)}
    Surface(as_network(args.network)).render(
        args.output,
        mode,
        size=tuple(args.size),
        **camera_options(args),
        zoom=args.zoom,
        title=f"{args.network.name}: {mode}",
        **extra,
    )
    print(f"wrote {args.output}")
    return EXIT_OK


def _batch(args: argparse.Namespace) -> int:
    from ..batch import FAILED, BuildOptions, run_batch, summary_table

    if args.max_input_size is not None:  # every input within the cap before any work (exit 2)
        from ..batch.plan import collect_inputs
        from ..io.meshfile import check_input

        for source in collect_inputs(args.inputs):
            check_input(source, args.max_input_size)
    options = BuildOptions(
        method=args.method,
        shape=args.shape,
        refine=args.refine,
        sharp_angle=args.sharp_angle,
        strict=args.strict,
        max_input_size=args.max_input_size,
        tolerance=args.tolerance,
    )
    records = run_batch(
        args.inputs,
        args.out,
        formats=args.formats,
        options=options,
        scheduler=args.scheduler,
        workers=args.workers,
        progress=not args.quiet and sys.stderr.isatty(),
    )
    print(summary_table(records))
    failed = [record["name"] for record in records if record["status"] == FAILED]
    if failed:
        say(f"g1patch: {len(failed)} of {len(records)} files failed: {', '.join(failed)}")
    return EXIT_CHECK_FAILED if failed else EXIT_OK


def _view(args: argparse.Namespace) -> int:
    from ..api import Surface, as_network
    from ..tessellate import _size_text, choose_resolution, triangle_count

    network = as_network(args.network)
    resolution = (
        choose_resolution(network.n_patches) if args.resolution is None else args.resolution
    )
    path = Surface(network).view(
        args.output, resolution=resolution, force=args.force, **camera_options(args)
    )
    print(
        f"wrote a viewer of {network.n_patches} patches, "
        f"{triangle_count(network.n_patches, resolution)} triangles "
        f"({_size_text(Path(path).stat().st_size, 'B')}) -> {path}"
    )
    return EXIT_OK


def _demo(args: argparse.Namespace) -> int:
    from ..demo import run_demo

    written = run_demo(args.out, camera_options(args))
    print("\nwrote " + ", ".join(str(path) for path in written))
    return EXIT_OK


def _at_the_door(
    handler: Callable[[argparse.Namespace], int],
) -> Callable[[argparse.Namespace], int]:
    """``handler`` after :func:`.options.check_options` (every option in range, or exit 2)."""
    from .options import check_options

    def run(args: argparse.Namespace) -> int:
        for note in check_options(args):
            say(note)
        if hasattr(args, "view"):  # --view ELEV AZIM: finite, the elevation within (-90, 90)
            from ..render.camera import _check_view

            _check_view(camera_options(args)["view"])
        return handler(args)

    return run


#: the function of each command, its options checked first
HANDLERS: dict[str, Callable[[argparse.Namespace], int]] = {
    "build": _build,
    "fit": _fit,
    "check": _check,
    "export": _export,
    "render": _render,
    "view": _view,
    "demo": _demo,
    "batch": _batch,
}
HANDLERS = {name: _at_the_door(handler) for name, handler in HANDLERS.items()}


def say(line: str) -> None:
    """One line on stderr; nothing when stderr itself is gone."""
    try:
        print(line, file=sys.stderr, flush=True)
    except (OSError, ValueError):
        pass
