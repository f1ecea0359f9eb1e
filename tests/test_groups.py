"""Face groups (issue 31): OBJ ``usemtl``/``g``/``o`` and ``mtllib`` colours from the cage through
the polygon split, repairs, refinement (global, adaptive, split4), the network file (version 6,
hostile members refused), STEP and .3dm faces (names and colours read back) and the tessellated
OBJ's ``g``/``usemtl``."""

from __future__ import annotations

import json
import logging
import re
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from ocp_marks import requires_ocp

import g1patch
from g1patch import shapes
from g1patch.build import build_network
from g1patch.errors import FormatError, InputError
from g1patch.io.meshfile import read_mesh
from g1patch.io.network_file import FORMAT_VERSION, load_network, save_network
from g1patch.mesh import QuadMesh
from g1patch.mesh.groups import FaceGroups
from g1patch.subdivision import refine

CUBE_OBJ = """\
mtllib cube.mtl
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
v 0 0 1
v 1 0 1
v 1 1 1
v 0 1 1
f 1 4 3 2
o body
usemtl red
f 5 6 7 8
f 1 2 6 5
g side
usemtl blue paint
f 2 3 7 6
f 3 4 8 7
g plain
f 4 1 5 8
"""
CUBE_MTL = "newmtl red\nKd 1 0 0\nnewmtl blue paint\nKd 0 0.5 1\n"
#: the cube's faces' groups: none, red ×2, blue paint ×3 (the material outlives 'g plain')
CUBE_IDS = [-1, 0, 0, 1, 1, 1]


def _cube(tmp_path: Path, mtl: str | None = CUBE_MTL) -> Path:
    (tmp_path / "cube.obj").write_text(CUBE_OBJ)
    if mtl is not None:
        (tmp_path / "cube.mtl").write_text(mtl)
    return tmp_path / "cube.obj"


def test_materials_name_the_groups_and_the_library_colours_them(tmp_path: Path) -> None:
    mesh = read_mesh(_cube(tmp_path))
    assert mesh.groups is not None
    assert mesh.groups.ids.tolist() == CUBE_IDS
    assert mesh.groups.names == ("red", "blue paint")
    assert np.array_equal(mesh.groups.colours, [[1, 0, 0], [0, 0.5, 1]])


def test_group_names_without_materials(tmp_path: Path) -> None:
    path = tmp_path / "g.obj"
    path.write_text(CUBE_OBJ.replace("usemtl red\n", "").replace("usemtl blue paint\n", ""))
    groups = read_mesh(path).groups
    assert groups is not None
    assert groups.ids.tolist() == [-1, 0, 0, 1, 1, 2]
    assert groups.names == ("body", "side", "plain") and np.isnan(groups.colours).all()


