"""The ``g1patch`` command line: a thin shell over build, check, export, render, demo and batch.

Exit codes: 0 success; 1 a check failed (``check --max-angle``) or a file of a batch failed; 2 bad
input or any other error g1patch reports (one line on stderr naming the path given and the reason,
no partial output file); 130 interrupted (Ctrl-C, SIGINT), 143 terminated (SIGTERM), 129 hung up
(SIGHUP): one line on stderr, the output file not written and its temporary removed; 141 standard
output is a closed pipe (``g1patch check x.npz | head -1``): quietly, as a Unix tool killed by
SIGPIPE.

Outputs are written like a Unix tool's: mode ``0o666 & ~umask`` (see :mod:`g1patch.io.atomic`),
complete or not at all. Sizes are bounded by default: ``export`` to a mesh aims at about 2 M
triangles (:data:`g1patch.tessellate.TRIANGLE_BUDGET`), and an explicit ``--resolution`` above
:data:`g1patch.tessellate.MAX_TRIANGLES` triangles needs ``--force``.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import signal
import sys
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from . import __version__
from .errors import FormatError, G1PatchError
from .memory import tune_for_large_arrays

EXIT_OK, EXIT_CHECK_FAILED, EXIT_ERROR = 0, 1, 2
#: 128 + the signal's number, as a shell reports a process the signal ended
EXIT_SIGNAL_BASE = 128
EXIT_BROKEN_PIPE = EXIT_SIGNAL_BASE + 13

_EXAMPLES = {
    "build": """examples:
  g1patch build mesh.obj -o surface.npz                  # exact G1 (Gregory), the default
  g1patch build mesh.ply -o surface.npz --check          # and the report, while the file is written
  g1patch build cube.obj -o cube.npz --method corner     # the paper's corner-G1 patches
  g1patch build mesh.obj -o cad.npz --method split4      # exact G1, polynomial: exact in STEP
  g1patch build cage.obj -o limit.npz --shape limit      # the Catmull–Clark limit of a cage
  g1patch build cage.obj -o fine.npz --shape limit --refine 1
  g1patch build mesh.off -o old.npz --shape legacy --tangents chord  # the first rules""",
    "check": """examples:
  g1patch check surface.npz
  g1patch check teapot.bpt --json
  g1patch check surface.npz --max-angle 1e-9     # exit 1 unless exactly G1 and free of folds""",
    "export": """examples:
  g1patch export surface.npz -o surface.obj            # about 2 M triangles at most
  g1patch export surface.npz -o surface.obj --resolution 33
  g1patch export surface.npz -o surface.step            # exact G1 B-splines
  g1patch export surface.npz -o surface.step --json     # faces, bytes, deviation, OCC's angle
  g1patch export surface.npz -o patches.bpt             # Bezier patches (polynomial networks)""",
    "render": """examples:
  g1patch render surface.npz -o surface.png
  g1patch render surface.npz -o zebra.png --zebra
  g1patch render surface.npz -o kinks.png --deviation --size 1200 900""",
    "view": """examples:
  g1patch view surface.npz -o surface.html              # open it in a browser: no network needed
  g1patch view surface.npz -o coarse.html --resolution 5
  g1patch view teapot.bpt -o teapot.html""",
    "demo": """example:
  g1patch demo --out out""",
    "batch": """examples:
  g1patch batch meshes/ --out out                        # every .obj .ply .off, local cluster
  g1patch batch a.obj b.ply --out out --formats npz,step,obj --method split4
  g1patch batch meshes/ --out out --workers 2 -q         # again: skips what is up to date
  g1patch batch meshes/ --out out --scheduler tcp://127.0.0.1:8786   # an existing Dask cluster""",
}


