"""Mesh readers: ``read_mesh`` of a 1 M-quad torus as OBJ, OFF, ASCII PLY and binary PLY.

Workload: ``shapes.large_torus(--quads)`` (default 1,000,000 quads) written to a temporary
directory as OBJ and binary PLY (``write_quads``), ASCII PLY (meshio) and OFF (shortest round-trip
digits, as the OBJ writer). For each file, best of ``--repeats``:

* ``read_mesh``: the whole read as shipped (parse, then :meth:`QuadMesh.from_arrays` validation);
* ``parse``: the format reader alone (its fast path for these files) and ``from_arrays`` alone on
  its arrays: the validation's share of the read;
* ``before``: the reader this replaces, once — the line-by-line parser (OBJ, OFF) or meshio
  (PLY), which the fast paths fall back to — plus ``from_arrays`` by its NumPy code.

Baselines of the same run: the raw read of the file's bytes (``Path.read_bytes``), ``np.fromfile``
of the same bytes, meshio's own reader of the file (OBJ, PLY; its OFF reader takes only
triangles), and, for the text formats, ``np.fromstring`` of the file's numbers alone (coordinates
as float64, indices as int64, already cut out of the text): the cost of the number conversion that
any text parser pays. Targets (issue 13, 1 M quads): OBJ read ≤ 1 s, binary PLY ≤ 0.5 s.

Below the table, the compiled paths against their NumPy references, same run: the OBJ kernel
(``_obj_compiled``) against the NumPy fast path (``_obj_fast``), and ``from_arrays`` with its
kernels against the NumPy pairing and face check (kernel thresholds raised); and the cold compile:
``read_mesh`` of the OBJ, and of the binary PLY, each in a fresh process with an empty numba cache
(what a fresh install's first large read costs), then again in that process (warm).

Run:  .venv/bin/python benchmarks/bench_readers.py [--quads N] [--repeats R] [--dir DIR]
"""

from __future__ import annotations

import argparse
import os
import platform
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import meshio
import numpy as np

from g1patch import mesh as meshmodule
from g1patch import shapes
from g1patch.io import meshfile
from g1patch.io.meshfile import read_mesh, write_quads
from g1patch.memory import tune_for_large_arrays
from g1patch.mesh import QuadMesh


def best(function: Callable[[], Any], repeats: int) -> float:
    """The shortest of ``repeats`` wall-clock times of ``function()``."""
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        function()
        times.append(time.perf_counter() - start)
    return min(times)


def write_files(mesh: QuadMesh, directory: Path) -> dict[str, Path]:
    """The mesh as OBJ, OFF, ASCII PLY and binary PLY in ``directory``."""
    paths = {
        name: directory / file
        for name, file in [
            ("OBJ", "torus.obj"),
            ("OFF", "torus.off"),
            ("PLY ascii", "torus_ascii.ply"),
            ("PLY binary", "torus.ply"),
        ]
    }
    write_quads(paths["OBJ"], mesh.vertices, mesh.faces)
    write_quads(paths["PLY binary"], mesh.vertices, mesh.faces)
    meshio.ply.write(
        str(paths["PLY ascii"]),
        meshio.Mesh(mesh.vertices, [("quad", mesh.faces.astype(np.int32))]),
        binary=False,
    )
    with open(paths["OFF"], "w", encoding="ascii") as handle:
        handle.write(f"OFF\n{mesh.n_vertices} {mesh.n_faces} 0\n")
        handle.write(("%r %r %r\n" * mesh.n_vertices) % tuple(mesh.vertices.ravel().tolist()))
        handle.write(("4 %d %d %d %d\n" * mesh.n_faces) % tuple(mesh.faces.ravel().tolist()))
    return paths


def numbers_text(mesh: QuadMesh) -> tuple[bytes, bytes]:
    """The coordinates and the indices alone, as a text parser meets them (shortest digits)."""
    coordinates = ("%r %r %r\n" * mesh.n_vertices) % tuple(mesh.vertices.ravel().tolist())
    indices = ("%d %d %d %d\n" * mesh.n_faces) % tuple((mesh.faces + 1).ravel().tolist())
    return coordinates.encode(), indices.encode()


