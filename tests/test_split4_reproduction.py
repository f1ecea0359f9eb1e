"""split4 reproduces targets that already meet its G1 conditions (g1patch.construct.split4, DESIGN §1).

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

from g1patch import shapes
from g1patch.build import build_network
from g1patch.construct.split4 import macro_nets
from g1patch.continuity import check
from g1patch.io.meshfile import read_mesh
from g1patch.mesh import QuadMesh, QuadTopology
from g1patch.network import PatchNetwork

from test_subdivision import grid_torus

#: uniform cubic B-spline control points → Bézier points of one span
B_TO_BEZIER = np.array([[1.0, 4, 1, 0], [0, 4, 2, 0], [0, 2, 4, 0], [0, 1, 4, 1]]) / 6.0
#: the issue's bound, relative to the bounding-box diagonal
REPRODUCTION_RTOL = 1e-12


def control_rings(topology: QuadTopology, faces: np.ndarray | None = None) -> np.ndarray:
    """(F, 4, 4) cage vertices of the control ring of each of ``faces`` (default all), ``ring[f, i, j]``:
    i along edge 0, the face's own corners at (1, 1), (2, 1), (2, 2), (1, 2). Needs valence-4 interior corners."""
    faces = np.arange(topology.n_faces) if faces is None else np.asarray(faces)
    ring = np.full((len(faces), 4, 4), -1, dtype=np.int64)
    rows = np.arange(len(faces))
    for k in range(4):
        h = 4 * faces + k  # V_k → V_{k+1}
        out = QuadTopology.next(topology.twin[h])  # V_k → the point outside V_k across edge k
        along = QuadTopology.next(out)  # → the point outside V_{k+1}
        diagonal = QuadTopology.next(QuadTopology.next(topology.twin[out]))  # → the diagonal point at V_k
        points = {(1, 1): topology.origin(h), (1, 0): topology.target(out), (2, 0): topology.target(along),
                  (0, 0): topology.target(diagonal)}
        for (i, j), vertex in points.items():
            for _ in range(k):  # a quarter turn about the ring's centre per corner
                i, j = 3 - j, i
            ring[rows, i, j] = vertex
    assert (ring >= 0).all()
    return ring


def halved(nets: np.ndarray) -> np.ndarray:
    """(F, 4, 4, 3) Bézier nets subdivided at ½ in u and v by de Casteljau: (F, 7, 7, 3) macro nets."""
    def along(c: np.ndarray, axis: int) -> np.ndarray:
        c = np.moveaxis(c, axis, 1)
        p0, p1, p2, p3 = c[:, 0], c[:, 1], c[:, 2], c[:, 3]
        a, b, d = 0.5 * (p0 + p1), 0.5 * (p1 + p2), 0.5 * (p2 + p3)
        e, f = 0.5 * (a + b), 0.5 * (b + d)
        return np.moveaxis(np.stack([p0, a, e, 0.5 * (e + f), f, d, p3], axis=1), 1, axis)

    return along(along(nets, 1), 2)


def bspline_macro_nets(mesh: QuadMesh, faces: np.ndarray | None = None) -> np.ndarray:
    """The uniform bicubic B-spline of the cage on each of ``faces`` (default all), subdivided at ½: (F, 7, 7, 3)."""
    control = mesh.vertices[control_rings(mesh.topology, faces)]
    return halved(np.einsum("ai,fijd,bj->fabd", B_TO_BEZIER, control, B_TO_BEZIER))


def reproduction_error(mesh: QuadMesh, network: PatchNetwork) -> float:
    """max |split4 control − B-spline control| / bounding-box diagonal."""
    diagonal = float(np.linalg.norm(mesh.vertices.max(axis=0) - mesh.vertices.min(axis=0)))
    return float(np.abs(macro_nets(network.patches.world_control()) - bspline_macro_nets(mesh)).max()) / diagonal


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
    gregory = build_network(mesh, "gregory", "limit").patches.evaluate_grid(s, s)
    from g1patch.patches import PatchSet

    control = mesh.vertices[control_rings(mesh.topology)]
    bezier = PatchSet(np.einsum("ai,fijd,bj->fabd", B_TO_BEZIER, control, B_TO_BEZIER))
    np.testing.assert_allclose(bezier.evaluate_grid(s, s), gregory, rtol=0, atol=1e-14)
    assert reproduction_error(mesh, build_network(mesh, "split4", "interpolate")) > 1e-4


@pytest.mark.parametrize("name", sorted(REGULAR))
def test_regular_closed_cages_give_the_bspline(name: str) -> None:
    mesh = REGULAR[name]()
    network = build_network(mesh, "split4", "limit")
    assert reproduction_error(mesh, network) <= REPRODUCTION_RTOL
    assert network.provenance["star_safeguard_vertices"] == "0" and network.provenance["fallback_vertices"] == "0"
    if mesh.n_faces <= 1000:  # the check of 80 000 sub-patches takes half a minute; the B-spline is G1 (C2) anyway
        assert_exact_g1(check(network))


def test_catmark_torus_gives_the_bspline(shared_data: Path) -> None:
    mesh = read_mesh(shared_data / "catmark_torus.obj")
    network = build_network(mesh, "split4", "limit")
    assert reproduction_error(mesh, network) <= REPRODUCTION_RTOL
    assert_exact_g1(check(network))


def test_kept_midpoints_report_the_surface_normal() -> None:
    """Where the targets' seam tangents are kept, the network's normal at M is ``t_L × t_X``: the
    patches' own normal at every corner (mesh vertices, midpoints, centres)."""
    for mesh, shape in ((shapes.torus(8, 4), "limit"), (shapes.flat_fan(16), "interpolate")):
        network = build_network(mesh, "split4", shape)  # type: ignore[arg-type]
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
    network = build_network(mesh, "split4", "limit")
    assert_exact_g1(check(network))
    regular = topology.face_count == 4
    around = regular[topology.faces].all(axis=1)  # faces with four regular corners ...
    at_vertex = np.zeros(topology.n_vertices, dtype=bool)
    np.logical_or.at(at_vertex, topology.faces, ~around[:, None])
    calm = ~at_vertex[topology.faces].any(axis=1)  # ... whose corners' faces all have four too
    h = topology.edge_halfedges[:, 0]
    mu = _chain_shears(topology, np.where(regular, 0.0, np.cos(2.0 * np.pi / topology.face_count)), topology.origin(h), topology.target(h))
    unsheared = (mu[topology.halfedge_edge] == 0.0).reshape(-1, 4).all(axis=1)
    faces = np.flatnonzero(calm & unsheared)
    assert 30 <= len(faces) < topology.n_faces
    diagonal = float(np.linalg.norm(mesh.vertices.max(axis=0) - mesh.vertices.min(axis=0)))
    error = np.abs(macro_nets(network.patches.world_control())[faces] - bspline_macro_nets(mesh, faces)).max()
    assert error <= REPRODUCTION_RTOL * diagonal
