"""split4 reproduces targets that already meet its G1 conditions (g1patch.construct.split4, DESIGN
§1).

On an all-regular closed cage the Catmull–Clark limit is the uniform bicubic B-spline, and its
limit targets are that B-spline's Bézier data; every grid line is closed, so μ = 0 and the split's
G1 conditions are the C1 conditions the B-spline meets. ``build_network(mesh, "split4", "limit")``
must then be that B-spline, each quad subdivided at ½: the reference here is computed from the
cage alone (each face's 4 × 4 control ring, walked on the half-edges, times the uniform
B-spline → Bézier matrix, then de Casteljau at ½), independent of the targets and the assembly.
Measured: ≤ 4e-16 of the bounding-box diagonal on torus(8, 4), torus(12, 6), a noisy grid torus,
large_torus(20 000) and catmark_torus.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from exactness import assert_exact_g1
from test_subdivision import grid_torus

from g1patch import shapes
from g1patch.build import build_network
from g1patch.construct.split4 import macro_nets
from g1patch.continuity import check
from g1patch.io.meshfile import read_mesh
from g1patch.mesh import QuadMesh, QuadTopology
from g1patch.network import PatchNetwork

#: uniform cubic B-spline control points → Bézier points of one span
B_TO_BEZIER = np.array([[1.0, 4, 1, 0], [0, 4, 2, 0], [0, 2, 4, 0], [0, 1, 4, 1]]) / 6.0
#: the issue's bound, relative to the bounding-box diagonal
REPRODUCTION_RTOL = 1e-12


def control_rings(topology: QuadTopology, faces: np.ndarray | None = None) -> np.ndarray:
    """(F, 4, 4) cage vertices of the control ring of each of ``faces`` (default all), ``ring[f, i,
    j]``: i along edge 0, the face's own corners at (1, 1), (2, 1), (2, 2), (1, 2). Needs valence-4
    interior corners."""
    faces = np.arange(topology.n_faces) if faces is None else np.asarray(faces)
    ring = np.full((len(faces), 4, 4), -1, dtype=np.int64)
    rows = np.arange(len(faces))
    for k in range(4):
        h = 4 * faces + k  # V_k → V_{k+1}
        out = QuadTopology.next(topology.twin[h])  # V_k → the point outside V_k across edge k
        along = QuadTopology.next(out)  # → the point outside V_{k+1}
        diagonal = QuadTopology.next(
            QuadTopology.next(topology.twin[out])
        )  # → the diagonal point at V_k
        points = {
            (1, 1): topology.origin(h),
            (1, 0): topology.target(out),
            (2, 0): topology.target(along),
            (0, 0): topology.target(diagonal),
        }
        for (i, j), vertex in points.items():
            for _ in range(k):  # a quarter turn about the ring's centre per corner
                i, j = 3 - j, i
            ring[rows, i, j] = vertex
    assert (ring >= 0).all()
    return ring


def halved(nets: np.ndarray) -> np.ndarray:
    """(F, 4, 4, 3) Bézier nets subdivided at ½ in u and v by de Casteljau: (F, 7, 7, 3) macro
    nets."""

    def along(c: np.ndarray, axis: int) -> np.ndarray:
        c = np.moveaxis(c, axis, 1)
        p0, p1, p2, p3 = c[:, 0], c[:, 1], c[:, 2], c[:, 3]
        a, b, d = 0.5 * (p0 + p1), 0.5 * (p1 + p2), 0.5 * (p2 + p3)
        e, f = 0.5 * (a + b), 0.5 * (b + d)
        return np.moveaxis(np.stack([p0, a, e, 0.5 * (e + f), f, d, p3], axis=1), 1, axis)

    return along(along(nets, 1), 2)


def bspline_macro_nets(mesh: QuadMesh, faces: np.ndarray | None = None) -> np.ndarray:
    """The uniform bicubic B-spline of the cage on each of ``faces`` (default all), subdivided at ½:
    (F, 7, 7, 3)."""
    control = mesh.vertices[control_rings(mesh.topology, faces)]
    return halved(np.einsum("ai,fijd,bj->fabd", B_TO_BEZIER, control, B_TO_BEZIER))


def reproduction_error(mesh: QuadMesh, network: PatchNetwork) -> float:
    """max |split4 control − B-spline control| / bounding-box diagonal."""
    diagonal = float(np.linalg.norm(mesh.vertices.max(axis=0) - mesh.vertices.min(axis=0)))
    return (
        float(np.abs(macro_nets(network.patches.world_control()) - bspline_macro_nets(mesh)).max())
        / diagonal
    )


REGULAR = {
    "torus_8_4": lambda: shapes.torus(8, 4),
    "torus_12_6": lambda: shapes.torus(12, 6, r=0.4),
    "grid_torus_noisy": lambda: grid_torus(noise=0.05),
    "large_torus": lambda: shapes.large_torus(20_000),
}


def test_reference_is_the_gregory_limit_network() -> None:
    """The independent reference agrees with the (already exact) Gregory limit network, and ≠ the
    plain split4 of the same cage under the interpolating rule."""
    mesh = shapes.torus(8, 4)
    s = np.linspace(0.0, 1.0, 4)
    gregory = build_network(mesh, "gregory", "limit", tolerance=None).patches.evaluate_grid(s, s)
    from g1patch.patches import PatchSet

    control = mesh.vertices[control_rings(mesh.topology)]
    bezier = PatchSet(np.einsum("ai,fijd,bj->fabd", B_TO_BEZIER, control, B_TO_BEZIER))
    np.testing.assert_allclose(bezier.evaluate_grid(s, s), gregory, rtol=0, atol=1e-14)
    assert reproduction_error(mesh, build_network(mesh, "split4", "interpolate")) > 1e-4


@pytest.mark.parametrize("name", sorted(REGULAR))
def test_regular_closed_cages_give_the_bspline(name: str) -> None:
    mesh = REGULAR[name]()
    network = build_network(mesh, "split4", "limit", tolerance=None)
    assert reproduction_error(mesh, network) <= REPRODUCTION_RTOL
    assert (
        network.provenance["star_safeguard_vertices"] == "0"
        and network.provenance["fallback_vertices"] == "0"
    )
    if (
        mesh.n_faces <= 1000
    ):  # the check of 80 000 sub-patches takes half a minute; the B-spline is G1 (C2) anyway
        assert_exact_g1(check(network))


def test_catmark_torus_gives_the_bspline(shared_data: Path) -> None:
    mesh = read_mesh(shared_data / "catmark_torus.obj")
    network = build_network(mesh, "split4", "limit", tolerance=None)
    assert reproduction_error(mesh, network) <= REPRODUCTION_RTOL
    assert_exact_g1(check(network))


def test_kept_midpoints_report_the_surface_normal() -> None:
    """Where the targets' seam tangents are kept, the network's normal at M is ``t_L × t_X``: the
    patches' own normal at every corner (mesh vertices, midpoints, centres)."""
    for mesh, shape in ((shapes.torus(8, 4), "limit"), (shapes.flat_fan(16), "interpolate")):
        network = build_network(mesh, "split4", shape, tolerance=None)  # type: ignore[arg-type]
        uv = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
        normal = np.cross(network.patches.evaluate(uv, 1, 0), network.patches.evaluate(uv, 0, 1))
        normal /= np.linalg.norm(normal, axis=-1, keepdims=True)
        assert network.vertex_normals is not None
        agreement = np.einsum("pkd,pkd->pk", normal, network.vertex_normals[network.corner_ids])
        assert agreement.min() >= 1.0 - 1e-12


