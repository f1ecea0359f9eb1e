"""Pictures: exact pixel size, not blank, every mode; zebra stripes jump across creases and only
there."""

from __future__ import annotations

import sys
from pathlib import Path

import matplotlib.image
import numpy as np
import pytest

from g1patch import render as render_module
from g1patch import shapes
from g1patch.construct.corner import build_corner_network
from g1patch.continuity import check
from g1patch.errors import InputError, MissingDependencyError
from g1patch.network import PatchNetwork, network_from_patch_points
from g1patch.patches import PatchSet
from g1patch.render import (
    MODES,
    RESOLUTION_RANGE,
    choose_resolution,
    render,
    render_side_by_side,
    render_surfaces,
    stripe_jumps,
    stripe_phase,
)
from g1patch.render import draw as render_draw
from g1patch.render import pictures as render_pictures
from g1patch.tessellate import tessellate


def bspline_torus(
    n_major: int = 8, n_minor: int = 6, R: float = 1.0, r: float = 0.4
) -> PatchNetwork:
    """A closed torus of uniform bicubic B-spline patches over a periodic control net: C2, so
    exactly G1."""
    u = 2 * np.pi * np.arange(n_major) / n_major
    v = 2 * np.pi * np.arange(n_minor) / n_minor
    U, V = np.meshgrid(u, v, indexing="ij")
    net = np.stack(
        [(R + r * np.cos(V)) * np.cos(U), (R + r * np.cos(V)) * np.sin(U), r * np.sin(V)], axis=-1
    )
    i = (np.arange(n_major)[:, None] + np.arange(4)) % n_major
    j = (np.arange(n_minor)[:, None] + np.arange(4)) % n_minor
    control = net[i[:, None, :, None], j[None, :, None, :]].reshape(-1, 4, 4, 3)
    return network_from_patch_points(PatchSet(control, "bspline"), source="B-spline torus")


@pytest.fixture(scope="module")
def corner_cube() -> PatchNetwork:
    """The paper's cube: G1 at the corners, creased (46°) along every edge."""
    return build_corner_network(shapes.cube(), tangents="arc", twist="coons")


@pytest.fixture(scope="module")
def smooth_torus() -> PatchNetwork:
    return bspline_torus()


def read_png(path: Path) -> np.ndarray:
    assert path.is_file(), f"{path} was not written"
    return matplotlib.image.imread(path)


def assert_picture(path: Path, size: tuple[int, int]) -> np.ndarray:
    """The PNG exists, has exactly ``size`` = (width, height) pixels and shows something."""
    image = read_png(path)
    assert image.shape[:2] == (size[1], size[0])
    grey = image[..., :3].mean(axis=-1)
    assert grey.std() > 0.1, f"{path} looks blank (pixel std {grey.std():.3f})"
    assert (grey < 0.98).mean() > 0.15, "the surface covers almost nothing of the picture"
    return image


def cube_scan() -> tuple[np.ndarray, np.ndarray]:
    """The triangles of the cube cage the corner cube is built on (a scan its surface bulges
    from: 0 at the corners, most in the middle of the faces)."""
    points = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], float)
    quads = np.array(
        [[0, 1, 3, 2], [4, 6, 7, 5], [0, 4, 5, 1], [2, 3, 7, 6], [0, 2, 6, 4], [1, 5, 7, 3]]
    )
    return points, np.concatenate([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]])


# --------------------------------------------------------------------------- pictures
@pytest.mark.parametrize("mode", MODES)
@pytest.mark.parametrize("size", [(321, 207), (400, 400)])
def test_every_mode_writes_a_png_of_exactly_the_requested_size(
    tmp_path: Path, corner_cube: PatchNetwork, mode: str, size: tuple[int, int]
) -> None:
    path = tmp_path / f"cube_{mode}.png"
    extra = {"scan": cube_scan()} if mode == "distance" else {}
    render(
        path,
        corner_cube,
        mode=mode,
        size=size,
        resolution=17,
        title=f"corner cube, {mode}",
        **extra,  # type: ignore[arg-type]
    )
    assert_picture(path, size)
    assert [p.name for p in tmp_path.iterdir()] == [path.name], "a temporary file was left behind"


