"""The README's figures from the benchmarks' records: ``python -m benchmarks.report``.

Rewrites the table between ``<!-- bench:begin -->`` and ``<!-- bench:end -->`` in README.md
from ``benchmarks/results.json`` (written by ``python -m benchmarks``). :data:`ROWS` says which
records make which row. A row whose records are missing (a benchmark not run, or run with other
sizes) keeps its current text in the README, matched by its key; records of a ``--quick`` run
are refused unless ``--allow-quick`` (for trying this script out, with ``--print``).

Run:  .venv/bin/python -m benchmarks.report [--results PATH] [--readme PATH] [--print]
      [--check] [--allow-quick]
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent
BEGIN, END = "<!-- bench:begin -->", "<!-- bench:end -->"
HEADER = "| what | figure |\n|---|---|"


class Missing(KeyError):
    """A record a row needs is not in the results."""


class Records:
    """The records of a results file, looked up by benchmark and name."""

    def __init__(self, results: dict[str, Any], allow_quick: bool = False) -> None:
        self.documents = results.get("benchmarks", {})
        self.values: dict[tuple[str, str], dict[str, Any]] = {}
        for bench, document in self.documents.items():
            if document.get("quick") and not allow_quick:
                continue  # smoke-run figures never go into the README
            if document.get("returncode"):
                continue
            for row in document.get("records", []):
                self.values[bench, row["name"]] = row

    def __call__(self, bench: str, name: str) -> Any:
        """The value of one record; :class:`Missing` when there is none."""
        if (bench, name) not in self.values:
            raise Missing(f"{bench}: {name}")
        return self.values[bench, name]["value"]

    def note(self, bench: str, name: str) -> str:
        """The note of one record."""
        self(bench, name)
        return str(self.values[bench, name]["note"])

    def of(self, bench: str, prefix: str = "") -> Callable[[str], Any]:
        """The look-up of one benchmark's records (whose names start with ``prefix``)."""
        return lambda name: self(bench, prefix + name)

    def maybe(self, bench: str, name: str) -> Any:
        """The value of one record, None when there is none."""
        row = self.values.get((bench, name))
        return None if row is None else row["value"]

    def present(self, bench: str, names: Iterable[str]) -> list[Any]:
        """The values of those of ``names`` that were recorded; :class:`Missing` if none."""
        wanted = list(names)
        found = [self.values[bench, n]["value"] for n in wanted if (bench, n) in self.values]
        if not found:
            raise Missing(f"{bench}: none of {len(wanted)} records like {wanted[0]!r}")
        return found

    def prefixed(self, bench: str, prefix: str) -> dict[str, Any]:
        """``{rest of the name: value}`` of the records whose name starts with ``prefix``."""
        return {
            name.removeprefix(prefix): row["value"]
            for (owner, name), row in self.values.items()
            if owner == bench and name.startswith(prefix)
        }

    def load(self, bench: str) -> float:
        """The 1-minute load average at the end of ``bench``'s run."""
        try:
            return float(self.documents[bench]["machine"]["load_average"]["end"][0])
        except (KeyError, IndexError, TypeError) as error:
            raise Missing(f"{bench}: load average") from error


def count(n: float) -> str:
    """A size as the README writes it: 1M, 4M, 100k, else with separators (819,200)."""
    n = int(n)
    for size, suffix in ((1_000_000, "M"), (1_000, "k")):
        if n >= size and n % size == 0:
            return f"{n // size:,}{suffix}"
    return f"{n:,}"


def span(values: Sequence[float], digits: int = 2) -> str:
    """``low–high`` of ``values`` (one figure when they agree to the digits shown)."""
    low, high = f"{min(values):.{digits}f}", f"{max(values):.{digits}f}"
    return low if low == high else f"{low}–{high}"


# ------------------------------------------------------------------------------------- rows
def build(r: Records) -> tuple[str, str]:
    quads = r("bench_build", "quads")
    scaled = r.maybe("bench_scaling", f"build, {quads} quads")
    scaling = "" if scaled is None else f"; {scaled:.2f} s in `bench_scaling.py`"
    return (
        f"Gregory build, {count(quads)} quads (as the CLI runs: freed memory kept, NumPy's "
        "huge-page advice on, `g1patch.memory`)",
        f"{r('bench_build', 'gregory build'):.2f} s, "
        f"{r('bench_build', 'gregory build peak per quad'):.0f} B/quad (`bench_build.py`, load "
        f"{r.load('bench_build'):.1f}{scaling}). The peak is the assembly's: targets and patches "
        "side by side (DESIGN §6)",
    )


