"""Texture coordinates (OBJ ``vt``) from the cage through the build, refinement, the network file,
the tessellated OBJ/PLY exports and the viewer."""

from __future__ import annotations

import json
from pathlib import Path

import meshio
import numpy as np
import pytest

import g1patch
from g1patch.build import build_network
from g1patch.errors import FormatError
from g1patch.io.meshfile import read_mesh
from g1patch.io.meshfile.obj import _face_sizes, _obj_uvs_lines, _read_obj
from g1patch.io.network_file import FORMAT_VERSION, load_network, save_network
from g1patch.mesh import QuadMesh
from g1patch.network import patch_uvs

CUBE_POINTS = [
    (0, 0, 0),
    (1, 0, 0),
    (1, 1, 0),
    (0, 1, 0),
    (0, 0, 1),
    (1, 0, 1),
    (1, 1, 1),
    (0, 1, 1),
]
CUBE_FACES = [
    (0, 3, 2, 1),
    (4, 5, 6, 7),
    (0, 1, 5, 4),
    (1, 2, 6, 5),
    (2, 3, 7, 6),
    (3, 0, 4, 7),
]


def _obj_text(points, faces, uvs) -> str:
    """OBJ with one ``vt`` per face corner (``uvs``: per face, a list of (u, v))."""
    lines = [f"v {x} {y} {z}" for x, y, z in points]
    lines += [f"vt {u!r} {v!r}" for face in uvs for u, v in face]
    lines.append("vn 0 0 1")
    at = 1
    for face in faces:
        corners = []
        for vertex in face:
            corners.append(f"{vertex + 1}/{at}/1" if at % 2 else f"{vertex + 1}/{at}")
            at += 1
        lines.append("f " + " ".join(corners))
    return "\n".join(lines) + "\n"


def _cube_uvs() -> list[list[tuple[float, float]]]:
    """A chart per face (a cross layout, so vertices have several UVs: seams in UV space)."""
    square = [(0.0, 0.0), (0.25, 0.0), (0.25, 0.25), (0.0, 0.25)]
    offsets = [(0.25, 0.0), (0.25, 0.5), (0.25, 0.25), (0.5, 0.25), (0.25, 0.75), (0.0, 0.25)]
    return [[(u + a, v + b) for u, v in square] for a, b in offsets]


def _house() -> tuple[list, list, list]:
    """Two quads and a pentagon, flat but for a bump; the second quad in a chart of its own."""
    points = [
        (0, 0, 0),
        (1, 0, 0),
        (2, 0, 0),
        (0, 1, 0),
        (1, 1, 0.3),
        (2, 1, 0),
        (0, 2, 0),
        (2, 2, 0),
    ]
    faces = [(0, 1, 4, 3), (1, 2, 5, 4), (3, 4, 5, 7, 6)]
    uvs = [
        [(0.1 * points[v][0], 0.1 * points[v][1]) for v in faces[0]],
        [(3.0 + 0.2 * points[v][0], 0.2 * points[v][1]) for v in faces[1]],
        [(0.1 * points[v][0], 0.1 * points[v][1]) for v in faces[2]],
    ]
    return points, faces, uvs


def _read_exported_obj(path: Path):
    """Points, vt and triangles (point and vt indices) of an OBJ the export wrote."""
    points, uvs, corners = [], [], []
    for line in path.read_text().splitlines():
        parts = line.split()
        if not parts:
            continue
        if parts[0] == "v":
            points.append([float(x) for x in parts[1:4]])
        elif parts[0] == "vt":
            uvs.append([float(x) for x in parts[1:3]])
        elif parts[0] == "f":
            corners.append([[int(i) - 1 for i in token.split("/")] for token in parts[1:]])
    return np.array(points), np.array(uvs), np.array(corners)


def _uvs_at_cage_vertices(points, faces, uvs):
    """Per cage vertex, the set of its UVs over its faces."""
    found: dict[int, set[tuple[float, float]]] = {}
    for face, face_uvs in zip(faces, uvs, strict=True):
        for vertex, uv in zip(face, face_uvs, strict=True):
            found.setdefault(vertex, set()).add(tuple(uv))
    return found


