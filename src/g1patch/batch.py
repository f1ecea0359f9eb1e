"""``g1patch batch``: many meshes converted on a Dask cluster, one task per file, with a summary.

Each input mesh is one task (:func:`convert`): :func:`g1patch.read` → :func:`g1patch.smooth` →
:meth:`~g1patch.api.Surface.check` → :meth:`~g1patch.api.Surface.export` of every format asked,
to ``OUT/<stem>.<format>`` (atomic, as every g1patch write: a file appears whole or not at all).
A task never raises: it returns one record (a JSON-ready dict) with the file's figures, or its
error in one line, so a failing file stops no other. :func:`run_batch` writes the records to
``OUT/summary.json`` and :func:`summary_table` prints them.

The cluster is an embedded :class:`distributed.LocalCluster` of worker processes on 127.0.0.1
(one thread each; as many as the cores, at most one per file to convert), or an existing one by
its scheduler's address. Workers read the inputs and write the outputs by absolute path, so they
must see the same file system as the caller.

Re-running skips a file whose outputs all exist and are newer than it, unless the folder's
previous ``summary.json`` says they were built with other options (method, shape, refine, sharp
angle, strict) or failed: its record is carried over with status ``skipped``. When nothing is left
to convert, no cluster is started.

dask.distributed is the ``batch`` extra (``pip install 'g1patch[batch]'``), imported only when a
batch runs: ``import g1patch.batch`` needs no Dask.
"""

from __future__ import annotations

import importlib.util
import json
import logging
import math
import os
import signal
import sys
import time
from collections.abc import Sequence
from contextlib import ExitStack
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

from .api import CAD_SUFFIXES, EXPORT_SUFFIXES, MESH_SUFFIXES, PathLike
from .errors import G1PatchError, InputError, MissingDependencyError, check_choice
from .memory import tune_for_large_arrays

__all__ = [
    "FORMATS",
    "SUMMARY_NAME",
    "BuildOptions",
    "Job",
    "collect_inputs",
    "convert",
    "parse_formats",
    "plan",
    "run_batch",
    "summary_table",
]

#: the formats ``--formats`` takes: the suffixes :meth:`Surface.export` writes, without the dot
FORMATS = tuple(suffix[1:] for suffix in EXPORT_SUFFIXES)
#: the file in the output folder that holds one record per input
SUMMARY_NAME = "summary.json"
#: seconds to wait for an existing cluster to have a worker
WORKER_WAIT_S = 30.0
#: record statuses: converted now, up to date from an earlier run, failed, never run (interrupted)
BUILT, SKIPPED, FAILED, CANCELLED = "built", "skipped", "failed", "cancelled"
SKIP_NOTE = "outputs newer than input"
#: the record fields that must match an earlier run's for its outputs to be reused
_OPTION_KEYS = ("method", "shape", "refine", "sharp_angle", "strict")


@dataclass(frozen=True)
class BuildOptions:
    """The options of ``g1patch build`` a batch applies to every file (see
    :func:`g1patch.smooth`)."""

    method: str = "gregory"
    shape: str = "interpolate"
    refine: int = 0
    sharp_angle: float | None = None
    strict: bool = False

    def __post_init__(self) -> None:
        from .construct import METHODS
        from .targets import SHAPES

        check_choice("method", self.method, METHODS)
        check_choice("shape", self.shape, tuple(SHAPES))
        if isinstance(self.refine, bool) or not isinstance(self.refine, int) or self.refine < 0:
            raise InputError(
                f"refine: expected a number of Catmull–Clark steps ≥ 0, got {self.refine!r}"
            )
        if self.sharp_angle is not None and not (
            math.isfinite(self.sharp_angle) and 0 < self.sharp_angle < 180
        ):
            raise InputError(
                f"sharp angle: expected degrees between 0 and 180, got {self.sharp_angle!r}"
            )


@dataclass(frozen=True)
class Job:
    """One task: the input mesh and the files to write from it (absolute paths)."""

    source: str
    outputs: tuple[str, ...]
    options: BuildOptions


# ------------------------------------------------------------------------------- planning


def parse_formats(text: str | Sequence[str]) -> tuple[str, ...]:
    """``"npz,step,obj"`` (or a sequence of names) as ``("npz", "step", "obj")``: lower case,
    without dots, each once; an unknown one, or none, raises :class:`InputError` listing
    :data:`FORMATS`."""
    names = [name for name in (text.split(",") if isinstance(text, str) else text) if name.strip()]
    if not names:
        raise InputError(f"--formats: give at least one of {', '.join(FORMATS)}")
    formats: list[str] = []
    for name in names:
        cleaned = name.strip().lower().lstrip(".")
        if cleaned not in FORMATS:
            raise InputError(
                f"--formats: unknown format {name.strip()!r}; expected a comma-separated list of "
                f"{', '.join(FORMATS)}"
            )
        if cleaned not in formats:
            formats.append(cleaned)
    return tuple(formats)


