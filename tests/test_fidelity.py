"""The distance from a cage's exact Catmull–Clark limit to its network (issue 30, item 2): exact
samples projected onto the patches (:mod:`g1patch.fidelity`), checked against the limit computed
by OpenSubdiv inside Blender, and the build's tolerance loop and report around it."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scipy.spatial import cKDTree

from g1patch.api import read
from g1patch.build import DEFAULT_TOLERANCE, MAX_TOLERANCE_STEPS, build_network
from g1patch.cli import main
from g1patch.compare import load_reference, reference_path
from g1patch.errors import InputError
from g1patch.fidelity import _face_patches, _start, limit_distance, project_to_network
from g1patch.mesh import QuadMesh
from g1patch.network import PatchNetwork
from g1patch.subdivision import catmull_clark_cage, limit_points, refine, refine_grids

EPS = float(np.finfo(float).eps)
PER_FACE = {"gregory": 1, "split4": 4}


def torus_cage(n: int = 8, m: int = 6) -> QuadMesh:
    """A regular torus cage: every vertex of valence 4, so its limit is the bicubic B-spline."""
    i, j = np.meshgrid(np.arange(n), np.arange(m), indexing="ij")
    a, b = 2 * np.pi * i / n, 2 * np.pi * j / m
    points = np.stack(
        [(2 + 0.7 * np.cos(b)) * np.cos(a), (2 + 0.7 * np.cos(b)) * np.sin(a), 0.7 * np.sin(b)],
        axis=-1,
    ).reshape(-1, 3)
    index = (i * m + j).reshape(-1)
    faces = np.stack(
        [
            index,
            (((i + 1) % n) * m + j).reshape(-1),
            (((i + 1) % n) * m + (j + 1) % m).reshape(-1),
            (i * m + (j + 1) % m).reshape(-1),
        ],
        axis=1,
    )
    return QuadMesh.from_arrays(points, faces)


def cube_cage() -> QuadMesh:
    points = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], float)
    faces = [[0, 1, 3, 2], [4, 6, 7, 5], [0, 4, 5, 1], [2, 3, 7, 6], [0, 2, 6, 4], [1, 5, 7, 3]]
    return QuadMesh.from_arrays(points, np.array(faces))


def at_the_start(
    network: PatchNetwork, cage: QuadMesh, method: str, levels: int
) -> tuple[np.ndarray, np.ndarray]:
    """The network at the start (patch, parameter) of every exact sample of ``levels``, and the
    exact limit samples themselves, both (F (2^levels + 1)², 3) in the measure's order."""
    first = _face_patches(cage.n_faces, cage.features.holes, PER_FACE[method], network)
    fine, grid = refine_grids(cage, levels)
    m = grid.shape[1]
    t = np.linspace(0.0, 1.0, m)
    uv = np.tile(np.stack(np.meshgrid(t, t, indexing="ij"), -1).reshape(-1, 2), (cage.n_faces, 1))
    patch, local = _start(np.repeat(first, m * m), uv, PER_FACE[method])
    values = network.patches.take(patch).evaluate(local[:, None, :])[:, 0]
    return values, limit_points(fine)[grid.reshape(-1)]


@pytest.mark.parametrize("method", ["gregory", "split4"])
def test_the_bspline_network_of_a_regular_cage_is_at_distance_zero(method: str) -> None:
    """Every face regular: the network is the limit's bicubic B-spline, so every exact sample
    lies on it (rounding only) and the loop adds no step."""
    network = build_network(torus_cage(), method, "limit")
    assert float(network.provenance["limit_distance"]) <= 16 * EPS
    assert network.provenance["tolerance_steps"] == "0"


@pytest.mark.parametrize("method", ["gregory", "split4"])
def test_start_parameters_are_the_faces_own(method: str) -> None:
    """Before any projection step, a regular cage's network at the start (patch, parameter) of
    each sample is the exact limit there: the split4 quarters run the face's directions."""
    cage = torus_cage()
    network = build_network(cage, method, "limit", tolerance=None)
    values, exact = at_the_start(network, cage, method, 2)
    np.testing.assert_allclose(values, exact, rtol=0, atol=1e-14)


def test_projection_walks_across_patches_to_the_foot() -> None:
    """A point above a patch four faces away from where its projection starts still finds its
    foot: the distance is the height above the surface (a flat grid: the plane z = 0)."""
    x, y = np.meshgrid(np.arange(7.0), np.arange(7.0), indexing="ij")
    points = np.stack([x, y, np.zeros_like(x)], -1).reshape(-1, 3)
    index = np.arange(49).reshape(7, 7)
    faces = np.stack([index[:-1, :-1], index[1:, :-1], index[1:, 1:], index[:-1, 1:]], -1).reshape(
        -1, 4
    )
    network = build_network(QuadMesh.from_arrays(points, faces), "gregory", "limit", tolerance=None)
    target = np.array([[4.3, 3.6, 0.25]])
    distance = project_to_network(network, target, np.array([0]), np.array([[0.5, 0.5]]))
    np.testing.assert_allclose(distance, [0.25], rtol=1e-12)


