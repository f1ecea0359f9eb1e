"""The native network file: ``.npz`` with a format version, patches and their sharing arrays.

Contents
--------
A zip archive of ``.npy`` members, the container ``numpy.savez`` writes (``numpy.load`` reads
it): ``header`` (a 0-d string, the JSON ``{"format": "g1patch-network", "version": …,
"provenance": {…}}``), ``patch_kind`` (``"bicubic"`` or ``"gregory"``), the patches' arrays
(:meth:`PatchSet.to_arrays`: ``control`` and ``form``; :meth:`GregoryPatchSet.to_arrays`:
``points``), the sharing arrays of :class:`PatchNetwork` (``corner_ids``, ``edge_ids``,
``edge_reversed``, ``neighbor``, ``neighbor_edge``, ``same_direction``, ``edge_collapsed``,
``seam``) and, when the network has them, ``vertices`` and ``vertex_normals``.

Version 2 stores the patches in their local coordinates and, when they have one, their frame as
the arrays ``frame_centre`` (3,) and ``frame_scale`` () (see :mod:`g1patch.frame`): the file holds
exactly the numbers the construction made. Version 3 adds ``seam`` (P, 4) bool, the patch edges
that are sharp on purpose (:attr:`PatchNetwork.seam`). Version 1 files (no frame) and version 2
files (no seams) are read as before: seam-free.

Container: stored, not compressed
---------------------------------
Measured by ``benchmarks/bench_files.py`` on a 1 M-quad Gregory network
(``build_network(shapes.large_torus(1_000_000))``: 1 000 000 patches, 670 MB of arrays), best of 3
on the shared 2-core development machine, every format read back by :func:`load_network`:

======================================  ========  ========  ========  =========
container                               size      save      load      build
======================================  ========  ========  ========  =========
``np.savez_compressed`` (until now)      324 MB    42.3 s     6.6 s    10.7 s
zipfile ``ZIP_DEFLATED``, level 1        328 MB    19.1 s    15.7 s    10.7 s
``np.savez`` (``ZIP_STORED``)            670 MB     1.19 s    0.93 s   10.7 s
this module (stored, see below)          670 MB     0.77 s    0.74 s   10.7 s
======================================  ========  ========  ========  =========

The machine was shared with other jobs (load 3–6 on its 2 cores) and first touches of fresh
memory are slow and erratic in its VM, so figures spread between runs: over four runs this
module saved in 0.71–1.87 s and loaded in 0.74–2.17 s, ``np.savez_compressed`` saved in 38–45 s
(20.7 s and a 2.9 s load in a quieter hour, when ``build`` took 33 s). Compression halves the
file and costs 25–50× the time to save: float64 control points with busy mantissas deflate by
2:1 at best, at ~35 MB/s even at level 1. So members are stored (``ZIP_STORED``): each ``.npy``
member is written straight from the array's memory (no copy) while a second thread computes its
CRC-32, and read back with ``readinto`` at its offset in 64 MB steps, each step's CRC computed on a
second thread while the next is read and the arrays are validated.
Arrays keep the dtypes :class:`PatchNetwork` holds (int64 indices, so loading allocates nothing
but the arrays themselves). The container is unchanged — a zip of ``.npy`` members, what
``np.load`` reads — so the version stays 3, and compressed files (every earlier release's) are
still read.

Loading validates, before and after reading
-------------------------------------------
Nothing is decompressed or allocated before the zip directory and the ``.npy`` headers agree with
a network: every member must be a known ``.npy`` array of this version (stored or deflated, not
encrypted, named once); its declared size (``ZipInfo.file_size``) is capped, and must equal its
``.npy`` header plus shape × itemsize. The caps, checked in this order:

* absolute: :data:`MAX_BYTES` (8 GiB) per member and in all, :data:`MAX_PATCHES` (2²³ patches);
  the JSON header at most :data:`MAX_HEADER_BYTES` (1 MiB), the other strings 1 KiB;
* per patch: with ``P`` patches (at most ``corner_ids``' size / 4 bytes before its ``.npy``
  header is read, exactly its first axis after), every array has the shape its role gives
  (``(P, 4)``, ``(P, 20, 3)``, ``(P, 4, 4, 3)``, ``(E,)`` and ``(V, 3)`` with E, V ≤ 4 P, ``(3,)``,
  ``()``) at most 8 bytes an element, so a file holds at most ``PER_PATCH_BYTES`` (1 KiB) of arrays
  per patch plus the headers (a Gregory network takes 670 bytes a patch), checked in all too. A
  member declaring more is refused by name with its claimed size: a zip bomb is refused before it
  expands.

Then the values, vectorised (one pass of ``min``/``max`` per array, no loop over patches):
integer arrays of an integer type, boolean arrays of type bool holding only 0 and 1 bytes,
coordinates of a floating type; ``corner_ids`` in ``0..V−1`` (``0..4P−1`` without vertices),
``edge_ids`` in ``0..E−1``, ``neighbor`` in ``−1..P−1``, ``neighbor_edge`` in ``−1..3``, −1 in both
at the same places, every neighbour pointing back and naming the same edge id; every coordinate
(control points, Gregory points, vertices, their normals, the frame centre) finite and of
magnitude at most :data:`MAX_COORDINATE` = 1e30, in world coordinates (``|c| + s·max|x|`` with a
frame, whose scale must be positive and at most the bound). 1e30 mm is larger than the observable
universe, and keeps every power the numerics form finite: the check and OpenCASCADE's G1
measurement square the cross product of two unnormalised normals, an eighth power of the
coordinates (1e240 here; at 1e40 the check overflows, measured). Any violation is one
:class:`FormatError` naming the file, the member and the problem. A file of another kind (a mesh, a
``.bpt``, a text file renamed ``.npz``, anything not a zip archive) is refused with what was
expected instead. :func:`save_network` runs the same checks first, so it never writes a file it
would not read.
"""