def _check_export_uvs(tmp_path: Path, points, faces, uvs, **build) -> g1patch.Surface:
    """Build from an OBJ with vt; the tessellated OBJ's and PLY's UVs at every cage vertex are the
    cage's, exactly."""
    source = tmp_path / "cage.obj"
    source.write_text(_obj_text(points, faces, uvs))
    surface = g1patch.smooth(source, **build)
    assert surface.uv is not None and surface.uv.shape == (surface.n_patches, 4, 2)
    expected = _uvs_at_cage_vertices(points, faces, uvs)
    # the surface passes through the network's vertices; a cage vertex keeps its index through
    # the split and the refinement (which moves it by Catmull–Clark's rules)
    assert surface.network.vertices is not None
    at_vertex = surface.network.vertices[: len(points)]
    if not build.get("refine"):
        np.testing.assert_array_equal(at_vertex, np.asarray(points, float))

    out = surface.export(tmp_path / "out.obj", resolution=5)
    tess_points, tess_uv, corners = _read_exported_obj(out)
    flat = corners.reshape(-1, 2)
    for vertex, wanted in expected.items():
        at = np.flatnonzero(np.linalg.norm(tess_points - at_vertex[vertex], axis=1) < 1e-9)
        assert at.size == 1, (vertex, at)
        got = {tuple(uv) for uv in tess_uv[flat[np.isin(flat[:, 0], at), 1]].tolist()}
        assert got == wanted, (vertex, got, wanted)

    ply = meshio.read(surface.export(tmp_path / "out.ply", resolution=5))
    st = np.stack([ply.point_data["s"], ply.point_data["t"]], axis=1)
    for vertex, wanted in expected.items():
        near = np.linalg.norm(ply.points - at_vertex[vertex], axis=1) < 1e-9
        assert {tuple(uv) for uv in st[near].tolist()} == wanted
    return surface


@pytest.mark.parametrize("method", ["gregory", "split4"])
@pytest.mark.parametrize("refine", [0, 1])
def test_cube_with_uv_seams_keeps_its_vt_at_the_vertices(
    tmp_path: Path, method: str, refine: int
) -> None:
    points = [tuple(float(c) for c in p) for p in CUBE_POINTS]
    surface = _check_export_uvs(
        tmp_path, points, CUBE_FACES, _cube_uvs(), method=method, refine=refine
    )
    assert surface.n_patches == 6 * 4**refine * (4 if method == "split4" else 1)


@pytest.mark.parametrize("method", ["gregory", "split4"])
@pytest.mark.parametrize("refine", [0, 1])
def test_pentagon_and_a_seam_keep_their_vt(tmp_path: Path, method: str, refine: int) -> None:
    points, faces, uvs = _house()
    _check_export_uvs(tmp_path, points, faces, uvs, method=method, refine=refine)


def test_polygon_split_uses_midpoints_and_the_centre() -> None:
    points, faces, uvs = _house()
    corner_uv = np.array([uv for face in uvs for uv in face])
    mesh = QuadMesh.from_arrays(points, [list(f) for f in faces], uv=corner_uv)
    assert mesh.uv is not None and mesh.uv.shape == (13, 4, 2)
    pentagon = np.array(uvs[2])
    centre = pentagon.mean(axis=0)
    for i in range(5):  # quad 8 + i of the pentagon: corner, midpoint, centre, midpoint
        quad = mesh.uv[8 + i]
        np.testing.assert_array_equal(quad[0], pentagon[i])
        np.testing.assert_allclose(quad[1], 0.5 * (pentagon[i] + pentagon[(i + 1) % 5]))
        np.testing.assert_allclose(quad[2], centre)
        np.testing.assert_allclose(quad[3], 0.5 * (pentagon[i - 1] + pentagon[i]))


