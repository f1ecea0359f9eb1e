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

Run:  .venv/bin/python benchmarks/bench_files.py [--quads N] [--repeats R] [--formats a,b,...] [--dir DIR]
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import shutil
import tempfile
import time
import zipfile
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from g1patch import shapes
from g1patch.build import build_network
from g1patch.io.network_file import FORMAT_VERSION, load_network, save_network
from g1patch.memory import tune_for_large_arrays
from g1patch.network import PatchNetwork


def members(network: PatchNetwork) -> dict[str, np.ndarray]:
    """The members save_network writes, for the other writers."""
    patches = network.patches
    arrays: dict[str, Any] = {
        "header": np.array(
            json.dumps(
                {
                    "format": "g1patch-network",
                    "version": FORMAT_VERSION,
                    "provenance": network.provenance,
                }
            )
        ),
        "patch_kind": np.array(getattr(patches, "kind", "bicubic")),
        **patches.to_arrays(),  # type: ignore[attr-defined]
    }
    for name in (
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
    ):
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


def best(run: Callable[[], Any], repeats: int) -> tuple[float, Any]:
    times, result = [], None
    for _ in range(repeats):
        result = None  # free the previous result before the next run allocates its own
        start = time.perf_counter()
        result = run()
        times.append(time.perf_counter() - start)
    return min(times), result


def numpy_load(path: Path) -> dict[str, np.ndarray]:
    with np.load(path, allow_pickle=False) as data:
        return {name: data[name] for name in data.files}


def same(a: PatchNetwork, b: PatchNetwork) -> bool:
    arrays = (
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
    return (
        np.array_equal(a.patches.points, b.patches.points)  # type: ignore[attr-defined]
        and a.patches.frame == b.patches.frame  # type: ignore[attr-defined]
        and all(np.array_equal(getattr(a, n), getattr(b, n)) for n in arrays)
        and a.provenance == b.provenance
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--quads", type=int, default=1_000_000, help="quads of the torus (default: 1,000,000)"
    )
    parser.add_argument(
        "--repeats",
        type=int,
        default=3,
        help="runs per measurement, the best is reported (default: 3)",
    )
    parser.add_argument(
        "--formats", default=",".join(FORMATS), help=f"comma-separated, of: {', '.join(FORMATS)}"
    )
    parser.add_argument(
        "--dir",
        type=Path,
        default=None,
        help="where to write the files (default: a temporary folder)",
    )
    args = parser.parse_args()
    tune_for_large_arrays()  # as the command line does (g1patch.memory)
    chosen = [name.strip() for name in args.formats.split(",") if name.strip()]
    unknown = [name for name in chosen if name not in FORMATS]
    if unknown:
        parser.error(f"unknown formats {unknown}; choose from {list(FORMATS)}")

    print(
        f"python {platform.python_version()}, numpy {np.__version__}, {os.cpu_count()} cores, {platform.machine()}"
    )
    start = time.perf_counter()
    mesh = shapes.large_torus(args.quads)
    mesh_seconds = time.perf_counter() - start
    start = time.perf_counter()
    network = build_network(mesh)
    build_seconds = time.perf_counter() - start
    del mesh
    raw = sum(np.asarray(a).nbytes for a in members(network).values())
    print(
        f"mesh: {args.quads} quads in {mesh_seconds:.1f} s; build_network (gregory): {network.n_patches} patches in "
        f"{build_seconds:.1f} s; {raw / 1e6:.1f} MB of arrays"
    )

    folder = Path(tempfile.mkdtemp(prefix="bench_files.", dir=args.dir))
    rows = []
    try:
        for name in chosen:
            path = folder / f"{name.replace(' ', '_')}.npz"
            writer = FORMATS[name]

            def save() -> None:
                path.unlink(missing_ok=True)
                writer(path, network)

            save_seconds, _ = best(save, args.repeats)
            size = path.stat().st_size
            load_seconds, loaded = best(lambda: load_network(path), args.repeats)
            if not same(loaded, network):
                raise SystemExit(f"{name}: the round trip is not exact")
            loaded = None
            numpy_seconds, _ = best(lambda: numpy_load(path), args.repeats)
            rows.append((name, size, save_seconds, load_seconds, numpy_seconds))
            print(
                f"  {name}: {size / 1e6:.1f} MB, save {save_seconds:.2f} s, load {load_seconds:.2f} s",
                flush=True,
            )
            path.unlink()
    finally:
        shutil.rmtree(folder, ignore_errors=True)

    print()
    print(
        f"{network.n_patches} Gregory patches (best of {args.repeats}; build {build_seconds:.1f} s in this run)"
    )
    header = f"{'format':22s} {'size MB':>9s} {'save s':>8s} {'load s':>8s} {'np.load s':>10s} {'build s':>8s} {'save+load / build':>18s}"
    print(header)
    print("-" * len(header))
    for name, size, save_seconds, load_seconds, numpy_seconds in rows:
        share = (save_seconds + load_seconds) / build_seconds
        print(
            f"{name:22s} {size / 1e6:9.1f} {save_seconds:8.2f} {load_seconds:8.2f} {numpy_seconds:10.2f} "
            f"{build_seconds:8.1f} {share:17.1%}"
        )
    print(
        "load: load_network (validated); np.load: every member read, no checks. Target: save and load ≤ 1 s at 1 M quads."
    )


if __name__ == "__main__":
    main()
