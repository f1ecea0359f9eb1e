"""Compiled kernels: how they are compiled, and how a large one runs on every core.

``jit_kernel`` compiles the numba kernels of the readers, the topology, the targets and the
assembly (plain functions with loops, each kept beside the NumPy code it replaces, which stays as
the reference). A layer-neutral module: the mesh, the subdivision and the targets all use it.

``in_chunks`` runs a kernel over ``[0, count)`` in contiguous ranges on one thread per core: the
kernels are compiled with ``nogil``, so the ranges run at the same time. Each core takes
:data:`RANGES_PER_WORKER` ranges in turn, so a core shared with another process takes fewer of
them instead of holding up the whole call. A kernel run this way writes each item's results in its
own place (no two items share an output), so the result is bit for bit that of one call over the
whole range, in any order.
"""

from __future__ import annotations

import logging
import os
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from functools import cache
from itertools import pairwise
from typing import Any, TypeVar

__all__ = [
    "CHUNK_ITEMS",
    "RANGES_PER_WORKER",
    "in_chunks",
    "jit_kernel",
    "kernels_cached",
    "njit_cached",
    "use_kernels",
    "workers",
]

T = TypeVar("T")

#: fewest items per range: below this a kernel runs in one call (threads cost ~50 µs to start,
#: and small builds should not pay them)
CHUNK_ITEMS = 50_000
#: ranges per core a call is cut into at most (with one range per core, a call waits for the
#: core another process is using: 2× slower on a loaded 2-core machine)
RANGES_PER_WORKER = 8

_pool: ThreadPoolExecutor | None = None


@cache
def jit_kernel(kernel: Callable[..., object]) -> Callable[..., Any]:
    """``kernel`` compiled by numba on first use: ``njit(cache=True, nogil=True)`` (cached on disk;
    without the GIL so that :func:`in_chunks` can run ranges side by side), float64 IEEE arithmetic
    as NumPy's (no fastmath, NumPy's division semantics). numba is imported here, so that
    ``import g1patch`` stays fast."""
    return njit_cached(kernel, nogil=True, error_model="numpy")


def njit_cached(function: Callable[..., object], **options: Any) -> Callable[..., Any]:
    """``numba.njit(cache=True, **options)(function)``; where numba finds no writable cache
    directory for it, the same compiled in memory only (``cache=False``, after the one warning of
    :func:`kernels_cached`): what a kernel without a NumPy twin runs on a read-only install."""
    import numba

    try:
        return numba.njit(cache=True, **options)(function)
    except RuntimeError as error:  # numba: "cannot cache function ...: no locator available"
        if "cannot cache" not in str(error):
            raise
        _warn_uncached()
        return numba.njit(cache=False, **options)(function)


def _probe() -> None:
    """A function beside the kernels, whose cache directory :func:`kernels_cached` asks numba
    for."""


@cache
def kernels_cached() -> bool:
    """Whether numba can cache the compiled kernels on disk: one of its cache directories (a
    ``__pycache__`` beside the module, ``NUMBA_CACHE_DIR``, the user's cache) is writable. Where
    none is (a system install, a read-only container), a kernel would be compiled anew by every
    command, tens of seconds each: the callers choosing between a kernel and its NumPy twin
    (:func:`use_kernels`) take NumPy, and a warning says so, once per process."""
    from numba.core.caching import FunctionCache

    try:
        FunctionCache(_probe)
    except RuntimeError:
        _warn_uncached()
        return False
    return True


def use_kernels(wanted: bool) -> bool:
    """``wanted`` (a caller would run a compiled kernel, with a NumPy twin), unless the kernels
    cannot be cached on disk (:func:`kernels_cached`): then the NumPy reference."""
    return bool(wanted) and kernels_cached()


@cache
def _warn_uncached() -> None:
    """The one warning of a process whose kernels cannot be cached on disk."""
    logging.getLogger("g1patch.kernels").warning(
        "g1patch: warning: numba has no writable cache directory (the package's __pycache__, "
        "NUMBA_CACHE_DIR or ~/.cache): using the NumPy code instead of compiled kernels; set "
        "NUMBA_CACHE_DIR to a writable folder for speed"
    )


def workers() -> int:
    """Cores this process may run on."""
    return max(
        1, len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1
    )


def _forget_pool() -> None:
    """A forked child has none of its parent's threads: it starts its own pool when it needs one."""
    global _pool
    _pool = None


if hasattr(os, "register_at_fork"):
    os.register_at_fork(after_in_child=_forget_pool)


def in_chunks(call: Callable[[int, int], T], count: int, least: int | None = None) -> list[T]:
    """``[call(lo, hi) for each range]`` over ``[0, count)`` cut into contiguous ranges of at least
    ``least`` items (default :data:`CHUNK_ITEMS`), at most :data:`RANGES_PER_WORKER` per core, run
    on one thread per core; one call on one core or for fewer than two ranges' worth. Results in
    range order."""
    global _pool
    cores = workers()
    parts = max(
        1, min(RANGES_PER_WORKER * cores, count // max(CHUNK_ITEMS if least is None else least, 1))
    )
    if cores == 1 or parts == 1:
        return [call(0, count)]
    bounds = [count * i // parts for i in range(parts + 1)]
    if _pool is None:
        _pool = ThreadPoolExecutor(max_workers=workers(), thread_name_prefix="g1patch-kernel")
    futures = [_pool.submit(call, lo, hi) for lo, hi in pairwise(bounds)]
    return [future.result() for future in futures]
