"""Seams: edges sharp on purpose (OpenSubdiv creases) in the network, the check, the file, the
pictures and CAD.

A seam is only meant to be G0: the report lists seams apart (count, G0 gap, angle range), never
counts them as G1 failures or folds, and compares corner normals only within a sector (the
patches joined around a point by edges that are not seams).
"""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import matplotlib.image
import numpy as np
import pytest

from g1patch import shapes
from g1patch.cli import main
from g1patch.construct.split4 import split4_network_from_targets
from g1patch.continuity import SEAM_G0_RTOL, check
from g1patch.errors import FormatError, InputError
from g1patch.frame import Frame
from g1patch.io.network_file import FORMAT_VERSION, load_network, save_network
from g1patch.mesh import QuadMesh
from g1patch.network import PatchNetwork, network_from_mesh, network_from_patch_points
from g1patch.patches import PatchSet
from g1patch.render import render
from g1patch.targets import shape_targets

EXACT = 1e-9


def bilinear_nets(corners: np.ndarray) -> np.ndarray:
    """Bézier nets (F, 4, 4, 3) of the bilinear patches through quad corners (F, 4, 3),
    counter-clockwise."""
    s = np.arange(4) / 3.0
    u, v = s[None, :, None, None], s[None, None, :, None]
    c0, c1, c2, c3 = (corners[:, k, None, None] for k in range(4))
    return (1 - u) * (1 - v) * c0 + u * (1 - v) * c1 + u * v * c2 + (1 - u) * v * c3


def flat_patches(mesh: QuadMesh) -> PatchSet:
    """One flat bicubic Bézier patch per quad of ``mesh``."""
    return PatchSet(bilinear_nets(mesh.vertices[mesh.faces]), "bezier")


#: a seam's G0 gap where both sides share the curve exactly, of the diagonal: 4 ε (the same cubic
#: evaluated from its two ends rounds differently; 0.07 ε measured)
SEAM_ROUNDING = 4 * np.finfo(float).eps


def seamed_cube(shift: float = 0.0) -> PatchNetwork:
    """The cube [-1, 1]³ as 6 flat bicubic patches, all 12 edges seams; face 0 moved out by
    ``shift``."""
    mesh = shapes.cube()
    control = flat_patches(mesh).control.copy()
    control[0, ..., 0] -= shift  # face 0 is x = −1
    return network_from_mesh(
        mesh.topology,
        PatchSet(control, "bezier"),
        mesh.vertices,
        seam_edges=np.ones(mesh.topology.n_edges, dtype=bool),
    )


def mesh_edge(mesh: QuadMesh, a: int, b: int) -> int:
    """Index of the edge a–b in ``mesh.topology.edges``."""
    return int(np.flatnonzero((mesh.topology.edges == sorted((a, b))).all(axis=1))[0])


def fading_crease(seams: list[tuple[int, int]], lift: float = 0.1) -> tuple[PatchNetwork, float]:
    """A 2 × 2 grid over [0, 2]² (centre vertex 4) whose two right-hand quads are lifted near the
    centre so that the centre corner normals of quads 1 and 3 lean by ``atan(3 lift)`` and those of
    quads 0 and 2 stay flat: the edges x = 1 (4–7 and 1–4) crease, fading out towards their far
    ends, while the edges y = 1 stay exactly G1. ``seams``: mesh edges (vertex pairs) marked."""
    mesh = shapes.grid(2, 2, size=(2.0, 2.0))
    control = flat_patches(mesh).control.copy()
    for point in (
        (4 / 3, 1.0),
        (4 / 3, 4 / 3),
        (4 / 3, 2 / 3),
    ):  # edge and first inner row beside x = 1
        near = (np.abs(control[..., :2] - point) < 1e-12).all(axis=-1)
        control[near, 2] = lift
    flags = np.zeros(mesh.topology.n_edges, dtype=bool)
    flags[[mesh_edge(mesh, a, b) for a, b in seams]] = True
    network = network_from_mesh(
        mesh.topology, PatchSet(control, "bezier"), mesh.vertices, seam_edges=flags
    )
    return network, float(np.degrees(np.arctan(3 * lift)))


