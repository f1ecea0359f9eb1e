"""Atomic writes: a file appears complete under its name, or not at all.

The data is written to a temporary file beside the target and renamed onto it when complete.
Temporaries are named ``.g1patch-tmp-<target name>.<host>-<pid>-<random><suffix>`` (hidden, and
marked as g1patch's): the context removes its temporary on every exit path it sees (an error,
Ctrl-C, and SIGTERM where the command line turns it into an exception). Only a process killed
outright (SIGKILL, a power cut) can leave one behind; such a file is never a finished output. The
next atomic write into the same folder (at most one look a minute per folder and process) removes
the stale ones of this host (``<host>``: its name and PID namespace): those whose writer ``<pid>``
is not running, or is a process younger than the file (the PID was reused; ``/proc/<pid>/stat``).
A live writer's temporary is never removed.

Files get the permissions ``open()`` would give them: a new file ``0o666 & ~umask`` (the
temporary is created with mode 0o666 and the kernel applies the umask), a replaced regular file
keeps its permission bits. Errors name the path the caller gave, never the temporary.
"""

from __future__ import annotations

import contextlib
import errno as errno_codes
import hashlib
import math
import os
import re
import secrets
import signal
import socket
import stat
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

__all__ = ["TEMPORARY_PREFIX", "atomic_path", "remove_stale_temporaries"]

#: every temporary file of an atomic write starts with this (then the target's name)
TEMPORARY_PREFIX = ".g1patch-tmp-"
#: the longest part of the target's name kept in a temporary's name (NAME_MAX is 255 bytes)
_NAME_PART = 120
_SIGNALS = tuple(
    getattr(signal, name) for name in ("SIGINT", "SIGTERM", "SIGHUP") if hasattr(signal, name)
)


#: a temporary's name: ``<host>-<pid>-<random><suffix>`` after the target's name
_WRITER = re.compile(r"\.(?P<host>[0-9a-f]{8})-(?P<pid>[0-9]+)-[0-9a-f]{8}(?:\.[^.]*)?$")
#: a folder is swept for stale temporaries at most once in this many seconds by one process
SWEEP_INTERVAL_S = 60.0
#: seconds of slack between a file's time and its writer's start (clock steps, boot-time rounding)
_START_SLACK_S = 2.0
_swept: dict[str, float] = {}


def _host() -> str:
    """8 hex digits naming this host and PID namespace: PIDs mean something only within them."""
    try:
        namespace = os.readlink("/proc/self/ns/pid")
    except OSError:
        namespace = ""
    return hashlib.sha256(f"{socket.gethostname()}/{namespace}".encode()).hexdigest()[:8]


def _boot_time() -> float | None:
    """The system's boot time (seconds since the epoch, ``btime`` of ``/proc/stat``), or None."""
    try:
        with open("/proc/stat", "rb") as lines:
            for line in lines:
                if line.startswith(b"btime "):
                    return float(line.split()[1])
    except (OSError, ValueError, IndexError):
        pass
    return None