def check(r: Records) -> tuple[str, str]:
    size = "1000000 quads"
    in_scaling = [
        f"{value:.2f}× at {label}"
        for n, label in ((1_000_000, "1M"), (4_000_000, "4M"))
        if (value := r.maybe("bench_scaling", f"check / build, {n} quads")) is not None
    ]
    scaling = " and ".join(in_scaling)
    return (
        "check of a Gregory network / its build, 1M quads (`bench_check.py`)",
        f"{r('bench_check', f'check / build, {size}'):.2f}× (check "
        f"{r('bench_check', f'check, {size}'):.2f} s, build "
        f"{r('bench_check', f'build, {size}'):.2f} s; load {r.load('bench_check'):.1f})"
        + (f"; {scaling} in `bench_scaling.py`" if scaling else ""),
    )


def scaling(r: Records) -> tuple[str, str]:
    names = ("build_s", "build_peak", "check_s", "check_peak")
    exponents = ", ".join(f"{r('bench_scaling', f'exponent of {n}'):.2f}" for n in names)
    return (
        f"scaling {count(r('bench_scaling', 'smallest size'))} → "
        f"{count(r('bench_scaling', 'largest size'))}: exponents of build time, build peak, "
        "check time, check peak",
        exponents,
    )


def end_to_end(r: Records) -> tuple[str, str]:
    s = r.of("bench_scaling", "end to end ")
    return (
        f"end to end, {count(s('quads'))} quads: binary PLY read, build, check while the file "
        "is written (`g1patch build --check`)",
        f"{s('read'):.2f} + {s('build'):.2f} + {s('check'):.2f} (+ {s('wait'):.2f} until the "
        f"file is written) = {s('total'):.1f} s (bar 30; one after the other the check takes "
        f"{s('check alone'):.2f} s and the save {s('save alone'):.2f} s), peak {s('peak'):.1f} GB",
    )


def limit(r: Records) -> tuple[str, str]:
    s = r.of("bench_limit")
    return (
        f"`limit` build with extraordinary vertices, {count(s('genus2 quads'))} quads / regular "
        f"{count(s('regular quads'))}",
        f"{s('genus2 limit build'):.2f} s / {s('regular limit build'):.2f} s, "
        f"{s('genus2 limit build peak per quad'):.0f} B/quad "
        f"({s('genus2 limit / interpolate build time'):.2f}× / "
        f"{s('regular limit / interpolate build time'):.2f}× the interpolating build)",
    )


def interpolants(r: Records) -> tuple[str, str]:
    constructions = ("interpolate", "limit-interpolate", "faired 0", "faired 1", "faired 2")
    smooth = ("catmark_cube", "catmark_torus", "spot_quadrangulated")
    cups = ("catmark_xord_interior", "catmark_xord_boundary")

    def p99(meshes: Sequence[str], names: Sequence[str], what: str = "p99") -> list[float]:
        wanted = [f"{m} {c} {what} turn / limit" for m in meshes for c in names]
        return r.present("bench_interpolants", wanted)

    def pair(name: str) -> str:
        return " / ".join(f"{p99([m], [name])[0]:.2f}" for m in cups)

    faired = [c for c in constructions if c.startswith("faired")]
    return (
        "p99 normal turn of surfaces through the vertices over the Catmull–Clark limit's "
        "(`bench_interpolants.py`)",
        f"cube, torus, Spot: {span(p99(smooth, constructions))} for every construction; the "
        f"xord cups: {span(p99(cups, constructions))} for every one (interpolate "
        f"{pair('interpolate')}, limit-interpolate {pair('limit-interpolate')}, "
        f"Halstead–Kass–DeRose faired {span(p99(cups, faired))}), their median turn already "
        f"{span(p99(cups, constructions, 'median'), 1)}× the limit's (DESIGN §5)",
    )


def polygon(r: Records) -> tuple[str, str]:
    s = r.of("bench_polygon")
    return (
        f"one {s('sides'):,}-sided face: split + build / `g1patch build`",
        f"{s('split'):.2f} + {s('build'):.2f} s, {s('split + build peak'):.0f} MB / "
        f"{s('command line build'):.2f} s, {s('command line resident peak'):.0f} MB resident "
        "(start-up included)",
    )


def files(r: Records) -> tuple[str, str]:
    s = r.of("bench_files")
    return (
        f"network save / load, {count(s('patches'))} Gregory patches ({s('arrays'):.0f} MB)",
        f"{s('g1patch save'):.2f} s / {s('g1patch load'):.2f} s",
    )


