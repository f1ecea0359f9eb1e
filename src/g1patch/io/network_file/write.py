"""Writing a network file: the members checked as the loader checks them, one stored zip written
in a single pass, atomically (:func:`save_network`), or on a thread of its own."""

from __future__ import annotations

import io
import json
import os
import struct
import zlib
from collections.abc import Mapping
from concurrent.futures import Future, ThreadPoolExecutor
from pathlib import Path
from typing import Any, BinaryIO

import numpy as np
from numpy.typing import NDArray

from ...errors import FormatError
from ...gregory import GregoryPatchSet
from ...network import PatchNetwork
from ...patches import PatchSet
from ..atomic import atomic_path
from .schema import (
    _ARRAYS,
    FORMAT_VERSION,
    MAX_GROUP_NAMES_BYTES,
)
from .values import _Checker

# ------------------------------------------------------------------------------------ saving


def save_network(path: str | os.PathLike[str], network: PatchNetwork) -> None:
    """Write ``network`` to ``path`` (``.npz``), atomically; see the module docstring for the
    format.

    The arrays pass the checks :func:`load_network` makes first (a network whose coordinates exceed
    :data:`MAX_COORDINATE`, say, raises :class:`FormatError` and writes nothing)."""
    _write_members(*_members(path, network))


def save_network_in_background(path: str | os.PathLike[str], network: PatchNetwork) -> Future[None]:
    """:func:`save_network` with the writing on a thread of its own: the checks run now (and raise
    here, writing nothing), the file is written while the caller goes on, and the returned future's
    ``result()`` waits for it and raises what writing raised. The arrays are written from the
    network's own memory, so they must not change until then. What it is for: the file's bytes
    reach the page cache at disk speed once it fills (4 M Gregory patches, 2.7 GB: 7 s alone), and
    a check run meanwhile hides that (``g1patch build --check``; 4 M: 18–19 s one after the other,
    11.5 s side by side). An interpreter exiting first still finishes the file: it waits for the
    thread."""
    members = _members(path, network)
    writer = ThreadPoolExecutor(max_workers=1, thread_name_prefix="g1patch-save")
    try:
        return writer.submit(_write_members, *members)
    finally:
        writer.shutdown(wait=False)


def _members(
    path: str | os.PathLike[str], network: PatchNetwork
) -> tuple[Path, dict[str, NDArray[Any]]]:
    """The target path and the file's members of ``network``, checked as :func:`load_network` checks
    them."""
    target = Path(path)
    if target.suffix.lower() != ".npz":
        raise FormatError(path, "a network file must end in .npz")
    patches = network.patches
    if isinstance(patches, PatchSet):
        kind = "bicubic"
    elif isinstance(patches, GregoryPatchSet):
        kind = GregoryPatchSet.kind
    else:
        raise FormatError(path, f"cannot store patches of type {type(patches).__name__}")
    arrays: dict[str, NDArray[Any]] = {"patch_kind": np.array(kind), **patches.to_arrays()}
    arrays.update({name: getattr(network, name) for name in (*_ARRAYS, "seam")})
    for name in ("vertices", "vertex_normals", "uv"):
        if getattr(network, name) is not None:
            arrays[name] = getattr(network, name)
    if network.hanging is not None and len(network.hanging):
        arrays["hanging_sides"] = network.hanging.sides
        arrays["hanging_span"] = network.hanging.span
    if network.groups is not None:
        names = json.dumps(list(network.groups.names), ensure_ascii=False)
        if len(names.encode()) > MAX_GROUP_NAMES_BYTES:
            raise FormatError(
                path,
                f"cannot store this network: its group names take {len(names.encode())} bytes, "
                f"above the cap of {MAX_GROUP_NAMES_BYTES}",
            )
        arrays["group"] = network.groups.ids
        arrays["group_names"] = np.array(names)
        arrays["group_colour"] = network.groups.colours
    arrays = _Checker(target, "cannot store this network: ").check(arrays)
    provenance = {str(k): str(v) for k, v in network.provenance.items()}
    header = {"format": "g1patch-network", "version": FORMAT_VERSION, "provenance": provenance}
    return target, {"header": np.array(json.dumps(header)), **arrays}


def _write_members(target: Path, members: dict[str, NDArray[Any]]) -> None:
    with atomic_path(target) as temporary:
        with open(temporary, "wb") as handle:
            _write_stored_zip(handle, members)


