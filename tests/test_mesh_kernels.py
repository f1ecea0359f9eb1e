"""The compiled connectivity and face-area kernels of :mod:`g1patch.mesh` against their NumPy
references.

``_connect(..., compiled=True)`` must return every array of the reference (``compiled=False``,
the half-edge pairing by one argsort) bit for bit, on quads and on polygons, closed and open, and
where a check fails the reference's own error (the kernel only declines; the NumPy code names the
problem). ``_check_face_areas(..., compiled=True)`` gives the reference's verdict and message.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from g1patch import shapes
from g1patch.errors import G1PatchError
from g1patch.mesh import QuadMesh, _as_polygons
from g1patch.mesh import connectivity as mesh_connectivity
from g1patch.mesh import validate as mesh_validate

SETTINGS = settings(
    max_examples=200, deadline=None, derandomize=True, suppress_health_check=list(HealthCheck)
)


def connectivity(corners: np.ndarray, sizes: np.ndarray, n_vertices: int, compiled: bool) -> tuple:
    """``_connect``'s arrays (dtype, shape, bytes), or its error."""
    try:
        result = mesh_connectivity._connect(corners, sizes, n_vertices, compiled=compiled)
    except G1PatchError as error:
        return (type(error).__name__, str(error))
    return tuple(
        (name, array.dtype.str, array.shape, array.tobytes())
        for name, array in vars(result).items()
    )


def assert_same(corners: np.ndarray, sizes: np.ndarray, n_vertices: int) -> tuple:
    reference = connectivity(corners, sizes, n_vertices, compiled=False)
    assert connectivity(corners, sizes, n_vertices, compiled=True) == reference
    return reference


MESHES = {
    "cube": shapes.cube,
    "torus": lambda: shapes.torus(12, 5),
    "grid": lambda: shapes.grid(7, 3),
    "strip": lambda: shapes.strip(4),
    "genus2": shapes.genus2,
    "fan300": lambda: shapes.fan(
        300
    ),  # a vertex beyond the kernel's insertion buckets: the NumPy code
    "boundary_fan": lambda: shapes.boundary_fan(6),
    "filleted_box": shapes.filleted_box,
}


@pytest.mark.parametrize("name", MESHES)
def test_connect_kernel_is_the_reference_on_quads(name: str) -> None:
    mesh = MESHES[name]()
    corners, sizes = mesh.faces.ravel().copy(), np.full(mesh.n_faces, 4, dtype=np.int64)
    assert len(assert_same(corners, sizes, mesh.n_vertices)) == 11


def test_connect_kernel_on_a_million_halfedges_is_the_reference() -> None:
    mesh = shapes.large_torus(250_000)
    corners, sizes = mesh.faces.ravel().copy(), np.full(mesh.n_faces, 4, dtype=np.int64)
    assert len(assert_same(corners, sizes, mesh.n_vertices)) == 11


def test_connect_kernel_on_polygons_and_unused_vertices() -> None:
    """A pentagon, a triangle and quads, with a vertex no face uses."""
    faces = [[0, 1, 2, 3, 4], [0, 4, 5], [1, 0, 5, 6], [2, 1, 6, 7]]
    corners, sizes = _as_polygons(faces)
    assert len(assert_same(corners, sizes, 9)) == 11


BROKEN = {
    "three faces on an edge": [[0, 1, 2, 3], [1, 0, 4, 5], [0, 1, 6, 7]],
    "orientation": [[0, 1, 2, 3], [0, 1, 4, 5]],
    "two fans": [[0, 1, 2, 3], [0, 4, 5, 6]],
    "repeated vertex": [[0, 1, 1, 3]],
    "index range": [[0, 1, 2, 99]],
}


@pytest.mark.parametrize("name", BROKEN)
def test_connect_kernel_leaves_errors_to_the_reference(name: str) -> None:
    corners, sizes = _as_polygons(BROKEN[name])
    assert len(assert_same(corners, sizes, 8)) == 2


