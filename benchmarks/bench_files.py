"""Network files: save and load time and file size of a large Gregory network, by container.

Workload: ``build_network(shapes.large_torus(--quads))`` (default 1,000,000 quads), built once and
timed: the baseline the file times are compared with (the issue: saving the compressed network
took 11 of the 19 s of a 1 M-quad ``build``). Then, for each container, best of ``--repeats``:

* ``g1patch``: :func:`save_network` / :func:`load_network` as shipped (stored members written from
  the arrays' memory, CRC on a second thread; the load fully validated);
* ``np.savez``: numpy's uncompressed writer (``ZIP_STORED``);
* ``np.savez_compressed``: numpy's deflate writer (level 6), what releases before issue 12 wrote;
* ``zip deflate 1``: zipfile ``ZIP_DEFLATED`` at level 1, the fastest deflate.

Every file holds the same members (a valid network file of format version 3), so ``load`` is
:func:`load_network` on each — the validated load g1patch does; ``np.load`` reads every member
without checks, for comparison. Each save writes a fresh file (the previous one deleted first).
The round trip is checked to be exact. Target (issue 12): save and load each ≤ 1 s at 1 M quads.

Run:  .venv/bin/python benchmarks/bench_files.py [--quads N] [--repeats R] [--formats a,b,...]
      [--dir DIR] [--quick]
"""

from __future__ import annotations

import json
import shutil
import tempfile
import zipfile
from collections.abc import Callable, Sequence
from functools import partial
from pathlib import Path
from typing import Any

import harness
import numpy as np

from g1patch import shapes
from g1patch.build import build_network
from g1patch.io.network_file import FORMAT_VERSION, load_network, save_network
from g1patch.memory import tune_for_large_arrays
from g1patch.network import PatchNetwork

record = harness.recorder("bench_files")
#: the network's arrays a network file holds beside its patches
ARRAYS = (
    "corner_ids",
    "edge_ids",
    "edge_reversed",
    "neighbor",
    "neighbor_edge",
    "same_direction",
    "edge_collapsed",
    "seam",
    "vertices",
    "vertex_normals",
)


def members(network: PatchNetwork) -> dict[str, np.ndarray]:
    """The members save_network writes, for the other writers."""
    patches = network.patches
    header = {"format": "g1patch-network", "version": FORMAT_VERSION}
    arrays: dict[str, Any] = {
        "header": np.array(json.dumps({**header, "provenance": network.provenance})),
        "patch_kind": np.array(getattr(patches, "kind", "bicubic")),
        **patches.to_arrays(),  # type: ignore[attr-defined]
    }
    for name in ARRAYS:
        if getattr(network, name) is not None:
            arrays[name] = getattr(network, name)
    return arrays


def zip_writer(compression: int, level: int | None) -> Callable[[Path, PatchNetwork], None]:
    def write(path: Path, network: PatchNetwork) -> None:
        with zipfile.ZipFile(
            path, "w", compression=compression, compresslevel=level, allowZip64=True
        ) as archive:
            for name, array in members(network).items():
                with archive.open(f"{name}.npy", "w", force_zip64=True) as stream:
                    np.lib.format.write_array(stream, np.asanyarray(array), allow_pickle=False)

    return write


def numpy_writer(compressed: bool) -> Callable[[Path, PatchNetwork], None]:
    def write(path: Path, network: PatchNetwork) -> None:
        with open(path, "wb") as handle:
            (np.savez_compressed if compressed else np.savez)(handle, **members(network))

    return write


FORMATS: dict[str, Callable[[Path, PatchNetwork], None]] = {
    "g1patch": save_network,
    "np.savez": numpy_writer(False),
    "np.savez_compressed": numpy_writer(True),
    "zip deflate 1": zip_writer(zipfile.ZIP_DEFLATED, 1),
}


def numpy_load(path: Path) -> dict[str, np.ndarray]:
    with np.load(path, allow_pickle=False) as data:
        return {name: data[name] for name in data.files}


def same(a: PatchNetwork, b: PatchNetwork) -> bool:
    return (
        np.array_equal(a.patches.points, b.patches.points)  # type: ignore[attr-defined]
        and a.patches.frame == b.patches.frame  # type: ignore[attr-defined]
        and all(np.array_equal(getattr(a, n), getattr(b, n)) for n in ARRAYS)
        and a.provenance == b.provenance
    )


