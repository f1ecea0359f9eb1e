"""Feature-adaptive refinement (issue 30, item 1): a Gregory limit network refined only where it
is off the exact Catmull–Clark limit, with hanging edges where finer patches meet coarser ones.

Measured independently of the refinement's own bookkeeping: the exact limit's samples (a cage
refined globally, its limit points) and OpenSubdiv's are projected onto the network from their
nearest patch sample, without the face each patch came from; G1 and gaps along hanging edges by
the check; watertightness by counting the triangles on every tessellation edge.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from ocp_marks import requires_ocp
from scipy.spatial import cKDTree

from g1patch.adaptive import EXACT
from g1patch.api import read
from g1patch.build import DEFAULT_TOLERANCE, build_network, semi_sharp_levels
from g1patch.compare import load_reference, reference_path
from g1patch.continuity import check
from g1patch.errors import FormatError, InputError
from g1patch.fidelity import project_to_network
from g1patch.io.network_file import load_network, save_network
from g1patch.mesh import QuadMesh
from g1patch.mesh.tags import Tag
from g1patch.network import HangingEdges, PatchNetwork
from g1patch.shapes import cube
from g1patch.subdivision import limit_points, refine, refine_grids
from g1patch.tessellate import tessellate

#: G1 and G0 bars of the design (§5), hanging edges included
EXACT_G1_DEG = 1e-9
#: the tolerance the generated cube is built to: two steps deep at its eight corners
CUBE_TOLERANCE = 3e-6


def distance_to(network: PatchNetwork, points: np.ndarray, starts: int = 4) -> np.ndarray:
    """Each point's distance to the network: Gauss–Newton (:func:`project_to_network`) from each
    of its ``starts`` nearest of 17 × 17 samples of every patch, the least; no knowledge of faces
    or levels."""
    n = 17
    t = np.linspace(0.0, 1.0, n)
    samples = network.patches.evaluate_grid(t, t).reshape(-1, 3)
    nearest = cKDTree(samples).query(points, k=starts)[1]
    patch, rest = np.divmod(nearest.reshape(-1), n * n)
    uv = np.stack([t[rest // n], t[rest % n]], axis=-1)
    repeated = np.repeat(points, starts, axis=0)
    return project_to_network(network, repeated, patch, uv).reshape(-1, starts).min(axis=1)


def exact_limit(cage: QuadMesh, levels: int = 3) -> np.ndarray:
    """The exact limit at the vertices of ``cage`` refined ``levels`` times."""
    return limit_points(refine_grids(cage, levels)[0])


def edge_counts(triangles: np.ndarray) -> np.ndarray:
    """How many triangles hold each undirected edge, counted by multiplicity."""
    edges = np.sort(
        np.concatenate([triangles[:, [0, 1]], triangles[:, [1, 2]], triangles[:, [2, 0]]]), 1
    )
    return np.unique(edges, axis=0, return_counts=True)[1]


def assert_near_opensubdiv_and_exact(network: PatchNetwork, path: Path, tolerance: float) -> None:
    """OpenSubdiv's limit points of the shared mesh ``path`` (Blender, float32: 7e-6 of the
    diagonal from the exact limit at most, test_fidelity) within ``tolerance`` of the network,
    which is exactly G1 (hanging edges included) and fold-free."""
    points = load_reference(reference_path(path)).points
    diagonal = network.bounding_box_diagonal()
    assert distance_to(network, points).max() / diagonal <= tolerance + 1e-5
    report = check(network)
    assert max(report.max_edge_angle_deg, report.max_corner_angle_deg) <= EXACT_G1_DEG
    assert report.folds == 0


@pytest.fixture(scope="module")
def cube_cage() -> QuadMesh:
    """A cube refined three times: 384 faces, eight valence-3 vertices far apart."""
    return refine(cube(), 3)


@pytest.fixture(scope="module")
def adaptive_cube(cube_cage: QuadMesh) -> PatchNetwork:
    uv = cube_cage.vertices[cube_cage.faces][..., :2] * 0.5 + 0.5
    return build_network(replace(cube_cage, uv=uv), "gregory", "limit", tolerance=CUBE_TOLERANCE)


def test_only_the_faces_that_are_off_are_refined(
    cube_cage: QuadMesh, adaptive_cube: PatchNetwork
) -> None:
    """Fewer patches than the global steps' (4^steps per face), and as close to the limit: the
    exact limit's samples lie within the tolerance of the adaptive network."""
    steps = int(adaptive_cube.provenance["tolerance_steps"])
    assert steps >= 2
    assert adaptive_cube.n_patches < cube_cage.n_faces * 4**steps / 2
    assert adaptive_cube.hanging is not None and len(adaptive_cube.hanging) > 0
    diagonal = adaptive_cube.bounding_box_diagonal()
    reached = float(adaptive_cube.provenance["limit_distance"])
    assert reached <= CUBE_TOLERANCE
    ours = distance_to(adaptive_cube, exact_limit(cube_cage)).max() / diagonal
    # the samples are a subset of the build's own (one level coarser): within what it reports
    assert ours <= reached * (1 + 1e-6) + 1e-12


