"""The automatic camera: which way is up and where the front is, on synthetic shapes whose answer
is known, on the shared Spot (y-up) and teapot (z-up), and in the pictures themselves."""

from __future__ import annotations

import math
from pathlib import Path

import matplotlib.image
import numpy as np
import pytest

from g1patch import shapes
from g1patch.build import build_gregory_network
from g1patch.cli import main
from g1patch.errors import InputError
from g1patch.network import PatchNetwork
from g1patch.render import (
    AUTO_TURN_DEG,
    DEFAULT_VIEW,
    FILL,
    _Camera,
    auto_camera,
    render,
    stripe_jumps,
)

AXES = {"x": 0, "y": 1, "z": 2}


def box_samples(size: tuple[float, float, float], n: int = 12) -> tuple[np.ndarray, np.ndarray]:
    """Points on the surface of the box [0, size] (an n × n grid of cell midpoints per face) and
    the area each stands for."""
    size_ = np.asarray(size, dtype=np.float64)
    t = (np.arange(n) + 0.5) / n
    a, b = (g.reshape(-1) for g in np.meshgrid(t, t, indexing="ij"))
    points, weights = [], []
    for axis in range(3):
        u, v = [k for k in range(3) if k != axis]
        for side in (0.0, 1.0):
            p = np.zeros((n * n, 3))
            p[:, axis], p[:, u], p[:, v] = side, a, b
            points.append(p * size_)
            weights.append(np.full(n * n, size_[u] * size_[v] / n**2))
    return np.concatenate(points), np.concatenate(weights)


def eye_of(up: str, view: tuple[float, float]) -> np.ndarray:
    """The world direction from the surface towards the camera of ``view`` about ``up``."""
    return _Camera.from_view(view, up).eye


# --------------------------------------------------------------------------- the rule on shapes
def test_a_slab_lying_in_the_xy_plane_is_z_up_and_seen_from_higher() -> None:
    up, (elevation, _) = auto_camera(*box_samples((4.0, 3.0, 0.5)))
    assert up == "z"
    assert 35.0 < elevation <= 45.0, "a flat slab is seen from above the 25° of a tall shape"


@pytest.mark.parametrize("size", [(1.0, 3.0, 1.0), (1.0, 3.0, 0.6)])
def test_a_tall_box_is_y_up_even_when_thinnest_along_z(size: tuple[float, float, float]) -> None:
    up, (elevation, _) = auto_camera(*box_samples(size))
    assert up == "y"
    assert elevation == pytest.approx(25.0), "a tall shape is seen from the lowest elevation"


def test_a_shape_without_a_long_axis_is_y_up_from_the_default_view() -> None:
    up, view = auto_camera(*box_samples((2.0, 2.0, 2.0)))
    assert up == "y" and view == pytest.approx(DEFAULT_VIEW)


def test_the_front_is_the_higher_end_of_the_long_axis_and_seen_three_quarter() -> None:
    """A y-up 'animal': a long body along z with a raised 'head' at −z."""
    body, body_w = box_samples((1.0, 1.0, 3.0))
    head, head_w = box_samples((1.0, 1.0, 0.8))
    points = np.concatenate([body, head + [0.0, 1.2, -0.4]])
    weights = np.concatenate([body_w, head_w])
    up, view = auto_camera(points, weights)
    assert up == "y"
    eye = eye_of(up, view)
    horizontal = eye * [1.0, 0.0, 1.0] / np.linalg.norm(eye * [1.0, 0.0, 1.0])
    assert math.degrees(math.acos(horizontal @ [0.0, 0.0, -1.0])) == pytest.approx(AUTO_TURN_DEG)
    assert horizontal[0] < 0.0, "the camera is on the model's left: up × front = y × (−z) = −x"
    # the head moved to +z turns the camera round to the other end
    flipped = points * [1.0, 1.0, -1.0]
    eye = eye_of(*auto_camera(flipped, weights))
    assert eye[2] > 0.0 and eye[0] > 0.0


def test_the_camera_follows_the_data_about_the_up_axis() -> None:
    """A slab turned by 30° about z: the azimuth turns by 30° (modulo the front's half turn)."""
    points, weights = box_samples((4.0, 2.0, 0.5))
    points -= points.mean(axis=0)
    points[:, 2] += np.where(
        points[:, 0] > 0, 0.2 * points[:, 0], 0.0
    )  # a raised +x end: the front
    turn = math.radians(30.0)
    rotation = np.array(
        [
            [math.cos(turn), -math.sin(turn), 0.0],
            [math.sin(turn), math.cos(turn), 0.0],
            [0.0, 0.0, 1.0],
        ]
    )
    up, view = auto_camera(points, weights)
    turned_up, turned_view = auto_camera(points @ rotation.T, weights)
    assert up == turned_up == "z"
    assert turned_view[0] == pytest.approx(view[0])
    assert (turned_view[1] - view[1]) % 360.0 == pytest.approx(30.0)