def test_connect_kernel_valence_two_and_closed_fans() -> None:
    """Two quads glued along two edges (interior valence 2), and a vertex with two closed fans."""
    corners, sizes = _as_polygons([[0, 1, 2, 3], [0, 3, 2, 1]])
    assert assert_same(corners, sizes, 4)[0] == "ValenceError"
    cube = shapes.cube()
    twice = np.concatenate([cube.faces, cube.faces + 8])
    twice[twice == 8] = 0  # two cubes sharing vertex 0 only
    assert (
        assert_same(twice.ravel().copy(), np.full(12, 4, dtype=np.int64), 16)[0]
        == "NonManifoldError"
    )


@st.composite
def quad_soups(draw) -> tuple[np.ndarray, np.ndarray, int]:
    """Patches of a grid, some faces flipped, removed or duplicated: valid or broken any way."""
    mesh = shapes.grid(draw(st.integers(1, 5)), draw(st.integers(1, 5)))
    faces = mesh.faces.copy()
    keep = draw(st.lists(st.booleans(), min_size=len(faces), max_size=len(faces)))
    faces = faces[np.array(keep)] if any(keep) else faces
    for row in draw(st.lists(st.integers(0, len(faces) - 1), max_size=2)):
        faces[row] = faces[row][::-1]
    if draw(st.booleans()):
        faces = np.concatenate([faces, faces[:1]])
    return faces.ravel().copy(), np.full(len(faces), 4, dtype=np.int64), mesh.n_vertices


@SETTINGS
@given(quad_soups())
def test_connect_kernel_is_the_reference_on_damaged_grids(
    soup: tuple[np.ndarray, np.ndarray, int],
) -> None:
    assert_same(*soup)


def area_outcome(vertices: np.ndarray, faces: np.ndarray, compiled: bool) -> str:
    try:
        mesh_validate._check_face_areas(vertices, faces, compiled=compiled)
    except G1PatchError as error:
        return f"{type(error).__name__}: {error}"
    return "ok"


@pytest.mark.parametrize("scale", [1.0, 1e-60, 1e29])
def test_face_area_kernel_gives_the_reference_verdict(scale: float) -> None:
    mesh = shapes.torus(10, 4)
    vertices, faces = mesh.vertices * scale, mesh.faces
    assert area_outcome(vertices, faces, True) == area_outcome(vertices, faces, False) == "ok"
    flat = vertices.copy()
    flat[faces[3, 2]] = flat[faces[3, 0]]  # a diagonal of zero length
    flat[faces[7, 1]] = (
        flat[faces[7, 0]] + flat[faces[7, 2]]
    ) / 2  # not zero area: one diagonal remains
    assert area_outcome(flat, faces, True) == area_outcome(flat, faces, False) != "ok"
    nan = vertices.copy()
    nan[0, 0] = np.nan
    assert area_outcome(nan, faces, True) == area_outcome(nan, faces, False)


def test_from_arrays_of_a_large_mesh_is_the_reference(monkeypatch: pytest.MonkeyPatch) -> None:
    """The whole QuadMesh through the kernels and through the NumPy code: every topology array
    equal."""
    mesh = shapes.large_torus(30_000)
    assert (
        mesh.n_faces >= mesh_validate.KERNEL_FACES
        and 4 * mesh.n_faces >= mesh_connectivity.KERNEL_HALFEDGES
    )
    fast = QuadMesh.from_arrays(mesh.vertices, mesh.faces)
    monkeypatch.setattr(mesh_connectivity, "KERNEL_HALFEDGES", 10**12)
    monkeypatch.setattr(mesh_validate, "KERNEL_FACES", 10**12)
    slow = QuadMesh.from_arrays(mesh.vertices, mesh.faces)
    assert fast.vertices.tobytes() == slow.vertices.tobytes()
    for name, value in vars(slow.topology).items():
        if isinstance(value, np.ndarray):
            assert getattr(fast.topology, name).tobytes() == value.tobytes(), name
