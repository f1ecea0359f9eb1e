"""The command line's arguments: every command's options, help and examples, choices from the
registries (so ``--help`` cannot drift from what the library does)."""

from __future__ import annotations

import argparse
import math
from pathlib import Path

from .. import __version__

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
  g1patch render surface.npz -o kinks.png --deviation --size 1200 900
  g1patch render part.npz -o off.png --distance scan.stl   # a fit's distance to its scan""",
    "view": """examples:
  g1patch view surface.npz -o surface.html              # open it in a browser: no network needed
  g1patch view surface.npz -o coarse.html --resolution 5
  g1patch view teapot.bpt -o teapot.html""",
    "fit": """examples:
  g1patch fit scan.stl -o part.step                 # within 1e-3 of the diagonal, exact G1
  g1patch fit scan.ply -o part.npz --tolerance 2e-4 --json
  g1patch fit scan.obj -o part.step --faces 4000     # a layout of about 4,000 quads
  g1patch fit scan.obj -o part.npz --layout quads.obj   # your own quad layout near the scan
  g1patch fit scan.ply -o fit.html                  # the viewer: the distance to the scan""",
    "demo": """example:
  g1patch demo --out out""",
    "batch": """examples:
  g1patch batch meshes/ --out out                        # every .obj .ply .off .stl, local cluster
  g1patch batch a.obj b.ply --out out --formats npz,step,obj --method split4
  g1patch batch meshes/ --out out --workers 2 -q         # again: skips what is up to date
  g1patch batch meshes/ --out out --scheduler tcp://127.0.0.1:8786   # an existing Dask cluster""",
}


def _sharp_angle(text: str) -> float | None:
    """``--sharp-angle``: degrees in (0, 180), or ``off``."""
    if text.strip().lower() == "off":
        return None
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected degrees or 'off', got {text!r}") from None
    if not (math.isfinite(value) and 0 < value < 180):
        raise argparse.ArgumentTypeError(f"expected degrees between 0 and 180, got {text!r}")
    return value


def build_parser() -> argparse.ArgumentParser:
    from ..build import DEFAULT_TOLERANCE
    from ..construct import ASSEMBLIES
    from ..construct.corner import TWISTS
    from ..fitting import FIT_SHARP_ANGLE
    from ..io.cad import CAD_METHODS, DEVIATION_RTOL
    from ..targets import SHAPES
    from ..targets.local import NORMALS, TANGENTS

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

    build = command("build", "build a patch network from a quad mesh (OBJ, PLY, OFF, STL)")
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
        "--tolerance",
        type=float,
        default=DEFAULT_TOLERANCE,
        metavar="REL",
        help="limit shapes: the largest distance from the exact Catmull–Clark limit, a fraction "
        "of the bounding-box diagonal; the cage takes more Catmull–Clark steps until it holds "
        f"(default: {DEFAULT_TOLERANCE:g}; exit 1 when the memory budget stops it first)",
    )
    build.add_argument(
        "--max-memory",
        type=memory_size,
        metavar="SIZE",
        help="refuse a build estimated to need more (e.g. 8G, 500M; default: half the RAM)",
    )
    input_size_argument(build)
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

    fit = command(
        "fit",
        "fit an exact-G1 surface to a dense triangle mesh (a scan: OBJ, PLY, OFF, STL) within a "
        "tolerance",
    )
    fit.add_argument("scan", type=Path, help="the triangle (or polygon) mesh to fit")
    fit.add_argument(
        "-o",
        "--output",
        type=Path,
        required=True,
        help="file to write: .npz (network), .step/.iges/.3dm (CAD), .obj/.ply/.stl (triangles), "
        ".html (the viewer, with the distance to the scan)",
    )
    fit.add_argument(
        "--tolerance",
        type=float,
        default=1e-3,
        metavar="REL",
        help="two-way distance to the scan, a fraction of its bounding-box diagonal (99.9%% "
        "of the scan's points within it of the surface, all of the surface within it of the "
        "scan); the layout is refined where it is off until it holds (default: 1e-3; exit 1 "
        "when not met)",
    )
    fit.add_argument(
        "--faces", type=int, metavar="N", help="quads of the layout (default: from the tolerance)"
    )
    fit.add_argument(
        "--layout",
        type=Path,
        metavar="QUADS",
        help="your own quad mesh near the scan (its topology is the cage's) instead of Instant "
        "Meshes'",
    )
    fit.add_argument(
        "--method",
        choices=methods,
        default="split4",
        help="the exact-G1 assembly (default: split4, polynomial: the CAD file is the surface)",
    )
    fit.add_argument(
        "--sharp-angle",
        type=_sharp_angle,
        default=FIT_SHARP_ANGLE,
        metavar="DEG",
        help="scan edges whose triangles turn by more than DEG degrees are features: creases of "
        "the surface, edges of the STEP solid (default: "
        f"{FIT_SHARP_ANGLE:g}, a CAD part's edges and none of an organic scan's; 'off': none)",
    )
    input_size_argument(fit)
    fit.add_argument("--json", action="store_true", help="print the report as one JSON object")

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
        "--verify",
        action=argparse.BooleanOptionalAction,
        default=None,
        help="STEP of a split4 network: have OpenCASCADE read the file back to check it and "
        "measure its G1 angles (default: up to 10,000 faces; --no-verify: never)",
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
    mode.add_argument(
        "--distance",
        type=Path,
        metavar="SCAN",
        help="colour the surface by its distance to the triangles of SCAN (a mesh file: what "
        "'g1patch fit' fitted), of the scan's diagonal",
    )
    render.add_argument(
        "--size",
        type=int,
        nargs=2,
        default=(900, 900),
        metavar=("W", "H"),
        help="pixels (default: 900 900)",
    )
    camera_arguments(render)
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
    camera_arguments(view)

    demo = command(
        "demo", "the paper's example: the cube smoothed by the paper's patches and by exact G1"
    )
    demo.add_argument(
        "--out",
        type=Path,
        default=Path("out"),
        help="folder for the OBJ and PNG files (default: out)",
    )
    camera_arguments(demo)

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
        help="mesh files, or folders of them (.obj .ply .off .stl)",
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
        "--tolerance",
        type=float,
        default=DEFAULT_TOLERANCE,
        metavar="REL",
        help=f"as for build (default: {DEFAULT_TOLERANCE:g})",
    )
    batch.add_argument(
        "--strict", action="store_true", help="as for build: refuse meshes that need repair"
    )
    input_size_argument(batch)
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


def input_size_argument(parser: argparse.ArgumentParser) -> None:
    """``--max-input-size`` of the commands that read meshes."""
    from ..io.meshfile import MAX_INPUT_BYTES

    parser.add_argument(
        "--max-input-size",
        type=memory_size,
        metavar="SIZE",
        help="refuse a mesh file larger than SIZE before reading it (e.g. 500M, 4G; default: "
        f"{MAX_INPUT_BYTES // 10**9}G); only regular files are read",
    )


def camera_arguments(parser: argparse.ArgumentParser) -> None:
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


_SIZE_UNITS = {"": 1, "K": 10**3, "M": 10**6, "G": 10**9, "T": 10**12}


def memory_size(text: str) -> int:
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
