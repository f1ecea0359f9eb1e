"""What the environment may add to a command's stderr, apart from what a test asserts: the one
warning of a process whose numba kernels cannot be cached (a read-only install; the suite is run
that way too, issue 32)."""

from __future__ import annotations

#: the start of :func:`g1patch.kernels._warn_uncached`'s line
KERNEL_WARNING = "g1patch: warning: numba has no writable cache directory"


def own_lines(stderr: str) -> list[str]:
    """``stderr``'s lines without the environment's warning."""
    return [line for line in stderr.splitlines() if not line.startswith(KERNEL_WARNING)]