@pytest.mark.parametrize("method", ["gregory", "split4", "corner"])
def test_patch_corners_carry_the_faces_uvs(method: str) -> None:
    """Patch corner k sits at face corner k (gregory, corner) and split4's sub-patch 4f + k covers
    the quarter at corner k: their UVs follow the same map as their points."""
    rng = np.random.default_rng(1)
    mesh = QuadMesh.from_arrays(CUBE_POINTS, CUBE_FACES, uv=rng.random((24, 2)))
    assert mesh.uv is not None
    network = build_network(mesh, method)
    assert network.uv is not None
    corners = network.patches.evaluate(np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]))
    if method == "split4":
        np.testing.assert_allclose(
            corners[np.arange(24), np.arange(24) % 4], mesh.vertices[mesh.faces.ravel()], atol=1e-12
        )
        np.testing.assert_array_equal(
            network.uv[np.arange(24), np.arange(24) % 4], mesh.uv.reshape(-1, 2)
        )
        np.testing.assert_allclose(network.uv[0::4, 2], mesh.uv.mean(axis=1))
    else:
        np.testing.assert_allclose(corners, mesh.vertices[mesh.faces], atol=1e-12)
        np.testing.assert_array_equal(network.uv, mesh.uv)


def test_refinement_is_bilinear_per_face() -> None:
    from g1patch.subdivision import refine

    uv = np.array([[0.0, 0.0], [2.0, 0.0], [2.0, 1.0], [0.0, 1.0]] * 6)
    mesh = QuadMesh.from_arrays(CUBE_POINTS, CUBE_FACES, uv=uv)
    fine = refine(mesh, 2)
    assert fine.uv is not None and fine.uv.shape == (96, 4, 2)
    # every child lies in its face's rectangle, the grid spacing 1/4 of it
    assert set(np.unique(fine.uv[..., 0]).tolist()) == {0.0, 0.5, 1.0, 1.5, 2.0}
    assert set(np.unique(fine.uv[..., 1]).tolist()) == {0.0, 0.25, 0.5, 0.75, 1.0}
    np.testing.assert_array_equal(patch_uvs(mesh.uv, 1), mesh.uv)


def test_reorientation_reverses_the_uvs_with_the_corners() -> None:
    points = [(0, 0, 0), (1, 0, 0), (2, 0, 0), (0, 1, 0), (1, 1, 0), (2, 1, 0)]
    faces = [(0, 1, 4, 3), (1, 4, 5, 2)]  # the second one clockwise
    offsets = [0.0, 10.0]
    corner_uv = [
        (points[v][0] + o, points[v][1]) for f, o in zip(faces, offsets, strict=True) for v in f
    ]
    mesh = QuadMesh.from_arrays(points, faces, uv=corner_uv)
    assert mesh.repairs and mesh.uv is not None
    xy = mesh.vertices[mesh.faces][..., :2]
    shift = mesh.uv - xy  # (offset, 0) at every corner of a face
    np.testing.assert_array_equal(shift[..., 1], 0.0)
    assert sorted(shift[:, :, 0].max(axis=1).tolist()) == [0.0, 10.0]
    np.testing.assert_array_equal(shift[:, :, 0], shift[:, :1, 0].repeat(4, axis=1))


def test_network_file_round_trip_and_version_3(tmp_path: Path) -> None:
    points, faces, uvs = _house()
    mesh = QuadMesh.from_arrays(
        points, [list(f) for f in faces], uv=[uv for face in uvs for uv in face]
    )
    network = build_network(mesh, "split4")
    save_network(tmp_path / "n.npz", network)
    with np.load(tmp_path / "n.npz") as data:
        assert json.loads(str(data["header"]))["version"] == FORMAT_VERSION >= 4  # UVs since 4
        members = {name: data[name] for name in data.files}
    loaded = load_network(tmp_path / "n.npz")
    assert loaded.uv is not None
    np.testing.assert_array_equal(loaded.uv, network.uv)
    # a version-3 file (no uv) still loads, without UVs
    header = json.loads(str(members["header"]))
    header["version"] = 3
    members["header"] = np.array(json.dumps(header))
    del members["uv"]
    np.savez(tmp_path / "old.npz", **members)
    old = load_network(tmp_path / "old.npz")
    assert old.uv is None
    np.testing.assert_array_equal(old.patches.control, network.patches.control)


