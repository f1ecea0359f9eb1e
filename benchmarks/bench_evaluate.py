"""Tessellation speed: positions, and positions + unit normals, of bicubic Bézier patches on a grid.

Workload: N random bicubic Bézier patches (a jittered 4×4 control net over a unit cell plus a random
height), each sampled on a G×G grid (u, v = linspace(0, 1, G)); output (N, G, G, 3) C-contiguous float64.
Defaults: N = 10,000, G = 32 (10.24 M points).

Everything in the table is measured in this run (DESIGN §6: absolute times drift on shared machines,
ratios hold):

* "× numpy" — against the plain NumPy baseline: ``einsum('ai,nijd,bj->nabd')`` made contiguous, and
  for normals the same for p_u and p_v, then ``np.cross`` and ``x / |x|``;
* "× splipy" — against splipy on the same patches: one ``splipy.Surface`` per patch, evaluated on the
  grid (``surface(u, v)``; normals from ``surface.derivative(u, v, d=(1, 0))`` and ``d=(0, 1)``,
  ``np.cross``, normalised). splipy runs on the first ``--splipy-patches`` patches and its time is
  scaled linearly to N (its cost is a fixed ~100 µs per patch plus per point work);
* "% bound" — against the memory-bandwidth bound: ``np.copyto`` on a 1 GiB array, in GB/s (bytes
  copied), divided by the bytes written per point (24 for positions, 48 for positions + normals).

Rows "fresh output" call the public PatchSet methods, which allocate their results with ``np.empty``;
rows "out=" run the same public methods into preallocated arrays, the situation the copyto bound
describes. At this size the methods run the compiled kernels (``g1patch._grid.KERNEL_POINTS``); the
rows "NumPy path" run the same functions with ``compiled=False``, the NumPy code the kernels replace
above that size (and their reference).

This process runs as the command line does (:func:`g1patch.memory.tune_for_large_arrays`: freed
memory kept by glibc's malloc, NumPy's huge-page advice as NumPy sets it), so a fresh output reuses
pages an earlier array freed. With glibc's defaults every fresh output is a new mapping whose pages
the kernel faults in and zeroes on first write (0.2-2 GB/s on this VM): a child process
(``--glibc-defaults``, the same but for the allocator) times the fresh rows that way too, and the
summary sets them beside the time ``np.empty`` + ``fill`` takes for the same bytes of new pages, on
one thread and split over two. Those new pages do not stay fast however they are mapped: the VM
these benchmarks run on hands free 2 MiB blocks back to the hypervisor within seconds
(virtio-balloon free page reporting), and re-backing one cost 2-12 ms, which is why the command
line keeps freed memory instead. Before timing, every tool's output is checked
against the baseline with ``np.allclose`` (tolerances in :func:`check`).

Each figure is the median of ``--repeats`` rounds; within a round every tool (and the copyto) runs
once, round-robin, so that load from other processes on a shared machine falls on all of them
alike. A first round warms up the g1patch kernels and is not counted. CPU time (process time) is
printed beside the wall-clock time; "CPU % of bound" is the same ratio computed from CPU times of
both the tool and the copyto, which is less sensitive to other processes taking the cores. About
50 s on an idle 2-core machine.

Run:  .venv/bin/python benchmarks/bench_evaluate.py [--patches N] [--grid G] [--repeats R]
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import subprocess
import sys
import time
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor

import numpy as np

from g1patch import _grid
from g1patch.basis import basis_values
from g1patch.memory import tune_for_large_arrays
from g1patch.patches import PatchSet

EPS = np.finfo(np.float64).eps


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

    Positions: both sides compute the 16-term sum Σ b_i P_ij b_j, each within γ_8 Σ|b_i||P_ij||b_j|
    of the exact value (≤ 8 roundings per term); Bernstein weights are ≥ 0 and sum to 1, so
    Σ|b_i||P_ij||b_j| ≤ max|P|, and atol = 16 eps max|P|.
    Normals: c = p_u × p_v differs by ≤ 48 eps |S| between any two ways of evaluating it
    (S_d = |p_u|_i |p_v|_k + |p_u|_k |p_v|_i with absolute-value evaluations; see
    tests/test_grid_kernels.py), which moves the unit normal by ≤ 2·48 eps |S| / |c|, plus 4 eps for
    the normalisations: atol = 96 eps |S| / |c| + 4 eps per point.
    """
    atol = 16 * EPS * np.abs(control).max()
    if not np.allclose(got[0], expected[0], rtol=0, atol=atol):
        raise SystemExit(
            f"{name}: positions differ from the baseline by {np.abs(got[0] - expected[0]).max():.3g} > {atol:.3g}"
        )
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
            f"{name}: normals differ from the baseline by up to {worst:.3g} (tolerance ≥ {tol.min():.3g})"
        )


