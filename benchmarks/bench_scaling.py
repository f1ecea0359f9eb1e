"""Scaling of the default build and check, 10k → 4M quads, and the 4M end-to-end run (issue 13).

Per size N (``--sizes``, default 10k, 100k, 1M, 4M), in a fresh subprocess so each size starts
from the same memory state, on ``shapes.large_torus(N)`` with its topology built before anything
is timed and the numba kernels warmed up on a small torus:

* ``build s``: one ``build_network(mesh)`` (Gregory, interpolate), after one untimed build of the
  same mesh (fresh memory is first touched lazily on this VM, see DESIGN §6);
* ``build MB``: the tracemalloc peak of another build, over what was held before it, and per quad;
* ``check s`` and ``check MB``: the same for ``continuity.check(network)`` with its defaults;
* ``check/build``: the issue's bar is ≤ 1.

Then the exponents ``b`` of ``t ∝ N^b`` fitted by least squares to log t over log N for the four
columns (issue bar: ≤ 1.1 for each).

End to end (``--end-to-end N``, default the largest size; 0 skips it): the mesh is written as a
binary PLY (untimed), then one process runs what ``g1patch build mesh.ply -o out.npz --check``
runs: it reads the mesh (``read_mesh``), builds the network, and checks it while the file is
written (``save_network_in_background``), timed stage by stage (the check, and the wait for the
file after it), with the process peak (``ru_maxrss``); then, for comparison, the same check and
save one after the other. Issue bar at 4M: ≤ 30 s and ≤ 8 GB.

The workers run as the command line does (``g1patch.memory.tune_for_large_arrays``: freed memory
kept for the next array, NumPy's huge-page advice as NumPy sets it).

Run:  .venv/bin/python benchmarks/bench_scaling.py [--sizes 10000 100000 1000000 4000000] [--end-to-end N]
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import resource
import subprocess
import sys
import tempfile
import time
import tracemalloc
from collections.abc import Callable
from pathlib import Path
from typing import TypeVar

import numpy as np

from g1patch.memory import TUNED_ENVIRONMENT

T = TypeVar("T")


def _timed(run: Callable[[], T]) -> tuple[T, float]:
    start = time.perf_counter()
    result = run()
    return result, time.perf_counter() - start


def _peak(run: Callable[[], object]) -> int:
    """Bytes allocated at the peak of ``run()`` over what was held when it started (tracemalloc)."""
    tracemalloc.start()
    try:
        run()
        return tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()


def _warm_up() -> None:
    """Import numba and load (or compile) the build's and check's kernels on a small torus."""
    from g1patch import shapes
    from g1patch.build import build_network
    from g1patch.continuity import check
    from g1patch.memory import tune_for_large_arrays

    tune_for_large_arrays()  # as the command line does
    small = shapes.large_torus(30_000)  # above continuity.KERNEL_PATCHES: the check's kernels too
    check(build_network(small))


def size_row(quads: int) -> dict[str, float]:
    """One size's build and check, time and peak (module docstring)."""
    from g1patch import shapes
    from g1patch.build import build_network
    from g1patch.continuity import check

    _warm_up()
    mesh = shapes.large_torus(quads)
    build_network(mesh)
    network, build_s = _timed(lambda: build_network(mesh))
    build_peak = _peak(lambda: build_network(mesh))
    _, check_s = _timed(lambda: check(network))
    check_peak = _peak(lambda: check(network))
    return {
        "quads": mesh.n_faces,
        "build_s": build_s,
        "build_peak": build_peak,
        "check_s": check_s,
        "check_peak": check_peak,
    }


