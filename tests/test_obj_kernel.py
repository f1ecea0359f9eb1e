"""The compiled OBJ reader (:func:`g1patch.io.meshfile._obj_compiled`) against the line-by-line
reference and the NumPy fast path, and its number conversion against ``float``.

The files are those of ``test_readers.obj_files`` (every spelling OBJ allows, valid or damaged):
whatever the kernel returns is the reference's result bit for bit, and it declines only files the
reference refuses. Its Eisel–Lemire conversion is ``float()`` to the bit on shortest round-trip
digits, every precision of ``%e``, long and halfway digit strings and the range's ends.
"""

from __future__ import annotations

from decimal import Decimal
from pathlib import Path

import meshio
import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from test_readers import PATH, PLAIN_COORDINATES, SETTINGS, obj_files, outcome

from g1patch import shapes
from g1patch.io import meshfile
from g1patch.io.meshfile import read_mesh, write_quads


@pytest.mark.slow
@SETTINGS
@given(obj_files())
def test_obj_kernel_is_the_reference(data: bytes) -> None:
    compiled = meshfile._obj_compiled(data)
    reference = outcome(meshfile._read_obj_lines, PATH, data)
    if compiled is not None:
        assert outcome(lambda path, data: compiled, PATH, data) == reference
        fast = meshfile._obj_fast(data)
        assert (
            fast is None or outcome(lambda path, data: fast, PATH, data) == reference
        )  # the NumPy fast path agrees
    else:
        assert len(reference) == 3, "the kernel declined a valid file"  # an error


def coordinates(tokens: list[str]) -> np.ndarray | None:
    """The tokens as the kernel reads them: the x, y, z of ``v`` lines (one more face line)."""
    rows = [tokens[i : i + 3] for i in range(0, len(tokens) - len(tokens) % 3, 3)]
    parsed = meshfile._obj_compiled(
        ("".join(f"v {' '.join(row)}\n" for row in rows) + "f 1 1 1\n").encode()
    )
    return None if parsed is None else parsed.vertices.ravel()


def assert_float(tokens: list[str]) -> None:
    tokens = tokens + ["0"] * (-len(tokens) % 3)
    expected = np.array([float(t) for t in tokens])
    got = coordinates(tokens)
    if not np.isfinite(expected).all():
        assert got is None
        return
    assert got is not None and got.view(np.uint64).tolist() == expected.view(np.uint64).tolist(), (
        tokens
    )


@SETTINGS
@given(
    st.lists(st.floats(allow_nan=False, allow_infinity=False), min_size=1, max_size=30),
    st.integers(0, 20),
)
def test_kernel_numbers_are_float(values: list[float], precision: int) -> None:
    assert_float(
        [repr(v) for v in values]
        + [f"{v:.{precision}e}" for v in values]
        + [f"{v:.{precision}f}" for v in values if abs(v) < 1e20]
    )


@SETTINGS
@given(
    st.lists(
        st.tuples(st.integers(1, 10**25), st.integers(-360, 330), st.booleans()),
        min_size=1,
        max_size=30,
    )
)
def test_kernel_digit_strings_are_float(parts: list[tuple[int, int, bool]]) -> None:
    """Up to 25 digits (beyond 19: float() converts), exponents past both ends of the range."""
    assert_float(
        [f"{'-' if negative else ''}{digits}e{exponent}" for digits, exponent, negative in parts]
    )


def test_kernel_halfway_and_edge_numbers_are_float() -> None:
    rng = np.random.default_rng(7)
    tokens = [
        "0",
        "-0",
        "+1.5",
        ".5",
        "-.25",
        "5.",
        "1e3",
        "1E-3",
        "-2.5e+2",
        "0.30000000000000004",
        "4.9e-324",
        "2.2250738585072014e-308",
        "2.2250738585072011e-308",
        "1.7976931348623157e308",
        "9007199254740993",
        "1e23",
        "8.98846567431158e307",
        "1_0",
        "0.0000000000000000000000000001",
        "00000000000000000000001.5",
        "1.00000000000000011102230246251565404236316680908203125",
        "7.2057594037927933e16",
        "1e-400",
        "-0e999",
    ]
    for x in rng.uniform(-300, 300, 300):
        x = float(10.0**x)
        middle = (
            Decimal(x) + Decimal(float(np.nextafter(x, np.inf)))
        ) / 2  # exactly halfway between two floats
        tokens += [f"{middle:.17e}", f"{middle:.18e}", f"{middle:.40e}"]
    assert_float(tokens)


def test_kernel_declines_what_float_refuses() -> None:
    for token in ["1e", "--1", "1.2.3", "x", "+", "nan", "inf", "1e400"]:
        assert coordinates([token, "0", "0"]) is None, token


