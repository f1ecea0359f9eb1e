"""Fuzzing at scale: 10,000 hostile inputs through build → check → export → render.

The cases are those of ``tests/fuzzing.py`` (seeds 0 … N − 1; the CI test draws its seeds with
hypothesis), run by a pool of worker processes so that a crash inside a native library kills a
worker, not the run: a crashed case is counted and the pool restarted. Every 20th case also
exports STEP through OpenCASCADE, every 5th renders a PNG. Per worker the resident peak is
checked against ``--memory-cap``.

Summary table: cases, commands run, exit codes, tracebacks, crashes, leftover files, NaN in
reports, slow commands, other broken promises, time; then the first findings, one line each.

Run:  .venv/bin/python benchmarks/fuzz.py [--cases N] [--workers W] [--memory-cap MB] [--quick]
"""

from __future__ import annotations

import collections
import multiprocessing
import os
import sys
import tempfile
import time
from collections.abc import Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from concurrent.futures.process import BrokenProcessPool
from pathlib import Path

import harness

sys.path.insert(0, str(harness.ROOT / "tests"))

import fuzzing  # noqa: E402

record = harness.recorder("fuzz")
TASKS_PER_WORKER = 200  #: cases a worker runs before its pool is replaced


def one_case(seed: int) -> tuple[int, list[int | None], list[str], float]:
    """Run case ``seed`` in a fresh directory: (seed, exit codes, findings, resident peak in MB)."""
    import warnings

    warnings.simplefilter("ignore")
    with tempfile.TemporaryDirectory() as directory:
        case = fuzzing.make_case(seed, Path(directory))
        outcomes = fuzzing.run_case(case, render=seed % 5 == 0, cad=seed % 20 == 0)
        found = fuzzing.problems(case, outcomes)
    peak = harness.process_peak() / 2**20
    return seed, [outcome.code for outcome in outcomes], found, peak


def _warm_up() -> None:
    """Build one small mesh untimed, so that the kernels' one-time compile (into numba's disk cache,
    which the workers share) is not counted as the first case's slow command."""
    from g1patch import shapes
    from g1patch.build import build_network

    build_network(shapes.cube_sphere(1))


#: the command line's options (harness.Option)
OPTIONS: dict[str, harness.Option] = {
    "cases": (10_000, "hostile inputs"),
    "workers": (os.cpu_count() or 2, "worker processes"),
    "memory_cap": (4096.0, "MB of resident memory per worker"),
}
#: the defaults --quick sets: small sizes, a smoke run
QUICK = {"cases": 20}


def main(argv: Sequence[str] | None = None) -> None:
    args = harness.parse_args(__doc__, argv, OPTIONS, QUICK)

    _warm_up()
    start = time.perf_counter()
    codes: collections.Counter[int | None] = collections.Counter()
    findings: list[str] = []
    crashes: list[int] = []
    peak = 0.0
    pending = list(range(args.cases))
    while pending:
        # a fresh pool per chunk of TASKS_PER_WORKER cases a worker, so no worker's memory grows
        # over the run (max_tasks_per_child hangs the pool once a worker retires, on Python 3.11)
        chunk = pending[: args.workers * TASKS_PER_WORKER]
        with ProcessPoolExecutor(
            args.workers, mp_context=multiprocessing.get_context("spawn")
        ) as pool:
            futures = {pool.submit(one_case, seed): seed for seed in chunk}
            done: set[int] = set()
            try:
                for future in as_completed(futures):
                    seed, case_codes, found, case_peak = future.result()
                    done.add(seed)
                    codes.update(case_codes)
                    findings += found
                    peak = max(peak, case_peak)
                    if case_peak > args.memory_cap:
                        findings.append(
                            f"seed {seed}: worker resident peak {case_peak:.0f} MB above "
                            f"{args.memory_cap:.0f} MB"
                        )
            except BrokenProcessPool:
                running = [s for f, s in futures.items() if s not in done and not f.done()]
                broken = [
                    s
                    for f, s in futures.items()
                    if s not in done and f.done() and f.exception() is not None
                ]
                crashes += broken[:1] or running[:1]
                first = (broken[:1] or running[:1])[0]
                findings.append(f"seed {first}: a worker crashed (native crash or killed)")
                done.update(crashes)
        pending = [seed for seed in pending if seed not in done]
        print(
            f"fuzz: {args.cases - len(pending)} of {args.cases} cases, "
            f"{time.perf_counter() - start:.0f} s",
            file=sys.stderr,
        )

    categories = {
        "tracebacks": "traceback",
        "leftover files": ": left ",
        "NaN in reports": "NaN",
        "slow commands": " took ",
        "crashes": "crashed",
    }
    counted = {
        name: sum(1 for line in findings if marker in line) for name, marker in categories.items()
    }
    commands = sum(codes.values())
    elapsed = time.perf_counter() - start
    print(f"fuzz: {args.cases} cases, {args.workers} workers, load average {harness.loads()}")
    print("| measure | value |")
    print("|---|---|")
    rows = [
        ("cases", args.cases),
        ("commands run", commands),
        ("exit 0 / 1 / 2", f"{codes.get(0, 0)} / {codes.get(1, 0)} / {codes.get(2, 0)}"),
        ("other exit codes", sum(n for code, n in codes.items() if code not in (0, 1, 2))),
        *((name, counted[name]) for name in categories),
        ("other broken promises", len(findings) - sum(counted.values())),
        ("largest worker resident peak", f"{peak:.0f} MB"),
        ("time", f"{elapsed / 60:.1f} min"),
    ]
    for name, value in rows:
        print(f"| {name} | {value} |")
    record("cases", args.cases)
    record("commands run", commands)
    for code in (0, 1, 2):
        record(f"exit {code}", codes.get(code, 0), "commands")
    for name, value in rows[3:-2]:  # other exit codes, the categories, other broken promises
        record(name, value)
    record("largest worker resident peak", peak, "MiB")
    record("time", elapsed / 60, "min")
    for line in findings[:50]:
        print(line)
    sys.exit(1 if findings else 0)


if __name__ == "__main__":
    main()