def test_hanging_edges_join_exactly(adaptive_cube: PatchNetwork) -> None:
    """Every link (fine edge against the part of its coarse edge) is G0 and G1 to rounding, as
    every shared edge and corner."""
    report = check(adaptive_cube)
    assert report.hanging_edges == len(adaptive_cube.hanging)
    assert report.max_edge_angle_deg <= EXACT_G1_DEG
    assert report.max_corner_angle_deg <= EXACT_G1_DEG
    assert report.max_g0_gap <= 1e-14
    assert report.folds == 0 and report.open_edges == 0


def test_hanging_spans_are_dyadic_and_cover_each_coarse_edge(adaptive_cube: PatchNetwork) -> None:
    """Spans are fractions k / 2^l (exact in floating point) and the fine edges on a coarse edge
    tile it: their lengths sum to 1."""
    hanging = adaptive_cube.hanging
    assert hanging is not None
    scaled = hanging.span * 2**10
    assert np.array_equal(scaled, np.round(scaled))
    assert (hanging.span[:, 0] > hanging.span[:, 1]).all()  # the sides run opposite ways
    coarse = hanging.sides[:, 2] * 4 + hanging.sides[:, 3]
    covered = np.bincount(coarse, weights=hanging.span[:, 0] - hanging.span[:, 1])
    assert np.allclose(covered[np.unique(coarse)], 1.0, rtol=0, atol=1e-15)


@pytest.mark.parametrize("resolution", [2, 3, 5, 10, 17])
def test_the_tessellation_is_watertight_across_hanging_edges(
    adaptive_cube: PatchNetwork, resolution: int
) -> None:
    """On the closed cube every triangle edge has exactly two triangles, the surface is a sphere
    (V − E + F = 2) and consistently oriented; texture coordinates follow the triangles."""
    mesh = tessellate(adaptive_cube, resolution)
    counts = edge_counts(mesh.triangles)
    assert (counts == 2).all()
    assert len(mesh.points) - len(counts) + len(mesh.triangles) == 2
    corners = mesh.points[mesh.triangles]
    normal = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    assert (np.einsum("ij,ij->i", normal, corners.mean(axis=1)) > 0).all()
    assert mesh.uv_points is not None and mesh.uv_triangles is not None
    assert np.array_equal(mesh.uv_points[mesh.uv_triangles], mesh.triangles)


def test_the_network_file_keeps_the_hanging_edges(
    adaptive_cube: PatchNetwork, tmp_path: Path
) -> None:
    path = tmp_path / "adaptive.npz"
    save_network(path, adaptive_cube)
    back = load_network(path)
    assert back.hanging is not None and adaptive_cube.hanging is not None
    assert np.array_equal(back.hanging.sides, adaptive_cube.hanging.sides)
    assert np.array_equal(back.hanging.span, adaptive_cube.hanging.span)
    assert back.provenance["limit_distance"] == adaptive_cube.provenance["limit_distance"]
    assert check(back).max_edge_angle_deg <= EXACT_G1_DEG


def test_taking_patches_keeps_the_links_between_kept_ones(adaptive_cube: PatchNetwork) -> None:
    hanging = adaptive_cube.hanging
    assert hanging is not None
    keep = np.ones(adaptive_cube.n_patches, dtype=bool)
    keep[hanging.sides[0, 2]] = False  # a coarse patch: its links go, the rest stay
    part = adaptive_cube.take_patches(keep)
    gone = (hanging.sides[:, 2] == hanging.sides[0, 2]).sum()
    assert part.hanging is not None and len(part.hanging) == len(hanging) - gone
    assert check(part).max_edge_angle_deg <= EXACT_G1_DEG