def test_read_mesh_of_a_large_obj_is_the_reference(tmp_path: Path) -> None:
    """A file beyond KERNEL_BYTES: read_mesh takes the kernel and gives the written mesh bit for
    bit."""
    mesh = shapes.large_torus(40_000)
    path = tmp_path / "torus.obj"
    write_quads(path, mesh.vertices, mesh.faces)
    data = path.read_bytes()
    assert len(data) >= meshfile.KERNEL_BYTES and meshfile._obj_compiled(data) is not None
    again = read_mesh(path)
    reference = meshfile._read_obj_lines(path, data)
    assert again.vertices.tobytes() == reference.vertices.tobytes() == mesh.vertices.tobytes()
    assert np.array_equal(again.faces, mesh.faces)


@pytest.mark.parametrize(
    ("text", "line"),
    [(b"v 0 0 0\nv 1 0 0\nv 1 1 x\nf 1 2 3\n", 3), (b"v 0 0 0\xc3\xa9\nf 1 1 1\n", 1)],
)
def test_large_malformed_obj_keeps_the_line_numbered_message(
    tmp_path: Path, text: bytes, line: int
) -> None:
    """Past KERNEL_BYTES (a long comment first) a bad line still gets the reference's message."""
    path = tmp_path / "bad.obj"
    path.write_bytes(b"#" + b" " * meshfile.KERNEL_BYTES + b"\n" + text)
    reference = outcome(meshfile._read_obj_lines, path, path.read_bytes())
    assert meshfile._obj_compiled(path.read_bytes()) is None
    assert (
        outcome(meshfile._read_obj, path, path.read_bytes()) == reference
        and reference[2] == line + 1
    )


# -- the numbers of OFF and ASCII PLY text ------------------------------------------------------


@SETTINGS
@given(
    st.lists(
        st.one_of(
            PLAIN_COORDINATES,
            st.sampled_from(["1_0", "x", "-", "+", "nan", "inf", "1e", "1e400", "--1", "1.2.3"]),
        ),
        min_size=1,
        max_size=40,
    ),
    st.sampled_from([" ", "\n"]),
)
def test_floats_kernel_is_numbers(tokens: list[str], separator: str) -> None:
    """``_floats_compiled`` returns what the NumPy ``_numbers`` returns where that accepts the text
    (the same bits), and declines the same texts, but for the numbers np.fromstring cannot be
    trusted with."""
    text = separator.join(tokens).encode() + b"\n"
    compiled = meshfile._floats_compiled(text, len(tokens))
    numpy = meshfile._numbers(text, b"", len(tokens), np.float64)
    if numpy is not None:
        assert compiled is not None and compiled.tobytes() == numpy.tobytes()
    if compiled is not None:
        assert compiled.tobytes() == np.array([float(t) for t in tokens]).tobytes()
    plain = all(
        t.lstrip("+-")[:1].isdigit() or t.lstrip("+-")[:1] == "." for t in tokens
    ) and not any(t in ("1e", "--1", "1.2.3", "1_0") for t in tokens)
    assert (compiled is not None) == plain, tokens


@pytest.mark.slow
def test_large_off_and_ascii_ply_are_the_references(tmp_path: Path) -> None:
    """Past KERNEL_BYTES, OFF and ASCII PLY coordinates go through the kernel: the reference's mesh
    bit for bit."""
    mesh = shapes.large_torus(40_000)
    off = tmp_path / "torus.off"
    off.write_text(
        f"OFF\n{mesh.n_vertices} {mesh.n_faces} 0\n"
        + ("%r %r %r\n" * mesh.n_vertices) % tuple(mesh.vertices.ravel().tolist())
        + ("4 %d %d %d %d\n" * mesh.n_faces) % tuple(mesh.faces.ravel().tolist())
    )
    assert off.stat().st_size >= meshfile.KERNEL_BYTES
    reference = meshfile._read_off_lines(off, off.read_bytes())
    assert (
        meshfile._off_fast(off.read_bytes()).vertices.tobytes()
        == reference.vertices.tobytes()
        == mesh.vertices.tobytes()
    )
    ply = tmp_path / "torus.ply"
    meshio.ply.write(
        str(ply), meshio.Mesh(mesh.vertices, [("quad", mesh.faces.astype(np.int32))]), binary=False
    )
    data = ply.read_bytes()
    header = meshfile._ply_header(ply, data)
    layout = meshfile._ply_layout(header)
    assert layout is not None
    records = meshfile._ply_text(data, header, layout)
    assert records is not None and records[0].tobytes() == mesh.vertices.tobytes()
    lines = meshfile._read_ply_lines(ply, data, header, layout)
    assert lines.vertices.tobytes() == mesh.vertices.tobytes()
    assert np.array_equal(lines.faces, records[1].reshape(-1, 4))
    assert (
        read_mesh(ply).vertices.tobytes()
        == read_mesh(off).vertices.tobytes()
        == mesh.vertices.tobytes()
    )
