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

Run:  .venv/bin/python benchmarks/bench_scaling.py [--sizes 10000 100000 1000000 4000000]
      [--end-to-end N] [--quick]
"""

from __future__ import annotations

import json
import tempfile
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import harness
import numpy as np

from g1patch.memory import TUNED_ENVIRONMENT

record = harness.recorder("bench_scaling")


def _warm_up() -> None:
    """Import numba and load (or compile) the build's and check's kernels on a small torus."""
    from g1patch import shapes
    from g1patch.build import build_network
    from g1patch.continuity import check
    from g1patch.memory import tune_for_large_arrays

    tune_for_large_arrays()  # as the command line does
    small = shapes.large_torus(30_000)  # above continuity.KERNEL_PATCHES: the check's kernels too
    check(build_network(small, "gregory"))


def size_row(quads: int) -> dict[str, float]:
    """One size's build and check, time and peak (module docstring)."""
    from g1patch import shapes
    from g1patch.build import build_network
    from g1patch.continuity import check

    _warm_up()
    mesh = shapes.large_torus(quads)
    build_network(mesh, "gregory")
    build_s, network = harness.timed(lambda: build_network(mesh, "gregory"))
    build_peak = harness.peak(lambda: build_network(mesh, "gregory"))
    check_s, _ = harness.timed(lambda: check(network))
    check_peak = harness.peak(lambda: check(network))
    return {
        "size": quads,
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
        baseline = harness.process_peak()
        start = time.perf_counter()
        read_s, mesh = harness.timed(lambda: read_mesh(ply))
        build_s, network = harness.timed(lambda: build_network(mesh, "gregory"))
        saving = save_network_in_background(out, network)
        check_s, _ = harness.timed(lambda: check(network))
        wait_s, _ = harness.timed(saving.result)
        total = time.perf_counter() - start
        peak = harness.process_peak()
        out.unlink()
        alone_check_s, _ = harness.timed(lambda: check(network))
        alone_save_s, _ = harness.timed(lambda: save_network(out, network))
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


def _in_subprocess(function: str, quads: int) -> dict[str, Any]:
    """``function(quads)`` of this file in a fresh interpreter, its result as JSON."""
    code = (
        f"import json, sys; sys.path.insert(0, {str(Path(__file__).parent)!r}); "
        f"import bench_scaling as b; print(json.dumps(b.{function}({quads})))"
    )
    line = harness.run_python(["-c", code], env=TUNED_ENVIRONMENT)
    if line is None:
        raise SystemExit(f"{function}({quads}) failed")
    return json.loads(line)


def exponent(quads: list[float], values: list[float]) -> float:
    """Least-squares slope b of ``log v = a + b log N``."""
    return float(np.polyfit(np.log(quads), np.log(values), 1)[0])


def print_sizes(rows: list[dict[str, Any]]) -> None:
    """The table of sizes and the fitted exponents, and their records."""
    print(f"\nload average {harness.loads()}")
    print(
        f"{'quads':>9} {'build s':>8} {'build MB':>9} {'B/quad':>7} {'check s':>8} "
        f"{'check MB':>9} {'B/quad':>7} {'check/build':>11}"
    )
    for row in rows:
        quads = row["quads"]
        print(
            f"{quads:9,.0f} {row['build_s']:8.2f} {row['build_peak'] / 1e6:9.0f} "
            f"{row['build_peak'] / quads:7.0f} {row['check_s']:8.2f} "
            f"{row['check_peak'] / 1e6:9.0f} {row['check_peak'] / quads:7.0f}"
            f" {row['check_s'] / row['build_s']:11.2f}"
        )
        size = f"{row['size']} quads"
        record(f"build, {size}", row["build_s"], "s", f"large_torus: {quads:,} quads")
        record(f"build peak per quad, {size}", row["build_peak"] / quads, "B/quad")
        record(f"check, {size}", row["check_s"], "s")
        record(f"check peak per quad, {size}", row["check_peak"] / quads, "B/quad")
        record(f"check / build, {size}", row["check_s"] / row["build_s"], "×", "bar ≤ 1")
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
        sizes = " ".join(str(row["size"]) for row in rows)
        record("smallest size", rows[0]["size"], "quads")
        record("largest size", rows[-1]["size"], "quads")
        for name, value in fitted.items():
            record(f"exponent of {name}", value, "", f"sizes {sizes}; bar ≤ 1.1")


def print_end_to_end(row: dict[str, Any]) -> None:
    """The end-to-end run, and its records."""
    print(
        f"\nend to end, {row['quads']:,.0f} quads (binary PLY → build → check → save), load "
        f"average {harness.loads()}:"
    )
    print(
        f"  read {row['read_s']:.2f} s, build {row['build_s']:.2f} s, check {row['check_s']:.2f} "
        f"s while the file is written, then {row['wait_s']:.2f} s until it is; total "
        f"{row['total_s']:.2f} s (bar 30 s); process peak {row['peak'] / 1e9:.2f} GB (bar 8 GB; "
        f"{row['baseline'] / 1e9:.2f} GB before reading)"
    )
    print(
        f"  one after the other instead: check {row['alone_check_s']:.2f} s, save "
        f"{row['alone_save_s']:.2f} s"
    )
    record("end to end quads", row["quads"], "quads")
    for stage in ("read", "build", "check", "wait", "total"):
        record(
            f"end to end {stage}", row[f"{stage}_s"], "s", "bar 30 s" if stage == "total" else ""
        )
    record("end to end peak", row["peak"] / 1e9, "GB", "ru_maxrss; bar 8 GB")
    record("end to end check alone", row["alone_check_s"], "s")
    record("end to end save alone", row["alone_save_s"], "s")


#: the command line's options (harness.Option)
OPTIONS: dict[str, harness.Option] = {
    "sizes": ([10_000, 100_000, 1_000_000, 4_000_000], "quads of the tori"),
    "end_to_end": (None, "quads of the end-to-end run (None: the largest size; 0: skip)", int),
}
#: the defaults --quick sets: small sizes, a smoke run
QUICK = {"sizes": [10_000, 40_000], "end_to_end": 10_000}


def main(argv: Sequence[str] | None = None) -> None:
    args = harness.parse_args(__doc__, argv, OPTIONS, QUICK)
    print(harness.machine_line())
    print_sizes([_in_subprocess("size_row", quads) for quads in args.sizes])
    size = args.sizes[-1] if args.end_to_end is None else args.end_to_end
    if size:
        print_end_to_end(_in_subprocess("end_to_end", size))


if __name__ == "__main__":
    main()