def _check_formats(formats: Sequence[str], options: BuildOptions) -> None:
    """Refuse, before any work, what every file would fail on: .bpt of rational patches, CAD without
    OCP."""
    if "bpt" in formats and options.method == "gregory":
        raise InputError(
            "--formats bpt: .bpt holds polynomial Bézier patches and gregory patches are rational; "
            "use --method split4 (or corner), or export .step instead"
        )
    if (
        any(f".{name}" in CAD_SUFFIXES for name in formats)
        and importlib.util.find_spec("OCP") is None
    ):
        raise MissingDependencyError("cadquery-ocp-novtk", "cad", "STEP/IGES export")


def collect_inputs(paths: Sequence[PathLike]) -> list[Path]:
    """The mesh files to convert, absolute, each once, in the order given: files as they are,
    folders by the mesh files directly inside them (``.obj .ply .off``, hidden ones left out,
    sorted). A missing path, a file of another kind or a folder without meshes raises
    :class:`InputError`."""
    found: dict[Path, None] = {}
    for given in paths:
        path = Path(given)
        if path.is_dir():
            inside = sorted(
                child
                for child in path.iterdir()
                if child.suffix.lower() in MESH_SUFFIXES
                and not child.name.startswith(".")
                and child.is_file()
            )
            if not inside:
                raise InputError(
                    f"{path}: a folder with no mesh files ({', '.join(MESH_SUFFIXES)}) directly "
                    "inside it"
                )
            found.update(dict.fromkeys(child.resolve() for child in inside))
        elif path.is_file():
            if path.suffix.lower() not in MESH_SUFFIXES:
                raise InputError(
                    f"{path}: not a mesh file; batch converts {', '.join(MESH_SUFFIXES)} files "
                    "(and the folders holding them)"
                )
            found[path.resolve()] = None
        else:
            raise InputError(f"{path}: no such file or folder")
    if not found:
        raise InputError("no inputs: give mesh files or folders holding them")
    return list(found)


def _outputs(
    sources: Sequence[Path], out: Path, formats: Sequence[str]
) -> dict[Path, tuple[Path, ...]]:
    """``OUT/<stem>.<format>`` per source; two sources writing one file, or an output that is an
    input, raise :class:`InputError` naming both."""
    writer: dict[Path, Path] = {}
    result = {}
    for source in sources:
        targets = tuple(out / f"{source.stem}.{name}" for name in formats)
        for target in targets:
            if target in writer:
                raise InputError(
                    f"{writer[target]} and {source} would both write {target}; rename one, or "
                    "batch "
                    "them into different --out folders"
                )
            writer[target] = source
        result[source] = targets
    inputs = set(sources)
    for target, source in writer.items():
        if target in inputs:
            raise InputError(
                f"{source}: its output {target} would overwrite the input {target}; choose "
                "another --out "
                "folder or other --formats"
            )
    return result


def _up_to_date(source: Path, outputs: Sequence[Path]) -> bool:
    """Every output exists and was modified after the source."""
    made = source.stat().st_mtime_ns
    try:
        return all(output.stat().st_mtime_ns > made for output in outputs)
    except FileNotFoundError:
        return False


def _previous_records(out: Path) -> dict[str, dict[str, Any]]:
    """The records of the folder's earlier ``summary.json`` by input path; none when it is missing
    or unreadable (then outputs are reused by their times alone, and it is rewritten)."""
    path = out / SUMMARY_NAME
    try:
        files = json.loads(path.read_text(encoding="utf-8"))["files"]
        return {
            record["input"]: record
            for record in files
            if isinstance(record, dict) and "input" in record
        }
    except FileNotFoundError:
        return {}
    except (OSError, ValueError, KeyError, TypeError) as error:
        print(f"g1patch: {path}: unreadable ({error}); it will be rewritten", file=sys.stderr)
        return {}


def _reusable(previous: dict[str, Any] | None, options: BuildOptions) -> bool:
    if previous is None:
        return True
    wanted = asdict(options)
    return previous.get("status") in (BUILT, SKIPPED) and all(
        previous.get(key) == wanted[key] for key in _OPTION_KEYS
    )