@pytest.mark.parametrize(
    ("sides", "span", "message"),
    [
        ([[0, 0, 1, 2]], [[0.5, 1.5]], "two different fractions in"),
        ([[0, 0, 1, 2]], [[0.5, 0.5]], "two different fractions in"),
        ([[0, 4, 1, 2]], [[0.5, 0.0]], "edges are 0…3"),
        ([[0, 0, 1, 2]], [[0.5, 0.0], [1.0, 0.5]], "expected one of each per link"),
    ],
)
def test_hanging_edges_are_validated(sides: list, span: list, message: str) -> None:
    with pytest.raises(InputError, match=message):
        HangingEdges(np.array(sides), np.array(span))


def test_a_link_must_name_open_edges_of_the_network(adaptive_cube: PatchNetwork) -> None:
    hanging = adaptive_cube.hanging
    assert hanging is not None
    beyond = hanging.sides.copy()
    beyond[0, 2] = adaptive_cube.n_patches
    with pytest.raises(InputError, match="names patch"):
        replace(adaptive_cube, hanging=HangingEdges(beyond, hanging.span))
    patch = int(np.flatnonzero((adaptive_cube.neighbor >= 0).all(axis=1))[0])
    shared = hanging.sides.copy()
    shared[0, :2] = patch, 0
    with pytest.raises(InputError, match="already has a neighbour"):
        replace(adaptive_cube, hanging=HangingEdges(shared, hanging.span))


def test_hostile_hanging_members_are_refused(adaptive_cube: PatchNetwork, tmp_path: Path) -> None:
    """One member of the pair without the other, a patch out of range, a span out of [0, 1]: a
    FormatError naming the file and the problem, before a network is made."""
    path = tmp_path / "adaptive.npz"
    save_network(path, adaptive_cube)
    with np.load(path) as data:
        members = {name: data[name] for name in data.files}

    def rewritten(**changes: np.ndarray | None) -> Path:
        out = tmp_path / "hostile.npz"
        arrays = {**members, **changes}
        np.savez(out, **{k: v for k, v in arrays.items() if v is not None})
        return out

    with pytest.raises(FormatError, match="lacks hanging_span"):
        load_network(rewritten(hanging_span=None))
    sides = members["hanging_sides"].copy()
    sides[3, 0] = 10**6
    with pytest.raises(FormatError, match="hanging_sides"):
        load_network(rewritten(hanging_sides=sides))
    span = members["hanging_span"].copy()
    span[2, 1] = 1.5
    with pytest.raises(FormatError, match=r"hostile\.npz.*spans"):
        load_network(rewritten(hanging_span=span))
    span[2, 1] = np.nan
    with pytest.raises(FormatError, match="not a number"):
        load_network(rewritten(hanging_span=span))
    with pytest.raises(FormatError, match="hanging_span"):
        load_network(rewritten(hanging_span=members["hanging_span"][:-1]))


def test_a_cage_of_regular_faces_needs_no_refinement() -> None:
    """Every face of a torus of valence-4 vertices is the limit itself: nothing to refine."""
    from test_fidelity import torus_cage

    network = build_network(torus_cage(), "gregory", "limit", tolerance=1e-6)
    assert network.n_patches == torus_cage().n_faces
    assert network.hanging is None or len(network.hanging) == 0
    assert float(network.provenance["limit_distance"]) <= EXACT


@pytest.mark.parametrize(
    ("name", "tolerance"),
    [
        ("catmark_xord_interior", DEFAULT_TOLERANCE),
        ("catmark_xord_boundary", DEFAULT_TOLERANCE),
        pytest.param("catmark_xord_interior", 1e-4, marks=pytest.mark.slow),
        pytest.param("catmark_xord_boundary", 1e-4, marks=pytest.mark.slow),
    ],
)
def test_opensubdiv_agrees_on_the_adaptive_network(
    shared_data: Path, name: str, tolerance: float
) -> None:
    """OpenSubdiv's limit points (Blender, float32: 7e-6 of the diagonal from the exact limit at
    most, test_fidelity) lie within the tolerance of the adaptive network, which is exact G1 and
    smaller than the global refinement's."""
    path = shared_data / f"{name}.obj"
    cage = read(path)
    network = build_network(cage, "gregory", "limit", tolerance=tolerance)
    steps = int(network.provenance["tolerance_steps"])
    assert network.n_patches < cage.n_faces * 4**steps
    assert_near_opensubdiv_and_exact(network, path, tolerance)


