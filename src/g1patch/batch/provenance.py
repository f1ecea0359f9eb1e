"""Each output's record of what it was made from, the truth a re-run goes by.

Beside every output ``OUT/<name>`` a batch writes ``OUT/.g1patch/<name>.json`` (hidden: OUT lists
only the outputs and ``summary.json``): the recipe (:func:`~g1patch.batch.jobs.recipe`: build
options, formats, export options, g1patch version), the input's path and SHA-256, the output's
size and modification time as written (so an output replaced or edited since has no record), and
the file's figures (so that a skipped file is reported without ``summary.json``).

The order makes the pair as good as one atomic write: the old record is removed before the
output is replaced, the new one written (atomically) after it, so an interruption anywhere
leaves an output without a record, never one with another output's. One format serves every
output (a mesh or CAD file has nowhere to keep it), and a record is read without opening the
output. A batch holds :func:`folder_lock` from reading the records to writing the summary: a
second batch into the same folder, whose outputs and records would interleave with the first's,
is refused.
"""

from __future__ import annotations

import errno
import hashlib
import json
import os
from collections.abc import Iterable, Iterator, Sequence
from concurrent.futures import ThreadPoolExecutor
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from ..errors import G1PatchError
from ..io.atomic import atomic_path
from .jobs import Job, json_text

__all__ = [
    "LOCK_NAME",
    "RECORDS_FOLDER",
    "folder_lock",
    "forget",
    "read_record",
    "record_path",
    "sha256_of",
    "sha256_of_each",
    "up_to_date",
    "write_record",
]

#: the hidden folder inside the output folder holding one record per output
RECORDS_FOLDER = ".g1patch"
#: the lock file inside :data:`RECORDS_FOLDER` (never a record's name: those end in ``.json``)
LOCK_NAME = "batch.lock"
#: the longest file name most file systems take (bytes); a longer record name is shortened
_NAME_MAX = 255
#: the version of the record's layout; a record of another is not trusted
SCHEMA = 1
#: bytes read at a time when hashing an input
_CHUNK = 1 << 20
#: threads hashing inputs at once (hashlib releases the GIL; the disk is shared anyway)
_HASH_THREADS = 4


def sha256_of(path: str | os.PathLike[str]) -> str:
    """The SHA-256 of the file's bytes (hex), read in chunks of a MiB."""
    digest = hashlib.sha256()
    buffer = bytearray(_CHUNK)
    view = memoryview(buffer)
    with open(path, "rb", buffering=0) as stream:
        while count := stream.readinto(buffer):
            digest.update(view[:count])
    return digest.hexdigest()


def sha256_of_each(paths: Iterable[str]) -> dict[str, str | None]:
    """:func:`sha256_of` of each path, on a few threads; None for a file that cannot be read (its
    task reports why)."""

    def one(path: str) -> str | None:
        try:
            return sha256_of(path)
        except OSError:
            return None

    paths = list(paths)
    if len(paths) < 2:
        return {path: one(path) for path in paths}
    with ThreadPoolExecutor(min(_HASH_THREADS, len(paths), os.cpu_count() or 1)) as pool:
        return dict(zip(paths, pool.map(one, paths), strict=True))


def record_path(output: str | os.PathLike[str]) -> Path:
    """Where the record of ``output`` is kept: ``<its folder>/.g1patch/<its name>.json``; a name
    too long for that keeps its first 200 bytes and a hash of the whole."""
    path = Path(output)
    name = path.name
    if len(os.fsencode(f"{name}.json")) > _NAME_MAX:
        digest = hashlib.sha256(os.fsencode(name)).hexdigest()[:16]
        while len(os.fsencode(name)) > 200:
            name = name[:-1]
        name = f"{name}~{digest}"
    return path.parent / RECORDS_FOLDER / f"{name}.json"


