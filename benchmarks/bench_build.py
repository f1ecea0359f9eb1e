"""Construction speed and memory: build + check of the Gregory (exact G1) and corner networks.

Workload: ``shapes.large_torus(--quads)`` (default 1,000,000 quads, a 2000 × 500 torus; its
topology is built before anything is timed). For each construction, in the same run:

* build: ``build_network(mesh, method, shape)`` for the default Gregory network, the same with the
  previous release's rules (``shape="legacy"``) and the paper's corner network; median of
  ``--repeats`` runs after one untimed build (``first s``), which faults the build's memory in: on
  a VM that backs fresh memory lazily (here: 2 GB first touched in 27 s, again in 0.3 s) that cost
  would otherwise fall on whichever build runs first. The release before this one is also timed
  from git (``--baseline``, default the commit before the targets/assembly split; its
  ``build_gregory_network`` in a subprocess on the same mesh, also after one untimed build): the
  issue asks the default build to stay within 1.5× of it;
* build peak: the tracemalloc peak of one more build (traced separately, as tracing slows the
  allocations it records), over the memory held before it; per quad against the 1 KB bar;
* ratio: Gregory / corner (DESIGN §6: absolute times drift, ratios hold);
* check: ``continuity.check`` of each network with its defaults (33 samples per edge, 9² fold
  grid), one run under tracemalloc (time and peak), and its max G1 angles and G0 gap.

The numba kernels of the default build are compiled on first use and cached on disk; before
anything is timed the run reports, apart, their compile time from an empty cache (a subprocess
with its own ``NUMBA_CACHE_DIR``) and the in-process warm-up (importing numba and loading the
cached kernels, one build of a small torus), so the timed builds measure the build alone.

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
from g1patch.build import build_network
from g1patch.continuity import check
from g1patch.memory import TUNED_ENVIRONMENT, tune_for_large_arrays
from g1patch.mesh import QuadMesh
from g1patch.network import PatchNetwork

T = TypeVar("T")
BUILDERS: dict[str, Callable[[QuadMesh], PatchNetwork]] = {
    "gregory": lambda mesh: build_network(mesh, "gregory"),
    "gregory·legacy": lambda mesh: build_network(mesh, "gregory", "legacy"),
    "corner": lambda mesh: build_network(mesh, "corner"),
}
#: the commit before shape targets and the assembly were split (issue 9)
BASELINE = "439cb54"
_BASELINE_SCRIPT = """
import sys, time, statistics
sys.path.insert(0, sys.argv[1])
from g1patch import shapes
from g1patch.construct.gregory import build_gregory_network
mesh = shapes.large_torus(int(sys.argv[2]))
build_gregory_network(mesh)  # untimed, as for the builds of this release
times = []
for _ in range(int(sys.argv[3])):
    start = time.perf_counter(); build_gregory_network(mesh); times.append(time.perf_counter() - start)
print(statistics.median(times))
"""


def baseline_build(commit: str, quads: int, repeats: int) -> float | None:
    """Median build time of ``commit``'s Gregory network on the same mesh (a subprocess on its sources), or None."""
    import subprocess
    import sys
    import tempfile
    from pathlib import Path

    root = Path(__file__).resolve().parents[1]
    with tempfile.TemporaryDirectory() as folder:
        archive = subprocess.run(
            ["git", "-C", str(root), "archive", commit, "src"], capture_output=True
        )
        if archive.returncode:
            return None
        subprocess.run(["tar", "-x", "-C", folder], input=archive.stdout, check=True)
        result = subprocess.run(
            [
                sys.executable,
                "-c",
                _BASELINE_SCRIPT,
                str(Path(folder) / "src"),
                str(quads),
                str(repeats),
            ],
            capture_output=True,
            text=True,
            env={**os.environ, **TUNED_ENVIRONMENT},
        )  # as this process runs
        return float(result.stdout.strip()) if result.returncode == 0 else None


_COMPILE_SCRIPT = """
import time
start = time.perf_counter()
from g1patch import shapes
from g1patch.build import build_network
build_network(shapes.large_torus(1000))
print(time.perf_counter() - start)
"""


