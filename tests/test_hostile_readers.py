"""The standing hostile suite of the readers (issue 32): nothing a file says is trusted.

Every case the issue measured, and its siblings, through the command line (exit 2, one line on
stderr naming the file and the limit, no output, within 5 s) and in this process under tracemalloc
(the peak bounded by the file's size): a face list of 4e9 corners, a 290-byte PLY announcing 1e8
or 1e9 faces, ``/dev/zero`` (or a link to it, a FIFO, a folder) given as a mesh, faces beyond an
OFF header's count, a byte-order mark before a valid file, header counts beyond the file, negative
or overflowing int64, binary PLY cut inside an element, ``--max-input-size`` / ``max_input_size``.

Then the generator: Hypothesis draws edit programs (a base file, up to three edits, a seed saying
where and with what) and applies each to a small valid OBJ, OFF, ASCII PLY, binary PLY and ``.bpt``
file: header counts and list counts replaced by hostile numbers, the file cut, bytes flipped, junk
appended, lines dropped, repeated or inserted, numbers respelt, a BOM, CR LF. :func:`g1patch.read`
reads each in this process: a mesh or network without NaN, or one
:class:`~g1patch.errors.G1PatchError` whose one-line message names the file; never another
exception or a warning; within :data:`TIME_CAP` and a tracemalloc peak of at most
:data:`MEMORY_PER_BYTE` × its size + :data:`MEMORY_BASE` (the modules a first read imports loaded
before). :data:`PROGRAMS` programs × 5 kinds: 10,000 files every CI run (~25 s on 2 cores;
derandomized there, see conftest.py). Files of ~0.5 MB through every reader, valid and not, hold
the multiplier where the constant does not dominate.
"""

from __future__ import annotations

import functools
import os
import re
import struct
import tempfile
import time
import tracemalloc
import warnings
from collections.abc import Callable
from pathlib import Path

import fuzzing
import numpy as np
import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st
from test_hardening_files import refused
from test_readers import ply_bytes

import g1patch
from g1patch import shapes
from g1patch.errors import FormatError, G1PatchError, InputError
from g1patch.io.bpt import write_bpt
from g1patch.io.meshfile import MAX_INPUT_BYTES, read_mesh
from g1patch.io.meshfile.source import BOM
from g1patch.network import PatchNetwork
from g1patch.patches import PatchSet

#: seconds any one read may take (the issue's bound)
TIME_CAP = 5.0
#: tracemalloc's peak while a file is read: at most this many bytes a byte of the file (~30 at
#: most measured: a text file of short numbers read line by line, then validated) ...
MEMORY_PER_BYTE = 48
#: ... plus this much (the readers' fixed costs, ~60 kB measured; their modules imported before)
MEMORY_BASE = 1 << 20
#: edit programs drawn per CI run, each applied to a file of each of the 5 kinds: 10,000 files
PROGRAMS = 2_000
SQUARE = (
    np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [2, 0, 0], [2, 1, 0]], float),
    [[0, 1, 2, 3], [1, 4, 5, 2]],
)


def _text(suffix: str, vertices: np.ndarray, faces: list[list[int]]) -> bytes:
    return fuzzing._mesh_text(suffix, vertices, faces, [])


def _binary(faces: np.ndarray | list[list[int]], count: str = "u1", index: str = "i4") -> bytes:
    return ply_bytes(SQUARE[0], faces, "f4", count, index, "<", False)


def _face_at(data: bytes, face: int, count: int = 1, index: int = 4, corners: int = 4) -> int:
    """The byte of face ``face``'s count in a binary file of :func:`_binary` (float x, y, z)."""
    start = data.index(b"end_header\n") + 11 + 12 * len(SQUARE[0])
    return start + face * (count + corners * index)


def _set(data: bytes, at: int, value: bytes) -> bytes:
    return data[:at] + value + data[at + len(value) :]


def _dev_zero(tmp_path: Path, name: str) -> Path:
    if not os.path.exists("/dev/zero"):
        pytest.skip("no /dev/zero")
    (tmp_path / name).symlink_to("/dev/zero")
    return tmp_path / name


def _fifo(tmp_path: Path, name: str) -> Path:
    if not hasattr(os, "mkfifo"):
        pytest.skip("no FIFOs here")
    os.mkfifo(tmp_path / name)
    return tmp_path / name


def _file(name: str, data: bytes) -> Callable[[Path], Path]:
    def write(folder: Path) -> Path:
        (folder / name).write_bytes(data)
        return folder / name

    return write


