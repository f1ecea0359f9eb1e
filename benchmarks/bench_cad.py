"""STEP export of the default networks per CAD method: file size, time, deviation, OCC's G1 angle.

Workload: every mesh of the shared data (``--data``, default ``../shared/data``; ``--meshes``
picks some; ``--quick``: the cube, one run), built with the defaults (Gregory, interpolate; not
timed). Per mesh and method, in the same run:

* ``fit`` (the baseline: the previous default): each Gregory patch fitted on adaptive knots within
  1e-6 of the diagonal (:func:`g1patch.io.cad.fit_bspline_surfaces`);
* ``split4`` (the default): the split4 re-assembly of the network's targets, written exactly
  (:mod:`g1patch.construct.polynomial`; seams: on the mesh cut open along them), each patch as
  n × n quads where n = 1 leaves it further than 1e-3 of the diagonal from the Gregory surface
  (column ``cells``: n); a network whose Gregory patches are bicubics already is written as they
  are (shown ``split4>exact``).

Columns: faces; a closed solid, OCC's validity (``BRepCheck_Analyzer``); the file's bytes; the
export's wall time (``export_step``, one run, the G1 measurement included); the deviation from
the Gregory surface over the bounding-box diagonal (fit: its fit deviation; split4: the foot-point
distance); OCC's max angle across shared smooth edges on the written shape and on the file read
back (:func:`g1patch.io.cad.file_g1_angles`); ratios split4 / fit of bytes and time. Times drift
on a shared machine; the ratios are of the same run.

Then where the default export's time goes: per mesh, ``--repeats`` more runs of ``export_step``
(default method), the best wall time and, per stage, its best time (:attr:`ExportResult.seconds`:
split4 = the re-assembly, deviation = its distance to the Gregory surface, fit = the split4 quads
read off, faces = the OCC faces, sew, solid = the solid and its volume, check = BRepCheck, g1 =
OCC's G1 angles on every shared edge, write = OCC's writer and the STEP compaction), with the
load average (1 min) at the start of each mesh's runs.

Run:  .venv/bin/python benchmarks/bench_cad.py [--data DIR] [--meshes NAME ...] [--out DIR]
      [--repeats N] [--quick]
"""

from __future__ import annotations

import tempfile
from collections.abc import Sequence
from functools import partial
from pathlib import Path
from typing import Literal

import harness

from g1patch.build import build_network
from g1patch.construct.polynomial import split4_of_gregory
from g1patch.io.cad import ExportResult, export_step, file_g1_angles
from g1patch.io.meshfile import read_mesh
from g1patch.network import PatchNetwork

record = harness.recorder("bench_cad")
METHODS: tuple[Literal["fit", "split4"], ...] = ("fit", "split4")


def file_angle(result: ExportResult, written: PatchNetwork) -> float:
    """OCC's max angle across shared smooth edges of the file read back."""
    angles = file_g1_angles(result.path, written)
    patch, edge = written.shared_edges()
    smooth = ~written.seam[patch, edge]
    return float(angles[smooth].max()) if smooth.any() else 0.0


