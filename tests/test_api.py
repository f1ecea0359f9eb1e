"""The top-level API (``g1patch.read``, ``g1patch.smooth``, ``Surface``), reprs and Jupyter
displays, import time."""

from __future__ import annotations

import importlib.util
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import g1patch
from g1patch.io.meshfile import write_quads

PNG = b"\x89PNG\r\n\x1a\n"
HAS_OCP = importlib.util.find_spec("OCP") is not None

#: the cube [-1, 1]³, faces counter-clockwise seen from outside
CUBE_VERTICES = np.array([[x, y, z] for x in (-1.0, 1.0) for y in (-1.0, 1.0) for z in (-1.0, 1.0)])
CUBE_QUADS = np.array(
    [[0, 1, 3, 2], [4, 6, 7, 5], [0, 4, 5, 1], [2, 3, 7, 6], [0, 2, 6, 4], [1, 5, 7, 3]]
)


@pytest.fixture(scope="module")
def cube_obj(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("api") / "cube.obj"
    write_quads(path, CUBE_VERTICES, CUBE_QUADS)
    return path


@pytest.fixture(scope="module")
def cube(cube_obj: Path) -> g1patch.Surface:
    return g1patch.smooth(cube_obj, method="gregory")


def _exact(report: g1patch.ContinuityReport) -> bool:
    return report.passes(1e-9)


# ----------------------------------------------------------------------------- the short script


def _script(path: Path, out: Path, cad: bool) -> None:
    """What a new user writes: one import, smooth, check, export, render."""
    n = g1patch.smooth(path, method="gregory")
    print(n.check())
    if cad:
        result = n.export(out / "m.step")
        assert result.path == out / "m.step" and result.faces == n.n_patches
    assert n.export(out / "m.npz") == out / "m.npz"
    assert n.export(out / "m.obj") == out / "m.obj"
    assert n.render(out / "m.png", mode="zebra", size=(200, 200)) == out / "m.png"


@pytest.mark.slow
@pytest.mark.parametrize(
    "cad",
    [
        pytest.param(
            True, marks=pytest.mark.skipif(not HAS_OCP, reason="needs OCP (g1patch[cad])")
        ),
        False,
    ],
)
def test_script_on_a_cube_file(
    cube_obj: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], cad: bool
) -> None:
    _script(cube_obj, tmp_path, cad)
    printed = capsys.readouterr().out
    assert (
        "max G1 angle on edges" in printed
    )  # print(report) prints the table, not a dataclass dump
    assert (tmp_path / "m.png").read_bytes().startswith(PNG)
    if cad:
        assert (tmp_path / "m.step").read_text(errors="replace").startswith("ISO-10303-21")
    network = g1patch.read(tmp_path / "m.npz")
    assert isinstance(network, g1patch.PatchNetwork) and network.n_patches == 6
    assert (tmp_path / "m.obj").read_text().count("\nf ") > 0


