"""The numba kernels' machinery: when the measures use the kernels, how a kernel is compiled, and
the form in which patches and weights enter the kernels.

Compiled kernels (``compiled=True``, the default of :func:`~g1patch.continuity.check`,
:func:`~g1patch.continuity.fairness` and :func:`~g1patch.continuity.folded_patches` from
:data:`KERNEL_PATCHES` patches on) live in :mod:`.edge_kernels`, :mod:`.corner_kernels` and
:mod:`.grid_kernels`; the NumPy code of :mod:`.edges` and :mod:`.grid` is their reference
(``compiled=False``), and tests/test_check_kernels.py holds the two to one report.

Patches enter the kernels as ``points (N, M, 3)`` and weight tables: Gregory patches their 20
points, a PatchSet its 16 control points ``4 i + j`` (any basis form). Edge samples and corner
normals are formed as the reference's matrix products form them: a sequential fused
multiply-add over the points, ``acc = fma(P_m, W_m, acc)`` for m = 0, 1, …, the order of
OpenBLAS's dgemm micro-kernel, skipping the weights that are exactly 0 (they add exactly
nothing); they equal the reference's bit for bit except on the rows OpenBLAS gives its tail
kernels.

A kernels' module names ``prange`` (``range`` until compiled), ``_fma`` and the helpers of
:data:`_KERNEL_HELPERS` it calls as its own globals; :func:`_compiled` binds them there to their
numba versions before it compiles the module's first kernel.
"""

from __future__ import annotations

import sys
from collections.abc import Callable
from functools import cache
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..basis import basis_values
from ..gregory import GregoryPatchSet, gregory_weights
from ..kernels import njit_cached, use_kernels
from ..network import Patches
from ..patches import PatchSet

#: networks of at least this many patches are measured by the kernels by default: below it the
#: NumPy reference takes seconds at most (Spot's 2,928 patches: 0.5–0.7 s), while the kernels'
#: one-time compile takes about a minute (57 s measured from an empty cache, against 0.8 s for
#: the reference's whole check of the cube), which a first ``make demo`` should not pay
KERNEL_PATCHES = 20_000


def _kernels_wanted(compiled: bool | None, count: int) -> bool:
    """Whether to use the kernels: ``compiled`` when given, else from :data:`KERNEL_PATCHES` patches
    on."""
    return use_kernels(count >= KERNEL_PATCHES) if compiled is None else compiled


def _kernel_form(patches: Patches, compiled: bool | None) -> tuple[NDArray[np.float64], str] | None:
    """The kernels' form of ``patches`` (:func:`_evaluation_form`) when the kernels are wanted
    (:func:`_kernels_wanted`) and take them, else None (the NumPy reference)."""
    return _evaluation_form(patches) if _kernels_wanted(compiled, len(patches)) else None


def _evaluation_form(patches: Patches) -> tuple[NDArray[np.float64], str] | None:
    """``(points (N, M, 3), form)``: Gregory patches' points (M = 20, form "gregory") or a
    PatchSet's control points (M = 16, its basis form); None for other patch types."""
    if isinstance(patches, GregoryPatchSet):
        return patches.points, "gregory"
    if isinstance(patches, PatchSet):
        return patches.control.reshape(len(patches), 16, 3), str(patches.form)
    return None


#: functions the kernels call, compiled (and rebound in every kernels' module that names them)
#: with the module's first kernel
_KERNEL_HELPERS = ("_pair_angle", "_hull_corners")


def _fma(a: float, b: float, c: float) -> float:
    """``a b + c`` rounded once; bound to an LLVM intrinsic by :func:`_compiled` (numba has no
    math.fma)."""
    raise NotImplementedError("_fma runs compiled only")


