"""The STEP file of a split4 network written directly (:mod:`g1patch.io.cad.step_write`): the
B-rep read off the network, checked by OpenCASCADE reading the file back — valid, solid or open
as the mesh is, one face per quad, the network's own poles, G1 in OCC's measure, turned
outwards."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest
from ocp_marks import requires_ocp

from g1patch import shapes
from g1patch.build import build_network
from g1patch.construct.split4 import bspline_nets
from g1patch.io import cad
from g1patch.io.cad import export as cad_export
from g1patch.mesh import QuadMesh
from g1patch.network import PatchNetwork

#: OCC's G1 angle on a read-back file of an exact split4 network: rounding of 15-digit poles
OCC_G1_DEG = 1e-7


def counts(path: Path) -> dict[str, int]:
    """How many entities of each type a STEP file holds."""
    text = path.read_text()
    return {
        name: len(re.findall(rf"=\s*{name}\(", text))
        for name in ("ADVANCED_FACE", "EDGE_CURVE", "VERTEX_POINT", "CLOSED_SHELL", "OPEN_SHELL")
    }


def nearest_net_error(path: Path, network: PatchNetwork) -> float:
    """Largest distance between a read-back face's poles and the nearest quad's exact 6 × 6 net
    (or its 4 × 4 single span, compared at its corners), over the model's size."""
    exact = bspline_nets(network)
    corners_exact = exact[:, [0, -1, -1, 0], [0, 0, -1, -1]]
    worst = 0.0
    for face in cad.read_step_faces(path).faces:
        poles = face.poles()
        assert poles is not None
        if poles.shape[0] == 6:
            gaps = np.abs(exact - poles[None]).max(axis=(1, 2, 3))
        else:
            corners = poles[[0, -1, -1, 0], [0, 0, -1, -1]]
            gaps = np.abs(np.sort(corners_exact, axis=1) - np.sort(corners, axis=0)[None]).max(
                axis=(1, 2)
            )
        worst = max(worst, float(gaps.min()))
    return worst / float(np.abs(exact).max())


@requires_ocp
def test_a_closed_quad_mesh_is_one_valid_solid_with_the_networks_poles(tmp_path: Path) -> None:
    """A torus cage (an extraordinary-free closed mesh with 2-span faces after interpolation):
    one face per quad, one EDGE_CURVE per mesh edge, one VERTEX_POINT per vertex, a valid solid
    of positive volume read back by OCC, poles within 15 digits of the network's, G1 in OCC's
    measure on every edge."""
    mesh = shapes.torus(12, 8, r=0.4)
    network = build_network(mesh, "split4", tolerance=None)
    result = cad.export_step(tmp_path / "torus.step", network)
    found = counts(result.path)
    topology = mesh.topology
    assert found["ADVANCED_FACE"] == result.faces == mesh.n_faces
    assert found["EDGE_CURVE"] == topology.n_edges and found["VERTEX_POINT"] == mesh.n_vertices
    assert found["CLOSED_SHELL"] == 1 and found["OPEN_SHELL"] == 0
    assert result.solid and result.valid and result.free_edges == 0 and result.volume > 0
    assert result.g1_measured and result.max_g1_angle_deg <= OCC_G1_DEG
    assert nearest_net_error(result.path, network) <= 1e-14


@requires_ocp
def test_an_inside_out_cage_is_written_outwards(tmp_path: Path) -> None:
    """The same cube with every face reversed: the file's solid is the same, turned outwards
    (OCC's volume positive and equal: its faces reversed, their surfaces the network's)."""
    mesh = shapes.cube()
    inside_out = QuadMesh.from_arrays(mesh.vertices, mesh.faces[:, ::-1])
    volumes = []
    for name, cage in (("out", mesh), ("in", inside_out)):
        network = build_network(cage, "split4", tolerance=None)
        result = cad.export_step(tmp_path / f"{name}.step", network)
        assert result.solid and result.valid and result.max_g1_angle_deg <= OCC_G1_DEG
        assert nearest_net_error(result.path, network) <= 1e-14
        volumes.append(result.volume)
    assert volumes[0] == pytest.approx(volumes[1], rel=1e-12) and volumes[0] > 0