def _parser() -> argparse.ArgumentParser:
    from .construct import ASSEMBLIES
    from .construct.corner import TWISTS
    from .io.cad import CAD_METHODS, DEVIATION_RTOL
    from .targets import SHAPES
    from .targets.local import NORMALS, TANGENTS

    methods = tuple(ASSEMBLIES)
    shapes = tuple(SHAPES)
    method_help = "; ".join(f"{a.name}: {a.summary}" for a in ASSEMBLIES.values())

    parser = argparse.ArgumentParser(
        prog="g1patch",
        description="Quad meshes to smooth bicubic patch networks, with a continuity report that "
        "proves it.",
        formatter_class=argparse.RawDescriptionHelpFormatter,
        epilog="run 'g1patch COMMAND --help' for a command's options and examples",
    )
    parser.add_argument("--version", action="version", version=f"g1patch {__version__}")
    commands = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    def command(name: str, text: str) -> argparse.ArgumentParser:
        sub = commands.add_parser(
            name,
            help=text,
            description=text,
            epilog=_EXAMPLES[name],
            formatter_class=argparse.RawDescriptionHelpFormatter,
        )
        sub.add_argument("-q", "--quiet", action="store_true", help="no progress bars")
        return sub

    build = command("build", "build a patch network from a quad mesh (OBJ, PLY, OFF)")
    build.add_argument("mesh", type=Path, help="input quad mesh")
    build.add_argument(
        "-o", "--output", type=Path, required=True, help="network file to write (.npz)"
    )
    build.add_argument(
        "--method",
        choices=methods,
        default=methods[0],
        help=method_help,
    )
    build.add_argument(
        "--shape",
        choices=shapes,
        default=shapes[0],
        help="interpolate: through the vertices, fitted normals, flexible tangent fans, "
        "curvature-carrying twists (default); limit: the Catmull–Clark limit of the mesh as a "
        "control cage; limit-interpolate: through the vertices as the limit of a solved cage; "
        "legacy: the first release's rules (fan normal, regular star, bilinear twist)",
    )
    build.add_argument(
        "--refine",
        type=int,
        default=0,
        metavar="N",
        help="Catmull–Clark steps before building (default: 0)",
    )
    build.add_argument(
        "--max-memory",
        type=_memory_size,
        metavar="SIZE",
        help="refuse a build estimated to need more (e.g. 8G, 500M; default: half the RAM)",
    )
    build.add_argument(
        "--tangents",
        choices=TANGENTS,
        default="arc",
        help="legacy shape: tangent lengths (default: arc)",
    )
    build.add_argument(
        "--twist",
        choices=TWISTS,
        default="bilinear",
        help="corner method, legacy shape: twist vectors (default: bilinear)",
    )
    build.add_argument(
        "--normals",
        choices=NORMALS,
        default="fan",
        help="corner method, legacy shape: vertex normals (default: fan)",
    )
    build.add_argument(
        "--no-split",
        action="store_true",
        help="reject faces that are not quads instead of splitting them",
    )
    build.add_argument(
        "--strict",
        action="store_true",
        help="refuse a mesh that needs repair (repeated vertices, non-manifold edges or vertices, "
        "inconsistent orientation, interior valence 2) instead of repairing it and saying how",
    )
    build.add_argument(
        "--sharp-angle",
        type=float,
        metavar="DEG",
        help="keep edges whose faces' normals differ by more than DEG degrees sharp (creases), and "
        "vertices with three such edges as corners (default: off; the file's own tags always "
        "count)",
    )
    build.add_argument(
        "--check",
        action="store_true",
        help="also measure the network's continuity, as 'g1patch check' does, while the file is "
        "written, "
        "and print the report",
    )

    check = command(
        "check", "measure G0/G1 continuity of a network (.npz) or a Bézier patch file (.bpt)"
    )
    check.add_argument("surface", type=Path, help="network (.npz) or patches (.bpt)")
    check.add_argument(
        "--max-angle",
        type=float,
        metavar="DEG",
        help="exit 1 if a G1 angle (seams aside) exceeds DEG degrees, the surface folds or a seam "
        "is open (G0)",
    )
    check.add_argument(
        "--samples", type=int, default=33, help="samples per edge, both ends included (default: 33)"
    )
    check.add_argument(
        "--json", action="store_true", help="print one JSON object instead of a table"
    )

    export = command(
        "export",
        "write a network as a triangle mesh (OBJ, PLY, STL), CAD file (STEP, IGES) or .bpt",
    )
    export.add_argument("network", type=Path, help="network file (.npz)")
    export.add_argument(
        "-o",
        "--output",
        type=Path,
        required=True,
        help="file to write; the extension picks the format",
    )
    export.add_argument(
        "--resolution",
        type=int,
        metavar="N",
        help="meshes: samples per patch side (default: 17, fewer above ~3 900 patches so that "
        "the mesh has at most ~2 M triangles, and at least 2)",
    )
    export.add_argument(
        "--force",
        action="store_true",
        help="meshes: allow a --resolution making more than 20 M triangles",
    )
    export.add_argument(
        "--fit-tolerance",
        type=float,
        metavar="REL",
        help="CAD: fit tolerance for rational patches, relative to the bbox diagonal (default: "
        "1e-6)",
    )
    export.add_argument(
        "--cad-method",
        choices=CAD_METHODS,
        default="auto",
        help="CAD, Gregory networks: split4 = re-assemble their targets polynomially (exact G1 in "
        "CAD), "
        "fit = fit each patch (closest, but CAD sees kinks); auto (default): split4, or fit where "
        "split4 cannot re-assemble the network",
    )
    export.add_argument(
        "--max-deviation",
        type=float,
        metavar="REL",
        default=DEVIATION_RTOL,
        help="CAD, split4 re-assembly of Gregory networks: cut each patch into n × n quads (n = "
        "2, 3, 4, 6, 8) "
        "until the exact surface lies within REL × the bbox diagonal of the network's (default: "
        "%(default)g)",
    )
    export.add_argument(
        "--json", action="store_true", help="CAD: print the figures as one JSON object"
    )

    render = command(
        "render", "draw a network as a PNG: shaded, zebra stripes or a map of G1 angles"
    )
    render.add_argument("network", type=Path, help="network (.npz) or patches (.bpt)")
    render.add_argument("-o", "--output", type=Path, required=True, help="PNG to write")
    mode = render.add_mutually_exclusive_group()
    mode.add_argument(
        "--zebra",
        action="store_true",
        help="reflection lines: they break where the surface creases",
    )
    mode.add_argument(
        "--deviation", action="store_true", help="colour every patch edge by its G1 angle"
    )
    render.add_argument(
        "--size",
        type=int,
        nargs=2,
        default=(900, 900),
        metavar=("W", "H"),
        help="pixels (default: 900 900)",
    )
    _camera_arguments(render)
    render.add_argument("--zoom", type=float, default=1.0, help="magnification (default: 1)")

    view = command(
        "view",
        "write an interactive viewer: one self-contained HTML page (shaded, zebra, G1 deviation)",
    )
    view.add_argument("network", type=Path, help="network (.npz) or patches (.bpt)")
    view.add_argument("-o", "--output", type=Path, required=True, help="HTML page to write")
    view.add_argument(
        "--resolution",
        type=int,
        metavar="R",
        help="samples per patch side (default: about 2 M triangles at most, 17 for small networks)",
    )
    view.add_argument(
        "--force", action="store_true", help="allow a page of more than 2 M triangles"
    )
    _camera_arguments(view)

    demo = command(
        "demo", "the paper's example: the cube smoothed by the paper's patches and by exact G1"
    )
    demo.add_argument(
        "--out",
        type=Path,
        default=Path("out"),
        help="folder for the OBJ and PNG files (default: out)",
    )
    _camera_arguments(demo)

    batch = command(
        "batch",
        "build, check and export many meshes on a Dask cluster, with a summary (needs "
        "g1patch[batch])",
    )
    batch.add_argument(
        "inputs",
        type=Path,
        nargs="+",
        metavar="INPUT",
        help="mesh files, or folders of them (.obj .ply .off)",
    )
    batch.add_argument(
        "--out",
        type=Path,
        required=True,
        help="folder for the outputs (<name>.<format>) and summary.json",
    )
    batch.add_argument(
        "--formats",
        default="npz",
        metavar="LIST",
        help="comma-separated formats to write per file: npz (network), obj, ply, stl, step, "
        "iges, bpt "
        "(default: npz)",
    )
    batch.add_argument(
        "--method", choices=methods, default=methods[0], help="as for build (default: %(default)s)"
    )
    batch.add_argument(
        "--shape", choices=shapes, default=shapes[0], help="as for build (default: %(default)s)"
    )
    batch.add_argument(
        "--refine", type=int, default=0, metavar="N", help="as for build (default: 0)"
    )
    batch.add_argument(
        "--sharp-angle", type=float, metavar="DEG", help="as for build (default: off)"
    )
    batch.add_argument(
        "--strict", action="store_true", help="as for build: refuse meshes that need repair"
    )
    where = batch.add_mutually_exclusive_group()
    where.add_argument(
        "--workers",
        type=int,
        metavar="N",
        help="worker processes of the embedded local cluster "
        "(default: one per core, at most one per file)",
    )
    where.add_argument(
        "--scheduler",
        metavar="ADDRESS",
        help="use the Dask cluster whose scheduler is at ADDRESS "
        "(e.g. tcp://127.0.0.1:8786) instead of a local one",
    )
    return parser


