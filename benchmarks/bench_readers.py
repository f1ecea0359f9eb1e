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
      [--no-cold] [--quick]
"""

from __future__ import annotations

import sys
import tempfile
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from functools import partial
from pathlib import Path
from typing import Any

import harness
import meshio
import numpy as np

from g1patch import shapes
from g1patch.io import meshfile
from g1patch.io.meshfile import read_mesh, write_quads
from g1patch.memory import tune_for_large_arrays
from g1patch.mesh import QuadMesh
from g1patch.mesh import connectivity as mesh_connectivity
from g1patch.mesh import validate as mesh_validate

record = harness.recorder("bench_readers")
COLUMNS = ("before", "read", "parse", "valid.", "raw read", "fromfile", "meshio", "numbers")


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
    saved = mesh_connectivity.KERNEL_HALFEDGES, mesh_validate.KERNEL_FACES
    mesh_connectivity.KERNEL_HALFEDGES = mesh_validate.KERNEL_FACES = sys.maxsize
    try:
        yield
    finally:
        mesh_connectivity.KERNEL_HALFEDGES, mesh_validate.KERNEL_FACES = saved


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


def cold_read(path: Path) -> tuple[float, float]:
    """(first, second) ``read_mesh`` seconds of ``path`` in a fresh process with an empty numba
    cache: the first read compiles every kernel the read uses."""
    line = harness.run_python(["-c", COLD, str(path)], empty_cache=True)
    if line is None:
        raise SystemExit(f"the cold read of {path} failed")
    first, second = map(float, line.split())
    return first, second


def from_arrays(parsed: meshfile._Parsed, path: Path) -> Callable[[], QuadMesh]:
    """``QuadMesh.from_arrays`` on a reader's arrays, as ``read_mesh`` calls it."""
    return partial(QuadMesh.from_arrays, parsed.vertices, parsed.faces, source=str(path))


def measure(
    name: str, path: Path, mesh: QuadMesh, numbers: Callable[[], None], repeats: int
) -> dict[str, Any]:
    """One format's row: seconds per column of :data:`COLUMNS` (None where it does not apply)."""
    read = harness.best(lambda: read_mesh(path), repeats)
    parse = parse_only(name, path)
    parsed = parse()
    again = from_arrays(parsed, path)()
    assert again.vertices.tobytes() == mesh.vertices.tobytes()
    assert np.array_equal(again.faces, mesh.faces)
    parse_seconds = harness.best(parse, repeats)
    validate = harness.best(from_arrays(parsed, path), repeats)
    with numpy_references():
        numpy_valid = harness.best(from_arrays(parsed, path), repeats)
    library = None
    if name != "OFF":  # meshio's OFF reader takes only triangles
        library = harness.best(lambda: meshio.read(path), 1 if name == "PLY ascii" else repeats)
    row = {
        "before": harness.best(before(name, path), 1) + numpy_valid,
        "read": read,
        "parse": parse_seconds,
        "valid.": validate,
        "raw read": harness.best(path.read_bytes, repeats),
        "fromfile": harness.best(lambda: np.fromfile(path, dtype=np.uint8), repeats),
        "meshio": library,
        # next to parse: the load changes
        "numbers": harness.best(numbers, repeats) if name != "PLY binary" else None,
        "numpy valid.": numpy_valid,
    }
    if name == "OBJ":
        data = path.read_bytes()
        row["kernel parse"] = harness.best(lambda: meshfile._obj_compiled(data), repeats)
        row["numpy parse"] = harness.best(lambda: meshfile._obj_fast(data), repeats)
    return row


def ratio(numerator: float | None, denominator: float | None) -> float | None:
    """``numerator / denominator``, None when either is missing."""
    return None if numerator is None or denominator is None else numerator / denominator


