"""Named groups of faces (or of the patches made from them): the OBJ file's ``usemtl`` materials
or ``g``/``o`` groups, carried by every step that makes new faces from old ones (each new face
takes its parent's group) so that CAD faces and tessellated OBJ groups can be named and coloured
after them (:class:`FaceGroups`)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InputError, as_index_array
from .features import _read_only

__all__ = ["FaceGroups"]

IntArray = NDArray[np.int64]
FloatArray = NDArray[np.float64]


@dataclass(frozen=True, eq=False)
class FaceGroups:
    """Each item's group ``ids`` (n,), −1 for none, with the groups' ``names`` (G,) and RGB
    ``colours`` (G, 3) in [0, 1], a row of NaN for a group without one (None: all without).

    Names are non-empty printable text without leading or trailing blanks (so they survive an OBJ
    line); ids lie in −1 … G − 1. Items are faces of a mesh or patches of a network: the class
    only knows their count."""

    ids: IntArray
    names: tuple[str, ...]
    colours: FloatArray = None  # type: ignore[assignment]  # None: all without a colour

    def __post_init__(self) -> None:
        ids = as_index_array("groups", self.ids)
        names = tuple(self.names)
        if ids.ndim != 1:
            raise InputError(f"groups: expected one id per item, shape (n,), got {ids.shape}")
        bad_name = [n for n in names if not isinstance(n, str) or not _valid_name(n)]
        if bad_name:
            raise InputError(
                f"groups: name {bad_name[0]!r} is not non-empty printable text without leading "
                "or trailing blanks"
            )
        if ids.size and (int(ids.min()) < -1 or int(ids.max()) >= len(names)):
            at = int(np.flatnonzero((ids < -1) | (ids >= len(names)))[0])
            raise InputError(
                f"groups: item {at} has group {int(ids[at])}, outside -1..{len(names) - 1} "
                f"({len(names)} names)"
            )
        colours = np.full((len(names), 3), np.nan) if self.colours is None else self.colours
        colours = np.array(colours, dtype=np.float64)
        if colours.shape != (len(names), 3):
            raise InputError(
                f"groups: expected colours of shape ({len(names)}, 3), got {colours.shape}"
            )
        unset = np.isnan(colours)
        wrong = ~(unset.all(axis=1) | ((colours >= 0) & (colours <= 1)).all(axis=1))
        if wrong.any():
            at = int(np.flatnonzero(wrong)[0])
            raise InputError(
                f"groups: colour {colours[at].tolist()} of group {names[at]!r} is neither RGB "
                "in [0, 1] nor all NaN"
            )
        object.__setattr__(self, "ids", _read_only(ids.copy()))
        object.__setattr__(self, "names", names)
        object.__setattr__(self, "colours", _read_only(colours))

    def __len__(self) -> int:
        return int(self.ids.size)

    def take(self, index: ArrayLike) -> FaceGroups:
        """The groups of the items ``index`` (an index or boolean array), names and colours kept."""
        return FaceGroups(self.ids[np.asarray(index)], self.names, self.colours)

    def repeat(self, counts: int | IntArray) -> FaceGroups:
        """Each item's group ``counts`` times in a row (one count, or one per item): the children
        of a split that makes ``counts[f]`` consecutive faces of face f."""
        return FaceGroups(np.repeat(self.ids, counts), self.names, self.colours)

    def label(self, item: int, fallback: str) -> str:
        """``'NAME item'`` for an item of a group, ``'fallback item'`` for one without."""
        group = int(self.ids[item])
        return f"{self.names[group] if group >= 0 else fallback} {item}"


def _valid_name(name: str) -> bool:
    return bool(name) and name.isprintable() and name.strip() == name