# ---------------------------------------------------------------------------------- timing
_halves = ThreadPoolExecutor(max_workers=2, thread_name_prefix="bench-fill")


def fill_in_halves(array: np.ndarray) -> None:
    """``array.fill(1.0)`` as two threads filling a half each (``np.copyto`` releases the GIL)."""
    half = array.size // 2
    for future in [_halves.submit(np.copyto, part, 1.0) for part in (array[:half], array[half:])]:
        future.result()


class Timings:
    """Wall-clock and CPU seconds per label, collected round-robin so that load from other processes
    on a shared machine falls on every tool alike."""

    def __init__(self) -> None:
        self.wall: dict[str, list[float]] = {}
        self.cpu: dict[str, list[float]] = {}

    def run(self, label: str, call: Callable[[], object], record: bool = True) -> None:
        wall, cpu = time.perf_counter(), time.process_time()
        call()
        wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
        if record:
            self.wall.setdefault(label, []).append(wall)
            self.cpu.setdefault(label, []).append(cpu)

    def median(self, label: str) -> float:
        return statistics.median(self.wall[label])

    def best(self, label: str) -> float:
        return min(self.wall[label])

    def cpu_median(self, label: str) -> float:
        return statistics.median(self.cpu[label])


def glibc_defaults_fresh(n: int, g: int, repeats: int) -> dict[str, float]:
    """Median seconds of the fresh-output calls and of ``np.empty`` + fill (1 GiB, one thread and
    two) with glibc's allocator defaults: run in a child process
    (``--glibc-defaults``) because this one keeps freed memory, as the command line does."""
    command = [
        sys.executable,
        __file__,
        "--glibc-defaults",
        "--patches",
        str(n),
        "--grid",
        str(g),
        "--repeats",
        str(repeats),
    ]
    result = subprocess.run(command, capture_output=True, text=True)
    if result.returncode:
        raise SystemExit(f"the glibc-defaults child failed:\n{result.stderr[-2000:]}")
    return json.loads(result.stdout.strip().splitlines()[-1])


