"""Tessellation speed: positions, and positions + unit normals, of Bézier patches on a grid.

Workload: N random bicubic Bézier patches (a jittered 4×4 control net over a unit cell plus a
random height), each sampled on a G×G grid (u, v = linspace(0, 1, G)); output (N, G, G, 3)
C-contiguous float64. Defaults: N = 10,000, G = 32 (10.24 M points).

Everything in the table is measured in this run (DESIGN §6: absolute times drift on shared
machines, ratios hold):

* "× numpy" — against the plain NumPy baseline: ``einsum('ai,nijd,bj->nabd')`` made contiguous,
  and for normals the same for p_u and p_v, then ``np.cross`` and ``x / |x|``;
* "× splipy" — against splipy on the same patches: one ``splipy.Surface`` per patch, evaluated on
  the grid (``surface(u, v)``; normals from ``surface.derivative(u, v, d=(1, 0))`` and
  ``d=(0, 1)``, ``np.cross``, normalised). splipy runs on the first ``--splipy-patches`` patches
  and its time is scaled linearly to N (its cost is a fixed ~100 µs per patch plus per point
  work);
* "% bound" — against the memory-bandwidth bound: ``np.copyto`` on a 1 GiB array
  (``--copy-mib``), in GB/s (bytes copied), divided by the bytes written per point (24 for
  positions, 48 for positions + normals).

Rows "fresh output" call the public PatchSet methods, which allocate their results with
``np.empty``; rows "out=" run the same public methods into preallocated arrays, the situation the
copyto bound describes. At this size the methods run the compiled kernels
(``g1patch._grid.KERNEL_POINTS``); the rows "NumPy path" run the same functions with
``compiled=False``, the NumPy code the kernels replace above that size (and their reference).

This process runs as the command line does (:func:`g1patch.memory.tune_for_large_arrays`: freed
memory kept by glibc's malloc, NumPy's huge-page advice as NumPy sets it), so a fresh output
reuses pages an earlier array freed. With glibc's defaults every fresh output is a new mapping
whose pages the kernel faults in and zeroes on first write (0.2-2 GB/s on this VM): a child
process (``--glibc-defaults``, the same but for the allocator) times the fresh rows that way too,
and the summary sets them beside the time ``np.empty`` + ``fill`` takes for the same bytes of new
pages, on one thread and split over two. Those new pages do not stay fast however they are
mapped: the VM these benchmarks run on hands free 2 MiB blocks back to the hypervisor within
seconds (virtio-balloon free page reporting), and re-backing one cost 2-12 ms, which is why the
command line keeps freed memory instead. Before timing, every tool's output is checked against
the baseline with ``np.allclose`` (tolerances in :func:`check`).

Each figure is the median of ``--repeats`` rounds; within a round every tool (and the copyto)
runs once, round-robin, so that load from other processes on a shared machine falls on all of
them alike. A first round warms up the g1patch kernels and is not counted. CPU time (process
time) is printed beside the wall-clock time; "CPU % of bound" is the same ratio computed from CPU
times of both the tool and the copyto, which is less sensitive to other processes taking the
cores. About 50 s on an idle 2-core machine.

Run:  .venv/bin/python benchmarks/bench_evaluate.py [--patches N] [--grid G] [--repeats R]
      [--splipy-patches S] [--copy-mib M] [--quick]
"""

from __future__ import annotations

import argparse
import json
import statistics
import time
from collections.abc import Callable, Sequence
from concurrent.futures import ThreadPoolExecutor
from typing import Any

import harness
import numpy as np

from g1patch import _grid
from g1patch.basis import basis_values
from g1patch.memory import tune_for_large_arrays
from g1patch.patches import PatchSet

EPS = np.finfo(np.float64).eps
record = harness.recorder("bench_evaluate")
#: a tool: label, call, factor its time is scaled by (splipy's subset), note
Tool = tuple[str, Callable[[], object], float, str]


