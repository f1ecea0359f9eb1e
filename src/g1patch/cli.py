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
import os
import signal
import sys
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from importlib import resources
from pathlib import Path
from typing import Any, Literal

import numpy as np

from . import __version__
from .errors import FormatError, G1PatchError
from .memory import tune_for_large_arrays

EXIT_OK, EXIT_CHECK_FAILED, EXIT_ERROR = 0, 1, 2
#: 128 + the signal's number, as a shell reports a process the signal ended
EXIT_SIGNAL_BASE = 128
EXIT_BROKEN_PIPE = EXIT_SIGNAL_BASE + 13
METHODS = ("gregory", "split4", "corner")
MESH_SUFFIXES = (".obj", ".ply", ".stl")
CAD_SUFFIXES = (".step", ".stp", ".iges", ".igs")

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
    from .construct.corner import TWISTS
    from .io.cad import CAD_METHODS, DEVIATION_RTOL
    from .targets.interpolate import SHAPES
    from .targets.local import NORMALS, TANGENTS

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
        choices=METHODS,
        default="gregory",
        help="gregory: exact G1, rational interiors (default); split4: exact G1 with polynomial "
        "bicubics, exact in STEP; corner: the paper's, G1 at corners only",
    )
    build.add_argument(
        "--shape",
        choices=SHAPES,
        default="interpolate",
        help="interpolate: through the vertices, fitted normals, flexible tangent fans, "
        "curvature-carrying "
        "twists (default); limit: the Catmull–Clark limit of the mesh as a control cage; "
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
        "--tolerance",
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
        "--method", choices=METHODS, default="gregory", help="as for build (default: gregory)"
    )
    batch.add_argument(
        "--shape", choices=SHAPES, default="interpolate", help="as for build (default: interpolate)"
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


def _load_surface(path: Path) -> Any:
    """The network ``check`` and ``render`` read: a network file (.npz, validated by
    :func:`load_network`) or Bézier patches (.bpt, validated by :func:`read_bpt`). Anything else,
    a missing file included, is one :class:`FormatError` saying what was expected instead."""
    from .io.bpt import read_bpt
    from .io.network_file import describe_file, load_network
    from .network import network_from_patch_points

    expects = (
        "check and render read a network file (.npz) written by g1patch build, "
        "or Bézier patches (.bpt)"
    )
    suffix = path.suffix.lower()
    if suffix == ".bpt":
        return network_from_patch_points(read_bpt(path), source=str(path))
    if suffix == ".npz":
        return load_network(path, expects=expects)
    if not path.exists():
        raise FormatError(path, "no such file")
    what = describe_file(path, b"")
    hint = (
        f" (make a network from it: g1patch build {path} -o {path.with_suffix('.npz')})"
        if suffix in MESH_SUFFIXES + (".off",)
        else ""
    )
    raise FormatError(path, f"not a network or patch file but {what}; {expects}{hint}")


def build_network(
    mesh: Any,
    method: str,
    *,
    shape: str = "interpolate",
    tangents: str = "arc",
    twist: str = "bilinear",
    normals: str = "fan",
    refine: int = 0,
) -> Any:
    """The network of ``mesh`` by ``method`` and ``shape`` (:func:`g1patch.build.build_network`).

    ``--method corner --shape legacy`` is the paper's construction as the first release built it,
    with its ``--twist`` and ``--normals`` options.
    """
    if method == "corner" and shape == "legacy" and not refine:
        from .construct.corner import build_corner_network

        return build_corner_network(mesh, tangents=tangents, twist=twist, normals=normals)  # type: ignore[arg-type]
    from .build import build_network as build

    return build(mesh, method, shape, tangents=tangents, refine=refine)  # type: ignore[arg-type]


def _build(args: argparse.Namespace) -> int:
    from .io.meshfile import read_mesh
    from .io.network_file import save_network, save_network_in_background
    from .mesh import strict_meshes

    if args.output.suffix.lower() != ".npz":
        raise FormatError(args.output, "a network file must end in .npz")
    with _progress("build", args.quiet) as progress:
        progress(0, 3)
        with strict_meshes(args.strict):
            mesh = read_mesh(args.mesh, split=not args.no_split, sharp_angle=args.sharp_angle)
        progress(1, 3)
        network = build_network(
            mesh,
            args.method,
            shape=args.shape,
            tangents=args.tangents,
            twist=args.twist,
            normals=args.normals,
            refine=args.refine,
        )
        progress(2, 3)
        if args.check:  # the file is written while the check runs
            saving = save_network_in_background(args.output, network)
        else:
            save_network(args.output, network)
        progress(3, 3)
    report = None
    if args.check:
        from .continuity import check

        with _progress("check", args.quiet) as progress:
            report = check(network, progress=progress)
        saving.result()
    if mesh.repairs:
        print(f"g1patch: {args.mesh}: {mesh.repair_note}", file=sys.stderr)
    fallback = int(network.provenance.get("fallback_vertices", "0"))
    note = (
        f"; {fallback} vertices needed a fallback (degenerate or folded fans)" if fallback else ""
    )
    print(
        f"built {network.n_patches} {args.method} patches from {args.mesh} -> {args.output}{note}"
    )
    if report is not None:
        print(report.summary())
    return EXIT_OK


def _check(args: argparse.Namespace) -> int:
    from .continuity import SEAM_G0_RTOL, check

    network = _load_surface(args.surface)
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
    suffix = args.output.suffix.lower()
    if suffix not in (*MESH_SUFFIXES, *CAD_SUFFIXES, ".bpt"):
        raise FormatError(
            args.output,
            f"unsupported extension {suffix or '(none)'!r}; expected one of "
            f"{', '.join((*MESH_SUFFIXES, *CAD_SUFFIXES, '.bpt'))}",
        )
    from .io.network_file import load_network

    network = load_network(args.network)
    if suffix in CAD_SUFFIXES:
        from .io.cad import export_cad

        with _progress("export", args.quiet or args.json) as progress:
            tolerance = (
                None if args.tolerance is None else args.tolerance * network.bounding_box_diagonal()
            )
            result = export_cad(
                args.output,
                network,
                tolerance=tolerance,
                method=args.cad_method,
                max_deviation=args.max_deviation,
                progress=lambda stage, done, total: progress(done, total),
            )
        corner_only = network.provenance.get("method") == "corner"
        if args.json:
            print(json.dumps({**result.to_dict(), "g1_by_design": not corner_only}))
            return EXIT_OK
        print(_cad_export_text(result, corner_only))
        return EXIT_OK
    if args.json:
        from .errors import InputError

        raise InputError(
            f"--json: reports CAD exports ({', '.join(CAD_SUFFIXES)}); {args.output} is not one"
        )
    if suffix == ".bpt":
        from .io.bpt import write_bpt
        from .patches import PatchSet

        if not isinstance(network.patches, PatchSet):
            raise FormatError(
                args.output,
                ".bpt holds polynomial Bézier patches; this network's patches are rational "
                "(export to .step instead)",
            )
        write_bpt(args.output, network.patches)
        print(f"wrote {network.n_patches} Bézier patches -> {args.output}")
        return EXIT_OK
    from .io.meshfile import write_triangles
    from .tessellate import choose_resolution, tessellate

    resolution = (
        choose_resolution(network.n_patches) if args.resolution is None else args.resolution
    )
    if args.resolution is not None:
        _check_export_size(network.n_patches, resolution, suffix, args.force)
    mesh = tessellate(network, resolution, force=True)
    write_triangles(args.output, mesh.points, mesh.triangles)
    print(f"wrote {len(mesh.triangles)} triangles, {len(mesh.points)} points -> {args.output}")
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


def _estimated_file_size(suffix: str, n_points: int, n_triangles: int) -> int:
    """Bytes of a triangle mesh file, about: OBJ ~60 bytes a point (shortest round-trip digits)
    and 3 indices a triangle; binary PLY 24 bytes a point, 13 a triangle; binary STL 50 a
    triangle."""
    if suffix == ".obj":
        return 60 * n_points + (3 * (len(str(max(n_points, 1))) + 1) + 2) * n_triangles
    if suffix == ".ply":
        return 24 * n_points + 13 * n_triangles
    return 84 + 50 * n_triangles


def _check_export_size(n_patches: int, resolution: int, suffix: str, force: bool) -> None:
    """Refuse (exit 2) an explicit ``--resolution`` above the triangle cap without ``--force``, with
    the sizes."""
    from .errors import InputError
    from .tessellate import MAX_TRIANGLES, _size_text, estimated_memory, triangle_count

    if resolution < 2:
        return  # tessellate names the bad resolution
    triangles = triangle_count(n_patches, resolution)
    if force or triangles <= MAX_TRIANGLES:
        return
    points = n_patches * (resolution - 1) ** 2
    largest = 1 + int((MAX_TRIANGLES / (2 * max(n_patches, 1))) ** 0.5)
    size = _size_text(_estimated_file_size(suffix, points, triangles), "B")
    memory = _size_text(estimated_memory(n_patches, resolution), "B")
    raise InputError(
        f"--resolution {resolution} on {n_patches} patches would write {_size_text(triangles)} "
        "triangles "
        f"(~{size}, ~{memory} of memory); use --force or a lower resolution "
        f"(at most {largest} stays within {_size_text(MAX_TRIANGLES)} triangles)"
    )


def _render(args: argparse.Namespace) -> int:
    from .render import render

    if args.output.suffix.lower() != ".png":
        raise FormatError(args.output, "pictures are written as .png")
    mode: Literal["shaded", "zebra", "deviation"] = (
        "zebra" if args.zebra else "deviation" if args.deviation else "shaded"
    )
    network = _load_surface(args.network)
    render(
        args.output,
        network,
        mode=mode,
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
    from .api import Surface
    from .tessellate import _size_text, choose_resolution, triangle_count

    network = _load_surface(args.network)
    resolution = (
        choose_resolution(network.n_patches) if args.resolution is None else args.resolution
    )
    path = Surface(network).view(
        args.output, resolution=resolution, force=args.force, **_camera_options(args)
    )
    print(
        f"wrote a viewer of {network.n_patches} patches, "
        f"{triangle_count(network.n_patches, resolution)} triangles "
        f"({_size_text(path.stat().st_size, 'B')}) -> {path}"
    )
    return EXIT_OK


def _demo(args: argparse.Namespace) -> int:
    from .build import build_gregory_network, build_network, build_split4_network
    from .construct.corner import build_corner_network
    from .continuity import check, format_reports
    from .io.meshfile import read_mesh, write_triangles
    from .patches import CORNER_PARAMETERS, PatchSet, polynomial_degree, unit
    from .render import render_side_by_side
    from .tessellate import tessellate

    camera = _camera_options(args)
    with resources.as_file(resources.files("g1patch") / "data" / "cube.obj") as cube_path:
        mesh = read_mesh(cube_path)
    corner = build_corner_network(mesh, tangents="arc", twist="coons")
    gregory = build_gregory_network(mesh)
    split4 = build_split4_network(mesh)
    limit = build_network(mesh, "gregory", shape="limit")
    print("The paper's example: the cube [-1, 1]^3, valence 3 at every corner, smoothed into a")
    print("sphere-like surface.\n")
    print("1. The paper's construction: bicubic Hermite patches whose corner tangents satisfy")
    print("   n^T p_u = n^T p_v = 0 (eq. 13), with S-/HS-patch (Coons) twists.")
    hermite = corner.patches
    assert isinstance(hermite, PatchSet)  # the corner construction makes Hermite bicubics
    normals = unit(np.cross(*hermite.tangents(CORNER_PARAMETERS)))[0]
    print("   Patch 0 (face 0), unit corner normals p_u x p_v:")
    for vertex, normal in zip(mesh.faces[0], normals, strict=True):
        print(f"     vertex {vertex}: ({normal[0]:+.6f}, {normal[1]:+.6f}, {normal[2]:+.6f})")
    diagonal, anti = hermite.diagonal_polynomials()
    print(
        f"   Degrees of its diagonal and anti-diagonal: {int(polynomial_degree(diagonal)[0])} and "
        f"{int(polynomial_degree(anti)[0])} (S-/HS closure |C| = "
        f"{np.linalg.norm(hermite.closure()[0]):.1e})."
    )
    print("2. g1patch's default: the interpolating Gregory network, G1 along every edge.")
    print(
        "3. g1patch's polynomial option: 2x2 bicubic pieces per quad, G1 everywhere, exact in CAD."
    )
    print(
        "4. The cube as a subdivision cage: the Catmull–Clark limit (what a SubD modeller shows), "
        "exactly G1.\n"
    )
    reports = [check(network) for network in (corner, gregory, split4, limit)]
    corner_report, gregory_report, split4_report, limit_report = reports
    print(
        format_reports(
            reports,
            [
                "1. paper (corner G1)",
                "2. Gregory (exact G1)",
                "3. split4 (exact G1)",
                "4. limit (exact G1)",
            ],
        )
    )
    radius = np.linalg.norm(gregory.patches.evaluate_grid(np.linspace(0, 1, 17)), axis=-1)
    limit_radius = np.linalg.norm(limit.patches.evaluate_grid(np.linspace(0, 1, 17)), axis=-1)
    exact = max(report.max_edge_angle_deg for report in reports[1:])
    print(
        "\nThe paper's conditions hold at the corners (angle ~1e-14°) but its patches crease "
        "along every"
    )
    print(
        f"edge by {corner_report.max_edge_angle_deg:.1f}°; the other three are G1 everywhere (max "
        f"{exact:.1e}°)."
    )
    print(
        "The interpolating Gregory cube is a sphere: radius "
        f"{radius.min():.4f}..{radius.max():.4f} (√3 = 1.7321);"
    )
    print(
        "the limit surface lies inside the cage: radius "
        f"{limit_radius.min():.4f}..{limit_radius.max():.4f}."
    )

    args.out.mkdir(parents=True, exist_ok=True)
    written = []
    for name, network in (
        ("cube_corner", corner),
        ("cube_gregory", gregory),
        ("cube_split4", split4),
        ("cube_limit", limit),
    ):
        surface = tessellate(network, 33)
        write_triangles(args.out / f"{name}.obj", surface.points, surface.triangles)
        written.append(args.out / f"{name}.obj")
    titles = [
        "paper: corner G1 (creased)",
        "Gregory (exact G1)",
        "split4 (exact G1, polynomial)",
        "Catmull–Clark limit (exact G1)",
    ]
    for mode in ("zebra", "deviation"):
        path = args.out / f"cube_{mode}.png"
        render_side_by_side(
            path,
            [corner, gregory, split4, limit],
            titles,
            mode=mode,
            size=(2400, 640),
            **camera,
            reports=reports if mode == "deviation" else None,
        )
        written.append(path)
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