def _glibc_defaults_child(n: int, g: int, repeats: int) -> None:
    u = np.linspace(0.0, 1.0, g)
    patches = PatchSet(make_patches(n), "bezier")
    calls = {
        "positions": lambda: patches.evaluate_grid(u),
        "positions + normals": lambda: patches.evaluate_grid_with_normals(u),
        "fresh fill": lambda: np.empty(2**27).fill(1.0),
        "fresh fill, 2 threads": lambda: fill_in_halves(np.empty(2**27)),
    }
    timings = Timings()
    for round_ in range(repeats + 1):
        for label, call in calls.items():
            timings.run(label, call, round_ > 0)
    print(json.dumps({label: timings.median(label) for label in calls}))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--patches", type=int, default=10_000)
    parser.add_argument("--grid", type=int, default=32)
    parser.add_argument("--splipy-patches", type=int, default=250)
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--glibc-defaults", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    n, g, repeats = args.patches, args.grid, args.repeats
    if args.glibc_defaults:
        _glibc_defaults_child(n, g, repeats)
        return
    tune_for_large_arrays()  # as the command line does (g1patch.memory)
    points = n * g * g
    control = make_patches(n)
    u = np.linspace(0.0, 1.0, g)
    patches = PatchSet(control, "bezier")
    subset = min(args.splipy_patches, n)
    surfaces = splipy_surfaces(control[:subset])
    started = time.perf_counter()
    load_start = os.getloadavg()

    # correctness first: every tool against the baseline
    base_p = numpy_positions(control, u)
    base_pn = numpy_positions_normals(control, u)
    check("numpy positions", control, u, (base_p,), base_pn)
    check("g1patch evaluate_grid", control, u, (patches.evaluate_grid(u),), base_pn)
    check(
        "g1patch evaluate_grid_with_normals",
        control,
        u,
        patches.evaluate_grid_with_normals(u),
        base_pn,
    )
    reused_p, reused_n = np.empty((n, g, g, 3)), np.empty((n, g, g, 3))
    check(
        "g1patch evaluate_grid_with_normals, out=",
        control,
        u,
        patches.evaluate_grid_with_normals(u, out=reused_p, normals_out=reused_n),
        base_pn,
    )
    check(
        "splipy",
        control[:subset],
        u,
        splipy_positions_normals(surfaces, u),
        (base_p[:subset], base_pn[1][:subset]),
    )
    del base_p, base_pn

    scale = n / subset
    note = f"{subset} patches, time × {scale:g}"
    b = basis_values("bezier", u)
    source, target = np.ones(2**27), np.empty(2**27)  # 1 GiB each
    tools = {
        "positions": [
            ("numpy einsum baseline", lambda: numpy_positions(control, u), 1.0, ""),
            ("g1patch evaluate_grid, fresh output", lambda: patches.evaluate_grid(u), 1.0, ""),
            (
                "g1patch evaluate_grid, out=",
                lambda: patches.evaluate_grid(u, out=reused_p),
                1.0,
                "",
            ),
            (
                "g1patch NumPy path, out=",
                lambda: _grid.contract(control, b, b, out=reused_p, compiled=False),
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
                lambda: patches.evaluate_grid_with_normals(u, out=reused_p, normals_out=reused_n),
                1.0,
                "",
            ),
            (
                "g1patch NumPy path, out=",
                lambda: _grid.positions_and_normals(
                    control, "bezier", u, u, reused_p, reused_n, compiled=False
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
    timings = Timings()
    rounds_started = time.perf_counter()
    for round_ in range(
        repeats + 1
    ):  # round 0 warms up the fast tools (the slow ones need no warm-up)
        record = round_ > 0
        timings.run("copyto", lambda: np.copyto(target, source), record)
        timings.run("fresh fill", lambda: np.empty(2**27).fill(1.0), record)
        timings.run("fresh fill, 2 threads", lambda: fill_in_halves(np.empty(2**27)), record)
        for kind, entries in tools.items():
            for label, call, factor, _ in entries:
                if record or label.startswith("g1patch"):
                    timings.run(f"{kind}: {label}", call, record)
    rounds = time.perf_counter() - rounds_started
    defaults = glibc_defaults_fresh(n, g, repeats)

    copy_gbs = source.nbytes / timings.median("copyto") / 1e9
    copy_cpu_gbs = source.nbytes / timings.cpu_median("copyto") / 1e9
    fresh_gbs = source.nbytes / timings.median("fresh fill") / 1e9
    fresh2_gbs = source.nbytes / timings.median("fresh fill, 2 threads") / 1e9
    new_gbs = np.array(
        [source.nbytes / defaults[label] / 1e9 for label in ("fresh fill", "fresh fill, 2 threads")]
    )
    print(
        f"# bench_evaluate: {n:,} bicubic Bézier patches on a {g}×{g} grid = {points / 1e6:.2f} M points, float64 output"
    )
    print(
        f"# {platform.machine()}, {os.cpu_count()} CPUs, numpy {np.__version__}; median of {repeats} rounds after a warm-up round,"
    )
    print(
        "# tools run round-robin within each round; wall-clock times (CPU time alongside: on a shared machine the gap is load)"
    )
    print(
        f"# np.copyto 1 GiB: {copy_gbs:.1f} GB/s copied (median; best {source.nbytes / timings.best('copyto') / 1e9:.1f}); "
        f"np.empty + fill: {fresh_gbs:.1f} GB/s, split over 2 threads {fresh2_gbs:.1f} GB/s (freed memory kept, as the "
        f"command line runs); with glibc's defaults (new pages): {new_gbs[0]:.1f} GB/s, over 2 threads {new_gbs[1]:.1f} GB/s"
    )
    print(
        f"# by CPU time instead of wall-clock: np.copyto {copy_cpu_gbs:.1f} GB/s; the column 'CPU % of bound' uses that"
    )
    print(
        f"# load average (1, 5, 15 min) at the start {load_start[0]:.2f} {load_start[1]:.2f} {load_start[2]:.2f}, "
        f"at the end {os.getloadavg()[0]:.2f} {os.getloadavg()[1]:.2f} {os.getloadavg()[2]:.2f}"
    )
    summary = []
    for kind, bytes_per_point in (("positions", 24), ("positions + normals", 48)):
        bound = copy_gbs * 1e9 / bytes_per_point
        entries = tools[kind]
        baseline = timings.median(f"{kind}: {entries[0][0]}")
        splipy = timings.median(f"{kind}: {entries[-1][0]}") * entries[-1][2]
        print()
        print(
            f"## {kind}: {bytes_per_point} B/point written; bandwidth bound {bound / 1e6:.0f} M points/s"
        )
        print()
        print(
            "| tool | median time | CPU time | M points/s (median / best) | × numpy | × splipy | % of bound | CPU % of bound | note |"
        )
        print("|---|---:|---:|---:|---:|---:|---:|---:|---|")
        for label, _, factor, note in entries:
            key = f"{kind}: {label}"
            median, best, cpu = (
                timings.median(key) * factor,
                timings.best(key) * factor,
                timings.cpu_median(key) * factor,
            )
            print(
                f"| {label} | {median * 1e3:.1f} ms | {cpu * 1e3:.1f} ms | {points / median / 1e6:.1f} / {points / best / 1e6:.1f} "
                f"| {baseline / median:.2f} | {splipy / median:.1f} | {100 * points / median / bound:.1f} % "
                f"| {100 * points / cpu / (copy_cpu_gbs * 1e9 / bytes_per_point):.1f} % | {note} |"
            )
            if kind == "positions + normals" and label.startswith("g1patch") and not note:
                cpu_share = points / cpu / (copy_cpu_gbs * 1e9 / bytes_per_point)
                fresh = ""
                if "fresh" in label:
                    pages = points * bytes_per_point / new_gbs / 1e9
                    untuned = defaults[kind]
                    fresh = (
                        f" (freed memory kept, as the command line runs); with glibc's defaults {untuned * 1e3:.0f} ms, "
                        f"{100 * points / untuned / bound:.0f} % of the bound: the first touch of the outputs' new 4 KiB "
                        f"pages alone takes {pages[0] * 1e3:.0f} ms on one thread, {pages[1] * 1e3:.0f} ms on two "
                        f"(np.empty + fill), at most {100 * points / pages.min() / bound:.0f} % of the bound"
                    )
                summary.append(
                    f"# positions + normals, {label}: {100 * points / median / bound:.0f} % of the bandwidth bound "
                    f"({100 * cpu_share:.0f} % by CPU time), {splipy / median:.0f}× splipy "
                    f"(issue 13 and DESIGN bar: ≥ 50 %, ≥ 100×){fresh}"
                )
    print()
    print("\n".join(summary))
    print(
        f"# total benchmark time {time.perf_counter() - started:.0f} s (timing rounds {rounds:.0f} s)"
    )


if __name__ == "__main__":
    main()
