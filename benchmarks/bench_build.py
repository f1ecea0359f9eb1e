"""Construction speed and memory: build + check of the Gregory (exact G1) and corner networks.

Workload: ``shapes.large_torus(--quads)`` (default 1,000,000 quads, a 2000 × 500 torus; its
topology is built before anything is timed). For each construction, in the same run:

* build: ``build_gregory_network(mesh)`` / ``build_corner_network(mesh)`` (tangents "arc",
  everything from the fan normals to the PatchNetwork); median of ``--repeats`` runs;
* build peak: the tracemalloc peak of one more build (traced separately, as tracing slows the
  allocations it records), over the memory held before it; per quad against the 1 KB bar;
* ratio: Gregory / corner (DESIGN §6: absolute times drift, ratios hold);
* check: ``continuity.check`` of each network with its defaults (33 samples per edge, 9² fold
  grid), one run under tracemalloc (time and peak), and its max G1 angles and G0 gap.

The process peak (``ru_maxrss``) is printed at the end. Targets (issue): build ≤ 10 s on this
2-core machine and ≤ 1 KB per quad; DESIGN §5 bar: ≤ 5 s.

Run:  .venv/bin/python benchmarks/bench_build.py [--quads N] [--repeats R] [--no-check]
"""

from __future__ import annotations

import argparse
import os
import platform
import resource
import statistics
import time
import tracemalloc
from collections.abc import Callable
from typing import TypeVar

from g1patch import shapes
from g1patch.construct.corner import build_corner_network
from g1patch.build import build_gregory_network
from g1patch.continuity import check
from g1patch.mesh import QuadMesh
from g1patch.network import PatchNetwork

T = TypeVar("T")
BUILDERS: dict[str, Callable[[QuadMesh], PatchNetwork]] = {
    "gregory": build_gregory_network,
    "corner": build_corner_network,
}


def timed(function: Callable[[], T]) -> tuple[float, T]:
    start = time.perf_counter()
    result = function()
    return time.perf_counter() - start, result


def traced(function: Callable[[], T]) -> tuple[float, int, T]:
    """Seconds, and bytes allocated at the peak above what was held when ``function()`` started."""
    tracemalloc.start()
    try:
        seconds, result = timed(function)
        return seconds, tracemalloc.get_traced_memory()[1], result
    finally:
        tracemalloc.stop()


def measure_build(build: Callable[[QuadMesh], PatchNetwork], mesh: QuadMesh, repeats: int) -> dict[str, float]:
    times = [timed(lambda: build(mesh))[0] for _ in range(repeats)]
    return {"build_s": statistics.median(times), "build_peak": traced(lambda: build(mesh))[1]}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quads", type=int, default=1_000_000, help="quads of the generated torus (default 1,000,000)")
    parser.add_argument("--repeats", type=int, default=3, help="timed builds per construction, median reported (default 3)")
    parser.add_argument("--no-check", action="store_true", help="skip the checks")
    args = parser.parse_args()

    seconds, mesh = timed(lambda: shapes.large_torus(args.quads))
    quads = mesh.n_faces
    print(f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores, python {platform.python_version()}")
    print(f"mesh: large_torus({args.quads}) → {quads:,} quads, {mesh.n_vertices:,} vertices (made in {seconds:.1f} s)\n")

    rows = {name: measure_build(build, mesh, args.repeats) for name, build in BUILDERS.items()}
    print(f"{'construction':<16}{'build s':>9}{'peak MB':>9}{'B/quad':>8}")
    for name, row in rows.items():
        print(f"{name:<16}{row['build_s']:>9.2f}{row['build_peak'] / 1e6:>9.0f}{row['build_peak'] / quads:>8.0f}")
    gregory, corner = rows["gregory"], rows["corner"]
    print(f"{'gregory / corner':<16}{gregory['build_s'] / corner['build_s']:>9.2f}{gregory['build_peak'] / corner['build_peak']:>9.2f}")
    if not args.no_check:
        print()
        for name, build in BUILDERS.items():
            network = build(mesh)
            seconds, peak, report = traced(lambda: check(network))  # noqa: B023 (called at once)
            print(f"check ({name}, traced): {seconds:.1f} s, peak {peak / 1e6:.0f} MB ({peak / quads:.0f} B/quad), "
                  f"max G1 angle on edges {report.max_edge_angle_deg:.2e}°, at corners {report.max_corner_angle_deg:.2e}°, "
                  f"max G0 gap {report.max_g0_gap:.1e}")
            del network
    print(f"\ntargets: build ≤ 10 s (DESIGN bar 5 s), ≤ 1000 B/quad; process peak (ru_maxrss) "
          f"{resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1e3:.0f} MB")


if __name__ == "__main__":
    main()
