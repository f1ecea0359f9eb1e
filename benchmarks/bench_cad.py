"""STEP export of the default (Gregory) networks per CAD method: file size, time, deviation, OCC's G1 angle.

Workload: every mesh of the shared data (``--data``, default ``../shared/data``; ``--meshes`` picks
some), built with the defaults (Gregory, interpolate; not timed). Per mesh and method, in the same run:

* ``fit`` (the baseline: the previous default): each Gregory patch fitted on adaptive knots within
  1e-6 of the diagonal (:func:`g1patch.io.cad.fit_bspline_surfaces`);
* ``split4`` (the default): the split4 re-assembly of the network's targets, written exactly
  (:mod:`g1patch.construct.polynomial`; seams: on the mesh cut open along them), each patch as
  n × n quads where n = 1 leaves it further than 1e-3 of the diagonal from the Gregory surface
  (column ``cells``: n); a network whose Gregory patches are bicubics already is written as they
  are (shown ``split4>exact``).

Columns: faces; a closed solid, OCC's validity (``BRepCheck_Analyzer``); the file's bytes; the export's wall time (``export_step``, one run, the G1
measurement included); the deviation from the Gregory surface over the bounding-box diagonal (fit:
its fit deviation; split4: the foot-point distance); OCC's max angle across shared smooth edges on
the written shape and on the file read back (:func:`g1patch.io.cad.file_g1_angles`); ratios
split4 / fit of bytes and time. Times drift on a shared machine; the ratios are of the same run.

Then where the default export's time goes: per mesh, ``--repeats`` more runs of ``export_step``
(default method), the best wall time and, per stage, its best time (:attr:`ExportResult.seconds`:
split4 = the re-assembly, deviation = its distance to the Gregory surface, fit = the split4 quads
read off, faces = the OCC faces, sew, solid = the solid and its volume, check = BRepCheck, g1 =
OCC's G1 angles on every shared edge, write = OCC's writer and the STEP compaction), with the
load average (1 min) at the start of each mesh's runs.

Run:  .venv/bin/python benchmarks/bench_cad.py [--data DIR] [--meshes NAME ...] [--out DIR] [--repeats N]
"""

from __future__ import annotations

import argparse
import os
import platform
import tempfile
import time
from pathlib import Path

from g1patch.build import build_network
from g1patch.construct.polynomial import split4_of_gregory
from g1patch.io.cad import ExportResult, export_step, file_g1_angles
from g1patch.io.meshfile import read_mesh
from g1patch.network import PatchNetwork

DATA = Path(__file__).resolve().parents[2] / "shared" / "data"
METHODS = ("fit", "split4")


def file_angle(result: ExportResult, written: PatchNetwork) -> float:
    """OCC's max angle across shared smooth edges of the file read back."""
    angles = file_g1_angles(result.path, written)
    patch, edge = written.shared_edges()
    smooth = ~written.seam[patch, edge]
    return float(angles[smooth].max()) if smooth.any() else 0.0


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", type=Path, default=DATA)
    parser.add_argument(
        "--meshes", nargs="*", help="mesh names (file stems); default: every .obj in --data"
    )
    parser.add_argument(
        "--out", type=Path, help="folder for the STEP files (default: a temporary one, removed)"
    )
    parser.add_argument(
        "--repeats",
        type=int,
        default=3,
        help="runs of the default export per mesh for the stage breakdown (0: none)",
    )
    args = parser.parse_args()
    paths = sorted(args.data.glob("*.obj"))
    if args.meshes:
        paths = [p for p in paths if p.stem in args.meshes]
    print(
        f"# {platform.processor() or platform.machine()}, Python {platform.python_version()}; export_step of the default network"
    )
    header = (
        f"{'mesh':26} {'method':12} {'cells':>5} {'faces':>6} {'solid':>5} {'valid':>5} {'bytes':>11} {'time s':>7} {'dev/diag':>9} "
        f"{'OCC max° (shape)':>17} {'OCC max° (file)':>16} {'bytes ratio':>11} {'time ratio':>10}"
    )
    print(header)
    networks = {path.stem: build_network(read_mesh(path)) for path in paths}
    with tempfile.TemporaryDirectory() as scratch:
        folder = args.out or Path(scratch)
        folder.mkdir(parents=True, exist_ok=True)
        for path in paths:
            network = networks[path.stem]
            diagonal = network.bounding_box_diagonal()
            rows: dict[str, tuple[ExportResult, float, float]] = {}
            for method in METHODS:
                start = time.perf_counter()
                result = export_step(folder / f"{path.stem}.{method}.step", network, method=method)
                seconds = time.perf_counter() - start
                written = (
                    split4_of_gregory(network, refine=result.refine)
                    if result.method == "split4"
                    else network
                )
                rows[method] = (result, seconds, file_angle(result, written))
            base = rows["fit"]
            for method, (result, seconds, angle) in rows.items():
                ratios = (
                    f"{result.file_bytes / base[0].file_bytes:11.3f} {seconds / base[1]:10.3f}"
                    if method != "fit"
                    else f"{'1':>11} {'1':>10}"
                )
                shown = method if result.method in (method, "fit") else f"{method}>{result.method}"
                print(
                    f"{path.stem:26} {shown:12} {result.refine or '':>5} {result.faces:6d} {result.solid!s:>5} {result.valid!s:>5} "
                    f"{result.file_bytes:11,d} {seconds:7.2f} "
                    f"{result.deviation / diagonal:9.2e} {result.max_g1_angle_deg:17.2e} {angle:16.2e} {ratios}"
                )
        if args.repeats > 0:
            stage_breakdown(networks, folder, args.repeats)


def stage_breakdown(networks: dict[str, PatchNetwork], folder: Path, repeats: int) -> None:
    """Per mesh, the best of ``repeats`` default exports: wall time and each stage's best time."""
    print(f"\n# stages of export_step (default method), best of {repeats}; seconds")
    rows = []
    for name, network in networks.items():
        load = os.getloadavg()[0]
        walls, stages = [], {}
        for _ in range(repeats):
            start = time.perf_counter()
            result = export_step(folder / f"{name}.stages.step", network)
            walls.append(time.perf_counter() - start)
            for stage, seconds in result.seconds.items():
                stages[stage] = min(seconds, stages.get(stage, seconds))
        rows.append((name, load, min(walls), stages))
    names = list(dict.fromkeys(stage for *_, stages in rows for stage in stages))
    print(f"{'mesh':26} {'load':>5} {'total':>7} " + " ".join(f"{stage:>9}" for stage in names))
    for name, load, wall, stages in rows:
        print(
            f"{name:26} {load:5.2f} {wall:7.2f} "
            + " ".join(f"{stages[s]:9.3f}" if s in stages else f"{'':>9}" for s in names)
        )


if __name__ == "__main__":
    main()
