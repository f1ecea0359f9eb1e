"""From how many faces split4 runs its numba kernels (:data:`KERNEL_FACES`).

Read when called (:func:`use_kernels`), so setting ``threshold.KERNEL_FACES`` switches the stars,
the assembly and the network's connectivity at once (tests, ``benchmarks/bench_split4.py
--numpy``).
"""

from __future__ import annotations

from ...kernels import use_kernels as cached_kernels

__all__ = ["KERNEL_FACES", "use_kernels"]

#: faces from which split4 runs its numba kernels (below, loading them costs more than they save)
KERNEL_FACES = 20_000


def use_kernels(n_faces: int, compiled: bool | None) -> bool:
    """``compiled`` where given, else whether ``n_faces`` reaches :data:`KERNEL_FACES` (and the
    kernels can be cached: :func:`g1patch.kernels.use_kernels`)."""
    return cached_kernels(n_faces >= KERNEL_FACES) if compiled is None else compiled
