"""The ``g1patch`` command line: a thin shell over build, check, export, render, demo and batch.

Exit codes: 0 success; 1 a check failed (``check --max-angle``) or a file of a batch failed; 2 bad
input or any other error g1patch reports (one line on stderr naming the path given and the reason,
no partial output file); 130 interrupted (Ctrl-C, SIGINT), 143 terminated (SIGTERM), 129 hung up
(SIGHUP): one line on stderr, the output file not written and its temporary removed; 141 standard
output is a closed pipe (``g1patch check x.npz | head -1``): quietly, as a Unix tool killed by
SIGPIPE.

Outputs are written like a Unix tool's: mode ``0o666 & ~umask`` (see :mod:`g1patch.io.atomic`),
complete or not at all. Sizes are bounded by default: ``export`` to a mesh aims at about 2 M
triangles (:data:`g1patch.tessellate.TRIANGLE_BUDGET`), and an explicit ``--resolution`` above
:data:`g1patch.tessellate.MAX_TRIANGLES` triangles needs ``--force``.
"""

from __future__ import annotations

import os
import signal
import sys
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from typing import Any

from ..errors import G1PatchError
from ..memory import tune_for_large_arrays
from .commands import (
    EXIT_BROKEN_PIPE,
    EXIT_CHECK_FAILED,
    EXIT_ERROR,
    EXIT_OK,
    EXIT_SIGNAL_BASE,
    HANDLERS,
    say,
)
from .parser import build_parser

__all__ = [
    "EXIT_BROKEN_PIPE",
    "EXIT_CHECK_FAILED",
    "EXIT_ERROR",
    "EXIT_OK",
    "EXIT_SIGNAL_BASE",
    "Terminated",
    "main",
]


class Terminated(KeyboardInterrupt):
    """SIGTERM or SIGHUP, raised in the main thread like Ctrl-C's KeyboardInterrupt, so that every
    ``finally`` and atomic write cleans up on the way out."""

    def __init__(self, signum: int) -> None:
        super().__init__(signal.Signals(signum).name)
        self.signum = signum


_SIGNAL_WORDS = {
    int(getattr(signal, name)): words
    for name, words in (("SIGINT", "interrupted"), ("SIGTERM", "terminated"), ("SIGHUP", "hung up"))
    if hasattr(signal, name)
}


def _raise_terminated(signum: int, frame: object) -> None:
    raise Terminated(signum)


@contextmanager
def _signal_handlers() -> Iterator[None]:
    """SIGTERM and SIGHUP raise :class:`Terminated` while the command runs (unless ignored, as under
    ``nohup``); the previous handlers come back afterwards. SIGINT keeps Python's
    KeyboardInterrupt."""
    installed: dict[int, Any] = {}
    try:
        for name in ("SIGTERM", "SIGHUP"):
            number = getattr(signal, name, None)
            if number is None:
                continue
            try:
                previous = signal.getsignal(number)
                if previous is signal.SIG_IGN:
                    continue
                signal.signal(number, _raise_terminated)
                installed[number] = previous
            except ValueError:  # not the main thread: leave the signals alone
                break
        yield
    finally:
        for number, previous in installed.items():
            signal.signal(number, previous if previous is not None else signal.SIG_DFL)


def _os_error_text(error: OSError) -> str:
    reason = (
        error.strerror
        or (os.strerror(error.errno) if error.errno else None)
        or str(error)
        or type(error).__name__
    )
    return (
        f"{os.fsdecode(error.filename)}: {reason}"
        if isinstance(error.filename, (str, bytes, os.PathLike))
        else reason
    )


def _quiet_stdout() -> None:
    """After EPIPE on stdout: point it at /dev/null, so that the interpreter's last flush is
    silent."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        os.close(devnull)
    except (OSError, ValueError, AttributeError):
        pass


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; returns the exit code (see the module docstring)."""
    tune_for_large_arrays()
    with _signal_handlers():
        try:
            args = build_parser().parse_args(argv)
            code = HANDLERS[args.command](args)
            sys.stdout.flush()  # a closed pipe shows here, not in the interpreter's exit
            return code
        except KeyboardInterrupt as interrupt:
            signum = int(getattr(interrupt, "signum", signal.SIGINT))
            say(f"g1patch: {_SIGNAL_WORDS.get(signum, signal.Signals(signum).name)}")
            return EXIT_SIGNAL_BASE + signum
        except BrokenPipeError:
            _quiet_stdout()
            return EXIT_BROKEN_PIPE
        except G1PatchError as error:
            say(f"g1patch: error: {error}")
            return EXIT_ERROR
        except OSError as error:
            say(f"g1patch: error: {_os_error_text(error)}")
            return EXIT_ERROR
        except MemoryError as error:
            detail = f" ({error})" if str(error) else ""
            say(
                f"g1patch: error: out of memory{detail}; try a lower --resolution, --samples or "
                "--size"
            )
            return EXIT_ERROR
