"""The compiled readers: numba kernels that convert numbers and scan OBJ text.

From :data:`KERNEL_BYTES` on, OBJ text is read by one numba kernel that scans the bytes once:
``v`` lines' first three numbers are converted as they are met (Eisel–Lemire: correctly rounded,
as float(); a number it cannot settle, or spelt otherwise, is left to float()), ``f`` lines'
indices (the part before a '/') resolved, ``vt`` / ``vn`` / ``vp`` skipped, and every other
statement handed back as a span for Python to read (tags, skipped statements, unknown keywords).
The coordinates of OFF and ASCII PLY (``_numbers``) are converted by the same code. As the NumPy
fast paths, they never raise: on anything else they decline and the line-by-line parser reads the
file.
"""

from __future__ import annotations

from collections.abc import Callable
from functools import cache

import numpy as np
from numpy.typing import NDArray

#: OBJ files, and OFF / ASCII PLY coordinates, of at least this many bytes are read by the kernels
#: (their first use, on a fresh install, compiles them: see benchmarks/bench_readers.py)
KERNEL_BYTES = 2 << 20
#: helpers the kernels call, compiled (and rebound) with the first kernel
_KERNEL_HELPERS = ("_product", "_decimal", "_number")
#: the sign bit of a float64, as int64
_SIGN_BIT = -(2**63)


@cache
def _powers_of_five() -> NDArray[np.uint64]:
    """``5^q`` for q in -342..308 as 128-bit significands (high, low word), the top bit set:
    truncated for q ≥ 0, rounded up for q < 0 (the table of Lemire's fast_float)."""
    words = []
    for q in range(-342, 309):
        if q >= 0:
            value = 5**q
            value <<= max(0, 128 - value.bit_length())
            value >>= max(0, value.bit_length() - 128)
        else:
            power = 5**-q
            z = power.bit_length()
            value = (1 << (z + 127 if q >= -27 else 2 * z + 128)) // power + 1
            value >>= max(0, value.bit_length() - 128)
        words += [value >> 64, value & (2**64 - 1)]
    return np.array(words, dtype=np.uint64)


def _product(a: np.uint64, b: np.uint64) -> tuple[np.uint64, np.uint64]:
    """The 128-bit product ``a b`` as (high, low) 64-bit words."""
    low32, shift = np.uint64(0xFFFFFFFF), np.uint64(32)
    a0, a1, b0, b1 = a & low32, a >> shift, b & low32, b >> shift
    p00, p01, p10, p11 = a0 * b0, a0 * b1, a1 * b0, a1 * b1
    middle = p10 + (p00 >> shift) + (p01 & low32)
    return p11 + (middle >> shift) + (p01 >> shift), (middle << shift) | (p00 & low32)


def _decimal(w: np.uint64, q: int, powers: NDArray[np.uint64]) -> int:
    """The float64 bits of ``w · 10^q`` (``0 < w < 10^19``), correctly rounded (Eisel–Lemire,
    as fast_float), or -1 where it cannot tell, the result is subnormal or infinite."""
    if q < -342 or q > 308:
        return -1
    one, ones = np.uint64(1), np.uint64(0xFFFFFFFFFFFFFFFF)
    lz = 0
    for shift in (32, 16, 8, 4, 2, 1):  # normalise: the top bit set
        if w < one << np.uint64(64 - shift):
            w <<= np.uint64(shift)
            lz += shift
    index = 2 * (q + 342)
    high, low = _product(w, powers[index])
    if high & np.uint64(0x1FF) == np.uint64(
        0x1FF
    ):  # the 55 bits needed may carry: the next 64 bits of 5^q
        high2, _ = _product(w, powers[index + 1])
        low += high2
        if high2 > low:
            high += one
    if low == ones and (q < -27 or q > 55):
        return -1
    upper = np.int64(high >> np.uint64(63))
    mantissa = high >> np.uint64(upper + 9)
    power2 = ((217706 * q) >> 16) + 63 + upper - lz + 1023
    if power2 <= 0:
        return -1
    if (
        low <= one
        and -4 <= q <= 23
        and mantissa & np.uint64(3) == one
        and (mantissa << np.uint64(upper + 9)) == high
    ):
        mantissa &= ~one  # exactly halfway: to even
    mantissa += mantissa & one
    mantissa >>= one
    if mantissa >= np.uint64(2) << np.uint64(52):
        mantissa = one << np.uint64(52)
        power2 += 1
    if power2 >= 0x7FF:
        return -1
    return np.int64(  # type: ignore[return-value]
        (mantissa & ~(one << np.uint64(52))) | (np.uint64(power2) << np.uint64(52))
    )  # int64 as every return


