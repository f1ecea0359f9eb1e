"""OBJ face groups: ``usemtl``, ``g`` and ``o`` statements give each face a group, ``mtllib``
files the materials' colours (:func:`_obj_groups`). A pass of its own, run only on files that may
hold such statements (:func:`_mentions_groups`), as the ``vt`` pass is.

The rule: a face's group is the material of the last ``usemtl`` before it where there was one,
else the name of the last ``g`` or ``o`` before it (a ``g`` without a name clears it); faces
before any of these have none (id −1). Names are the statement's words joined by one space.
Colours come from the ``Kd r g b`` of the ``newmtl`` entries of the ``mtllib`` files next to the
OBJ file; a library that is missing or unreadable, or a bad ``Kd``, costs a one-line warning and
the colour, never the names.
"""

from __future__ import annotations

import logging
from pathlib import Path

import numpy as np

from ...errors import FormatError, G1PatchError
from ...mesh.groups import FaceGroups
from .parsed import _decode
from .source import read_input
from .text import _scan

logger = logging.getLogger(__name__)

#: the largest material library read (a bigger one is skipped with a warning)
MAX_MTL_BYTES = 1 << 24
_KEYWORDS = ("g", "o", "usemtl", "mtllib")
#: what may stand next to a statement's keyword: nothing, a blank or a line break
#: ``Kd`` forms that give no RGB colour (skipped without a warning)
_OTHER_KD = (["spectral"], ["xyz"])
_BLANK = (b"", b" ", b"\t", b"\r", b"\n")


def _mentions_groups(data: bytes) -> bool:
    """Whether ``data`` may hold a ``g``, ``o`` or ``usemtl`` statement: ``usemtl`` anywhere, or a
    ``g`` or ``o`` standing alone between blanks (a ``memchr`` for each byte, which numbers never
    hold)."""
    if b"usemtl" in data:
        return True
    for letter in (b"g", b"o"):
        at = data.find(letter)
        while at >= 0:
            before, after = data[at - 1 : at] if at else b"", data[at + 1 : at + 2]
            if before in _BLANK and after in _BLANK:
                return True
            at = data.find(letter, at + 1)
    return False


def _statements(path: Path, data: bytes) -> tuple[list[tuple[int, str, str]], list[int], int]:
    """The grouping statements of ``data`` as (line, keyword, name), the faces before each, and
    the faces in all: from the vectorised line scan, or line by line for text it declines."""
    lines = _scan(data)
    found: list[tuple[int, str, str]] = []
    before: list[int] = []
    if lines is not None:
        first, second = lines.byte(0), lines.byte(1)
        is_face = (first == ord("f")) & (second == ord(" "))
        faces_before = np.cumsum(is_face) - is_face
        candidates = np.flatnonzero(np.isin(first, np.frombuffer(b"goum", np.uint8)))
        for row in candidates.tolist():
            keyword, _, name = lines.text[lines.starts[row] : lines.ends[row]].partition(b" ")
            if keyword.decode() in _KEYWORDS:
                found.append((row + 1, keyword.decode(), name.decode()))
                before.append(int(faces_before[row]))
        return found, before, int(is_face.sum())
    faces = 0
    for number, line in enumerate(_decode(path, data), start=1):
        parts = line.split("#", 1)[0].split()
        if parts and parts[0] == "f":
            faces += 1
        elif parts and parts[0] in _KEYWORDS:
            found.append((number, parts[0], " ".join(parts[1:])))
            before.append(faces)
    return found, before, faces