@contextmanager
def folder_lock(folder: str | os.PathLike[str]) -> Iterator[None]:
    """Hold ``folder/.g1patch/batch.lock`` (``flock``, released when the process ends however it
    ends); :class:`G1PatchError` naming the holder's PID when another batch holds it. Where the
    system or file system has no such locks, nothing is held."""
    try:
        import fcntl
    except ImportError:  # not POSIX
        yield
        return
    records = Path(folder) / RECORDS_FOLDER
    records.mkdir(parents=True, exist_ok=True)
    handle = os.open(records / LOCK_NAME, os.O_RDWR | os.O_CREAT | os.O_CLOEXEC, 0o666)
    try:
        try:
            fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError as error:
            if error.errno in (errno.EAGAIN, errno.EWOULDBLOCK, errno.EACCES):
                holder = os.pread(handle, 32, 0).decode("ascii", "replace").strip() or "?"
                raise G1PatchError(
                    f"{folder}: another batch (PID {holder}) is writing into this folder; wait "
                    "for it to end or choose another --out folder"
                ) from None
            # a file system without locks (ENOLCK, EOPNOTSUPP): nothing held
        else:
            os.ftruncate(handle, 0)
            os.pwrite(handle, f"{os.getpid()}\n".encode("ascii"), 0)
        yield
    finally:
        os.close(handle)


def _file_state(path: str | os.PathLike[str]) -> dict[str, int]:
    """What ties a record to the output as written: its size and modification time (ns)."""
    status = os.stat(path)
    return {"size": status.st_size, "mtime_ns": status.st_mtime_ns}


def forget(output: str | os.PathLike[str]) -> None:
    """Remove the record of ``output`` (before the output is replaced)."""
    record_path(output).unlink(missing_ok=True)


def write_record(
    output: str | os.PathLike[str],
    recipe: dict[str, Any],
    source: str,
    sha256: str,
    record: dict[str, Any],
) -> None:
    """Record that ``output``, as it is now, was made by ``recipe`` from ``source`` whose bytes
    hash to ``sha256``, with the figures of ``record`` (written atomically)."""
    path = record_path(output)
    path.parent.mkdir(exist_ok=True)
    content = {
        "g1patch_output": SCHEMA,
        "output": Path(output).name,
        "recipe": recipe,
        "input": {"path": source, "sha256": sha256},
        "file": _file_state(output),
        "record": record,
    }
    with atomic_path(path) as temporary:
        temporary.write_text(json_text(content), encoding="utf-8")


def read_record(output: str | os.PathLike[str]) -> dict[str, Any] | None:
    """The record of ``output`` if it describes the file there now; None when either is missing,
    the record is unreadable or of another layout, or the output changed since it was written."""
    try:
        content = json.loads(record_path(output).read_text(encoding="utf-8"))
        if (
            not isinstance(content, dict)
            or content.get("g1patch_output") != SCHEMA
            or not isinstance(content.get("input"), dict)
            or not isinstance(content.get("record"), dict)
            or content.get("file") != _file_state(output)
        ):
            return None
    except (OSError, ValueError):
        return None
    return content


def _matching(job: Job, wanted: dict[str, Any]) -> list[dict[str, Any]] | None:
    """The records of all the job's outputs if each is there and says it was made by ``wanted``
    from the job's input (its hash not yet compared); else None."""
    found = []
    for output in job.outputs:
        content = read_record(output)
        if (
            content is None
            or content["recipe"] != wanted
            or content["input"].get("path") != job.source
        ):
            return None
        found.append(content)
    return found


def up_to_date(jobs: Sequence[Job], wanted: dict[str, Any]) -> dict[str, dict[str, Any]]:
    """The jobs with nothing to do, by input path: the figures recorded with their last output
    (it was written last, knowing the others), for each job whose every output has a record made by
    ``wanted`` from the input's present bytes. Only those inputs are hashed."""
    candidates = {job.source: found for job in jobs if (found := _matching(job, wanted))}
    digests = sha256_of_each(candidates)
    return {
        source: found[-1]["record"]
        for source, found in candidates.items()
        if digests[source] is not None
        and all(content["input"].get("sha256") == digests[source] for content in found)
    }