# --------------------------------------------------------------------------------- workload
def make_patches(n: int, seed: int = 0) -> np.ndarray:
    """Random but valid Bézier patches: a jittered 4×4 net over a unit cell, random heights."""
    rng = np.random.default_rng(seed)
    steps = np.arange(4) / 3.0
    cell = np.stack(np.meshgrid(steps, steps, indexing="ij"), axis=-1)  # (4, 4, 2)
    control = np.empty((n, 4, 4, 3))
    control[..., :2] = cell + rng.uniform(-0.1, 0.1, size=(n, 4, 4, 2))
    control[..., 2] = rng.uniform(-0.3, 0.3, size=(n, 4, 4))
    return control


# --------------------------------------------------------------------------------- baseline
def numpy_positions(control: np.ndarray, u: np.ndarray) -> np.ndarray:
    b = basis_values("bezier", u)
    return np.ascontiguousarray(np.einsum("ai,nijd,bj->nabd", b, control, b, optimize=True))


def numpy_positions_normals(control: np.ndarray, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    b, db = basis_values("bezier", u), basis_values("bezier", u, 1)
    positions = np.ascontiguousarray(np.einsum("ai,nijd,bj->nabd", b, control, b, optimize=True))
    p_u = np.ascontiguousarray(np.einsum("ai,nijd,bj->nabd", db, control, b, optimize=True))
    p_v = np.ascontiguousarray(np.einsum("ai,nijd,bj->nabd", b, control, db, optimize=True))
    cross = np.cross(p_u, p_v)
    length = np.linalg.norm(cross, axis=-1, keepdims=True)
    return positions, np.divide(cross, length, out=np.zeros_like(cross), where=length > 0)


# ----------------------------------------------------------------------------------- splipy
def splipy_surfaces(control: np.ndarray) -> list:
    from splipy import BSplineBasis, Surface

    basis = BSplineBasis(4, [0, 0, 0, 0, 1, 1, 1, 1])  # one Bézier span
    # splipy's control points run with the first (u) index fastest
    return [Surface(basis, basis, net.transpose(1, 0, 2).reshape(16, 3)) for net in control]


def splipy_positions(surfaces: list, u: np.ndarray) -> np.ndarray:
    out = np.empty((len(surfaces), u.size, u.size, 3))
    for k, surface in enumerate(surfaces):
        out[k] = surface(u, u)
    return out


def splipy_positions_normals(surfaces: list, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    positions = np.empty((len(surfaces), u.size, u.size, 3))
    normals = np.empty_like(positions)
    for k, surface in enumerate(surfaces):
        positions[k] = surface(u, u)
        cross = np.cross(surface.derivative(u, u, d=(1, 0)), surface.derivative(u, u, d=(0, 1)))
        length = np.linalg.norm(cross, axis=-1, keepdims=True)
        normals[k] = np.divide(cross, length, out=np.zeros_like(cross), where=length > 0)
    return positions, normals


# --------------------------------------------------------------------------------- checking
def check(name: str, control: np.ndarray, u: np.ndarray, got: tuple, expected: tuple) -> None:
    """np.allclose against the baseline with forward-error tolerances (ULP-scaled).

    Positions: both sides compute the 16-term sum Σ b_i P_ij b_j, each within
    γ_8 Σ|b_i||P_ij||b_j| of the exact value (≤ 8 roundings per term); Bernstein weights are ≥ 0
    and sum to 1, so Σ|b_i||P_ij||b_j| ≤ max|P|, and atol = 16 eps max|P|.
    Normals: c = p_u × p_v differs by ≤ 48 eps |S| between any two ways of evaluating it
    (S_d = |p_u|_i |p_v|_k + |p_u|_k |p_v|_i with absolute-value evaluations; see
    tests/test_grid_kernels.py), which moves the unit normal by ≤ 2·48 eps |S| / |c|, plus 4 eps
    for the normalisations: atol = 96 eps |S| / |c| + 4 eps per point.
    """
    atol = 16 * EPS * np.abs(control).max()
    if not np.allclose(got[0], expected[0], rtol=0, atol=atol):
        worst = np.abs(got[0] - expected[0]).max()
        raise SystemExit(f"{name}: positions differ from the baseline by {worst:.3g} > {atol:.3g}")
    if len(got) == 1:
        return
    b, db = basis_values("bezier", u), basis_values("bezier", u, 1)
    p_u = np.einsum("ai,nijd,bj->nabd", db, control, b, optimize=True)
    p_v = np.einsum("ai,nijd,bj->nabd", b, control, db, optimize=True)
    a_u = np.einsum("ai,nijd,bj->nabd", np.abs(db), np.abs(control), b, optimize=True)
    a_v = np.einsum("ai,nijd,bj->nabd", b, np.abs(control), np.abs(db), optimize=True)
    s = np.stack(
        [
            a_u[..., i] * a_v[..., k] + a_u[..., k] * a_v[..., i]
            for i, k in ((1, 2), (2, 0), (0, 1))
        ],
        -1,
    )
    length = np.linalg.norm(np.cross(p_u, p_v), axis=-1)
    if not np.all(length > 0):
        raise SystemExit(f"{name}: the benchmark patches should have no degenerate normal")
    tol = 96 * EPS * np.linalg.norm(s, axis=-1) / length + 4 * EPS
    if not np.allclose(got[1], expected[1], rtol=0, atol=tol[..., None]):
        worst = np.abs(got[1] - expected[1]).max()
        raise SystemExit(
            f"{name}: normals differ from the baseline by up to {worst:.3g} (tolerance ≥ "
            f"{tol.min():.3g})"
        )


def check_all(
    control: np.ndarray, u: np.ndarray, patches: PatchSet, surfaces: list, reused: tuple
) -> None:
    """Correctness first: every tool against the baseline."""
    subset = len(surfaces)
    base_p = numpy_positions(control, u)
    base_pn = numpy_positions_normals(control, u)
    check("numpy positions", control, u, (base_p,), base_pn)
    check("g1patch evaluate_grid", control, u, (patches.evaluate_grid(u),), base_pn)
    got = patches.evaluate_grid_with_normals(u)
    check("g1patch evaluate_grid_with_normals", control, u, got, base_pn)
    got = patches.evaluate_grid_with_normals(u, out=reused[0], normals_out=reused[1])
    check("g1patch evaluate_grid_with_normals, out=", control, u, got, base_pn)
    got = splipy_positions_normals(surfaces, u)
    expected = (base_p[:subset], base_pn[1][:subset])
    check("splipy", control[:subset], u, got, expected)


# ----------------------------------------------------------------------------------- timing
_halves = ThreadPoolExecutor(max_workers=2, thread_name_prefix="bench-fill")


def fill_in_halves(array: np.ndarray) -> None:
    """``array.fill(1.0)`` as two threads filling a half each (``np.copyto`` releases the GIL)."""
    half = array.size // 2
    for future in [_halves.submit(np.copyto, part, 1.0) for part in (array[:half], array[half:])]:
        future.result()


class Timings:
    """Wall-clock and CPU seconds per label, collected round-robin so that load from other
    processes on a shared machine falls on every tool alike."""

    def __init__(self) -> None:
        self.wall: dict[str, list[float]] = {}
        self.cpu: dict[str, list[float]] = {}

    def run(self, label: str, call: Callable[[], object], keep: bool = True) -> None:
        wall, cpu, _ = harness.clocked(call)
        if keep:
            self.wall.setdefault(label, []).append(wall)
            self.cpu.setdefault(label, []).append(cpu)

    def median(self, label: str) -> float:
        return statistics.median(self.wall[label])

    def best(self, label: str) -> float:
        return min(self.wall[label])

    def cpu_median(self, label: str) -> float:
        return statistics.median(self.cpu[label])


def fresh_calls(patches: PatchSet, u: np.ndarray, doubles: int) -> dict[str, Callable[[], object]]:
    """The calls that write into new memory: the fresh outputs, and ``np.empty`` + fill."""
    return {
        "positions": lambda: patches.evaluate_grid(u),
        "positions + normals": lambda: patches.evaluate_grid_with_normals(u),
        "fresh fill": lambda: np.empty(doubles).fill(1.0),
        "fresh fill, 2 threads": lambda: fill_in_halves(np.empty(doubles)),
    }


def glibc_defaults_fresh(args: argparse.Namespace) -> dict[str, float]:
    """Median seconds of :func:`fresh_calls` with glibc's allocator defaults: run in a child
    process (``--glibc-defaults``) because this one keeps freed memory, as the command line
    does."""
    arguments = [
        __file__,
        "--glibc-defaults",
        *("--patches", str(args.patches), "--grid", str(args.grid)),
        *("--repeats", str(args.repeats), "--copy-mib", str(args.copy_mib)),
    ]
    line = harness.run_python(arguments)
    if line is None:
        raise SystemExit("the glibc-defaults child failed")
    return json.loads(line)


def _glibc_defaults_child(n: int, g: int, repeats: int, doubles: int) -> None:
    u = np.linspace(0.0, 1.0, g)
    calls = fresh_calls(PatchSet(make_patches(n), "bezier"), u, doubles)
    timings = Timings()
    for round_ in range(repeats + 1):
        for label, call in calls.items():
            timings.run(label, call, round_ > 0)
    print(json.dumps({label: timings.median(label) for label in calls}))


def tools(
    control: np.ndarray, u: np.ndarray, patches: PatchSet, surfaces: list, reused: tuple
) -> dict[str, list[Tool]]:
    """The rows of both tables: (label, call, time factor, note)."""
    scale = len(control) / len(surfaces)
    note = f"{len(surfaces)} patches, time × {scale:g}"
    b = basis_values("bezier", u)
    positions, normals = reused
    return {
        "positions": [
            ("numpy einsum baseline", lambda: numpy_positions(control, u), 1.0, ""),
            ("g1patch evaluate_grid, fresh output", lambda: patches.evaluate_grid(u), 1.0, ""),
            (
                "g1patch evaluate_grid, out=",
                lambda: patches.evaluate_grid(u, out=positions),
                1.0,
                "",
            ),
            (
                "g1patch NumPy path, out=",
                lambda: _grid.contract(control, b, b, out=positions, compiled=False),
                1.0,
                "compiled=False",
            ),
            ("splipy Surface per patch", lambda: splipy_positions(surfaces, u), scale, note),
        ],
        "positions + normals": [
            ("numpy einsum + cross baseline", lambda: numpy_positions_normals(control, u), 1.0, ""),
            (
                "g1patch evaluate_grid_with_normals, fresh",
                lambda: patches.evaluate_grid_with_normals(u),
                1.0,
                "",
            ),
            (
                "g1patch evaluate_grid_with_normals, out=",
                lambda: patches.evaluate_grid_with_normals(u, out=positions, normals_out=normals),
                1.0,
                "",
            ),
            (
                "g1patch NumPy path, out=",
                lambda: _grid.positions_and_normals(
                    control, "bezier", u, u, positions, normals, compiled=False
                ),
                1.0,
                "compiled=False",
            ),
            (
                "splipy Surface + 2 derivatives + cross",
                lambda: splipy_positions_normals(surfaces, u),
                scale,
                note,
            ),
        ],
    }


def time_rounds(table: dict[str, list[Tool]], doubles: int, repeats: int) -> Timings:
    """``repeats`` rounds of every tool, the copyto and the fills, after a warm-up round."""
    source, target = np.ones(doubles), np.empty(doubles)
    timings = Timings()
    for round_ in range(repeats + 1):  # round 0 warms up the fast tools (the slow ones need none)
        keep = round_ > 0
        timings.run("copyto", lambda: np.copyto(target, source), keep)
        timings.run("fresh fill", lambda: np.empty(doubles).fill(1.0), keep)
        timings.run("fresh fill, 2 threads", lambda: fill_in_halves(np.empty(doubles)), keep)
        for kind, entries in table.items():
            for label, call, _, _ in entries:
                if keep or label.startswith("g1patch"):
                    timings.run(f"{kind}: {label}", call, keep)
    return timings


def print_header(
    args: argparse.Namespace, timings: Timings, defaults: dict[str, float], load: str
) -> dict[str, Any]:
    """The header lines on the bandwidth bounds; returns the figures the tables need."""
    bytes_ = args.copy_mib * 2**20
    copy_gbs = bytes_ / timings.median("copyto") / 1e9
    figures = {
        "copy_gbs": copy_gbs,
        "copy_cpu_gbs": bytes_ / timings.cpu_median("copyto") / 1e9,
        "new_gbs": np.array(
            [bytes_ / defaults[label] / 1e9 for label in ("fresh fill", "fresh fill, 2 threads")]
        ),
    }
    fresh_gbs = bytes_ / timings.median("fresh fill") / 1e9
    fresh2_gbs = bytes_ / timings.median("fresh fill, 2 threads") / 1e9
    new_gbs = figures["new_gbs"]
    points = args.patches * args.grid**2
    print(
        f"# bench_evaluate: {args.patches:,} bicubic Bézier patches on a {args.grid}×{args.grid} "
        f"grid = {points / 1e6:.2f} M points, float64 output"
    )
    print(f"# {harness.machine_line()}; median of {args.repeats} rounds after a warm-up round,")
    print(
        "# tools run round-robin within each round; wall-clock times (CPU time alongside: on a "
        "shared machine the gap is load)"
    )
    print(
        f"# np.copyto {args.copy_mib} MiB: {copy_gbs:.1f} GB/s copied (median; best "
        f"{bytes_ / timings.best('copyto') / 1e9:.1f}); np.empty + fill: {fresh_gbs:.1f} GB/s, "
        f"split over 2 threads {fresh2_gbs:.1f} GB/s (freed memory kept, as the command line "
        f"runs); with glibc's defaults (new pages): {new_gbs[0]:.1f} GB/s, over 2 threads "
        f"{new_gbs[1]:.1f} GB/s"
    )
    print(
        f"# by CPU time instead of wall-clock: np.copyto {figures['copy_cpu_gbs']:.1f} GB/s; the "
        "column 'CPU % of bound' uses that"
    )
    print(f"# load average (1, 5, 15 min) at the start {load}, at the end {harness.loads()}")
    record("patches", args.patches, "")
    record("grid", args.grid, "", "points per side")
    record("np.copyto", copy_gbs, "GB/s", f"{args.copy_mib} MiB, median")
    record("np.copyto by CPU time", figures["copy_cpu_gbs"], "GB/s")
    record("np.empty + fill", fresh_gbs, "GB/s", "freed memory kept")
    record("np.empty + fill, 2 threads", fresh2_gbs, "GB/s", "freed memory kept")
    record("np.empty + fill, glibc defaults", new_gbs[0], "GB/s", "new pages")
    record("np.empty + fill, 2 threads, glibc defaults", new_gbs[1], "GB/s", "new pages")
    return figures


def print_kind(
    kind: str,
    per_point: int,
    entries: list[Tool],
    timings: Timings,
    figures: dict[str, Any],
    points: int,
) -> list[tuple[str, float, float, float]]:
    """One table: every tool for ``kind``. Returns the g1patch rows of the summary: (label,
    median, CPU time, splipy's time)."""
    bound = figures["copy_gbs"] * 1e9 / per_point
    cpu_bound = figures["copy_cpu_gbs"] * 1e9 / per_point
    baseline = timings.median(f"{kind}: {entries[0][0]}")
    splipy = timings.median(f"{kind}: {entries[-1][0]}") * entries[-1][2]
    print(
        f"\n## {kind}: {per_point} B/point written; bandwidth bound {bound / 1e6:.0f} M points/s\n"
    )
    print(
        "| tool | median time | CPU time | M points/s (median / best) | × numpy | × splipy "
        "| % of bound | CPU % of bound | note |"
    )
    print("|---|---:|---:|---:|---:|---:|---:|---:|---|")
    summary = []
    for label, _, factor, note in entries:
        key = f"{kind}: {label}"
        median = timings.median(key) * factor
        best = timings.best(key) * factor
        cpu = timings.cpu_median(key) * factor
        share, cpu_share = points / median / bound, points / cpu / cpu_bound
        print(
            f"| {label} | {median * 1e3:.1f} ms | {cpu * 1e3:.1f} ms | {points / median / 1e6:.1f}"
            f" / {points / best / 1e6:.1f} | {baseline / median:.2f} | {splipy / median:.1f} "
            f"| {100 * share:.1f} % | {100 * cpu_share:.1f} % | {note} |"
        )
        record(f"{key} time", median * 1e3, "ms", note or "median")
        record(f"{key} × numpy", baseline / median, "×")
        record(f"{key} × splipy", splipy / median, "×")
        record(f"{key} of bound", 100 * share, "%", "np.copyto bound")
        record(f"{key} CPU of bound", 100 * cpu_share, "%", "by CPU times")
        if label.startswith("g1patch") and not note:
            summary.append((label, median, cpu, splipy))
    return summary


def print_summary(
    rows: list[tuple[str, float, float, float]],
    figures: dict[str, Any],
    defaults: dict[str, float],
    points: int,
) -> None:
    """The summary lines of positions + normals against the issue's bars."""
    per_point = 48
    bound = figures["copy_gbs"] * 1e9 / per_point
    cpu_bound = figures["copy_cpu_gbs"] * 1e9 / per_point
    print()
    for label, median, cpu, splipy in rows:
        fresh = ""
        if "fresh" in label:
            pages = points * per_point / figures["new_gbs"] / 1e9
            untuned = defaults["positions + normals"]
            fresh = (
                f" (freed memory kept, as the command line runs); with glibc's defaults "
                f"{untuned * 1e3:.0f} ms, {100 * points / untuned / bound:.0f} % of the bound: "
                f"the first touch of the outputs' new 4 KiB pages alone takes "
                f"{pages[0] * 1e3:.0f} ms on one thread, {pages[1] * 1e3:.0f} ms on two "
                f"(np.empty + fill), at most {100 * points / pages.min() / bound:.0f} % of the "
                "bound"
            )
            key = "positions + normals: g1patch fresh, glibc defaults"
            record(f"{key} time", untuned * 1e3, "ms", "child process")
            record(f"{key} of bound", 100 * points / untuned / bound, "%")
            record("first touch of the outputs' new pages", pages[0] * 1e3, "ms", "one thread")
            record("first touch of the outputs' new pages, 2 threads", pages[1] * 1e3, "ms")
            record("outputs' new pages", points * per_point / 1e6, "MB")
        print(
            f"# positions + normals, {label}: {100 * points / median / bound:.0f} % of the "
            f"bandwidth bound ({100 * points / cpu / cpu_bound:.0f} % by CPU time), "
            f"{splipy / median:.0f}× splipy (issue 13 and DESIGN bar: ≥ 50 %, ≥ 100×){fresh}"
        )


#: the command line's options (harness.Option)
OPTIONS: dict[str, harness.Option] = {
    "patches": (10_000, "Bézier patches"),
    "grid": (32, "grid points per side"),
    "splipy_patches": (250, "patches splipy evaluates"),
    "repeats": (5, "rounds, the median"),
    "copy_mib": (1024, "MiB of the copyto and fill arrays"),
    "glibc_defaults": (False, argparse.SUPPRESS),  # the child of glibc_defaults_fresh
}
#: the defaults --quick sets: small sizes, a smoke run
QUICK = {"patches": 500, "grid": 16, "splipy_patches": 20, "repeats": 2, "copy_mib": 64}


def main(argv: Sequence[str] | None = None) -> None:
    args = harness.parse_args(__doc__, argv, OPTIONS, QUICK)
    n, g, repeats, doubles = args.patches, args.grid, args.repeats, args.copy_mib * 2**17
    if args.glibc_defaults:
        _glibc_defaults_child(n, g, repeats, doubles)
        return
    tune_for_large_arrays()  # as the command line does (g1patch.memory)
    control = make_patches(n)
    u = np.linspace(0.0, 1.0, g)
    patches = PatchSet(control, "bezier")
    surfaces = splipy_surfaces(control[: min(args.splipy_patches, n)])
    started, load = time.perf_counter(), harness.loads()
    reused = (np.empty((n, g, g, 3)), np.empty((n, g, g, 3)))
    check_all(control, u, patches, surfaces, reused)

    table = tools(control, u, patches, surfaces, reused)
    rounds, timings = harness.timed(lambda: time_rounds(table, doubles, repeats))
    defaults = glibc_defaults_fresh(args)
    figures = print_header(args, timings, defaults, load)
    summary = []
    for kind, per_point in (("positions", 24), ("positions + normals", 48)):
        rows = print_kind(kind, per_point, table[kind], timings, figures, n * g * g)
        summary += rows if kind == "positions + normals" else []
    print_summary(summary, figures, defaults, n * g * g)
    print(
        f"# total benchmark time {time.perf_counter() - started:.0f} s (timing rounds "
        f"{rounds:.0f} s)"
    )


if __name__ == "__main__":
    main()