def measure(name: str, path: Path, network: PatchNetwork, repeats: int) -> dict[str, float]:
    """Save, load and np.load of one container: best seconds, and the file's bytes."""
    writer = FORMATS[name]

    def save() -> None:
        path.unlink(missing_ok=True)
        writer(path, network)

    save_seconds = harness.best(save, repeats)
    size = path.stat().st_size
    times, loaded = harness.runs(lambda: load_network(path), repeats)
    if not same(loaded, network):
        raise SystemExit(f"{name}: the round trip is not exact")
    del loaded
    numpy_seconds = harness.best(lambda: numpy_load(path), repeats)
    path.unlink()
    return {"size": size, "save": save_seconds, "load": min(times), "np.load": numpy_seconds}


def print_table(rows: dict[str, dict[str, float]], build_seconds: float) -> None:
    """The table of containers, and its records."""
    header = (
        f"{'format':22s} {'size MB':>9s} {'save s':>8s} {'load s':>8s} {'np.load s':>10s} "
        f"{'build s':>8s} {'save+load / build':>18s}"
    )
    print(header)
    print("-" * len(header))
    for name, row in rows.items():
        share = (row["save"] + row["load"]) / build_seconds
        print(
            f"{name:22s} {row['size'] / 1e6:9.1f} {row['save']:8.2f} {row['load']:8.2f} "
            f"{row['np.load']:10.2f} {build_seconds:8.1f} {share:17.1%}"
        )
        record(f"{name} file", row["size"] / 1e6, "MB")
        record(f"{name} save", row["save"], "s", "best")
        record(f"{name} load", row["load"], "s", "best; load_network, validated")
        record(f"{name} np.load", row["np.load"], "s", "best; no checks")
        record(f"{name} save + load / build", share, "×")
    print(
        "load: load_network (validated); np.load: every member read, no checks. Target: save "
        "and load ≤ 1 s at 1 M quads."
    )


#: the command line's options (harness.Option)
OPTIONS: dict[str, harness.Option] = {
    "quads": (1_000_000, "quads of the torus"),
    "repeats": (3, "runs per measurement, the best"),
    "formats": (",".join(FORMATS), "comma-separated containers"),
    "dir": (None, "where to write the files (default: a temporary folder)", Path),
}
#: the defaults --quick sets: small sizes, a smoke run
QUICK = {"quads": 20_000, "repeats": 1}


def main(argv: Sequence[str] | None = None) -> None:
    args = harness.parse_args(__doc__, argv, OPTIONS, QUICK)
    tune_for_large_arrays()  # as the command line does (g1patch.memory)
    chosen = [name.strip() for name in args.formats.split(",") if name.strip()]
    unknown = [name for name in chosen if name not in FORMATS]
    if unknown:
        raise SystemExit(f"unknown formats {unknown}; choose from {list(FORMATS)}")

    print(harness.machine_line())
    mesh_seconds, mesh = harness.timed(lambda: shapes.large_torus(args.quads))
    build_seconds, network = harness.timed(partial(build_network, mesh))
    del mesh
    raw = sum(np.asarray(a).nbytes for a in members(network).values())
    print(
        f"mesh: {args.quads} quads in {mesh_seconds:.1f} s; build_network (gregory): "
        f"{network.n_patches} patches in {build_seconds:.1f} s; {raw / 1e6:.1f} MB of arrays"
    )
    record("patches", network.n_patches, "", f"build_network(shapes.large_torus({args.quads}))")
    record("arrays", raw / 1e6, "MB")
    record("build", build_seconds, "s", "one build, the baseline of the ratios")

    folder = Path(tempfile.mkdtemp(prefix="bench_files.", dir=args.dir))
    rows = {}
    try:
        for name in chosen:
            path = folder / f"{name.replace(' ', '_')}.npz"
            rows[name] = row = measure(name, path, network, args.repeats)
            print(
                f"  {name}: {row['size'] / 1e6:.1f} MB, save {row['save']:.2f} s, load "
                f"{row['load']:.2f} s",
                flush=True,
            )
    finally:
        shutil.rmtree(folder, ignore_errors=True)
    print(
        f"\n{network.n_patches} Gregory patches (best of {args.repeats}; build "
        f"{build_seconds:.1f} s in this run)"
    )
    print_table(rows, build_seconds)


if __name__ == "__main__":
    main()