def _camera_arguments(parser: argparse.ArgumentParser) -> None:
    """``--view`` and ``--up`` of the commands that draw pictures."""
    parser.add_argument(
        "--view",
        nargs="+",
        default=["auto"],
        metavar=("auto|ELEV", "AZIM"),
        help="camera: elevation and azimuth in degrees, or auto (default): the front three-quarter "
        "view of the surface when it has a long axis (g1patch.render.auto_camera)",
    )
    parser.add_argument(
        "--up",
        choices=("auto", "x", "y", "z"),
        default="auto",
        help="the model's up axis (default: auto: z for a surface lying flat in the xy plane, "
        "else y as in OBJ files)",
    )


def _camera_options(args: argparse.Namespace) -> dict[str, Any]:
    """The ``view`` and ``up`` of :func:`g1patch.render.render` from ``--view`` and ``--up``."""
    from .errors import InputError

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


_SIZE_UNITS = {"": 1, "K": 10**3, "M": 10**6, "G": 10**9, "T": 10**12}


def _memory_size(text: str) -> int:
    """``8G``, ``8GB``, ``500M``, ``1.5T`` or a number of bytes, as bytes (decimal units)."""
    value = text.strip().upper().removesuffix("B")
    unit = value[-1:] if value[-1:] in _SIZE_UNITS else ""
    try:
        number = float(value[: len(value) - len(unit)])
    except ValueError:
        number = math.nan
    if not (math.isfinite(number) and number > 0):
        raise argparse.ArgumentTypeError(
            f"expected a size such as 8G, 500M or a number of bytes, got {text!r}"
        )
    return int(number * _SIZE_UNITS[unit])


