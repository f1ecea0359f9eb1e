"""split4's numba kernels (``split4_patches(..., compiled=True)``) against the NumPy reference.

Both compute the same formulas from the same stars, shears and even-valence shifts; they differ
only in the order of a few sums: the net quantities (BLAS's matrix product against the kernel's
sums of at most 16 nonzero weights in index order) and the min-norm operators (BLAS against
``Σ_i op[j, i] x_i`` in order), each a sum of a handful of terms of size ≤ max|x|. So every control
point, midpoint and centre agrees within :data:`POINT_ULPS` ε · max|x| (measured ≤ 4.3). A unit
normal is a cross product of tangents of length ~ an edge ℓ, so a point's rounding turns it by
~ε max|x| / ℓ: normals agree within :data:`NORMAL_ULPS` ε · max|x| / ℓ_min (measured ≤ 9.6). A wrong
index or formula in a kernel moves points by the size of a patch, far outside either bound. Cut
into many ranges on threads, the kernels give their one-range result bit for bit.
"""

from __future__ import annotations

import numpy as np
import pytest

from g1patch import kernels, shapes
from g1patch.construct import split4
from g1patch.construct.split4 import macro_nets, split4_patches, split4_star, threshold
from g1patch.frame import Frame
from g1patch.mesh import QuadMesh, subdivide
from g1patch.targets import Targets, shape_targets

EPS = np.finfo(np.float64).eps
POINT_ULPS = 16
NORMAL_ULPS = 64


def irregular(levels: int) -> QuadMesh:
    """The bench's mesh, small: a torus with three quads collapsed along a diagonal (valences 3
    and 6 beside 4), subdivided ``levels`` times, its vertices jittered."""
    base = shapes.torus(16, 16, r=0.4)
    faces, vertices = base.faces.copy(), base.vertices.copy()
    keep = np.ones(len(faces), dtype=bool)
    for f in (17, 100, 183):
        a, c = faces[f, 0], faces[f, 2]
        vertices[a] = 0.5 * (vertices[a] + vertices[c])
        faces[faces == c] = a
        keep[f] = False
    mesh = QuadMesh.from_arrays(vertices, faces[keep])
    for _ in range(levels):
        mesh = subdivide(mesh)
    return noisy(mesh, 0.1, 3)


def noisy(mesh: QuadMesh, share: float, seed: int) -> QuadMesh:
    """``mesh`` with every vertex moved by up to ``share`` of the shortest edge."""
    edges = mesh.vertices[mesh.topology.edges]
    shortest = np.linalg.norm(edges[:, 0] - edges[:, 1], axis=1).min()
    rng = np.random.default_rng(seed)
    return mesh.with_vertices(
        mesh.vertices + rng.uniform(-share * shortest, share * shortest, mesh.vertices.shape)
    )


MESHES = {
    "cube": lambda: shapes.cube(),
    "noisy torus": lambda: noisy(shapes.torus(24, 12), 0.2, 1),
    "irregular": lambda: irregular(1),
    "fan 7": lambda: noisy(shapes.fan(7, rings=2), 0.1, 2),
    "fan 24": lambda: shapes.fan(24, rings=2),  # an even high valence: the midpoint shifts
    "boundary fan": lambda: shapes.boundary_fan(5),
    "grid": lambda: noisy(shapes.grid(7, 5), 0.2, 4),
    "noisy sphere": lambda: shapes.noisy_sphere(2),
    "genus 2": lambda: shapes.genus2(),
}


def local_targets(mesh: QuadMesh, shape: str = "interpolate") -> tuple[Targets, Frame]:
    frame = Frame.of_points(mesh.vertices)
    return shape_targets(mesh.with_vertices(frame.to_local(mesh.vertices)), shape), frame


def assert_close(
    mesh: QuadMesh, reference: split4.Split4Parts, compiled: split4.Split4Parts
) -> None:
    """Points within POINT_ULPS ε · max|x|, normals within NORMAL_ULPS ε · max|x| / ℓ_min (module
    docstring)."""
    size = np.abs(reference[0].control).max()
    np.testing.assert_array_less(
        np.abs(compiled[0].control - reference[0].control), POINT_ULPS * EPS * size
    )
    np.testing.assert_array_less(np.abs(compiled[1] - reference[1]), POINT_ULPS * EPS * size)
    edges = mesh.vertices[mesh.topology.edges]
    shortest = np.linalg.norm(edges[:, 0] - edges[:, 1], axis=1).min()
    np.testing.assert_array_less(
        np.abs(compiled[2] - reference[2]), NORMAL_ULPS * EPS * size / shortest
    )


@pytest.mark.parametrize("name", MESHES)
@pytest.mark.parametrize("shape", ["interpolate", "limit"])
def test_kernels_give_the_reference_patches(name: str, shape: str) -> None:
    mesh = MESHES[name]()
    targets, frame = local_targets(mesh, shape)
    reference = split4_patches(targets, mesh.vertices, frame.centre, frame.scale, compiled=False)
    compiled = split4_patches(targets, mesh.vertices, frame.centre, frame.scale, compiled=True)
    assert_close(mesh, reference, compiled)
    np.testing.assert_array_equal(
        compiled[0].control[::4, 0, 0], mesh.vertices[mesh.topology.faces[:, 0]]
    )  # corners exact