def plan(
    sources: Sequence[Path], out: Path, formats: Sequence[str], options: BuildOptions
) -> tuple[list[Job], dict[str, dict[str, Any]]]:
    """(jobs to run, records of the files skipped, by input path): see the module docstring for when
    a file is skipped."""
    previous = _previous_records(out)
    jobs, skipped = [], {}
    for source, targets in _outputs(sources, out, formats).items():
        job = Job(str(source), tuple(map(str, targets)), options)
        earlier = previous.get(job.source)
        if _up_to_date(source, targets) and _reusable(earlier, options):
            record = _record(job) if earlier is None else {**_record(job), **earlier}
            record.update(status=SKIPPED, outputs=list(job.outputs), error=None, note=SKIP_NOTE)
            skipped[job.source] = record
        else:
            jobs.append(job)
    return jobs, skipped


# ------------------------------------------------------------------------------- one file


def _record(job: Job, status: str = CANCELLED) -> dict[str, Any]:
    """A record with the job's identity and options and no figures yet."""
    return {
        "input": job.source,
        "name": Path(job.source).name,
        "status": status,
        **asdict(job.options),
        "patches": None,
        "max_g1_angle_deg": None,
        "max_edge_angle_deg": None,
        "max_corner_angle_deg": None,
        "folds": None,
        "repairs": [],
        "seams": None,
        "fallback_vertices": None,
        "times": {},
        "outputs": [],
        "cad": {},
        "error": None,
        "note": None,
    }


def one_line(error: BaseException) -> str:
    """An error as one line: g1patch's own message; an OS error's file and reason; anything else by
    its type too (it is a bug in g1patch or a library it uses)."""
    if isinstance(error, G1PatchError):
        text = str(error)
    elif isinstance(error, OSError) and error.strerror:
        text = f"{error.filename}: {error.strerror}" if error.filename else error.strerror
    elif isinstance(error, MemoryError):
        text = "out of memory"
    else:
        text = f"{type(error).__name__}: {error} (unexpected: please report it)"
    return " ".join(text.split()) or type(error).__name__


def _finite(value: float) -> float | None:
    return float(value) if math.isfinite(value) else None


def convert(job: Job) -> dict[str, Any]:
    """Build, check and export one file through the top-level API; the record of how it went.

    Never raises for the file's own failure (a bad mesh, a full disk, a bug): the record's
    ``status`` is ``failed`` and ``error`` says why in one line, so the batch goes on.
    """
    import g1patch

    options = job.options
    record = _record(job)
    times: dict[str, Any] = record["times"]
    start = last = time.perf_counter()

    def lap() -> float:
        nonlocal last
        now = time.perf_counter()
        spent, last = now - last, now
        return spent

    try:
        mesh = g1patch.read(
            job.source, sharp_angle=options.sharp_angle, strict=True if options.strict else None
        )
        times["read"] = lap()
        surface = g1patch.smooth(
            mesh, shape=options.shape, method=options.method, refine=options.refine
        )
        times["build"] = lap()
        record.update(
            patches=surface.n_patches,
            repairs=list(surface.repairs),
            seams=surface.network.n_seams,
            fallback_vertices=int(surface.provenance.get("fallback_vertices", "0")),
        )
        report = surface.check()
        times["check"] = lap()
        record.update(
            max_g1_angle_deg=_finite(max(report.max_edge_angle_deg, report.max_corner_angle_deg)),
            max_edge_angle_deg=_finite(report.max_edge_angle_deg),
            max_corner_angle_deg=_finite(report.max_corner_angle_deg),
            folds=report.folds,
        )
        times["export"] = {}
        for output in job.outputs:
            written = surface.export(output)
            name = Path(output).suffix[1:]
            times["export"][name] = lap()
            record["outputs"].append(output)
            if not isinstance(
                written, Path
            ):  # STEP/IGES: faces, deviation, OpenCASCADE's G1 angles
                record["cad"][name] = written.to_dict()
        record["status"] = BUILT
        if surface.repairs:
            record["note"] = surface.mesh.repair_note  # type: ignore[union-attr]
    except Exception as error:  # a batch reports each file's failure, whatever it is, and goes on
        record.update(status=FAILED, error=one_line(error))
    times["total"] = time.perf_counter() - start
    return record


# ------------------------------------------------------------------------------- the cluster


def _cores() -> int:
    """The cores this process may run on."""
    if hasattr(os, "sched_getaffinity"):
        return max(1, len(os.sched_getaffinity(0)))
    return max(1, os.cpu_count() or 1)


def _distributed() -> Any:
    """The ``distributed`` module, or :class:`MissingDependencyError` naming the ``batch`` extra."""
    try:
        import distributed
    except ImportError:
        raise MissingDependencyError("distributed", "batch", "g1patch batch") from None
    return distributed


