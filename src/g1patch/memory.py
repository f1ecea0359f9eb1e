"""Process-wide memory settings for runs over large arrays: what the command line sets up (DESIGN
§6).

A build or a check of millions of patches allocates and frees many arrays of hundreds of
megabytes. With glibc's defaults each one is a fresh ``mmap`` that the kernel faults in page by
page on first write and unmaps again on ``free``, so the next array pays the faults again; on a
VM that first touch runs at 0.2–2 GB/s, far below the copy bandwidth, and it was the largest
single cost of the split4 build (DESIGN §6). So the command line sets one thing:

* :func:`keep_freed_memory`: glibc's malloc serves every block from its heap
  (``mallopt(M_MMAP_MAX, 0)``) and keeps freed blocks there for the next allocation
  (``mallopt(M_TRIM_THRESHOLD, −1)``: never trimmed), so a later array reuses pages that are
  already mapped. The process keeps its peak footprint until it exits.

and leaves NumPy's own setting alone: it asks for transparent huge pages for its large arrays
(``madvise(MADV_HUGEPAGE)``), so the heap's first growth is faulted in 2 MiB at a time. On the
development VM that first touch ran 5–10× faster than in 4 KiB pages (6 GiB: 1.6–3.2 s against
15.5–17.3 s), and where memory was full of page cache, so that faults had to compact, about as fast
(4.0 s against 3.5 s). :func:`without_huge_page_advice` turns the advice off for a host whose
compaction stalls for longer.

This changes the host process, so the library never applies it on its own: the command line
calls :func:`tune_for_large_arrays` at start-up, the benchmarks call it to measure what the
command line does, and a program that embeds g1patch may call it too.
"""

from __future__ import annotations

import ctypes
import os
from collections.abc import Callable

__all__ = [
    "TUNED_ENVIRONMENT",
    "memory_budget",
    "keep_freed_memory",
    "tune_for_large_arrays",
    "without_huge_page_advice",
]

#: glibc's ``mallopt`` parameters (malloc.h)
_M_TRIM_THRESHOLD = -1
_M_MMAP_THRESHOLD = -3
_M_MMAP_MAX = -4
# : glibc's defaults for them (mallopt(3)): 128 KiB, 128 KiB (raised dynamically up to 32 MiB),
# 65,536 maps
_DEFAULTS = {_M_TRIM_THRESHOLD: 128 * 1024, _M_MMAP_THRESHOLD: 128 * 1024, _M_MMAP_MAX: 65_536}
# : the trim threshold that disables trimming (mallopt(3)); as an environment variable, any value
# above every heap
_NEVER_TRIM = -1
_NEVER_TRIM_ENVIRONMENT = str(2**62)


def without_huge_page_advice() -> None:
    """Stop NumPy asking the kernel for huge pages for its large arrays
    (``madvise(MADV_HUGEPAGE)``).

    Where the kernel's ``transparent_hugepage/defrag`` is ``madvise`` (a common default) each such
    request may compact memory first. On a host where that stalls (measured once on the
    development VM under load: first writes at ~80 MB/s instead of ~1.7 GB/s, 48 MB in 0.6 s
    against 0.03 s) a program may call this; the command line does not (module docstring)."""
    import importlib

    try:
        multiarray = importlib.import_module("numpy._core.multiarray")  # NumPy ≥ 2
    except ImportError:  # pragma: no cover - NumPy 1.26
        multiarray = importlib.import_module("numpy.core.multiarray")
    multiarray._set_madvise_hugepage(False)


def _glibc() -> bool:
    """Whether this process runs on glibc (``confstr(_CS_GNU_LIBC_VERSION)``: musl, macOS and
    Windows have none)."""
    try:
        return (os.confstr("CS_GNU_LIBC_VERSION") or "").startswith("glibc ")
    except (AttributeError, ValueError, OSError):
        return False


def _mallopt() -> Callable[..., int] | None:
    """glibc's ``mallopt``, or None on another C library."""
    if not _glibc():
        return None
    try:
        function = ctypes.CDLL(None).mallopt
    except (OSError, AttributeError):  # pragma: no cover - a static or unusual libc
        return None
    function.argtypes, function.restype = (ctypes.c_int, ctypes.c_int), ctypes.c_int
    return function


def keep_freed_memory(keep: bool = True) -> bool:
    """Let glibc's malloc keep freed memory for reuse (module docstring), or with ``keep=False``
    restore its defaults (blocks from 128 KiB on mapped and unmapped one by one). Returns whether
    the settings took effect: False where the C library is not glibc, which has its own policy."""
    mallopt = _mallopt()
    if mallopt is None:
        return False
    settings = {_M_MMAP_MAX: 0, _M_TRIM_THRESHOLD: _NEVER_TRIM} if keep else _DEFAULTS
    return all(mallopt(parameter, value) == 1 for parameter, value in settings.items())


def tune_for_large_arrays() -> None:
    """The process settings the command line runs with (module docstring):
    :func:`keep_freed_memory`, with NumPy's huge-page advice left as NumPy sets it."""
    keep_freed_memory()


#: the same settings as environment variables, for a child process (glibc reads them at start-up)
TUNED_ENVIRONMENT = {"MALLOC_MMAP_MAX_": "0", "MALLOC_TRIM_THRESHOLD_": _NEVER_TRIM_ENVIRONMENT}


def memory_budget() -> int:
    """The default memory budget of a build or a check: half of this machine's RAM (bytes)."""
    try:
        return os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES") // 2
    except (ValueError, OSError, AttributeError):  # no sysconf: a budget that refuses nothing
        return 2**62