def _build(args: argparse.Namespace) -> int:
    from .api import smooth
    from .io.network_file import MAX_PATCHES

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
        )
        progress(1, 2)
        # with --check the file is written while the check runs
        saving = surface.export(args.output, background=args.check)
        progress(2, 2)
    report = None
    if args.check:
        with _progress("check", args.quiet) as progress:
            report = surface.check(progress=progress)
        saving.result()
    if surface.repairs:
        print(f"g1patch: {args.mesh}: {surface.mesh.repair_note}", file=sys.stderr)  # type: ignore[union-attr]
    fallback = int(surface.provenance.get("fallback_vertices", "0"))
    vertices = "1 vertex" if fallback == 1 else f"{fallback} vertices"
    note = f"; {vertices} needed a fallback (degenerate or folded fans)" if fallback else ""
    print(
        f"built {surface.n_patches} {args.method} patches from {args.mesh} -> {args.output}{note}"
    )
    if report is not None:
        print(report.summary())
    return EXIT_OK


def _check(args: argparse.Namespace) -> int:
    from .api import as_network, check
    from .continuity import SEAM_G0_RTOL

    network = as_network(args.surface)
    with _progress("check", args.quiet) as progress:
        report = check(network, samples=args.samples, progress=progress)
    if args.json:
        print(json.dumps(report.to_dict()))
    else:
        print(f"{args.surface} ({network.provenance.get('method', 'file')})")
        print(report.summary())
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