def _writer_alive(pid: int, since: float) -> bool:
    """Whether process ``pid`` runs and started no later than ``since`` (the temporary's time):
    a younger process with that PID (reuse) or a zombie cannot be the temporary's writer."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:  # another user's process, or no way to ask: alive
        return True
    try:
        with open(f"/proc/{pid}/stat", "rb") as handle:
            fields = handle.read().rsplit(b")", 1)[1].split()
        state, ticks = fields[0], int(fields[19])
    except (OSError, ValueError, IndexError):  # no /proc: the PID alone decides
        return True
    boot = _boot_time()
    if state == b"Z" or boot is None:
        return state != b"Z"
    started = boot + ticks / os.sysconf("SC_CLK_TCK")
    return started <= since + _START_SLACK_S


def remove_stale_temporaries(folder: str | os.PathLike[str], *, force: bool = False) -> list[Path]:
    """Delete the temporaries of atomic writes in ``folder`` left by this host's dead writers
    (SIGKILL, a power cut); returns them. A folder is looked at once a :data:`SWEEP_INTERVAL_S`
    per process unless ``force``; every error is ignored (a sweep never fails a write)."""
    key = os.path.abspath(folder)
    now = time.monotonic()
    if os.name != "posix" or (not force and now - _swept.get(key, -math.inf) < SWEEP_INTERVAL_S):
        return []
    _swept[key] = now
    host, removed = _host(), []
    try:
        entries = list(os.scandir(key))
    except OSError:
        return []
    for entry in entries:
        match = _WRITER.search(entry.name) if entry.name.startswith(TEMPORARY_PREFIX) else None
        if match is None or match["host"] != host:
            continue
        try:
            info = entry.stat(follow_symlinks=False)
            if not stat.S_ISREG(info.st_mode) or _writer_alive(int(match["pid"]), info.st_mtime):
                continue
            os.unlink(entry.path)
        except OSError:
            continue
        removed.append(Path(entry.path))
    return removed


@contextmanager
def _signals_blocked() -> Iterator[None]:
    """Hold SIGINT, SIGTERM and SIGHUP back (delivered on exit) while a temporary is created or
    removed, so that an interrupt can never fall between creating the file and knowing its name."""
    if not hasattr(signal, "pthread_sigmask"):
        yield
        return
    previous = signal.pthread_sigmask(signal.SIG_BLOCK, _SIGNALS)
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, previous)


def _temporary_name(target: Path) -> str:
    name, suffix = target.name[:_NAME_PART], target.suffix or ".tmp"
    return f"{TEMPORARY_PREFIX}{name}.{_host()}-{os.getpid()}-{secrets.token_hex(4)}{suffix}"


def _create_temporary(target: Path) -> Path:
    """A new empty file beside ``target``, mode ``0o666 & ~umask`` or the mode of the file it will
    replace."""
    directory = target.parent
    try:
        existing = os.stat(target)
        mode = stat.S_IMODE(existing.st_mode) & 0o777 if stat.S_ISREG(existing.st_mode) else 0o666
    except OSError:
        mode = 0o666
    for _ in range(100):
        candidate = directory / _temporary_name(target)
        try:
            handle = os.open(
                candidate, os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_CLOEXEC", 0), 0o666
            )
        except FileExistsError:
            continue
        try:
            if mode != 0o666 and hasattr(os, "fchmod"):
                os.fchmod(handle, mode)
        finally:
            os.close(handle)
        return candidate
    raise FileExistsError(errno_codes.EEXIST, "cannot find an unused temporary name", str(target))


def _renamed(error: OSError, target: Path, temporary: Path | None) -> OSError:
    """``error`` about the temporary (or about no file at all) as the same error about
    ``target``."""
    about = error.filename
    if isinstance(about, (str, bytes, os.PathLike)):
        ours = os.path.basename(os.fsdecode(about)).startswith(TEMPORARY_PREFIX)
    else:
        ours = about is None
    if error.errno is None or not ours:
        return error
    return OSError(error.errno, error.strerror or os.strerror(error.errno), str(target))


@contextmanager
def atomic_path(path: str | os.PathLike[str]) -> Iterator[Path]:
    """Yield a temporary path beside ``path``; on success rename it onto ``path``, on any exit by an
    exception (KeyboardInterrupt included) delete it.

    The temporary (``.g1patch-tmp-<name>.<random><suffix>``, see the module docstring) keeps the
    suffix of ``path`` so that writers choosing a format by extension (meshio, matplotlib) pick the
    right one. An :class:`OSError` about the temporary, or about no file (a full disk, a file too
    large), is raised again about ``path``. A target that exists and is not a regular file or a
    directory (``/dev/null``, a named pipe) is written directly: it cannot be replaced.
    """
    target = Path(path)
    try:
        existing = os.stat(target)
    except OSError:
        existing = None
    if existing is not None and not (
        stat.S_ISREG(existing.st_mode) or stat.S_ISDIR(existing.st_mode)
    ):
        try:
            yield target
        except OSError as error:
            raise _renamed(error, target, None) from None
        return

    temporary: Path | None = None
    remove_stale_temporaries(target.parent)
    try:
        with _signals_blocked():
            temporary = _create_temporary(target)
        yield temporary
        os.replace(temporary, target)
    except BaseException as error:
        if temporary is not None:
            with _signals_blocked(), contextlib.suppress(OSError):
                temporary.unlink(missing_ok=True)
        if isinstance(error, OSError):
            raise _renamed(error, target, temporary) from None
        raise
