"""Make the pictures of the documentation: ``python docs/make_pictures.py`` (from the repository).

Every picture is drawn by g1patch itself, with the default camera (``render``'s ``up`` and ``view``
``"auto"``), from meshes that :mod:`g1patch.shapes` generates or that the package ships, and from
the shared meshes (Spot, the teapot) when ``../shared/data`` is beside the repository (their
pictures are skipped, and the old ones kept, when it is not). Each PNG is written to
``docs/images/`` reduced to an adaptive palette of at most 256 colours, so that it stays below
:data:`MAX_BYTES` (checked: the script fails on a larger one).
"""

from __future__ import annotations

import argparse
import tempfile
from collections.abc import Callable
from importlib import resources
from pathlib import Path

import numpy as np

from g1patch import shapes
from g1patch.build import build_gregory_network, build_split4_network
from g1patch.construct.corner import build_corner_network
from g1patch.io.bpt import read_bpt
from g1patch.io.meshfile import read_mesh
from g1patch.network import PatchNetwork, network_from_patch_points
from g1patch.render import render, render_side_by_side, render_surfaces
from g1patch.tessellate import TriangleMesh, tessellate

ROOT = Path(__file__).resolve().parents[1]
IMAGES = ROOT / "docs" / "images"
SHARED = ROOT.parent / "shared" / "data"
#: the largest PNG committed
MAX_BYTES = 150_000
SIZE = (600, 450)
WIDE = (900, 300)


def save_small(draw: Callable[[Path], None], name: str) -> Path:
    """Draw into a temporary PNG, reduce it to a 256-colour palette and write
    ``docs/images/name``."""
    from PIL import Image

    target = IMAGES / name
    with tempfile.TemporaryDirectory() as folder:
        full = Path(folder) / name
        draw(full)
        with Image.open(full) as image:
            image.convert("RGB").quantize(
                256, method=Image.Quantize.MEDIANCUT, dither=Image.Dither.NONE
            ).save(target, optimize=True)
    size = target.stat().st_size
    if size > MAX_BYTES:
        raise SystemExit(f"{target}: {size} bytes, more than {MAX_BYTES}")
    print(f"wrote {target.relative_to(ROOT)} ({size // 1000} kB)")
    return target


def flat_triangles(network: PatchNetwork, resolution: int) -> TriangleMesh:
    """The triangles ``export`` writes at ``resolution``, each lit by its own normal (facets
    show)."""
    mesh = tessellate(network, resolution)
    corners = mesh.points[mesh.triangles]
    normal = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    normal /= np.maximum(np.linalg.norm(normal, axis=1, keepdims=True), 1e-300)
    points = corners.reshape(-1, 3)
    return TriangleMesh(
        points, np.repeat(normal, 3, axis=0), np.arange(len(points), dtype=np.int64).reshape(-1, 3)
    )


def generated() -> None:
    """Pictures of generated and packaged meshes: the paper's cube and a torus."""
    with resources.as_file(resources.files("g1patch") / "data" / "cube.obj") as path:
        cube = read_mesh(path)
    three = [
        build_corner_network(cube, tangents="arc", twist="coons"),
        build_gregory_network(cube),
        build_split4_network(cube),
    ]
    titles = ["paper: corner G1 (creased)", "Gregory (exact G1)", "split4 (exact G1)"]
    for mode in ("zebra", "deviation"):
        save_small(
            lambda p, m=mode: render_side_by_side(p, three, titles, mode=m, size=WIDE),
            f"cube_three_ways_{mode}.png",
        )
    torus = build_gregory_network(shapes.torus(12, 6))
    save_small(
        lambda p: render_surfaces(
            p,
            [flat_triangles(torus, 3), flat_triangles(torus, 9)],
            ["resolution 3", "resolution 9"],
            size=(600, 300),
        ),
        "torus_export.png",
    )


def shared() -> None:
    """Pictures of the shared Spot cow (y-up OBJ), OpenSubdiv's creased cube and the Utah teapot
    (z-up Bézier patches)."""
    spot_mesh = read_mesh(SHARED / "spot_quadrangulated.obj")
    spot = build_gregory_network(spot_mesh)
    for mode in ("shaded", "zebra", "deviation"):
        save_small(lambda p, m=mode: render(p, spot, mode=m, size=SIZE), f"spot_{mode}.png")
    corner = build_corner_network(spot_mesh)
    save_small(
        lambda p: render_side_by_side(
            p,
            [corner, spot],
            ["paper: corner G1", "Gregory (exact G1)"],
            mode="deviation",
            size=(800, 360),
        ),
        "spot_corner_vs_gregory.png",
    )
    creased = build_gregory_network(read_mesh(SHARED / "catmark_cube_creases2.obj"))
    save_small(lambda p: render(p, creased, mode="deviation", size=SIZE), "creases_deviation.png")
    teapot = network_from_patch_points(read_bpt(SHARED / "teapot.bpt"), source="teapot")
    save_small(lambda p: render(p, teapot, size=SIZE), "teapot_shaded.png")
    save_small(lambda p: render(p, teapot, mode="deviation", size=SIZE), "teapot_deviation.png")


def main() -> None:
    argparse.ArgumentParser(description=__doc__.splitlines()[0]).parse_args()
    IMAGES.mkdir(parents=True, exist_ok=True)
    generated()
    if all(
        (SHARED / name).is_file()
        for name in ("spot_quadrangulated.obj", "catmark_cube_creases2.obj", "teapot.bpt")
    ):
        shared()
    else:
        print(f"skipped the pictures of the shared meshes: {SHARED} not found")


if __name__ == "__main__":
    main()