def _embedded_worker_setup() -> Any:
    """A worker plugin for the embedded cluster's worker processes, set up like the command line's:
    they ignore SIGINT (Ctrl-C reaches the whole process group; the command handles it and closes
    the cluster, where each worker would print its own KeyboardInterrupt traceback) and keep freed
    memory for their next job (:func:`g1patch.memory.tune_for_large_arrays`). The workers of a
    cluster given by ``scheduler`` are someone else's processes and are left as they are."""
    from distributed.diagnostics.plugin import WorkerPlugin

    class EmbeddedWorkerSetup(WorkerPlugin):
        name = "g1patch-embedded-worker"

        def setup(self, worker: Any) -> None:
            signal.signal(signal.SIGINT, signal.SIG_IGN)
            tune_for_large_arrays()

    return EmbeddedWorkerSetup()


def _client(
    stack: ExitStack, scheduler: str | None, workers: int | None, n_jobs: int
) -> tuple[Any, str]:
    """A connected ``distributed.Client`` (closed by ``stack``) and a phrase saying where it
    runs."""
    Client, LocalCluster = _distributed().Client, _distributed().LocalCluster
    if scheduler is None:
        count = workers or min(_cores(), n_jobs)
        cluster = stack.enter_context(
            LocalCluster(
                n_workers=count,
                threads_per_worker=1,
                processes=True,
                host="127.0.0.1",
                dashboard_address=None,
                # a record says what failed; no shutdown races on stderr
                silence_logs=logging.CRITICAL,
            )
        )
        client = stack.enter_context(Client(cluster))
        client.register_plugin(_embedded_worker_setup())
        return client, f"{count} local worker{'s' if count > 1 else ''}"
    try:
        client = stack.enter_context(Client(scheduler))
    except (OSError, TimeoutError, ValueError) as error:
        raise InputError(
            f"--scheduler {scheduler}: cannot connect ({' '.join(str(error).split())})"
        ) from None
    try:
        client.wait_for_workers(1, timeout=WORKER_WAIT_S)
    except TimeoutError:
        raise G1PatchError(
            f"--scheduler {scheduler}: no worker joined within {WORKER_WAIT_S:g} s "
            f"(start one: dask worker {scheduler})"
        ) from None
    count = len(client.scheduler_info().get("workers", {}))
    return client, f"the cluster at {scheduler} ({count} worker{'s' if count > 1 else ''})"


def _run(
    jobs: Sequence[Job],
    scheduler: str | None,
    workers: int | None,
    progress: bool,
    done: dict[str, dict[str, Any]],
) -> None:
    """Run ``jobs`` on the cluster, one task each, putting each record into ``done`` (by input path)
    as it finishes. On an interrupt the tasks already finished are collected too before it is raised
    again, so that their outputs count as built."""
    from tqdm import tqdm

    as_completed = _distributed().as_completed
    with ExitStack() as stack:
        client, where = _client(stack, scheduler, workers, len(jobs))
        if progress:
            print(
                f"g1patch: converting {len(jobs)} file{'s' if len(jobs) > 1 else ''} on {where}",
                file=sys.stderr,
            )
        futures = {client.submit(convert, job, pure=False): job for job in jobs}
        bar = stack.enter_context(
            tqdm(
                total=len(jobs),
                desc="batch",
                unit="file",
                file=sys.stderr,
                disable=not progress,
                leave=False,
            )
        )
        try:
            for future in as_completed(futures):
                try:
                    record = future.result()
                except Exception as error:  # the task died (its worker killed, the cluster gone)
                    record = {
                        **_record(futures[future], FAILED),
                        "error": f"task lost: {one_line(error)}",
                    }
                done[record["input"]] = record
                bar.update()
        except KeyboardInterrupt:
            finished = [future for future in futures if future.status == "finished"]
            for record in client.gather(finished, errors="skip"):
                done.setdefault(record["input"], record)
            raise