def test_faces_on_closed_lines_of_an_irregular_cage_give_the_bspline() -> None:
    """A diagonal collapse on a torus makes valence 3, 3 and 6: the grid lines through them open,
    and their shear μ ≠ 0 (the extraordinary vertices' G1 needs it) moves those edges off the
    targets. Every face away from them — a regular two-ring, μ = 0 on its four edges — is still
    the B-spline exactly (41 of 95 here; the others are ~1e-2 off), and the whole is exactly G1."""
    from test_split4 import collapsed

    from g1patch.construct.split4 import _chain_shears

    mesh = collapsed(shapes.torus(12, 8), [0])
    assert mesh is not None
    topology = mesh.topology
    network = build_network(mesh, "split4", "limit", tolerance=None)
    assert_exact_g1(check(network))
    regular = topology.face_count == 4
    around = regular[topology.faces].all(axis=1)  # faces with four regular corners ...
    at_vertex = np.zeros(topology.n_vertices, dtype=bool)
    np.logical_or.at(at_vertex, topology.faces, ~around[:, None])
    calm = ~at_vertex[topology.faces].any(axis=1)  # ... whose corners' faces all have four too
    h = topology.edge_halfedges[:, 0]
    cosine = np.where(regular, 0.0, np.cos(2.0 * np.pi / topology.face_count))
    mu = _chain_shears(topology, cosine[np.stack([topology.origin(h), topology.target(h)], axis=1)])
    unsheared = (mu[topology.halfedge_edge] == 0.0).reshape(-1, 4).all(axis=1)
    faces = np.flatnonzero(calm & unsheared)
    assert 30 <= len(faces) < topology.n_faces
    diagonal = float(np.linalg.norm(mesh.vertices.max(axis=0) - mesh.vertices.min(axis=0)))
    error = np.abs(
        macro_nets(network.patches.world_control())[faces] - bspline_macro_nets(mesh, faces)
    ).max()
    assert error <= REPRODUCTION_RTOL * diagonal