def test_an_explicit_up_is_kept_and_weights_count() -> None:
    points, weights = box_samples((4.0, 3.0, 0.5))
    assert auto_camera(points, weights, up="x")[0] == "x"
    # a tall post at the far end: the thing stands on its slab (the base rule: z whatever the
    # weights), and a heavy post makes it taller, so it is seen from lower down
    wall, wall_w = box_samples((0.2, 0.2, 6.0))
    both = np.concatenate([points, wall + [4.0, 1.5, 0.0]])
    heavy = auto_camera(both, np.concatenate([weights, 100.0 * wall_w]))
    light = auto_camera(both, np.concatenate([weights, 0.0 * wall_w]))
    assert heavy[0] == light[0] == "z" and heavy[1][0] < light[1][0]


def test_bad_inputs_name_themselves(tmp_path: Path) -> None:
    points, weights = box_samples((1.0, 1.0, 1.0))
    with pytest.raises(InputError, match="points"):
        auto_camera(points[:, :2])
    with pytest.raises(InputError, match="weights"):
        auto_camera(points, weights[:-1])
    with pytest.raises(InputError, match="weights"):
        auto_camera(points, -weights)
    with pytest.raises(InputError, match="up"):
        auto_camera(points, up="w")
    network = build_gregory_network(shapes.cube())
    with pytest.raises(InputError, match="weights"):
        auto_camera(network, weights)
    with pytest.raises(InputError, match="view"):
        render(tmp_path / "x.png", network, view="sideways")
    assert auto_camera(np.zeros((5, 3))) == ("y", DEFAULT_VIEW), "no area: nothing to choose by"


def test_generated_shapes_get_their_expected_up() -> None:
    assert auto_camera(build_gregory_network(shapes.torus(16, 8)))[0] == "z"  # lies in the xy plane
    assert auto_camera(build_gregory_network(shapes.genus2()))[0] == "z"  # a 5 × 3 × 1 slab
    assert auto_camera(build_gregory_network(shapes.cube()))[0] == "y"


def test_stripe_jumps_default_to_the_pictures_camera() -> None:
    from g1patch.construct.corner import build_corner_network

    network = build_corner_network(shapes.cube_sphere(1))
    up, view = auto_camera(network)
    np.testing.assert_array_equal(stripe_jumps(network), stripe_jumps(network, view=view, up=up))


# --------------------------------------------------------------------------- shared data
@pytest.fixture(scope="module")
def shared_data_path() -> Path:
    import conftest

    return conftest.shared_data_path()


@pytest.fixture(scope="module")
def spot(shared_data_path: Path) -> tuple[PatchNetwork, np.ndarray]:
    from g1patch.io.meshfile import read_mesh

    mesh = read_mesh(shared_data_path / "spot_quadrangulated.obj")
    return build_gregory_network(mesh), mesh.vertices


def test_spot_is_y_up_and_seen_from_its_front_three_quarter(
    spot: tuple[PatchNetwork, np.ndarray],
) -> None:
    network, vertices = spot
    up, view = auto_camera(network)
    assert up == "y"
    assert vertices[np.argmax(vertices[:, 1]), 2] < 0.0, (
        "Spot faces −z: its horns stand at the −z end"
    )
    eye = eye_of(up, view)
    horizontal = eye * [1.0, 0.0, 1.0] / np.linalg.norm(eye * [1.0, 0.0, 1.0])
    assert math.degrees(math.acos(horizontal @ [0.0, 0.0, -1.0])) == pytest.approx(
        AUTO_TURN_DEG, abs=1.0
    )
    assert 20.0 <= view[0] <= 30.0


def silhouette(path: Path) -> np.ndarray:
    """The pixels (rows, columns) the surface covers."""
    image = matplotlib.image.imread(path)[..., :3]
    return image.mean(axis=-1) < 0.99