def bspline_torus(n_major: int = 8, n_minor: int = 6) -> PatchNetwork:
    """A closed torus of uniform bicubic B-spline patches: C2, so exactly G1."""
    u = 2 * np.pi * np.arange(n_major) / n_major
    v = 2 * np.pi * np.arange(n_minor) / n_minor
    U, V = np.meshgrid(u, v, indexing="ij")
    net = np.stack(
        [(1 + 0.4 * np.cos(V)) * np.cos(U), (1 + 0.4 * np.cos(V)) * np.sin(U), 0.4 * np.sin(V)],
        axis=-1,
    )
    i = (np.arange(n_major)[:, None] + np.arange(4)) % n_major
    j = (np.arange(n_minor)[:, None] + np.arange(4)) % n_minor
    return network_from_patch_points(
        PatchSet(net[i[:, None, :, None], j[None, :, None, :]].reshape(-1, 4, 4, 3), "bspline")
    )


# ----------------------------------------------------------------------------- the network
def test_network_from_mesh_marks_both_sides_of_each_seam() -> None:
    network = seamed_cube()
    assert network.seam.shape == (6, 4) and network.seam.all() and network.n_seams == 12
    mesh = shapes.cube()
    flags = np.zeros(12, dtype=bool)
    flags[mesh_edge(mesh, 0, 1)] = True
    one = network_from_mesh(mesh.topology, flat_patches(mesh), mesh.vertices, seam_edges=flags)
    patch, edge = np.nonzero(one.seam)
    assert len(patch) == 2 and one.n_seams == 1
    assert (one.edge_ids[patch, edge] == mesh_edge(mesh, 0, 1)).all()
    assert (
        one.neighbor[patch[0], edge[0]] == patch[1]
        and one.neighbor_edge[patch[0], edge[0]] == edge[1]
    )
    plain = network_from_mesh(mesh.topology, flat_patches(mesh), mesh.vertices)
    assert plain.seam.shape == (6, 4) and not plain.seam.any() and plain.n_seams == 0


def test_seams_are_kept_by_copies_and_ignored_on_boundary_edges() -> None:
    network = seamed_cube()
    assert dataclasses.replace(network, vertex_normals=None).seam.all()
    assert PatchNetwork(**network.__dict__).seam.all()
    grid = shapes.grid(2, 1)
    marked = network_from_mesh(
        grid.topology,
        flat_patches(grid),
        grid.vertices,
        seam_edges=np.ones(grid.n_edges, dtype=bool),
    )
    assert marked.n_seams == 1  # the one interior edge; boundary edges are sharp anyway


def test_seam_flags_are_validated_and_errors_name_the_edge() -> None:
    network = seamed_cube()
    one_sided = network.seam.copy()
    one_sided[0, 0] = False
    other, other_edge = network.neighbor[0, 0], network.neighbor_edge[0, 0]
    with pytest.raises(
        InputError,
        match=rf"patch {other} edge {other_edge} is a seam but its other side, patch 0 edge 0, is "
        r"not",
    ):
        dataclasses.replace(network, seam=one_sided)
    with pytest.raises(InputError, match=r"seam: expected shape \(6, 4\)"):
        dataclasses.replace(network, seam=np.ones((6, 3), dtype=bool))
    with pytest.raises(InputError, match="seam: expected booleans"):
        dataclasses.replace(network, seam=np.full((6, 4), 0.5))
    grid = shapes.grid(1, 1)
    lone = network_from_mesh(grid.topology, flat_patches(grid), grid.vertices)
    with pytest.raises(InputError, match="patch 0 edge 0 is marked a seam but has no neighbour"):
        dataclasses.replace(lone, seam=np.ones((1, 4), dtype=bool))
    mesh = shapes.cube()
    with pytest.raises(InputError, match=r"seam_edges: expected shape \(12,\)"):
        network_from_mesh(
            mesh.topology, flat_patches(mesh), mesh.vertices, seam_edges=np.ones(11, dtype=bool)
        )