def _number(
    data: NDArray[np.uint8], classes: NDArray[np.uint8], first: int, powers: NDArray[np.uint64]
) -> tuple[int, int]:
    """The float64 bits (as int64) of the token at ``first`` and where it ends, read in one pass: a
    token spelt ``[+-]digits[.digits][(e|E)[+-]digits]`` (or ``.digits``) correctly rounded as
    ``float`` rounds it; -1 for any other spelling, more than 19 significant digits, or a number
    :func:`_decimal` cannot settle: ``float`` must convert it."""
    n, at, negative = data.size, first, False
    if data[at] == 43 or data[at] == 45:
        negative = data[at] == 45
        at += 1
    w, digits, fraction, seen = np.uint64(0), 0, 0, False
    while at < n and 48 <= data[at] <= 57:
        seen = True
        if w != np.uint64(0) or data[at] != 48:  # leading zeros are not significant
            w = w * np.uint64(10) + np.uint64(data[at] - 48)
            digits += 1
        at += 1
    if at < n and data[at] == 46:
        at += 1
        while at < n and 48 <= data[at] <= 57:
            seen = True
            fraction += 1
            if w != np.uint64(0) or data[at] != 48:
                w = w * np.uint64(10) + np.uint64(data[at] - 48)
                digits += 1
            at += 1
    exponent = 0
    if seen and at < n and (data[at] == 101 or data[at] == 69):
        at += 1
        sign = 1
        if at < n and (data[at] == 43 or data[at] == 45):
            sign = -1 if data[at] == 45 else 1
            at += 1
        seen = at < n and 48 <= data[at] <= 57
        while at < n and 48 <= data[at] <= 57:
            exponent = min(exponent * 10 + data[at] - 48, 100_000)
            at += 1
        exponent *= sign
    if at < n and classes[data[at]] == _TOKEN:  # more of the token: another spelling
        seen = False
        while at < n and classes[data[at]] == _TOKEN:
            at += 1
    if not seen or digits > 19:
        return -1, at
    bits = 0 if w == np.uint64(0) else _decimal(w, exponent - fraction, powers)
    return (
        -1 if bits < 0 else bits | (_SIGN_BIT if negative else 0)
    ), at  # -1: a NaN's bits, never a number's


#: byte classes of the OBJ kernel: 0 a token's, 1 space or tab, 2 LF or CR, 3 '#', 4 any other (not
#: ASCII, a control byte, or one ``str.splitlines`` breaks at): the kernel declines the file
_TOKEN, _SPACE, _BREAK, _HASH, _ODD = range(5)
_BYTE_CLASSES = np.full(256, _ODD, dtype=np.uint8)
_BYTE_CLASSES[33:128] = _TOKEN
_BYTE_CLASSES[[ord(" "), ord("\t")]] = _SPACE
_BYTE_CLASSES[[ord("\n"), ord("\r")]] = _BREAK
_BYTE_CLASSES[ord("#")] = _HASH


def _obj_kernel(
    data: NDArray[np.uint8],
    classes: NDArray[np.uint8],
    powers: NDArray[np.uint64],
    points: NDArray[np.uint64],
    corners: NDArray[np.int64],
    sizes: NDArray[np.int64],
    hard: NDArray[np.int64],
    others: NDArray[np.int64],
) -> tuple[bool, int, int, int, int, int]:
    """Scan OBJ bytes once into the arrays given; returns ``valid`` and the items found:
    coordinates, faces, corners, hard numbers, other lines (those beyond an array's length are
    counted, not written). ``points``: float64 bits, x y z per vertex (0 where hard); ``corners``
    (0-based, resolved) and ``sizes`` of the faces; ``hard``: (start, end, slot in points) of each
    number left to ``float``; ``others``: (start, end) of each line of another statement, comment
    cut. Not ``valid`` (a byte of class 4, or anything the line-by-line parser reports): that parser
    reads the file."""
    n = data.size
    n_points = n_faces = n_corners = n_hard = n_others = 0
    i, valid = 0, True
    while i < n and valid:
        while i < n and classes[data[i]] == _SPACE:
            i += 1
        start = i
        while i < n and classes[data[i]] == _TOKEN:  # the keyword
            i += 1
        keyword = i - start
        kind = 0  # 1: v, 2: f, 3: vt/vn/vp, 4: other
        if keyword == 1 and data[start] == 118:
            kind = 1
        elif keyword == 1 and data[start] == 102:
            kind = 2
        elif (
            keyword == 2
            and data[start] == 118
            and (data[start + 1] == 116 or data[start + 1] == 110 or data[start + 1] == 112)
        ):
            kind = 3
        elif keyword > 0:
            kind = 4
        tokens = 0
        while True:  # the tokens after the keyword, up to a comment or the end of the line
            while i < n and classes[data[i]] == _SPACE:
                i += 1
            if i >= n or classes[data[i]] != _TOKEN:
                break
            first = i
            tokens += 1
            if kind == 1 and tokens <= 3:
                bits, i = _number(data, classes, first, powers)
                if bits == -1:
                    if n_hard < hard.shape[0]:
                        hard[n_hard, 0], hard[n_hard, 1], hard[n_hard, 2] = (
                            first,
                            i,
                            n_points + tokens - 1,
                        )
                    n_hard += 1
                    bits = 0
                if n_points + 3 <= points.size:
                    points[n_points + tokens - 1] = np.uint64(bits)
                continue
            while i < n and classes[data[i]] == _TOKEN:
                i += 1
            if kind == 2:
                at, negative, value = first, False, 0
                if data[at] == 43 or data[at] == 45:
                    negative = data[at] == 45
                    at += 1
                end = at
                while end < i and data[end] != 47:  # the index: up to a '/'
                    end += 1
                valid = at < end <= at + 18
                while valid and at < end:
                    valid = 48 <= data[at] <= 57
                    value = value * 10 + data[at] - 48
                    at += 1
                if not valid or value == 0:
                    valid = False
                    break
                if n_corners < corners.size:
                    corners[n_corners] = n_points // 3 - value if negative else value - 1
                n_corners += 1
        if i < n and classes[data[i]] == _HASH:  # a comment
            while i < n and classes[data[i]] != _BREAK:
                valid = valid and classes[data[i]] != _ODD
                i += 1
        if i < n and classes[data[i]] == _ODD:
            valid = False
        if kind == 1:
            valid = valid and 4 <= tokens + 1 <= 8
            n_points += 3
        elif kind == 2:
            valid = valid and tokens >= 3
            if n_faces < sizes.size:
                sizes[n_faces] = tokens
            n_faces += 1
        elif kind == 4:
            if n_others < others.shape[0]:
                others[n_others, 0], others[n_others, 1] = start, i
            n_others += 1
        i += 1  # the line break (CR LF: the LF ends an empty line)
    return valid, n_points, n_faces, n_corners, n_hard, n_others


