"""One 100,000-sided face (issue 11: builds in ≤ 2 s and ≤ 500 MB).

The face is the wavy polygon ``(cos θ, sin θ, 0.1 sin 3θ)`` with ``--sides`` vertices (default
100,000), split around its centre into as many quads. Rows:

* in process: ``QuadMesh.from_arrays`` (the split) and ``build_network`` (the default Gregory
  build, fold guard included), best of ``--repeats`` after one untimed run that loads the numba
  kernels; their tracemalloc peak (a separate run); the folded patches and the fallback count;
* command line: ``g1patch build FACE.obj -o OUT.npz`` in a subprocess (imports, kernel loading,
  reading, build, writing), its wall time (best of ``--repeats``) and maximum resident set
  (by GNU time, the largest), after one uncounted run that may compile kernels.

Run:  .venv/bin/python benchmarks/bench_polygon.py [--sides N] [--repeats R]
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
import time
import tracemalloc
from pathlib import Path

import numpy as np

from g1patch.build import build_network
from g1patch.continuity import folded_patches
from g1patch.memory import tune_for_large_arrays
from g1patch.mesh import QuadMesh


def wavy_polygon(sides: int) -> np.ndarray:
    theta = np.linspace(0.0, 2.0 * np.pi, sides, endpoint=False)
    return np.stack([np.cos(theta), np.sin(theta), 0.1 * np.sin(3.0 * theta)], axis=1)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sides", type=int, default=100_000)
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    tune_for_large_arrays()  # as the command line does
    points, face = wavy_polygon(args.sides), [list(range(args.sides))]

    network = build_network(QuadMesh.from_arrays(points, face))  # loads the kernels
    splits, builds = [], []
    for _ in range(args.repeats):
        start = time.perf_counter()
        mesh = QuadMesh.from_arrays(points, face)
        split = time.perf_counter()
        network = build_network(mesh)
        splits.append(split - start)
        builds.append(time.perf_counter() - split)
    tracemalloc.start()
    build_network(QuadMesh.from_arrays(points, face))
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    folds = int(folded_patches(network.patches, 9).sum())
    print(f"{args.sides:,}-gon, load average {' '.join(f'{x:.2f}' for x in os.getloadavg())}")
    print(
        f"  in process: split {min(splits):.2f} s + build {min(builds):.2f} s = {min(splits) + min(builds):.2f} s,"
        f" tracemalloc peak {peak / 1e6:.0f} MB; {network.n_patches:,} patches, {folds} folded,"
        f" {network.provenance['fallback_vertices']} fallback vertices"
    )

    with tempfile.TemporaryDirectory() as folder:
        obj, out = Path(folder) / "face.obj", Path(folder) / "face.npz"
        np.savetxt(obj, points, fmt="v %.17g %.17g %.17g")
        with obj.open("a") as stream:
            stream.write("f " + " ".join(str(i + 1) for i in range(args.sides)) + "\n")
        command = [
            str(Path(sys.executable).with_name("g1patch")),
            "build",
            str(obj),
            "-o",
            str(out),
            "-q",
        ]
        # the child's ru_maxrss counts this process's pages until the exec, so GNU time (a small
        # process) runs it and reports the peak; without it only the wall time is measured
        gnu_time = shutil.which("time", path="/usr/bin:/bin")
        walls, rss = [], []
        for run in range(
            args.repeats + 1
        ):  # the first run may compile the readers' kernels: not counted
            start = time.perf_counter()
            result = subprocess.run(
                [gnu_time, "-f", "%M", *command] if gnu_time else command,
                capture_output=True,
                text=True,
            )
            if result.returncode:
                raise SystemExit(f"{' '.join(command)} failed: {result.stderr.strip()}")
            if run:
                walls.append(time.perf_counter() - start)
                if gnu_time:
                    rss.append(int(result.stderr.strip().splitlines()[-1]) * 1024)
    resident = (
        f"maximum resident {max(rss) / 1e6:.0f} MB (imports and kernels included)"
        if rss
        else "no GNU time: resident peak not measured"
    )
    print(f"  command line: {min(walls):.2f} s wall, {resident}")


if __name__ == "__main__":
    main()
