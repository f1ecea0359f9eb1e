"""The histogram of the normal turns between neighbouring grid samples (the fairness figures'
median and p99), in bounded memory: its bins, and the turn of a squared chord."""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

# Histogram of the turns, in bounded memory: the squared chord ``s = |n̂_a − n̂_b|² = 4 sin²(θ/2)``
# (monotone in θ) as float32, whose bit pattern read as an integer is monotone too; its top
# 8 exponent + 8 mantissa bits make 256 bins per octave of s (bins 0.27 % wide in s, 0.14 % in θ
# for small θ), from θ = 1e-12° to 180°, and a bin 0 for smaller turns.
_SHIFT = 23 - 8
_MIN_TURN_DEG = 1e-12


def _chord_codes(chord2: NDArray[np.floating[Any]]) -> NDArray[np.int32]:
    return np.asarray(chord2, dtype=np.float32).view(np.int32) >> _SHIFT


_CODE_MIN = int(_chord_codes(np.array([4.0 * np.sin(np.radians(_MIN_TURN_DEG) / 2.0) ** 2]))[0])
_CODE_MAX = int(_chord_codes(np.array([4.0]))[0])
_BINS = _CODE_MAX - _CODE_MIN + 2
#: bin b holds squared chords in [_EDGES[b], _EDGES[b + 1])
_EDGES = np.r_[
    0.0, (np.arange(_CODE_MIN, _CODE_MAX + 2, dtype=np.int32) << _SHIFT).view(np.float32)
].astype(np.float64)


def _turn_deg(chord2: float) -> float:
    """The angle θ of unit vectors a chord ``√chord2 = |a − b| = 2 sin(θ/2)`` apart, in degrees."""
    return float(np.degrees(2.0 * np.arcsin(min(1.0, np.sqrt(chord2) / 2.0))))
