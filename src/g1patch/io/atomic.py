"""Atomic writes: a file appears complete under its name, or not at all.

The data is written to a temporary file beside the target and renamed onto it when complete.
Temporaries are named ``.g1patch-tmp-<target name>.<random><suffix>`` (hidden, and marked as
g1patch's): the context removes its temporary on every exit path it sees (an error, Ctrl-C, and
SIGTERM where the command line turns it into an exception). Only a process killed outright
(SIGKILL, a power cut) can leave one behind; such a file is never a finished output and may be
deleted (``rm .g1patch-tmp-*``).

Files get the permissions ``open()`` would give them: a new file ``0o666 & ~umask`` (the
temporary is created with mode 0o666 and the kernel applies the umask), a replaced regular file
keeps its permission bits. Errors name the path the caller gave, never the temporary.
"""

from __future__ import annotations

import contextlib
import errno as errno_codes
import os
import secrets
import signal
import stat
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

__all__ = ["TEMPORARY_PREFIX", "atomic_path"]

#: every temporary file of an atomic write starts with this (then the target's name)
TEMPORARY_PREFIX = ".g1patch-tmp-"
#: the longest part of the target's name kept in a temporary's name (NAME_MAX is 255 bytes)
_NAME_PART = 120
_SIGNALS = tuple(
    getattr(signal, name) for name in ("SIGINT", "SIGTERM", "SIGHUP") if hasattr(signal, name)
)


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
    return f"{TEMPORARY_PREFIX}{name}.{secrets.token_hex(4)}{suffix}"


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
