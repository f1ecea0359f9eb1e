"""Bounded by default: export size, render time and memory, check memory at a high valence.

Three measurements, each in a fresh subprocess of the command line or in this process:

* export: Spot split4 (``../shared/data/spot_quadrangulated.obj``, 2928 quads → 11 712 patches;
  ``--export-mesh`` names another shared mesh) exported to OBJ at the default resolution (the 2
  M-triangle budget: resolution 10) and, for comparison, at the old default ``--resolution 17``:
  triangles, file size, seconds, peak RSS;
* render: a corner network of ``--patches`` patches (default 1 M, ``shapes.large_torus``),
  ``render`` shaded and ``--deviation`` at 900 × 900: seconds and peak RSS of each;
* check: ``continuity.check`` of the corner network of ``shapes.fan(--valence)`` (default
  10 000, one vertex of that valence): tracemalloc peak and seconds.

Peak RSS is GNU time's for the command alone (:func:`harness.run_command`).

Run:  .venv/bin/python benchmarks/bench_bounds.py [--patches N] [--valence K]
      [--skip export,render,check] [--export-mesh NAME] [--quick]
"""

from __future__ import annotations

import re
import sys
import tempfile
from collections.abc import Sequence
from pathlib import Path

import harness
import numpy as np

from g1patch import shapes
from g1patch.construct.corner import build_corner_network
from g1patch.continuity import check
from g1patch.io.network_file import save_network

record = harness.recorder("bench_bounds")


def command(*args: str | Path) -> harness.Finished:
    """``g1patch args`` in a subprocess: seconds, resident peak, stdout."""
    return harness.run_command([sys.executable, "-m", "g1patch.cli", *args])


def megabytes(resident: int | None) -> float:
    """Bytes as MB, NaN when not measured (no GNU time)."""
    return float("nan") if resident is None else resident / 1e6


def bench_export(folder: Path, name: str) -> None:
    source = harness.SHARED / f"{name}.obj"
    if not source.is_file():
        print(f"export: skipped ({source} not found)")
        return
    network = folder / f"{name}_split4.npz"
    command("build", source, "-o", network, "--method", "split4", "--quiet")
    print(f"{name + ' split4 → OBJ':<28}{'triangles':>11}{'MB':>8}{'s':>7}{'RSS MB':>8}")
    for label, extra in (
        ("default (budget)", ()),
        ("--resolution 17 (old)", ("--resolution", "17")),
    ):
        output = folder / "export.obj"
        run = command("export", network, "-o", output, *extra)
        triangles = int(re.search(r"wrote (\d+) triangles", run.stdout).group(1))  # type: ignore[union-attr]
        size = output.stat().st_size / 1e6
        rss = megabytes(run.resident)
        print(f"{label:<28}{triangles:>11,}{size:>8.0f}{run.seconds:>7.1f}{rss:>8.0f}")
        output.unlink()
        key = f"export {name} {label.split(' (')[0]}"
        record(f"{key} triangles", triangles, "")
        record(f"{key} file", size, "MB")
        record(f"{key} time", run.seconds, "s", "command line")
        record(f"{key} resident peak", rss, "MB", "GNU time")


def bench_render(folder: Path, patches: int) -> None:
    network = folder / "many.npz"
    built = build_corner_network(shapes.large_torus(patches))
    save_network(network, built)
    print(f"\nrender {built.n_patches:,} patches, 900 × 900{'':<6}{'s':>7}{'RSS MB':>8}")
    record("render patches", built.n_patches, "")
    del built
    for mode in ((), ("--zebra",), ("--deviation",)):
        run = command("render", network, "-o", folder / "picture.png", *mode)
        label = mode[0] if mode else "shaded"
        print(f"{label:<38}{run.seconds:>7.1f}{megabytes(run.resident):>8.0f}")
        record(f"render {label.lstrip('-')} time", run.seconds, "s", "command line")
        record(f"render {label.lstrip('-')} resident peak", megabytes(run.resident), "MB")


def bench_check(valence: int) -> None:
    mesh = shapes.fan(valence)
    lifted = mesh.vertices.copy()
    lifted[1:, 2] = 0.1 * np.sin(np.arange(len(lifted) - 1))
    network = build_corner_network(mesh.with_vertices(lifted))
    seconds, peak, report = harness.traced(lambda: check(network))
    print(
        f"\ncheck, one vertex of valence {valence:,}: peak {peak / 1e6:.0f} MB (bar: 500 MB), "
        f"{seconds:.1f} s, max corner angle {report.max_corner_angle_deg:.4g}°"
    )
    record("check valence", valence, "")
    record("check peak", peak / 1e6, "MB", "tracemalloc; bar 500 MB")
    record("check", seconds, "s", "traced")


#: the command line's options (harness.Option)
OPTIONS: dict[str, harness.Option] = {
    "patches": (1_000_000, "patches of the render workload"),
    "valence": (10_000, "valence of the check workload"),
    "skip": ("", "comma-separated parts to skip: export, render, check"),
    "export_mesh": ("spot_quadrangulated", "the shared mesh exported"),
}
#: the defaults --quick sets: small sizes, a smoke run
QUICK = {"patches": 20_000, "valence": 500, "export_mesh": "catmark_cube"}


def main(argv: Sequence[str] | None = None) -> None:
    args = harness.parse_args(__doc__, argv, OPTIONS, QUICK)
    skip = set(filter(None, args.skip.split(",")))
    print(harness.machine_line() + "\n")
    with tempfile.TemporaryDirectory() as name:
        folder = Path(name)
        if "export" not in skip:
            bench_export(folder, args.export_mesh)
        if "render" not in skip:
            bench_render(folder, args.patches)
    if "check" not in skip:
        bench_check(args.valence)


if __name__ == "__main__":
    main()
