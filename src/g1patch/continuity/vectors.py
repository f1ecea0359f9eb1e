"""Vector algebra on planar arrays ``(3, ...)`` (component first, each component contiguous), and
the angle between vectors.

The edge and fold measures touch tens of millions of 3-vectors, and component-wise products on
interleaved ``(..., 3)`` arrays run on stride-3 views. Each helper performs exactly the
floating-point operations, in the same order, of the interleaved NumPy formulation it replaces
(``np.cross``, ``np.linalg.norm(axis=-1)``, ``np.einsum("...d,...d->...")``), so the reported
figures do not depend on the layout.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray


def angle_between(a: NDArray[np.float64], b: NDArray[np.float64]) -> NDArray[np.float64]:
    """Angle in degrees between vectors along the last axis: ``atan2(|a × b|, a · b)``."""
    a, b = np.broadcast_arrays(np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64))
    shape = a.shape[:-1]
    return _angle3(_planar(a.reshape(-1, 3)), _planar(b.reshape(-1, 3))).reshape(shape)[()]


def _planar(values: NDArray[np.float64]) -> NDArray[np.float64]:
    """``(..., 3)`` vectors as a ``(3, ...)`` view (no copy: the helpers below read strided
    components several times faster than NumPy transposes them into contiguous ones, and they
    write contiguous planar results)."""
    return np.moveaxis(values, -1, 0)


def _cross3(a: NDArray[np.float64], b: NDArray[np.float64]) -> NDArray[np.float64]:
    """``a × b`` of planar ``(3, ...)`` arrays, planar."""
    out = np.empty(np.broadcast_shapes(a.shape, b.shape))
    scratch = np.empty(out.shape[1:])
    for i, j, k in ((0, 1, 2), (1, 2, 0), (2, 0, 1)):
        np.multiply(a[j], b[k], out=out[i])
        np.multiply(a[k], b[j], out=scratch)
        out[i] -= scratch
    return out


def _dot3(a: NDArray[np.float64], b: NDArray[np.float64]) -> NDArray[np.float64]:
    """``a · b`` of planar arrays, summed as ``(a₀b₀ + a₂b₂) + a₁b₁`` like ``np.einsum``."""
    out = a[0] * b[0]
    scratch = a[2] * b[2]
    out += scratch
    np.multiply(a[1], b[1], out=scratch)
    out += scratch
    return out


def _norm3(a: NDArray[np.float64]) -> NDArray[np.float64]:
    """``|a|`` of a planar array, summed as ``(a₀² + a₁²) + a₂²`` like ``np.linalg.norm``."""
    out = a[0] * a[0]
    scratch = a[1] * a[1]
    out += scratch
    np.multiply(a[2], a[2], out=scratch)
    out += scratch
    return np.sqrt(out, out=out)


def _angle3(a: NDArray[np.float64], b: NDArray[np.float64]) -> NDArray[np.float64]:
    """:func:`angle_between` of planar arrays."""
    angle = np.arctan2(_norm3(_cross3(a, b)), _dot3(a, b))
    return np.degrees(angle, out=angle)
