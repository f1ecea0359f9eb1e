"""One error hierarchy for g1patch, and the argument checks every public function shares.

Every message names the offending argument, file, line, vertex, edge or value, and what was
expected. The CLI maps any :class:`G1PatchError` to exit code 2 and one line on stderr.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from contextlib import contextmanager

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = [
    "G1PatchError",
    "InputError",
    "MeshError",
    "NonManifoldError",
    "DegenerateFaceError",
    "ValenceError",
    "OrientationError",
    "FormatError",
    "ConstructionError",
    "BudgetError",
    "MissingDependencyError",
    "all_finite",
    "as_float_array",
    "as_index_array",
    "check_choice",
    "named_errors",
]


class G1PatchError(Exception):
    """Base class of every error g1patch raises on purpose."""


class InputError(G1PatchError, ValueError):
    """An argument has the wrong shape, type or value."""


class MeshError(G1PatchError, ValueError):
    """A mesh is not a valid manifold quad mesh."""


class NonManifoldError(MeshError):
    """An edge has more than two faces, or a vertex's faces form more than one fan."""


class DegenerateFaceError(MeshError):
    """A face repeats a vertex or has zero area."""


class ValenceError(MeshError):
    """A vertex has a valence the construction cannot handle."""


class OrientationError(MeshError):
    """Two faces sharing an edge traverse it in the same direction."""


class FormatError(G1PatchError, ValueError):
    """A file cannot be read: names the file, the line, and what was expected."""

    def __init__(self, path: object, message: str, line: int | None = None) -> None:
        where = f"{path}" if line is None else f"{path}:{line}"
        super().__init__(f"{where}: {message}")
        self.path = path
        self.line = line


class ConstructionError(G1PatchError):
    """A surface construction cannot be carried out on this input."""


class BudgetError(InputError):
    """A run would need more memory (or make more items) than its budget allows; the message
    gives the estimate, the budget and what to change."""


class MissingDependencyError(G1PatchError, ImportError):
    """An optional dependency is missing; the message names the extra to install."""

    def __init__(self, package: str, extra: str, feature: str) -> None:
        super().__init__(
            f"{feature} needs the package '{package}': install it with "
            f"pip install 'g1patch[{extra}]'"
        )


@contextmanager
def named_errors(
    source: str | None, kinds: tuple[type[G1PatchError], ...] = (MeshError, InputError)
) -> Iterator[None]:
    """Prefix errors of ``kinds`` raised in the block with the source file name, keeping their
    class (and never twice)."""
    try:
        yield
    except kinds as error:
        if source is None or str(error).startswith(f"{source}: "):
            raise
        raise type(error)(f"{source}: {error}") from None


def _shape_text(shape: Sequence[int | None]) -> str:
    return "(" + ", ".join("N" if s is None else str(s) for s in shape) + ")"


def all_finite(array: NDArray[np.float64]) -> bool:
    """Whether every entry of ``array`` is finite. One pass without a temporary: the sum is finite
    unless an entry is NaN or ±inf, or finite entries overflow it, which ``isfinite`` then tells
    apart (3.7× faster on the 200 MB of a 1 M-quad split4 network's control)."""
    with np.errstate(over="ignore", invalid="ignore"):
        total = array.sum()
    return bool(np.isfinite(total)) or bool(np.isfinite(array).all())


def as_float_array(
    name: str,
    value: ArrayLike,
    trailing: Sequence[int | None] = (),
    *,
    min_ndim: int | None = None,
    finite: bool = True,
) -> NDArray[np.float64]:
    """Convert ``value`` to a C-contiguous float64 array whose last axes are ``trailing``.

    ``None`` in ``trailing`` accepts any length on that axis. Leading axes are the batch
    axes; at least ``min_ndim`` axes in all (default: ``len(trailing)``). Raises
    :class:`InputError` naming ``name`` on a wrong shape, a non-numeric value or (when
    ``finite``) a NaN/inf entry.
    """
    try:
        array = np.asarray(value, dtype=np.float64, order="C")
    except (TypeError, ValueError) as exc:
        raise InputError(
            f"{name}: expected an array of numbers, got {type(value).__name__} ({exc})"
        ) from None
    need = len(trailing) if min_ndim is None else min_ndim
    shape_ok = array.ndim >= need and all(
        want is None or got == want
        for got, want in zip(array.shape[array.ndim - len(trailing) :], trailing, strict=False)
    )
    if not shape_ok:
        expected = "(..., " + _shape_text(trailing)[1:] if trailing else f"at least {need} axes"
        raise InputError(f"{name}: expected shape {expected}, got {array.shape}")
    if finite and array.size and not all_finite(array):
        bad = np.argwhere(~np.isfinite(array))[0]
        raise InputError(
            f"{name}: non-finite value {array[tuple(bad)]} at index {tuple(int(i) for i in bad)}"
        )
    return array


def as_batch_array(name: str, value: ArrayLike, trailing: Sequence[int]) -> NDArray[np.float64]:
    """:func:`as_float_array` with exactly one batch axis: shape ``(N, *trailing)``."""
    array = as_float_array(name, value, trailing)
    if array.ndim != len(trailing) + 1:
        raise InputError(
            f"{name}: expected shape (N, {_shape_text(trailing)[1:]}, got {array.shape}"
        )
    return array


def as_index_array(
    name: str, value: ArrayLike, trailing: Sequence[int | None] = ()
) -> NDArray[np.int64]:
    """Convert ``value`` to a C-contiguous int64 array with last axes ``trailing``."""
    array = np.asarray(value)
    if array.size and not np.issubdtype(array.dtype, np.integer):
        if (
            not np.issubdtype(array.dtype, np.floating)
            or not np.all(np.isfinite(array))
            or np.any(array != np.round(array))
        ):
            raise InputError(f"{name}: expected integer indices, got dtype {array.dtype}")
    array = np.asarray(array, dtype=np.int64, order="C")
    shape_ok = array.ndim >= len(trailing) and all(
        want is None or got == want
        for got, want in zip(array.shape[array.ndim - len(trailing) :], trailing, strict=False)
    )
    if not shape_ok:
        raise InputError(
            f"{name}: expected shape (..., {_shape_text(trailing)[1:]}, got {array.shape}"
        )
    return array


def check_choice(name: str, value: str, choices: Sequence[str]) -> str:
    """Return ``value`` if it is one of ``choices``, else raise :class:`InputError` listing them."""
    if not isinstance(value, str) or value not in choices:
        raise InputError(
            f"{name}: unknown value {value!r}; expected one of {', '.join(map(repr, choices))}"
        )
    return value