def _obj_groups(path: Path, data: bytes, n_faces: int) -> FaceGroups | None:
    """Each of the ``n_faces`` faces' group by the module's rule, with the colours of the
    libraries' materials; None where no face has one. A ``usemtl``, ``mtllib`` without a name or
    a name with a control character is a :class:`FormatError` naming the line."""
    statements, before, faces = _statements(path, data)
    if faces != n_faces:
        raise G1PatchError(f"{path}: the group pass counted {faces} faces, the reader {n_faces}")
    names: dict[str, int] = {}
    materials: set[str] = set()
    libraries: list[tuple[int, str]] = []
    state = np.full(len(statements), -1, dtype=np.int64)
    material: str | None = None
    group: str | None = None
    for k, (number, keyword, name) in enumerate(statements):
        if not name.isprintable():
            raise FormatError(
                path, f"{keyword}: the name {name!r} holds a control character", number
            )
        if keyword in ("usemtl", "mtllib") and not name:
            what = "'usemtl NAME'" if keyword == "usemtl" else "'mtllib FILE'"
            raise FormatError(path, f"expected {what}, got {keyword!r} alone", number)
        if keyword == "usemtl":
            material = name
            materials.add(name)
        elif keyword == "mtllib":
            libraries.append((number, name))
        else:
            group = name or None
        key = material if material is not None else group
        if key is not None:
            state[k] = names.setdefault(key, len(names))
    if not statements:
        return None
    last = np.searchsorted(np.asarray(before), np.arange(n_faces), side="right") - 1
    ids = np.where(last >= 0, state[np.maximum(last, 0)], -1)
    if (ids < 0).all():
        return None
    used = np.zeros(len(names), dtype=bool)
    used[ids[ids >= 0]] = True
    renumber = np.cumsum(used) - 1
    kept = [name for name, index in names.items() if used[index]]
    colours = np.full((len(kept), 3), np.nan)
    if libraries and materials:
        known = _library_colours(path, libraries)
        for row, name in enumerate(kept):
            if name in materials and name in known:
                colours[row] = known[name]
    return FaceGroups(np.where(ids >= 0, renumber[np.maximum(ids, 0)], -1), tuple(kept), colours)


def _library_colours(path: Path, libraries: list[tuple[int, str]]) -> dict[str, tuple[float, ...]]:
    """The ``Kd`` colour of every ``newmtl`` of the ``mtllib`` files (named relative to the OBJ
    file, a name with blanks tried whole first, then word by word), clipped to [0, 1]; what cannot
    be read is skipped with a one-line warning."""
    colours: dict[str, tuple[float, ...]] = {}
    for number, name in libraries:
        candidates = [name, *name.split()] if " " in name else [name]
        found = next((path.parent / c for c in candidates if (path.parent / c).is_file()), None)
        if found is None:
            logger.warning(
                "%s:%d: material library %r not found: its materials have no colour",
                path,
                number,
                name,
            )
            continue
        try:
            text = read_input(found, MAX_MTL_BYTES).decode("utf-8")
        except (G1PatchError, OSError, UnicodeDecodeError) as exc:
            reason = " ".join(str(exc).split())[:160]
            logger.warning(
                "%s:%d: material library %r cannot be read (%s): its materials have no colour",
                path,
                number,
                name,
                reason,
            )
            continue
        colours.update(_mtl_colours(found, text))
    return colours


def _mtl_colours(path: Path, text: str) -> dict[str, tuple[float, ...]]:
    """``newmtl NAME`` … ``Kd r g b`` of one material library; a ``Kd`` that is not three finite
    numbers is skipped with a one-line warning (``Kd spectral``/``xyz`` silently)."""
    colours: dict[str, tuple[float, ...]] = {}
    material: str | None = None
    for number, line in enumerate(text.splitlines(), start=1):
        parts = line.split("#", 1)[0].split()
        if not parts:
            continue
        if parts[0] == "newmtl":
            material = " ".join(parts[1:]) or None
        elif parts[0] == "Kd" and material is not None and parts[1:2] not in _OTHER_KD:
            try:
                rgb = np.array([float(x) for x in parts[1:4]], dtype=np.float64)
                if rgb.size != 3 or not np.isfinite(rgb).all():
                    raise ValueError
            except ValueError:
                logger.warning(
                    "%s:%d: expected 'Kd r g b' with 3 finite numbers, got %r: %r has no colour",
                    path,
                    number,
                    line.strip()[:60],
                    material,
                )
                continue
            colours[material] = tuple(np.clip(rgb, 0.0, 1.0).tolist())
    return colours