@pytest.mark.parametrize("name", ["catmark_xord_interior", "catmark_xord_boundary", "catmark_cube"])
def test_the_measure_agrees_with_opensubdiv(shared_data: Path, name: str) -> None:
    """OpenSubdiv's limit points (Blender, float32) projected onto the network the same way give
    the same largest distance as the exact samples, within the reference's own precision: the
    samples are the Catmull–Clark limit, and the projection finds the feet."""
    path = shared_data / f"{name}.obj"
    cage = read(path)
    network = build_network(cage, "gregory", "limit", tolerance=None)
    reference = load_reference(reference_path(path))
    levels = reference.levels
    ours = limit_distance(network, cage, 1, levels=levels)
    fine, grid = refine_grids(cage, levels)
    samples = limit_points(fine)[grid.reshape(-1)]
    gap, nearest = cKDTree(samples).query(reference.points)
    diagonal = network.bounding_box_diagonal()
    # the reference's points are our samples: 7e-6 of the diagonal apart at most (float32 storage
    # and Blender's evaluator), 1e-9 or less at most of them
    assert gap.max() / diagonal <= 1e-5 and np.median(gap) / diagonal <= 1e-7
    m = grid.shape[1]
    face, rest = np.divmod(nearest, m * m)
    t = np.linspace(0.0, 1.0, m)
    uv = np.stack([t[rest // m], t[rest % m]], -1)
    theirs = project_to_network(network, reference.points, face, uv).max() / diagonal
    assert ours.relative == pytest.approx(theirs, abs=1e-5)
    assert ours.levels == levels and ours.samples == cage.n_faces * m * m


def test_limit_on_a_cage_with_holes(tmp_path: Path) -> None:
    """Hole faces get no patch and no sample: their per-face figure is NaN, the rest are
    measured."""
    text = ["v {} {} {}".format(*p) for p in torus_cage().vertices]
    text += ["f " + " ".join(str(v + 1) for v in f) for f in torus_cage().faces]
    text += ["t hole 2/0/0 0 7"]  # diagonal neighbours: they share vertex 7 only
    path = tmp_path / "holes.obj"
    path.write_text("\n".join(text) + "\n")
    cage = read(path)
    for method in PER_FACE:
        network = build_network(cage, method, "limit", tolerance=None)
        result = limit_distance(network, cage, PER_FACE[method], levels=2)
        assert np.isnan(result.per_face[[0, 7]]).all()
        assert np.isfinite(np.delete(result.per_face, [0, 7])).all()
        assert result.relative <= 1e-12


@pytest.mark.parametrize("method", ["gregory", "split4"])
def test_the_build_refines_until_the_tolerance_holds(shared_data: Path, method: str) -> None:
    """catmark_xord_boundary is 2.7e-3 (gregory) / 3.5e-3 (split4) of the diagonal off at one
    patch (or one 2×2 split) per face; the build adds Catmull–Clark steps until it is within the
    default 1e-3, and a network of the refined cage is as exactly G1."""
    from g1patch.continuity import check

    cage = read(shared_data / "catmark_xord_boundary.obj")
    once = build_network(cage, method, "limit", tolerance=None)
    first = limit_distance(once, catmull_clark_cage(cage), PER_FACE[method])
    assert first.relative > DEFAULT_TOLERANCE
    network = build_network(cage, method, "limit")
    reached = float(network.provenance["limit_distance"])
    steps = int(network.provenance["tolerance_steps"])
    assert reached <= DEFAULT_TOLERANCE and steps >= 1
    if method == "split4":  # refined globally: the network of the refined cage
        assert network.n_patches == cage.n_faces * PER_FACE[method] * 4**steps
        finer = refine(cage, steps)
        assert limit_distance(network, finer, PER_FACE[method]).relative == pytest.approx(reached)
    else:  # refined where it is off only (test_adaptive measures it)
        assert network.n_patches < cage.n_faces * 4**steps
    report = check(network)
    assert max(report.max_edge_angle_deg, report.max_corner_angle_deg) <= 1e-9
    assert report.folds == 0


@pytest.mark.slow
@pytest.mark.parametrize("method", ["gregory", "split4"])
@pytest.mark.parametrize("name", ["catmark_xord_interior", "catmark_xord_boundary"])
def test_a_tight_tolerance_holds_on_the_shared_cages(
    shared_data: Path, name: str, method: str
) -> None:
    """``--tolerance 1e-4`` on OpenSubdiv's extraordinary-vertex cages: the distance roughly halves
    a step (it is largest at the extraordinary vertices), so it takes 4–6 steps; the build gets
    there within its step limit and memory budget, and (split4, refined globally) its figure is
    the measure's on the refined cage."""
    cage = read(shared_data / f"{name}.obj")
    network = build_network(cage, method, "limit", tolerance=1e-4)
    assert "tolerance_stop" not in network.provenance
    reached = float(network.provenance["limit_distance"])
    assert reached <= 1e-4
    steps = int(network.provenance["tolerance_steps"])
    assert 1 <= steps <= MAX_TOLERANCE_STEPS
    if method == "split4":  # gregory refines locally: test_adaptive measures it
        finer = refine(catmull_clark_cage(cage), steps)
        assert limit_distance(network, finer, PER_FACE[method]).relative == pytest.approx(reached)


def test_limit_interpolate_stays_through_the_vertices_when_refined() -> None:
    """limit-interpolate refines its solved cage, not the mesh: the finer network still passes
    through every original vertex exactly and is within the tolerance of the solved cage's
    limit."""
    mesh = refine(cube_cage(), 1)  # a cube's own cage is singular for the solve
    network = build_network(mesh, "gregory", "limit-interpolate", tolerance=2e-4)
    assert int(network.provenance["tolerance_steps"]) >= 1
    assert float(network.provenance["limit_distance"]) <= 2e-4
    assert network.provenance["shape"] == "limit-interpolate"
    assert network.vertices is not None
    np.testing.assert_array_equal(network.vertices[: mesh.n_vertices], mesh.vertices)


@pytest.mark.parametrize("bad", [0, 1, -1e-3, 2.0, float("nan"), True, "1e-3"])
def test_tolerance_must_be_a_fraction(bad: object) -> None:
    with pytest.raises(InputError, match="tolerance"):
        build_network(cube_cage(), "gregory", "limit", tolerance=bad)  # type: ignore[arg-type]


def test_interpolate_is_not_measured() -> None:
    network = build_network(cube_cage(), "gregory", "interpolate")
    assert "limit_distance" not in network.provenance


def test_cli_prints_the_distance_and_fails_when_the_budget_stops_it(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], shared_data: Path
) -> None:
    """The build says the distance reached; where the memory budget stops the refinement first
    it writes the network, warns with the figure and exits 1; `check` reports the figure."""
    source = shared_data / "catmark_xord_boundary.obj"
    output = tmp_path / "x.npz"
    assert main(["build", str(source), "-o", str(output), "--shape", "limit", "-q"]) == 0
    out = capsys.readouterr().out
    assert "distance to the Catmull–Clark limit:" in out and "(tolerance 0.001;" in out
    code = main(
        [
            "build",
            str(source),
            "-o",
            str(output),
            "--shape",
            "limit",
            "--tolerance",
            "1e-5",
            "--max-memory",
            "1M",
            "-q",
        ]
    )
    captured = capsys.readouterr()
    assert code == 1 and output.exists()
    assert "above the tolerance 1e-05" in captured.err and "--max-memory" in captured.err
    assert main(["check", str(output)]) == 0
    assert "distance to limit (of diag)" in capsys.readouterr().out
    assert main(["build", str(source), "-o", str(output), "--tolerance", "0", "-q"]) == 2


@pytest.mark.parametrize("method", ["gregory", "split4"])
def test_the_measure_never_exceeds_the_start(method: str) -> None:
    """Every figure is a distance to a point on the network no farther than the one at the same
    face parameter (the projection keeps the nearest point it visits), on a cage whose
    parameterisation differs most from the limit's: a valence-12 vertex on a pyramid-like cage."""
    n = 12
    angles = 2 * np.pi * np.arange(2 * n) / (2 * n)
    radius = np.where(np.arange(2 * n) % 2 == 0, 1.0, 1.6)
    ring = np.stack([radius * np.cos(angles), radius * np.sin(angles), np.zeros(2 * n)], 1)
    points = np.concatenate([[[0.0, 0.0, 0.8]], ring])
    i = np.arange(n)
    faces = np.stack([np.zeros(n, int), 1 + 2 * i, 2 + 2 * i, 1 + (2 * i + 2) % (2 * n)], 1)
    cage = QuadMesh.from_arrays(points, faces)
    network = build_network(cage, method, "limit", tolerance=None)
    ours = limit_distance(network, cage, PER_FACE[method], levels=3)
    start, exact = at_the_start(network, cage, method, 3)
    gap = np.linalg.norm(start - exact, axis=1)
    per_face = gap.reshape(cage.n_faces, -1).max(axis=1)
    assert (ours.per_face <= per_face * (1 + 1e-12)).all()
    assert ours.max < per_face.max()  # and the feet are nearer than the start


def test_the_distance_on_some_faces_is_theirs_of_the_whole() -> None:
    """``only`` measures the chosen faces alone: NaN elsewhere, their figures unchanged (the
    adaptive refinement measures a level's own faces this way)."""
    cage = refine(cube_cage(), 1)
    network = build_network(cage, "gregory", "limit", tolerance=None)
    whole = limit_distance(network, cage, 1, levels=2)
    only = np.zeros(cage.n_faces, dtype=bool)
    only[::3] = True
    part = limit_distance(network, cage, 1, levels=2, only=only)
    assert np.isnan(part.per_face[~only]).all()
    np.testing.assert_array_equal(part.per_face[only], whole.per_face[only])
    assert part.samples == only.sum() * 5 * 5
