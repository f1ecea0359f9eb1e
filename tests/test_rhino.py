"""Rhino's .3dm (rhino3dm, OpenNURBS): the STEP file's B-spline faces, read back by OpenNURBS and
evaluated by it (an evaluator independent of ours)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from g1patch import shapes
from g1patch.api import Surface
from g1patch.build import build_network
from g1patch.cli import main
from g1patch.io.cad import cad_surfaces, export_3dm
from g1patch.patches import PatchSet

rhino3dm = pytest.importorskip("rhino3dm", reason="the extra 'rhino' (rhino3dm) is not installed")

EPS = float(np.finfo(float).eps)


def _faces(path: Path) -> list:
    model = rhino3dm.File3dm.Read(str(path))
    return [model.Objects[i] for i in range(len(model.Objects))]


def test_split4_faces_round_trip_and_evaluate_as_ours(tmp_path: Path) -> None:
    network = build_network(shapes.torus(8, 4), "split4", "limit")
    result = export_3dm(tmp_path / "t.3dm", network)
    surfaces = cad_surfaces(tmp_path / "t.3dm", network)
    faces = _faces(tmp_path / "t.3dm")
    assert result.faces == len(faces) == 32 and result.method == "exact"  # one face per quad
    scale = float(np.abs(network.patches.world_control()).max())
    for index, (face, net, (knots_u, _)) in enumerate(
        zip(faces, surfaces.nets(), surfaces.knots(), strict=True)
    ):
        surface = face.Geometry
        assert face.Attributes.Name == f"face {index}"
        assert list(surface.KnotsU.ToList()) == knots_u[1:-1].tolist()
        poles = [surface.Points[i, j] for i in range(net.shape[0]) for j in range(net.shape[1])]
        np.testing.assert_array_equal([[p.X, p.Y, p.Z] for p in poles], net.reshape(-1, 3))
        if net.shape[:2] == (4, 4):  # a single-span face: the Bézier patch, evaluated by OpenNURBS
            ours = PatchSet(net[None], "bezier").evaluate(np.array([[0.3, 0.7]]))[0, 0]
            point = surface.PointAt(0.3, 0.7)
            np.testing.assert_allclose([point.X, point.Y, point.Z], ours, atol=64 * EPS * scale)


def test_a_gregory_surface_is_written_as_its_step_faces(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    surface = Surface(build_network(shapes.torus(8, 4), "gregory"))
    surface.export(tmp_path / "t.npz")
    assert main(["export", str(tmp_path / "t.npz"), "-o", str(tmp_path / "t.3dm")]) == 0
    assert "wrote 32 NURBS faces (split4)" in capsys.readouterr().out
    assert len(_faces(tmp_path / "t.3dm")) == 32
    result = surface.export(tmp_path / "u.3dm", max_deviation=1e-3)
    assert result.relative_deviation <= 1e-3 and result.file_bytes < 8_000 * 32
