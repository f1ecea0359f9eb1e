"""Construction speed and memory: build + check of the Gregory (exact G1) and corner networks.

Workload: ``shapes.large_torus(--quads)`` (default 1,000,000 quads, a 2000 × 500 torus; its
topology is built before anything is timed). For each construction, in the same run:

* build: ``build_network(mesh, method, shape)`` for the default Gregory network, the same with
  the previous release's rules (``shape="legacy"``) and the paper's corner network; median of
  ``--repeats`` runs after one untimed build (``first s``), which faults the build's memory in:
  on a VM that backs fresh memory lazily (here: 2 GB first touched in 27 s, again in 0.3 s) that
  cost would otherwise fall on whichever build runs first. The release before this one is also
  timed from git (``--baseline``, default the commit before the targets/assembly split; its
  ``build_gregory_network`` in a subprocess on the same mesh, also after one untimed build): the
  issue asks the default build to stay within 1.5× of it;
* build peak: the tracemalloc peak of one more build (traced separately, as tracing slows the
  allocations it records), over the memory held before it; per quad against the 1 KB bar;
* ratio: Gregory / corner (DESIGN §6: absolute times drift, ratios hold);
* check: ``continuity.check`` of each network with its defaults (33 samples per edge, 9² fold
  grid), one run under tracemalloc (time and peak), and its max G1 angles and G0 gap.

The numba kernels of the default build are compiled on first use and cached on disk; before
anything is timed the run reports, apart, their compile time from an empty cache (a subprocess
with its own ``NUMBA_CACHE_DIR``; ``--no-compile`` skips it) and the in-process warm-up
(importing numba and loading the cached kernels, one build of a small torus), so the timed
builds measure the build alone.

The process peak (``ru_maxrss``) is printed at the end. Targets (issue): build ≤ 10 s on this
2-core machine and ≤ 1 KB per quad; DESIGN §5 bar: ≤ 5 s.

Run:  .venv/bin/python benchmarks/bench_build.py [--quads N] [--repeats R] [--no-check] [--quick]
"""

from __future__ import annotations

import subprocess
import tempfile
from collections.abc import Callable, Sequence
from functools import partial
from pathlib import Path

import harness

from g1patch import shapes
from g1patch.build import build_network
from g1patch.continuity import check
from g1patch.memory import TUNED_ENVIRONMENT, tune_for_large_arrays
from g1patch.mesh import QuadMesh
from g1patch.network import PatchNetwork

record = harness.recorder("bench_build")
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
    start = time.perf_counter()
    build_gregory_network(mesh)
    times.append(time.perf_counter() - start)
print(statistics.median(times))
"""
_COMPILE_SCRIPT = """
import time
start = time.perf_counter()
from g1patch import shapes
from g1patch.build import build_network
build_network(shapes.large_torus(1000))
print(time.perf_counter() - start)
"""


def baseline_build(commit: str, quads: int, repeats: int) -> float | None:
    """Median build time of ``commit``'s Gregory network on the same mesh (a subprocess on its
    sources, run as this process runs), or None."""
    archive = subprocess.run(
        ["git", "-C", str(harness.ROOT), "archive", commit, "src"], capture_output=True
    )
    if archive.returncode:
        return None
    with tempfile.TemporaryDirectory() as folder:
        subprocess.run(["tar", "-x", "-C", folder], input=archive.stdout, check=True)
        source = str(Path(folder) / "src")
        arguments = ["-c", _BASELINE_SCRIPT, source, str(quads), str(repeats)]
        line = harness.run_python(arguments, env=TUNED_ENVIRONMENT)
    return None if line is None else float(line)


def measure_build(
    build: Callable[[QuadMesh], PatchNetwork], mesh: QuadMesh, repeats: int
) -> dict[str, float]:
    """First (untimed for the median) build, median of ``repeats`` more, tracemalloc peak."""
    first = harness.timed(lambda: build(mesh))[0]
    return {
        "first_s": first,
        "build_s": harness.median(lambda: build(mesh), repeats),
        "build_peak": harness.peak(lambda: build(mesh)),
    }


def report_builds(rows: dict[str, dict[str, float]], quads: int, repeats: int) -> None:
    """The build table, and the records of it."""
    print(f"{'construction':<16}{'build s':>9}{'peak MB':>9}{'B/quad':>8}{'first s':>9}")
    for name, row in rows.items():
        peak = row["build_peak"]
        print(
            f"{name:<16}{row['build_s']:>9.2f}{peak / 1e6:>9.0f}{peak / quads:>8.0f}"
            f"{row['first_s']:>9.2f}"
        )
        record(f"{name} build", row["build_s"], "s", f"median of {repeats}")
        record(f"{name} first build", row["first_s"], "s", "untimed for the median")
        record(f"{name} build peak", peak / 1e6, "MB", "tracemalloc")
        record(f"{name} build peak per quad", peak / quads, "B/quad")
    gregory = rows["gregory"]
    for other in ("corner", "gregory·legacy"):
        time_ratio = gregory["build_s"] / rows[other]["build_s"]
        peak_ratio = gregory["build_peak"] / rows[other]["build_peak"]
        label = f"gregory / {other.removeprefix('gregory·')}"
        print(f"{label:<16}{time_ratio:>9.2f}{peak_ratio:>9.2f}")
        record(f"{label} build time", time_ratio, "×")
        record(f"{label} build peak", peak_ratio, "×")


def report_checks(mesh: QuadMesh) -> None:
    """One traced check of each construction's network."""
    quads = mesh.n_faces
    for name, build in BUILDERS.items():
        network = build(mesh)
        seconds, peak, report = harness.traced(partial(check, network))
        print(
            f"check ({name}, traced): {seconds:.1f} s, peak {peak / 1e6:.0f} MB "
            f"({peak / quads:.0f} B/quad), max G1 angle on edges "
            f"{report.max_edge_angle_deg:.2e}°, at corners {report.max_corner_angle_deg:.2e}°, "
            f"max G0 gap {report.max_g0_gap:.1e}"
        )
        record(f"{name} check", seconds, "s", "traced")
        record(f"{name} check peak per quad", peak / quads, "B/quad")
        record(f"{name} max G1 angle on edges", report.max_edge_angle_deg, "°")
        record(f"{name} max G1 angle at corners", report.max_corner_angle_deg, "°")
        record(f"{name} max G0 gap", report.max_g0_gap, "")
        del network