def parse_only(name: str, path: Path) -> Callable[[], meshfile._Parsed]:
    data = path.read_bytes()
    reader = {"OBJ": meshfile._read_obj, "OFF": meshfile._read_off}.get(name, meshfile._read_ply)
    return lambda: reader(path, data)


def before(name: str, path: Path) -> Callable[[], meshfile._Parsed]:
    """The reader the fast path replaces, which it falls back to."""
    data = path.read_bytes()
    if name == "OBJ":
        return lambda: meshfile._read_obj_lines(path, data)
    if name == "OFF":
        return lambda: meshfile._read_off_lines(path, data)

    def meshio_path() -> meshfile._Parsed:
        points, corners, sizes, _, _ = meshfile._ply_meshio(path, meshfile._ply_header(path, data))
        return meshfile._Parsed(points, corners.reshape(-1, int(sizes[0])))

    return meshio_path


@contextmanager
def numpy_references() -> Iterator[None]:
    """``from_arrays`` by its NumPy code: the kernels' thresholds out of reach."""
    saved = meshmodule.KERNEL_HALFEDGES, meshmodule.KERNEL_FACES
    meshmodule.KERNEL_HALFEDGES = meshmodule.KERNEL_FACES = sys.maxsize
    try:
        yield
    finally:
        meshmodule.KERNEL_HALFEDGES, meshmodule.KERNEL_FACES = saved


COLD = """
import sys, time
from g1patch.memory import tune_for_large_arrays
tune_for_large_arrays()
from g1patch.io.meshfile import read_mesh
times = []
for _ in range(2):
    start = time.perf_counter()
    read_mesh(sys.argv[1])
    times.append(time.perf_counter() - start)
print(*times)
"""