from __future__ import annotations

import io
import json
import math
import os
import struct
import zipfile
import zlib
from collections.abc import Mapping
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path
from typing import Any, BinaryIO

import numpy as np
from numpy.typing import NDArray

from ..errors import FormatError, InputError
from ..frame import Frame
from ..gregory import GregoryPatchSet
from ..network import PatchNetwork
from ..patches import PatchSet
from .atomic import atomic_path

__all__ = [
    "FORMAT_VERSION",
    "READABLE_VERSIONS",
    "MAX_COORDINATE",
    "MAX_PATCHES",
    "MAX_BYTES",
    "PER_PATCH_BYTES",
    "MAX_HEADER_BYTES",
    "save_network",
    "save_network_in_background",
    "load_network",
    "describe_file",
]

#: the version :func:`save_network` writes
FORMAT_VERSION = 3
#: the versions :func:`load_network` reads (1: no frame, 2: no seams)
READABLE_VERSIONS = (1, 2, 3)
_ARRAYS = (
    "corner_ids",
    "edge_ids",
    "edge_reversed",
    "neighbor",
    "neighbor_edge",
    "same_direction",
    "edge_collapsed",
)
#: the first version with a frame
FRAME_VERSION = 2
#: the first version with seams
SEAM_VERSION = 3

#: largest magnitude of a coordinate in world units (see the module docstring)
MAX_COORDINATE = 1e30
#: most patches a network file may hold
MAX_PATCHES = 2**23
#: most bytes of arrays, per member and in all
MAX_BYTES = 2**33
#: bytes of arrays a file may hold per patch, headers aside (a Gregory network needs ≈ 600)
PER_PATCH_BYTES = 1024
#: largest JSON header
MAX_HEADER_BYTES = 2**20
#: largest other string member (patch kind, form)
_MAX_NAME_BYTES = 1024
#: elements per chunk of the value checks: their temporaries stay in the cache
_CHUNK = 1 << 17
#: bytes per read of a stored member, whose CRC runs on the second thread while the next is read
_READ_STEP = 1 << 26
#: room for one ``.npy`` header (numpy reads at most 10 000 bytes of one) and its preamble
_NPY_HEADER_BYTES = 10_000 + 16

