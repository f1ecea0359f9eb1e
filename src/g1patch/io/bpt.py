"""Newell's Bézier patch format (``.bpt``): a patch count, then per patch ``3 3`` and 16 points.

The 16 points of a patch are 4 rows of 4; row r, column c is control point ``P[r, c]`` (r along
u, c along v).

Reading validates every line: the count is a positive integer the file has room for (17 non-empty
lines a patch; a truncated file names its last line), every patch header is ``3 3``, every point
three finite numbers of magnitude at most :data:`MAX_COORDINATE` (1e30, the bound of the network
file, :mod:`g1patch.io.network_file`), nothing follows the last patch; a file larger than
:data:`MAX_BPT_BYTES` (1 GiB, ~5 million patches) is refused before it is read. Each violation is
one :class:`FormatError` naming the file and the line.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from ..errors import FormatError
from ..patches import PatchSet
from .atomic import atomic_path
from .network_file import MAX_COORDINATE

__all__ = ["read_bpt", "write_bpt", "MAX_BPT_BYTES"]

#: largest .bpt file read (a patch takes ~200 bytes of text: about 5 million patches)
MAX_BPT_BYTES = 2**30


def read_bpt(path: str | os.PathLike[str]) -> PatchSet:
    """Read a ``.bpt`` file into Bézier patches; a malformed file raises FormatError naming the
    line."""
    source = Path(path)
    try:
        size = source.stat().st_size
        if size > MAX_BPT_BYTES:
            raise FormatError(
                source, f"{size} bytes, above the {MAX_BPT_BYTES} a .bpt file may have"
            )
        text = source.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise FormatError(source, "no such file") from None
    except UnicodeDecodeError:
        raise FormatError(source, "not a text file") from None
    except OSError as exc:
        raise FormatError(source, f"cannot read: {exc.strerror}") from None
    lines = [(number, line.split()) for number, line in enumerate(text.splitlines(), start=1)]
    lines = [(number, words) for number, words in lines if words]
    if not lines:
        raise FormatError(source, "empty file; expected a patch count on the first line")
    number, words = lines[0]
    if len(words) != 1 or not (words[0].isascii() and words[0].isdigit()) or int(words[0]) < 1:
        raise FormatError(
            source, f"expected a positive patch count, got {' '.join(words)!r}", number
        )
    count = int(words[0])
    expected_lines = 1 + 17 * count
    if len(lines) < expected_lines:
        raise FormatError(
            source,
            f"truncated: {count} patches need {expected_lines} non-empty lines, the file has "
            f"{len(lines)}",
            lines[-1][0],
        )
    if len(lines) > expected_lines:
        raise FormatError(
            source, f"unexpected content after {count} patches", lines[expected_lines][0]
        )
    control = np.empty((count, 16, 3))
    for patch in range(count):
        number, words = lines[1 + 17 * patch]
        if words != ["3", "3"]:
            raise FormatError(
                source,
                f"patch {patch + 1}: expected degrees '3 3', got {' '.join(words)!r}",
                number,
            )
        for point in range(16):
            number, words = lines[2 + 17 * patch + point]
            try:
                values = [float(word) for word in words]
            except ValueError:
                values = []
            if len(values) != 3 or not np.isfinite(values).all():
                raise FormatError(
                    source,
                    f"patch {patch + 1}: expected three finite numbers 'x y z', got "
                    f"{' '.join(words)!r}",
                    number,
                )
            if not max(map(abs, values)) <= MAX_COORDINATE:
                raise FormatError(
                    source,
                    f"patch {patch + 1}: coordinate of magnitude {max(map(abs, values)):g} in "
                    f"{' '.join(words)!r} exceeds the bound |x| ≤ {MAX_COORDINATE:g}",
                    number,
                )
            control[patch, point] = values
    return PatchSet(control.reshape(count, 4, 4, 3), "bezier")


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