def _list_count(count: str, face: int, value: bytes) -> bytes:
    """A binary square of :func:`_binary` with face ``face``'s list count (of type ``count``)
    replaced by ``value``."""
    data = _binary(np.array(SQUARE[1]), count)
    return _set(data, _face_at(data, face, np.dtype(count).itemsize), value)


_PLY = _binary(np.array(SQUARE[1]))
_ASCII_PLY = _text(".ply", *SQUARE)
_OFF = _text(".off", *SQUARE)
#: name: (what writes the file into a folder, what its one line must say)
CASES: dict[str, tuple[Callable[[Path], Path], str]] = {
    "1: list uint count 4e9": (
        _file("c.ply", _list_count("u4", 0, struct.pack("<I", 4_000_000_000))),
        "face 0 announces 4000000000 corners (its uint count at byte 253), 16000000004 bytes",
    ),
    "2: PLY announcing 1e8 faces": (
        _file("c.ply", _PLY.replace(b"element face 2", b"element face 100000000")),
        "announces 100000000 'face' elements of at least 13 bytes each",
    ),
    "2: PLY announcing 1e9 faces": (
        _file("c.ply", _PLY.replace(b"element face 2", b"element face 1000000000")),
        "13000000072 bytes (after 72 for the elements before them), but only 106 bytes",
    ),
    "2: ASCII PLY announcing 1e8 faces": (
        _file("c.ply", _ASCII_PLY.replace(b"element face 2", b"element face 100000000")),
        "'face' elements of at least 8 bytes each",
    ),
    "3: a link to /dev/zero": (
        lambda folder: _dev_zero(folder, "zero.obj"),
        "a character device (a link to /dev/zero), not a regular file",
    ),
    "3: a .bpt link to /dev/zero": (
        lambda folder: _dev_zero(folder, "zero.bpt"),
        "a character device",
    ),
    "3: a FIFO": (lambda folder: _fifo(folder, "pipe.off"), "a FIFO (named pipe)"),
    "3: a folder": (
        lambda folder: (folder / "folder.ply").mkdir() or folder / "folder.ply",
        "a directory, not a regular file",
    ),
    "4: OFF faces beyond the count": (
        _file("c.off", _OFF + b"4 3 2 1 0\n"),
        ":11: unexpected content after the 6 vertices and 2 faces",
    ),
    "4: ASCII PLY lines beyond the count": (
        _file("c.ply", _ASCII_PLY + b"4 3 2 1 0\n"),
        ":18: unexpected content after the 6 vertices and 2 faces",
    ),
    "4: binary PLY bytes beyond the count": (
        _file("c.ply", _PLY + b"\0\0"),
        "2 bytes after the last of the 2 faces the header announces",
    ),
    "OFF announcing 1e8 vertices": (
        _file("c.off", _OFF.replace(b"6 2 0", b"100000000 2 0")),
        "truncated: the header announces 100000000 vertices and 2 faces",
    ),
    "OFF counts beyond int64": (
        _file("c.off", _OFF.replace(b"6 2 0", b"6 99999999999999999999999 0")),
        "announces 6 vertices and 99999999999999999999999 faces",
    ),
    "OFF negative counts": (
        _file("c.off", _OFF.replace(b"6 2 0", b"-6 2 0")),
        ":2: expected the counts 'n_vertices n_faces n_edges' (integers ≥ 0), got '-6 2 0'",
    ),
    "PLY negative count": (
        _file("c.ply", _PLY.replace(b"element face 2", b"element face -2")),
        "(a count of at most 30 digits), got 'element face -2'",
    ),
    "PLY count beyond int64": (
        _file("c.ply", _PLY.replace(b"element vertex 6", b"element vertex 18446744073709551617")),
        "announces 18446744073709551617 'vertex' elements",
    ),
    "binary PLY cut inside a vertex": (
        _file("c.ply", _PLY[: _face_at(_PLY, 0) - 5]),
        "announces 6 'vertex' elements of at least 12 bytes each, 72 bytes, but only 67",
    ),
    "binary PLY cut inside a face": (
        _file("c.ply", _PLY[:-3]),
        "truncated: face 1 announces 4 corners (its uchar count at byte",
    ),
    "binary PLY negative list count": (
        _file("c.ply", _list_count("i4", 1, struct.pack("<i", -1))),
        "face 1 has a negative corner count -1",
    ),
    "binary PLY face of 2 corners": (
        _file("c.ply", _set(_PLY, _face_at(_PLY, 0), b"\x02")),
        "face 0 has 2 corners",
    ),
    "ASCII PLY list count above its indices": (
        _file("c.ply", _ASCII_PLY.replace(b"\n4 1 4 5 2", b"\n5 1 4 5 2")),
        ":17: expected a face 'n i_1 ... i_n' with n ≥ 3 and exactly n indices, got '5 1 4 5 2'",
    ),
    "ASCII PLY list count below its indices": (
        _file("c.ply", _ASCII_PLY.replace(b"\n4 1 4 5 2", b"\n3 1 4 5 2")),
        ":17: expected a face",
    ),
    "OFF index beyond int64": (
        _file("c.off", _OFF.replace(b"\n4 1 4 5 2", b"\n4 1 4 5 99999999999999999999")),
        ":10: expected a face 'n i_1 ... i_n' with n >= 3",
    ),
    ".bpt announcing 1e20 patches": (
        _file("c.bpt", b"100000000000000000000\n3 3\n" + b"0 0 0\n" * 16),
        "truncated: 100000000000000000000 patches need",
    ),
}