def test_the_default_picture_of_spot_is_upright_from_the_front_three_quarter(
    tmp_path: Path, spot: tuple[PatchNetwork, np.ndarray]
) -> None:
    """The default picture is the orthographic projection from a camera whose screen-up is world
    y, turned 35° from Spot's front (−z) towards its left (−x), set up here independently of the
    renderer: the silhouette's box has that projection's aspect, fills 90 % of the picture, and
    the mesh vertices (which the interpolating surface passes through) land on the silhouette, the
    horns at its top and the hooves at its bottom. The picture drawn on its back (z-up) fails
    all."""
    network, vertices = spot
    size = (480, 400)
    path = tmp_path / "spot.png"
    render(path, network, size=size)
    mask = silhouette(path)

    up, (elevation, _) = auto_camera(network)
    e, turn = math.radians(elevation), math.radians(AUTO_TURN_DEG)
    horizontal = np.array([-math.sin(turn), 0.0, -math.cos(turn)])  # front −z, turned towards −x
    eye = math.cos(e) * horizontal + math.sin(e) * np.array([0.0, 1.0, 0.0])
    right = np.cross([0.0, 1.0, 0.0], eye)
    right /= np.linalg.norm(right)
    screen_up = np.cross(eye, right)
    assert screen_up[1] > 0.85  # cos(elevation): world y is drawn upwards
    screen = np.stack([vertices @ right, vertices @ screen_up], axis=-1)
    low, high = screen.min(axis=0), screen.max(axis=0)

    rows, columns = np.nonzero(mask)
    box = np.array(
        [columns.max() - columns.min() + 1, rows.max() - rows.min() + 1], dtype=np.float64
    )
    assert (box / size).max() == pytest.approx(FILL, abs=0.02), "framed to 90 % of the binding side"
    assert box[1] / box[0] == pytest.approx((high - low)[1] / (high - low)[0], rel=0.04), (
        "the aspect of an upright Spot"
    )

    scale = (box[1] - 1) / (high - low)[1]
    column = columns.min() + (screen[:, 0] - low[0]) * scale
    row = rows.max() - (screen[:, 1] - low[1]) * scale
    r, c = (
        np.clip(np.round(row).astype(int), 0, size[1] - 1),
        np.clip(np.round(column).astype(int), 0, size[0] - 1),
    )
    grown = (
        mask
        | np.roll(mask, 1, 0)
        | np.roll(mask, -1, 0)
        | np.roll(mask, 1, 1)
        | np.roll(mask, -1, 1)
    )
    assert grown[r, c].mean() > 0.99, "the vertices project onto the silhouette"
    top, bottom = np.argmin(row), np.argmax(row)
    assert abs(row[top] - rows.min()) < 3 and abs(row[bottom] - rows.max()) < 3
    assert vertices[top, 1] > vertices[:, 1].max() - 0.1, "a horn is at the top of the picture"
    assert vertices[bottom, 1] < vertices[:, 1].min() + 0.1, (
        "a hoof is at the bottom of the picture"
    )

    on_its_back = tmp_path / "back.png"
    render(on_its_back, network, size=size, up="z")
    rows_z, columns_z = np.nonzero(silhouette(on_its_back))
    aspect_z = (rows_z.max() - rows_z.min() + 1) / (columns_z.max() - columns_z.min() + 1)
    assert abs(aspect_z - box[1] / box[0]) > 0.1 * box[1] / box[0], (
        "the test tells a z-up picture apart"
    )


#: rotations taking a y-up model to z-up and a z-up one to y-up (about x, by ±90°)
Y_TO_Z = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])


def _rotated(network: PatchNetwork, rotation: np.ndarray) -> PatchNetwork:
    from dataclasses import replace

    from g1patch.gregory import GregoryPatchSet

    assert isinstance(network.patches, GregoryPatchSet)
    vertices = None if network.vertices is None else network.vertices @ rotation.T
    points = network.patches.world_points() @ rotation.T
    return replace(network, patches=GregoryPatchSet(points), vertices=vertices)


def test_spot_stood_on_z_is_z_up_and_drawn_as_upright(
    tmp_path: Path, spot: tuple[PatchNetwork, np.ndarray]
) -> None:
    """The same cow in a z-up file stands on its hooves (the largest flat face of its hull faces
    −z), so its picture is the y-up file's, pixel for pixel: once it lay on its side."""
    network, _ = spot
    standing = _rotated(network, Y_TO_Z)
    assert auto_camera(standing)[0] == "z"
    pictures = []
    for name, surface in (("y", network), ("z", standing)):
        render(tmp_path / f"{name}.png", surface, size=(240, 240))
        pictures.append(matplotlib.image.imread(tmp_path / f"{name}.png"))
    assert np.abs(pictures[0] - pictures[1]).max() <= 1 / 255


