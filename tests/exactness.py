"""Shared by the exact-G1 construction tests: the bars, noise, generated shapes, the assertion."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from hypothesis import strategies as st

from g1patch import shapes
from g1patch.continuity import ContinuityReport
from g1patch.mesh import QuadMesh

SHARED_MESHES = [
    "catmark_cube.obj",
    "catmark_torus.obj",
    "catmark_xord_boundary.obj",
    "catmark_xord_interior.obj",
    "spot_quadrangulated.obj",
]
#: DESIGN §4/§5: "exactly G1", G0 gap and vertex interpolation, relative to the bbox diagonal
MAX_ANGLE_DEG = 1e-9
MAX_GAP = 1e-12
MAX_VERTEX_DEVIATION = 1e-12
#: the shape rules whose surfaces pass through the mesh vertices (``limit`` has its own tests)
INTERPOLATING = ("interpolate", "legacy")
#: vertex noise, in units of the shortest edge: beyond ~5 % thin quads fold (G1 stays exact)
NOISE = 0.05


def perturbed(mesh: QuadMesh, amplitude: float, seed: int) -> QuadMesh:
    """Uniform vertex noise of ``amplitude`` × the shortest edge in each coordinate."""
    edges = mesh.topology.edges
    shortest = np.linalg.norm(mesh.vertices[edges[:, 0]] - mesh.vertices[edges[:, 1]], axis=1).min()
    noise = np.random.default_rng(seed).uniform(-1.0, 1.0, mesh.vertices.shape)
    return mesh.with_vertices(mesh.vertices + amplitude * shortest * noise)


def height(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    return 0.3 * np.sin(3.0 * x) * y + 0.2 * x * x


#: shapes drawn by the property tests, each from a size index
GENERATED: dict[str, Callable[[int], QuadMesh]] = {
    "fan": lambda n: shapes.fan(3 + n % 10, 1 + n % 3),  # interior valence 3..12, 1..3 rings
    "boundary_fan": lambda n: shapes.boundary_fan(1 + n % 7),  # boundary vertex with 1..7 faces
    "strip": lambda n: shapes.strip(1 + n % 5),
    "grid": lambda n: shapes.grid(2 + n % 3, 1 + n % 4, height=height),
    "torus": lambda n: shapes.torus(3 + n % 6, 3 + n % 4),
    "genus2": lambda n: shapes.genus2(),
    "cube_sphere": lambda n: shapes.cube_sphere(n % 3),
}


def assert_exact_g1(report: ContinuityReport, folds: bool = True) -> None:
    assert report.max_edge_angle_deg <= MAX_ANGLE_DEG, report.worst_edge
    assert report.max_corner_angle_deg <= MAX_ANGLE_DEG
    assert report.max_g0_gap <= MAX_GAP
    assert (
        report.max_vertex_deviation is not None
        and report.max_vertex_deviation <= MAX_VERTEX_DEVIATION
    )
    assert report.degenerate_normals == 0
    if folds:
        assert report.folds == 0


@st.composite
def noisy_generated_meshes(draw: st.DrawFn) -> tuple[QuadMesh, str]:
    """A generated shape of a drawn kind and size, with drawn vertex noise, and a shape rule."""
    shape = draw(st.sampled_from(sorted(GENERATED)))
    mesh = GENERATED[shape](draw(st.integers(0, 59)))
    noisy = perturbed(mesh, draw(st.floats(0.0, NOISE)), draw(st.integers(0, 2**32 - 1)))
    return noisy, draw(st.sampled_from(["interpolate", "legacy"]))