def test_zebra_pictures_are_black_and_white(tmp_path: Path, corner_cube: PatchNetwork) -> None:
    path = tmp_path / "zebra.png"
    render(path, corner_cube, mode="zebra", size=(300, 300), resolution=33)
    grey = read_png(path)[..., :3].mean(axis=-1)
    assert (grey < 0.15).mean() > 0.15 and (grey > 0.6).mean() > 0.3


def test_deviation_pictures_colour_the_edges(
    tmp_path: Path, corner_cube: PatchNetwork, smooth_torus: PatchNetwork
) -> None:
    for network, name in ((corner_cube, "crease"), (smooth_torus, "smooth")):
        path = tmp_path / f"{name}.png"
        render(path, network, mode="deviation", size=(400, 300), resolution=33)
        rgb = read_png(path)[..., :3]
        saturated = (rgb.max(axis=-1) - rgb.min(axis=-1)) > 0.3
        assert saturated.sum() > 200, f"{name}: no coloured edge lines"


def test_distance_pictures_colour_the_surface_by_its_distance_to_the_scan(
    tmp_path: Path, smooth_torus: PatchNetwork
) -> None:
    """The distance mode: the colour map over the whole surface, the largest distance in the
    title; without a scan, or with one in another mode, a clear error."""
    mesh = tessellate(smooth_torus, 9)
    shifted = (mesh.points + 0.05 * mesh.normals, mesh.triangles)  # a scan 0.05 off the surface
    path = tmp_path / "distance.png"
    render(path, smooth_torus, mode="distance", size=(400, 300), resolution=9, scan=shifted)
    rgb = assert_picture(path, (400, 300))[..., :3]
    saturated = (rgb.max(axis=-1) - rgb.min(axis=-1)) > 0.3
    assert saturated.mean() > 0.1
    with pytest.raises(InputError, match="scan=\\(points, triangles\\)"):
        render(tmp_path / "no.png", smooth_torus, mode="distance")
    with pytest.raises(InputError, match="only the distance mode"):
        render(tmp_path / "no.png", smooth_torus, mode="zebra", scan=shifted)
    with pytest.raises(InputError, match="scan: expected points"):
        render(tmp_path / "no.png", smooth_torus, mode="distance", scan=(mesh.points, [[0, 1]]))
    assert not (tmp_path / "no.png").exists()


def test_deviation_accepts_a_report_and_a_fixed_scale(
    tmp_path: Path, corner_cube: PatchNetwork
) -> None:
    path = tmp_path / "fixed.png"
    render(
        path,
        corner_cube,
        mode="deviation",
        size=(300, 300),
        report=check(corner_cube),
        angle_range=(1e-10, 90.0),
    )
    assert_picture(path, (300, 300))


@pytest.mark.parametrize("mode", MODES)
def test_side_by_side_draws_every_network_in_one_png(
    tmp_path: Path, corner_cube: PatchNetwork, smooth_torus: PatchNetwork, mode: str
) -> None:
    path = tmp_path / f"pair_{mode}.png"
    render_side_by_side(
        path,
        [corner_cube, smooth_torus],
        ["creased", "smooth"],
        mode=mode,
        size=(500, 260),
        resolution=9,
        scan=cube_scan() if mode == "distance" else None,
    )
    image = assert_picture(path, (500, 260))
    grey = image[..., :3].mean(axis=-1)
    barred = mode in ("deviation", "distance")  # a colour bar at the right
    half = int(image.shape[1] * 0.4) if barred else image.shape[1] // 2
    assert (grey[:, :half] < 0.98).mean() > 0.15 and (grey[:, half:] < 0.98).mean() > 0.15