def evaluate(r: Records) -> tuple[str, str]:
    s = r.of("bench_evaluate")
    given = "positions + normals: g1patch evaluate_grid_with_normals, out="
    fresh = "positions + normals: g1patch evaluate_grid_with_normals, fresh"
    glibc = "positions + normals: g1patch fresh, glibc defaults"
    pages = "first touch of the outputs' new pages"
    return (
        f"positions + normals of {count(s('patches'))} Bézier patches × {s('grid')}² "
        "(`bench_evaluate.py`)",
        f"into given arrays {s(f'{given} time'):.0f} ms: {s(f'{given} of bound'):.0f} % of the "
        f"`np.copyto` bound, {s(f'{given} × splipy'):.0f}× splipy; into fresh arrays "
        f"{s(f'{fresh} time'):.0f} ms, {s(f'{fresh} of bound'):.0f} %, "
        f"{s(f'{fresh} × splipy'):.0f}× as the CLI runs (freed memory kept); with glibc's "
        f"allocator defaults {s(f'{glibc} time'):.0f} ms, {s(f'{glibc} of bound'):.0f} % (the "
        f"first touch of {s(pages.removeprefix('first touch of the ')):.0f} MB of new pages "
        f"alone: {s(pages):.0f} ms on one thread, {s(pages + ', 2 threads'):.0f} ms on two)",
    )


def split4(r: Records) -> tuple[str, str]:
    s = r.of("bench_split4")
    return (
        f"split4 build, irregular {count(s('quads'))} quads (`bench_split4.py`)",
        f"{s('split4 build'):.2f} s ({r.note('bench_split4', 'split4 build')}; load "
        f"{r.load('bench_split4'):.1f}); {s('split4 build peak per quad'):.0f} B/quad, "
        f"{s('split4 / gregory build time'):.2f}× the Gregory build in the same run",
    )


def readers(r: Records) -> tuple[str, str]:
    s = r.of("bench_readers")
    return (
        f"read_mesh, {count(s('quads'))} quads: OBJ / binary PLY (load "
        f"{r.load('bench_readers'):.1f})",
        f"{s('OBJ read'):.2f} s / {s('PLY binary read'):.2f} s (were 5.0 / 1.4 s when issue 13 "
        "was filed)",
    )


def cells(n: int) -> str:
    """How a patch was cut for STEP."""
    return "one quad per patch" if n == 1 else f"{n} × {n} quads per patch"


def spot(r: Records) -> tuple[str, str]:
    s = r.of("bench_cad", "spot_quadrangulated ")
    stages = r.prefixed("bench_cad", "spot_quadrangulated default export stage ")
    if not stages:
        raise Missing("bench_cad: the stages of Spot's export")
    spent = ", ".join(f"{k} {v:.2f}" for k, v in sorted(stages.items(), key=lambda kv: -kv[1]))
    best = r.note("bench_cad", "spot_quadrangulated default export").split(";")[0]
    return (
        "STEP of Spot, default (split4 re-assembly, exact G1 in OpenCASCADE)",
        f"{s('split4 file'):.1f} MB, ≤ {s('split4 OCC max angle on the file'):.1e}° on the "
        f"file's surfaces, {s('split4 deviation'):.1e} of the diagonal from the Gregory surface "
        f"({cells(s('split4 cells'))}); `export_step` {s('split4 export'):.2f} s in one run, "
        f"{s('default export'):.2f} s {best} ({spent}), the `fit` baseline "
        f"{s('fit file'):.0f} MB and {s('fit OCC max angle on the file'):.2f}° in "
        f"{s('fit export'):.0f} s",
    )


#: the coarse shared meshes of the STEP row, as the README names them
COARSE = {
    "catmark_xord_boundary": "xord_boundary",
    "catmark_xord_interior": "xord_interior",
    "catmark_tent_creases1": "tent",
    "catmark_dart_edgecorner": "dart",
}


def coarse(r: Records) -> tuple[str, str]:
    def s(mesh: str, name: str) -> Any:
        return r("bench_cad", f"{mesh} split4 {name}")

    parts = [
        f"{short} {s(mesh, 'deviation'):.1e} with {cells(s(mesh, 'cells'))} "
        f"({s(mesh, 'file'):.2f} MB)"
        for mesh, short in COARSE.items()
    ]
    angle = max(s(mesh, "OCC max angle on the file") for mesh in COARSE)
    return (
        "STEP of the coarse shared meshes, default",
        "within 1e-3 of the diagonal of the Gregory surface, cutting each patch into n × n quads "
        f"where one is not enough (`--max-deviation`): {', '.join(parts)}; OCC ≤ {angle:.1e}° on "
        "the file read back (`bench_cad.py`)",
    )


