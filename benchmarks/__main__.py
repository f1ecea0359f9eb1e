"""Run the benchmarks and gather their records: ``python -m benchmarks [NAME ...] [--quick]``.

Each script (default: every ``bench_*.py`` here; ``fuzz`` runs when named) runs in a fresh
process, as it runs alone (``python benchmarks/bench_build.py``), with ``--json`` to hand its
records back (and ``--quick`` passed on: small sizes, a couple of minutes for them all). Its
tables print as it goes. Then:

* ``results.json``: per benchmark, its records (bench, name, value, unit, note), the machine
  (cores, load averages at the start and the end, Python, NumPy), the git commit, the dates, its
  arguments and exit status. A run of some benchmarks replaces theirs and keeps the others';
* ``results.md``: the same as Markdown, one table per benchmark.

A ``--quick`` run writes ``results-quick.json`` and ``results-quick.md`` instead, so that its
figures never mix with a full run's (``benchmarks.report`` refuses them for the README).
"""

from __future__ import annotations

import argparse
import json
import math
import subprocess
import sys
import tempfile
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from . import harness

HERE = Path(__file__).resolve().parent
#: the benchmarks run by default, in this order (the cheap and the much-quoted first)
DEFAULT = (
    "bench_evaluate",
    "bench_build",
    "bench_split4",
    "bench_shape",
    "bench_limit",
    "bench_tolerance",
    "bench_interpolants",
    "bench_cages",
    "bench_check",
    "bench_readers",
    "bench_files",
    "bench_cad",
    "bench_polygon",
    "bench_scaling",
    "bench_bounds",
)
#: run only when named: 10,000 fuzzed inputs take about 10 minutes on 2 cores
ON_REQUEST = ("fuzz",)


def known() -> list[str]:
    """Every benchmark script here: the default ones, the others found, those on request."""
    found = sorted(path.stem for path in HERE.glob("bench_*.py"))
    return [*DEFAULT, *(name for name in found if name not in DEFAULT), *ON_REQUEST]


def run_one(name: str, quick: bool, extra: Sequence[str]) -> dict[str, Any]:
    """Run one script in a fresh process; its records document, with its exit status added."""
    with tempfile.TemporaryDirectory(prefix="bench-records.") as folder:
        output = Path(folder) / f"{name}.json"
        command = [sys.executable, str(HERE / f"{name}.py"), "--json", str(output), *extra]
        command += ["--quick"] if quick else []
        print(f"\n===== {name}{' --quick' if quick else ''} =====", flush=True)
        seconds, result = harness.timed(lambda: subprocess.run(command, cwd=HERE.parent))
        document: dict[str, Any] = {"records": []}
        if output.is_file():
            document = json.loads(output.read_text())
    document.update(returncode=result.returncode, seconds=round(seconds, 1), quick=quick)
    status = "ok" if result.returncode == 0 else f"FAILED (exit {result.returncode})"
    print(
        f"===== {name}: {status}, {seconds:.0f} s, {len(document['records'])} records", flush=True
    )
    return document


def load(path: Path) -> dict[str, Any]:
    """The results so far, or an empty set."""
    if path.is_file():
        return json.loads(path.read_text())
    return {"benchmarks": {}}


def cell(value: Any) -> str:
    """A value for a Markdown table: counts with separators, floats to 4 significant digits."""
    if value is None:
        return "—"
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, int):
        return f"{value:,}"
    if isinstance(value, float):
        size = abs(value)
        if value == 0 or 0.01 <= size < 1000:
            return f"{value:.4g}"
        return f"{value:,.0f}" if size >= 1000 else f"{value:.2e}"
    return str(value)


def escape(text: str) -> str:
    """Text safe inside a Markdown table cell."""
    return text.replace("|", "\\|").replace("\n", " ")


def markdown(results: dict[str, Any]) -> str:
    """``results`` as Markdown: one section and table per benchmark."""
    lines = [
        "# Benchmark results",
        "",
        f"Written by `python -m benchmarks` on {results.get('updated', '?')}; figures of "
        "different benchmarks may come from different runs (each section says which).",
    ]
    for name, document in results["benchmarks"].items():
        info = document.get("machine", {})
        loads = info.get("load_average", {})
        start, end = loads.get("start", [math.nan])[0], loads.get("end", [math.nan])[0]
        commit = (document.get("commit") or "?")[:12]
        lines += [
            "",
            f"## {name}",
            "",
            f"{document.get('started', '?')}, commit {commit}, {document.get('seconds', '?')} s"
            f"{', quick' if document.get('quick') else ''}"
            f"{'' if document.get('returncode') == 0 else ', FAILED'}; "
            f"{info.get('processor', '?')}, {info.get('cores', '?')} cores, "
            f"Python {info.get('python', '?')}, NumPy {info.get('numpy', '?')}; "
            f"load average (1 min) {start:.2f} at the start, {end:.2f} at the end; "
            f"arguments: `{' '.join(document.get('argv', [])) or '(defaults)'}`",
            "",
            "| record | value | unit | note |",
            "|---|---:|---|---|",
        ]
        for row in document.get("records", []):
            lines.append(
                f"| {escape(row['name'])} | {escape(cell(row['value']))} | {escape(row['unit'])} "
                f"| {escape(row['note'])} |"
            )
    return "\n".join(lines) + "\n"


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m benchmarks", description=(__doc__ or "").split("\n\n")[0]
    )
    parser.add_argument("names", nargs="*", help="benchmarks to run (default: every bench_*)")
    parser.add_argument("--quick", action="store_true", help="small sizes: a smoke run")
    parser.add_argument("--list", action="store_true", help="list the benchmarks and stop")
    parser.add_argument(
        "--output", type=Path, help="results file (default: results.json, or results-quick.json)"
    )
    parser.add_argument(
        "--args",
        action="append",
        default=[],
        metavar="NAME=ARGS",
        help="more arguments for one script, e.g. --args 'bench_build=--quads 500000'",
    )
    args = parser.parse_args(argv)
    if args.list:
        print("\n".join(known()))
        return 0
    names = args.names or list(DEFAULT)
    unknown = [
        name.removesuffix(".py") for name in names if name.removesuffix(".py") not in known()
    ]
    if unknown:
        parser.error(f"unknown benchmarks {unknown}; --list shows them")
    extra: dict[str, list[str]] = {}
    for item in args.args:
        name, _, words = item.partition("=")
        extra.setdefault(name.removesuffix(".py"), []).extend(words.split())
    output = args.output or HERE / ("results-quick.json" if args.quick else "results.json")

    results = load(output)
    started = time.perf_counter()
    for name in (name.removesuffix(".py") for name in names):
        results["benchmarks"][name] = run_one(name, args.quick, extra.get(name, []))
        results["updated"] = harness.now()
        output.write_text(json.dumps(results, indent=1, ensure_ascii=False) + "\n")
        output.with_suffix(".md").write_text(markdown(results))
    ran = [name.removesuffix(".py") for name in names]
    failed = [name for name in ran if results["benchmarks"][name].get("returncode")]
    print(
        f"\n{len(names)} benchmarks in {time.perf_counter() - started:.0f} s; records in "
        f"{output} and {output.with_suffix('.md')}"
        + (f"; failed: {', '.join(failed)}" if failed else "")
    )
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