def test_open_and_mixed_orientation_networks_render(tmp_path: Path, shared_data: Path) -> None:
    from g1patch.io.bpt import read_bpt

    wave = build_corner_network(
        shapes.grid(4, 3, height=lambda x, y: 0.2 * np.sin(3 * x) * np.cos(2 * y))
    )
    teapot = network_from_patch_points(read_bpt(shared_data / "teapot.bpt"), source="teapot")
    for network, name in ((wave, "wave"), (teapot, "teapot")):
        for mode in MODES:
            path = tmp_path / f"{name}_{mode}.png"
            tessellated = tessellate(network, 5)
            scan = (tessellated.points, tessellated.triangles) if mode == "distance" else None
            render(path, network, mode=mode, size=(240, 180), resolution=9, scan=scan)
            assert_picture(path, (240, 180))


def test_the_spot_cow_renders_with_the_default_budget(tmp_path: Path, shared_data: Path) -> None:
    from g1patch.io.meshfile import read_mesh

    network = build_corner_network(read_mesh(shared_data / "spot_quadrangulated.obj"))
    path = tmp_path / "spot.png"
    render(path, network, mode="zebra", size=(360, 320), view=(20.0, 130.0), up="y")
    assert_picture(path, (360, 320))


def test_up_axis_is_a_rotation_of_the_world(tmp_path: Path) -> None:
    """A cube drawn with z up equals the cube with coordinates (y, z, x) drawn with y up."""
    mesh = shapes.cube_sphere(1)
    turned = mesh.with_vertices(np.roll(mesh.vertices, -1, axis=1))
    first, second = tmp_path / "z.png", tmp_path / "y.png"
    render(first, build_corner_network(mesh), mode="zebra", size=(200, 200), resolution=9, up="z")
    render(
        second, build_corner_network(turned), mode="zebra", size=(200, 200), resolution=9, up="y"
    )
    assert np.abs(read_png(first) - read_png(second)).mean() < 2e-3


def test_zoom_magnifies_about_the_target(tmp_path: Path, corner_cube: PatchNetwork) -> None:
    whole, zoomed = tmp_path / "whole.png", tmp_path / "zoomed.png"
    camera = {
        "view": render_module.DEFAULT_VIEW,
        "up": "z",
    }  # the corner (1, -1, 1) faces this camera
    render(whole, corner_cube, size=(200, 200), resolution=9, **camera)
    render(
        zoomed,
        corner_cube,
        size=(200, 200),
        resolution=9,
        zoom=4.0,
        target=(1.0, -1.0, 1.0),
        **camera,
    )

    def background(image: np.ndarray) -> float:
        return float((image[..., :3].mean(axis=-1) > 0.99).mean())

    assert background(read_png(zoomed)) < 0.5 * background(read_png(whole)), (
        "zooming in should fill the picture"
    )


def test_render_surfaces_draws_triangle_meshes(tmp_path: Path, corner_cube: PatchNetwork) -> None:
    path = tmp_path / "meshes.png"
    surface = tessellate(corner_cube, 9)
    render_surfaces(path, [surface, surface], ["one", "two"], size=(420, 210))
    assert_picture(path, (420, 210))


# --------------------------------------------------------------------------- stripes measure
# smoothness
def test_stripes_jump_across_creases_and_flow_across_g1_edges(
    corner_cube: PatchNetwork, smooth_torus: PatchNetwork
) -> None:
    assert check(smooth_torus).is_g1()
    creased = stripe_jumps(corner_cube)
    smooth = stripe_jumps(smooth_torus)
    assert creased.shape == (check(corner_cube).shared_edges,) and smooth.shape == (
        check(smooth_torus).shared_edges,
    )
    assert creased.min() > 0.5, (
        f"a 46° crease moves the stripes by less than half a period: {creased}"
    )
    assert smooth.max() < 1e-9


