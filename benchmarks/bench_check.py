"""Check speed: ``continuity.check`` and the fold guard's ``folded_patches`` against the build.

Workload: ``shapes.large_torus(n)`` for each ``--quads`` (default 100,000 and 1,000,000), its
Gregory network built (``build_gregory_network``) once untimed (faulting its memory in), then, in
the same run and process:

* build: the best of ``--repeats`` builds of the same network;
* check: the best of ``--repeats`` ``check(network)`` (the numba kernels) and its ratio to the
  build (target ≤ 1×), wall time and CPU time (both cores: CPU / wall ≈ 2 where the kernels run in parallel);
* folded_patches: ``folded_patches(patches, 9)``, the guard's call, per patch and against the build;
* the NumPy reference (``compiled=False``) of both, unless ``--no-reference`` (at 1 M quads the
  reference check takes minutes: ``--reference-max`` quads, default 100,000);
* peak memory of one more (untimed) build and check: the largest NumPy memory traced
  (``tracemalloc``; the kernels' per-thread scratch is a few hundred KB and not traced), in MB.

Before anything is timed: the one-time compile cost of the check kernels from an empty cache (a
subprocess with its own ``NUMBA_CACHE_DIR``), then one small check in process (loading the cached
kernels). The process runs as the command line does (:func:`g1patch.memory.tune_for_large_arrays`);
``--no-huge-page-advice`` also turns NumPy's huge-page advice off, for comparison. The machine's
load average is printed with the table: absolute times drift on a shared machine, ratios hold.

Run:  .venv/bin/python benchmarks/bench_check.py [--quads 100000 1000000] [--repeats 3]
"""

from __future__ import annotations

import argparse
import os
import time
import tracemalloc
from collections.abc import Callable
from typing import TypeVar

import numpy as np

from g1patch import shapes
from g1patch.build import build_gregory_network
from g1patch.continuity import check, folded_patches
from g1patch.memory import tune_for_large_arrays, without_huge_page_advice

T = TypeVar("T")

_COMPILE_SCRIPT = """
import time
start = time.perf_counter()
from g1patch import shapes
from g1patch.build import build_gregory_network
from g1patch.continuity import check, folded_patches
network = build_gregory_network(shapes.torus(6, 4))
built = time.perf_counter()
check(network, compiled=True)
folded_patches(network.patches, compiled=True)
print(time.perf_counter() - built)
"""


def timed(run: Callable[[], T]) -> tuple[T, float, float]:
    """``run()``, its wall and CPU (all threads) seconds."""
    wall, cpu = time.perf_counter(), time.process_time()
    result = run()
    return result, time.perf_counter() - wall, time.process_time() - cpu


def peak_mb(run: Callable[[], object]) -> float:
    """The peak of the memory traced by ``tracemalloc`` (NumPy arrays included) while ``run()`` runs, in MB."""
    tracemalloc.start()
    try:
        run()
        return tracemalloc.get_traced_memory()[1] / 1e6
    finally:
        tracemalloc.stop()


def compile_seconds() -> float | None:
    """Seconds to compile the check kernels into an empty numba cache (a subprocess), or None on failure."""
    import subprocess
    import sys
    import tempfile

    with tempfile.TemporaryDirectory() as cache:
        result = subprocess.run(
            [sys.executable, "-c", _COMPILE_SCRIPT],
            capture_output=True,
            text=True,
            env={**os.environ, "NUMBA_CACHE_DIR": cache},
        )
        return float(result.stdout.strip()) if result.returncode == 0 else None


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--quads", type=int, nargs="+", default=[100_000, 1_000_000])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument(
        "--reference-max",
        type=int,
        default=100_000,
        help="largest network also checked by the NumPy reference",
    )
    parser.add_argument("--no-reference", action="store_true")
    parser.add_argument(
        "--no-huge-page-advice", action="store_true", help="also turn NumPy's huge-page advice off"
    )
    parser.add_argument(
        "--no-compile", action="store_true", help="skip the empty-cache compile subprocess"
    )
    args = parser.parse_args()
    tune_for_large_arrays()  # as the command line does
    if args.no_huge_page_advice:
        without_huge_page_advice()

    if not args.no_compile:
        seconds = compile_seconds()
        print(
            f"compile (empty cache, subprocess): {'failed' if seconds is None else f'{seconds:.1f} s'}"
        )
    small = build_gregory_network(shapes.torus(6, 4))
    _, load, _ = timed(
        lambda: (check(small, compiled=True), folded_patches(small.patches, compiled=True))
    )
    print(
        f"load cached kernels (in process): {load:.2f} s; huge-page advice {'off' if args.no_huge_page_advice else 'as NumPy sets it'}"
    )

    rows = []
    for quads in args.quads:
        mesh = shapes.large_torus(quads)
        network = build_gregory_network(mesh)
        build = min(timed(lambda: build_gregory_network(mesh))[1] for _ in range(args.repeats))
        report, check_wall, check_cpu = min(
            (timed(lambda: check(network)) for _ in range(args.repeats)), key=lambda run: run[1]
        )
        _, fold_wall, fold_cpu = timed(lambda: folded_patches(network.patches, 9))
        row = {
            "quads": quads,
            "patches": len(network.patches),
            "build": build,
            "check": check_wall,
            "check_cpu": check_cpu,
            "fold": fold_wall,
            "fold_cpu": fold_cpu,
            "g1": report.max_edge_angle_deg,
            "folds": report.folds,
        }
        if not args.no_reference and quads <= args.reference_max:
            reference, row["check_ref"], _ = timed(lambda: check(network, compiled=False))
            _, row["fold_ref"], _ = timed(
                lambda: folded_patches(network.patches, 9, compiled=False)
            )
            row["same"] = (
                reference.folds,
                reference.degenerate_normals,
                reference.turn_max_deg,
            ) == (report.folds, report.degenerate_normals, report.turn_max_deg)
        row["build_mb"], row["check_mb"] = (
            peak_mb(lambda: build_gregory_network(mesh)),
            peak_mb(lambda: check(network)),
        )
        rows.append(row)

    print(f"\nload average {' '.join(f'{x:.2f}' for x in os.getloadavg())}, {os.cpu_count()} cores")
    print(
        f"{'quads':>9} {'build s':>8} {'check s':>8} {'/build':>7} {'cpu/wall':>8} {'build MB':>9} {'check MB':>9}"
        f" {'fold9 s':>8} {'µs/patch':>8} {'/build':>7}"
        f" {'ref check':>10} {'/build':>7} {'ref fold9':>10} {'speed-up':>8} {'same':>5}"
    )
    for row in rows:
        reference = ""
        if "check_ref" in row:
            reference = (
                f" {row['check_ref']:10.2f} {row['check_ref'] / row['build']:7.2f} {row['fold_ref']:10.3f}"
                f" {row['fold_ref'] / row['fold']:8.1f} {row['same']!s:>5}"
            )
        print(
            f"{row['quads']:9d} {row['build']:8.2f} {row['check']:8.2f} {row['check'] / row['build']:7.2f}"
            f" {row['check_cpu'] / row['check']:8.2f} {row['build_mb']:9.0f} {row['check_mb']:9.0f} {row['fold']:8.3f} {row['fold'] / row['patches'] * 1e6:8.2f}"
            f" {row['fold'] / row['build']:7.3f}{reference}"
        )


if __name__ == "__main__":
    main()