def fuzz(r: Records) -> tuple[str, str]:
    s = r.of("fuzz")
    kinds = {"tracebacks": "tracebacks", "crashes": "crashes", "leftover files": "leftovers"}
    kinds["NaN in reports"] = "NaN"
    found = {label: s(name) for name, label in kinds.items()}
    if not any(found.values()):
        problems = "0 " + " / ".join(found)
    else:
        problems = " / ".join(f"{n} {label}" for label, n in found.items())
    return f"{s('cases'):,} fuzzed inputs", f"{s('time'):.1f} min, {problems}"


@dataclass(frozen=True)
class Row:
    """One row of the README's table: ``key`` finds its current text, ``make`` the new one."""

    key: str
    make: Callable[[Records], tuple[str, str]]


#: the README's rows, in order
ROWS = (
    Row("Gregory build,", build),
    Row("check of a Gregory network", check),
    Row("scaling ", scaling),
    Row("end to end,", end_to_end),
    Row("`limit` build", limit),
    Row("p99 normal turn", interpolants),
    Row("-sided face", polygon),
    Row("network save / load", files),
    Row("positions + normals of", evaluate),
    Row("split4 build", split4),
    Row("read_mesh,", readers),
    Row("STEP of Spot", spot),
    Row("STEP of the coarse shared meshes", coarse),
    Row("fuzzed inputs", fuzz),
)


# ----------------------------------------------------------------------------------- README
def block(text: str) -> tuple[int, int]:
    """Where the generated block's contents start and end in ``text``."""
    start, end = text.find(BEGIN), text.find(END)
    if start < 0 or end < start:
        raise SystemExit(f"the README has no {BEGIN} … {END} block")
    return start + len(BEGIN), end


def current_rows(text: str) -> list[str]:
    """The table rows now between the markers."""
    start, end = block(text)
    lines = text[start:end].splitlines()
    return [line for line in lines if line.startswith("| ") and not line.startswith("| what |")]


def table(records: Records, old: Sequence[str]) -> tuple[str, list[str]]:
    """The new table, and the keys of the rows kept as they were."""
    lines, kept = [HEADER], []
    for row in ROWS:
        try:
            what, figure = row.make(records)
            lines.append(f"| {what} | {figure} |")
        except Missing as missing:
            previous = [line for line in old if row.key in line.split(" | ")[0]]
            kept.append(f"{row.key.strip()} ({missing.args[0]})")
            lines += previous[:1]
    return "\n".join(lines), kept


def caption(results: dict[str, Any], path: Path) -> str:
    """Where the figures come from."""
    commits = sorted({(d.get("commit") or "?")[:7] for d in results["benchmarks"].values()})
    shown = path.resolve()
    shown = shown.relative_to(HERE.parent) if shown.is_relative_to(HERE.parent) else shown
    return (
        f"Generated by `python -m benchmarks.report` from `{shown}` "
        f"({results.get('updated', '?')[:10]}, commit {', '.join(commits)}); a row whose "
        "benchmark was not run keeps its earlier text."
    )


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=(__doc__ or "").split("\n\n")[0])
    parser.add_argument("--results", type=Path, default=HERE / "results.json")
    parser.add_argument("--readme", type=Path, default=HERE.parent / "README.md")
    parser.add_argument("--print", action="store_true", help="print the block, change nothing")
    parser.add_argument("--check", action="store_true", help="exit 1 if the README would change")
    parser.add_argument("--allow-quick", action="store_true", help="use --quick records too")
    args = parser.parse_args(argv)
    if not args.results.is_file():
        raise SystemExit(f"{args.results} not found: run python -m benchmarks first")
    results = json.loads(args.results.read_text())
    text = args.readme.read_text()
    new, kept = table(Records(results, args.allow_quick), current_rows(text))
    start, end = block(text)
    updated = f"{text[:start]}\n{new}\n\n{caption(results, args.results)}\n{text[end:]}"
    if kept:
        print(f"{len(kept)} rows kept as they were, records missing:", file=sys.stderr)
        print("\n".join(f"  {line}" for line in kept), file=sys.stderr)
    if args.print:
        print(new)
        return 0
    if args.check:
        return int(updated != text)
    if updated != text:
        args.readme.write_text(updated)
        print(f"{args.readme}: {len(ROWS) - len(kept)} rows from {args.results}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