def test_split4_marks_both_halves_of_each_seam_mesh_edge() -> None:
    mesh = shapes.cube()
    frame = Frame.of_points(mesh.vertices)
    targets = shape_targets(mesh.with_vertices(frame.to_local(mesh.vertices)), "interpolate")
    flags = np.zeros(mesh.n_edges, dtype=bool)
    flags[[2, 7]] = True
    network = split4_network_from_targets(mesh, targets, frame, {}, seam_edges=flags)
    assert network.n_patches == 24 and network.n_seams == 4
    patch, edge = np.nonzero(network.seam)
    assert set((network.edge_ids[patch, edge] // 2).tolist()) == {2, 7}
    assert (
        network.edge_ids[patch, edge] < 2 * mesh.n_edges
    ).all()  # never the split's inner seams M–C
    plain = split4_network_from_targets(mesh, targets, frame, {})
    assert not plain.seam.any()
    np.testing.assert_array_equal(network.patches.control, plain.patches.control)
    report = check(network)  # the targets knew nothing of the seams: still G1 across them
    assert (
        report.seam_edges == 4
        and report.seam_angle_max_deg is not None
        and report.seam_angle_max_deg < EXACT
    )
    assert report.passes(EXACT)
    with pytest.raises(InputError, match=r"seam_edges: expected shape \(12,\), one per mesh edge"):
        split4_network_from_targets(mesh, targets, frame, {}, seam_edges=np.ones(24, dtype=bool))


# ----------------------------------------------------------------------------- the check
def test_the_seamed_cube_passes_with_12_seams_at_90_degrees() -> None:
    report = check(seamed_cube())
    assert report.seam_edges == 12 and report.shared_edges == 12
    assert report.seam_angle_min_deg == pytest.approx(90.0, abs=1e-12)
    assert report.seam_angle_max_deg == pytest.approx(90.0, abs=1e-12)
    # both sides evaluate the same cubic, from opposite ends: its Bernstein weights round apart
    assert report.seam_g0_max <= SEAM_ROUNDING and report.max_g0_gap <= SEAM_ROUNDING
    assert report.max_edge_angle_deg == 0.0 and report.mean_edge_angle_deg == 0.0
    assert report.max_corner_angle_deg == 0.0  # three sectors of one patch at every cube corner
    assert report.folds == 0 and report.worst_edge is None
    assert report.passes(EXACT) and report.is_g1(EXACT) and report.seams_closed()
    assert report.edge_seam.all() and np.allclose(report.edge_angle_deg, 90.0)

    plain = check(dataclasses.replace(seamed_cube(), seam=None))
    assert (
        plain.seam_edges == 0
        and plain.seam_angle_min_deg is None
        and plain.seam_angle_max_deg is None
    )
    assert plain.max_edge_angle_deg == pytest.approx(
        90.0
    ) and plain.max_corner_angle_deg == pytest.approx(90.0)
    assert not plain.passes(EXACT)


def test_seams_in_the_text_and_json_report() -> None:
    report = check(seamed_cube())
    rows = dict(report.rows())
    assert rows["seams (sharp on purpose)"] == "12"
    assert rows["seam angle min / max"] == "90° / 90°"
    assert float(rows["seam max G0 gap (of bbox diag)"]) <= SEAM_ROUNDING
    data = json.loads(json.dumps(report.to_dict()))
    assert data["seams"]["count"] == 12 and data["seams"]["g0_max"] <= SEAM_ROUNDING
    assert data["seams"]["angle_min_deg"] == pytest.approx(90.0) and data["seams"][
        "angle_max_deg"
    ] == pytest.approx(90.0)
    assert data["worst_edge"] is None
    plain = check(bspline_torus()).to_dict()
    assert plain["seams"] == {
        "count": 0,
        "g0_max": 0.0,
        "angle_min_deg": None,
        "angle_max_deg": None,
    }
    assert "seams (sharp on purpose)" not in dict(check(bspline_torus()).rows())


def test_a_gap_on_a_seam_still_fails() -> None:
    network = seamed_cube(shift=1e-6)
    report = check(network)
    assert report.seam_g0_max == pytest.approx(1e-6 / network.bounding_box_diagonal(), rel=1e-6)
    assert report.is_g1(EXACT) and report.folds == 0
    assert not report.seams_closed() and not report.passes(EXACT)
    assert report.passes(EXACT, max_seam_gap=1e-6)
    assert SEAM_G0_RTOL == 1e-12


def test_seams_on_a_g1_network_measure_angle_zero() -> None:
    torus = bspline_torus()
    flags = np.zeros(torus.n_edges, dtype=bool)
    flags[::5] = True
    seamed = torus.with_seams(flags)
    report, plain = check(seamed), check(torus)
    assert report.seam_edges == flags.sum() == seamed.n_seams
    assert (
        report.seam_angle_max_deg is not None
        and report.seam_angle_max_deg < EXACT
        and report.seam_g0_max < SEAM_G0_RTOL
    )
    assert (
        report.passes(EXACT) and report.max_corner_angle_deg <= plain.max_corner_angle_deg + EXACT
    )
    np.testing.assert_array_equal(
        report.edge_angle_deg, plain.edge_angle_deg
    )  # measured alike, reported apart


def test_a_dart_end_is_one_sector_and_stays_g1() -> None:
    torus = bspline_torus()
    flags = np.zeros(torus.n_edges, dtype=bool)
    flags[0] = True  # one seam edge: a dart at both its ends
    dart = torus.with_seams(flags)
    sectors = dart.corner_sectors()
    patch, edge = np.nonzero(dart.seam)
    for end in (dart.corner_ids[patch[0], edge[0]], dart.corner_ids[patch[0], (edge[0] + 1) % 4]):
        assert len(np.unique(sectors[dart.corner_ids == end])) == 1
    report = check(dart)
    assert report.seam_edges == 1 and report.max_corner_angle_deg < EXACT and report.passes(EXACT)


def test_corners_compare_normals_only_within_a_sector() -> None:
    # the crease along x = 1 fades out upwards and downwards from the centre
    through, angle = fading_crease([(4, 7), (1, 4)])  # a seam all across: two sectors at the centre
    report = check(through)
    assert report.seam_edges == 2
    assert (
        report.max_edge_angle_deg < EXACT and report.max_corner_angle_deg < EXACT
    )  # quads 1 and 3 agree, 0 and 2 too
    assert report.seam_angle_max_deg == pytest.approx(angle, rel=1e-12)
    assert (
        report.seam_angle_min_deg is not None and report.seam_angle_min_deg < EXACT
    )  # the far ends are flat
    assert report.passes(EXACT)
    sectors = through.corner_sectors()
    assert len(np.unique(sectors[through.corner_ids == 4])) == 2

    dart, _ = fading_crease(
        [(4, 7)]
    )  # the seam ends at the centre: one sector there, which is not G1
    report = check(dart)
    assert len(np.unique(dart.corner_sectors()[dart.corner_ids == 4])) == 1
    assert report.max_corner_angle_deg == pytest.approx(angle, rel=1e-12)
    assert report.max_edge_angle_deg == pytest.approx(
        angle, rel=1e-12
    )  # edge 1–4 creases, and is no seam
    assert not report.passes(EXACT)


def test_an_intended_sharp_fin_is_not_a_fold() -> None:
    a = np.radians(150.0)
    first = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], dtype=float)
    far = np.array([1 + np.cos(a), 0.0, np.sin(a)])
    second = np.array([[1, 0, 0], far, far + [0, 1, 0], [1, 1, 0]], dtype=float)
    fin = network_from_patch_points(PatchSet(bilinear_nets(np.stack([first, second])), "bezier"))
    plain = check(fin)
    assert plain.folds == 2 and not plain.passes(EXACT)
    seamed = fin.with_seams(np.ones(fin.n_edges, dtype=bool))
    assert seamed.n_seams == 1
    report = check(seamed)
    assert report.folds == 0 and report.fold_locations == ()
    assert report.seam_angle_min_deg == pytest.approx(
        150.0
    ) and report.seam_angle_max_deg == pytest.approx(150.0)
    assert (
        report.max_edge_angle_deg == 0.0
        and report.max_corner_angle_deg == 0.0
        and report.passes(EXACT)
    )


