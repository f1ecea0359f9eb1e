"""Process-wide memory settings for runs over large arrays: what the command line sets up (DESIGN §6).

A build or a check of millions of patches allocates and frees many arrays of hundreds of
megabytes. With glibc's defaults each one is a fresh ``mmap`` that the kernel faults in page by
page on first write and unmaps again on ``free``, so the next array pays the faults again; on a
VM that first touch runs at 0.2–2 GB/s, far below the copy bandwidth, and it was the largest
single cost of the split4 build (DESIGN §6). Two settings change that for the whole process:

* :func:`without_huge_page_advice`: NumPy stops asking for transparent huge pages
  (``madvise(MADV_HUGEPAGE)``), which compacts memory first where ``transparent_hugepage/defrag``
  is ``madvise`` (first writes ran ~20× slower);
* :func:`keep_freed_memory`: glibc's malloc serves every block from its heap
  (``mallopt(M_MMAP_MAX, 0)``) and keeps freed blocks there for the next allocation
  (``mallopt(M_TRIM_THRESHOLD, −1)``: never trimmed), so a later array reuses pages that are
  already mapped. The process keeps its peak footprint until it exits.

Both change the host process, so the library never applies them on its own: the command line
calls :func:`tune_for_large_arrays` at start-up, the benchmarks call it to measure what the
command line does, and a program that embeds g1patch may call it too.
"""

from __future__ import annotations

import ctypes
import os

__all__ = ["TUNED_ENVIRONMENT", "keep_freed_memory", "tune_for_large_arrays", "without_huge_page_advice"]

#: glibc's ``mallopt`` parameters (malloc.h)
_M_TRIM_THRESHOLD = -1
_M_MMAP_THRESHOLD = -3
_M_MMAP_MAX = -4
#: glibc's defaults for them (mallopt(3)): 128 KiB, 128 KiB (raised dynamically up to 32 MiB), 65,536 maps
_DEFAULTS = {_M_TRIM_THRESHOLD: 128 * 1024, _M_MMAP_THRESHOLD: 128 * 1024, _M_MMAP_MAX: 65_536}
#: the trim threshold that disables trimming (mallopt(3)); as an environment variable, any value above every heap
_NEVER_TRIM = -1
_NEVER_TRIM_ENVIRONMENT = str(2**62)


def without_huge_page_advice() -> None:
    """Stop NumPy asking the kernel for huge pages for its large arrays (``madvise(MADV_HUGEPAGE)``).

    Where the kernel's ``transparent_hugepage/defrag`` is ``madvise`` (a common default) each such
    request may compact memory first: first writes to fresh arrays then ran at ~80 MB/s instead
    of ~1.7 GB/s (48 MB: 0.6 s against 0.03 s), and a 100,000-gon's build took 11.9 s instead
    of 8.6 s. A build's arrays live briefly, so the TLB gain of huge pages never pays for that."""
    try:
        from numpy._core.multiarray import _set_madvise_hugepage  # NumPy ≥ 2
    except ImportError:  # pragma: no cover - NumPy 1.26
        from numpy.core.multiarray import _set_madvise_hugepage
    _set_madvise_hugepage(False)


def _glibc() -> bool:
    """Whether this process runs on glibc (``confstr(_CS_GNU_LIBC_VERSION)``: musl, macOS and Windows have none)."""
    try:
        return os.confstr("CS_GNU_LIBC_VERSION").startswith("glibc ")
    except (AttributeError, ValueError, OSError):
        return False


def _mallopt() -> ctypes._CFuncPtr | None:
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
    """Both settings of this module, as the command line runs: :func:`without_huge_page_advice`
    and :func:`keep_freed_memory`."""
    without_huge_page_advice()
    keep_freed_memory()


#: the same settings as environment variables, for a child process (NumPy and glibc read them at start-up)
TUNED_ENVIRONMENT = {"NUMPY_MADVISE_HUGEPAGE": "0", "MALLOC_MMAP_MAX_": "0", "MALLOC_TRIM_THRESHOLD_": _NEVER_TRIM_ENVIRONMENT}
