"""One task of a batch, run on a worker: read, build, check and export one file, recording what
each output was made from (:mod:`~g1patch.batch.provenance`)."""

from __future__ import annotations

import math
import os
import time
from pathlib import Path
from typing import Any

from ..errors import G1PatchError
from . import provenance
from .jobs import BUILT, FAILED, Job, blank_record, recipe


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


def _identity(path: str) -> tuple[int, ...]:
    """What changes when a file is written to or replaced."""
    status = os.stat(path)
    return status.st_size, status.st_mtime_ns, status.st_ctime_ns, status.st_ino, status.st_dev


def _read(job: Job) -> tuple[Any, str]:
    """The job's mesh and the SHA-256 of the bytes it was read from: the file hashed, then read,
    and refused if it changed in between (its identity before the hash and after the read)."""
    import g1patch

    options = job.options
    before = _identity(job.source)
    digest = provenance.sha256_of(job.source)
    mesh = g1patch.read(
        job.source,
        sharp_angle=options.sharp_angle,
        strict=True if options.strict else None,
        max_input_size=options.max_input_size,
    )
    if _identity(job.source) != before:
        raise G1PatchError(f"{job.source}: changed while it was read; run the batch again")
    return mesh, digest


def convert(job: Job) -> dict[str, Any]:
    """Build, check and export one file through the top-level API; the record of how it went.

    Never raises for the file's own failure (a bad mesh, a full disk, a bug): the record's
    ``status`` is ``failed`` and ``error`` says why in one line, so the batch goes on. Each output
    is written with its record of what it was made from (:func:`provenance.write_record`).
    """
    import g1patch

    options = job.options
    record = blank_record(job)
    times: dict[str, Any] = record["times"]
    start = last = time.perf_counter()

    def lap() -> float:
        nonlocal last
        now = time.perf_counter()
        spent, last = now - last, now
        return spent

    try:
        if job.version is not None and job.version != g1patch.__version__:
            raise G1PatchError(
                f"this worker runs g1patch {g1patch.__version__} and the batch {job.version}; "
                "install the same version on every worker"
            )
        made_by = recipe(options, job.formats, g1patch.__version__)
        mesh, record["sha256"] = _read(job)
        times["read"] = lap()
        surface = g1patch.smooth(
            mesh,
            shape=options.shape,
            method=options.method,
            refine=options.refine,
            tolerance=options.tolerance,
        )
        times["build"] = lap()
        record.update(
            patches=surface.n_patches,
            repairs=list(surface.repairs),
            seams=surface.network.n_seams,
            fallback_vertices=int(surface.provenance.get("fallback_vertices", "0")),
            # vertices the surface does not pass through (moved off to mend a fold)
            relaxed_vertices=int(surface.provenance.get("relaxed_vertices", "0")),
        )
        if "limit_distance" in surface.provenance:  # a limit shape: how far from the limit
            record["limit_distance"] = float(surface.provenance["limit_distance"])
        if surface.repairs:
            record["note"] = surface.mesh.repair_note  # type: ignore[union-attr]
        report = surface.check()
        times["check"] = lap()
        record.update(
            max_g1_angle_deg=_finite(max(report.max_edge_angle_deg, report.max_corner_angle_deg)),
            max_edge_angle_deg=_finite(report.max_edge_angle_deg),
            max_corner_angle_deg=_finite(report.max_corner_angle_deg),
            folds=report.folds,
        )
        times["export"] = {}
        for output, name in zip(job.outputs, job.formats, strict=True):
            provenance.forget(output)
            written = surface.export(output, **made_by["export"][name])
            times["export"][name] = lap()
            record["outputs"].append(output)
            if not isinstance(written, Path):  # STEP/IGES: faces, deviation, OpenCASCADE's angles
                record["cad"][name] = written.to_dict()
            provenance.write_record(output, made_by, job.source, record["sha256"], record)
        record["status"] = BUILT
    except Exception as error:  # a batch reports each file's failure, whatever it is, and goes on
        record.update(status=FAILED, error=one_line(error))
    times["total"] = time.perf_counter() - start
    return record