def test_gregory_cube_zebra_differs_from_the_corner_cube_along_the_edges(
    corner_cube: PatchNetwork, tmp_path: Path
) -> None:
    """Same cube, same camera: the corner cube's stripes jump at every edge, Gregory's do not."""
    from g1patch.build import build_gregory_network

    gregory = build_gregory_network(shapes.cube())
    assert stripe_jumps(corner_cube).min() > 0.5
    assert stripe_jumps(gregory).max() < 1e-9
    pictures = []
    for name, network in (("corner", corner_cube), ("gregory", gregory)):
        render(tmp_path / f"{name}.png", network, mode="zebra", size=(300, 300))
        pictures.append(matplotlib.image.imread(tmp_path / f"{name}.png")[..., :3])
    assert np.abs(pictures[0] - pictures[1]).mean() > 0.01


def test_stripe_jumps_grow_with_the_crease_and_the_stripe_count(corner_cube: PatchNetwork) -> None:
    coarse = build_corner_network(shapes.cube_sphere(1))
    fine = build_corner_network(shapes.cube_sphere(3))
    assert stripe_jumps(fine).max() < stripe_jumps(coarse).max() < stripe_jumps(corner_cube).max()
    np.testing.assert_allclose(
        stripe_jumps(corner_cube, stripes=24),
        2.0 * stripe_jumps(corner_cube, stripes=12),
        rtol=1e-12,
    )


def test_stripe_phase_is_a_function_of_the_normal_line() -> None:
    normals = np.random.default_rng(1).normal(size=(50, 3))
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    phase = stripe_phase(normals, view=(10.0, 20.0), stripes=7)
    np.testing.assert_allclose(
        np.sin(stripe_phase(-normals, view=(10.0, 20.0), stripes=7)), np.sin(phase), atol=1e-12
    )
    assert phase.shape == (50,)


def test_the_picture_keeps_both_sides_of_an_edge(
    corner_cube: PatchNetwork, smooth_torus: PatchNetwork
) -> None:
    """What is painted: the stripe phase at coincident samples of neighbouring patches jumps on
    the creased cube and agrees on the smooth torus (the sides' normals are not averaged)."""
    from scipy.spatial import cKDTree

    camera = render_module._Camera.from_view(render_module.DEFAULT_VIEW)

    def largest_jump(network: PatchNetwork) -> float:
        surface = render_module._sample(network, 17, None)
        patch = np.arange(len(surface.points)) // 17**2
        pairs = cKDTree(surface.points).query_pairs(1e-9, output_type="ndarray")
        pairs = pairs[patch[pairs[:, 0]] != patch[pairs[:, 1]]]
        assert len(pairs) > 0
        phase = render_module._phase(surface.normals, camera, 1)
        difference = (phase[pairs[:, 0]] - phase[pairs[:, 1]] + np.pi) % (2 * np.pi) - np.pi
        return float(np.abs(difference).max())

    assert largest_jump(corner_cube) > np.radians(20.0)
    assert largest_jump(smooth_torus) < 1e-9


# --------------------------------------------------------------------------- resolution
def test_choose_resolution_stays_in_range_and_within_budget() -> None:
    low, high = RESOLUTION_RANGE
    previous = high
    for count in (1, 6, 96, 2928, 100_000, 10**7):
        r = choose_resolution(count)
        assert low <= r <= previous
        previous = r
        if low < r < high:
            assert 2 * (r - 1) ** 2 * count <= 2 * render_module.TRIANGLE_BUDGET
    assert choose_resolution(96, panels=2) < choose_resolution(96)
    assert choose_resolution(96, closed=False) < choose_resolution(96)


