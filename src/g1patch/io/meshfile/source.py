"""Reading an input file's bytes, bounded: only a regular file (after resolving links) is read,
and only up to a size cap; what every reader then checks its header counts against.

``/dev/zero``, a FIFO or a symbolic link to one would otherwise be read until memory runs out (or
wait forever): the file is opened without blocking, and its kind and size are taken from the
open file (``fstat``), so that it cannot be swapped between the check and the read.
"""

from __future__ import annotations

import os
import stat
from pathlib import Path

from ...errors import FormatError, InputError

#: the default cap on an input file's size (bytes, 2 GB): above any mesh g1patch builds on one
#: machine (a 2 GB OBJ holds ~25 M quads; reading a text mesh peaks at ~15-30 bytes a byte)
MAX_INPUT_BYTES = 2 * 10**9
#: the UTF-8 byte-order mark some editors write first; accepted before OBJ, OFF, PLY and .bpt text
BOM = b"\xef\xbb\xbf"
#: the most digits a count in a file may have: far above any count a file can hold (2 GB hold fewer
#: than 10^10 of anything), far below the 4300 digits Python's ``int`` refuses to convert
MAX_COUNT_DIGITS = 30
#: the most one ``read`` returns on Linux: a file up to the default cap is read in one call
_READ_MAX = 0x7FFFF000
_KINDS = (
    (stat.S_ISDIR, "a directory"),
    (stat.S_ISCHR, "a character device"),
    (stat.S_ISBLK, "a block device"),
    (stat.S_ISFIFO, "a FIFO (named pipe)"),
    (stat.S_ISSOCK, "a socket"),
)


def size_text(size: int) -> str:
    """``size`` bytes as ``'2.35 GB (2350000000 bytes)'`` (decimal units, as ``--max-input-size``
    takes them)."""
    for unit, scale in (("TB", 10**12), ("GB", 10**9), ("MB", 10**6), ("kB", 10**3)):
        if size >= scale:
            return f"{size / scale:.3g} {unit} ({size} bytes)"
    return f"{size} bytes"


def input_cap(max_bytes: int | None) -> int:
    """The cap in bytes: ``max_bytes``, or :data:`MAX_INPUT_BYTES` for None; anything but a
    positive integer raises :class:`InputError`."""
    if max_bytes is None:
        return MAX_INPUT_BYTES
    if isinstance(max_bytes, bool) or not isinstance(max_bytes, int) or max_bytes < 1:
        raise InputError(
            f"max_input_size: expected a number of bytes ≥ 1 (or None: {MAX_INPUT_BYTES}), got "
            f"{max_bytes!r}"
        )
    return max_bytes


def _cannot(path: Path, exc: OSError) -> FormatError:
    reason = "no such file" if isinstance(exc, FileNotFoundError) else exc.strerror or str(exc)
    return FormatError(path, f"cannot read the file ({reason})")


def _kind(mode: int) -> str:
    return next((text for test, text in _KINDS if test(mode)), "not a regular file")


def _check_status(path: Path, status: os.stat_result, cap: int) -> None:
    """Refuse anything but a regular file of at most ``cap`` bytes."""
    if not stat.S_ISREG(status.st_mode):
        target = os.path.realpath(path)
        link = f" (a link to {target})" if target != os.path.abspath(path) else ""
        raise FormatError(
            path, f"{_kind(status.st_mode)}{link}, not a regular file: only files are read"
        )
    if status.st_size > cap:
        raise FormatError(
            path,
            f"{size_text(status.st_size)}, above the input size cap of {size_text(cap)} "
            "(max_input_size, --max-input-size)",
        )


def check_input(path: Path, max_bytes: int | None = None) -> int:
    """The size of ``path`` if it is a regular file (links resolved) of at most ``max_bytes``
    (default :data:`MAX_INPUT_BYTES`); else :class:`FormatError` naming it, its kind or size and
    the cap. Reads nothing."""
    cap = input_cap(max_bytes)
    try:
        status = path.stat()
    except OSError as exc:
        raise _cannot(path, exc) from None
    _check_status(path, status, cap)
    return status.st_size


def read_input(path: Path, max_bytes: int | None = None) -> bytes:
    """The bytes of ``path``, a regular file (links resolved) of at most ``max_bytes`` (default
    :data:`MAX_INPUT_BYTES`); anything else is one :class:`FormatError` naming the file, its kind
    or size and the cap, before a byte is read. A file that grows while it is read is read only
    up to the size it had when opened (and the cap)."""
    cap = input_cap(max_bytes)
    check_input(path, cap)  # before opening: opening a device may have effects of its own
    flags = os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_BINARY", 0)
    try:
        descriptor = os.open(path, flags | getattr(os, "O_CLOEXEC", 0))
    except OSError as exc:
        raise _cannot(path, exc) from None
    try:
        status = os.fstat(descriptor)  # the file opened, whatever the path names now
        _check_status(path, status, cap)
        chunks, left = [], status.st_size
        while left > 0 and (chunk := os.read(descriptor, min(left, _READ_MAX))):
            chunks.append(chunk)
            left -= len(chunk)
    except OSError as exc:
        raise _cannot(path, exc) from None
    finally:
        os.close(descriptor)
    return chunks[0] if len(chunks) == 1 else b"".join(chunks)


def room_error(
    path: Path, line: int, count: int, what: str, each: int, need: int, have: int, after: str
) -> FormatError:
    """The error of a header count the file has no room for: ``count`` ``what`` of at least
    ``each`` bytes (``need`` bytes with what comes before them) where ``have`` bytes follow the
    header."""
    return FormatError(
        path,
        f"truncated: the header announces {count} {what} of at least {each} bytes each, "
        f"{need} bytes{after}, but only {have} bytes follow the header",
        line,
    )