def test_files_without_vt_read_and_write_as_before(tmp_path: Path) -> None:
    source = tmp_path / "plain.obj"
    source.write_text(
        "\n".join(f"v {x} {y} {z}" for x, y, z in CUBE_POINTS)
        + "\n"
        + "\n".join("f " + " ".join(str(v + 1) for v in f) for f in CUBE_FACES)
        + "\n"
    )
    parsed = _read_obj(source, source.read_bytes())
    assert parsed.uv is None
    surface = g1patch.smooth(source)
    assert surface.mesh is not None and surface.mesh.uv is None and surface.uv is None
    text = surface.export(tmp_path / "out.obj", resolution=4).read_text()
    assert "vt" not in text and "/" not in text
    surface.export(tmp_path / "n.npz")
    with np.load(tmp_path / "n.npz") as data:
        assert "uv" not in data.files
    assert "s" not in meshio.read(surface.export(tmp_path / "out.ply")).point_data
    assert '"uv":false' in surface.view()


def test_faces_without_vt_give_no_uvs(tmp_path: Path) -> None:
    text = _obj_text(CUBE_POINTS, CUBE_FACES, _cube_uvs()).replace("f 1/1/1 ", "f 1//1 ")
    source = tmp_path / "partial.obj"
    source.write_text(text)
    assert read_mesh(source).uv is None


def test_fast_and_line_readers_agree_and_bad_indices_name_the_line(tmp_path: Path) -> None:
    text = _obj_text(CUBE_POINTS, CUBE_FACES, _cube_uvs())
    data = text.encode()
    parsed = _read_obj(Path("a.obj"), data)
    assert parsed.uv is not None and parsed.uv.shape == (24, 2)
    reference = _obj_uvs_lines(Path("a.obj"), data, _face_sizes(parsed.faces))
    np.testing.assert_array_equal(parsed.uv, reference)
    # 'vt u' (v = 0) and negative indices go the reference way
    short = text.replace("vt 0.25 0.0\n", "vt 0.25\n", 1).replace("f 1/1/1", "f 1/-24/1")
    parsed = _read_obj(Path("b.obj"), short.encode())
    assert parsed.uv is not None and tuple(parsed.uv[0]) == (0.25, 0.0)
    bad = tmp_path / "bad.obj"
    bad.write_text(text.replace("f 1/1/1", "f 1/99/1"))
    with pytest.raises(
        FormatError, match=r"bad\.obj:34: face corner '1/99/1' names texture coordinate 99"
    ):
        read_mesh(bad)


def test_viewer_carries_the_uvs(tmp_path: Path) -> None:
    source = tmp_path / "cage.obj"
    source.write_text(_obj_text(CUBE_POINTS, CUBE_FACES, _cube_uvs()))
    page = g1patch.smooth(source).view(resolution=3)
    assert '"uv":true' in page and 'id="uv-mode"' in page and "@@" not in page


def test_a_merge_of_faces_drops_the_uvs_and_says_so() -> None:
    from g1patch.mesh.quadmesh import UV_DROPPED

    points = [(0, 0, 0), (1, 0, 0), (2, 0, 0), (0, 1, 0), (1, 1, 0), (2, 1, 0), (0.5, 0.5, 0)]
    faces = [(6, 0, 1, 4), (6, 4, 3, 0), (1, 2, 5, 4)]  # vertex 6: interior valence 2
    mesh = QuadMesh.from_arrays(points, faces, uv=np.zeros((12, 2)))
    assert mesh.uv is None and UV_DROPPED in mesh.repairs
    assert UV_DROPPED in mesh.repair_note


# ------------------------------------------------------------------ PLY texture coordinates
_STRIP = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [2, 0, 0], [2, 1, 0]], float)
_STRIP_FACES = np.array([[0, 1, 2, 3], [1, 4, 5, 2]])
_STRIP_ST = _STRIP[:, :2] * 0.5 + 0.125


