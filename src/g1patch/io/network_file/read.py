"""Reading a network file: the zip's directory and every member's header checked against the
file's size before anything is allocated, then the arrays (:func:`load_network`)."""

from __future__ import annotations

import io
import json
import math
import os
import struct
import zipfile
import zlib
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path
from typing import Any, BinaryIO

import numpy as np
from numpy.typing import NDArray

from ...errors import FormatError, InputError
from ...gregory import GregoryPatchSet
from ...mesh.groups import FaceGroups
from ...network import HangingEdges, PatchNetwork
from ...patches import PatchSet
from .schema import (
    _ARRAYS,
    _BOOL_ARRAYS,
    _FLOAT_ARRAYS,
    _INDEX_ARRAYS,
    _KIND_ARRAYS,
    _MAX_NAME_BYTES,
    _MESH_SUFFIXES,
    _NETWORK,
    _NPY_HEADER_BYTES,
    _READ_STEP,
    _SHAPES,
    _STRING_ARRAYS,
    _SUFFIX_KINDS,
    FRAME_VERSION,
    GROUP_ARRAYS,
    GROUP_VERSION,
    HANGING_ARRAYS,
    HANGING_VERSION,
    MAX_BYTES,
    MAX_GROUP_NAMES_BYTES,
    MAX_HEADER_BYTES,
    MAX_PATCHES,
    PER_PATCH_BYTES,
    READABLE_VERSIONS,
    SEAM_VERSION,
    UV_VERSION,
)
from .values import _Checker
from .write import _crc_step

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

    def __init__(self, source: Path, handle: io.BufferedReader, archive: zipfile.ZipFile) -> None:
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
        view = array.reshape(-1, order="A").view(np.uint8).data if array.size else memoryview(b"")
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
        if version < UV_VERSION:  # no texture coordinates: an array of that name is not part of it
            ignored.add("uv")
        if version < HANGING_VERSION:  # no hanging edges: arrays of those names are not part of it
            ignored.update(HANGING_ARRAYS)
        if version < GROUP_VERSION:  # no face groups: arrays of those names are not part of it
            ignored.update(GROUP_ARRAYS)
        required = (
            "patch_kind",
            *_KIND_ARRAYS[kind],
            *_ARRAYS,
            *(("seam",) if version >= SEAM_VERSION else ()),
        )
        optional = {
            "header",
            "vertices",
            "vertex_normals",
            "frame_centre",
            "frame_scale",
            "uv",
            *HANGING_ARRAYS,
            *GROUP_ARRAYS,
        } - ignored
        missing = [name for name in required if name not in members]
        hanging = [name for name in HANGING_ARRAYS if name in members and name not in ignored]
        if len(hanging) == 1:
            missing.append(next(n for n in HANGING_ARRAYS if n not in hanging))
        groups = [name for name in GROUP_ARRAYS if name in members and name not in ignored]
        if 0 < len(groups) < len(GROUP_ARRAYS):
            missing.extend(n for n in GROUP_ARRAYS if n not in groups)
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
        for name, dim in (
            ("edge_collapsed", "E"),
            ("vertices", "V"),
            ("vertex_normals", "V"),
            ("hanging_sides", "H"),
            ("group_colour", "G"),
        ):
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
        for dim, name in (("E", "edge_collapsed"), ("V", "vertices"), ("H", "hanging_sides")):
            if dims.get(dim, 0) > 4 * count:
                raise self.fail(
                    f"member '{name}.npy' has {dims[dim]} rows, more than 4 per patch ({4 * count})"
                )
        # the names have a cap of their own (check_cap)
        total = sum(m.info.file_size for m in wanted.values() if m.name != "group_names")
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
                seam=arrays.get("seam"),  # type: ignore[arg-type]  # None: no seams
                uv=arrays.get("uv"),
                hanging=(
                    HangingEdges(arrays["hanging_sides"], arrays["hanging_span"])
                    if "hanging_sides" in arrays
                    else None
                ),
                groups=(
                    FaceGroups(
                        arrays["group"],
                        _Checker(self.source, "").group_names(arrays["group_names"]),
                        arrays["group_colour"],
                    )
                    if "group" in arrays
                    else None
                ),
                provenance={str(k): str(v) for k, v in provenance.items()},
            )
        except (InputError, KeyError) as exc:
            raise self.fail(f"corrupt network file: {exc}") from None

    def check_cap(self, member: _Member, patches: int, qualifier: str) -> None:
        """``member``'s declared size against the most its role allows a network of ``patches``
        patches."""
        shape = _SHAPES[member.name]
        rows = {"P": patches, "E": 4 * patches, "V": 4 * patches, "H": 4 * patches}
        rows["G"] = 4 * patches
        elements = math.prod(rows[d] if isinstance(d, str) else d for d in shape)
        strings = MAX_GROUP_NAMES_BYTES if member.name == "group_names" else _MAX_NAME_BYTES
        cap = _NPY_HEADER_BYTES + (elements * 8 if member.name not in _STRING_ARRAYS else strings)
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
