"""Hardened network files (issue 12): a damaged, hostile or wrong file is one clear error, never a
crash.

Every case the issue measured is reproduced here, through the command line (``g1patch.cli.main``):
exit 2, exactly one line on stderr naming the user's file, and the output directory left as it
was (no file, no hidden temporary) — for ``check``, ``export`` (STEP, IGES, OBJ) and ``render``.
Round trips stay exact, files of every earlier version still load, and nothing reaches OpenCASCADE
that could crash it.
"""

from __future__ import annotations

import dataclasses
import json
import re
import struct
import tracemalloc
import zipfile
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest
from ocp_marks import HAVE_OCP, requires_ocp  # noqa: E402

from g1patch import shapes
from g1patch.build import build_network
from g1patch.cli import main
from g1patch.construct.corner import build_corner_network
from g1patch.errors import FormatError, G1PatchError, InputError
from g1patch.gregory import GregoryPatchSet
from g1patch.io.bpt import read_bpt, write_bpt
from g1patch.io.network_file import MAX_COORDINATE, load_network, save_network
from g1patch.network import PatchNetwork, network_from_patch_points
from g1patch.patches import PatchSet

#: every command that reads a network, with the output it would write (None: writes nothing)
COMMANDS: dict[str, Callable[[Path, Path], list[str]]] = {
    "check": lambda network, out: ["check", str(network), "--max-angle", "1e-9"],
    "export-step": lambda network, out: ["export", str(network), "-o", str(out / "s.step"), "-q"],
    "export-iges": lambda network, out: ["export", str(network), "-o", str(out / "s.iges"), "-q"],
    "export-obj": lambda network, out: ["export", str(network), "-o", str(out / "s.obj"), "-q"],
    "render": lambda network, out: ["render", str(network), "-o", str(out / "p.png")],
}
COMMAND_PARAMS = [
    pytest.param(name, marks=requires_ocp) if name in ("export-step", "export-iges") else name
    for name in COMMANDS
]


