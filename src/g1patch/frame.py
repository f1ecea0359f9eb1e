"""Frame: the centred, unit-scaled coordinates patch sets are built and stored in.

A frame is the similarity ``x_world = c + s · x_local`` with centre ``c`` and scale ``s > 0``.
:meth:`Frame.of_points` takes the centre and the diagonal of the bounding box, so a model's
local coordinates lie in ``[-½, ½]³`` wherever the model sits: a construction in local
coordinates has the same rounding for a mesh at the origin and for the same mesh moved by 10⁶,
and the G1 identities between neighbouring patches hold to the rounding of unit-sized numbers.

Positions map with ``c + s x``; derivatives of any order by the surface parameters, tangents,
twists and other differences of points (vectors) with ``s d``; unit normals are unchanged
(``s > 0``: the orientation is kept).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .errors import InputError, as_float_array

__all__ = ["Frame", "check_frame"]

#: rows of 3 per chunk of :meth:`Frame.to_world`: the multiply and the add of a chunk run in the
#: L2 cache, so a large array is read and written once
_CHUNK_ROWS = 8192


@dataclass(frozen=True, eq=False)
class Frame:
    """``x_world = centre + scale · x_local`` (centre (3,), scale > 0, both finite)."""

    centre: NDArray[np.float64]
    scale: float

    def __post_init__(self) -> None:
        centre = np.array(as_float_array("frame centre", self.centre, (3,)), copy=True)
        if centre.shape != (3,):
            raise InputError(f"frame centre: expected shape (3,), got {centre.shape}")
        centre.setflags(write=False)
        scale = self.scale
        if isinstance(scale, (bool, np.bool_)) or not isinstance(
            scale, (int, float, np.integer, np.floating)
        ):
            raise InputError(f"frame scale: expected a positive finite number, got {scale!r}")
        if not (np.isfinite(scale) and scale > 0):
            raise InputError(
                f"frame scale: expected a positive finite number, got {float(scale)!r}"
            )
        object.__setattr__(self, "centre", centre)
        object.__setattr__(self, "scale", float(scale))

    @classmethod
    def identity(cls) -> Frame:
        """``c = 0``, ``s = 1``: local coordinates are world coordinates."""
        return cls(np.zeros(3), 1.0)

    @classmethod
    def of_points(cls, points: ArrayLike) -> Frame:
        """Centre and diagonal of the bounding box of ``points`` (..., 3).

        ``c = (min + max) / 2``, ``s = |max − min|``; ``s = 1`` when the box is a point, and the
        identity for no points at all.
        """
        flat = as_float_array("points", points, (3,)).reshape(-1, 3)
        if not len(flat):
            return cls.identity()
        low, high = flat.min(axis=0), flat.max(axis=0)
        diagonal = float(np.linalg.norm(high - low))
        return cls(0.5 * (low + high), diagonal if diagonal > 0 else 1.0)

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Frame):
            return NotImplemented
        return self.scale == other.scale and bool(np.array_equal(self.centre, other.centre))

    def __hash__(self) -> int:
        return hash((tuple(self.centre.tolist()), self.scale))

    # ------------------------------------------------------------------ maps
    def to_local(self, x: ArrayLike) -> NDArray[np.float64]:
        """Positions ``(x − c) / s``, shape (..., 3)."""
        points = as_float_array("x", x, (3,))
        return (points - self.centre) / self.scale

    def vectors_to_local(self, d: ArrayLike) -> NDArray[np.float64]:
        """Vectors (derivatives, differences of points) ``d / s``, shape (..., 3)."""
        return as_float_array("d", d, (3,)) / self.scale

    def to_world(self, x: ArrayLike, out: NDArray[np.float64] | None = None) -> NDArray[np.float64]:
        """Positions ``c + s x``, shape (..., 3); written into ``out`` when given (``out=x`` maps in
        place)."""
        points = as_float_array("x", x, (3,), finite=False)
        target = _check_out(out, points.shape)
        if not (points.flags.c_contiguous and target.flags.c_contiguous):
            np.multiply(points, self.scale, out=target)
            return np.add(target, self.centre, out=target)
        # flat chunks against a tiled centre: a broadcast (3,) operand makes the add ~7x slower
        source, flat = points.reshape(-1), target.reshape(-1)
        step = 3 * _CHUNK_ROWS
        tiled = np.tile(self.centre, min(_CHUNK_ROWS, len(flat) // 3))
        for start in range(0, len(flat), step):
            chunk = flat[start : start + step]
            np.multiply(source[start : start + step], self.scale, out=chunk)
            np.add(chunk, tiled[: len(chunk)], out=chunk)
        return target

    def vectors_to_world(
        self, d: ArrayLike, out: NDArray[np.float64] | None = None
    ) -> NDArray[np.float64]:
        """Vectors ``s d`` (a derivative of any order by u, v), shape (..., 3); into ``out`` when
        given."""
        vectors = as_float_array("d", d, (3,), finite=False)
        return np.multiply(vectors, self.scale, out=_check_out(out, vectors.shape))

    def derivative_to_world(
        self, values: NDArray[np.float64], order: int, out: NDArray[np.float64] | None = None
    ) -> NDArray[np.float64]:
        """A surface's ``∂^order p`` by its parameters: positions (order 0) ``c + s x``, else ``s
        x``."""
        return self.to_world(values, out) if order == 0 else self.vectors_to_world(values, out)

    # ------------------------------------------------------------------ files
    def to_arrays(self) -> dict[str, NDArray[np.float64]]:
        """``{"frame_centre": (3,), "frame_scale": ()}``, as a network file stores them."""
        return {"frame_centre": np.array(self.centre), "frame_scale": np.array(self.scale)}

    @classmethod
    def from_arrays(cls, arrays: Mapping[str, ArrayLike]) -> Frame | None:
        """Inverse of :meth:`to_arrays`; None when ``arrays`` holds neither of the two."""
        present = [name for name in ("frame_centre", "frame_scale") if name in arrays]
        if not present:
            return None
        if len(present) == 1:
            raise InputError(
                "arrays: a frame needs both 'frame_centre' and 'frame_scale', got only "
                f"{present[0]!r}"
            )
        scale = np.asarray(arrays["frame_scale"])
        if scale.shape != () or not np.issubdtype(scale.dtype, np.number):
            raise InputError(
                f"frame scale: expected one number, got an array of {scale.dtype} {scale.shape}"
            )
        return cls(np.asarray(arrays["frame_centre"]), scale.item())


def in_world(frame: Frame | None, values: NDArray[np.float64], order: int) -> NDArray[np.float64]:
    """Local values of an ``order``-th derivative (0: points) mapped to world in place
    (:meth:`Frame.derivative_to_world`); ``values`` itself without a frame."""
    return values if frame is None else frame.derivative_to_world(values, order, out=values)


def check_frame(frame: object) -> Frame | None:
    """``frame`` if it is a :class:`Frame` or None, else :class:`InputError`."""
    if frame is not None and not isinstance(frame, Frame):
        raise InputError(
            f"frame: expected a g1patch.frame.Frame or None, got {type(frame).__name__}"
        )
    return frame


def _check_out(out: NDArray[np.float64] | None, shape: tuple[int, ...]) -> NDArray[np.float64]:
    if out is None:
        return np.empty(shape)
    if out.shape != shape or out.dtype != np.float64:
        raise InputError(
            f"out: expected a float64 array of shape {shape}, got {out.dtype} {out.shape}"
        )
    return out
