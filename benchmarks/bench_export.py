"""CAD export of the default network (split4): STEP and Rhino .3dm time, size and faces per cage
quad, on the shared meshes and on a generated 1 M-quad torus (issue 31, item 5).

Workload, in the same run:

* every shared mesh (``--data``; ``--meshes`` picks some), built with the defaults (not timed),
  written as STEP (``export_step``: the B-rep read off the network, read back by OpenCASCADE to
  check it and measure G1 up to 20,000 faces) and as .3dm (``export_3dm``): faces, faces per
  cage quad (quads of the built mesh: a triangle counts as three), MB, kB per face, seconds, the
  file's OCC G1 angle;
* tori of ``--sizes`` quads (default 8,192, 131,072 and 1,048,576), each built by the CLI and
  exported by it in a child process (``g1patch export --no-verify``): wall time and resident peak
  (GNU time), MB and kB per face; the baseline, in the same run, is OpenCASCADE's own route
  (faces, sewing, solid, its writer, the compaction) on the smallest torus, in a child process
  too: its time and peak over the direct route's there;
* .3dm of the tori up to ``--rhino-quads`` (default 131,072): rhino3dm takes one Python call per
  pole, ~1 ms a face, so a million faces would take ~20 min; its rate per face is recorded.

Run:  .venv/bin/python benchmarks/bench_export.py [--data DIR] [--meshes NAME ...]
      [--sizes N ...] [--rhino-quads N] [--quick]
"""

from __future__ import annotations

import math
import sys
import tempfile
from collections.abc import Sequence
from functools import partial
from pathlib import Path

import harness
import numpy as np

from g1patch.build import build_network
from g1patch.io.cad import export_3dm, export_step
from g1patch.io.meshfile import read_mesh

record = harness.recorder("bench_export")

#: the OpenCASCADE route for the baseline: export_cad with the direct B-rep switched off
_OCC_ROUTE = """
import sys
from g1patch.io.cad import export as cad_export
from g1patch.io.network_file import load_network
cad_export.quad_brep = lambda *args: None
result = cad_export.export_step(sys.argv[1], load_network(sys.argv[2]), g1_samples=0)
print(result.faces)
"""


def torus_obj(quads: int, folder: Path) -> Path:
    """A torus cage of about ``quads`` quads (n × n/2 … a power of two) as OBJ."""
    minor = 2 ** max(2, round(math.log2(math.sqrt(quads / 2))))
    major = max(4, quads // minor)
    path = folder / f"torus{major * minor}.obj"
    u, v = np.meshgrid(
        np.linspace(0, 2 * np.pi, major, endpoint=False),
        np.linspace(0, 2 * np.pi, minor, endpoint=False),
        indexing="ij",
    )
    points = np.stack(
        [(1 + 0.4 * np.cos(v)) * np.cos(u), (1 + 0.4 * np.cos(v)) * np.sin(u), 0.4 * np.sin(v)],
        axis=-1,
    ).reshape(-1, 3)
    i, j = np.meshgrid(np.arange(major), np.arange(minor), indexing="ij")
    at = lambda a, b: (a % major) * minor + (b % minor) + 1  # noqa: E731
    faces = np.stack([at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)], axis=-1)
    with open(path, "w") as out:
        np.savetxt(out, points, fmt="v %.17g %.17g %.17g")
        np.savetxt(out, faces.reshape(-1, 4), fmt="f %d %d %d %d")
    return path


def shared(paths: list[Path], folder: Path) -> None:
    """Per shared mesh: STEP and .3dm of its default network."""
    print(
        f"{'mesh':26} {'format':6} {'faces':>7} {'per quad':>8} {'MB':>8} {'kB/face':>8} "
        f"{'s':>7} {'OCC G1°':>9}"
    )
    for path in paths:
        mesh = read_mesh(path)
        network = build_network(mesh)
        quads = network.n_patches // 4
        for kind, write in (("step", export_step), ("3dm", export_3dm)):
            target = folder / f"{path.stem}.{kind}"
            seconds, result = harness.timed(partial(write, target, network))
            size = result.path.stat().st_size
            angle = getattr(result, "max_g1_angle_deg", None)
            shown = "—" if angle is None else f"{angle:9.1e}"
            print(
                f"{path.stem:26} {kind:6} {result.faces:7d} {result.faces / quads:8.2f} "
                f"{size / 1e6:8.2f} {size / 1e3 / result.faces:8.2f} {seconds:7.2f} {shown:>9}"
            )
            key = f"{path.stem} {kind}"
            record(f"{key} faces", result.faces, "")
            record(f"{key} faces per cage quad", result.faces / quads, "")
            record(f"{key} file", size / 1e6, "MB")
            record(f"{key} per face", size / 1e3 / result.faces, "kB")
            record(f"{key} export", seconds, "s", "one run, OCC's read-back included (STEP)")
            if angle is not None:
                record(f"{key} OCC G1 on the file", angle, "°")


