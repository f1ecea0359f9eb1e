"""Check speed: ``continuity.check`` and the fold guard's ``folded_patches`` against the build.

Workload: ``shapes.large_torus(n)`` for each ``--quads`` (default 100,000 and 1,000,000), its
Gregory network built (``build_gregory_network``) once untimed (faulting its memory in), then, in
the same run and process:

* build: the best of ``--repeats`` builds of the same network;
* check: the best of ``--repeats`` ``check(network)`` (the numba kernels) and its ratio to the
  build (target ≤ 1×), wall time and CPU time (both cores: CPU / wall ≈ 2 where the kernels run
  in parallel);
* folded_patches: ``folded_patches(patches, 9)``, the guard's call, per patch and against the
  build;
* the NumPy reference (``compiled=False``) of both, unless ``--no-reference`` (at 1 M quads the
  reference check takes minutes: ``--reference-max`` quads, default 100,000);
* peak memory of one more (untimed) build and check: the largest NumPy memory traced
  (``tracemalloc``; the kernels' per-thread scratch is a few hundred KB and not traced), in MB.

Before anything is timed: the one-time compile cost of the check kernels from an empty cache (a
subprocess with its own ``NUMBA_CACHE_DIR``), then one small check in process (loading the
cached kernels). The process runs as the command line does
(:func:`g1patch.memory.tune_for_large_arrays`); ``--no-huge-page-advice`` also turns NumPy's
huge-page advice off, for comparison. The machine's load average is printed with the table:
absolute times drift on a shared machine, ratios hold.

Run:  .venv/bin/python benchmarks/bench_check.py [--quads 100000 1000000] [--repeats 3] [--quick]
"""

from __future__ import annotations

from collections.abc import Sequence
from functools import partial
from typing import Any

import harness

from g1patch import shapes
from g1patch.build import build_gregory_network
from g1patch.continuity import check, folded_patches
from g1patch.memory import tune_for_large_arrays, without_huge_page_advice
from g1patch.network import PatchNetwork

record = harness.recorder("bench_check")
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


def measure(quads: int, repeats: int, reference: bool) -> dict[str, Any]:
    """One size's row of the table (module docstring)."""
    mesh = shapes.large_torus(quads)
    network: PatchNetwork = build_gregory_network(mesh)
    build = harness.best(lambda: build_gregory_network(mesh), repeats)
    check_wall, check_cpu, report = min(
        (harness.clocked(partial(check, network)) for _ in range(repeats)), key=lambda r: r[0]
    )
    fold_wall, fold_cpu, _ = harness.clocked(lambda: folded_patches(network.patches, 9))
    row: dict[str, Any] = {
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
    if reference:
        row["check_ref"], _, slow = harness.clocked(lambda: check(network, compiled=False))
        row["fold_ref"] = harness.timed(lambda: folded_patches(network.patches, 9, compiled=False))[
            0
        ]
        fields = ("folds", "degenerate_normals", "turn_max_deg")
        row["same"] = all(getattr(slow, f) == getattr(report, f) for f in fields)
    row["build_mb"] = harness.peak(lambda: build_gregory_network(mesh)) / 1e6
    row["check_mb"] = harness.peak(lambda: check(network)) / 1e6
    return row


def print_rows(rows: list[dict[str, Any]]) -> None:
    """The table, and its records."""
    print(f"\nload average {harness.loads()}, {harness.machine()['cores']} cores")
    print(
        f"{'quads':>9} {'build s':>8} {'check s':>8} {'/build':>7} {'cpu/wall':>8} "
        f"{'build MB':>9} {'check MB':>9} {'fold9 s':>8} {'µs/patch':>8} {'/build':>7}"
        f" {'ref check':>10} {'/build':>7} {'ref fold9':>10} {'speed-up':>8} {'same':>5}"
    )
    for row in rows:
        reference = ""
        if "check_ref" in row:
            reference = (
                f" {row['check_ref']:10.2f} {row['check_ref'] / row['build']:7.2f} "
                f"{row['fold_ref']:10.3f} {row['fold_ref'] / row['fold']:8.1f} {row['same']!s:>5}"
            )
        print(
            f"{row['quads']:9d} {row['build']:8.2f} {row['check']:8.2f} "
            f"{row['check'] / row['build']:7.2f} {row['check_cpu'] / row['check']:8.2f} "
            f"{row['build_mb']:9.0f} {row['check_mb']:9.0f} {row['fold']:8.3f} "
            f"{row['fold'] / row['patches'] * 1e6:8.2f} {row['fold'] / row['build']:7.3f}"
            f"{reference}"
        )
        size = f"{row['quads']} quads"
        record(f"build, {size}", row["build"], "s", "best")
        record(f"check, {size}", row["check"], "s", "best")
        record(f"check / build, {size}", row["check"] / row["build"], "×", "target ≤ 1")
        record(f"check cpu / wall, {size}", row["check_cpu"] / row["check"], "")
        record(f"build peak, {size}", row["build_mb"], "MB", "tracemalloc")
        record(f"check peak, {size}", row["check_mb"], "MB", "tracemalloc")
        record(f"folded_patches, {size}", row["fold"], "s", "9 samples")
        record(f"folded_patches per patch, {size}", row["fold"] / row["patches"] * 1e6, "µs")
        record(f"max G1 angle, {size}", row["g1"], "°")
        if "check_ref" in row:
            record(f"NumPy reference check, {size}", row["check_ref"], "s", "compiled=False")
            record(f"NumPy reference folded_patches, {size}", row["fold_ref"], "s")
            record(f"reference report the same, {size}", row["same"], "")


#: the command line's options (harness.Option)
OPTIONS: dict[str, harness.Option] = {
    "quads": ([100_000, 1_000_000], "quads of the tori"),
    "repeats": (3, "runs of each, the best"),
    "reference_max": (100_000, "largest network also checked by the NumPy reference"),
    "no_reference": (False, "skip the NumPy reference"),
    "no_huge_page_advice": (False, "also turn NumPy's huge-page advice off"),
    "no_compile": (False, "skip the empty-cache compile subprocess"),
}
#: the defaults --quick sets: small sizes, a smoke run
QUICK = {"quads": [20_000], "repeats": 1, "reference_max": 20_000, "no_compile": True}


def main(argv: Sequence[str] | None = None) -> None:
    args = harness.parse_args(__doc__, argv, OPTIONS, QUICK)
    tune_for_large_arrays()  # as the command line does
    if args.no_huge_page_advice:
        without_huge_page_advice()

    if not args.no_compile:
        line = harness.run_python(["-c", _COMPILE_SCRIPT], empty_cache=True)
        seconds = None if line is None else float(line)
        shown = "failed" if seconds is None else f"{seconds:.1f} s"
        print(f"compile (empty cache, subprocess): {shown}")
        if seconds is not None:
            record("compile from an empty cache", seconds, "s", "check kernels")
    small = build_gregory_network(shapes.torus(6, 4))
    load = harness.timed(
        lambda: (check(small, compiled=True), folded_patches(small.patches, compiled=True))
    )[0]
    advice = "off" if args.no_huge_page_advice else "as NumPy sets it"
    print(f"load cached kernels (in process): {load:.2f} s; huge-page advice {advice}")
    record("load cached kernels", load, "s", f"huge-page advice {advice}")
    reference = not args.no_reference
    rows = [measure(q, args.repeats, reference and q <= args.reference_max) for q in args.quads]
    print_rows(rows)


if __name__ == "__main__":
    main()
