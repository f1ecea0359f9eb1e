"""The run of a batch: its tasks on a Dask cluster (embedded, or an existing one by address), and
``summary.json``."""

from __future__ import annotations

import logging
import os
import signal
import sys
import time
from collections.abc import Sequence
from contextlib import ExitStack
from pathlib import Path
from typing import Any

from ..api import PathLike
from ..errors import G1PatchError, InputError, MissingDependencyError
from ..memory import tune_for_large_arrays
from .jobs import (
    FAILED,
    STATUSES,
    BuildOptions,
    Job,
    blank_record,
    check_formats,
    json_text,
    parse_formats,
    recipe,
)
from .plan import collect_inputs, jobs_for, plan
from .provenance import folder_lock
from .task import convert, one_line

#: the file in the output folder that holds one record per input
SUMMARY_NAME = "summary.json"
#: seconds to wait for an existing cluster to have a worker
WORKER_WAIT_S = 30.0


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
                        **blank_record(futures[future], FAILED),
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
    a file's own failure is its record's ``error``; another batch writing into ``out`` raises
    :class:`G1PatchError` before any is read (:func:`~.provenance.folder_lock`).
    ``out/summary.json`` is written at the end, and on an interrupt too (the files not done marked
    ``cancelled``) before it is raised again.
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
    check_formats(formats, options)
    sources = collect_inputs(inputs)
    folder = Path(out).resolve()
    every = jobs_for(sources, folder, formats, options)
    with folder_lock(folder):
        jobs, done = plan(every, formats, options)
        pending = {job.source: job for job in jobs}
        start = time.perf_counter()

        def records() -> list[dict[str, Any]]:
            return [
                done.get(str(source)) or blank_record(pending[str(source)]) for source in sources
            ]

        try:
            if jobs:
                _run(jobs, scheduler, workers, progress, done)
        except KeyboardInterrupt:
            wall = time.perf_counter() - start
            _write_summary(folder, records(), formats, options, wall, scheduler)
            raise
        result = records()
        _write_summary(folder, result, formats, options, time.perf_counter() - start, scheduler)
    return result


def _write_summary(
    folder: Path,
    records: list[dict[str, Any]],
    formats: Sequence[str],
    options: BuildOptions,
    wall: float,
    scheduler: str | None,
) -> None:
    """``folder/summary.json``: the batch's recipe (what each output's record must say too) and
    the records."""
    from .. import __version__
    from ..io.atomic import atomic_path

    summary = {
        "g1patch": __version__,
        "formats": list(formats),
        "options": recipe(options, formats, __version__),
        "scheduler": scheduler or "local",
        "wall_s": wall,
        "counts": {status: sum(r["status"] == status for r in records) for status in STATUSES},
        "files": records,
    }
    with atomic_path(folder / SUMMARY_NAME) as temporary:
        temporary.write_text(json_text(summary), encoding="utf-8")
