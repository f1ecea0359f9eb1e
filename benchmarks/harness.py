"""The benchmarks' one timing, memory and record helper (issue 29, item 7).

* timing: wall-clock seconds by :func:`time.perf_counter`, CPU seconds (all threads) by
  :func:`time.process_time`; :func:`best` and :func:`median` of N runs;
* memory: :func:`traced`, the ``tracemalloc`` peak of a call over what was held when it started
  (NumPy's arrays included; numba's per-thread scratch is not traced); :func:`process_peak`, this
  process's resident peak (``ru_maxrss``); :func:`run_command`, a child's resident peak by GNU time
  (a small process, so the peak is the command's own: a child forked from this process would
  start its count from this process's pages);
* machine: :func:`machine` (processor, cores, load average, Python, NumPy) and :func:`git_commit`;
* records: :func:`record` collects ``(bench, name, value, unit, note)`` rows; a script's
  ``--json PATH`` writes them there when it exits, for ``python -m benchmarks``, which gathers
  them into ``results.json`` and ``results.md``;
* command line: :func:`parse_args` makes a script's options from its ``OPTIONS``, and adds
  ``--json`` and ``--quick`` (the script's ``QUICK`` defaults: small sizes, a smoke run).

Every script in this folder imports it from beside itself (``import harness``), so each one still
runs alone: ``python benchmarks/bench_build.py``.
"""

from __future__ import annotations

import argparse
import atexit
import datetime
import json
import os
import platform
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
import tracemalloc
from collections.abc import Callable, Mapping, Sequence
from dataclasses import asdict, dataclass
from functools import partial
from pathlib import Path
from typing import Any, NamedTuple, TypeVar

T = TypeVar("T")
Value = float | int | str | bool | None

ROOT = Path(__file__).resolve().parents[1]
#: the shared meshes and their Catmull–Clark references, beside the repository
SHARED = ROOT.parent / "shared" / "data"
#: the shared meshes with a Catmull–Clark limit reference (``reference/NAME.limit.npz``)
SHARED_MESHES = (
    "catmark_cube",
    "catmark_torus",
    "catmark_xord_interior",
    "catmark_xord_boundary",
    "spot_quadrangulated",
)


# ----------------------------------------------------------------------------------- timing
def timed(run: Callable[[], T]) -> tuple[float, T]:
    """Wall-clock seconds of ``run()``, and its result."""
    start = time.perf_counter()
    result = run()
    return time.perf_counter() - start, result


def clocked(run: Callable[[], T]) -> tuple[float, float, T]:
    """Wall-clock and CPU (this process, all threads) seconds of ``run()``, and its result."""
    wall, cpu = time.perf_counter(), time.process_time()
    result = run()
    return time.perf_counter() - wall, time.process_time() - cpu, result


def runs(run: Callable[[], T], repeats: int) -> tuple[list[float], T]:
    """Wall-clock seconds of ``repeats`` runs (≥ 1), and the last result; each result is dropped
    before the next run, so that two never stand in memory side by side."""
    seconds: list[float] = []
    result: Any = None
    for _ in range(max(repeats, 1)):
        result = None
        elapsed, result = timed(run)
        seconds.append(elapsed)
    return seconds, result


def best(run: Callable[[], object], repeats: int) -> float:
    """The shortest of ``repeats`` wall-clock times of ``run()``."""
    return min(runs(run, repeats)[0])


def median(run: Callable[[], object], repeats: int) -> float:
    """The median of ``repeats`` wall-clock times of ``run()``."""
    return statistics.median(runs(run, repeats)[0])


# ----------------------------------------------------------------------------------- memory
def traced(run: Callable[[], T]) -> tuple[float, int, T]:
    """Seconds (slowed by the tracing) and the bytes allocated at the peak of ``run()`` above
    what was held when it started (``tracemalloc``), and its result."""
    tracemalloc.start()
    try:
        seconds, result = timed(run)
        return seconds, tracemalloc.get_traced_memory()[1], result
    finally:
        tracemalloc.stop()