# zip records (PKWARE APPNOTE 4.3): local header, central header, zip64 end record and locator, end
# record
_LOCAL = struct.Struct("<4sHHHHHIIIHH")
_LOCAL_ZIP64 = struct.Struct("<HHQQ")
_CENTRAL = struct.Struct("<4sBBBBHHHHIIIHHHHHII")
_CENTRAL_ZIP64 = struct.Struct("<HHQQQ")
_END64 = struct.Struct("<4sQHHIIQQQQ")
_LOCATOR64 = struct.Struct("<4sIQI")
_END = struct.Struct("<4sHHHHIIH")
_ZIP64_VERSION = 45
_DOS_DATE = (
    (0 << 9) | (1 << 5) | 1
)  # 1980-01-01, as zipfile dates entries without one: files are reproducible
_UNIX_FILE = 0o100644 << 16
_FULL32 = 0xFFFFFFFF


def _as_bytes(array: NDArray[Any]) -> memoryview:
    """The C-ordered bytes of ``array`` without a copy where it is contiguous."""
    return np.ascontiguousarray(array).reshape(-1).view(np.uint8).data


def _crc(header: bytes, data: memoryview) -> int:
    return zlib.crc32(data, zlib.crc32(header))  # releases the GIL on large buffers


def _crc_step(running: list[int], data: memoryview) -> int:
    """The CRC-32 of everything so far, ``running[0]``, extended by ``data`` (steps run in
    order)."""
    running[0] = zlib.crc32(data, running[0])
    return running[0]


def _write_stored_zip(handle: BinaryIO, members: Mapping[str, NDArray[Any]]) -> None:
    """A zip64 archive of ``.npy`` members, uncompressed, as ``np.savez`` writes it, but each member
    written straight from the array's memory while a second thread computes its CRC-32; the local
    headers get their CRCs when the data is written (zipfile computes it in the writing thread)."""
    entries: list[tuple[bytes, int, int, Future[int]]] = []
    with ThreadPoolExecutor(max_workers=1) as crc_thread:
        for name, array in members.items():
            npy = io.BytesIO()
            np.lib.format.write_array_header_1_0(
                npy, np.lib.format.header_data_from_array_1_0(array)
            )
            header, data = npy.getvalue(), _as_bytes(array)
            size = len(header) + data.nbytes
            filename = f"{name}.npy".encode("ascii")
            offset = handle.tell()
            handle.write(
                _LOCAL.pack(
                    b"PK\x03\x04",
                    _ZIP64_VERSION,
                    0,
                    0,
                    0,
                    _DOS_DATE,
                    0,
                    _FULL32,
                    _FULL32,
                    len(filename),
                    _LOCAL_ZIP64.size,
                )
            )
            handle.write(filename)
            handle.write(_LOCAL_ZIP64.pack(1, 16, size, size))
            crc = crc_thread.submit(_crc, header, data)
            handle.write(header)
            handle.write(data)
            entries.append((filename, offset, size, crc))
        end_of_data = handle.tell()
        for _, offset, _, crc in entries:
            handle.seek(offset + 14)  # the CRC field of the local header
            handle.write(struct.pack("<I", crc.result()))
    handle.seek(end_of_data)
    directory = io.BytesIO()
    for filename, offset, size, crc in entries:
        directory.write(
            _CENTRAL.pack(
                b"PK\x01\x02",
                _ZIP64_VERSION,
                3,
                _ZIP64_VERSION,
                0,
                0,
                0,
                0,
                _DOS_DATE,
                crc.result(),
                _FULL32,
                _FULL32,
                len(filename),
                _CENTRAL_ZIP64.size,
                0,
                0,
                0,
                _UNIX_FILE,
                _FULL32,
            )
        )
        directory.write(filename)
        directory.write(_CENTRAL_ZIP64.pack(1, 24, size, size, offset))
    count, listing = len(entries), directory.getvalue()
    handle.write(listing)
    end64 = end_of_data + len(listing)
    handle.write(
        _END64.pack(
            b"PK\x06\x06",
            _END64.size - 12,
            _ZIP64_VERSION,
            _ZIP64_VERSION,
            0,
            0,
            count,
            count,
            len(listing),
            end_of_data,
        )
    )
    handle.write(_LOCATOR64.pack(b"PK\x06\x07", 0, end64, 1))
    handle.write(
        _END.pack(
            b"PK\x05\x06",
            0,
            0,
            min(count, 0xFFFF),
            min(count, 0xFFFF),
            min(len(listing), _FULL32),
            min(end_of_data, _FULL32),
            0,
        )
    )
