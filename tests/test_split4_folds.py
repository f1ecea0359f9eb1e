"""split4 without folds where the mesh itself does not fold (g1patch.construct.split4).

The free parameters of the 2×2 split (seam tangents at edge midpoints, the centre, the star's
length) are chosen from each face's own extent, so thin wedges (a flat disk around a vertex of
valence up to 360), 1 : 4 neighbouring edges (box cages) and flat faces meeting at sharp rims
(thin slab) give regular sub-patches: no folds, and still exactly G1.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pytest
from exactness import INTERPOLATING, assert_exact_g1

from g1patch import shapes
from g1patch.build import build_split4_network
from g1patch.construct.split4 import STAR_LENGTH_LIMIT, split4_star
from g1patch.continuity import check
from g1patch.mesh import QuadMesh
from g1patch.targets import shape_targets
from g1patch.targets.interpolate import slot_vertices

FAN_VALENCES = [3, 4, 5, 6, 8, 12, 16, 32, 64, 128, 360]

CAGES: dict[str, Callable[[], QuadMesh]] = {
    "box_cage": lambda: shapes.box_cage(),
    "box_cage_jitter1": lambda: shapes.box_cage(jitter_seed=1),
    "box_cage_jitter2": lambda: shapes.box_cage(jitter_seed=2),
    "box_cage_jitter3": lambda: shapes.box_cage(jitter_seed=3),
    "thin_slab": lambda: shapes.thin_slab(),
    "noisy_sphere1_seed0": lambda: shapes.noisy_sphere(1, 0.08, 0),
    "noisy_sphere1_seed1": lambda: shapes.noisy_sphere(1, 0.08, 1),
    "noisy_sphere2_seed0": lambda: shapes.noisy_sphere(2, 0.08, 0),
    "noisy_sphere2_seed1": lambda: shapes.noisy_sphere(2, 0.08, 1),
}


@pytest.mark.parametrize("shape", INTERPOLATING)
@pytest.mark.parametrize("valence", FAN_VALENCES)
def test_flat_fans_do_not_fold(valence: int, shape: str) -> None:
    """A flat disk of n kites around one vertex (1° wedges at n = 360): flat, unfolded, exact."""
    mesh = shapes.flat_fan(valence)
    network = build_split4_network(mesh, shape=shape)  # type: ignore[arg-type]
    report = check(network)
    assert report.folds == 0, report.fold_locations
    assert_exact_g1(report)
    # the disk is planar: every control point stays in z = 0, and the normals all point one way
    assert np.abs(network.patches.world_control()[..., 2]).max() <= 1e-12
    assert report.turn_max_deg <= 1e-6


@pytest.mark.parametrize("shape", INTERPOLATING)
@pytest.mark.parametrize("name", sorted(CAGES))
def test_cages_do_not_fold(name: str, shape: str) -> None:
    report = check(build_split4_network(CAGES[name](), shape=shape))  # type: ignore[arg-type]
    assert report.folds == 0, report.fold_locations
    assert_exact_g1(report)


@pytest.mark.parametrize("shape", INTERPOLATING)
@pytest.mark.parametrize("name", ["box_cage", "thin_slab", "noisy_sphere1_seed0"])
def test_star_length_safeguard(name: str, shape: str) -> None:
    """No star tangent is longer than STAR_LENGTH_LIMIT × its target nor × the circle-aware length
    of its edge; shrinking is uniform per vertex (the star stays regular), and only refits count as
    fallbacks."""
    mesh = CAGES[name]()
    low, high = (
        mesh.vertices.min(axis=0),
        mesh.vertices.max(axis=0),
    )  # the build's working coordinates
    local = (mesh.vertices - 0.5 * (low + high)) / np.linalg.norm(high - low)
    targets = shape_targets(mesh.with_vertices(local), shape)  # type: ignore[arg-type]
    stars = split4_star(targets)
    topology = targets.topology
    slot_vertex = slot_vertices(topology)
    length = np.linalg.norm(stars.star, axis=1)
    edge = targets.positions[topology.neighbors] - targets.positions[slot_vertex]
    normal = targets.normals[slot_vertex]
    chord = np.linalg.norm(edge, axis=1)
    arc = (
        2.0
        * chord**2
        / (chord + np.linalg.norm(edge - np.sum(edge * normal, axis=1)[:, None] * normal, axis=1))
    )
    wanted = np.linalg.norm(targets.tangents, axis=1)
    fine = ~stars.refitted[slot_vertex]
    assert (length[fine] <= STAR_LENGTH_LIMIT * wanted[fine] * (1 + 1e-12)).all()
    assert (length <= STAR_LENGTH_LIMIT * arc * (1 + 1e-12)).all()
    assert ((stars.factor < 1.0) == stars.shrunk).all() and (stars.factor > 0).all()
    network = build_split4_network(mesh, shape=shape)  # type: ignore[arg-type]
    provenance = network.provenance
    assert int(provenance["star_safeguard_vertices"]) == int(stars.shrunk.sum())
    assert int(provenance["fallback_vertices"]) == int((targets.fallback | stars.refitted).sum())


def test_box_cage_safeguard_is_not_a_fallback() -> None:
    """The 1 : 4 box shrinks nearly every star (its regular stars cannot follow 1 : 4 edges), but
    no fan needed a fallback: the two counts are separate provenance keys."""
    network = build_split4_network(shapes.box_cage())
    assert int(network.provenance["star_safeguard_vertices"]) > 100
    assert network.provenance["fallback_vertices"] == "0"
    flat = build_split4_network(shapes.flat_fan(8)).provenance
    assert flat["star_safeguard_vertices"] == "0" and flat["fallback_vertices"] == "0"


@pytest.mark.parametrize("valence", [16, 360])
def test_seams_stay_inside_thin_wedges(valence: int) -> None:
    """On the flat fan every sub-patch control point lies in its own kite's angular wedge (up to
    rounding): the seam tangents at the midpoints are sized from the face's width, not the edge
    length."""
    mesh = shapes.flat_fan(valence)
    control = build_split4_network(mesh).patches.world_control().reshape(valence, -1, 3)
    angle = np.arctan2(control[..., 1], control[..., 0])
    start = 2.0 * np.pi * np.arange(valence) / valence
    offset = np.mod(angle - start[:, None] + 1e-12, 2.0 * np.pi) - 1e-12
    radius = np.linalg.norm(control[..., :2], axis=-1)
    inside = (offset <= 2.0 * np.pi / valence + 1e-9) | (radius < 1e-12)
    assert inside.all()


def lattice_box(xs: list[float], ys: list[float], zs: list[float]) -> QuadMesh:
    """The closed quad surface of the box lattice over the coordinates (unequal spacings allowed),
    faces turned outwards."""
    axes = [np.asarray(a, dtype=float) for a in (xs, ys, zs)]
    counts = [len(a) - 1 for a in axes]
    index: dict[tuple[int, ...], int] = {}
    vertices: list[tuple[float, ...]] = []
    faces: list[list[int]] = []

    def vertex(c: tuple[int, ...]) -> int:
        if c not in index:
            index[c] = len(vertices)
            vertices.append(tuple(float(axes[d][c[d]]) for d in range(3)))
        return index[c]

    for fixed in range(3):
        a_axis, b_axis = (d for d in range(3) if d != fixed)
        for end in (0, counts[fixed]):
            for a in range(counts[a_axis]):
                for b in range(counts[b_axis]):
                    corners = []
                    for da, db in ((0, 0), (1, 0), (1, 1), (0, 1)):
                        c = [0, 0, 0]
                        c[fixed], c[a_axis], c[b_axis] = end, a + da, b + db
                        corners.append(vertex(tuple(c)))
                    p = np.array([vertices[i] for i in corners])
                    outward = np.zeros(3)
                    outward[fixed] = 1.0 if end else -1.0
                    if np.cross(p[1] - p[0], p[2] - p[0]) @ outward < 0:
                        corners.reverse()
                    faces.append(corners)
    return QuadMesh.from_arrays(np.array(vertices), np.array(faces))


def support_box() -> QuadMesh:
    """A hard-surface box with support loops 4 % from every edge (edges 1 : 23)."""
    g = np.array([0.0, 0.04, 0.96, 1.0])
    return lattice_box(list(2.0 * g), list(1.4 * g), list(g))


def test_support_loops_do_not_fold_split4() -> None:
    """Support loops 4 % from a box's edges (faces 1 : 23 side by side): the midpoint star makes
    both seams' cross parts equal; without the length safeguard that was the mean of the two,
    12 × the narrow face's own, and 120 of 216 sub-patches folded."""
    network = build_split4_network(support_box())
    report = check(network)
    assert report.is_g1() and report.folds == 0