@pytest.fixture
def out(tmp_path: Path) -> Path:
    """An empty output folder: it must stay so."""
    (tmp_path / "out").mkdir()
    return tmp_path / "out"


def _argv(path: Path, out: Path) -> list[str]:
    """What reads ``path`` on the command line: build a mesh, check a .bpt."""
    if path.suffix == ".bpt":
        return ["check", str(path), "-q"]
    return ["build", str(path), "-o", str(out / "x.npz"), "-q"]


@functools.cache
def _warm() -> None:
    """Read a valid file of every kind once: what a first read imports is not the reader's."""
    with tempfile.TemporaryDirectory() as folder:
        for kind in KINDS:
            path = Path(folder) / f"warm{'.ply' if kind == 'binary' else kind}"
            path.write_bytes(BASES[kind][0])
            g1patch.read(path)


def _read_traced(path: Path) -> tuple[int, G1PatchError | None]:
    """``g1patch.read(path)`` under tracemalloc: its peak, and the g1patch error it raised."""
    _warm()
    tracemalloc.start()
    try:
        g1patch.read(path)
        error = None
    except G1PatchError as raised:
        error = raised
    finally:
        _, peak = tracemalloc.get_traced_memory()
        tracemalloc.stop()
    return peak, error


@pytest.mark.parametrize("name", sorted(CASES))
def test_every_case_is_one_line_exit_2_in_time(
    name: str, tmp_path: Path, out: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    write, says = CASES[name]
    path = write(tmp_path)
    start = time.perf_counter()
    refused(capsys, _argv(path, out), path, out, contains=says)
    assert time.perf_counter() - start <= TIME_CAP


@pytest.mark.parametrize("name", sorted(CASES))
def test_every_case_is_bounded_in_memory(name: str, tmp_path: Path) -> None:
    """In this process, the issue's cases allocate no more than their few bytes allow."""
    path = CASES[name][0](tmp_path)
    size = path.stat().st_size if path.is_file() else 0
    peak, error = _read_traced(path)
    assert isinstance(error, FormatError) and str(path) in str(error), error
    assert peak <= MEMORY_PER_BYTE * size + MEMORY_BASE, (peak, size)


# -- byte-order marks, the size cap ---------------------------------------------------------------


@pytest.mark.parametrize(
    "name,data",
    [
        ("m.obj", _text(".obj", *SQUARE)),
        ("m.off", _OFF),
        ("m.ply", _ASCII_PLY),
        ("m.ply", _PLY),
        ("m.ply", _ASCII_PLY.replace(b"float", b"double")),
    ],
)
def test_a_byte_order_mark_is_skipped(name: str, data: bytes, tmp_path: Path) -> None:
    plain, marked = tmp_path / name, tmp_path / f"bom-{name}"
    plain.write_bytes(data)
    marked.write_bytes(BOM + data)
    mesh, again = read_mesh(plain), read_mesh(marked)
    assert mesh.vertices.tobytes() == again.vertices.tobytes()
    assert np.array_equal(mesh.faces, again.faces)


def test_a_bpt_with_a_byte_order_mark(tmp_path: Path) -> None:
    write_bpt(tmp_path / "p.bpt", PatchSet(np.random.default_rng(3).normal(size=(2, 4, 4, 3))))
    marked = tmp_path / "bom.bpt"
    marked.write_bytes(BOM + (tmp_path / "p.bpt").read_bytes())
    assert np.array_equal(
        g1patch.read(marked).patches.control, g1patch.read(tmp_path / "p.bpt").patches.control
    )


def test_max_input_size_in_the_api(tmp_path: Path) -> None:
    path = tmp_path / "m.off"
    path.write_bytes(_OFF)
    assert g1patch.read(path, max_input_size=len(_OFF)).n_faces == 2
    cap = f"above the input size cap of {len(_OFF) - 1} bytes"
    with pytest.raises(FormatError, match=rf"m\.off: {len(_OFF)} bytes, {cap}"):
        g1patch.read(path, max_input_size=len(_OFF) - 1)
    with pytest.raises(FormatError, match=cap):
        g1patch.smooth(path, max_input_size=len(_OFF) - 1)
    for bad in (0, -1, 1.5, True, "1G"):
        with pytest.raises(InputError, match="max_input_size: expected a number of bytes"):
            g1patch.read(path, max_input_size=bad)  # type: ignore[arg-type]


def test_the_default_cap_refuses_before_reading(tmp_path: Path) -> None:
    """A (sparse) file one byte above the 2 GB default: refused at once, nothing read."""
    path = tmp_path / "huge.obj"
    with open(path, "wb") as handle:
        handle.truncate(MAX_INPUT_BYTES + 1)
    peak, error = _read_traced(path)
    assert isinstance(error, FormatError) and peak < 1 << 20
    assert "2 GB (2000000001 bytes), above the input size cap of 2 GB (2000000000 bytes)" in str(
        error
    )


@pytest.mark.parametrize("command", ["build", "batch"])
def test_max_input_size_on_the_command_line(
    command: str, tmp_path: Path, out: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "m.obj"
    path.write_bytes(_text(".obj", *SQUARE))
    argv = (
        ["build", str(path), "-o", str(out / "m.npz")]
        if command == "build"
        else ["batch", str(path), "--out", str(out)]
    )
    refused(
        capsys,
        [*argv, "--max-input-size", "50", "-q"],
        path,
        out,
        contains=f"{path.stat().st_size} bytes, above the input size cap of 50 bytes",
    )


# -- the generator --------------------------------------------------------------------------------

#: a square of two quads and a triangle on it: mixed corner counts
_MIXED = (np.vstack([SQUARE[0], [[1.5, 2.0, 0.0]]]), [*SQUARE[1], [2, 5, 6]])
_TYPES = [("f4", "u1", "i4"), ("f8", "i4", "u4"), ("f4", "u2", "i4"), ("f8", "u4", "i4")]
_TAGS = ["t corner 1/1/0 0 10", "t interpolateboundary 1/0/0 1"]
#: numbers a header or a list may claim
HOSTILE_INTS = [-(2**63), -1, 0, 1, 2, 3, 127, 128, 255, 256, 2**16, 2**31, 2**32 - 1, 2**32]
HOSTILE_INTS += [4_000_000_000, 10**8, 10**9, 2**63 - 1, 2**63, 2**64, 10**23]
#: tokens a number may be replaced by, besides those
HOSTILE_TOKENS = ["nan", "inf", "-inf", "1e309", "1e-400", "-0", "0x10", "1_0", "", "x", "٣", "１"]
HOSTILE_TOKENS += ["1e", "1" * 5000, "3.5", "+", "--1", "0" * 30 + "1", "4e9"]
#: what may be appended to a file or put between its lines
JUNK = [b"4 0 1 2 3\n", b"\n\n", b"0 0 0\n", b"f 1 2 3\n", b"3 3\n", BOM, b"\x00\xff", b"# c"]
JUNK += [b"comment x", b"v 1 2", b"end_header\n", b"element face 1"]
#: the edits: a count of the header replaced (anywhere in OBJ), any number respelt, the file cut,
#: bytes flipped, junk appended, a line dropped, repeated or inserted, CR LF, a BOM; binary PLY:
#: four bytes of the body (a list count, perhaps) set to a hostile number
EDITS = ("count", "number", "cut", "flip", "append", "drop", "repeat", "insert", "crlf", "bom")
KINDS = (".obj", ".off", ".ply", "binary", ".bpt")


def _meshes() -> list[tuple[np.ndarray, list[list[int]]]]:
    grid, cube, torus = shapes.grid(3, 2), shapes.cube(), shapes.torus(4, 3)
    return [
        (cube.vertices, cube.faces.tolist()),
        (grid.vertices, grid.faces.tolist()),
        (torus.vertices, torus.faces.tolist()),
        (shapes.fan(5).vertices, shapes.fan(5).faces.tolist()),
        _MIXED,
    ]


def _bases() -> dict[str, list[bytes]]:
    """Valid small files of each kind the generator edits."""
    meshes = _meshes()
    bases = {suffix: [_text(suffix, *mesh) for mesh in meshes] for suffix in (".off", ".ply")}
    bases[".obj"] = [fuzzing._mesh_text(".obj", *mesh, _TAGS) for mesh in meshes]
    bases[".ply"] += [data.replace(b"float", b"double") for data in bases[".ply"]]
    bases["binary"] = [
        ply_bytes(vertices, faces, *types, order, extra)
        for (vertices, faces), types in zip(meshes, _TYPES * 2, strict=False)
        for order, extra in (("<", False), (">", True))
    ]
    with tempfile.TemporaryDirectory() as folder:
        bases[".bpt"] = []
        for count in (1, 2):
            path = Path(folder) / "p.bpt"
            write_bpt(path, PatchSet(np.random.default_rng(count).normal(size=(count, 4, 4, 3))))
            bases[".bpt"].append(path.read_bytes())
    return bases


BASES = _bases()


def _header_end(data: bytes) -> int:
    """Where the counts end: a PLY's ``end_header``, an OFF's or a .bpt's first lines."""
    end = data.find(b"end_header")
    if end >= 0:
        return end
    return len(b"\n".join(data.split(b"\n", 2)[:2]))


def _hostile_int(rng: np.random.Generator) -> int:
    if rng.random() < 0.7:
        return int(HOSTILE_INTS[rng.integers(len(HOSTILE_INTS))])
    return int(rng.integers(-10, 10**6))


def _replace(
    rng: np.random.Generator, data: bytes, end: int, pattern: bytes, token: bytes
) -> bytes:
    found = list(re.finditer(pattern, data[:end]))
    if not found:
        return data
    match = found[rng.integers(len(found))]
    return data[: match.start()] + token + data[match.end() :]


def _edit(rng: np.random.Generator, kind: str, data: bytes) -> bytes:
    """The edit ``kind`` of ``data``, where and with what drawn from ``rng``."""
    if kind == "count":
        token = str(_hostile_int(rng)).encode()
        return _replace(rng, data, _header_end(data), rb"-?\d+", token)
    if kind == "number":
        spelt = HOSTILE_TOKENS[rng.integers(len(HOSTILE_TOKENS))] if rng.random() < 0.6 else None
        token = (str(_hostile_int(rng)) if spelt is None else spelt).encode()
        return _replace(rng, data, len(data), rb"-?[\d.]+(?:e-?\d+)?", token)
    if kind == "cut":
        return data[: rng.integers(len(data) + 1)]
    if kind == "flip" and data:
        buffer = bytearray(data)
        for at in rng.integers(len(data), size=rng.integers(1, 5)):
            buffer[at] = int(rng.integers(256))
        return bytes(buffer)
    if kind == "append":
        return data + (JUNK[rng.integers(len(JUNK))] if rng.random() < 0.7 else rng.bytes(16))
    if kind == "crlf":
        return data.replace(b"\n", b"\r\n")
    if kind == "bom":
        return BOM + data
    lines = data.split(b"\n")
    at = int(rng.integers(len(lines)))
    if kind == "drop":
        del lines[at]
    elif kind == "repeat":
        lines.insert(at, lines[at])
    elif kind == "insert":
        lines.insert(at, JUNK[rng.integers(len(JUNK))])
    return b"\n".join(lines)


def hostile_file(kind: str, base: int, edits: list[str], seed: int) -> bytes:
    """Base file ``base`` of ``kind`` with ``edits`` made where ``seed`` says; a binary PLY gets
    four bytes of its body set to a hostile number first, one time in two."""
    rng = np.random.default_rng([seed, KINDS.index(kind)])
    data = BASES[kind][base % len(BASES[kind])]
    if kind == "binary" and edits and rng.random() < 0.5:
        at = int(rng.integers(data.index(b"end_header\n") + 11, len(data)))
        value = _hostile_int(rng) % 2**32
        data = _set(data, at, value.to_bytes(4, "little" if rng.random() < 0.5 else "big"))
    for edit in edits:
        data = _edit(rng, edit, data)
    return data


def _judge(path: Path, data: bytes, valid: bool) -> str | None:
    """What is wrong with reading ``data`` as ``path`` (None: nothing): it must give a mesh or
    network without NaN, or one g1patch error naming the file; no other exception, no warning,
    within the time and memory bounds."""
    path.write_bytes(data)
    start = time.perf_counter()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        tracemalloc.start()  # the read alone traced: three times faster than tracing throughout
        try:
            result: object = g1patch.read(path)
        except G1PatchError as error:
            result = error
        finally:
            peak = tracemalloc.get_traced_memory()[1]
            tracemalloc.stop()
    seconds = time.perf_counter() - start
    if isinstance(result, G1PatchError):
        text = str(result)
        if str(path) not in text or "\n" in text or valid:
            return f"{type(result).__name__}: {text[:300]}"
    if caught:
        return f"warnings: {[f'{w.category.__name__}: {w.message}' for w in caught]}"
    if seconds > TIME_CAP:
        return f"took {seconds:.1f} s"
    if peak > MEMORY_PER_BYTE * len(data) + MEMORY_BASE:
        return f"peak {peak} bytes for a file of {len(data)}"
    control = result.patches.control if isinstance(result, PatchNetwork) else None
    points = control if control is not None else getattr(result, "vertices", np.zeros(0))
    return None if np.isfinite(points).all() else "NaN or infinity in the result"


@pytest.mark.slow
def test_generated_hostile_files(tmp_path_factory: pytest.TempPathFactory) -> None:
    """:data:`PROGRAMS` drawn edit programs, each applied to a file of every kind: 10,000 files
    (module docstring). Any other exception escapes and fails the test with the program that
    raised it."""
    _warm()
    folder = tmp_path_factory.mktemp("hostile")
    paths = {kind: folder / f"input{'.ply' if kind == 'binary' else kind}" for kind in KINDS}

    @settings(max_examples=PROGRAMS, deadline=None, suppress_health_check=list(HealthCheck))
    @given(
        st.integers(0, 9),
        st.lists(st.sampled_from(EDITS), max_size=3),
        st.integers(0, 2**32 - 1),
    )
    @example(2, ["count", "repeat"], 6119)  # faces of 0 corners: a reshape error, once
    def run(base: int, edits: list[str], seed: int) -> None:
        found = {}
        for kind in KINDS:
            data = hostile_file(kind, base, edits, seed)
            found[kind] = _judge(paths[kind], data, valid=not edits)
        found = {kind: problem for kind, problem in found.items() if problem}
        assert not found, found

    run()


@pytest.fixture(scope="module")
def medium_files(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """Files of ~0.5 MB of short numbers (the most lines a byte), valid and with a last line or
    byte too many (read line by line, then refused), of every kind."""
    folder = tmp_path_factory.mktemp("medium")
    mesh = shapes.large_torus(15_000)
    vertices, faces = np.round(mesh.vertices, 3), mesh.faces
    patches = PatchSet(np.round(np.random.default_rng(0).normal(size=(2_500, 4, 4, 3)), 2))
    write_bpt(folder / "valid.bpt", patches)
    files = {
        "valid.obj": _text(".obj", vertices, faces.tolist()),
        "valid.off": _text(".off", vertices, faces.tolist()),
        "valid.ply": _text(".ply", vertices, faces.tolist()),
        "binary.ply": ply_bytes(vertices, faces, "f4", "u1", "i4", "<", False),
        "valid.bpt": (folder / "valid.bpt").read_bytes(),
    }
    for name, data in list(files.items()):
        files[f"bad-{name}"] = data + (b"\0" if name == "binary.ply" else b"x\n")
    for name, data in files.items():
        (folder / name).write_bytes(data)
    return {name: folder / name for name in files}


@pytest.mark.slow
@pytest.mark.parametrize(
    "name",
    [f"{bad}{kind}" for bad in ("", "bad-") for kind in ("valid.obj", "valid.off")]
    + [f"{bad}{kind}" for bad in ("", "bad-") for kind in ("valid.ply", "binary.ply", "valid.bpt")],
)
def test_memory_is_a_multiple_of_the_size(name: str, medium_files: dict[str, Path]) -> None:
    path = medium_files[name]
    start = time.perf_counter()
    peak, error = _read_traced(path)
    assert (error is None) == (not name.startswith("bad-")), error
    assert peak <= MEMORY_PER_BYTE * path.stat().st_size + MEMORY_BASE, (peak, path.stat().st_size)
    assert time.perf_counter() - start <= TIME_CAP