def _floats_kernel(
    data: NDArray[np.uint8],
    classes: NDArray[np.uint8],
    powers: NDArray[np.uint64],
    out: NDArray[np.uint64],
    hard: NDArray[np.int64],
) -> tuple[bool, int, int]:
    """The numbers of a text of numbers separated by spaces and line breaks, by :func:`_number`,
    into ``out`` (float64 bits; 0 where hard): returns ``valid`` (no byte but a number's, a space or
    a line break), the numbers and the hard ones found (those beyond ``out`` or ``hard`` counted,
    not written); ``hard``: (start, end, slot in out) of each number left to ``float``."""
    n, count, n_hard, i = data.size, 0, 0, 0
    while i < n:
        kind = classes[data[i]]
        if kind == _SPACE or kind == _BREAK:
            i += 1
            continue
        if kind != _TOKEN:
            return False, count, n_hard
        first = i
        bits, i = _number(data, classes, first, powers)
        if bits == -1:
            if n_hard < hard.shape[0]:
                hard[n_hard, 0], hard[n_hard, 1], hard[n_hard, 2] = first, i, count
            n_hard += 1
            bits = 0
        if count < out.size:
            out[count] = np.uint64(bits)
        count += 1
    return True, count, n_hard


@cache
def _compiled(kernel: Callable[..., tuple]) -> Callable[..., tuple]:
    """``kernel`` compiled by :func:`~g1patch.kernels.jit_kernel`, the helpers first."""
    from ...kernels import jit_kernel  # numba, imported on first use

    for name in _KERNEL_HELPERS:
        if not hasattr(globals()[name], "py_func"):
            globals()[name] = jit_kernel(globals()[name])
    return jit_kernel(kernel)


def _floats_compiled(text: bytes, count: int) -> NDArray[np.float64] | None:
    """The ``count`` numbers of ``text`` (numbers, spaces, line breaks) converted as ``float``
    converts them, by :func:`_floats_kernel`; None if it holds anything else or another count. As
    :func:`_numbers`, a token of other bytes than ``0-9 . e E + -`` is refused, not given to
    ``float``."""
    buffer, kernel, n_hard = np.frombuffer(text, dtype=np.uint8), _compiled(_floats_kernel), 1024
    out = np.empty(count, dtype=np.uint64)
    while True:
        hard = np.empty((n_hard, 3), dtype=np.int64)
        valid, found, n_hard = kernel(buffer, _BYTE_CLASSES, _powers_of_five(), out, hard)
        if not valid or found != count or n_hard <= len(hard):
            break
    if not valid or found != count:
        return None
    values = out.view(np.float64)
    for start, end, slot in hard[:n_hard].tolist():
        token = text[start:end]
        if token.translate(None, b"0123456789.eE+-"):
            return None
        try:
            values[slot] = float(token)
        except ValueError:
            return None
    return values
