"""Bounded by default: export size, render time and memory, check memory at a high valence.

Three measurements, each in a fresh subprocess of the command line or in this process:

* export: Spot split4 (``../shared/data/spot_quadrangulated.obj``, 2928 quads → 11 712 patches)
  exported to OBJ at the default resolution (the 2 M-triangle budget: resolution 10) and, for
  comparison, at the old default ``--resolution 17``: triangles, file size, seconds, peak RSS;
* render: a corner network of ``--patches`` patches (default 1 M, ``shapes.large_torus``),
  ``render`` shaded and ``--deviation`` at 900 × 900: seconds and peak RSS of each;
* check: ``continuity.check`` of the corner network of ``shapes.fan(--valence)`` (default
  10 000, one vertex of that valence): tracemalloc peak and seconds.

Run:  .venv/bin/python benchmarks/bench_bounds.py [--patches N] [--valence K] [--skip export,render,check]
"""

from __future__ import annotations

import argparse
import os
import platform
import re
import subprocess
import sys
import tempfile
import time
import tracemalloc
from pathlib import Path

import numpy as np

from g1patch import shapes
from g1patch.construct.corner import build_corner_network
from g1patch.continuity import check
from g1patch.io.network_file import save_network

SPOT = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "spot_quadrangulated.obj"


def command(*args: str | Path) -> tuple[float, float, str]:
    """Seconds, peak RSS (MB) and stdout of ``g1patch args`` in a subprocess."""
    start = time.perf_counter()
    process = subprocess.Popen(
        [sys.executable, "-m", "g1patch.cli", *map(str, args)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    _, status, usage = os.wait4(process.pid, 0)
    seconds = time.perf_counter() - start
    stdout = process.stdout.read() if process.stdout else ""
    stderr = process.stderr.read() if process.stderr else ""
    if os.waitstatus_to_exitcode(status) != 0:
        raise SystemExit(f"g1patch {' '.join(map(str, args))} failed: {stderr.strip()}")
    return seconds, usage.ru_maxrss / 1024.0, stdout


def bench_export(folder: Path) -> None:
    if not SPOT.is_file():
        print(f"export: skipped ({SPOT} not found)")
        return
    network = folder / "spot_split4.npz"
    command("build", SPOT, "-o", network, "--method", "split4", "--quiet")
    print(f"{'Spot split4 → OBJ':<28}{'triangles':>11}{'MB':>8}{'s':>7}{'RSS MB':>8}")
    for label, extra in (
        ("default (budget)", ()),
        ("--resolution 17 (old)", ("--resolution", "17")),
    ):
        output = folder / "spot.obj"
        seconds, rss, stdout = command("export", network, "-o", output, *extra)
        triangles = int(re.search(r"wrote (\d+) triangles", stdout).group(1))  # type: ignore[union-attr]
        print(
            f"{label:<28}{triangles:>11,}{output.stat().st_size / 1e6:>8.0f}{seconds:>7.1f}{rss:>8.0f}"
        )
        output.unlink()


def bench_render(folder: Path, patches: int) -> None:
    network = folder / "many.npz"
    built = build_corner_network(shapes.large_torus(patches))
    save_network(network, built)
    print(f"\nrender {built.n_patches:,} patches, 900 × 900{'':<6}{'s':>7}{'RSS MB':>8}")
    del built
    for mode in ((), ("--zebra",), ("--deviation",)):
        seconds, rss, _ = command("render", network, "-o", folder / "picture.png", *mode)
        print(f"{(mode[0] if mode else 'shaded'):<38}{seconds:>7.1f}{rss:>8.0f}")


def bench_check(valence: int) -> None:
    mesh = shapes.fan(valence)
    lifted = mesh.vertices.copy()
    lifted[1:, 2] = 0.1 * np.sin(np.arange(len(lifted) - 1))
    network = build_corner_network(mesh.with_vertices(lifted))
    tracemalloc.start()
    start = time.perf_counter()
    report = check(network)
    seconds = time.perf_counter() - start
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    print(
        f"\ncheck, one vertex of valence {valence:,}: peak {peak / 1e6:.0f} MB (bar: 500 MB), {seconds:.1f} s, "
        f"max corner angle {report.max_corner_angle_deg:.4g}°"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--patches",
        type=int,
        default=1_000_000,
        help="patches of the render workload (default 1,000,000)",
    )
    parser.add_argument(
        "--valence", type=int, default=10_000, help="valence of the check workload (default 10,000)"
    )
    parser.add_argument(
        "--skip", default="", help="comma-separated parts to skip: export, render, check"
    )
    args = parser.parse_args()
    skip = set(filter(None, args.skip.split(",")))
    print(
        f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores, python {platform.python_version()}\n"
    )
    with tempfile.TemporaryDirectory() as name:
        folder = Path(name)
        if "export" not in skip:
            bench_export(folder)
        if "render" not in skip:
            bench_render(folder, args.patches)
    if "check" not in skip:
        bench_check(args.valence)


if __name__ == "__main__":
    main()
