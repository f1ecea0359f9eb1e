"""One 100,000-sided face (issue 11: builds in ≤ 2 s and ≤ 500 MB).

The face is the wavy polygon ``(cos θ, sin θ, 0.1 sin 3θ)`` with ``--sides`` vertices (default
100,000), split around its centre into as many quads. Rows:

* in process: ``QuadMesh.from_arrays`` (the split) and ``build_network`` (the default Gregory
  build, fold guard included), best of ``--repeats`` after one untimed run that loads the numba
  kernels; their tracemalloc peak (a separate run); the folded patches and the fallback count;
* command line: ``g1patch build FACE.obj -o OUT.npz`` in a subprocess (imports, kernel loading,
  reading, build, writing), its wall time (best of ``--repeats``) and maximum resident set
  (by GNU time, the largest), after one uncounted run that may compile kernels.

Run:  .venv/bin/python benchmarks/bench_polygon.py [--sides N] [--repeats R] [--quick]
"""

from __future__ import annotations

import sys
import tempfile
from collections.abc import Sequence
from functools import partial
from pathlib import Path

import harness
import numpy as np

from g1patch.build import build_network
from g1patch.continuity import folded_patches
from g1patch.memory import tune_for_large_arrays
from g1patch.mesh import QuadMesh

record = harness.recorder("bench_polygon")


def wavy_polygon(sides: int) -> np.ndarray:
    theta = np.linspace(0.0, 2.0 * np.pi, sides, endpoint=False)
    return np.stack([np.cos(theta), np.sin(theta), 0.1 * np.sin(3.0 * theta)], axis=1)


def in_process(points: np.ndarray, repeats: int) -> None:
    """The split and the build, best of ``repeats`` after a warm-up, and the traced peak."""
    face = [list(range(len(points)))]
    network = build_network(QuadMesh.from_arrays(points, face))  # loads the kernels
    splits, builds = [], []
    for _ in range(repeats):
        split, mesh = harness.timed(lambda: QuadMesh.from_arrays(points, face))
        build, network = harness.timed(partial(build_network, mesh))
        splits.append(split)
        builds.append(build)
    peak = harness.peak(lambda: build_network(QuadMesh.from_arrays(points, face)))
    folds = int(folded_patches(network.patches, 9).sum())
    fallback = network.provenance["fallback_vertices"]
    print(f"{len(points):,}-gon, load average {harness.loads()}")
    print(
        f"  in process: split {min(splits):.2f} s + build {min(builds):.2f} s = "
        f"{min(splits) + min(builds):.2f} s, tracemalloc peak {peak / 1e6:.0f} MB; "
        f"{network.n_patches:,} patches, {folds} folded, {fallback} fallback vertices"
    )
    record("split", min(splits), "s", f"best of {repeats}")
    record("build", min(builds), "s", f"best of {repeats}")
    record("split + build peak", peak / 1e6, "MB", "tracemalloc; issue 11 bar 500 MB")
    record("patches", network.n_patches, "")
    record("folded patches", folds, "")
    record("fallback vertices", fallback, "")


def command_line(points: np.ndarray, repeats: int) -> None:
    """``g1patch build FACE.obj``: wall time (best) and resident peak (largest), after one
    uncounted run that may compile the readers' kernels."""
    with tempfile.TemporaryDirectory() as folder:
        obj, out = Path(folder) / "face.obj", Path(folder) / "face.npz"
        np.savetxt(obj, points, fmt="v %.17g %.17g %.17g")
        with obj.open("a") as stream:
            stream.write("f " + " ".join(str(i + 1) for i in range(len(points))) + "\n")
        g1patch = Path(sys.executable).with_name("g1patch")
        command: list[str | Path] = [g1patch, "build", obj, "-o", out, "-q"]
        runs = [harness.run_command(command) for _ in range(repeats + 1)][1:]
    seconds = min(run.seconds for run in runs)
    resident = [run.resident for run in runs if run.resident is not None]
    shown = (
        f"maximum resident {max(resident) / 1e6:.0f} MB (imports and kernels included)"
        if resident
        else "no GNU time: resident peak not measured"
    )
    print(f"  command line: {seconds:.2f} s wall, {shown}")
    record("command line build", seconds, "s", f"best of {repeats}, start-up included")
    if resident:
        record("command line resident peak", max(resident) / 1e6, "MB", "GNU time")


#: the command line's options (harness.Option)
OPTIONS: dict[str, harness.Option] = {
    "sides": (100_000, "sides of the face"),
    "repeats": (3, "runs, the best"),
}
#: the defaults --quick sets: small sizes, a smoke run
QUICK = {"sides": 5_000, "repeats": 1}


def main(argv: Sequence[str] | None = None) -> None:
    args = harness.parse_args(__doc__, argv, OPTIONS, QUICK)
    tune_for_large_arrays()  # as the command line does
    points = wavy_polygon(args.sides)
    record("sides", args.sides, "")
    in_process(points, args.repeats)
    command_line(points, args.repeats)


if __name__ == "__main__":
    main()