_INDEX_ARRAYS = ("corner_ids", "edge_ids", "neighbor", "neighbor_edge")
_BOOL_ARRAYS = ("edge_reversed", "same_direction", "edge_collapsed", "seam")
_FLOAT_ARRAYS = ("points", "control", "vertices", "vertex_normals", "frame_centre", "frame_scale")
_STRING_ARRAYS = ("header", "patch_kind", "form")
#: shape of every array member, by its dimensions: P patches, E edges, V vertices
_SHAPES: dict[str, tuple[str | int, ...]] = {
    "corner_ids": ("P", 4),
    "edge_ids": ("P", 4),
    "neighbor": ("P", 4),
    "neighbor_edge": ("P", 4),
    "edge_reversed": ("P", 4),
    "same_direction": ("P", 4),
    "seam": ("P", 4),
    "edge_collapsed": ("E",),
    "points": ("P", 20, 3),
    "control": ("P", 4, 4, 3),
    "vertices": ("V", 3),
    "vertex_normals": ("V", 3),
    "frame_centre": (3,),
    "frame_scale": (),
    "header": (),
    "patch_kind": (),
    "form": (),
}
_KIND_ARRAYS = {"bicubic": ("control", "form"), GregoryPatchSet.kind: ("points",)}

_NETWORK = "a network file (.npz) written by g1patch build"
_SUFFIX_KINDS = {
    ".obj": "a Wavefront OBJ mesh",
    ".ply": "a PLY mesh",
    ".stl": "an STL mesh",
    ".off": "an OFF mesh",
    ".bpt": "a Bézier patch file (.bpt)",
    ".step": "a STEP file",
    ".stp": "a STEP file",
    ".iges": "an IGES file",
    ".igs": "an IGES file",
    ".png": "a PNG picture",
    ".npy": "a single NumPy array (.npy)",
}
_MESH_SUFFIXES = (".obj", ".ply", ".stl", ".off")


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
    for name in ("vertices", "vertex_normals"):
        if getattr(network, name) is not None:
            arrays[name] = getattr(network, name)
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
    return memoryview(np.ascontiguousarray(array).reshape(-1).view(np.uint8))


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


# ----------------------------------------------------------------------------------- loading


def describe_file(path: Path, head: bytes) -> str | None:
    """What a file that is not a network file is, from its suffix and its first bytes ``head``;
    None when it may be one (a ``.npz`` zip archive)."""
    suffix = path.suffix.lower()
    if suffix != ".npz":
        return _SUFFIX_KINDS.get(
            suffix, f"a {suffix} file" if suffix else "a file without the .npz extension"
        )
    if not head:
        return "an empty file"
    if head.startswith((b"PK\x03\x04", b"PK\x05\x06")):
        return None
    if head.startswith(b"\x93NUMPY"):
        return "a single NumPy array (.npy)"
    try:
        text = head.decode("utf-8")
    except UnicodeDecodeError as exc:
        if exc.start < len(head) - 4:  # not only a character cut at the end of the sample
            return "not a zip archive"
        text = head[: exc.start].decode("utf-8")
    return "a text file" if "\x00" not in text else "not a zip archive"


def load_network(path: str | os.PathLike[str], *, expects: str | None = None) -> PatchNetwork:
    """Read and validate a network written by :func:`save_network` (any readable version).

    Every violation — not a network file, a damaged archive, a member too large for the network it
    describes, a wrong dtype or shape, an index out of range, a coordinate that is not finite or
    beyond :data:`MAX_COORDINATE` — raises one :class:`FormatError` naming ``path``, the member and
    the problem (module docstring). ``expects`` phrases what the caller wanted, for files of another
    kind (default: "expected a network file (.npz) written by g1patch build"; the CLI passes e.g.
    "export expects a network file (.npz) written by g1patch build").
    """
    source = Path(path)
    wanted = expects or f"expected {_NETWORK}"
    try:
        handle = open(source, "rb")
    except FileNotFoundError:
        raise FormatError(source, "no such file") from None
    except IsADirectoryError:
        raise FormatError(source, f"is a directory; {wanted}") from None
    except OSError as exc:
        raise FormatError(source, f"cannot read: {exc.strerror}") from None
    with handle:
        other = describe_file(source, handle.read(512))
        if other is not None:
            hint = (
                f" (make one from it: g1patch build {source} -o {source.with_suffix('.npz')})"
                if source.suffix.lower() in _MESH_SUFFIXES
                else ""
            )
            raise FormatError(source, f"not a g1patch network file but {other}; {wanted}{hint}")
        try:
            archive = zipfile.ZipFile(handle)
        # zipfile parses untrusted bytes: BadZipFile, NotImplementedError, struct.error, …
        except Exception as exc:
            raise FormatError(
                source, f"not a g1patch network file (a damaged or truncated zip archive: {exc})"
            ) from None
        with archive:
            return _Reader(source, handle, archive).network()