# ------------------------------------------------------------------------------ CAD export

from ocp_marks import requires_ocp  # noqa: E402

CUBE = Path(__file__).parents[1] / "src" / "g1patch" / "data" / "cube.obj"


def quad_order(model: object, network: PatchNetwork, n_quads: int) -> list[int]:
    """For each quad the read face whose middle (u, v) = (½, ½) is the quad's centre point."""
    from scipy.spatial import cKDTree

    middles = np.concatenate([face.evaluate(np.array([[0.5, 0.5]])) for face in model.faces])  # type: ignore[attr-defined]
    centres = network.patches.evaluate(np.array([[1.0, 1.0]]))[
        ::4, 0
    ]  # corner 2 of sub-patch 4f: C
    distance, order = cKDTree(middles).query(centres)
    assert (
        distance.max() <= 1e-9 * network.bounding_box_diagonal()
        and len(set(order.tolist())) == n_quads
    )
    return order.tolist()


def read_back(
    path: Path, mesh: QuadMesh, network: PatchNetwork, samples: int = 9
) -> tuple[list[tuple[int, int]], float, float]:
    """Per quad its read face's pole-grid size; the read surfaces' largest distance from the
    sub-patches (relative to the diagonal); the largest angle between the read faces' OCC normals
    across the mesh edges (degrees)."""
    from g1patch.continuity import angle_between
    from g1patch.io.cad import read_step_faces
    from g1patch.network import edge_parameters

    topology = mesh.topology
    model = read_step_faces(path)
    assert len(model.faces) == topology.n_faces
    faces = [model.faces[i] for i in quad_order(model, network, topology.n_faces)]
    assert all(face.bounds == (0.0, 1.0, 0.0, 1.0) for face in faces)
    s = np.linspace(0.0, 1.0, 5)
    uv = np.stack(np.meshgrid(s, s, indexing="ij"), axis=-1).reshape(-1, 2)
    corner = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    distance = 0.0
    for f, face in enumerate(faces):
        for k in range(4):
            expected = network.patches.take([4 * f + k]).evaluate(uv)[0]
            distance = max(
                distance,
                float(
                    np.linalg.norm(face.evaluate(0.5 * (uv + corner[k])) - expected, axis=1).max()
                ),
            )
    t = np.linspace(0.0, 1.0, samples)
    angle = 0.0
    for h in topology.edge_halfedges[~topology.is_boundary_edge, 0].tolist():
        twin = int(topology.twin[h])
        a = faces[h >> 2].normals(edge_parameters(np.full(samples, h & 3), t))
        b = faces[twin >> 2].normals(edge_parameters(np.full(samples, twin & 3), 1.0 - t))
        angle = max(angle, float(angle_between(a, b).max()))
    return (
        [face.poles().shape[:2] for face in faces],
        distance / network.bounding_box_diagonal(),
        angle,
    )