def test_missing_or_broken_library_keeps_the_names(
    tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    with caplog.at_level(logging.WARNING):
        missing = read_mesh(_cube(tmp_path, mtl=None)).groups
    assert missing is not None and missing.names == ("red", "blue paint")
    assert np.isnan(missing.colours).all()
    assert "cube.mtl" in caplog.text and "not found" in caplog.text
    caplog.clear()
    (tmp_path / "cube.mtl").write_bytes(b"newmtl red\nKd 1 x 0\nnewmtl blue paint\n\xff\xfe")
    with caplog.at_level(logging.WARNING):
        broken = read_mesh(tmp_path / "cube.obj").groups
    assert broken is not None and np.isnan(broken.colours).all()
    assert len(caplog.records) == 1  # one line: the library is not UTF-8


def test_files_without_groups_have_none_and_bad_statements_name_the_line(tmp_path: Path) -> None:
    plain = tmp_path / "plain.obj"
    plain.write_text("\n".join(x for x in CUBE_OBJ.splitlines() if x[:1] in "vf") + "\n")
    assert read_mesh(plain).groups is None
    bad = tmp_path / "bad.obj"
    bad.write_text(CUBE_OBJ.replace("usemtl red", "usemtl"))
    with pytest.raises(FormatError, match=r"bad\.obj:12: expected 'usemtl NAME'"):
        read_mesh(bad)


def test_non_ascii_names_go_the_line_way(tmp_path: Path) -> None:
    path = tmp_path / "k.obj"
    path.write_text(CUBE_OBJ.replace("usemtl red", "usemtl Körper"), encoding="utf-8")
    groups = read_mesh(path).groups
    assert groups is not None and groups.names[0] == "Körper"


def test_split_and_repair_carry_the_groups() -> None:
    # a pentagon and a quad: the pentagon's 5 quads keep its group
    points = [(0, 0, 0), (2, 0, 0), (3, 1, 0), (1, 2, 0), (-1, 1, 0), (4, 3, 0), (2, 4, 0)]
    faces = [(0, 1, 2, 3, 4), (3, 2, 5, 6)]
    groups = FaceGroups(np.array([1, 0]), ("a", "b"))
    mesh = QuadMesh.from_arrays(points, faces, groups=groups)
    assert mesh.groups is not None and mesh.groups.ids.tolist() == [1] * 5 + [0] * 4
    # a flipped face is repaired: its group follows it
    flipped = QuadMesh.from_arrays(
        [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (2, 0, 0), (2, 1, 0)],
        [(0, 1, 2, 3), (1, 2, 5, 4)],
        groups=FaceGroups(np.array([0, 1]), ("a", "b")),
    )
    assert flipped.repairs and flipped.groups is not None
    assert flipped.groups.ids.tolist() == [0, 1]
    with pytest.raises(InputError, match="groups: expected one per face"):
        QuadMesh.from_arrays(points, faces, groups=FaceGroups(np.array([0]), ("a",)))


@pytest.mark.parametrize(
    ("method", "shape", "options", "per_face"),
    [
        ("gregory", "interpolate", {}, 1),
        ("split4", "interpolate", {}, 4),
        ("gregory", "interpolate", {"refine": 1}, 4),
        ("split4", "limit", {"refine": 1}, 16),
    ],
)
def test_every_patch_takes_its_cage_face_group(
    tmp_path: Path, method: str, shape: str, options: dict, per_face: int
) -> None:
    mesh = read_mesh(_cube(tmp_path))
    network = build_network(mesh, method, shape, **options)
    assert network.groups is not None and network.n_patches == 6 * per_face
    assert network.groups.ids.tolist() == np.repeat(CUBE_IDS, per_face).tolist()


def test_local_refinement_follows_the_root_faces() -> None:
    """``--method gregory --shape limit`` on a cube refined three times, at 1e-4 (within it at
    once) and 3e-6 (refined locally round its 8 valence-3 vertices, as in test_adaptive): each
    patch is in its root face's group, the side of x = 0 its centre lies on."""
    cage = refine(shapes.cube(), 3)
    right = cage.vertices[cage.faces].mean(axis=1)[:, 0] > 0
    cage = replace(cage, groups=FaceGroups(right.astype(np.int64), ("left", "right")))
    for tolerance in (1e-4, 3e-6):
        network = build_network(cage, "gregory", "limit", tolerance=tolerance)
        assert network.groups is not None and network.groups.names == ("left", "right")
        centre = network.patches.world_points()[:, :4].mean(axis=1)  # type: ignore[attr-defined]
        assert np.array_equal(network.groups.ids, (centre[:, 0] > 0).astype(np.int64))
    assert network.hanging is not None and len(network.hanging)  # refined locally


def test_network_file_round_trip_and_older_versions(tmp_path: Path) -> None:
    network = build_network(read_mesh(_cube(tmp_path)), "gregory")
    save_network(tmp_path / "n.npz", network)
    loaded = load_network(tmp_path / "n.npz")
    assert FORMAT_VERSION == 6 and loaded.groups is not None
    assert loaded.groups.ids.tolist() == CUBE_IDS and loaded.groups.names == ("red", "blue paint")
    assert np.array_equal(loaded.groups.colours, network.groups.colours)  # type: ignore[union-attr]
    # a version 5 file's members of those names are not its own: ignored
    old = _rewrite(tmp_path / "n.npz", tmp_path / "v5.npz", version=5)
    assert load_network(old).groups is None


def _rewrite(source: Path, target: Path, version: int | None = None, **arrays: object) -> Path:
    with np.load(source, allow_pickle=False) as data:
        members = {name: data[name] for name in data.files}
    if version is not None:
        header = json.loads(str(members["header"]))
        header["version"] = version
        members["header"] = np.array(json.dumps(header))
    members.update({name: np.asarray(value) for name, value in arrays.items()})
    members = {name: value for name, value in members.items() if value.dtype != object}
    np.savez(target, **members)  # type: ignore[arg-type]
    return target


HOSTILE = {
    "ids of 2 columns": ({"group": np.zeros((6, 2), np.int64)}, r"member 'group\.npy': expected"),
    "id past the names": ({"group": np.array([0, 0, 0, 0, 0, 2])}, r"value 2 at index \(5,\)"),
    "id below -1": ({"group": np.array([-2, 0, 0, 0, 0, 0])}, r"out of range -1\.\.1"),
    "ids as floats": ({"group": np.zeros(6)}, r"'group\.npy': expected integers"),
    "NaN in a colour": (
        {"group_colour": np.array([[1.0, np.nan, 0.0], [0.0, 0.0, 1.0]])},
        r"'group_colour\.npy': colour .* neither RGB",
    ),
    "colour above 1": (
        {"group_colour": np.array([[2.0, 0.0, 0.0], [0.0, 0.0, 1.0]])},
        r"neither RGB in \[0, 1\]",
    ),
    "a colour short": ({"group_colour": np.zeros((1, 3))}, r"'group_colour\.npy': expected"),
    "names not JSON": ({"group_names": np.array("red, blue")}, r"'group_names\.npy'.*no JSON"),
    "names not strings": ({"group_names": np.array("[1, 2]")}, r"list of names \(strings\)"),
    "empty name": ({"group_names": np.array('["", "b"]')}, r"'group_names\.npy': name ''"),
    "name with a line break": ({"group_names": np.array('["a\\nb", "b"]')}, "printable"),
}


@pytest.mark.parametrize("case", sorted(HOSTILE))
def test_hostile_group_members_are_one_format_error(case: str, tmp_path: Path) -> None:
    network = build_network(read_mesh(_cube(tmp_path)), "gregory")
    save_network(tmp_path / "n.npz", network)
    arrays, message = HOSTILE[case]
    bad = _rewrite(tmp_path / "n.npz", tmp_path / "bad.npz", **arrays)
    with pytest.raises(FormatError, match=message):
        load_network(bad)


@pytest.mark.parametrize("member", ["group", "group_names", "group_colour"])
def test_group_members_come_together(member: str, tmp_path: Path) -> None:
    save_network(tmp_path / "n.npz", build_network(read_mesh(_cube(tmp_path)), "gregory"))
    with np.load(tmp_path / "n.npz") as data:
        members = {name: data[name] for name in data.files if name != member}
    np.savez(tmp_path / "bad.npz", **members)  # type: ignore[arg-type]
    with pytest.raises(FormatError, match=f"network file lacks {member}"):
        load_network(tmp_path / "bad.npz")


def test_tessellated_obj_writes_a_group_per_material(tmp_path: Path) -> None:
    surface = g1patch.smooth(_cube(tmp_path), method="gregory")
    surface.export(tmp_path / "out.obj", resolution=3)
    text = (tmp_path / "out.obj").read_text()
    assert re.findall(r"^(?:g|usemtl) .*$", text, re.M) == [
        "g red",
        "usemtl red",
        "g blue paint",
        "usemtl blue paint",
    ]
    assert "mtllib" not in text
    # 8 triangles a patch at resolution 3 (read back, each split into 3 quads); the groupless
    # face's come first, before any statement
    assert text.index("\nf ") < text.index("\ng red")
    again = read_mesh(tmp_path / "out.obj").groups
    assert again is not None and np.bincount(again.ids + 1).tolist() == [24, 48, 72]


@requires_ocp
@pytest.mark.parametrize("method", ["split4", "gregory"])
def test_step_faces_are_named_and_coloured_by_group(tmp_path: Path, method: str) -> None:
    from OCP.Quantity import Quantity_Color, Quantity_TypeOfColor
    from OCP.STEPCAFControl import STEPCAFControl_Reader
    from OCP.TCollection import TCollection_ExtendedString
    from OCP.TDF import TDF_ChildIterator
    from OCP.TDocStd import TDocStd_Document
    from OCP.TopAbs import TopAbs_FACE
    from OCP.TopExp import TopExp_Explorer
    from OCP.XCAFDoc import XCAFDoc_ColorType, XCAFDoc_DocumentTool

    surface = g1patch.smooth(_cube(tmp_path), method=method)
    target = tmp_path / "cube.step"
    result = surface.export(target)
    assert result.faces == 6 and result.max_g1_angle_deg < 1e-7
    names = re.findall(r"ADVANCED_FACE\('([^']*)'", target.read_text())
    assert sorted(names) == ["blue paint 3", "blue paint 4", "blue paint 5", "face 0"] + [
        "red 1",
        "red 2",
    ]
    reader = STEPCAFControl_Reader()
    reader.SetColorMode(True)
    document = TDocStd_Document(TCollection_ExtendedString("XmlOcaf"))
    assert reader.ReadFile(str(target)) == reader.ReadFile(str(target))
    reader.Transfer(document)
    shapes = XCAFDoc_DocumentTool.ShapeTool_s(document.Main())
    palette = XCAFDoc_DocumentTool.ColorTool_s(document.Main())
    shape = shapes.GetShape_s(TDF_ChildIterator(shapes.BaseLabel(), False).Value())
    colours = []
    explorer = TopExp_Explorer(shape, TopAbs_FACE)
    while explorer.More():
        colour = Quantity_Color()
        if palette.GetColor(explorer.Current(), XCAFDoc_ColorType.XCAFDoc_ColorSurf, colour):
            colours.append(
                tuple(round(c, 6) for c in colour.Values(Quantity_TypeOfColor.Quantity_TOC_sRGB))
            )
        explorer.Next()
    assert sorted(colours) == [(0.0, 0.5, 1.0)] * 3 + [(1.0, 0.0, 0.0)] * 2


@requires_ocp
def test_step_without_groups_is_as_before(tmp_path: Path) -> None:
    surface = g1patch.smooth(shapes.cube(), method="split4")
    target = tmp_path / "plain.step"
    surface.export(target)
    text = target.read_text()
    names = re.findall(r"ADVANCED_FACE\('([^']*)'", text)
    assert sorted(names) == [f"face {n}" for n in range(6)]
    assert "STYLED_ITEM" not in text


def test_3dm_has_a_layer_per_group(tmp_path: Path) -> None:
    rhino3dm = pytest.importorskip("rhino3dm")
    surface = g1patch.smooth(_cube(tmp_path), method="split4")
    surface.export(tmp_path / "cube.3dm")
    model = rhino3dm.File3dm.Read(str(tmp_path / "cube.3dm"))
    layers = [(layer.Name, tuple(layer.Color)) for layer in model.Layers]
    assert layers == [
        ("Default", (0, 0, 0, 255)),
        ("red", (255, 0, 0, 255)),
        ("blue paint", (0, 128, 255, 255)),
    ]
    objects = sorted(
        (o.Attributes.Name, o.Attributes.LayerIndex, o.Attributes.ColorSource)
        for o in model.Objects
    )
    from_layer = rhino3dm.ObjectColorSource.ColorFromLayer
    assert [(name, layer) for name, layer, _ in objects] == [
        ("blue paint 3", 2),
        ("blue paint 4", 2),
        ("blue paint 5", 2),
        ("face 0", 0),
        ("red 1", 1),
        ("red 2", 1),
    ]
    assert all(source == from_layer for _, _, source in objects)
