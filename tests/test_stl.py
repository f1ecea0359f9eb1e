"""STL input (what scanners write; issue 33): binary and ASCII, corners welded into shared
vertices, every damaged file one clear error."""

from __future__ import annotations

import struct
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import g1patch
from g1patch.errors import FormatError, G1PatchError
from g1patch.io.meshfile import read_polygons, write_triangles

#: a tetrahedron: 4 vertices, 4 outward triangles
POINTS = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])
TRIANGLES = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])


def ascii_stl(points: np.ndarray, triangles: np.ndarray, separator: str = " ") -> bytes:
    lines = ["solid tetra"]
    for triangle in triangles:
        lines += ["  facet normal 0 0 0", "    outer loop"]
        lines += [
            "      vertex" + separator + separator.join(repr(float(x)) for x in points[v])
            for v in triangle
        ]
        lines += ["    endloop", "  endfacet"]
    return ("\n".join([*lines, "endsolid tetra"]) + "\n").encode()


def binary_stl(points: np.ndarray, triangles: np.ndarray, header: bytes = b"") -> bytes:
    body = b"".join(
        struct.pack("<3f", 0, 0, 0) + points[t].astype("<f4").tobytes() + b"\0\0" for t in triangles
    )
    return header.ljust(80, b" ")[:80] + struct.pack("<I", len(triangles)) + body


def same_triangles(read: tuple[np.ndarray, np.ndarray, np.ndarray]) -> None:
    points, corners, sizes = read
    assert len(points) == 4 and (sizes == 3).all()
    np.testing.assert_array_equal(points[corners.reshape(-1, 3)], POINTS[TRIANGLES])


def test_binary_ascii_and_our_own_stl_read_as_four_shared_vertices(tmp_path: Path) -> None:
    files = {
        "ascii.stl": ascii_stl(POINTS, TRIANGLES),
        "tabs.stl": ascii_stl(POINTS, TRIANGLES, "\t"),
        "binary.stl": binary_stl(POINTS, TRIANGLES),
        # a binary file whose header starts like ASCII: its size decides
        "solid.stl": binary_stl(POINTS, TRIANGLES, b"solid exported by some CAD system"),
    }
    for name, data in files.items():
        (tmp_path / name).write_bytes(data)
        same_triangles(read_polygons(tmp_path / name))
    write_triangles(tmp_path / "ours.stl", POINTS, TRIANGLES)
    same_triangles(read_polygons(tmp_path / "ours.stl"))
    mesh = g1patch.read(tmp_path / "binary.stl")  # a quad mesh: each triangle split in three
    assert mesh.n_faces == 12


@pytest.mark.parametrize(
    ("data", "message"),
    [
        (binary_stl(POINTS, TRIANGLES)[:-7], "neither binary STL nor ASCII STL"),
        (binary_stl(POINTS, TRIANGLES[:0]), "announces 0 triangles"),
        (b"solid x\nendsolid x\n", "no 'vertex' lines"),
        (ascii_stl(POINTS, TRIANGLES).replace(b"      vertex 0.0 0.0 1.0\n", b"", 1), "not three"),
        (ascii_stl(POINTS, TRIANGLES).replace(b"vertex 1.0 0.0 0.0", b"vertex 1.0 x 0.0", 1), ":"),
    ],
)
def test_damaged_files_are_one_clear_error(tmp_path: Path, data: bytes, message: str) -> None:
    path = tmp_path / "bad.stl"
    path.write_bytes(data)
    with pytest.raises(FormatError, match=message) as error:
        read_polygons(path)
    assert str(path) in str(error.value)


def test_a_bad_ascii_vertex_names_its_line(tmp_path: Path) -> None:
    path = tmp_path / "bad.stl"
    path.write_bytes(
        ascii_stl(POINTS, TRIANGLES).replace(b"vertex 1.0 0.0 0.0", b"vertex 1 x 0", 1)
    )
    with pytest.raises(FormatError, match=r"bad\.stl:6: a vertex is not three numbers"):
        read_polygons(path)


@settings(max_examples=200, deadline=None, suppress_health_check=list(HealthCheck))
@given(
    binary=st.booleans(),
    cut=st.integers(0, 400),
    flips=st.lists(st.tuples(st.integers(0, 400), st.integers(0, 255)), max_size=6),
)
def test_any_damage_is_a_named_error_or_a_mesh(
    tmp_path_factory: pytest.TempPathFactory,
    binary: bool,
    cut: int,
    flips: list[tuple[int, int]],
) -> None:
    """Truncated or overwritten bytes: the reader returns polygons or raises one of the project's
    errors, never anything else (no NaN slips through: the polygon checks refuse them)."""
    data = bytearray(binary_stl(POINTS, TRIANGLES) if binary else ascii_stl(POINTS, TRIANGLES))
    for at, value in flips:
        if at < len(data):
            data[at] = value
    path = tmp_path_factory.mktemp("stl") / "damaged.stl"
    path.write_bytes(bytes(data[: max(len(data) - cut, 0)]))
    try:
        points, _, _ = read_polygons(path)
    except G1PatchError:
        return
    assert np.isfinite(points).all()