def end_to_end(quads: int) -> dict[str, float]:
    """Read a binary PLY → build → check → save, stage by stage, and the process peak."""
    import meshio

    from g1patch import shapes
    from g1patch.build import build_network
    from g1patch.continuity import check
    from g1patch.io.meshfile import read_mesh
    from g1patch.io.network_file import save_network, save_network_in_background

    _warm_up()
    with tempfile.TemporaryDirectory() as folder:
        ply, out = Path(folder) / "mesh.ply", Path(folder) / "network.npz"
        mesh = shapes.large_torus(quads)
        meshio.write(ply, meshio.Mesh(mesh.vertices, [("quad", mesh.topology.faces)]), binary=True)
        del mesh
        baseline = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
        start = time.perf_counter()
        mesh, read_s = _timed(lambda: read_mesh(ply))
        network, build_s = _timed(lambda: build_network(mesh))
        saving = save_network_in_background(out, network)
        _, check_s = _timed(lambda: check(network))
        _, wait_s = _timed(saving.result)
        total = time.perf_counter() - start
        peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
        out.unlink()
        _, alone_check_s = _timed(lambda: check(network))
        _, alone_save_s = _timed(lambda: save_network(out, network))
    return {
        "quads": network.n_patches,
        "read_s": read_s,
        "build_s": build_s,
        "check_s": check_s,
        "wait_s": wait_s,
        "total_s": total,
        "peak": peak,
        "baseline": baseline,
        "alone_check_s": alone_check_s,
        "alone_save_s": alone_save_s,
    }


def _in_subprocess(function: str, quads: int) -> dict[str, float]:
    """``function(quads)`` of this file in a fresh interpreter, its result as JSON."""
    code = (
        f"import json, sys; sys.path.insert(0, {str(Path(__file__).parent)!r}); import bench_scaling as b; "
        f"print(json.dumps(b.{function}({quads})))"
    )
    result = subprocess.run(
        [sys.executable, "-c", code],
        capture_output=True,
        text=True,
        env={**os.environ, **TUNED_ENVIRONMENT},
    )
    if result.returncode:
        raise SystemExit(f"{function}({quads}) failed:\n{result.stderr[-2000:]}")
    return json.loads(result.stdout.strip().splitlines()[-1])


def exponent(quads: list[float], values: list[float]) -> float:
    """Least-squares slope b of ``log v = a + b log N``."""
    return float(np.polyfit(np.log(quads), np.log(values), 1)[0])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--sizes", type=int, nargs="+", default=[10_000, 100_000, 1_000_000, 4_000_000]
    )
    parser.add_argument(
        "--end-to-end",
        type=int,
        default=None,
        help="quads of the end-to-end run (default: the largest size; 0: skip)",
    )
    args = parser.parse_args()
    print(f"{platform.machine()}, {os.cpu_count()} cores, python {platform.python_version()}")

    rows = [_in_subprocess("size_row", quads) for quads in args.sizes]
    print(f"\nload average {' '.join(f'{x:.2f}' for x in os.getloadavg())}")
    print(
        f"{'quads':>9} {'build s':>8} {'build MB':>9} {'B/quad':>7} {'check s':>8} {'check MB':>9} {'B/quad':>7} {'check/build':>11}"
    )
    for row in rows:
        print(
            f"{row['quads']:9,.0f} {row['build_s']:8.2f} {row['build_peak'] / 1e6:9.0f} {row['build_peak'] / row['quads']:7.0f}"
            f" {row['check_s']:8.2f} {row['check_peak'] / 1e6:9.0f} {row['check_peak'] / row['quads']:7.0f}"
            f" {row['check_s'] / row['build_s']:11.2f}"
        )
    if len(rows) > 1:
        quads = [row["quads"] for row in rows]
        fitted = {
            name: exponent(quads, [row[name] for row in rows])
            for name in ("build_s", "build_peak", "check_s", "check_peak")
        }
        print(
            "exponents (t ∝ N^b, bar ≤ 1.1): "
            + ", ".join(f"{name} {value:.3f}" for name, value in fitted.items())
        )

    size = args.sizes[-1] if args.end_to_end is None else args.end_to_end
    if size:
        row = _in_subprocess("end_to_end", size)
        print(
            f"\nend to end, {row['quads']:,.0f} quads (binary PLY → build → check → save), load average "
            f"{' '.join(f'{x:.2f}' for x in os.getloadavg())}:"
        )
        print(
            f"  read {row['read_s']:.2f} s, build {row['build_s']:.2f} s, check {row['check_s']:.2f} s while the file is written,"
            f" then {row['wait_s']:.2f} s until it is; total {row['total_s']:.2f} s (bar 30 s); process peak"
            f" {row['peak'] / 1e9:.2f} GB (bar 8 GB; {row['baseline'] / 1e9:.2f} GB before reading)"
        )
        print(
            f"  one after the other instead: check {row['alone_check_s']:.2f} s, save {row['alone_save_s']:.2f} s"
        )


if __name__ == "__main__":
    main()
