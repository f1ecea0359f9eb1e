"""Newell's Bézier patch format (``.bpt``): a patch count, then per patch ``3 3`` and 16 points.

The 16 points of a patch are 4 rows of 4; row r, column c is control point ``P[r, c]`` (r along
u, c along v).

Reading validates every line: the count is a positive integer the file has room for (17 non-empty
lines a patch; a truncated file names its last line), every patch header is ``3 3``, every point
three finite numbers of magnitude at most :data:`MAX_COORDINATE` (1e30, the bound of the network
file, :mod:`g1patch.io.network_file`), nothing follows the last patch. Only a regular file is read
(never ``/dev/zero`` or a FIFO, links resolved), and one larger than :data:`MAX_BPT_BYTES` (1 GiB,
~5 million patches) is refused before it is read; the patches' array is allocated for no more than
the file has room for (:data:`PATCH_BYTES` a patch). A UTF-8 byte-order mark is skipped. Each
violation is one :class:`FormatError` naming the file and the line.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from ..errors import FormatError
from ..patches import PatchSet
from .atomic import atomic_path
from .meshfile.source import BOM, MAX_COUNT_DIGITS, read_input
from .network_file import MAX_COORDINATE

__all__ = ["read_bpt", "write_bpt", "MAX_BPT_BYTES"]

#: largest .bpt file read (a patch takes ~200 bytes of text: about 5 million patches)
MAX_BPT_BYTES = 2**30
#: the fewest bytes a patch takes: ``3 3`` and 16 points ``0 0 0``, each line with its line break
PATCH_BYTES = 4 + 16 * 6


def read_bpt(path: str | os.PathLike[str], max_bytes: int = MAX_BPT_BYTES) -> PatchSet:
    """Read a ``.bpt`` file of at most ``max_bytes`` into Bézier patches; a malformed file raises
    FormatError naming the line."""
    source = Path(path)
    data = read_input(source, max_bytes).removeprefix(BOM)
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError:
        raise FormatError(source, "not a text file") from None
    lines = (
        (number, words)
        for number, line in enumerate(text.splitlines(), start=1)
        if (words := line.split())
    )
    number, words = next(lines, (0, []))
    if not words:
        raise FormatError(source, "empty file; expected a patch count on the first line")
    if (
        len(words) != 1
        or not (words[0].isascii() and words[0].isdigit())
        or len(words[0]) > MAX_COUNT_DIGITS
        or int(words[0]) < 1
    ):
        raise FormatError(
            source, f"expected a positive patch count, got {' '.join(words)[:60]!r}", number
        )
    count = int(words[0])
    # no more patches than the file has room for: a count beyond it ends in 'truncated' below
    control = np.empty((min(count, len(data) // PATCH_BYTES + 1), 16, 3))
    seen = 1
    for patch in range(count):
        for point in range(-1, 16):
            number, words = next(lines, (number, []))
            if not words:
                raise FormatError(
                    source,
                    f"truncated: {count} patches need {1 + 17 * count} non-empty lines, the file "
                    f"has {seen}",
                    number,
                )
            seen += 1
            if point < 0:
                if words != ["3", "3"]:
                    raise FormatError(
                        source,
                        f"patch {patch + 1}: expected degrees '3 3', got {' '.join(words)[:60]!r}",
                        number,
                    )
            elif patch < len(control):
                control[patch, point] = _point(source, patch, number, words)
    extra = next(lines, None)
    if extra is not None:
        raise FormatError(source, f"unexpected content after {count} patches", extra[0])
    return PatchSet(control.reshape(count, 4, 4, 3), "bezier")


def _point(source: Path, patch: int, number: int, words: list[str]) -> list[float]:
    """The point ``x y z`` of patch ``patch`` on line ``number``: three finite numbers within
    :data:`MAX_COORDINATE`."""
    try:
        values = [float(word) for word in words]
    except ValueError:
        values = []
    if len(values) != 3 or not np.isfinite(values).all():
        raise FormatError(
            source,
            f"patch {patch + 1}: expected three finite numbers 'x y z', got "
            f"{' '.join(words)[:80]!r}",
            number,
        )
    if not max(map(abs, values)) <= MAX_COORDINATE:
        raise FormatError(
            source,
            f"patch {patch + 1}: coordinate of magnitude {max(map(abs, values)):g} in "
            f"{' '.join(words)!r} exceeds the bound |x| ≤ {MAX_COORDINATE:g}",
            number,
        )
    return values


def write_bpt(path: str | os.PathLike[str], patches: PatchSet) -> None:
    """Write patches (converted to Bézier form) as ``.bpt``, atomically, with round-trip precision.

    The points are world coordinates (:meth:`PatchSet.world_control`): a framed set is written as
    the surface it describes, its frame is not stored."""
    control = patches.convert("bezier").world_control().reshape(len(patches), 16, 3)
    lines = [f"{len(patches)}"]
    for points in control:
        lines.append("3 3")
        lines.extend(" ".join(repr(float(value)) for value in point) for point in points)
    with atomic_path(path) as temporary:
        temporary.write_text("\n".join(lines) + "\n", encoding="utf-8")