# ----------------------------------------------------------------------------- the file
def test_network_file_round_trip_keeps_the_seams(tmp_path: Path) -> None:
    network = fading_crease([(4, 7)])[0]
    save_network(tmp_path / "n.npz", network)
    with np.load(tmp_path / "n.npz") as data:
        assert json.loads(str(data["header"]))["version"] == FORMAT_VERSION >= 3
        np.testing.assert_array_equal(data["seam"], network.seam)
    loaded = load_network(tmp_path / "n.npz")
    np.testing.assert_array_equal(loaded.seam, network.seam)
    assert check(loaded).to_dict() == check(network).to_dict()


def _rewrite(
    source: Path, target: Path, version: int, drop: tuple[str, ...] = (), **arrays: np.ndarray
) -> Path:
    with np.load(source) as data:
        contents = {name: data[name] for name in data.files if name not in drop}
    header = json.loads(str(contents["header"]))
    header["version"] = version
    contents["header"] = np.array(json.dumps(header))
    np.savez(target, **{**contents, **arrays})
    return target


def test_older_files_load_seam_free(tmp_path: Path) -> None:
    network = seamed_cube()
    save_network(tmp_path / "n.npz", network)
    version2 = load_network(_rewrite(tmp_path / "n.npz", tmp_path / "v2.npz", 2, drop=("seam",)))
    assert version2.seam.shape == (6, 4) and not version2.seam.any()
    # an array named seam is no part of a version 2 file
    assert not load_network(_rewrite(tmp_path / "n.npz", tmp_path / "v2s.npz", 2)).seam.any()
    version1 = load_network(_rewrite(tmp_path / "n.npz", tmp_path / "v1.npz", 1, drop=("seam",)))
    assert not version1.seam.any()
    with pytest.raises(FormatError, match="lacks seam"):
        load_network(_rewrite(tmp_path / "n.npz", tmp_path / "v3.npz", 3, drop=("seam",)))
    one_sided = network.seam.copy()
    one_sided[0, 0] = False
    with pytest.raises(FormatError, match="corrupt network file: seam: patch"):
        load_network(_rewrite(tmp_path / "n.npz", tmp_path / "bad.npz", 3, seam=one_sided))