def print_table(rows: dict[str, dict[str, Any]]) -> None:
    """The table of formats, and its records."""
    ratios = {
        "before/read": ("before", "read"),
        "read/meshio": ("read", "meshio"),
        "parse/numbers": ("parse", "numbers"),
        "parse/fromfile": ("parse", "fromfile"),
    }
    print(
        f"\n{'format':11s} {'MB':>6s} "
        + " ".join(f"{c:>8s}" for c in COLUMNS)
        + " "
        + " ".join(f"{c:>9s}" for c in ratios)
    )
    for name, row in rows.items():
        cells = [f"{row[c]:8.2f}" if row[c] is not None else f"{'-':>8s}" for c in COLUMNS]
        quotients = [ratio(row[a], row[b]) for a, b in ratios.values()]
        shown = [f"{q:8.1f}×" if q is not None else f"{'-':>9s}" for q in quotients]
        print(f"{name:11s} {row['MB']:6.1f} " + " ".join(cells) + " " + " ".join(shown))
        record(f"{name} file", row["MB"], "MB")
        for column in COLUMNS:
            if row[column] is not None:
                record(f"{name} {column.rstrip('.')}", row[column], "s", "best")
        for label, value in zip(ratios, quotients, strict=True):
            if value is not None:
                record(f"{name} {label}", value, "×")
    print(
        "seconds. before: the replaced reader (line-by-line OBJ/OFF parser, meshio for PLY) + "
        "NumPy validation, once; read: read_mesh; parse: the reader alone; valid.: "
        "QuadMesh.from_arrays on its arrays; numbers: np.fromstring of the coordinates and "
        "indices alone."
    )
    print(
        f"load average {harness.loads()}. Targets: OBJ read ≤ 1 s, binary PLY read ≤ 0.5 s "
        "(1 M quads)."
    )


def print_compiled(obj: dict[str, Any], repeats: int) -> None:
    """The compiled paths against their NumPy references, and their records."""
    kernel, numpy_parse = obj["kernel parse"], obj["numpy parse"]
    valid, numpy_valid = obj["valid."], obj["numpy valid."]
    print(f"\ncompiled paths against their NumPy references (best of {repeats}):")
    print(
        f"  OBJ parse: kernel {kernel:.2f} s, NumPy fast path {numpy_parse:.2f} s "
        f"({numpy_parse / kernel:.1f}×)"
    )
    print(
        f"  from_arrays: kernels {valid:.2f} s, NumPy {numpy_valid:.2f} s "
        f"({numpy_valid / valid:.1f}×)"
    )
    record("OBJ kernel parse", kernel, "s", "best")
    record("OBJ NumPy fast path parse", numpy_parse, "s", "best")
    record("from_arrays NumPy / kernels", numpy_valid / valid, "×", "OBJ's arrays")


def print_cold(paths: dict[str, Path]) -> None:
    """``read_mesh`` in a fresh process with an empty numba cache, OBJ and binary PLY."""
    texts = []
    for name in ("OBJ", "PLY binary"):
        first, warm = cold_read(paths[name])
        texts.append(
            f"{name} first read_mesh {first:.2f} s, then {warm:.2f} s (compile ≈ "
            f"{first - warm:.1f} s)"
        )
        record(f"{name} cold first read", first, "s", "fresh process, empty numba cache")
        record(f"{name} cold second read", warm, "s", "the same process")
    print("  cold compile (fresh process, empty numba cache): " + "; ".join(texts))


#: the command line's options (harness.Option)
OPTIONS: dict[str, harness.Option] = {
    "quads": (1_000_000, "quads of the torus"),
    "repeats": (3, "runs per measurement, the best"),
    "dir": (None, "where to write the files (default: a temporary folder)", Path),
    "no_cold": (False, "skip the cold-compile reads"),
}
#: the defaults --quick sets: small sizes, a smoke run
QUICK = {"quads": 20_000, "repeats": 1, "no_cold": True}


def main(argv: Sequence[str] | None = None) -> None:
    args = harness.parse_args(__doc__, argv, OPTIONS, QUICK)
    tune_for_large_arrays()  # as the command line does

    mesh = shapes.large_torus(args.quads)
    print(f"{harness.machine_line()}, meshio {meshio.__version__}")
    print(
        f"mesh: shapes.large_torus({args.quads}): {mesh.n_vertices} vertices, {mesh.n_faces} "
        f"quads; best of {args.repeats}"
    )
    record("quads", mesh.n_faces, "quads", f"shapes.large_torus({args.quads})")
    coordinates, indices = numbers_text(mesh)

    def numbers() -> None:
        np.fromstring(coordinates, sep=" ")
        np.fromstring(indices, dtype=np.int64, sep=" ")

    with tempfile.TemporaryDirectory(dir=args.dir) as directory:
        paths = write_files(mesh, Path(directory))
        rows = {}
        for name, path in paths.items():
            rows[name] = measure(name, path, mesh, numbers, args.repeats)
            rows[name]["MB"] = path.stat().st_size / 1e6
            print(f"  {name}: read_mesh {rows[name]['read']:.2f} s", flush=True)
        print_table(rows)
        print_compiled(rows["OBJ"], args.repeats)
        if not args.no_cold:
            print_cold(paths)
    print(f"load average at end {harness.loads()}")


if __name__ == "__main__":
    main()