def _export(args: argparse.Namespace) -> int:
    from .api import CAD_SUFFIXES, EXPORT_SUFFIXES, as_network, export
    from .errors import InputError
    from .io.cad import ExportResult

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
    if suffix in CAD_SUFFIXES:
        with _progress("export", args.quiet or args.json) as progress:
            fit_tolerance = (
                None
                if args.fit_tolerance is None
                else args.fit_tolerance * network.bounding_box_diagonal()
            )
            result = export(
                network,
                args.output,
                fit_tolerance=fit_tolerance,
                method=args.cad_method,
                max_deviation=args.max_deviation,
                progress=lambda stage, done, total: progress(done, total),
            )
        corner_only = network.provenance.get("method") == "corner"
        assert isinstance(result, ExportResult)
        if args.json:
            print(json.dumps({**result.to_dict(), "g1_by_design": not corner_only}))
            return EXIT_OK
        print(_cad_export_text(result, corner_only))
        return EXIT_OK
    if suffix == ".bpt":
        export(network, args.output)
        print(f"wrote {network.n_patches} Bézier patches -> {args.output}")
        return EXIT_OK
    from .tessellate import choose_resolution, triangle_count

    resolution = args.resolution or choose_resolution(network.n_patches)
    export(network, args.output, resolution=resolution, force=args.force or args.resolution is None)
    print(f"wrote {triangle_count(network.n_patches, resolution)} triangles -> {args.output}")
    return EXIT_OK


def _cad_export_text(result: Any, corner_only: bool) -> str:
    """The lines ``export`` prints for a CAD file: faces, size, deviation, OCC's G1 angle, seams."""
    from .tessellate import _size_text

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
    from .api import Surface, as_network

    if args.output.suffix.lower() != ".png":
        raise FormatError(args.output, "pictures are written as .png")
    mode = "zebra" if args.zebra else "deviation" if args.deviation else "shaded"
    Surface(as_network(args.network)).render(
        args.output,
        mode,
        size=tuple(args.size),
        **_camera_options(args),
        zoom=args.zoom,
        title=f"{args.network.name}: {mode}",
    )
    print(f"wrote {args.output}")
    return EXIT_OK