@cache
def _compiled(kernel: Callable[..., Any]) -> Callable[..., Any]:
    """``kernel`` compiled by numba, cached on disk, with float64 IEEE arithmetic as NumPy's (no
    fastmath) and ``parallel=True`` (its ``prange`` loop runs on every core), which
    :func:`g1patch.kernels.jit_kernel` does not offer, after its module's names are bound
    (:func:`_bind`). numba is imported here, so that ``import g1patch`` stays fast."""
    _bind(vars(sys.modules[kernel.__module__]))
    return njit_cached(kernel, error_model="numpy", parallel=True)


def _bind(namespace: dict[str, Any]) -> None:
    """Once per kernels' module (its ``namespace``): ``prange`` becomes ``numba.prange``, ``_fma``
    the fused multiply-add intrinsic and each of :data:`_KERNEL_HELPERS` the module names its
    compiled version (one per helper, shared by the modules)."""
    import numba

    if namespace.get("prange") is not range:
        return
    namespace["_fma"], namespace["prange"] = _fused(), numba.prange
    for name in _KERNEL_HELPERS:
        if name in namespace:
            namespace[name] = _helper(namespace[name])


@cache
def _fused() -> Any:
    """The kernels' ``_fma``: an LLVM intrinsic (numba has no math.fma)."""
    import numba
    from numba.extending import intrinsic

    @intrinsic
    def fused(typingctx: Any, a: Any, b: Any, c: Any) -> Any:
        signature = numba.types.float64(
            numba.types.float64, numba.types.float64, numba.types.float64
        )
        return signature, lambda context, builder, sig, args: builder.fma(*args)

    return fused


@cache
def _helper(function: Callable[..., Any]) -> Callable[..., Any]:
    """A function the kernels call, compiled (without a parallel loop) and cached on disk."""
    return njit_cached(function, error_model="numpy")


@cache
def _serial(kernel: Callable[..., Any]) -> Callable[..., Any]:
    """A kernel without a parallel loop, compiled once per process
    (:func:`g1patch.kernels.jit_kernel`)."""
    from ..kernels import jit_kernel

    return jit_kernel(kernel)


def _chunks(count: int) -> int:
    """Chunks of a kernel's parallel loop: a few per core (the cores share the machine)."""
    import numba

    return max(1, min(count, 4 * numba.get_num_threads()))


def _weights(form: str, uv: NDArray[np.float64], du: int, dv: int) -> NDArray[np.float64]:
    """Weights ``(..., M)`` of the points in ``∂^(du+dv) p`` at ``uv (..., 2)``, formed as the
    reference forms them (:func:`gregory_weights`, or the tensor of ``PatchSet.evaluate``)."""
    if form == "gregory":
        return gregory_weights(uv[..., 0], uv[..., 1], du, dv)
    weights_u = basis_values(form, uv[..., 0], du)  # type: ignore[arg-type]
    weights_v = basis_values(form, uv[..., 1], dv)  # type: ignore[arg-type]
    return (weights_u[..., :, None] * weights_v[..., None, :]).reshape(*uv.shape[:-1], 16)


def _sparse(
    weights: NDArray[np.float64],
) -> tuple[NDArray[np.float64], NDArray[np.int64], NDArray[np.int64]]:
    """``weights (..., K, M)`` as ``(W (..., M, K), index (..., M), count (...))``: the points with
    a nonzero weight at some sample are ``index[..., :count]``, ascending."""
    nonzero = (weights != 0.0).any(axis=-2)
    index = np.argsort(~nonzero, axis=-1, kind="stable").astype(np.int64)
    return (
        np.ascontiguousarray(np.swapaxes(weights, -1, -2)),
        index,
        nonzero.sum(axis=-1).astype(np.int64),
    )


def _pair_angle(a: NDArray[np.float64], b: NDArray[np.float64], oriented: bool) -> float:
    """``atan2(|a × b|, a · b)`` in degrees (``|a · b|`` unless ``oriented``)."""
    c0, c1, c2 = a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]
    dot = (a[0] * b[0] + a[2] * b[2]) + a[1] * b[1]
    return float(
        np.degrees(
            np.arctan2(np.sqrt((c0 * c0 + c1 * c1) + c2 * c2), dot if oriented else abs(dot))
        )
    )