def test_script_on_the_shared_torus(
    shared_data: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from conftest import shared_data_path

    torus = shared_data_path("catmark_torus.obj")
    _script(torus, tmp_path, HAS_OCP)
    assert "folds" in capsys.readouterr().out
    surface = g1patch.smooth(torus, method="gregory")
    assert surface.n_patches == 32 and _exact(surface.check())


def test_read_by_suffix(cube_obj: Path, cube: g1patch.Surface, tmp_path: Path) -> None:
    mesh = g1patch.read(cube_obj)
    assert isinstance(mesh, g1patch.QuadMesh) and mesh.n_faces == 6
    cube.export(tmp_path / "s.npz")
    assert isinstance(g1patch.read(str(tmp_path / "s.npz")), g1patch.PatchNetwork)
    bezier = g1patch.smooth(cube_obj, method="split4")
    bezier.export(tmp_path / "s.bpt")
    patches = g1patch.read(tmp_path / "s.bpt")
    assert isinstance(patches, g1patch.PatchNetwork) and patches.n_patches == 24
    with pytest.raises(g1patch.FormatError, match=r"unsupported extension '\.3mf'.*\.npz"):
        g1patch.read(tmp_path / "mesh.3mf")
    with pytest.raises(g1patch.InputError, match="path: expected a file name.*int"):
        g1patch.read(3)  # type: ignore[arg-type]


# ----------------------------------------------------------------------------- inputs


def test_the_cube_is_exactly_g1(cube: g1patch.Surface) -> None:
    report = cube.check()
    assert _exact(report) and cube.check() is report  # the default report is kept
    assert cube.method == "gregory" and cube.shape == "interpolate" and cube.mesh is not None


@pytest.mark.parametrize("as_lists", [False, True])
def test_arrays_of_quads(as_lists: bool) -> None:
    source = (
        (CUBE_VERTICES.tolist(), CUBE_QUADS.tolist()) if as_lists else (CUBE_VERTICES, CUBE_QUADS)
    )
    surface = g1patch.smooth(source, method="gregory")
    assert surface.n_patches == 6 and _exact(surface.check())


def test_ragged_polygons_are_split() -> None:
    faces = [list(face) for face in CUBE_QUADS[:5]] + [
        [1, 5, 7],
        [1, 7, 3],
    ]  # one side as two triangles
    surface = g1patch.smooth((CUBE_VERTICES, faces), method="gregory")
    assert surface.n_patches == 4 * 5 + 3 * 2 and _exact(surface.check())


def test_planar_points_get_z_zero() -> None:
    surface = g1patch.smooth(([[0, 0], [1, 0], [1, 1], [0, 1]], [[0, 1, 2, 3]]), method="gregory")
    low, high = surface.bounding_box
    assert surface.n_patches == 1 and low[2] == high[2] == 0.0


def test_meshio_mesh_with_quads_triangles_polygons_and_lines() -> None:
    meshio = pytest.importorskip("meshio")
    # a prism: two triangles and three quads, with a polygon block (one quad as a 4-gon) and a line
    # block
    vertices = np.array(
        [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [0, 1, 1]], dtype=float
    )
    mesh = meshio.Mesh(
        vertices,
        [
            ("triangle", np.array([[0, 2, 1], [3, 4, 5]])),
            ("quad", np.array([[0, 1, 4, 3], [1, 2, 5, 4]])),
            ("polygon", np.array([[2, 0, 3, 5]])),
            ("line", np.array([[0, 1]])),
        ],
    )
    surface = g1patch.smooth(mesh, method="gregory")
    assert surface.n_patches == 2 * 3 + 3 * 4 and _exact(surface.check())
    quads = g1patch.smooth(meshio.Mesh(CUBE_VERTICES, [("quad", CUBE_QUADS)]), method="gregory")
    assert quads.n_patches == 6


def test_meshio_volume_cells_are_refused_by_name() -> None:
    meshio = pytest.importorskip("meshio")
    mesh = meshio.Mesh(CUBE_VERTICES[:4], [("tetra", np.array([[0, 1, 2, 3]]))])
    with pytest.raises(g1patch.InputError, match="cell block 0 holds 'tetra' cells"):
        g1patch.smooth(mesh, method="gregory")
    with pytest.raises(g1patch.InputError, match="no triangle, quad or polygon cells"):
        g1patch.smooth(meshio.Mesh(CUBE_VERTICES, [("line", np.array([[0, 1]]))]), method="gregory")


class TrimeshLike:
    """What trimesh.Trimesh offers the API: ``vertices`` and ``faces``."""

    def __init__(self, vertices: object, faces: object) -> None:
        self.vertices, self.faces = vertices, faces


class PolyDataLike:
    """What pyvista.PolyData offers: ``points`` and a VTK cell array ``faces``."""

    def __init__(self, points: object, faces: object) -> None:
        self.points, self.faces = points, faces


def test_trimesh_like_object() -> None:
    assert g1patch.smooth(TrimeshLike(CUBE_VERTICES, CUBE_QUADS), method="gregory").n_patches == 6
    triangles = np.array(
        [face[[0, 1, 2]] for face in CUBE_QUADS] + [face[[0, 2, 3]] for face in CUBE_QUADS]
    )
    assert (
        g1patch.smooth(TrimeshLike(CUBE_VERTICES, triangles), method="gregory").n_patches == 3 * 12
    )


def test_pyvista_like_object() -> None:
    cells = np.hstack([np.full((6, 1), 4), CUBE_QUADS]).ravel()
    assert g1patch.smooth(PolyDataLike(CUBE_VERTICES, cells), method="gregory").n_patches == 6


def test_quad_mesh_and_options(cube_obj: Path) -> None:
    mesh = g1patch.read(cube_obj)
    assert g1patch.as_mesh(mesh) is mesh
    limit = g1patch.smooth(mesh, "limit", "split4", refine=1)
    assert limit.n_patches == 4 * 24 and limit.shape == "limit" and limit.method == "split4"
    assert limit.provenance["refine"] == "1"
    sharp = g1patch.smooth(
        mesh, method="gregory", sharp_angle=30
    )  # every cube edge turns by 90°: all seams
    assert sharp.network.n_seams == 12 and sharp.check().seam_edges == 12
    assert (
        g1patch.smooth(
            (CUBE_VERTICES, CUBE_QUADS), method="gregory", sharp_angle=30
        ).network.n_seams
        == 12
    )
    with pytest.raises(g1patch.InputError, match="method: unknown value 'bezier'"):
        g1patch.smooth(mesh, method="bezier")
    with pytest.raises(g1patch.MeshError, match="not quads"):
        g1patch.smooth(
            (CUBE_VERTICES, [[0, 1, 3]] + CUBE_QUADS[1:].tolist()), method="gregory", split=False
        )


@pytest.mark.parametrize(
    "bad, named",
    [
        ({"vertices": 1}, r"a dict \(\{'vertices': 1\}\)"),
        (42, r"an int \(42\)"),
        (np.zeros((4, 3)), r"a numpy\.ndarray of shape \(4, 3\) and dtype float64"),
        ((1, 2, 3), r"a tuple \(\(1, 2, 3\)\)"),
        (None, r"a NoneType \(None\)"),
    ],
)
def test_bad_inputs_name_what_was_passed(bad: object, named: str) -> None:
    with pytest.raises(
        g1patch.InputError,
        match=r"smooth: cannot make a mesh of " + named + r"; expected a mesh file path",
    ):
        g1patch.smooth(bad, method="gregory")


def test_a_network_file_or_network_is_not_a_mesh(cube: g1patch.Surface) -> None:
    with pytest.raises(g1patch.InputError, match=r"surface\.npz: is a network file.*g1patch\.read"):
        g1patch.smooth("surface.npz", method="gregory")
    with pytest.raises(g1patch.InputError, match=r"already a surface.*g1patch\.Surface"):
        g1patch.smooth(cube.network, method="gregory")


def test_repairs_are_kept_and_shown() -> None:
    flipped = CUBE_QUADS.copy()
    flipped[0] = flipped[0][::-1]
    surface = g1patch.smooth((CUBE_VERTICES, flipped), method="gregory")
    assert (
        surface.repairs == ("1 face (0) reoriented",)
        and "repaired" in repr(surface)
        and "repaired" in repr(surface.mesh)
    )
    assert _exact(surface.check())
    with pytest.raises(g1patch.MeshError, match="oriented consistently"):
        g1patch.smooth((CUBE_VERTICES, flipped), method="gregory", strict=True)


def test_choices_are_checked_before_reading() -> None:
    with pytest.raises(g1patch.InputError, match="shape: unknown value 'round'"):
        g1patch.smooth("no such file.obj", method="gregory", shape="round")


def test_bad_arrays_raise_the_mesh_checks() -> None:
    with pytest.raises(g1patch.InputError, match="vertices"):
        g1patch.smooth((np.zeros((4, 4)), [[0, 1, 2, 3]]), method="gregory")
    with pytest.raises(g1patch.MeshError, match=r"face 0 has vertex index 9 outside 0\.\.7"):
        g1patch.smooth((CUBE_VERTICES, [[0, 1, 3, 9]]), method="gregory")


# ----------------------------------------------------------------------------- patch sets


@pytest.fixture(scope="module")
def bezier_patches(cube_obj: Path) -> g1patch.PatchSet:
    patches = g1patch.smooth(cube_obj, method="split4").patches
    assert isinstance(patches, g1patch.PatchSet)
    return g1patch.PatchSet(
        patches.convert("bezier").world_control(), "bezier"
    )  # bare: no network, no frame


def test_bare_patch_set_through_check_tessellate_export(
    bezier_patches: g1patch.PatchSet, tmp_path: Path
) -> None:
    from g1patch.continuity import check

    assert _exact(check(bezier_patches))  # the deep function too
    assert _exact(g1patch.check(bezier_patches))
    surface = g1patch.Surface(bezier_patches)
    points, triangles = surface.tessellate(5)
    assert (
        triangles.shape == (24 * 2 * 16, 3) and len(points) == 24 * 16 + 2
    )  # welded: a closed genus-0 mesh
    assert g1patch.export(bezier_patches, tmp_path / "p.obj") == tmp_path / "p.obj"
    assert g1patch.export(bezier_patches, tmp_path / "p.bpt") == tmp_path / "p.bpt"
    assert g1patch.read(tmp_path / "p.bpt").n_patches == 24
    if HAS_OCP:
        result = g1patch.export(bezier_patches, tmp_path / "p.iges", g1_samples=0)
        assert (
            result.faces == 6 and result.exact
        )  # the 2×2 pieces of a quad are recognised: one B-spline face each


def test_bare_gregory_patch_set(cube: g1patch.Surface, tmp_path: Path) -> None:
    gregory = cube.patches
    assert isinstance(gregory, g1patch.GregoryPatchSet)
    from g1patch.continuity import check

    assert _exact(check(gregory)) and _exact(g1patch.check(gregory))
    assert g1patch.Surface(gregory).tessellate(3)[1].shape == (6 * 8, 3)
    g1patch.export(gregory, tmp_path / "g.npz")
    assert g1patch.read(tmp_path / "g.npz").n_patches == 6
    with pytest.raises(g1patch.FormatError, match=r"\.bpt holds polynomial Bézier patches"):
        g1patch.export(gregory, tmp_path / "g.bpt")


def test_check_refuses_other_objects_by_name() -> None:
    from g1patch.continuity import check

    with pytest.raises(
        g1patch.InputError, match=r"network: expected a PatchNetwork, PatchSet.*got a dict"
    ):
        check({})  # type: ignore[arg-type]
    with pytest.raises(g1patch.InputError, match=r"surface: expected a Surface.*got a list"):
        g1patch.check([1, 2])


def test_export_options_and_suffixes(cube: g1patch.Surface, tmp_path: Path) -> None:
    cube.export(tmp_path / "fine.stl", resolution=3)
    assert (tmp_path / "fine.stl").stat().st_size == 84 + 50 * 6 * 8
    with pytest.raises(g1patch.InputError, match=r"export to \.obj: unknown option 'tolerance'"):
        cube.export(tmp_path / "m.obj", tolerance=1e-3)
    with pytest.raises(
        g1patch.InputError, match=r"export to \.npz: unknown option 'resolution'.*only background"
    ):
        cube.export(tmp_path / "m.npz", resolution=3)
    with pytest.raises(g1patch.FormatError, match=r"unsupported extension '\.xyz'"):
        cube.export(tmp_path / "m.xyz")
    assert not list(tmp_path.glob("m.*"))


def test_render_to_bytes_and_view(cube: g1patch.Surface) -> None:
    assert cube.render(mode="deviation", size=(120, 120)).startswith(PNG)
    assert cube.view().startswith("<!DOCTYPE html>")  # the viewer's own tests: test_viewer.py


# ----------------------------------------------------------------------------- reprs and displays


def test_reprs_are_short(
    cube_obj: Path, cube: g1patch.Surface, bezier_patches: g1patch.PatchSet
) -> None:
    mesh = g1patch.read(cube_obj)
    objects = {
        "QuadMesh": mesh,
        "QuadTopology": mesh.topology,
        "PatchSet": bezier_patches,
        "GregoryPatchSet": cube.patches,
        "PatchNetwork": cube.network,
        "ContinuityReport": cube.check(),
        "Surface": cube,
    }
    for name, value in objects.items():
        text = repr(value)
        assert text.startswith(f"<{name} ") and text.endswith(">") and len(text) < 200, text
        assert "array(" not in text and "\n" not in text, text
    # the cube comes out a sphere through its corners
    sphere = "bbox (-1.732, -1.732, -1.732)…(1.732, 1.732, 1.732)"
    assert repr(cube.network) == f"<PatchNetwork 6 gregory patches, interpolate, {sphere}>"
    assert repr(cube) == f"<Surface 6 gregory patches, interpolate, {sphere}>"
    assert repr(cube.patches) == f"<GregoryPatchSet 6 patches, {sphere}>"
    assert (
        repr(mesh)
        == "<QuadMesh 8 vertices, 6 quads, 12 edges, closed, bbox (-1, -1, -1)…(1, 1, 1), cube.obj>"
    )
    assert re.fullmatch(
        r"<ContinuityReport 6 patches, 12 shared edges: exact G1 \(max angle .*°\), no folds>",
        repr(cube.check()),
    )
    assert repr(bezier_patches) == f"<PatchSet 24 bezier patches, {sphere}>"
    assert (
        repr(g1patch.Surface(bezier_patches))
        == f"<Surface 24 bezier patches, from PatchSet, {sphere}>"
    )


def test_jupyter_displays(cube_obj: Path, cube: g1patch.Surface) -> None:
    for value in (cube, cube.network, g1patch.read(cube_obj)):
        picture = value._repr_png_()
        assert picture is not None and picture.startswith(PNG) and len(picture) > 1000
    html = cube.check()._repr_html_()
    assert html.startswith("<div>") and "<table>" in html and "max G1 angle on edges" in html


def test_jupyter_skips_large_networks(
    cube: g1patch.Surface, monkeypatch: pytest.MonkeyPatch
) -> None:
    import g1patch.display

    monkeypatch.setattr(g1patch.display, "PREVIEW_MAX_PATCHES", 5)
    assert cube._repr_png_() is None  # the text repr is shown instead


# ----------------------------------------------------------------------------- the package


def test_import_is_fast_and_light() -> None:
    heavy = "('numpy', 'scipy', 'matplotlib', 'numba', 'meshio')"
    code = f"import sys, g1patch; print(sorted(m for m in {heavy} if m in sys.modules))"
    loaded = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True
    ).stdout.strip()
    assert loaded == "[]"
    timing = subprocess.run(
        [sys.executable, "-X", "importtime", "-c", "import g1patch"],
        capture_output=True,
        text=True,
        check=True,
    )
    cumulative = [
        int(line.split("|")[1])
        for line in timing.stderr.splitlines()
        if line.rstrip().endswith("| g1patch")
    ]
    assert cumulative and cumulative[0] < 500_000  # microseconds


def test_public_names_and_deep_modules() -> None:
    for name in (
        "read",
        "smooth",
        "Surface",
        "check",
        "export",
        "QuadMesh",
        "PatchNetwork",
        "PatchSet",
        "GregoryPatchSet",
        "ContinuityReport",
        "InputError",
        "G1PatchError",
        "__version__",
    ):
        assert name in dir(g1patch) and getattr(g1patch, name) is not None
    from g1patch import __version__
    from g1patch.build import build_network
    from g1patch.continuity import check
    from g1patch.render import render
    from g1patch.tessellate import tessellate

    assert isinstance(__version__, str) and all(
        map(callable, (build_network, check, render, tessellate))
    )
    assert g1patch.QuadMesh is __import__("g1patch.mesh").mesh.QuadMesh
    with pytest.raises(AttributeError, match="no attribute 'nonsense'"):
        g1patch.nonsense  # noqa: B018
