"""Vectorised text parsing, the fast path of the OBJ, OFF and ASCII PLY readers.

The text readers first try a fast path: the whole file is normalised by bytes operations
(comments cut, CR LF and tabs made LF and spaces, runs of spaces made one, no space at a line's
ends), its lines located and their tokens counted with NumPy, and each kind of line (``v``,
``f``, an OFF vertex or face) converted in bulk. It never raises: on anything it does not handle
exactly as the line-by-line parser does (non-ASCII text, a token it does not convert the same
way, any error in the file) it returns None, and the line-by-line parser reads the file again, so
every result and every message is that parser's.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from ...kernels import use_kernels
from .compiled import KERNEL_BYTES, _floats_compiled

#: bytes ``str.splitlines`` or ``str.split`` treat as line breaks or spaces; the fast path declines
#: a file with one
_ODD_BYTES = (b"\x0b", b"\x0c", b"\x1c", b"\x1d", b"\x1e", b"\x1f")
_SPACES = re.compile(rb" {2,}")
_EDGE_SPACE = re.compile(rb"(?m)^ | $")


class _Lines(NamedTuple):
    """A normalised text and its lines: line ``i`` is ``text[starts[i]:ends[i]]``, line ``i + 1`` of
    the file."""

    text: bytes
    array: NDArray[np.uint8]
    starts: NDArray[np.int64]
    ends: NDArray[np.int64]
    tokens: NDArray[np.int64]

    def byte(self, column: int) -> NDArray[np.uint8]:
        """Byte ``column`` of every line (0 where the line is shorter)."""
        if self.array.size == 0:
            return np.zeros(self.starts.size, dtype=np.uint8)
        at = np.minimum(self.starts + column, self.array.size - 1)
        return np.where(self.ends - self.starts > column, self.array[at], 0).astype(np.uint8)

    def chunk(self, rows: NDArray[np.int64]) -> bytes:
        """The text of lines ``rows`` (increasing), one per line: consecutive lines are sliced at
        once."""
        if rows.size == 0:
            return b""
        breaks = np.flatnonzero(np.diff(rows) != 1) + 1
        first, last = rows[np.r_[0, breaks]], rows[np.r_[breaks - 1, rows.size - 1]]
        text = self.text
        return b"\n".join(
            [
                text[s:e]
                for s, e in zip(self.starts[first].tolist(), self.ends[last].tolist(), strict=True)
            ]
        )


def _scan(data: bytes) -> _Lines | None:
    """``data`` normalised and split into lines, or None if it is not plain ASCII text."""
    if not data.isascii() or any(odd in data for odd in _ODD_BYTES):
        return None
    text = data
    if b"\r" in text:  # CR LF or a lone CR ends a line, as for str.splitlines
        text = text.replace(b"\r\n", b"\n").replace(b"\r", b"\n")
    if b"#" in text:
        text = _uncommented(text)
    if b"\t" in text:
        text = text.replace(b"\t", b" ")
    separators = _separators(text)
    if separators is None:
        return None
    # a run of spaces, or a space at either end of a line (two-byte searches are slow: found here)
    adjacent = np.flatnonzero(np.diff(separators) == 1)
    array = np.frombuffer(text, dtype=np.uint8)
    messy = (array[separators[adjacent]] == ord(" ")) | (
        array[separators[adjacent + 1]] == ord(" ")
    )
    if messy.any() or text.startswith(b" ") or text.endswith(b" "):
        text = _EDGE_SPACE.sub(b"", _SPACES.sub(b" ", text))
        array, normalised = np.frombuffer(text, dtype=np.uint8), _separators(text)
        assert normalised is not None  # cutting spaces adds no control byte
        separators = normalised
    newlines = np.flatnonzero(array[separators] == ord("\n"))
    ends = separators[newlines]
    if text and not text.endswith(b"\n"):
        ends, newlines = np.append(ends, len(text)), np.append(newlines, separators.size)
    starts = np.concatenate(([0], ends[:-1] + 1)).astype(np.int64)
    spaces = (
        np.diff(newlines, prepend=-1) - 1
    )  # separators between a line's end and the previous one's
    return _Lines(
        text, array, starts, ends.astype(np.int64), np.where(ends > starts, spaces + 1, 0)
    )


def _separators(text: bytes) -> NDArray[np.int64] | None:
    """Where ``text`` (no tab or CR) has a space or LF; None if it has another control byte, which
    ``str.split`` does not split at."""
    array = np.frombuffer(text, dtype=np.uint8)
    separators = np.flatnonzero(array <= ord(" "))
    kinds = array[separators]
    return None if ((kinds != ord(" ")) & (kinds != ord("\n"))).any() else separators


def _uncommented(text: bytes) -> bytes:
    """``text`` with each ``#`` and the rest of its line cut (lines end in LF)."""
    parts, at = [], 0
    while (mark := text.find(b"#", at)) >= 0:
        parts.append(text[at:mark])
        at = text.find(b"\n", mark)
        if at < 0:
            return b"".join(parts)
    parts.append(text[at:])
    return b"".join(parts)


def _gather_floats(
    text: bytes, counts: NDArray[np.int64], columns: Sequence[int]
) -> NDArray[np.float64] | None:
    """Tokens ``columns`` of each line of ``text`` (``counts`` tokens each) as floats, converted as
    ``float`` converts them; None if one is not a number."""
    tokens = np.array(text.split(), dtype=object)
    if tokens.size != counts.sum():
        return None
    offsets = np.cumsum(counts) - counts
    try:
        return tokens[offsets[:, None] + np.asarray(columns)].astype(np.float64)
    except (ValueError, OverflowError, TypeError):
        return None


#: the bytes a line of numbers may hold besides its keyword, and those that may follow a sign
_NUMBER_BYTES = {
    np.int64: (b"0123456789+- \n", b"0123456789"),
    np.float64: (b"0123456789.eE+- \n", b"0123456789."),
}


def _numbers(
    text: bytes, keyword: bytes, count: int, dtype: type[np.int64] | type[np.float64]
) -> NDArray | None:
    """The ``count`` numbers of ``text`` (lines of ``keyword`` then numbers), each token converted
    as ``int`` or ``float`` converts it, by one ``np.fromstring`` (floats from :data:`KERNEL_BYTES`
    on, without a keyword: :func:`_floats_compiled`); None where ``text`` holds anything else, or a
    token that ``np.fromstring`` might read otherwise."""
    if dtype is np.float64 and not keyword and use_kernels(len(text) >= KERNEL_BYTES):
        return _floats_compiled(text, count)
    allowed, after_sign = _NUMBER_BYTES[dtype]
    if text.translate(None, allowed).replace(keyword, b"") != b"":
        return None
    if (
        b"-" in text or b"+" in text
    ):  # numpy reads a lone sign at the end as 0; int and float refuse it
        array = np.frombuffer(text, dtype=np.uint8)
        signs = np.flatnonzero((array == ord("-")) | (array == ord("+")))
        if (
            signs[-1] + 1 == array.size
            or not np.isin(array[signs + 1], np.frombuffer(after_sign, dtype=np.uint8)).all()
        ):
            return None
    try:
        values = np.fromstring(
            text.replace(keyword, b" ") if keyword else text, dtype=dtype, sep=" "
        )
    except ValueError:  # a token it cannot read; a token it reads as two numbers changes the count
        return None
    return values if values.size == count else None