def run_batch(
    inputs: Sequence[PathLike],
    out: PathLike,
    *,
    formats: str | Sequence[str] = ("npz",),
    options: BuildOptions | None = None,
    scheduler: str | None = None,
    workers: int | None = None,
    progress: bool = False,
) -> list[dict[str, Any]]:
    """Convert ``inputs`` (mesh files and folders of them) into ``out``: the records, in input
    order.

    ``formats``: what to write per file (:data:`FORMATS`, e.g. ``"npz,step,obj"``). ``options``:
    the build options. ``scheduler``: the address of an existing Dask scheduler; without it an
    embedded LocalCluster of ``workers`` processes (default: the cores, at most one per file).
    ``progress``: a bar on stderr. Usage mistakes (a missing input, an unknown format, clashing
    outputs, an unreachable scheduler) raise :class:`InputError` before any file is converted;
    a file's own failure is its record's ``error``. ``out/summary.json`` is written at the end,
    and on an interrupt too (the files not done marked ``cancelled``) before it is raised again.
    The local cluster's workers are spawned processes: a script calling this needs Python's
    ``if __name__ == "__main__":`` guard (the ``g1patch`` command has it).
    """
    options = BuildOptions() if options is None else options
    formats = parse_formats(formats)
    if workers is not None and scheduler is not None:
        raise InputError(
            "--workers: sets the size of the embedded cluster; with --scheduler the cluster's own "
            "workers run the files"
        )
    if workers is not None and (isinstance(workers, bool) or workers < 1):
        raise InputError(f"--workers: expected a number of worker processes ≥ 1, got {workers!r}")
    _check_formats(formats, options)
    sources = collect_inputs(inputs)
    folder = Path(out).resolve()
    jobs, done = plan(sources, folder, formats, options)
    folder.mkdir(parents=True, exist_ok=True)
    pending = {job.source: job for job in jobs}
    start = time.perf_counter()

    def records() -> list[dict[str, Any]]:
        return [done.get(str(source)) or _record(pending[str(source)]) for source in sources]

    try:
        if jobs:
            _run(jobs, scheduler, workers, progress, done)
    except KeyboardInterrupt:
        _write_summary(folder, records(), formats, time.perf_counter() - start, scheduler)
        raise
    result = records()
    _write_summary(folder, result, formats, time.perf_counter() - start, scheduler)
    return result


def _write_summary(
    folder: Path,
    records: list[dict[str, Any]],
    formats: Sequence[str],
    wall: float,
    scheduler: str | None,
) -> None:
    from . import __version__
    from .io.atomic import atomic_path

    summary = {
        "g1patch": __version__,
        "formats": list(formats),
        "scheduler": scheduler or "local",
        "wall_s": wall,
        "counts": {
            status: sum(r["status"] == status for r in records)
            for status in (BUILT, SKIPPED, FAILED, CANCELLED)
        },
        "files": records,
    }
    with atomic_path(folder / SUMMARY_NAME) as temporary:
        temporary.write_text(
            json.dumps(_json_ready(summary), indent=1, allow_nan=False) + "\n", encoding="utf-8"
        )


def _json_ready(value: Any) -> Any:
    """``value`` with NaN and infinities as None (JSON has neither), NumPy scalars as Python's, and
    anything else JSON lacks as its str."""
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, dict):
        return {str(key): _json_ready(item) for key, item in value.items()}
    if isinstance(value, (list, tuple)):
        return [_json_ready(item) for item in value]
    if isinstance(value, bool) or value is None or isinstance(value, (int, str)):
        return value
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    return str(value)


# ------------------------------------------------------------------------------- the table


def _cell(value: Any, form: str) -> str:
    return "-" if value is None else format(value, form)


def summary_table(records: Sequence[dict[str, Any]]) -> str:
    """The records as a text table: one row per file, the note (an error, a repair, why it was
    skipped) last, then a line of counts."""
    header = (
        "file",
        "status",
        "method",
        "shape",
        "patches",
        "max G1°",
        "folds",
        "repairs",
        "seams",
        "time s",
        "note",
    )
    rows = [header]
    for r in records:
        total = r["times"].get("total") if r["status"] != SKIPPED else None
        note = r["error"] if r["status"] == FAILED else r.get("note") or ""
        rows.append(
            (
                r["name"],
                r["status"],
                r["method"],
                r["shape"],
                _cell(r["patches"], "d"),
                _cell(r["max_g1_angle_deg"], ".2e"),
                _cell(r["folds"], "d"),
                str(len(r["repairs"])),
                _cell(r["seams"], "d"),
                _cell(total, ".2f"),
                note,
            )
        )
    widths = [max(len(row[column]) for row in rows) for column in range(len(header) - 1)]
    lines = [
        "  ".join(cell.ljust(width) for cell, width in zip(row, widths, strict=False))
        + "  "
        + row[-1]
        for row in rows
    ]
    counts = {
        status: sum(r["status"] == status for r in records)
        for status in (BUILT, SKIPPED, FAILED, CANCELLED)
    }
    tally = ", ".join(
        f"{count} {status}" for status, count in counts.items() if count or status != CANCELLED
    )
    lines.append(f"{len(records)} file{'s' if len(records) != 1 else ''}: {tally}")
    return "\n".join(line.rstrip() for line in lines)