@requires_ocp
def test_an_open_mesh_and_two_components(tmp_path: Path) -> None:
    """A grid (open: its rim is free edges, one OPEN_SHELL) and two disjoint cubes (two closed
    shells, two solids whose volumes add up)."""
    grid = shapes.grid(4, 3)
    network = build_network(grid, "split4", tolerance=None)
    result = cad.export_step(tmp_path / "grid.step", network)
    assert not result.solid and result.volume is None and result.valid
    assert result.free_edges == 2 * (4 + 3) and counts(result.path)["OPEN_SHELL"] == 1
    assert result.max_g1_angle_deg <= OCC_G1_DEG

    cube = shapes.cube()
    two = QuadMesh.from_arrays(
        np.concatenate([cube.vertices, cube.vertices + [5.0, 0.0, 0.0]]),
        np.concatenate([cube.faces, cube.faces + cube.n_vertices]),
    )
    single = cad.export_step(tmp_path / "one.step", build_network(cube, "split4", tolerance=None))
    result = cad.export_step(tmp_path / "two.step", build_network(two, "split4", tolerance=None))
    assert result.solid and result.valid and counts(result.path)["CLOSED_SHELL"] == 2
    assert result.volume == pytest.approx(2.0 * single.volume, rel=1e-12)


@requires_ocp
def test_single_and_two_span_faces_share_their_edges(tmp_path: Path) -> None:
    """The limit of an open grid: 14 of its 30 quads are one bicubic (4 × 4 poles), the others
    two-span (6 × 6); edges between the two kinds are one EDGE_CURVE, OCC finds the shell valid
    and the joins G1."""
    mesh = shapes.grid(6, 5, height=lambda x, y: 0.3 * np.sin(3.0 * x) * np.cos(2.0 * y))
    network = build_network(mesh, "split4", "limit", tolerance=None)
    result = cad.export_step(tmp_path / "mixed.step", network)
    text = result.path.read_text()
    assert "(4,4),(4,4)" in text and "(4,2,4),(4,2,4)" in text
    assert counts(result.path)["EDGE_CURVE"] == mesh.topology.n_edges
    assert result.valid and result.free_edges == 2 * (6 + 5)
    assert result.max_g1_angle_deg <= OCC_G1_DEG


@requires_ocp
def test_large_files_are_not_read_back(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Above VERIFY_FACES faces (or with verify=False) OCC does not read the file back: nothing
    measured, the note says why; verify=True reads it whatever its size."""
    network = build_network(shapes.cube(), "split4", tolerance=None)
    monkeypatch.setattr(cad_export, "VERIFY_FACES", 3)
    result = cad.export_step(tmp_path / "big.step", network)
    assert not result.g1_measured and "more than the 3 read back" in result.g1_note
    assert result.solid and result.volume is None and result.faces == 6
    assert cad.export_step(tmp_path / "forced.step", network, verify=True).g1_measured
    assert not cad.export_step(tmp_path / "off.step", network, verify=False).g1_measured


@requires_ocp
def test_the_command_line_skips_or_forces_the_read_back(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``export --no-verify`` writes the file and says its angles were not measured; ``--verify``
    measures them."""
    from g1patch.cli import main
    from g1patch.io.network_file import save_network

    save_network(tmp_path / "cube.npz", build_network(shapes.cube(), "split4", tolerance=None))
    for flag, said in (("--no-verify", "not read back"), ("--verify", "max G1 angle")):
        target = tmp_path / f"cube{flag}.step"
        assert main(["export", str(tmp_path / "cube.npz"), "-o", str(target), flag, "-q"]) == 0
        assert said in capsys.readouterr().out and target.stat().st_size > 0