def peak(run: Callable[[], object]) -> int:
    """The ``tracemalloc`` peak of ``run()`` in bytes (:func:`traced`)."""
    return traced(run)[1]


def process_peak() -> int:
    """This process's resident peak so far (``ru_maxrss``), in bytes."""
    scale = 1 if sys.platform == "darwin" else 1024  # Linux reports KiB
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * scale


class Finished(NamedTuple):
    """A command's wall-clock seconds, resident peak in bytes (None without GNU time), output."""

    seconds: float
    resident: int | None
    stdout: str


def run_command(command: Sequence[str | Path], env: Mapping[str, str] | None = None) -> Finished:
    """Run ``command`` to its end, timed, with its resident peak from GNU time
    (``/usr/bin/time -f %M``); raises SystemExit with its error output if it fails."""
    words = [str(word) for word in command]
    gnu_time = shutil.which("time", path="/usr/bin:/bin")
    with tempfile.NamedTemporaryFile("r", suffix=".rss") as rss:
        wrapped = [gnu_time, "-o", rss.name, "-f", "%M", *words] if gnu_time else words
        seconds, result = timed(
            lambda: subprocess.run(wrapped, capture_output=True, text=True, env=env)
        )
        if result.returncode:
            raise SystemExit(f"{' '.join(words)} failed:\n{result.stderr[-2000:]}")
        kib = rss.read().split()
    return Finished(seconds, int(kib[-1]) * 1024 if kib else None, result.stdout)


def run_python(
    arguments: Sequence[str], env: Mapping[str, str] | None = None, empty_cache: bool = False
) -> str | None:
    """The last line ``python arguments…`` prints, in a fresh interpreter (with
    ``empty_cache``, an empty numba cache of its own: it compiles every kernel it uses), or None
    when it fails (its error's tail printed to stderr)."""
    environment = {**os.environ, **(env or {})}
    with tempfile.TemporaryDirectory(prefix="bench-numba.") as cache:
        if empty_cache:
            environment["NUMBA_CACHE_DIR"] = cache
        result = subprocess.run(
            [sys.executable, *arguments], capture_output=True, text=True, env=environment
        )
    lines = result.stdout.strip().splitlines()
    if result.returncode or not lines:
        print(f"(a child python failed: {result.stderr.strip()[-500:]})", file=sys.stderr)
        return None
    return lines[-1]


# ---------------------------------------------------------------------------------- machine
def load_average() -> tuple[float, float, float]:
    """The 1, 5 and 15 min load averages."""
    return os.getloadavg()


def loads() -> str:
    """The load averages as text, ``0.31 0.16 0.06``."""
    return " ".join(f"{x:.2f}" for x in load_average())


def machine() -> dict[str, Any]:
    """Processor, cores, load averages, Python and NumPy versions."""
    import numpy as np

    return {
        "processor": platform.processor() or platform.machine(),
        "cores": os.cpu_count(),
        "load_average": list(load_average()),
        "python": platform.python_version(),
        "numpy": np.__version__,
        "platform": platform.platform(),
    }


def machine_line() -> str:
    """One line of :func:`machine` for a script's header."""
    info = machine()
    return (
        f"{info['processor']}, {info['cores']} cores, Python {info['python']}, "
        f"NumPy {info['numpy']}; load average {loads()}"
    )


def git_commit() -> str | None:
    """HEAD's commit, with ``+dirty`` when the working tree has changes; None outside git."""

    def git(*words: str) -> str:
        return subprocess.run(
            ["git", "-C", str(ROOT), *words], capture_output=True, text=True, check=True
        ).stdout.strip()

    try:
        commit = git("rev-parse", "HEAD")
        return commit + ("+dirty" if git("status", "--porcelain", "--untracked-files=no") else "")
    except (OSError, subprocess.CalledProcessError):
        return None