#: the command line's options (harness.Option)
OPTIONS: dict[str, harness.Option] = {
    "quads": (1_000_000, "quads of the torus"),
    "repeats": (3, "timed builds per construction, the median"),
    "no_check": (False, "skip the checks"),
    "no_compile": (False, "skip the empty-cache compile subprocess"),
    "baseline": (BASELINE, "git commit of the previous release, '' skips it"),
}
#: the defaults --quick sets: small sizes, a smoke run
QUICK = {"quads": 20_000, "repeats": 1, "baseline": "", "no_compile": True}


def main(argv: Sequence[str] | None = None) -> None:
    args = harness.parse_args(__doc__, argv, OPTIONS, QUICK)
    tune_for_large_arrays()  # as the command line does (g1patch.memory)

    line = None if args.no_compile else harness.run_python(["-c", _COMPILE_SCRIPT], None, True)
    cold = None if line is None else float(line)
    warm, _ = harness.timed(lambda: build_network(shapes.large_torus(1000), "gregory"))
    print(
        f"numba kernels: compile from an empty cache "
        f"{'not measured' if cold is None else f'{cold:.1f} s'} (first build of a 1000-quad "
        f"torus in a fresh process); warm-up here (import + cached kernels) {warm:.1f} s, "
        "not timed below"
    )
    if cold is not None:
        record("compile from an empty cache", cold, "s", "fresh process, 1000-quad torus")
    record("warm-up", warm, "s", "import + cached kernels")
    seconds, mesh = harness.timed(lambda: shapes.large_torus(args.quads))
    quads = mesh.n_faces
    print(harness.machine_line())
    print(
        f"mesh: large_torus({args.quads}) → {quads:,} quads, {mesh.n_vertices:,} vertices "
        f"(made in {seconds:.1f} s)\n"
    )
    record("quads", quads, "quads", f"shapes.large_torus({args.quads})")

    rows = {name: measure_build(build, mesh, args.repeats) for name, build in BUILDERS.items()}
    report_builds(rows, quads, args.repeats)
    before = baseline_build(args.baseline, args.quads, args.repeats) if args.baseline else None
    if before is not None:
        ratio = rows["gregory"]["build_s"] / before
        print(
            f"{'release ' + args.baseline:<16}{before:>9.2f}      (gregory / it: {ratio:.2f}, "
            "bar 1.5)"
        )
        record("release build", before, "s", f"{args.baseline}, median of {args.repeats}")
        record("gregory / release build time", ratio, "×", "bar 1.5")
    if not args.no_check:
        print()
        report_checks(mesh)
    process = harness.process_peak()
    print(
        f"\ntargets: build ≤ 10 s (DESIGN bar 5 s), ≤ 1000 B/quad; process peak (ru_maxrss) "
        f"{process / 1e6:.0f} MB"
    )
    record("process peak", process / 1e6, "MB", "ru_maxrss")


if __name__ == "__main__":
    main()
