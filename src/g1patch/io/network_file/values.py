"""The values a network file holds, checked before a network is made of them: index ranges,
consistent edges, finite coordinates within the format's limits."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ...errors import FormatError, InputError
from ...frame import Frame
from ...gregory import GregoryPatchSet
from ...mesh.groups import FaceGroups
from .schema import (
    _BOOL_ARRAYS,
    _CHUNK,
    _FLOAT_ARRAYS,
    MAX_COORDINATE,
)


class _Checker:
    """The value checks shared by loading and saving (vectorised; the module docstring's list)."""

    def __init__(self, source: Path, prefix: str) -> None:
        self.source, self.prefix = source, prefix

    def fail(self, name: str, message: str) -> FormatError:
        return FormatError(self.source, f"{self.prefix}member '{name}.npy': {message}")

    def check(self, arrays: dict[str, Any]) -> dict[str, Any]:
        """``arrays`` with index arrays as int64 and floats as float64, or FormatError naming the
        member."""
        kind = str(arrays["patch_kind"])
        patch_name = "points" if kind == GregoryPatchSet.kind else "control"
        patches = np.asarray(arrays[patch_name])
        count = patches.shape[0] if patches.ndim else 0
        out = dict(arrays)
        for name in (
            "corner_ids",
            "edge_ids",
            "neighbor",
            "neighbor_edge",
            "edge_reversed",
            "same_direction",
            "seam",
        ):
            if name in arrays and np.shape(arrays[name]) != (count, 4):
                raise self.fail(name, f"expected shape ({count}, 4), got {np.shape(arrays[name])}")
        if "uv" in arrays and np.shape(arrays["uv"]) != (count, 4, 2):
            raise self.fail("uv", f"expected shape ({count}, 4, 2), got {np.shape(arrays['uv'])}")
        for name in _BOOL_ARRAYS:
            if name in arrays:
                out[name] = self.booleans(name, arrays[name])
        extent = {}
        for name in _FLOAT_ARRAYS:
            if name in arrays and not name.startswith("frame_") and name != "group_colour":
                out[name], extent[name] = self.coordinates(name, arrays[name])
        extent.pop("hanging_span", None)  # fractions of an edge, not coordinates
        if "hanging_sides" in arrays:
            links = np.shape(arrays["hanging_sides"])[:1]
            for name, width in (("hanging_sides", 4), ("hanging_span", 2)):
                if np.shape(arrays[name]) != (*links, width):
                    raise self.fail(
                        name, f"expected shape {(*links, width)}, got {np.shape(arrays[name])}"
                    )
            out["hanging_sides"] = self.indices(
                "hanging_sides",
                arrays["hanging_sides"],
                0,
                max(count, 4) - 1,
                "patch indices and patch edges 0..3",
            )
        if "group" in arrays:
            out["group"], out["group_colour"] = self.groups(arrays, count)
        edges = len(out["edge_collapsed"])
        vertices = [len(out[name]) for name in ("vertices", "vertex_normals") if name in out]
        if len(set(vertices)) > 1:
            raise self.fail("vertex_normals", f"has {vertices[1]} rows for {vertices[0]} vertices")
        for name, rows in (("edge_collapsed", edges), ("vertices", vertices[0] if vertices else 0)):
            if rows > 4 * count:
                raise self.fail(name, f"has {rows} rows, more than 4 per patch ({4 * count})")
        corner_limit = vertices[0] if vertices else 4 * count
        limits = {
            "corner_ids": (
                0,
                corner_limit - 1,
                f"vertex indices of the {corner_limit} vertices"
                if vertices
                else "corner point ids, at most 4 per patch",
            ),
            "edge_ids": (
                0,
                edges - 1,
                f"edge indices of the {edges} edges of 'edge_collapsed.npy'",
            ),
            "neighbor": (-1, count - 1, f"patch indices of the {count} patches, or -1"),
            "neighbor_edge": (-1, 3, "patch edges 0..3, or -1"),
        }
        for name, (low, high, meaning) in limits.items():
            out[name] = self.indices(name, arrays[name], low, high, meaning)
        self.sharing(out["neighbor"], out["neighbor_edge"], out["edge_ids"])
        self.frame(out, extent, patch_name)
        return out

    def group_names(self, value: Any) -> tuple[str, ...]:
        """The names of ``group_names.npy``: a JSON list of strings."""
        try:
            names = json.loads(str(value))
        except json.JSONDecodeError:
            raise self.fail("group_names", "expected a JSON list of names, got no JSON") from None
        if not isinstance(names, list) or not all(isinstance(name, str) for name in names):
            raise self.fail("group_names", "expected a JSON list of names (strings)")
        return tuple(names)

    def groups(self, arrays: dict[str, Any], count: int) -> tuple[NDArray[np.int64], Any]:
        """``group`` (P,) ids in −1 … G − 1 of the G names, ``group_colour`` (G, 3) RGB in [0, 1] or
        a row of NaN (:class:`~g1patch.mesh.groups.FaceGroups`' rules), each named when wrong."""
        names = self.group_names(arrays["group_names"])
        if len(names) > 4 * count:
            raise self.fail("group_names", f"has {len(names)} names, more than 4 per patch")
        colour = np.asarray(arrays["group_colour"])
        if colour.dtype.kind != "f" or colour.dtype.itemsize > 8:
            raise self.fail(
                "group_colour", f"expected floating-point numbers, got an array of {colour.dtype}"
            )
        for name, shape, got in (
            ("group", (count,), np.shape(arrays["group"])),
            ("group_colour", (len(names), 3), colour.shape),
        ):
            if got != shape:
                raise self.fail(name, f"expected shape {shape} ({len(names)} names), got {got}")
        ids = self.indices(
            "group", arrays["group"], -1, len(names) - 1, f"ids of the {len(names)} names, or -1"
        )
        colour = colour.astype(np.float64, copy=False)
        try:
            FaceGroups(ids[:0], names, colour)
        except InputError as exc:
            member = "group_colour" if "colour" in str(exc) else "group_names"
            raise self.fail(member, str(exc).removeprefix("groups: ")) from None
        return ids, colour

    def booleans(self, name: str, value: Any) -> NDArray[np.bool_]:
        array = np.asarray(value)
        if array.dtype != np.bool_:
            raise self.fail(name, f"expected booleans, got an array of {array.dtype}")
        if array.size and np.ascontiguousarray(array).view(np.uint8).max() > 1:
            bad = np.argwhere(np.ascontiguousarray(array).view(np.uint8) > 1)[0]
            raise self.fail(
                name,
                f"byte {int(np.ascontiguousarray(array).view(np.uint8)[tuple(bad)])} at "
                f"{_where(bad)} "
                f"is not a boolean (0 or 1)",
            )
        return array

    def coordinates(self, name: str, value: Any) -> tuple[NDArray[np.float64], float]:
        """``value`` as float64, finite and within the bound; and its largest magnitude."""
        array = np.asarray(value)
        if array.dtype.kind != "f" or array.dtype.itemsize > 8:
            raise self.fail(name, f"expected floating-point numbers, got an array of {array.dtype}")
        array = array.astype(np.float64, copy=False)
        if not array.size:
            return array, 0.0
        low, high = _extremes(array)
        if low >= -MAX_COORDINATE and high <= MAX_COORDINATE:
            return array, max(-low, high)
        bad = np.argwhere(~(np.abs(array) <= MAX_COORDINATE))[0]
        number = float(array[tuple(bad)])
        problem = (
            "is not a number"
            if np.isnan(number)
            else "is infinite"
            if np.isinf(number)
            else f"exceeds the bound |x| ≤ {MAX_COORDINATE:g} on coordinates"
        )
        raise self.fail(name, f"value {number!r} at {_where(bad)} {problem}")

    def indices(
        self, name: str, value: Any, low: int, high: int, meaning: str
    ) -> NDArray[np.int64]:
        array = np.asarray(value)
        if array.dtype.kind not in "iu" or array.dtype.itemsize > 8:
            raise self.fail(name, f"expected integers, got an array of {array.dtype}")
        if array.size and not (int(array.min()) >= low and int(array.max()) <= high):
            bad = np.argwhere((array < low) | (array > high))[0]
            raise self.fail(
                name,
                f"value {int(array[tuple(bad)])} at {_where(bad)} is out of range {low}..{high} "
                f"({meaning})",
            )
        return array.astype(
            np.int64, copy=False
        )  # what PatchNetwork keeps: no copy for the int64 we write

    def sharing(
        self,
        neighbor: NDArray[np.int64],
        neighbor_edge: NDArray[np.int64],
        edge_ids: NDArray[np.int64],
    ) -> None:
        """−1 at the same places, every neighbour pointing back, both sides naming one edge id.

        On the flat half-edge numbering ``4 p + k``: ``twin = 4 neighbor + neighbor_edge`` (−5 on an
        open edge) must satisfy ``twin[twin[h]] = h`` on every shared edge (gathered modulo 4P, so
        open edges index harmlessly and are masked after). In chunks of :data:`_CHUNK` half-edges:
        the temporaries stay in the cache and no large array is allocated."""
        flat_neighbor, flat_edge, flat_ids = (
            neighbor.reshape(-1),
            neighbor_edge.reshape(-1),
            edge_ids.reshape(-1),
        )
        for start in range(0, len(flat_neighbor), _CHUNK):
            stop = min(start + _CHUNK, len(flat_neighbor))
            near, edge = flat_neighbor[start:stop], flat_edge[start:stop]
            shared = near >= 0
            mismatch = shared != (edge >= 0)
            if mismatch.any():
                at = start + int(np.argmax(mismatch))
                raise self.fail(
                    "neighbor_edge",
                    f"value {int(flat_edge[at])} at index ({at // 4}, {at % 4}) does not match "
                    f"'neighbor.npy' ({int(flat_neighbor[at])}): -1 in both or in neither",
                )
            twin = near * 4 + edge
            back = np.take(flat_neighbor, twin, mode="wrap") * 4 + np.take(
                flat_edge, twin, mode="wrap"
            )
            wrong = (back != np.arange(start, stop)) & shared
            if wrong.any():
                at = int(np.argmax(wrong))
                h, q = start + at, int(twin[at])
                raise self.fail(
                    "neighbor",
                    f"patch {h // 4} edge {h % 4} points to patch {q // 4} edge {q % 4}, "
                    f"which does not point back",
                )
            differs = (np.take(flat_ids, twin, mode="wrap") != flat_ids[start:stop]) & shared
            if differs.any():
                at = int(np.argmax(differs))
                h, q = start + at, int(twin[at])
                raise self.fail(
                    "edge_ids",
                    f"patch {h // 4} edge {h % 4} and its neighbour, patch {q // 4} edge {q % 4}, "
                    f"name different edges ({int(flat_ids[h])} and {int(flat_ids[q])})",
                )

    def frame(self, arrays: dict[str, Any], extent: dict[str, float], patch_name: str) -> None:
        """The frame's own checks (:meth:`Frame.from_arrays`: both arrays, shapes, finite, scale >
        0), then the centre and scale within the bound and the world coordinates ``|c| + s·max|x|``
        too."""
        try:
            frame = Frame.from_arrays(arrays)
        except InputError as exc:
            raise FormatError(self.source, f"{self.prefix}corrupt network file: {exc}") from None
        if frame is None:
            return
        for name in ("frame_centre", "frame_scale"):
            arrays[name], extent[name] = self.coordinates(name, arrays[name])
        world = extent["frame_centre"] + frame.scale * extent[patch_name]
        if not world <= MAX_COORDINATE:
            raise self.fail(
                patch_name,
                f"in world coordinates (centre + scale × value) the patches reach {world:g}, "
                f"beyond the bound |x| ≤ {MAX_COORDINATE:g} on coordinates",
            )


def _extremes(array: NDArray[np.float64]) -> tuple[float, float]:
    """``(min, max)`` of ``array`` in one pass over memory (each chunk's min and max while it is in
    the cache); a NaN anywhere makes both NaN."""
    flat = array.reshape(-1) if array.flags.c_contiguous else np.ravel(array)
    low, high = np.inf, -np.inf
    for start in range(0, len(flat), _CHUNK):
        chunk = flat[start : start + _CHUNK]
        chunk_low, chunk_high = float(chunk.min()), float(chunk.max())
        if chunk_low != chunk_low:  # NaN (numpy's min propagates it; Python's min would drop it)
            return np.nan, np.nan
        low, high = min(low, chunk_low), max(high, chunk_high)
    return low, high


def _where(index: NDArray[np.int64]) -> str:
    return f"index {tuple(int(i) for i in index)}"