def compile_time() -> float | None:
    """Seconds of a first build of a small torus in a fresh process with an empty numba cache
    (compiling every kernel), or None."""
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


def measure_build(
    build: Callable[[QuadMesh], PatchNetwork], mesh: QuadMesh, repeats: int
) -> dict[str, float]:
    first = timed(lambda: build(mesh))[0]
    times = [timed(lambda: build(mesh))[0] for _ in range(repeats)]
    return {
        "first_s": first,
        "build_s": statistics.median(times),
        "build_peak": traced(lambda: build(mesh))[1],
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--quads",
        type=int,
        default=1_000_000,
        help="quads of the generated torus (default 1,000,000)",
    )
    parser.add_argument(
        "--repeats",
        type=int,
        default=3,
        help="timed builds per construction, median reported (default 3)",
    )
    parser.add_argument("--no-check", action="store_true", help="skip the checks")
    parser.add_argument(
        "--baseline",
        default=BASELINE,
        help=f"git commit of the previous release (default {BASELINE}); '' skips it",
    )
    args = parser.parse_args()
    tune_for_large_arrays()  # as the command line does (g1patch.memory)

    cold = compile_time()
    warm, _ = timed(lambda: build_network(shapes.large_torus(1000)))
    print(
        f"numba kernels: compile from an empty cache {cold if cold is None else round(cold, 1)} s (first build of a "
        f"1000-quad torus in a fresh process); warm-up here (import + cached kernels) {warm:.1f} s, not timed below"
    )
    seconds, mesh = timed(lambda: shapes.large_torus(args.quads))
    quads = mesh.n_faces
    print(
        f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores, python {platform.python_version()}"
    )
    print(
        f"mesh: large_torus({args.quads}) → {quads:,} quads, {mesh.n_vertices:,} vertices (made in {seconds:.1f} s)\n"
    )

    rows = {name: measure_build(build, mesh, args.repeats) for name, build in BUILDERS.items()}
    print(f"{'construction':<16}{'build s':>9}{'peak MB':>9}{'B/quad':>8}{'first s':>9}")
    for name, row in rows.items():
        print(
            f"{name:<16}{row['build_s']:>9.2f}{row['build_peak'] / 1e6:>9.0f}{row['build_peak'] / quads:>8.0f}"
            f"{row['first_s']:>9.2f}"
        )
    gregory, corner = rows["gregory"], rows["corner"]
    print(
        f"{'gregory / corner':<16}{gregory['build_s'] / corner['build_s']:>9.2f}{gregory['build_peak'] / corner['build_peak']:>9.2f}"
    )
    legacy = rows["gregory·legacy"]
    print(
        f"{'gregory / legacy':<16}{gregory['build_s'] / legacy['build_s']:>9.2f}{gregory['build_peak'] / legacy['build_peak']:>9.2f}"
    )
    before = baseline_build(args.baseline, args.quads, args.repeats) if args.baseline else None
    if before is not None:
        print(
            f"{'release ' + args.baseline:<16}{before:>9.2f}      (gregory / it: {gregory['build_s'] / before:.2f}, bar 1.5)"
        )
    if not args.no_check:
        print()
        for name, build in BUILDERS.items():
            network = build(mesh)
            seconds, peak, report = traced(lambda: check(network))  # noqa: B023 (called at once)
            print(
                f"check ({name}, traced): {seconds:.1f} s, peak {peak / 1e6:.0f} MB ({peak / quads:.0f} B/quad), "
                f"max G1 angle on edges {report.max_edge_angle_deg:.2e}°, at corners {report.max_corner_angle_deg:.2e}°, "
                f"max G0 gap {report.max_g0_gap:.1e}"
            )
            del network
    print(
        f"\ntargets: build ≤ 10 s (DESIGN bar 5 s), ≤ 1000 B/quad; process peak (ru_maxrss) "
        f"{resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1e3:.0f} MB"
    )


if __name__ == "__main__":
    main()
