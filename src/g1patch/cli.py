"""The ``g1patch`` command line: a thin shell over build, check, export and demo.

Exit codes: 0 success; 1 a check failed (``check --max-angle``); 2 bad input or any other
error g1patch reports (one line on stderr, no partial output file).
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Sequence
from importlib import resources
from pathlib import Path

import numpy as np

from . import __version__
from .errors import FormatError, G1PatchError

EXIT_OK, EXIT_CHECK_FAILED, EXIT_ERROR = 0, 1, 2

_EXAMPLES = {
    "build": "examples:\n  g1patch build mesh.obj -o surface.npz\n  g1patch build cube.obj -o cube.npz --tangents chord --twist coons",
    "check": "examples:\n  g1patch check surface.npz\n  g1patch check teapot.bpt --json\n  g1patch check surface.npz --max-angle 1e-9   # exit 1 if not G1",
    "export": "examples:\n  g1patch export surface.npz -o surface.obj --resolution 33",
    "demo": "example:\n  g1patch demo --out out",
}


def _parser() -> argparse.ArgumentParser:
    from .construct.corner import NORMALS, TANGENTS, TWISTS

    parser = argparse.ArgumentParser(
        prog="g1patch",
        description="Quad meshes to smooth bicubic patch networks, with a continuity report.",
        formatter_class=argparse.RawDescriptionHelpFormatter,
        epilog="run 'g1patch COMMAND --help' for a command's options and examples",
    )
    parser.add_argument("--version", action="version", version=f"g1patch {__version__}")
    commands = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    def command(name: str, text: str) -> argparse.ArgumentParser:
        return commands.add_parser(
            name, help=text, description=text, epilog=_EXAMPLES[name], formatter_class=argparse.RawDescriptionHelpFormatter
        )

    build = command("build", "build a patch network from a quad mesh (OBJ, PLY, OFF)")
    build.add_argument("mesh", type=Path, help="input quad mesh")
    build.add_argument("-o", "--output", type=Path, required=True, help="network file to write (.npz)")
    build.add_argument("--method", choices=("corner",), default="corner", help="construction (default: corner, the paper's)")
    build.add_argument("--tangents", choices=TANGENTS, default="arc", help="corner tangent lengths (default: arc)")
    build.add_argument("--twist", choices=TWISTS, default="bilinear", help="twist vectors (default: bilinear)")
    build.add_argument("--normals", choices=NORMALS, default="fan", help="vertex normals (default: fan)")
    build.add_argument("--no-split", action="store_true", help="reject faces that are not quads instead of splitting them")

    check = command("check", "measure G0/G1 continuity of a network (.npz) or a Bézier patch file (.bpt)")
    check.add_argument("surface", type=Path, help="network (.npz) or patches (.bpt)")
    check.add_argument("--max-angle", type=float, metavar="DEG", help="exit 1 if a G1 angle exceeds DEG degrees")
    check.add_argument("--samples", type=int, default=33, help="samples per edge, both ends included (default: 33)")
    check.add_argument("--json", action="store_true", help="print one JSON object instead of a table")

    export = command("export", "tessellate a network into a watertight triangle mesh (OBJ, PLY, STL)")
    export.add_argument("network", type=Path, help="network file (.npz)")
    export.add_argument("-o", "--output", type=Path, required=True, help="mesh file to write")
    export.add_argument("--resolution", type=int, default=17, help="samples per patch side (default: 17)")

    demo = command("demo", "the paper's example: the cube smoothed into a sphere-like surface")
    demo.add_argument("--out", type=Path, default=Path("out"), help="folder for the OBJ and PNG (default: out)")
    return parser


def _load_surface(path: Path):  # type: ignore[no-untyped-def]
    from .io.bpt import read_bpt
    from .io.network_file import load_network
    from .network import network_from_patch_points

    suffix = path.suffix.lower()
    if suffix == ".bpt":
        return network_from_patch_points(read_bpt(path), source=str(path))
    if suffix == ".npz":
        return load_network(path)
    raise FormatError(path, f"unsupported extension {suffix or '(none)'!r}; expected .npz or .bpt")


def _build(args: argparse.Namespace) -> int:
    from .construct.corner import build_corner_network
    from .io.meshfile import read_mesh
    from .io.network_file import save_network

    if args.output.suffix.lower() != ".npz":
        raise FormatError(args.output, "a network file must end in .npz")
    mesh = read_mesh(args.mesh, split=not args.no_split)
    network = build_corner_network(mesh, tangents=args.tangents, twist=args.twist, normals=args.normals)
    save_network(args.output, network)
    print(f"built {network.n_patches} {args.method} patches from {args.mesh} -> {args.output}")
    return EXIT_OK


def _check(args: argparse.Namespace) -> int:
    from .continuity import check

    report = check(_load_surface(args.surface), samples=args.samples)
    if args.json:
        print(json.dumps(report.to_dict()))
    else:
        print(f"{args.surface}")
        print(report.summary())
    if args.max_angle is not None and not report.is_g1(args.max_angle):
        if not args.json:
            print(f"FAILED: G1 angle above {args.max_angle}°", file=sys.stderr)
        return EXIT_CHECK_FAILED
    return EXIT_OK


def _export(args: argparse.Namespace) -> int:
    from .io.meshfile import write_triangles
    from .io.network_file import load_network
    from .tessellate import tessellate

    network = load_network(args.network)
    mesh = tessellate(network, args.resolution)
    write_triangles(args.output, mesh.points, mesh.triangles)
    print(f"wrote {len(mesh.triangles)} triangles, {len(mesh.points)} points -> {args.output}")
    return EXIT_OK


def _demo(args: argparse.Namespace) -> int:
    from .construct.corner import build_corner_network
    from .continuity import check
    from .io.meshfile import read_mesh, write_triangles
    from .patches import CORNER_PARAMETERS, polynomial_degree, unit
    from .render import render_surfaces
    from .tessellate import tessellate

    with resources.as_file(resources.files("g1patch") / "data" / "cube.obj") as cube_path:
        mesh = read_mesh(cube_path)
    network = build_corner_network(mesh, tangents="arc", twist="coons")
    patches = network.patches
    print("The paper's example: the cube [-1, 1]^3 (valence 3 at every corner) smoothed by")
    print("bicubic Hermite patches with Skala's corner conditions n^T p_u = n^T p_v = 0 (eq. 13)")
    print("and S-/HS-patch (Coons) twists.\n")
    first = patches.convert("hermite")
    normals = unit(np.cross(*first.tangents(CORNER_PARAMETERS)))[0]
    print("Patch 0 (face 0), corner normals p_u x p_v / |p_u x p_v|:")
    for corner, normal in zip(mesh.faces[0], normals):
        print(f"  vertex {corner}: ({normal[0]:+.6f}, {normal[1]:+.6f}, {normal[2]:+.6f})")
    diagonal, anti = first.diagonal_polynomials()
    print(f"Degrees of its diagonal and anti-diagonal: {int(polynomial_degree(diagonal)[0])}, "
          f"{int(polynomial_degree(anti)[0])} (S-/HS closure |C| = {np.linalg.norm(first.closure()[0]):.1e})\n")
    report = check(network)
    print(report.summary())
    print("\nThe corner angle is zero: the paper's conditions hold. The edge angle is not: the paper's")
    print("patches meet with a crease along every edge.")
    surface = tessellate(network, 33)
    args.out.mkdir(parents=True, exist_ok=True)
    write_triangles(args.out / "cube_corner.obj", surface.points, surface.triangles)
    render_surfaces(args.out / "cube_corner.png", [surface], ["corner G1 (Skala)"], size=(700, 700))
    print(f"\nwrote {args.out / 'cube_corner.obj'} and {args.out / 'cube_corner.png'}")
    return EXIT_OK


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; returns the exit code."""
    args = _parser().parse_args(argv)
    handlers = {"build": _build, "check": _check, "export": _export, "demo": _demo}
    try:
        return handlers[args.command](args)
    except G1PatchError as error:
        print(f"g1patch: error: {error}", file=sys.stderr)
        return EXIT_ERROR
    except OSError as error:
        print(f"g1patch: error: {error.filename or ''}: {error.strerror}", file=sys.stderr)
        return EXIT_ERROR


if __name__ == "__main__":
    sys.exit(main())