def now() -> str:
    """The local date and time, ISO 8601 to the second."""
    return datetime.datetime.now().astimezone().isoformat(timespec="seconds")


# ---------------------------------------------------------------------------------- records
@dataclass(frozen=True)
class Record:
    """One figure of one benchmark: its value, unit (``s``, ``MB``, ``×``, …) and a note."""

    bench: str
    name: str
    value: Value
    unit: str = ""
    note: str = ""


RECORDS: list[Record] = []


def record(bench: str, name: str, value: Value, unit: str = "", note: str = "") -> None:
    """Add one figure to this process's records (NumPy scalars become Python numbers)."""
    if hasattr(value, "item"):
        value = value.item()  # type: ignore[union-attr]
    RECORDS.append(Record(bench, name, value, unit, note))


def recorder(bench: str) -> Callable[..., None]:
    """:func:`record` for one benchmark: ``record = recorder("bench_build")``."""
    return partial(record, bench)


def write_records(
    path: Path, started: str, load: Sequence[float], argv: Sequence[str], quick: bool
) -> None:
    """This process's records, with the machine (its load averages at the start and at the end),
    commit, dates and arguments, as JSON."""
    info = machine()
    info["load_average"] = {"start": list(load), "end": info["load_average"]}
    document = {
        "started": started,
        "finished": now(),
        "commit": git_commit(),
        "argv": list(argv),
        "quick": quick,
        "machine": info,
        "records": [asdict(row) for row in RECORDS],
    }
    Path(path).write_text(json.dumps(document, indent=1, ensure_ascii=False) + "\n")


#: an option ``--name``: (default, help) or (default, help, type); a default False makes a flag,
#: a list one or more values (an empty one: zero or more strings)
Option = tuple[Any, str] | tuple[Any, str, Callable[[str], Any]]


def _without_json(words: list[str]) -> list[str]:
    """The command-line words but ``--json PATH`` (a temporary file of the runner's)."""
    kept: list[str] = []
    for index, word in enumerate(words):
        if not (word.startswith("--json") or (index and words[index - 1] == "--json")):
            kept.append(word)
    return kept


def parse_args(
    doc: str | None,
    argv: Sequence[str] | None,
    options: Mapping[str, Option],
    quick: Mapping[str, Any] | None = None,
) -> argparse.Namespace:
    """The script's arguments: ``options`` (described in its ``doc``'s first paragraph), plus
    ``--quick`` (the defaults in ``quick``: small sizes, seconds in all) and ``--json PATH``
    (the records are written there when the process exits)."""
    parser = argparse.ArgumentParser(description=(doc or "").split("\n\n")[0])
    for name, (default, text, *kind) in options.items():
        flag = f"--{name.replace('_', '-')}"
        if default is False:
            parser.add_argument(flag, action="store_true", help=text)
            continue
        many = isinstance(default, list)
        if kind:
            value_type = kind[0]
        elif many:
            value_type = type(default[0]) if default else str
        else:
            value_type = type(default)
        shown = " ".join(map(str, default)) if many else default
        if text != argparse.SUPPRESS:
            text = f"{text} (default: {shown})".replace("%", "%%")
        nargs = ("+" if default else "*") if many else None
        parser.add_argument(flag, type=value_type, nargs=nargs, default=default, help=text)
    quick = dict(quick or {})
    shown = ", ".join(f"--{k.replace('_', '-')} {v}" for k, v in quick.items() if v is not True)
    parser.add_argument(
        "--quick", action="store_true", help=f"small sizes for a smoke run ({shown or 'fewer'})"
    )
    parser.add_argument("--json", type=Path, help="write the run's records there (JSON)")
    if parser.parse_known_args(argv)[0].quick:
        parser.set_defaults(**quick)
    arguments = parser.parse_args(argv)
    if arguments.json:
        given = _without_json(list(sys.argv[1:] if argv is None else argv))
        start = (now(), load_average())
        atexit.register(write_records, arguments.json, *start, given, arguments.quick)
    return arguments