@pytest.mark.parametrize("binary", [False, True])
@pytest.mark.parametrize("names", [("s", "t"), ("u", "v"), ("texture_u", "texture_v")])
def test_ply_vertex_uvs_become_corner_uvs(tmp_path: Path, binary: bool, names: tuple) -> None:
    path = tmp_path / "strip.ply"
    data = {names[0]: _STRIP_ST[:, 0], names[1]: _STRIP_ST[:, 1]}
    mesh = meshio.Mesh(_STRIP, [("quad", _STRIP_FACES.astype(np.int32))], point_data=data)
    meshio.ply.write(str(path), mesh, binary=binary)
    read = read_mesh(path)
    assert read.uv is not None and np.array_equal(read.uv, _STRIP_ST[read.faces])


def _texcoord_header(form: str, coordinate: str = "float") -> str:
    return (
        f"ply\nformat {form} 1.0\nelement vertex 6\nproperty {coordinate} x\n"
        f"property {coordinate} y\nproperty {coordinate} z\nelement face 2\n"
        "property list uchar int vertex_indices\nproperty list uchar float texcoord\nend_header\n"
    )


def test_ply_texcoord_lists_ascii_and_binary(tmp_path: Path) -> None:
    # face-varying: each face its own chart (a seam between them)
    corner_uv = np.arange(16, dtype=np.float32).reshape(2, 8) / 16
    text = tmp_path / "a.ply"
    rows = [" ".join(map(str, p)) for p in _STRIP]
    rows += [
        f"4 {' '.join(map(str, q))} 8 {' '.join(map(repr, uv.tolist()))}"
        for q, uv in zip(_STRIP_FACES, corner_uv, strict=True)
    ]
    text.write_text(_texcoord_header("ascii") + "\n".join(rows) + "\n")
    record = np.dtype([("n", "u1"), ("i", "<i4", (4,)), ("tn", "u1"), ("t", "<f4", (8,))])
    faces = np.zeros(2, record)
    faces["n"], faces["i"], faces["tn"], faces["t"] = 4, _STRIP_FACES, 8, corner_uv
    binary = tmp_path / "b.ply"
    binary.write_bytes(
        _texcoord_header("binary_little_endian", "double").encode()
        + _STRIP.astype("<f8").tobytes()
        + faces.tobytes()
    )
    for path in (text, binary):
        mesh = read_mesh(path)
        assert mesh.uv is not None
        assert np.array_equal(mesh.uv.reshape(2, 8), corner_uv.astype(np.float64)), path


def test_bad_ply_texture_coordinates_name_the_line(tmp_path: Path) -> None:
    path = tmp_path / "bad.ply"
    rows = [" ".join(map(str, p)) for p in _STRIP]
    rows += ["4 0 1 2 3 8 0 0 1 0 1 1 0 nan", "4 1 4 5 2 6 0 0 1 0 1 1"]
    path.write_text(_texcoord_header("ascii") + "\n".join(rows) + "\n")
    with pytest.raises(FormatError, match=r"bad\.ply:18: expected a face"):
        read_mesh(path)
    rows[-1] = "4 1 4 5 2 8 0 0 1 0 1 1 0 1"
    path.write_text(_texcoord_header("ascii") + "\n".join(rows) + "\n")
    with pytest.raises(FormatError, match=r"bad\.ply:17: face: texture coordinates .* not finite"):
        read_mesh(path)


def test_the_in_memory_api_takes_corner_uvs() -> None:
    """``QuadMesh.from_arrays(uv=...)`` (one UV per face corner, in the faces' order) is the way
    in for UVs that come from no file; ``g1patch.smooth`` keeps them."""
    uv = _STRIP_ST[_STRIP_FACES].reshape(-1, 2)
    mesh = QuadMesh.from_arrays(_STRIP, _STRIP_FACES, uv=uv)
    surface = g1patch.smooth(mesh, method="gregory")
    assert surface.uv is not None and np.array_equal(surface.uv, _STRIP_ST[_STRIP_FACES])
