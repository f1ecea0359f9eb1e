"""split4 keeps seams: assembled on the mesh cut open along them (one vertex per sector, the seam
tangents kept in both copies), connected on the uncut mesh with the seams marked."""

from __future__ import annotations

import logging

import numpy as np
import pytest

from g1patch.build import build_network
from g1patch.construct.split4.seams import cut_along_seams
from g1patch.continuity import check
from g1patch.mesh import QuadMesh, Tag
from g1patch.shapes import cube, cube_sphere
from g1patch.targets import halfedge_slots
from g1patch.targets.interpolate import interpolate_targets

#: exact G1, degrees (DESIGN §5)
G1 = 1e-9


def _tagged(mesh: QuadMesh, edges: np.ndarray) -> QuadMesh:
    pairs = mesh.topology.edges[edges].ravel().tolist()
    return QuadMesh(mesh.vertices, mesh.topology, (Tag("crease", tuple(pairs), (10.0,)),))


def test_cutting_a_sharp_box_gives_three_sectors_per_corner_and_keeps_every_tangent() -> None:
    box = _tagged(cube(), np.arange(12))
    targets = interpolate_targets(box)
    cut = cut_along_seams(targets)
    topology = cut.targets.topology
    assert topology.n_vertices == 8 * 3 and topology.n_faces == 6
    assert cut.seam_halfedges.sum() == 24 and (topology.twin < 0).sum() == 24
    assert cut.seams.all()
    np.testing.assert_array_equal(cut.targets.positions, targets.positions[cut.sector_vertex])
    slot_out, slot_in = halfedge_slots(box.topology)
    cut_out, cut_in = halfedge_slots(topology)
    np.testing.assert_array_equal(cut.targets.tangents[cut_out], targets.tangents[slot_out])
    np.testing.assert_array_equal(cut.targets.tangents[cut_in], targets.tangents[slot_in])
    # each copy has its face's normal: the box's faces are flat
    corners = box.vertices[box.faces]
    face_normal = np.cross(corners[:, 1] - corners[:, 0], corners[:, 3] - corners[:, 0])
    face_normal /= np.linalg.norm(face_normal, axis=1, keepdims=True)
    np.testing.assert_allclose(
        cut.targets.normals[topology.faces], np.repeat(face_normal[:, None], 4, axis=1), atol=1e-12
    )


def test_an_isolated_sharp_edge_between_two_darts_is_built_smooth_and_said(
    caplog: pytest.LogCaptureFixture,
) -> None:
    sphere = cube_sphere(3)
    inner = np.flatnonzero(
        ~np.isin(sphere.topology.edges, np.flatnonzero(sphere.topology.valence != 4)).any(axis=1)
    )
    # an edge whose neighbouring edges are all smooth: both its ends are darts
    with caplog.at_level(logging.WARNING):
        network = build_network(_tagged(sphere, inner[:1]), "split4")
    assert "between two darts" in caplog.text
    assert network.seam.sum() == 0
    report = check(network)
    assert report.passes(G1) and report.folds == 0


def test_a_seam_that_runs_into_a_dart_is_cut_open_up_to_it() -> None:
    """A crease of two edges on a closed surface: its middle vertex has two sectors, its ends
    (darts) one each; both edges are cut open up to the darts and stay sharp on both halves."""
    sphere = cube_sphere(3)
    topology = sphere.topology
    start = int(np.flatnonzero(topology.valence == 3)[0])
    first = np.flatnonzero((topology.edges == start).any(axis=1))[0]
    middle = int(topology.edges[first][topology.edges[first] != start][0])
    # the edge after `first` along the same grid line: opposite in middle's valence-4 ring
    ring = np.flatnonzero((topology.edges == middle).any(axis=1))
    others = topology.edges[ring][topology.edges[ring] != middle]
    direction = sphere.vertices[middle] - sphere.vertices[start]
    ahead = ring[np.argmax((sphere.vertices[others] - sphere.vertices[middle]) @ direction)]
    mesh = _tagged(sphere, np.array([first, ahead]))
    network = build_network(mesh, "split4")
    assert network.seam.sum() == 2 * 2 * 2  # two edges, two halves, both sides
    report = check(network)
    assert report.passes(G1) and report.folds == 0
    assert report.to_dict()["seams"]["g0_max"] <= 1e-12


def test_take_patches_opens_the_edges_to_patches_left_out() -> None:
    network = build_network(_tagged(cube(), np.arange(12)), "split4")
    keep = np.ones(network.n_patches, dtype=bool)
    keep[:4] = False  # the first face
    taken = network.take_patches(keep)
    assert taken.n_patches == network.n_patches - 4
    assert taken.open_edges()[0].size == 8  # the face's four edges, two halves each
    assert not taken.seam[taken.neighbor < 0].any()
    patch, edge = np.nonzero(taken.neighbor >= 0)
    back = taken.neighbor[taken.neighbor[patch, edge], taken.neighbor_edge[patch, edge]]
    np.testing.assert_array_equal(back, patch)
    assert check(taken).passes(G1)