# ----------------------------------------------------------------------------- helpers
@pytest.fixture(scope="module")
def gregory_file(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A small Gregory network (a 6 × 4 torus: 24 patches, framed), written by save_network."""
    path = tmp_path_factory.mktemp("good") / "torus.npz"
    save_network(path, build_network(shapes.torus(6, 4), "gregory"))
    return path


@pytest.fixture(scope="module")
def bicubic_file(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The paper's corner network of the cube (6 Hermite bicubics), written by save_network."""
    path = tmp_path_factory.mktemp("good") / "cube.npz"
    save_network(path, build_corner_network(shapes.cube()))
    return path


def contents(path: Path) -> dict[str, np.ndarray]:
    with np.load(path, allow_pickle=False) as data:
        return {name: data[name] for name in data.files}


def rewrite(
    source: Path,
    target: Path,
    *,
    drop: tuple[str, ...] = (),
    version: int | None = None,
    compressed: bool = False,
    **arrays: object,
) -> Path:
    """``source``'s members, some dropped or replaced, written by numpy (as a user's script
    would)."""
    members = {name: value for name, value in contents(source).items() if name not in drop}
    if version is not None:
        header = json.loads(str(members["header"]))
        header["version"] = version
        members["header"] = np.array(json.dumps(header))
    members.update({name: np.asarray(value) for name, value in arrays.items()})
    (np.savez_compressed if compressed else np.savez)(target, **members)  # type: ignore[operator]
    return target


def changed(source: Path, target: Path, name: str, change: Callable[[np.ndarray], None]) -> Path:
    """``source`` with a copy of array ``name`` modified in place by ``change``."""
    array = contents(source)[name].copy()
    change(array)
    return rewrite(source, target, **{name: array})


def set_at(index: tuple[int, ...], value: object) -> Callable[[np.ndarray], None]:
    def change(array: np.ndarray) -> None:
        array[index] = value

    return change


def refused(
    capsys: pytest.CaptureFixture[str],
    args: list[str],
    path: Path,
    out: Path,
    *,
    contains: str = "",
) -> str:
    """Run the CLI; assert exit 2, one line on stderr naming ``path``, ``out`` untouched. Returns
    the line."""
    before = sorted(out.iterdir())
    code = main(args)
    captured = capsys.readouterr()
    lines = captured.err.strip().splitlines()
    assert code == 2, (code, captured.out, captured.err)
    assert len(lines) == 1, captured.err
    assert lines[0].startswith("g1patch: error: ") and str(path) in lines[0], lines[0]
    assert contains in lines[0], lines[0]
    assert "Traceback" not in captured.err and "allow_pickle" not in captured.err
    assert sorted(out.iterdir()) == before, "an output or temporary file was left behind"
    return lines[0]


@pytest.fixture
def out(tmp_path: Path) -> Path:
    """An empty output directory (hidden files count: it must stay empty)."""
    folder = tmp_path / "out"
    folder.mkdir()
    return folder


# ------------------------------------------------------------------- corrupt networks
#: (description, how to make the bad file from the good Gregory file, what the message says)
CORRUPTIONS: dict[str, tuple[Callable[[Path, Path], Path], str]] = {
    "neighbor out of range": (
        lambda g, t: changed(g, t, "neighbor", set_at((0, 0), 10**6)),
        "member 'neighbor.npy': value 1000000 at index (0, 0) is out of range -1..23",
    ),
    "neighbor below -1": (
        lambda g, t: changed(g, t, "neighbor", set_at((3, 1), -7)),
        "out of range -1..23",
    ),
    "corner id negative": (
        lambda g, t: changed(g, t, "corner_ids", set_at((2, 2), -5)),
        "member 'corner_ids.npy': value -5",
    ),
    "corner id past the vertices": (
        lambda g, t: changed(g, t, "corner_ids", set_at((0, 0), 24)),
        "out of range 0..23",
    ),
    "edge id past the edges": (
        lambda g, t: changed(g, t, "edge_ids", set_at((1, 3), 10**9)),
        "member 'edge_ids.npy'",
    ),
    "neighbor edge 7": (
        lambda g, t: changed(g, t, "neighbor_edge", set_at((0, 1), 7)),
        "out of range -1..3",
    ),
    "neighbor edge -1 on a shared edge": (
        lambda g, t: changed(g, t, "neighbor_edge", set_at((0, 1), -1)),
        "-1 in both or in neither",
    ),
    "neighbor not pointing back": (
        lambda g, t: changed(g, t, "neighbor", set_at((0, 0), 5)),
        "does not point back",
    ),
    "edge ids disagree across an edge": (
        lambda g, t: changed(g, t, "edge_ids", lambda a: a.__setitem__((0, 0), (a[0, 0] + 1) % 48)),
        "name different edges",
    ),
    "1e308 points": (
        lambda g, t: changed(g, t, "points", lambda a: a.__setitem__(..., 1e308)),
        "value 1e+308 at index (0, 0, 0) exceeds the bound",
    ),
    "1e200 point": (
        lambda g, t: changed(g, t, "points", set_at((5, 7, 2), -1e200)),
        "value -1e+200 at index (5, 7, 2)",
    ),
    "NaN point": (
        lambda g, t: changed(g, t, "points", set_at((1, 2, 0), np.nan)),
        "at index (1, 2, 0) is not a number",
    ),
    "inf point": (lambda g, t: changed(g, t, "points", set_at((0, 19, 2), np.inf)), "is infinite"),
    "1e200 vertex": (
        lambda g, t: changed(g, t, "vertices", set_at((0, 0), 1e200)),
        "member 'vertices.npy'",
    ),
    "NaN vertex normal": (
        lambda g, t: changed(g, t, "vertex_normals", set_at((3, 1), np.nan)),
        "member 'vertex_normals.npy'",
    ),
    "frame scale 1e300": (
        lambda g, t: rewrite(g, t, frame_scale=np.array(1e300)),
        "member 'frame_scale.npy': value 1e+300",
    ),
    "world coordinates past the bound": (
        lambda g, t: rewrite(g, t, frame_scale=np.array(1e30), points=contents(g)["points"] * 4),
        "in world coordinates (centre + scale × value) the patches reach",
    ),
    "frame centre 1e200": (
        lambda g, t: rewrite(g, t, frame_centre=np.array([1e200, 0.0, 0.0])),
        "member 'frame_centre.npy'",
    ),
    "frame scale 0": (lambda g, t: rewrite(g, t, frame_scale=np.array(0.0)), "frame scale"),
    "NaN uv": (
        lambda g, t: rewrite(g, t, uv=np.full((24, 4, 2), np.nan)),
        "member 'uv.npy': value nan at index (0, 0, 0) is not a number",
    ),
    "uv of 3 columns": (
        lambda g, t: rewrite(g, t, uv=np.zeros((24, 4, 3))),
        "member 'uv.npy': expected shape (P, 4, 2) = (24, 4, 2)",
    ),
    "uv as integers": (
        lambda g, t: rewrite(g, t, uv=np.zeros((24, 4, 2), np.int64)),
        "member 'uv.npy': expected floating-point",
    ),
    "missing neighbor": (
        lambda g, t: rewrite(g, t, drop=("neighbor",)),
        "network file lacks neighbor",
    ),
    "missing points": (lambda g, t: rewrite(g, t, drop=("points",)), "network file lacks points"),
    "missing seam (version 3)": (lambda g, t: rewrite(g, t, drop=("seam",)), "lacks seam"),
    "missing header": (lambda g, t: rewrite(g, t, drop=("header",)), "no header"),
    "neighbor as floats": (
        lambda g, t: rewrite(g, t, neighbor=contents(g)["neighbor"].astype(float)),
        "member 'neighbor.npy': expected integers, got an array of float64",
    ),
    "points as integers": (
        lambda g, t: rewrite(g, t, points=np.zeros((24, 20, 3), np.int64)),
        "expected floating-point",
    ),
    "points as complex": (
        lambda g, t: rewrite(g, t, points=contents(g)["points"].astype(complex)),
        "expected floating-point",
    ),
    "points as float128": (
        lambda g, t: rewrite(g, t, points=contents(g)["points"].astype(np.longdouble)),
        "expected floating-point",
    ),
    "seam as integers": (
        lambda g, t: rewrite(g, t, seam=contents(g)["seam"].astype(np.int8)),
        "expected booleans",
    ),
    "edge_reversed holding 2": (
        lambda g, t: rewrite(g, t, edge_reversed=np.full((24, 4), 2, np.uint8).view(bool)),
        "member 'edge_reversed.npy': byte 2 at index (0, 0) is not a boolean",
    ),
    "seam holding 255": (
        lambda g, t: changed(g, t, "seam", lambda a: a.view(np.uint8).__setitem__((4, 2), 255)),
        "byte 255 at index (4, 2)",
    ),
    "wrong shape": (
        lambda g, t: rewrite(g, t, neighbor=np.zeros((24, 3), np.int64)),
        "expected shape (P, 4) = (24, 4)",
    ),
    "vertices of 5 columns": (
        lambda g, t: rewrite(g, t, vertices=np.zeros((24, 5))),
        "member 'vertices.npy'",
    ),
    "version 99": (
        lambda g, t: rewrite(g, t, version=99),
        "network format version 99 is not supported",
    ),
    "version as text": (
        lambda g, t: rewrite(
            g, t, header=np.array(json.dumps({"format": "g1patch-network", "version": "3"}))
        ),
        "version '3' is not supported",
    ),
    "header not JSON": (
        lambda g, t: rewrite(g, t, header=np.array("{not json")),
        "header is not JSON",
    ),
    "header not a string": (
        lambda g, t: rewrite(g, t, header=np.zeros(3)),
        "member 'header.npy': expected one string",
    ),
    "provenance not a mapping": (
        lambda g, t: rewrite(
            g,
            t,
            header=np.array(
                json.dumps({"format": "g1patch-network", "version": 3, "provenance": [1, 2]})
            ),
        ),
        "provenance",
    ),
    "unknown patch kind": (
        lambda g, t: rewrite(g, t, patch_kind=np.array("nurbs")),
        "unknown patch kind 'nurbs'",
    ),
    "an extra member": (
        lambda g, t: rewrite(g, t, junk=np.zeros(3)),
        "unexpected member 'junk.npy'",
    ),
    "an object array": (lambda g, t: _with_object_member(g, t), "holds object values"),
}


def _with_object_member(good: Path, target: Path) -> Path:
    members = contents(good)
    members["vertices"] = np.array([None, 1, "x"], dtype=object)
    np.savez(target, allow_pickle=True, **members)  # type: ignore[arg-type]
    return target


@pytest.mark.parametrize("command", COMMAND_PARAMS)
@pytest.mark.parametrize("case", sorted(CORRUPTIONS))
def test_corrupt_networks_are_one_line_exit_2(
    case: str,
    command: str,
    gregory_file: Path,
    tmp_path: Path,
    out: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    make, message = CORRUPTIONS[case]
    bad = make(gregory_file, tmp_path / "bad.npz")
    refused(capsys, COMMANDS[command](bad, out), bad, out, contains=message)


@pytest.mark.parametrize("case", sorted(CORRUPTIONS))
def test_corrupt_networks_raise_format_error(case: str, gregory_file: Path, tmp_path: Path) -> None:
    make, message = CORRUPTIONS[case]
    with pytest.raises(
        FormatError, match="^" + str(tmp_path / "bad.npz").replace(".", r"\.") + ": "
    ) as error:
        load_network(make(gregory_file, tmp_path / "bad.npz"))
    assert message in str(error.value) and "\n" not in str(error.value)


@pytest.mark.parametrize("value", [1e308, np.nan, np.inf, -np.inf, 1e200, 2 * MAX_COORDINATE])
def test_bicubic_control_points_are_bounded(
    value: float, bicubic_file: Path, tmp_path: Path
) -> None:
    bad = changed(bicubic_file, tmp_path / "bad.npz", "control", set_at((2, 1, 3, 0), value))
    with pytest.raises(
        FormatError, match=r"member 'control\.npy': value .* at index \(2, 1, 3, 0\)"
    ):
        load_network(bad)


def test_the_bound_itself_still_loads(bicubic_file: Path, tmp_path: Path) -> None:
    """|x| = MAX_COORDINATE is allowed: the bound is inclusive and not below any real model."""
    network = load_network(bicubic_file)
    control = network.patches.control.copy()  # type: ignore[attr-defined]
    control[0, 0, 0, 0] = MAX_COORDINATE
    edge = dataclasses.replace(network, patches=PatchSet(control, network.patches.form))  # type: ignore[attr-defined]
    save_network(tmp_path / "edge.npz", edge)
    assert load_network(tmp_path / "edge.npz").patches.control[0, 0, 0, 0] == MAX_COORDINATE  # type: ignore[attr-defined]


# ------------------------------------------------------------------- zip bombs and damage
def _patch_central_size(path: Path, member: str, size: int) -> None:
    """Rewrite the uncompressed size the zip directory declares for ``member`` (32-bit field)."""
    data = bytearray(path.read_bytes())
    name = member.encode()
    at = data.find(b"PK\x01\x02")
    while at >= 0:
        name_length = struct.unpack_from("<H", data, at + 28)[0]
        if data[at + 46 : at + 46 + name_length] == name:
            struct.pack_into("<I", data, at + 24, size)
            path.write_bytes(bytes(data))
            return
        at = data.find(b"PK\x01\x02", at + 4)
    raise AssertionError(f"{member} not in {path}")


def _bomb(good: Path, target: Path, *, member: str = "vertices", rows: int = 2**22) -> Path:
    """``good`` with ``member`` replaced by ``rows`` × 3 float64 zeros, deflated: 100 MB in a ~100
    kB file."""
    with (
        zipfile.ZipFile(good) as source,
        zipfile.ZipFile(target, "w", zipfile.ZIP_DEFLATED) as bomb,
    ):
        for info in source.infolist():
            if info.filename != f"{member}.npy":
                bomb.writestr(info.filename, source.read(info))
                continue
            with bomb.open(info.filename, "w", force_zip64=True) as stream:
                header = {"descr": "<f8", "fortran_order": False, "shape": (rows, 3)}
                np.lib.format.write_array_header_1_0(stream, header)
                zeros = bytes(1 << 20)
                for _ in range(rows * 24 // len(zeros)):
                    stream.write(zeros)
    return target


def test_a_zip_bomb_is_refused_before_it_expands(
    gregory_file: Path, tmp_path: Path, out: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    bomb = _bomb(gregory_file, tmp_path / "bomb.npz")
    assert bomb.stat().st_size < 1_000_000  # small on disk, 100 MB inside
    tracemalloc.start()
    with pytest.raises(
        FormatError,
        match=r"member 'vertices\.npy' declares 100\.7 MB \(100663424 bytes\) uncompressed, more "
        r"than "
        r"the 31\.5 kB \(31520 bytes\) it can take in a network of at most 224 patches",
    ):
        load_network(bomb)
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    assert peak < 4_000_000, f"{peak} bytes allocated: the bomb was expanded"
    for command in COMMANDS:
        if command.startswith("export-") and command != "export-obj" and not HAVE_OCP:
            continue
        refused(capsys, COMMANDS[command](bomb, out), bomb, out, contains="declares 100.7 MB")


def test_a_member_claiming_4_gb_in_the_zip_directory(gregory_file: Path, tmp_path: Path) -> None:
    """The issue's bomb: the directory declares ~4 GB for one member; refused from the directory
    alone."""
    bad = rewrite(gregory_file, tmp_path / "claims.npz")
    _patch_central_size(bad, "vertices.npy", 0xFFFFFFFE)
    with pytest.raises(
        FormatError,
        match=r"member 'vertices\.npy' declares 4\.3 GB \(4294967294 bytes\) uncompressed, more "
        r"than "
        r"the .* it can take in a network of at most \d+ patches",
    ):
        load_network(bad)


def test_a_member_above_the_absolute_cap(gregory_file: Path, tmp_path: Path) -> None:
    """A zip64 directory may declare anything: above 32 GiB a member is refused whatever the
    network.

    save_network writes zip64 records: the uncompressed size of a member is the first field of the
    zip64 extra field of its central header."""
    data = bytearray(gregory_file.read_bytes())
    at = data.find(b"PK\x01\x02")
    while at >= 0:
        name_length = struct.unpack_from("<H", data, at + 28)[0]
        if data[at + 46 : at + 46 + name_length] == b"points.npy":
            struct.pack_into("<Q", data, at + 46 + name_length + 4, 2**40)
            break
        at = data.find(b"PK\x01\x02", at + 4)
    bad = tmp_path / "huge.npz"
    bad.write_bytes(bytes(data))
    with pytest.raises(
        FormatError,
        match=r"member 'points\.npy' declares 1099\.5 GB \(1099511627776 bytes\) uncompressed, "
        r"above the cap of 34\.4 GB \(34359738368 bytes\) per member",
    ):
        load_network(bad)


def test_a_npy_header_larger_than_its_member(gregory_file: Path, tmp_path: Path) -> None:
    """A ``.npy`` header claiming a billion rows in a member of a few bytes: refused, nothing
    allocated."""
    bad = rewrite(gregory_file, tmp_path / "liar.npz")
    with zipfile.ZipFile(gregory_file) as source, zipfile.ZipFile(bad, "w") as target:
        for info in source.infolist():
            data = source.read(info)
            if info.filename == "corner_ids.npy":
                stream = __import__("io").BytesIO()
                np.lib.format.write_array_header_1_0(
                    stream, {"descr": "<i8", "fortran_order": False, "shape": (10**9, 4)}
                )
                data = stream.getvalue() + data[len(stream.getvalue()) :]
            target.writestr(info.filename, data)
    with pytest.raises(
        FormatError,
        match=r"member 'corner_ids\.npy': its \.npy header describes int64 \(1000000000, 4\) "
        r"\(32\.0 GB .*\), but the zip directory says",
    ):
        load_network(bad)


@pytest.mark.parametrize("keep", [0.5, 0.9, 0.999])
def test_truncated_files(
    keep: float, gregory_file: Path, tmp_path: Path, out: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    data = gregory_file.read_bytes()
    bad = tmp_path / "cut.npz"
    bad.write_bytes(data[: int(len(data) * keep)])
    line = refused(capsys, COMMANDS["export-obj"](bad, out), bad, out)
    assert "truncated" in line


def test_a_flipped_bit_fails_the_crc(gregory_file: Path, tmp_path: Path) -> None:
    data = bytearray(gregory_file.read_bytes())
    with zipfile.ZipFile(gregory_file) as archive:
        info = archive.getinfo("points.npy")
    data[info.header_offset + 200] ^= 0x10  # inside the points' data
    bad = tmp_path / "flipped.npz"
    bad.write_bytes(bytes(data))
    with pytest.raises(FormatError, match=r"member 'points\.npy' fails its CRC check"):
        load_network(bad)


def test_duplicate_members_are_refused(gregory_file: Path, tmp_path: Path) -> None:
    bad = tmp_path / "twice.npz"
    with zipfile.ZipFile(gregory_file) as source, zipfile.ZipFile(bad, "w") as target:
        for info in source.infolist():
            target.writestr(info.filename, source.read(info))
        with pytest.warns(UserWarning, match="Duplicate name"):
            target.writestr("neighbor.npy", source.read("neighbor.npy"))
    with pytest.raises(FormatError, match=r"member 'neighbor\.npy' appears twice"):
        load_network(bad)


def test_other_compression_methods_are_refused(gregory_file: Path, tmp_path: Path) -> None:
    bad = tmp_path / "lzma.npz"
    with (
        zipfile.ZipFile(gregory_file) as source,
        zipfile.ZipFile(bad, "w", zipfile.ZIP_LZMA) as target,
    ):
        for info in source.infolist():
            target.writestr(info.filename, source.read(info))
    with pytest.raises(FormatError, match="compression method 14"):
        load_network(bad)


# ------------------------------------------------------------------- files of another kind
def _wrong_files(tmp_path: Path, gregory_file: Path) -> dict[str, tuple[Path, str]]:
    mesh = shapes.cube()
    from g1patch.io.meshfile import write_quads

    obj = tmp_path / "x.obj"
    write_quads(obj, mesh.vertices, mesh.faces)
    text = tmp_path / "notes.txt"
    text.write_text("hello\n")
    renamed = tmp_path / "text.npz"
    renamed.write_text("v 0 0 0\nf 1 2 3 4\n")
    binary = tmp_path / "binary.npz"
    binary.write_bytes(bytes(range(256)) * 4)
    empty = tmp_path / "empty.npz"
    empty.write_bytes(b"")
    npy = tmp_path / "array.npz"
    np.save(tmp_path / "array.npy", np.zeros(3))
    npy.write_bytes((tmp_path / "array.npy").read_bytes())
    directory = tmp_path / "folder.npz"
    directory.mkdir()
    return {
        "obj": (obj, "a Wavefront OBJ mesh"),
        "txt": (text, "a .txt file"),
        "text renamed .npz": (renamed, "a text file"),
        "binary .npz": (binary, "not a zip archive"),
        "empty .npz": (empty, "an empty file"),
        "npy renamed .npz": (npy, "a single NumPy array (.npy)"),
        "directory": (directory, "is a directory"),
        "missing": (tmp_path / "missing.npz", "no such file"),
    }


WRONG = [
    "obj",
    "txt",
    "text renamed .npz",
    "binary .npz",
    "empty .npz",
    "npy renamed .npz",
    "directory",
    "missing",
]


@pytest.mark.parametrize("kind", WRONG)
def test_export_names_what_it_expects(
    kind: str, gregory_file: Path, tmp_path: Path, out: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path, what = _wrong_files(tmp_path, gregory_file)[kind]
    line = refused(capsys, COMMANDS["export-obj"](path, out), path, out, contains=what)
    if kind not in ("directory", "missing"):
        assert "a network file (.npz) written by g1patch build" in line
    if kind == "obj":
        assert "g1patch build" in line and "x.npz" in line  # how to make one


def test_export_reads_a_bpt_as_check_does(
    tmp_path: Path, out: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A Bézier patch file is a network to every command (one reader, the API's)."""
    bpt = tmp_path / "p.bpt"
    write_bpt(bpt, PatchSet(np.random.default_rng(0).normal(size=(2, 4, 4, 3)), "bezier"))
    assert main(["export", str(bpt), "-o", str(out / "p.obj"), "--resolution", "2"]) == 0
    assert "wrote 4 triangles" in capsys.readouterr().out


@pytest.mark.parametrize("command", ["check", "render"])
@pytest.mark.parametrize(
    "kind", ["obj", "txt", "text renamed .npz", "binary .npz", "npy renamed .npz", "missing"]
)
def test_check_and_render_name_what_they_read(
    kind: str,
    command: str,
    gregory_file: Path,
    tmp_path: Path,
    out: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    path, what = _wrong_files(tmp_path, gregory_file)[kind]
    line = refused(capsys, COMMANDS[command](path, out), path, out, contains=what)
    if kind != "missing":
        assert "or Bézier patches (.bpt)" in line


# ------------------------------------------------------------------- .bpt files
@pytest.mark.parametrize(
    "value,message",
    [
        ("1e308", "coordinate of magnitude 1e+308"),
        ("-1e200", "exceeds the bound"),
        ("nan", "three finite numbers"),
        ("inf", "three finite numbers"),
        ("1e999", "three finite numbers"),
    ],
)
def test_bpt_coordinates_are_bounded(
    value: str, message: str, tmp_path: Path, out: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    good = tmp_path / "good.bpt"
    write_bpt(good, PatchSet(np.random.default_rng(2).normal(size=(2, 4, 4, 3)), "bezier"))
    lines = good.read_text().splitlines()
    lines[20] = f"0 {value} 0"  # patch 2, its second point: line 21
    bad = tmp_path / "bad.bpt"
    bad.write_text("\n".join(lines) + "\n")
    with pytest.raises(FormatError, match=rf"bad\.bpt:21: patch 2: .*{re.escape(message)}"):
        read_bpt(bad)
    for command in ("check", "render"):
        refused(capsys, COMMANDS[command](bad, out), bad, out, contains="bad.bpt:21")


@pytest.mark.parametrize(
    "text,message",
    [
        ("99999999999999999999\n3 3\n", "truncated: 99999999999999999999 patches need"),
        ("²\n", "expected a positive patch count"),
        (
            "1\n3 3\n" + "0 0 0\n" * 15,
            r"bad\.bpt:17: truncated: 1 patches need 18 non-empty lines, the file has 17",
        ),
    ],
)
def test_bpt_counts_and_truncation(text: str, message: str, tmp_path: Path) -> None:
    bad = tmp_path / "bad.bpt"
    bad.write_text(text)
    with pytest.raises(FormatError, match=message):
        read_bpt(bad)


# ------------------------------------------------------------------- round trips and old versions
def _networks() -> dict[str, Callable[[], PatchNetwork]]:
    return {
        "gregory": lambda: build_network(shapes.torus(6, 4), "gregory"),
        "gregory limit": lambda: build_network(shapes.cube(), "gregory", "limit"),
        "split4": lambda: build_network(shapes.torus(5, 3), "split4"),
        "corner": lambda: build_corner_network(shapes.cube()),
        "seamed": lambda: (lambda n: n.with_seams(np.ones(n.n_edges, dtype=bool)))(
            build_network(shapes.cube(), "gregory")
        ),
        "patch file": lambda: network_from_patch_points(
            PatchSet(np.random.default_rng(3).normal(size=(3, 4, 4, 3)))
        ),
        "grid": lambda: build_network(shapes.grid(3, 2), "gregory"),
    }


@pytest.mark.parametrize("name", sorted(_networks()))
def test_round_trips_are_exact(name: str, tmp_path: Path) -> None:
    network = _networks()[name]()
    save_network(tmp_path / "n.npz", network)
    loaded = load_network(tmp_path / "n.npz")
    assert type(loaded.patches) is type(network.patches)
    assert getattr(loaded.patches, "frame", None) == getattr(network.patches, "frame", None)
    for attribute in ("points", "control", "form"):
        if hasattr(network.patches, attribute):
            value = getattr(loaded.patches, attribute)
            assert (
                np.array_equal(value, getattr(network.patches, attribute))
                if attribute != "form"
                else value == network.patches.form
            )
    for field in (
        "corner_ids",
        "edge_ids",
        "edge_reversed",
        "neighbor",
        "neighbor_edge",
        "same_direction",
        "edge_collapsed",
        "seam",
        "vertices",
        "vertex_normals",
    ):
        mine, theirs = getattr(loaded, field), getattr(network, field)
        assert (mine is None and theirs is None) or (
            np.array_equal(mine, theirs) and mine.dtype == theirs.dtype
        ), field
    assert loaded.provenance == network.provenance
    # the container is numpy's: np.load and zipfile read it, every CRC right
    assert set(contents(tmp_path / "n.npz")) >= {"header", "patch_kind", "corner_ids", "seam"}
    with zipfile.ZipFile(tmp_path / "n.npz") as archive:
        assert archive.testzip() is None
        assert all(info.compress_type == zipfile.ZIP_STORED for info in archive.infolist())
    # and a second save writes the same bytes
    save_network(tmp_path / "again.npz", loaded)
    assert (tmp_path / "again.npz").read_bytes() == (tmp_path / "n.npz").read_bytes()


@pytest.mark.parametrize("version", [1, 2, 3, 4, 5])
@pytest.mark.parametrize("compressed", [True, False])
def test_files_of_every_version_still_load(
    version: int, compressed: bool, gregory_file: Path, tmp_path: Path
) -> None:
    """Earlier releases wrote np.savez_compressed; version 1 had no frame, version 2 no seams."""
    original = load_network(gregory_file)
    drop = ("seam",) if version < 3 else ()
    old = rewrite(
        gregory_file, tmp_path / "old.npz", version=version, compressed=compressed, drop=drop
    )
    loaded = load_network(old)
    assert np.array_equal(loaded.patches.points, original.patches.points)  # type: ignore[attr-defined]
    assert (loaded.patches.frame is None) == (version == 1)  # type: ignore[attr-defined]
    assert np.array_equal(loaded.neighbor, original.neighbor) and not loaded.seam.any()


def test_narrow_index_types_written_by_users_still_load(gregory_file: Path, tmp_path: Path) -> None:
    arrays = contents(gregory_file)
    narrow = {
        name: arrays[name].astype(np.int32) for name in ("corner_ids", "edge_ids", "neighbor")
    }
    loaded = load_network(
        rewrite(
            gregory_file,
            tmp_path / "narrow.npz",
            neighbor_edge=arrays["neighbor_edge"].astype(np.int8),
            **narrow,
        )
    )
    assert loaded.neighbor.dtype == np.int64 and np.array_equal(loaded.neighbor, arrays["neighbor"])


def test_save_refuses_what_load_would_refuse(tmp_path: Path) -> None:
    network = build_network(shapes.torus(6, 4), "gregory")
    huge = dataclasses.replace(network, patches=GregoryPatchSet(network.patches.points * 1e200))  # type: ignore[attr-defined]
    with pytest.raises(
        FormatError,
        match=r"n\.npz: cannot store this network: member 'points\.npy': value .* exceeds the "
        r"bound",
    ):
        save_network(tmp_path / "n.npz", huge)
    assert list(tmp_path.iterdir()) == []


# ------------------------------------------------------------------- OpenCASCADE guards
def _cube(scale: float = 1.0) -> PatchNetwork:
    network = build_corner_network(shapes.cube())
    return dataclasses.replace(
        network, patches=PatchSet(network.patches.control * scale, network.patches.form)
    )  # type: ignore[attr-defined]


def _collapsed_patch() -> PatchNetwork:
    network = _cube()
    control = network.patches.convert("bezier").control.copy()  # type: ignore[attr-defined]
    control[0] = control[
        0, 0, 0
    ]  # patch 0 is one point: OCC's sewing drops it, and evaluating it crashed
    return dataclasses.replace(network, patches=PatchSet(control, "bezier"))


@requires_ocp
@pytest.mark.parametrize(
    "network,message",
    [
        (lambda: _cube(1e200), "magnitude 1.8e+200; OpenCASCADE export needs finite coordinates"),
        (lambda: _cube(1e40), "magnitude 1.8e+40"),
        (lambda: _cube(1e-8), "patch 0 (and 5 more) spans 3.72e-08"),
        (lambda: _cube(0.0), "all patch corners coincide"),
        (_collapsed_patch, "patch 0 spans 0"),
        (lambda: PatchSet(_cube(1e200).patches.control), "magnitude 1.8e+200"),  # type: ignore[attr-defined]  (bare patches too)
    ],
)
def test_nothing_reaches_opencascade_unchecked(
    network: Callable[[], PatchNetwork | PatchSet], message: str, tmp_path: Path
) -> None:
    from g1patch.io.cad import export_cad

    for suffix in (".step", ".iges"):
        with pytest.raises(InputError, match="cannot export: ") as error:
            export_cad(tmp_path / f"x{suffix}", network())
        assert message in str(error.value) and str(tmp_path / f"x{suffix}") in str(error.value)
    assert list(tmp_path.iterdir()) == []


@requires_ocp
def test_a_sewn_away_face_is_an_error_not_a_crash(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """With the size check off, the collapsed patch reaches OCC: its dropped face is caught after
    sewing."""
    from g1patch.io import cad
    from g1patch.io.cad import export as cad_export

    monkeypatch.setattr(cad_export, "_check_fit", lambda *args: None)
    with pytest.raises(cad.OpenCascadeError, match="sewing dropped the face of patch 0"):
        cad.export_cad(tmp_path / "x.step", _collapsed_patch())
    assert list(tmp_path.iterdir()) == []


@requires_ocp
@pytest.mark.parametrize(
    "stage,name",
    [
        ("sewing", "BRepBuilderAPI_Sewing"),
        ("making the faces", "Geom_BSplineSurface"),
        ("writing the file", "STEPControl_Writer"),
    ],
)
def test_exceptions_inside_occ_become_g1patch_errors(
    stage: str,
    name: str,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    from OCP.Standard import Standard_Failure

    from g1patch.io import cad
    from g1patch.io.cad import export as cad_export

    real = cad_export._occ

    def failing() -> object:
        occ = real()

        def boom(*args: object) -> None:
            raise Standard_Failure("simulated failure")

        setattr(occ, name, boom)
        return occ

    monkeypatch.setattr(cad_export, "_occ", failing)
    with pytest.raises(
        cad.OpenCascadeError,
        match=rf"x\.step: OpenCASCADE failed while {stage} \(Standard_Failure: simulated failure\)",
    ):
        cad.export_cad(tmp_path / "x.step", _cube())
    assert isinstance(cad.OpenCascadeError("x"), G1PatchError)
    assert list(tmp_path.iterdir()) == []
    save_network(tmp_path / "cube.npz", _cube())
    out = tmp_path / "out"
    out.mkdir()
    refused(
        capsys,
        ["export", str(tmp_path / "cube.npz"), "-o", str(out / "x.step"), "-q"],
        out / "x.step",
        out,
        contains="OpenCASCADE failed while",
    )


# ------------------------------------------------------------------- fuzzing
@pytest.mark.parametrize("compressed", [False, True])
def test_random_damage_is_always_a_format_error(compressed: bool, tmp_path: Path) -> None:
    """Bytes overwritten, inserted or cut anywhere (headers, directory, data): the file loads (the
    damage hit nothing that matters) or raises one one-line FormatError — never anything else."""
    import random
    import warnings

    good = tmp_path / "good.npz"
    save_network(good, build_network(shapes.torus(4, 3), "gregory"))
    if compressed:
        rewrite(good, good, compressed=True)
    data = good.read_bytes()
    rng = random.Random(12)
    bad = tmp_path / "bad.npz"
    refused = 0
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for _ in range(400):
            damaged = bytearray(data)
            kind = rng.random()
            if kind < 0.6:
                for _ in range(rng.randint(1, 4)):
                    damaged[rng.randrange(len(damaged))] = rng.randrange(256)
            elif kind < 0.8:
                damaged = damaged[: rng.randrange(len(damaged))]
            else:
                at = rng.randrange(len(damaged))
                damaged[at:at] = bytes(rng.randrange(256) for _ in range(rng.randint(1, 50)))
            bad.write_bytes(bytes(damaged))
            try:
                load_network(bad)
            except FormatError as error:
                assert "\n" not in str(error) and str(error).startswith(str(bad))
                refused += 1
    assert refused > 300


@pytest.mark.parametrize("at", [0, 1 << 17, (1 << 17) + 5, 3 * (1 << 17) - 1])
@pytest.mark.parametrize("value", [np.nan, np.inf, -np.inf, -1e31])
def test_the_bound_check_sees_every_chunk(at: int, value: float) -> None:
    """The coordinate check runs in chunks: a bad value in any of them, first or last element, is
    found."""
    from g1patch.io.network_file.values import _Checker, _extremes

    array = np.zeros(3 * (1 << 17))
    array[at] = value
    low, high = _extremes(array)
    assert not (low >= -MAX_COORDINATE and high <= MAX_COORDINATE)
    with pytest.raises(FormatError, match=rf"member 'points\.npy': value .* at index \({at},\)"):
        _Checker(Path("x.npz"), "").coordinates("points", array)