@pytest.mark.parametrize(
    "name",
    [
        "catmark_torus_creases0",
        "catmark_tent_creases1",
        "catmark_cube_creases2",
        "catmark_dart_edgecorner",
    ],
)
def test_semi_sharp_creases_refine_locally(shared_data: Path, name: str) -> None:
    """OpenSubdiv's crease shapes (sharpness up to 4.7: five levels globally, 32,768 patches on
    the torus): refined around their semi-sharp features and where the network is off their
    limit only, OpenSubdiv's points (same tags) lie within the default tolerance, every edge but
    the infinitely sharp ones is exactly G1."""
    path = shared_data / f"{name}.obj"
    cage = read(path)
    network = build_network(cage, "gregory", "limit")
    everywhere = cage.n_faces * 4 ** semi_sharp_levels(cage)
    assert network.n_patches <= everywhere
    assert network.n_patches <= max(everywhere // 8, 20 * cage.n_faces)  # torus: 3,008 of 32,768
    assert_near_opensubdiv_and_exact(network, path, DEFAULT_TOLERANCE)


def test_a_box_of_semi_sharp_edges_refines_at_its_edges() -> None:
    """A coarse box whose twelve edges are semi-sharp (3.0): three levels globally (64 patches a
    face, 6,144); locally the three levels around the edges only (the faces touching a semi-sharp
    edge are refined until its sharpness is spent, whatever their distance: a partly resolved
    crease is within the tolerance but ripples in the zebra), the limit to rounding and exactly
    G1."""
    c = refine(cube(), 2)
    v = c.vertices / np.abs(c.vertices).max(axis=1, keepdims=True)
    on_edge = (np.abs(np.abs(v) - 1.0) < 1e-12).sum(axis=1) >= 2
    tags = [
        Tag("crease", (int(a), int(b)), (3.0,))
        for a, b in c.topology.edges
        if on_edge[[a, b]].all()
    ]
    cage = QuadMesh.from_arrays(v, c.faces, tags=tags)
    network = build_network(cage, "gregory", "limit")
    assert semi_sharp_levels(cage) == 3
    assert network.n_patches <= 0.6 * cage.n_faces * 4**3  # 3,264 of 6,144
    diagonal = network.bounding_box_diagonal()
    ours = distance_to(network, exact_limit(cage, 4)).max() / diagonal
    assert ours <= 1e-4  # 2.2e-5: the face centres' coarse patches, off by their corners' valence
    report = check(network)
    assert max(report.max_edge_angle_deg, report.max_corner_angle_deg) <= EXACT_G1_DEG
    assert report.folds == 0 and report.hanging_edges > 0


def test_cad_export_of_a_locally_refined_network_says_it_is_fitted(
    adaptive_cube: PatchNetwork, tmp_path: Path
) -> None:
    """split4 cannot re-assemble a network with hanging edges: asked for, it is refused before
    anything is written (naming the hanging edges and what to do instead)."""
    from g1patch.io.cad import export_cad

    target = tmp_path / "adaptive.step"
    with pytest.raises(InputError, match=r"refined locally \(\d+ hanging edges\).*--method split4"):
        export_cad(target, adaptive_cube, method="split4")
    assert not target.exists()


@requires_ocp
@pytest.mark.slow
def test_cad_export_of_a_locally_refined_network_is_a_sewn_solid(
    tmp_path: Path,
) -> None:
    """OpenCASCADE sews the T-junctions: one closed, valid solid, each face within the fit's
    tolerance of its patch, and the note says why it was fitted."""
    from g1patch.io.cad import export_cad

    network = build_network(refine(cube(), 2), "gregory", "limit", tolerance=3e-5)
    assert network.hanging is not None and len(network.hanging)
    result = export_cad(tmp_path / "adaptive.step", network)
    assert result.solid and result.valid and result.faces == network.n_patches
    assert "hanging edges" in result.method_note
    assert result.deviation <= 1e-5