@dataclass
class _Member:
    """One ``.npy`` member: its zip entry and, once read, its ``.npy`` header."""

    name: str
    info: zipfile.ZipInfo
    shape: tuple[int, ...] = ()
    dtype: np.dtype[Any] = np.dtype(np.float64)
    fortran: bool = False
    npy_header: bytes = b""  # the .npy preamble and header, for the CRC of a stored member
    header_length: int = 0  # bytes of that preamble and header
    data_offset: int = -1  # where the array's bytes start in the file (stored members)


def _size(count: int) -> str:
    """``count`` bytes, readably."""
    for unit, step in (("GB", 1e9), ("MB", 1e6), ("kB", 1e3)):
        if count >= step:
            return f"{count / step:.1f} {unit} ({count} bytes)"
    return f"{count} bytes"


class _Reader:
    """Reads one archive: directory, ``.npy`` headers, caps, data, values (the module docstring's
    order)."""

    def __init__(self, source: Path, handle: BinaryIO, archive: zipfile.ZipFile) -> None:
        self.source, self.handle, self.archive = source, handle, archive
        self.file_size = os.fstat(handle.fileno()).st_size

    def fail(self, message: str) -> FormatError:
        return FormatError(self.source, message)

    # -------------------------------------------------------------- the zip directory
    def directory(self) -> dict[str, _Member]:
        members: dict[str, _Member] = {}
        total = 0
        for info in self.archive.infolist():
            label = info.filename
            if not label.endswith(".npy"):
                raise self.fail(
                    f"not a g1patch network file (member {label!r} is not a .npy array)"
                )
            name = label[:-4]
            if name in members:
                raise self.fail(f"corrupt network file: member {label!r} appears twice")
            if info.flag_bits & 0x1:
                raise self.fail(f"member {label!r} is encrypted")
            if info.compress_type not in (zipfile.ZIP_STORED, zipfile.ZIP_DEFLATED):
                raise self.fail(
                    f"member {label!r} uses zip compression method {info.compress_type}; "
                    f"network files are stored or deflated"
                )
            if info.file_size > MAX_BYTES:
                raise self.fail(
                    f"member {label!r} declares {_size(info.file_size)} uncompressed, above the "
                    "cap of "
                    f"{_size(MAX_BYTES)} per member"
                )
            total += info.file_size
            members[name] = _Member(name, info)
        if total > MAX_BYTES:
            raise self.fail(
                f"the members declare {_size(total)} uncompressed in all, above the cap of "
                f"{_size(MAX_BYTES)}"
            )
        return members

    # -------------------------------------------------------------- raw member access
    def stream(self, member: _Member) -> BinaryIO:
        try:
            return self.archive.open(member.info)  # type: ignore[return-value]
        except (
            zipfile.BadZipFile,
            OSError,
            ValueError,
            EOFError,
            NotImplementedError,
            RuntimeError,
        ) as exc:
            raise self.fail(f"member {member.info.filename!r} cannot be read ({exc})") from None

    def read_npy_header(self, member: _Member) -> None:
        """Shape, dtype and order from the ``.npy`` header: reads at most ~10 kB of the member."""
        label = member.info.filename
        try:
            if member.info.compress_type == zipfile.ZIP_STORED:
                start = self.stored_start(member)
                self.handle.seek(start)
                stream: BinaryIO = self.handle
            else:
                start, stream = 0, self.stream(member)
            version = np.lib.format.read_magic(stream)
            if version == (1, 0):
                shape, fortran, dtype = np.lib.format.read_array_header_1_0(stream)
            elif version == (2, 0):
                shape, fortran, dtype = np.lib.format.read_array_header_2_0(stream)
            else:
                raise ValueError(f".npy format version {version[0]}.{version[1]} is not read here")
            length = stream.tell() - start
            if member.info.compress_type == zipfile.ZIP_STORED:
                self.handle.seek(start)
                member.npy_header = self.handle.read(length)
                member.data_offset = start + length
            else:
                stream.close()
        except FormatError:
            raise
        except (
            Exception
        ) as exc:  # numpy parses the header with ast (SyntaxError, TokenError, ValueError, …)
            raise self.fail(
                f"member {label!r}: not a readable .npy array "
                f"({str(exc).splitlines()[0] if str(exc) else type(exc).__name__})"
            ) from None
        if dtype.hasobject or dtype.fields is not None or dtype.subdtype is not None:
            raise self.fail(
                f"member {label!r} holds {dtype} values (Python objects or records); network "
                "files hold plain numbers and strings"
            )
        member.shape, member.dtype, member.fortran = (
            tuple(int(n) for n in shape),
            dtype,
            bool(fortran),
        )
        member.header_length = length
        declared = length + math.prod(member.shape) * dtype.itemsize
        if declared != member.info.file_size:
            raise self.fail(
                f"member {label!r}: its .npy header describes {dtype} {member.shape} "
                f"({_size(declared)}), "
                f"but the zip directory says {_size(member.info.file_size)}"
            )

    def stored_start(self, member: _Member) -> int:
        """Offset of a stored member's bytes, from its local header; truncation is named."""
        info = member.info
        self.handle.seek(info.header_offset)
        local = self.handle.read(30)
        if len(local) < 30 or local[:4] != b"PK\x03\x04":
            raise self.fail(
                f"corrupt network file: the local header of member {info.filename!r} is missing "
                "(truncated?)"
            )
        name_length, extra_length = struct.unpack("<HH", local[26:30])
        start = info.header_offset + 30 + name_length + extra_length
        if info.compress_size != info.file_size:
            raise self.fail(
                f"corrupt network file: stored member {info.filename!r} has compressed size "
                f"{info.compress_size} ≠ its size {info.file_size}"
            )
        if start + info.file_size > self.file_size:
            raise self.fail(
                f"truncated: member {info.filename!r} needs bytes "
                f"{start}..{start + info.file_size} "
                f"of the file, which has {self.file_size}"
            )
        return start

    def read_data(
        self,
        member: _Member,
        crc_thread: ThreadPoolExecutor,
        crcs: list[tuple[_Member, Future[int]]],
    ) -> NDArray[Any]:
        """The array of ``member`` (shape and size already checked); a stored member's CRC is
        queued."""
        shape, dtype = member.shape, member.dtype
        array = np.empty(shape[::-1], dtype).T if member.fortran else np.empty(shape, dtype)
        view = (
            memoryview(array.reshape(-1, order="A").view(np.uint8))
            if array.size
            else memoryview(b"")
        )
        label = member.info.filename
        if member.info.compress_type == zipfile.ZIP_STORED:
            # read in steps, each step's CRC queued as it arrives: the one CRC thread runs them in
            # order, chaining the running value, while the next step is read
            self.handle.seek(member.data_offset)
            running = [zlib.crc32(member.npy_header)]
            crc: Future[int] = crc_thread.submit(lambda: running[0])
            done = 0
            while done < view.nbytes:
                got = self.handle.readinto(view[done : done + _READ_STEP])
                if not got:
                    raise self.fail(
                        f"truncated: member {label!r} ends after {done} of {view.nbytes} bytes"
                    )
                crc = crc_thread.submit(_crc_step, running, view[done : done + got])
                done += got
            crcs.append((member, crc))
            return array
        try:
            with self.stream(member) as stream:
                stream.read(member.header_length)
                done, step = 0, 1 << 24
                while done < view.nbytes:
                    chunk = stream.readinto(view[done : done + step])  # type: ignore[attr-defined]
                    if not chunk:
                        raise EOFError("the data ends early")
                    done += chunk
                stream.read(1)  # reaching the end checks the CRC
        except (
            zipfile.BadZipFile,
            EOFError,
            OSError,
            zlib.error,
            ValueError,
            NotImplementedError,
        ) as exc:
            raise self.fail(
                f"corrupt network file: member {label!r} cannot be decompressed ({exc})"
            ) from None
        return array

    def read_string(self, member: _Member, cap: int) -> str:
        label = member.info.filename
        if member.info.file_size > cap + _NPY_HEADER_BYTES:
            raise self.fail(
                f"member {label!r} declares {_size(member.info.file_size)}, above the cap of "
                f"{_size(cap)} for it"
            )
        self.read_npy_header(member)
        if member.shape != () or member.dtype.kind != "U":
            raise self.fail(
                f"member {label!r}: expected one string, got {member.dtype} {member.shape}"
            )
        with ThreadPoolExecutor(max_workers=1) as crc_thread:
            crcs: list[tuple[_Member, Future[int]]] = []
            value = self.read_data(member, crc_thread, crcs)
            self.check_crcs(crcs)
        return str(value)

    def check_crcs(self, crcs: list[tuple[_Member, Future[int]]]) -> None:
        for member, crc in crcs:
            if crc.result() != member.info.CRC:
                raise self.fail(
                    f"corrupt network file: member {member.info.filename!r} fails its CRC check"
                )

    # -------------------------------------------------------------- the network
    def network(self) -> PatchNetwork:
        members = self.directory()
        if "header" not in members:
            raise self.fail("not a g1patch network file (no header)")
        try:
            header = json.loads(self.read_string(members["header"], MAX_HEADER_BYTES))
        except json.JSONDecodeError:
            raise self.fail("not a g1patch network file (its header is not JSON)") from None
        if not isinstance(header, dict) or header.get("format") != "g1patch-network":
            raise self.fail("not a g1patch network file (wrong header)")
        version = header.get("version")
        if isinstance(version, bool) or version not in READABLE_VERSIONS:
            readable = ", ".join(map(str, READABLE_VERSIONS))
            raise self.fail(
                f"network format version {version!r} is not supported (this g1patch reads "
                f"{readable})"
            )
        version = int(version)
        provenance = header.get("provenance", {})
        if not isinstance(provenance, dict) or not all(
            v is None or isinstance(v, (str, int, float)) for v in provenance.values()
        ):
            raise self.fail("corrupt network file: header: provenance must map names to strings")
        if "patch_kind" not in members:
            raise self.fail("network file lacks patch_kind")
        kind = self.read_string(members["patch_kind"], _MAX_NAME_BYTES)
        if kind not in _KIND_ARRAYS:
            raise self.fail(f"unknown patch kind {kind!r}")

        # which members this version and kind have
        ignored = set()
        if (
            version < FRAME_VERSION
        ):  # version 1 has no frame: arrays of that name are not part of it
            ignored |= {"frame_centre", "frame_scale"}
        if version < SEAM_VERSION:  # seam-free: an array of that name is not part of it
            ignored.add("seam")
        required = (
            "patch_kind",
            *_KIND_ARRAYS[kind],
            *_ARRAYS,
            *(("seam",) if version >= SEAM_VERSION else ()),
        )
        optional = {"header", "vertices", "vertex_normals", "frame_centre", "frame_scale"} - ignored
        missing = [name for name in required if name not in members]
        if missing:
            raise self.fail(f"network file lacks {', '.join(missing)}")
        unexpected = [
            m.info.filename
            for name, m in members.items()
            if name not in (*required, *optional, *ignored)
        ]
        if unexpected:
            raise self.fail(
                f"corrupt network file: unexpected member {unexpected[0]!r} in a version "
                f"{version} {kind} network file"
            )
        wanted = {
            name: m
            for name, m in members.items()
            if name not in ignored and name not in ("header", "patch_kind")
        }

        # caps from the directory alone: P ≤ corner_ids' size / 4 (an element is at least 1 byte)
        bound = min(MAX_PATCHES, wanted["corner_ids"].info.file_size // 4)
        for member in wanted.values():
            self.check_cap(member, bound, "at most ")
        # the .npy headers: exact shapes
        for member in wanted.values():
            self.read_npy_header(member)
        corner = wanted["corner_ids"]
        if len(corner.shape) != 2 or corner.shape[1] != 4:
            raise self.fail(f"member 'corner_ids.npy': expected shape (P, 4), got {corner.shape}")
        count = corner.shape[0]
        if not 1 <= count <= MAX_PATCHES:
            raise self.fail(
                f"member 'corner_ids.npy' claims {count} patches; network files hold 1 to "
                f"{MAX_PATCHES}"
            )
        dims = {"P": count}
        for name, dim in (("edge_collapsed", "E"), ("vertices", "V"), ("vertex_normals", "V")):
            if name in wanted and len(wanted[name].shape) == len(_SHAPES[name]):
                dims.setdefault(dim, wanted[name].shape[0])
        for member in wanted.values():
            self.check_dtype(member)
            self.check_cap(member, count, "")
            if member.name.startswith("frame_"):
                continue  # the frame's shapes are checked with its values (Frame.from_arrays)
            template = _SHAPES[member.name]
            expected = tuple(dims.get(d, -1) if isinstance(d, str) else d for d in template)
            if member.shape != expected:
                text = (
                    "(" + ", ".join(map(str, template)) + ("," if len(template) == 1 else "") + ")"
                )
                raise self.fail(
                    f"member {member.info.filename!r}: expected shape {text} = {expected} for "
                    f"{count} patches, got {member.shape}"
                )
        for dim in ("E", "V"):
            if dims.get(dim, 0) > 4 * count:
                name = "edge_collapsed" if dim == "E" else "vertices"
                raise self.fail(
                    f"member '{name}.npy' has {dims[dim]} rows, more than 4 per patch ({4 * count})"
                )
        total = sum(member.info.file_size for member in wanted.values())
        budget = PER_PATCH_BYTES * count + _NPY_HEADER_BYTES * len(wanted)
        if total > budget:
            raise self.fail(
                f"the arrays declare {_size(total)} in all, more than the {_size(budget)} a "
                "network of "
                f"{count} patches may hold ({PER_PATCH_BYTES} bytes a patch)"
            )

        # the data, CRCs on a second thread while the values are checked
        try:
            with ThreadPoolExecutor(max_workers=1) as crc_thread:
                crcs: list[tuple[_Member, Future[int]]] = []
                arrays: dict[str, Any] = {"patch_kind": np.array(kind)}
                for name, member in wanted.items():
                    arrays[name] = self.read_data(member, crc_thread, crcs)
                if "form" in arrays:
                    arrays["form"] = np.array(str(arrays["form"]))
                arrays = _Checker(self.source, "").check(arrays)
                self.check_crcs(crcs)
        except MemoryError:
            total = sum(m.info.file_size for m in wanted.values())
            raise self.fail(
                f"not enough memory to load its {count} patches ({_size(total)} of arrays)"
            ) from None
        try:
            patches = (
                PatchSet.from_arrays(arrays)
                if kind == "bicubic"
                else GregoryPatchSet.from_arrays(arrays)
            )
            return PatchNetwork(
                patches=patches,
                **{name: arrays[name] for name in _ARRAYS},
                vertices=arrays.get("vertices"),
                vertex_normals=arrays.get("vertex_normals"),
                seam=arrays.get("seam"),
                provenance={str(k): str(v) for k, v in provenance.items()},
            )
        except (InputError, KeyError) as exc:
            raise self.fail(f"corrupt network file: {exc}") from None

    def check_cap(self, member: _Member, patches: int, qualifier: str) -> None:
        """``member``'s declared size against the most its role allows a network of ``patches``
        patches."""
        shape = _SHAPES[member.name]
        rows = {"P": patches, "E": 4 * patches, "V": 4 * patches}
        elements = math.prod(rows[d] if isinstance(d, str) else d for d in shape)
        cap = _NPY_HEADER_BYTES + (
            elements * 8 if member.name not in _STRING_ARRAYS else _MAX_NAME_BYTES
        )
        if member.info.file_size > cap:
            raise self.fail(
                f"member {member.info.filename!r} declares {_size(member.info.file_size)} "
                "uncompressed, more than "
                f"the {_size(cap)} it can take in a network of {qualifier}{patches} patches (from "
                "'corner_ids.npy')"
            )

    def check_dtype(self, member: _Member) -> None:
        dtype, label = member.dtype, member.info.filename
        if member.name in _INDEX_ARRAYS:
            ok, wanted = dtype.kind in "iu" and dtype.itemsize <= 8, "integers"
        elif member.name in _BOOL_ARRAYS:
            ok, wanted = dtype.kind == "b", "booleans"
        elif member.name in _FLOAT_ARRAYS:
            ok, wanted = (
                dtype.kind == "f" and dtype.itemsize <= 8,
                "floating-point numbers of at most 64 bits",
            )
        else:
            ok, wanted = dtype.kind == "U", "a string"
        if not ok:
            raise self.fail(f"member {label!r}: expected {wanted}, got an array of {dtype}")


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
        for name in _BOOL_ARRAYS:
            if name in arrays:
                out[name] = self.booleans(name, arrays[name])
        extent = {}
        for name in _FLOAT_ARRAYS:
            if name in arrays and not name.startswith("frame_"):
                out[name], extent[name] = self.coordinates(name, arrays[name])
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