def export_methods(name: str, network: PatchNetwork, folder: Path) -> None:
    """One mesh's rows: each method's export, and its ratios to ``fit``."""
    diagonal = network.bounding_box_diagonal()
    rows: dict[str, tuple[ExportResult, float, float]] = {}
    for method in METHODS:
        path = folder / f"{name}.{method}.step"
        seconds, result = harness.timed(partial(export_step, path, network, method=method))
        written = (
            split4_of_gregory(network, refine=result.refine)
            if result.method == "split4"
            else network
        )
        rows[method] = (result, seconds, file_angle(result, written))
    base = rows["fit"]
    for label, (result, seconds, angle) in rows.items():
        size_ratio, time_ratio = result.file_bytes / base[0].file_bytes, seconds / base[1]
        shown = label if result.method in (label, "fit") else f"{label}>{result.method}"
        deviation = result.deviation / diagonal
        print(
            f"{name:26} {shown:12} {result.refine or '':>5} {result.faces:6d} "
            f"{result.solid!s:>5} {result.valid!s:>5} {result.file_bytes:11,d} {seconds:7.2f} "
            f"{deviation:9.2e} {result.max_g1_angle_deg:17.2e} {angle:16.2e} "
            f"{size_ratio:11.3f} {time_ratio:10.3f}"
        )
        key = f"{name} {label}"
        record(f"{key} written as", shown, "")
        record(f"{key} cells", result.refine or 1, "", "n × n quads per patch")
        record(f"{key} faces", result.faces, "")
        record(f"{key} valid solid", bool(result.solid and result.valid), "")
        record(f"{key} file", result.file_bytes / 1e6, "MB")
        record(f"{key} export", seconds, "s", "one run")
        record(f"{key} deviation", deviation, "of diagonal")
        record(f"{key} OCC max angle on the shape", result.max_g1_angle_deg, "°")
        record(f"{key} OCC max angle on the file", angle, "°")
        if label != "fit":
            record(f"{key} / fit file", size_ratio, "×")
            record(f"{key} / fit export time", time_ratio, "×")


def stage_breakdown(networks: dict[str, PatchNetwork], folder: Path, repeats: int) -> None:
    """Per mesh, the best of ``repeats`` default exports: wall time and each stage's best time."""
    print(f"\n# stages of export_step (default method), best of {repeats}; seconds")
    rows = []
    for name, network in networks.items():
        load = harness.load_average()[0]
        walls: list[float] = []
        stages: dict[str, float] = {}
        for _ in range(repeats):
            path = folder / f"{name}.stages.step"
            seconds, result = harness.timed(partial(export_step, path, network))
            walls.append(seconds)
            for stage, spent in result.seconds.items():
                stages[stage] = min(spent, stages.get(stage, spent))
        rows.append((name, load, min(walls), stages))
        record(f"{name} default export", min(walls), "s", f"best of {repeats}; load {load:.2f}")
        for stage, spent in stages.items():
            record(f"{name} default export stage {stage}", spent, "s", "best")
    names = list(dict.fromkeys(stage for *_, stages in rows for stage in stages))
    print(f"{'mesh':26} {'load':>5} {'total':>7} " + " ".join(f"{stage:>9}" for stage in names))
    for name, load, wall, stages in rows:
        print(
            f"{name:26} {load:5.2f} {wall:7.2f} "
            + " ".join(f"{stages[s]:9.3f}" if s in stages else f"{'':>9}" for s in names)
        )


#: the command line's options (harness.Option)
OPTIONS: dict[str, harness.Option] = {
    "data": (harness.SHARED, "folder of the meshes"),
    "meshes": ([], "mesh names (file stems); none: every .obj in --data"),
    "out": (None, "folder for the STEP files (default: a temporary one, removed)", Path),
    "repeats": (3, "default exports per mesh for the stage breakdown, 0: none"),
}
#: the defaults --quick sets: small sizes, a smoke run
QUICK = {"meshes": ["catmark_cube"], "repeats": 1}


def main(argv: Sequence[str] | None = None) -> None:
    args = harness.parse_args(__doc__, argv, OPTIONS, QUICK)
    paths = sorted(args.data.glob("*.obj"))
    if args.meshes:
        paths = [p for p in paths if p.stem in args.meshes]
    print(f"# {harness.machine_line()}; export_step of the default network")
    print(
        f"{'mesh':26} {'method':12} {'cells':>5} {'faces':>6} {'solid':>5} {'valid':>5} "
        f"{'bytes':>11} {'time s':>7} {'dev/diag':>9} {'OCC max° (shape)':>17} "
        f"{'OCC max° (file)':>16} {'bytes ratio':>11} {'time ratio':>10}"
    )
    networks = {path.stem: build_network(read_mesh(path)) for path in paths}
    with tempfile.TemporaryDirectory() as scratch:
        folder = args.out or Path(scratch)
        folder.mkdir(parents=True, exist_ok=True)
        for name, network in networks.items():
            export_methods(name, network, folder)
        if args.repeats > 0:
            stage_breakdown(networks, folder, args.repeats)


if __name__ == "__main__":
    main()