def cold_read(path: Path, directory: Path | None) -> tuple[float, float]:
    """(first, second) ``read_mesh`` seconds of ``path`` in a fresh process with an empty numba
    cache: the first read compiles every kernel the read uses."""
    with tempfile.TemporaryDirectory(dir=directory) as cache:
        environment = dict(os.environ, NUMBA_CACHE_DIR=cache)
        output = subprocess.run(
            [sys.executable, "-c", COLD, str(path)],
            env=environment,
            check=True,
            capture_output=True,
            text=True,
        ).stdout
    first, second = map(float, output.split())
    return first, second


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quads", type=int, default=1_000_000)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument(
        "--dir",
        type=Path,
        default=None,
        help="where to write the files (default: a temporary directory)",
    )
    args = parser.parse_args()
    tune_for_large_arrays()  # as the command line does

    mesh = shapes.large_torus(args.quads)
    print(
        f"python {platform.python_version()}, numpy {np.__version__}, meshio {meshio.__version__}, "
        f"{os.cpu_count()} cores; load average at start {os.getloadavg()[0]:.2f}"
    )
    print(
        f"mesh: shapes.large_torus({args.quads}): {mesh.n_vertices} vertices, {mesh.n_faces} quads; best of {args.repeats}"
    )
    coordinates, indices = numbers_text(mesh)

    def numbers() -> None:
        np.fromstring(coordinates, sep=" ")
        np.fromstring(indices, dtype=np.int64, sep=" ")

    with tempfile.TemporaryDirectory(dir=args.dir) as directory:
        paths = write_files(mesh, Path(directory))
        rows = []
        for name, path in paths.items():
            read = best(lambda: read_mesh(path), args.repeats)
            parse = parse_only(name, path)
            parsed = parse()
            again = QuadMesh.from_arrays(parsed.vertices, parsed.faces, source=str(path))
            assert again.vertices.tobytes() == mesh.vertices.tobytes() and np.array_equal(
                again.faces, mesh.faces
            )
            parse_seconds = best(parse, args.repeats)
            validate = best(
                lambda: QuadMesh.from_arrays(parsed.vertices, parsed.faces, source=str(path)),
                args.repeats,
            )
            with numpy_references():
                numpy_valid = best(
                    lambda: QuadMesh.from_arrays(parsed.vertices, parsed.faces, source=str(path)),
                    args.repeats,
                )
            old = best(before(name, path), 1) + numpy_valid
            raw = best(path.read_bytes, args.repeats)
            fromfile = best(lambda: np.fromfile(path, dtype=np.uint8), args.repeats)
            library = (
                None
                if name == "OFF"
                else best(lambda: meshio.read(path), 1 if name == "PLY ascii" else args.repeats)
            )
            bound = (
                best(numbers, args.repeats) if name != "PLY binary" else None
            )  # next to parse: the load changes
            rows.append(
                (
                    name,
                    path.stat().st_size,
                    old,
                    read,
                    parse_seconds,
                    validate,
                    raw,
                    fromfile,
                    library,
                    bound,
                )
            )
            print(f"  {name}: read_mesh {read:.2f} s", flush=True)
            if name == "OBJ":
                data = path.read_bytes()
                kernel_parse = best(lambda: meshfile._obj_compiled(data), args.repeats)
                numpy_parse = best(lambda: meshfile._obj_fast(data), args.repeats)
                kernel_valid, numpy_obj_valid = validate, numpy_valid
        cold = [cold_read(paths[name], args.dir) for name in ("OBJ", "PLY binary")]

    def cell(seconds: float | None) -> str:
        return f"{seconds:8.2f}" if seconds is not None else f"{'-':>8s}"

    def ratio(numerator: float | None, denominator: float | None) -> str:
        return (
            f"{numerator / denominator:7.1f}×"
            if numerator is not None and denominator is not None
            else f"{'-':>8s}"
        )

    print()
    header = (
        f"{'format':11s} {'MB':>6s} {'before':>8s} {'read':>8s} {'parse':>8s} {'valid.':>8s} {'raw read':>8s} "
        f"{'fromfile':>8s} {'meshio':>8s} {'numbers':>8s} {'before/':>8s} {'read/':>8s} {'parse/':>8s} {'parse/':>8s}"
    )
    print(header)
    print(
        f"{'':11s} {'':6s} {'':8s} {'':8s} {'':8s} {'':8s} {'':8s} {'':8s} {'':8s} {'':8s} {'read':>8s} {'meshio':>8s} {'numbers':>8s} {'fromfile':>8s}"
    )
    print("-" * len(header))
    for name, size, old, read, parse_seconds, validate, raw, fromfile, library, bound in rows:
        print(
            f"{name:11s} {size / 1e6:6.1f} {cell(old)} {cell(read)} {cell(parse_seconds)} {cell(validate)} {cell(raw)} "
            f"{cell(fromfile)} {cell(library)} {cell(bound)} {ratio(old, read)} {ratio(read, library)} "
            f"{ratio(parse_seconds, bound)} {ratio(parse_seconds, fromfile)}"
        )
    print(
        "seconds. before: the replaced reader (line-by-line OBJ/OFF parser, meshio for PLY) + NumPy validation, once; "
        "read: read_mesh; parse: the reader alone; valid.: QuadMesh.from_arrays on its arrays; numbers: np.fromstring "
        "of the coordinates and indices alone."
    )
    print(
        f"load average {os.getloadavg()[0]:.2f}. Targets: OBJ read ≤ 1 s, binary PLY read ≤ 0.5 s (1 M quads)."
    )

    print()
    print(f"compiled paths against their NumPy references (best of {args.repeats}):")
    print(
        f"  OBJ parse: kernel {kernel_parse:.2f} s, NumPy fast path {numpy_parse:.2f} s ({numpy_parse / kernel_parse:.1f}×)"
    )
    print(
        f"  from_arrays: kernels {kernel_valid:.2f} s, NumPy {numpy_obj_valid:.2f} s ({numpy_obj_valid / kernel_valid:.1f}×)"
    )
    (obj_first, obj_warm), (ply_first, ply_warm) = cold
    print(
        f"  cold compile (fresh process, empty numba cache): first read_mesh OBJ {obj_first:.2f} s, then {obj_warm:.2f} s "
        f"(compile ≈ {obj_first - obj_warm:.1f} s); binary PLY {ply_first:.2f} s, then {ply_warm:.2f} s "
        f"(≈ {ply_first - ply_warm:.1f} s)"
    )
    print(f"load average at end {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
