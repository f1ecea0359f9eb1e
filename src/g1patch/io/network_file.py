"""The native network file: ``.npz`` with a format version, patches and their sharing arrays.

Version 2 stores the patches in their local coordinates and, when they have one, their frame as
the arrays ``frame_centre`` (3,) and ``frame_scale`` () (see :mod:`g1patch.frame`): the file holds
exactly the numbers the construction made. Version 3 adds ``seam`` (P, 4) bool, the patch edges
that are sharp on purpose (:attr:`PatchNetwork.seam`). Version 1 files (no frame) and version 2
files (no seams) are read as before: seam-free.
"""

from __future__ import annotations

import json
import os
import zipfile
from pathlib import Path

import numpy as np

from ..errors import FormatError, InputError
from ..network import PatchNetwork
from ..gregory import GregoryPatchSet
from ..patches import PatchSet
from .atomic import atomic_path

__all__ = ["FORMAT_VERSION", "READABLE_VERSIONS", "save_network", "load_network"]

#: the version :func:`save_network` writes
FORMAT_VERSION = 3
#: the versions :func:`load_network` reads (1: no frame, 2: no seams)
READABLE_VERSIONS = (1, 2, 3)
_ARRAYS = ("corner_ids", "edge_ids", "edge_reversed", "neighbor", "neighbor_edge", "same_direction", "edge_collapsed")
#: the first version with seams
SEAM_VERSION = 3


def save_network(path: str | os.PathLike[str], network: PatchNetwork) -> None:
    """Write ``network`` to ``path`` (``.npz``), atomically."""
    if Path(path).suffix.lower() != ".npz":
        raise FormatError(path, "a network file must end in .npz")
    patches = network.patches
    if isinstance(patches, PatchSet):
        patch_arrays = {"patch_kind": np.array("bicubic"), **patches.to_arrays()}
    elif isinstance(patches, GregoryPatchSet):
        patch_arrays = {"patch_kind": np.array(GregoryPatchSet.kind), **patches.to_arrays()}
    else:
        raise FormatError(path, f"cannot store patches of type {type(patches).__name__}")
    arrays = {name: getattr(network, name) for name in (*_ARRAYS, "seam")}
    for name in ("vertices", "vertex_normals"):
        if getattr(network, name) is not None:
            arrays[name] = getattr(network, name)
    header = {"format": "g1patch-network", "version": FORMAT_VERSION, "provenance": network.provenance}
    with atomic_path(path) as temporary:
        with open(temporary, "wb") as handle:
            np.savez_compressed(handle, header=np.array(json.dumps(header)), **patch_arrays, **arrays)


def load_network(path: str | os.PathLike[str]) -> PatchNetwork:
    """Read a network written by :func:`save_network`; anything else raises FormatError."""
    source = Path(path)
    try:
        with np.load(source, allow_pickle=False) as data:
            contents = {name: data[name] for name in data.files}
    except FileNotFoundError:
        raise FormatError(source, "no such file") from None
    except (OSError, ValueError, zipfile.BadZipFile, EOFError) as exc:
        raise FormatError(source, f"not a g1patch network file ({exc})") from None
    try:
        header = json.loads(str(contents["header"]))
    except (KeyError, json.JSONDecodeError):
        raise FormatError(source, "not a g1patch network file (no header)") from None
    if header.get("format") != "g1patch-network":
        raise FormatError(source, "not a g1patch network file (wrong header)")
    if header.get("version") not in READABLE_VERSIONS:
        readable = ", ".join(map(str, READABLE_VERSIONS))
        raise FormatError(source, f"network format version {header.get('version')} is not supported (this g1patch reads {readable})")
    version = header["version"]
    if version == 1:  # version 1 has no frame: arrays of that name are not part of it
        contents = {name: value for name, value in contents.items() if not name.startswith("frame_")}
    if version < SEAM_VERSION:  # seam-free: an array of that name is not part of it
        contents.pop("seam", None)
    expected = ("patch_kind", *_ARRAYS, *(("seam",) if version >= SEAM_VERSION else ()))
    missing = [name for name in expected if name not in contents]
    if missing:
        raise FormatError(source, f"network file lacks {', '.join(missing)}")
    kind = str(contents["patch_kind"])
    if kind not in ("bicubic", GregoryPatchSet.kind):
        raise FormatError(source, f"unknown patch kind {kind!r}")
    try:
        patches = PatchSet.from_arrays(contents) if kind == "bicubic" else GregoryPatchSet.from_arrays(contents)
        return PatchNetwork(
            patches=patches,
            **{name: contents[name] for name in _ARRAYS},
            vertices=contents.get("vertices"),
            vertex_normals=contents.get("vertex_normals"),
            seam=contents.get("seam"),
            provenance={str(k): str(v) for k, v in header.get("provenance", {}).items()},
        )
    except (InputError, KeyError) as exc:
        raise FormatError(source, f"corrupt network file: {exc}") from None