def tori(sizes: Sequence[int], rhino_quads: int, folder: Path) -> None:
    """Generated tori built and exported by the CLI in child processes; the OCC route's baseline
    on the smallest."""
    cli = [sys.executable, "-m", "g1patch.cli"]
    print(f"\n{'quads':>9} {'format':6} {'s':>8} {'peak GB':>8} {'MB':>9} {'kB/face':>8}")
    direct_small: tuple[float, int] | None = None
    for quads in sorted(sizes):
        cage = torus_obj(quads, folder)
        network = folder / f"{cage.stem}.npz"
        harness.run_command([*cli, "build", cage, "-o", network, "-q"])
        formats = ["step"] + (["3dm"] if quads <= rhino_quads else [])
        for kind in formats:
            target = folder / f"{cage.stem}.{kind}"
            done = harness.run_command(
                [*cli, "export", network, "-o", target, "-q", "--no-verify"]
                if kind == "step"
                else [*cli, "export", network, "-o", target]
            )
            size = target.stat().st_size
            faces = quads
            peak = (done.resident or 0) / 1e9
            print(
                f"{quads:9,d} {kind:6} {done.seconds:8.2f} {peak:8.2f} {size / 1e6:9.1f} "
                f"{size / 1e3 / faces:8.2f}"
            )
            key = f"torus {quads} quads {kind}"
            record(f"{key} export", done.seconds, "s", "CLI, child process, read included")
            record(f"{key} peak", peak, "GB", "resident, GNU time")
            record(f"{key} file", size / 1e6, "MB")
            record(f"{key} per face", size / 1e3 / faces, "kB")
            if kind == "step" and direct_small is None:
                direct_small = (done.seconds, done.resident or 0)
                script = folder / "occ_route.py"
                script.write_text(_OCC_ROUTE)
                occ = harness.run_command(
                    [sys.executable, script, folder / f"{cage.stem}.occ.step", network]
                )
                record(f"torus {quads} quads OCC route export", occ.seconds, "s", "baseline")
                record(
                    f"torus {quads} quads OCC route / direct time", occ.seconds / done.seconds, "×"
                )
                if occ.resident and done.resident:
                    record(
                        f"torus {quads} quads OCC route / direct peak",
                        occ.resident / done.resident,
                        "×",
                    )
                print(
                    f"{quads:9,d} {'occ':6} {occ.seconds:8.2f} "
                    f"{(occ.resident or 0) / 1e9:8.2f}  (OpenCASCADE's route, baseline)"
                )


OPTIONS: dict[str, harness.Option] = {
    "data": (harness.SHARED, "folder of the meshes"),
    "meshes": ([], "mesh names (file stems); none: every .obj in --data"),
    "sizes": ([8192, 131072, 1048576], "quads of the generated tori", int),
    "rhino_quads": (131072, "largest torus also written as .3dm"),
}
QUICK = {"meshes": ["catmark_cube"], "sizes": [2048], "rhino_quads": 2048}


def main(argv: Sequence[str] | None = None) -> None:
    args = harness.parse_args(__doc__, argv, OPTIONS, QUICK)
    paths = sorted(args.data.glob("*.obj"))
    if args.meshes:
        paths = [p for p in paths if p.stem in args.meshes]
    print(f"# {harness.machine_line()}; CAD export of the default network")
    with tempfile.TemporaryDirectory() as scratch:
        folder = Path(scratch)
        shared(paths, folder)
        tori(args.sizes, args.rhino_quads, folder)


if __name__ == "__main__":
    main()