# ----------------------------------------------------------------------------- the command line
def test_check_command_reports_seams(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    save_network(tmp_path / "cube.npz", seamed_cube())
    assert main(["check", str(tmp_path / "cube.npz"), "--max-angle", "1e-9"]) == 0
    out = capsys.readouterr().out
    assert "seams (sharp on purpose)" in out and "90° / 90°" in out
    assert (
        "passed: G1 angles within 1e-09°, no folds; 12 seams (sharp on purpose) closed within 1e-12"
        in out
    )
    assert main(["check", str(tmp_path / "cube.npz"), "--json"]) == 0
    seams = json.loads(capsys.readouterr().out)["seams"]
    assert seams["count"] == 12 and seams["angle_min_deg"] == pytest.approx(90.0)

    save_network(tmp_path / "gap.npz", seamed_cube(shift=1e-6))
    assert main(["check", str(tmp_path / "gap.npz"), "--max-angle", "1e-9"]) == 1
    assert "FAILED: seam G0 gap 2.887e-07 (of bbox diag) above 1e-12" in capsys.readouterr().err


# ----------------------------------------------------------------------------- pictures
def _seam_pixels(picture: np.ndarray) -> np.ndarray:
    """Pixels of the seam green (lit or not): green well above red and blue."""
    r, g, b = picture[..., 0], picture[..., 1], picture[..., 2]
    return (g > r + 0.35) & (g > b + 0.1)


def test_deviation_pictures_draw_seams_in_their_own_colour_with_a_legend(tmp_path: Path) -> None:
    from g1patch.render import _SEAM_COLOUR

    seamed, plain = seamed_cube(), dataclasses.replace(seamed_cube(), seam=None)
    render(tmp_path / "seams.png", seamed, mode="deviation", size=(400, 360), resolution=9)
    render(tmp_path / "plain.png", plain, mode="deviation", size=(400, 360), resolution=9)
    with_seams, without = (
        matplotlib.image.imread(tmp_path / name) for name in ("seams.png", "plain.png")
    )
    assert with_seams.shape[:2] == (360, 400)
    assert _seam_pixels(with_seams).sum() > 300 and _seam_pixels(without).sum() == 0
    # the legend's swatch: the seam colour itself, unlit, in the band below the picture
    swatch = (np.abs(with_seams[..., :3] - _SEAM_COLOUR) < 1.5 / 255).all(axis=-1)
    rows = np.flatnonzero(swatch.any(axis=1))
    assert swatch.sum() > 20 and rows.min() > 0.85 * 360

    for mode in ("shaded", "zebra"):  # seams change nothing there
        render(tmp_path / f"s_{mode}.png", seamed, mode=mode, size=(200, 200), resolution=9)
        render(tmp_path / f"p_{mode}.png", plain, mode=mode, size=(200, 200), resolution=9)
        np.testing.assert_array_equal(
            matplotlib.image.imread(tmp_path / f"s_{mode}.png"),
            matplotlib.image.imread(tmp_path / f"p_{mode}.png"),
        )


# ----------------------------------------------------------------------------- CAD
def _occ_edges(shape: object) -> list[tuple[np.ndarray, float]]:
    """Every B-rep edge of ``shape`` with its midpoint and the angle (degrees) between the outward
    normals of its two faces there (OCC: BRepAdaptor_Curve2d on each face, BRepLProp_SLProps)."""
    from OCP.BRepAdaptor import BRepAdaptor_Curve, BRepAdaptor_Curve2d, BRepAdaptor_Surface
    from OCP.BRepLProp import BRepLProp_SLProps
    from OCP.collections import (
        IndexedDataMap_TopoDS_Shape_List_TopoDS_Shape_TopTools_ShapeMapHasher as EdgeFaces,
    )
    from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE, TopAbs_REVERSED
    from OCP.TopExp import TopExp
    from OCP.TopoDS import TopoDS

    edges = EdgeFaces()
    TopExp.MapShapesAndAncestors_s(shape, TopAbs_EDGE, TopAbs_FACE, edges)
    measured = []
    for index in range(1, edges.Extent() + 1):
        edge = TopoDS.Edge(edges.FindKey(index))
        curve = BRepAdaptor_Curve(edge)
        middle = 0.5 * (curve.FirstParameter() + curve.LastParameter())
        normals = []
        for shape_face in edges.FindFromIndex(index):
            face = TopoDS.Face(shape_face)
            uv = BRepAdaptor_Curve2d(edge, face).Value(middle)
            normal = np.array(
                BRepLProp_SLProps(BRepAdaptor_Surface(face), uv.X(), uv.Y(), 1, 1e-9)
                .Normal()
                .Coord()
            )
            normals.append(-normal if face.Orientation() == TopAbs_REVERSED else normal)
        assert len(normals) == 2, "every edge of a closed solid has two faces"
        a, b = normals
        measured.append(
            (
                np.array(curve.Value(middle).Coord()),
                float(np.degrees(np.arctan2(np.linalg.norm(np.cross(a, b)), a @ b))),
            )
        )
    return measured


@pytest.mark.parametrize("name", ["cube.step", "cube.igs"])
def test_cad_export_keeps_seams_as_sharp_edges_of_one_solid(name: str, tmp_path: Path) -> None:
    pytest.importorskip("OCP")
    from OCP.BRep import BRep_Tool
    from OCP.BRepCheck import BRepCheck_Analyzer
    from OCP.collections import IndexedMap_TopoDS_Shape_TopTools_ShapeMapHasher as ShapeMap
    from OCP.TopAbs import TopAbs_SHELL, TopAbs_SOLID
    from OCP.TopExp import TopExp

    from g1patch.io.cad import export_cad, read_cad_faces

    result = export_cad(tmp_path / name, seamed_cube())
    assert result.solid and result.valid and result.free_edges == 0 and result.exact
    assert result.volume == pytest.approx(8.0, rel=1e-12)
    assert result.seam_edges == 12 and result.max_g1_angle_deg == 0.0
    assert result.seam_angle_min_deg == pytest.approx(
        90.0, abs=1e-9
    ) and result.seam_angle_max_deg == pytest.approx(90.0, abs=1e-9)

    model = read_cad_faces(tmp_path / name)
    assert BRepCheck_Analyzer(model.shape).IsValid() and len(model.faces) == 6
    solids, shells = ShapeMap(), ShapeMap()
    TopExp.MapShapes_s(model.shape, TopAbs_SOLID, solids)
    TopExp.MapShapes_s(model.shape, TopAbs_SHELL, shells)
    assert solids.Extent() == 1 and shells.Extent() == 1 and BRep_Tool.IsClosed_s(shells.FindKey(1))
    edges = _occ_edges(model.shape)
    assert len(edges) == 12
    for middle, angle in edges:
        assert angle == pytest.approx(90.0, abs=1e-9)
        assert np.sort(np.abs(middle)) == pytest.approx(
            [0.0, 1.0, 1.0], abs=1e-12
        )  # the middle of a cube edge