def _batch(args: argparse.Namespace) -> int:
    from .batch import FAILED, BuildOptions, run_batch, summary_table

    options = BuildOptions(
        method=args.method,
        shape=args.shape,
        refine=args.refine,
        sharp_angle=args.sharp_angle,
        strict=args.strict,
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
        _say(f"g1patch: {len(failed)} of {len(records)} files failed: {', '.join(failed)}")
    return EXIT_CHECK_FAILED if failed else EXIT_OK


def _view(args: argparse.Namespace) -> int:
    from .api import Surface, as_network
    from .tessellate import _size_text, choose_resolution, triangle_count

    network = as_network(args.network)
    resolution = (
        choose_resolution(network.n_patches) if args.resolution is None else args.resolution
    )
    path = Surface(network).view(
        args.output, resolution=resolution, force=args.force, **_camera_options(args)
    )
    print(
        f"wrote a viewer of {network.n_patches} patches, "
        f"{triangle_count(network.n_patches, resolution)} triangles "
        f"({_size_text(Path(path).stat().st_size, 'B')}) -> {path}"
    )
    return EXIT_OK


def _demo(args: argparse.Namespace) -> int:
    from .demo import run_demo

    written = run_demo(args.out, _camera_options(args))
    print("\nwrote " + ", ".join(str(path) for path in written))
    return EXIT_OK


class Terminated(KeyboardInterrupt):
    """SIGTERM or SIGHUP, raised in the main thread like Ctrl-C's KeyboardInterrupt, so that every
    ``finally`` and atomic write cleans up on the way out."""

    def __init__(self, signum: int) -> None:
        super().__init__(signal.Signals(signum).name)
        self.signum = signum


_SIGNAL_WORDS = {
    int(getattr(signal, name)): words
    for name, words in (("SIGINT", "interrupted"), ("SIGTERM", "terminated"), ("SIGHUP", "hung up"))
    if hasattr(signal, name)
}


def _raise_terminated(signum: int, frame: object) -> None:
    raise Terminated(signum)


@contextmanager
def _signal_handlers() -> Iterator[None]:
    """SIGTERM and SIGHUP raise :class:`Terminated` while the command runs (unless ignored, as under
    ``nohup``); the previous handlers come back afterwards. SIGINT keeps Python's
    KeyboardInterrupt."""
    installed: dict[int, Any] = {}
    try:
        for name in ("SIGTERM", "SIGHUP"):
            number = getattr(signal, name, None)
            if number is None:
                continue
            try:
                previous = signal.getsignal(number)
                if previous is signal.SIG_IGN:
                    continue
                signal.signal(number, _raise_terminated)
                installed[number] = previous
            except ValueError:  # not the main thread: leave the signals alone
                break
        yield
    finally:
        for number, previous in installed.items():
            signal.signal(number, previous if previous is not None else signal.SIG_DFL)


def _say(line: str) -> None:
    """One line on stderr; nothing when stderr itself is gone."""
    try:
        print(line, file=sys.stderr, flush=True)
    except (OSError, ValueError):
        pass


def _os_error_text(error: OSError) -> str:
    reason = (
        error.strerror
        or (os.strerror(error.errno) if error.errno else None)
        or str(error)
        or type(error).__name__
    )
    return (
        f"{os.fsdecode(error.filename)}: {reason}"
        if isinstance(error.filename, (str, bytes, os.PathLike))
        else reason
    )


def _quiet_stdout() -> None:
    """After EPIPE on stdout: point it at /dev/null, so that the interpreter's last flush is
    silent."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        os.close(devnull)
    except (OSError, ValueError, AttributeError):
        pass


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; returns the exit code (see the module docstring)."""
    tune_for_large_arrays()
    handlers = {
        "build": _build,
        "check": _check,
        "export": _export,
        "render": _render,
        "view": _view,
        "demo": _demo,
        "batch": _batch,
    }
    with _signal_handlers():
        try:
            args = _parser().parse_args(argv)
            code = handlers[args.command](args)
            sys.stdout.flush()  # a closed pipe shows here, not in the interpreter's exit
            return code
        except KeyboardInterrupt as interrupt:
            signum = int(getattr(interrupt, "signum", signal.SIGINT))
            _say(f"g1patch: {_SIGNAL_WORDS.get(signum, signal.Signals(signum).name)}")
            return EXIT_SIGNAL_BASE + signum
        except BrokenPipeError:
            _quiet_stdout()
            return EXIT_BROKEN_PIPE
        except G1PatchError as error:
            _say(f"g1patch: error: {error}")
            return EXIT_ERROR
        except OSError as error:
            _say(f"g1patch: error: {_os_error_text(error)}")
            return EXIT_ERROR
        except MemoryError as error:
            detail = f" ({error})" if str(error) else ""
            _say(
                f"g1patch: error: out of memory{detail}; try a lower --resolution, --samples or "
                "--size"
            )
            return EXIT_ERROR


if __name__ == "__main__":
    sys.exit(main())