def test_kernels_follow_a_guide_and_given_stars() -> None:
    """The guided path (a 7×7 macro net per face, as the CAD re-assembly passes) and given stars."""
    mesh = irregular(1)
    targets, _ = local_targets(mesh)
    rng = np.random.default_rng(5)
    guide = macro_nets(
        split4_patches(targets, targets.positions, np.zeros(3), 1.0, compiled=False)[0].control
    )
    guide += rng.normal(scale=1e-3, size=guide.shape)
    star = split4_star(targets)
    star = star._replace(factor=np.where(rng.random(len(star.factor)) < 0.1, 0.7, 1.0))
    reference = split4_patches(
        targets, targets.positions, np.zeros(3), 1.0, guide, star, compiled=False
    )
    compiled = split4_patches(
        targets, targets.positions, np.zeros(3), 1.0, guide, star, compiled=True
    )
    assert_close(mesh.with_vertices(targets.positions), reference, compiled)


def test_kernels_in_ranges_are_the_kernels_in_one(monkeypatch: pytest.MonkeyPatch) -> None:
    """Every pass writes its own items' points: many ranges on threads give the same bits."""
    mesh = irregular(1)
    targets, frame = local_targets(mesh)
    whole = split4_patches(targets, mesh.vertices, frame.centre, frame.scale, compiled=True)
    monkeypatch.setattr(kernels, "CHUNK_ITEMS", 7)
    monkeypatch.setattr(kernels, "workers", lambda: 5)
    ranged = split4_patches(targets, mesh.vertices, frame.centre, frame.scale, compiled=True)
    for a, b in zip(whole[:3], ranged[:3], strict=True):
        np.testing.assert_array_equal(getattr(a, "control", a), getattr(b, "control", b))


def test_the_default_is_numpy_below_the_threshold_and_kernels_above(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    mesh = irregular(0)
    targets, frame = local_targets(mesh)
    reference = split4_patches(targets, mesh.vertices, frame.centre, frame.scale, compiled=False)
    compiled = split4_patches(targets, mesh.vertices, frame.centre, frame.scale, compiled=True)
    assert not np.array_equal(
        reference[0].control, compiled[0].control
    )  # rounding tells the paths apart
    np.testing.assert_array_equal(
        split4_patches(targets, mesh.vertices, frame.centre, frame.scale)[0].control,
        reference[0].control,
    )
    monkeypatch.setattr(threshold, "KERNEL_FACES", mesh.topology.n_faces)
    monkeypatch.setattr(kernels, "kernels_cached", lambda: True)  # NumPy where it is not
    np.testing.assert_array_equal(
        split4_patches(targets, mesh.vertices, frame.centre, frame.scale)[0].control,
        compiled[0].control,
    )


@pytest.mark.parametrize("name", MESHES)
def test_the_line_walk_gives_the_shears_bit_for_bit(name: str) -> None:
    mesh = MESHES[name]()
    targets, _ = local_targets(mesh)
    topology = targets.topology
    ends = split4.edge_end_cosines(topology, split4_star(targets, compiled=False).cosine)
    reference = split4._chain_shears(topology, ends)
    np.testing.assert_array_equal(split4._chain_shears(topology, ends, compiled=True), reference)


@pytest.mark.parametrize("name", MESHES)
def test_the_star_kernel_gives_the_reference_stars(name: str) -> None:
    """The fit and the safeguard as NumPy's, to rounding (sums in another order); the same shrunk
    vertices. A shrunk star is tested on the fan whose tangents are made 3× too long at one
    vertex."""
    mesh = MESHES[name]()
    targets, _ = local_targets(mesh)
    long = targets.tangents.copy()
    long[targets.topology.neighbor_offsets[0] : targets.topology.neighbor_offsets[1]] *= 3.0
    for wanted in (
        targets,
        Targets(targets.topology, targets.positions, targets.normals, long, targets.interior),
    ):
        reference, compiled = (
            split4_star(wanted, compiled=False),
            split4_star(wanted, compiled=True),
        )
        np.testing.assert_array_equal(compiled.cosine, reference.cosine)
        np.testing.assert_array_equal(compiled.shrunk, reference.shrunk)
        np.testing.assert_array_equal(compiled.refitted, reference.refitted)
        np.testing.assert_allclose(compiled.factor, reference.factor, rtol=POINT_ULPS * EPS, atol=0)
        size = np.abs(reference.star).max()
        np.testing.assert_array_less(
            np.abs(compiled.star - reference.star), POINT_ULPS * EPS * size
        )
    assert split4_star(
        Targets(targets.topology, targets.positions, targets.normals, long, targets.interior),
        compiled=True,
    ).shrunk[0]


@pytest.mark.parametrize("name", MESHES)
def test_the_network_kernel_gives_the_reference_connectivity(name: str) -> None:
    mesh = MESHES[name]()
    targets, _ = local_targets(mesh)
    patches, extra, normals, _ = split4_patches(targets, targets.positions, np.zeros(3), 1.0)
    points, point_normals = (
        np.concatenate([targets.positions, extra]),
        np.concatenate([targets.normals, normals]),
    )
    reference = split4._split4_network(
        targets.topology, patches, points, point_normals, {}, compiled=False
    )
    compiled = split4._split4_network(
        targets.topology, patches, points, point_normals, {}, compiled=True
    )
    for field in (
        "corner_ids",
        "edge_ids",
        "edge_reversed",
        "neighbor",
        "neighbor_edge",
        "same_direction",
        "edge_collapsed",
    ):
        np.testing.assert_array_equal(getattr(compiled, field), getattr(reference, field))