# --------------------------------------------------------------------------- bad input
@pytest.mark.parametrize(
    ("arguments", "name"),
    [
        ({"mode": "wireframe"}, "mode"),
        ({"size": (0, 100)}, "size"),
        ({"size": (100.5, 100)}, "size"),
        ({"size": "large"}, "size"),
        ({"size": (100, 100, 3)}, "size"),
        ({"resolution": 1}, "resolution"),
        ({"resolution": 4.0}, "resolution"),
        ({"view": (90.0, 0.0)}, "view"),
        ({"view": ("up", 0.0)}, "view"),
        ({"view": (float("nan"), 0.0)}, "view"),
        ({"title": 3}, "title"),
        ({"stripes": 0}, "stripes"),
        ({"up": "w"}, "up"),
        ({"angle_range": (5.0, 1.0)}, "angle_range"),
        ({"report": "report"}, "report"),
        ({"zoom": 0.0}, "zoom"),
        ({"zoom": "4x"}, "zoom"),
        ({"target": (1.0, 2.0)}, "target"),
        ({"target": [[0.0, 0.0, 0.0], [1.0, 1.0, 1.0]]}, "target"),
    ],
)
def test_bad_arguments_name_themselves(
    tmp_path: Path, corner_cube: PatchNetwork, arguments: dict, name: str
) -> None:
    path = tmp_path / "bad.png"
    with pytest.raises(InputError, match=name):
        render(path, corner_cube, **arguments)
    assert not any(tmp_path.iterdir()), "a failed call left a file"


def test_bad_networks_paths_titles_and_reports(
    tmp_path: Path, corner_cube: PatchNetwork, smooth_torus: PatchNetwork
) -> None:
    path = tmp_path / "bad.png"
    with pytest.raises(InputError, match="network"):
        render(path, shapes.cube(), mode="shaded")  # a mesh, not a network
    with pytest.raises(InputError, match="path"):
        render(tmp_path / "picture.jpg", corner_cube)
    with pytest.raises(InputError, match="networks"):
        render_side_by_side(path, [], [])
    with pytest.raises(InputError, match="titles"):
        render_side_by_side(path, [corner_cube, smooth_torus], ["only one"])
    with pytest.raises(InputError, match="report"):
        render(path, corner_cube, mode="deviation", report=check(smooth_torus))
    with pytest.raises(InputError, match="meshes"):
        render_surfaces(path, [], [])
    with pytest.raises(InputError, match="samples"):
        stripe_jumps(corner_cube, samples=1)
    assert not any(tmp_path.iterdir())


def test_missing_matplotlib_is_a_clear_error(
    tmp_path: Path, corner_cube: PatchNetwork, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setitem(sys.modules, "matplotlib", None)
    monkeypatch.setitem(sys.modules, "matplotlib.figure", None)
    with pytest.raises(MissingDependencyError, match=r"matplotlib.*g1patch\[viz\]"):
        render(tmp_path / "x.png", corner_cube)
    assert not any(tmp_path.iterdir())


def test_a_failed_render_leaves_the_old_file_and_no_partial_one(
    tmp_path: Path, corner_cube: PatchNetwork, monkeypatch: pytest.MonkeyPatch
) -> None:
    path = tmp_path / "picture.png"
    path.write_bytes(b"old picture")

    def broken(*args: object) -> None:
        raise RuntimeError("drawing failed")

    monkeypatch.setattr(render_draw, "_gouraud_artist", broken)
    with pytest.raises(RuntimeError):
        render(path, corner_cube, resolution=5)
    assert path.read_bytes() == b"old picture"
    assert [p.name for p in tmp_path.iterdir()] == ["picture.png"]


def test_deviation_map_keeps_the_edges_of_patches_seen_edge_on(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A coarse sphere's patches at the silhouette are seen edge-on but are large: their edges stay
    lines, none is filled (their projected spacing is ~0; their spacing at the picture's scale is
    not)."""
    from g1patch.build import build_split4_network

    filled_counts: list[int] = []
    original = render_module._sample

    def spy(network, resolution, band, filled=None):  # type: ignore[no-untyped-def]
        filled_counts.append(0 if filled is None else int(np.count_nonzero(filled)))
        return original(network, resolution, band, filled)

    monkeypatch.setattr(render_pictures, "_sample", spy)
    render_module.render(
        tmp_path / "sphere.png",
        build_split4_network(shapes.cube()),
        mode="deviation",
        size=(600, 600),
    )
    assert filled_counts == [0]