@requires_ocp
@pytest.mark.parametrize("name", ["torus_8_4", "cube", "collapsed_torus"])
def test_limit_split4_step_is_one_face_per_quad(name: str, tmp_path: Path) -> None:
    """A valid solid, one face per quad named after it, single-span where the quad is one bicubic,
    the surface itself to the file's decimals, and OCC's own normals agree across every mesh
    edge."""
    from test_split4 import collapsed

    from g1patch.io.cad import export_step, split4_quad_faces

    mesh = {
        "torus_8_4": lambda: shapes.torus(8, 4),
        "cube": lambda: read_mesh(CUBE),
        "collapsed_torus": lambda: collapsed(shapes.torus(12, 8), [0]),
    }[name]()
    assert mesh is not None
    network = build_network(mesh, "split4", "limit", tolerance=None)
    quads = split4_quad_faces(network)
    assert quads is not None
    result = export_step(tmp_path / f"{name}.step", network)
    assert (
        result.faces == mesh.n_faces
        and result.exact
        and result.solid
        and result.valid
        and result.free_edges == 0
    )
    assert result.max_g1_angle_deg <= 1e-7
    text = (tmp_path / f"{name}.step").read_text()
    assert text.count("ADVANCED_FACE(") == mesh.n_faces
    assert all(f"ADVANCED_FACE('face {f}'" in text for f in range(mesh.n_faces))
    sizes, distance, angle = read_back(result.path, mesh, network)
    assert sizes == [(4, 4) if one else (6, 6) for one in quads.single]
    assert distance <= 1e-11 and angle <= 1e-7
    single = int(quads.single.sum())
    if name == "torus_8_4":
        assert (
            single == mesh.n_faces and result.spans == 1
        )  # all regular: every quad is the B-spline's span
    elif name == "cube":
        assert single == 0 and result.spans == 2  # no regular face: two spans each, never dozens
    else:
        assert 0 < single < mesh.n_faces and result.spans == 2


@requires_ocp
def test_limit_split4_cube_file_is_a_tenth_of_the_gregory_one(tmp_path: Path) -> None:
    """The issue's size bar: split4 limit cube ≤ 1/10 of the Gregory cube's fitted (22 spans)."""
    from g1patch.io.cad import export_step

    mesh = read_mesh(CUBE)
    split4 = export_step(
        tmp_path / "split4.step", build_network(mesh, "split4", "limit", tolerance=None)
    )
    gregory = export_step(tmp_path / "gregory.step", build_network(mesh, "gregory"), method="fit")
    assert split4.spans == 2 and gregory.spans > 10
    assert 10 * split4.path.stat().st_size <= gregory.path.stat().st_size


def test_quads_that_are_not_one_bicubic_keep_two_spans() -> None:
    """The single-span test reads the bicubic off the net's corners and subdivides it again: one
    moved interior point of the 7×7 net (C1 kept) makes that quad two-span; a net that is not C1
    inside, or patches without split4's connectivity (4f + k at corner k of quad f), are not split4
    quads at all (they are written one face per patch)."""
    import dataclasses

    from g1patch.io.cad import split4_quad_faces
    from g1patch.network import network_from_patch_points
    from g1patch.patches import PatchSet

    network = build_network(shapes.torus(8, 4), "split4", "limit")
    quads = split4_quad_faces(network)
    assert quads is not None and quads.single.all()
    control = network.patches.control.copy()  # local coordinates
    control[4 * 5, 1, 1] += (
        1e-9  # the twist at corner 0 of quad 5: rows and columns 2–4 untouched, still C1
    )
    moved = dataclasses.replace(
        network, patches=dataclasses.replace(network.patches, control=control)
    )
    quads = split4_quad_faces(moved)
    assert quads is not None and np.flatnonzero(~quads.single).tolist() == [5]
    control[4 * 5, 2, 2] += (
        1e-6  # next to the seams: row 3 is no longer the midpoints, a kink inside quad 5
    )
    assert (
        split4_quad_faces(
            dataclasses.replace(
                network, patches=dataclasses.replace(network.patches, control=control)
            )
        )
        is None
    )
    # bare sub-patches in split4's order are recognised from their shared points; in any other order
    # they are not
    bare = network.patches.world_control()
    assert split4_quad_faces(network_from_patch_points(PatchSet(bare))) is not None
    assert split4_quad_faces(network_from_patch_points(PatchSet(np.roll(bare, 1, axis=0)))) is None