def test_a_shape_with_two_equal_flat_sides_keeps_the_slab_rule() -> None:
    """A flat torus touches its top and bottom planes alike: no base to tell, so the slab rule
    (z-up for a slab in the xy plane) decides, as before."""
    assert auto_camera(build_gregory_network(shapes.torus(8, 4)))[0] == "z"


def test_the_teapot_is_z_up(shared_data_path: Path) -> None:
    from g1patch.io.bpt import read_bpt
    from g1patch.network import network_from_patch_points

    teapot = network_from_patch_points(read_bpt(shared_data_path / "teapot.bpt"))
    up, (elevation, _) = auto_camera(teapot)
    assert up == "z" and 25.0 < elevation < 40.0


# --------------------------------------------------------------------------- command line
def test_render_and_demo_take_auto_and_explicit_cameras(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    network = tmp_path / "cube.npz"
    mesh = tmp_path / "cube.obj"
    cube = shapes.cube()
    mesh.write_text(
        "".join(f"v {x} {y} {z}\n" for x, y, z in cube.vertices)
        + "".join("f " + " ".join(str(i + 1) for i in face) + "\n" for face in cube.faces)
    )
    assert main(["build", str(mesh), "-o", str(network)]) == 0
    pictures = {}
    for name, options in (
        ("auto", []),
        ("auto2", ["--view", "auto", "--up", "auto"]),
        ("y", ["--up", "y", "--view", "25", "-60"]),
        ("high", ["--view", "60", "30"]),
    ):
        pictures[name] = tmp_path / f"{name}.png"
        assert (
            main(
                [
                    "render",
                    str(network),
                    "-o",
                    str(pictures[name]),
                    "--size",
                    "120",
                    "120",
                    *options,
                ]
            )
            == 0
        )
    read = {name: matplotlib.image.imread(path) for name, path in pictures.items()}
    np.testing.assert_array_equal(read["auto"], read["auto2"])
    assert np.abs(read["auto"] - read["y"]).max() < 0.02  # the cube: y-up from the default view
    assert np.abs(read["auto"] - read["high"]).mean() > 1e-3
    capsys.readouterr()
    assert main(["render", str(network), "-o", str(tmp_path / "bad.png"), "--view", "up"]) == 2
    assert "--view" in capsys.readouterr().err
    assert (
        main(["render", str(network), "-o", str(tmp_path / "bad.png"), "--view", "1", "2", "3"])
        == 2
    )
    assert not (tmp_path / "bad.png").exists()


def test_a_long_title_fits_its_panel(tmp_path: Path) -> None:
    """The title's font shrinks until its longest line fits: no text runs off the picture's
    sides."""
    path = tmp_path / "titled.png"
    render(
        path,
        build_gregory_network(shapes.cube()),
        size=(240, 200),
        title="a rather long title " * 4,
    )
    grey = matplotlib.image.imread(path)[..., :3].mean(axis=-1)
    band = grey[: grey.shape[0] // 6]
    assert (band < 0.5).any(), "the title is drawn"
    assert (band[:, :3] > 0.99).all() and (band[:, -3:] > 0.99).all(), (
        "the title runs off the picture"
    )


def squat_blob(up: str, seed: int = 3) -> tuple[np.ndarray, np.ndarray]:
    """A Stanford-bunny-like sample: an egg as wide (x) as it is tall, three quarters as deep, cut
    off a fifth of its height up, its base bumpy (heights within 1.5 % of the size, so its hull's
    base facets are of many planes a few degrees apart); ``up`` "y" or "z" (the same blob
    turned)."""
    rng = np.random.default_rng(seed)
    direction = rng.normal(size=(40_000, 3))
    direction /= np.linalg.norm(direction, axis=1, keepdims=True)
    points = direction * [1.0, 1.0, 0.77]
    base = points[:, 1] < -0.6
    points[base, 1] = -0.6 + 0.03 * rng.random(base.sum())
    if up == "z":
        points = points[:, [0, 2, 1]] * [1.0, -1.0, 1.0]  # y → z, right-handed
    return points, np.ones(len(points))


@pytest.mark.parametrize("up", ["y", "z"])
def test_a_rough_base_is_stood_on_in_either_up_axis(up: str) -> None:
    """Three scans of the Stanford bunny (two y-up, one z-up) were drawn lying down: thinnest
    front to back, it read as a z slab, and its scanned base is no one plane of the hull. Facets
    gathered by direction find the base whichever axis is up (before: z for the y-up blob, y for
    the z-up one)."""
    points, weights = squat_blob(up)
    assert auto_camera(points, weights)[0] == up
