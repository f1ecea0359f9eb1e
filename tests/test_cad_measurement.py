"""The export's OCC-side measurements, made fast but kept what they were (issue 13).

G1 angles: the normals on the sewn faces are evaluated vectorised from the B-spline data OCC holds
(poles, knots, orientation read back from each face) instead of one ``BRepAdaptor_Surface::D1``
call per point; every test here compares them with OCC's own per-point evaluation, the previous
measurement. Solids: oriented by the sign of OCC's volume instead of a point classification.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from ocp_marks import requires_ocp  # noqa: E402

from g1patch import shapes
from g1patch.build import build_network
from g1patch.construct.corner import build_corner_network
from g1patch.construct.polynomial import split4_of_gregory
from g1patch.io.meshfile import read_mesh
from g1patch.network import PatchNetwork, edge_parameters
from g1patch.patches import PatchSet

pytestmark = requires_ocp


def sewn_faces(network: PatchNetwork) -> tuple[list[object], bool]:
    """The sewn OCC faces of a network, as export_cad makes them, and whether they are split4
    quads."""
    from g1patch.io import cad
    from g1patch.io.cad import opencascade

    occ = opencascade._occ()
    quads = cad.split4_quad_faces(network)
    tolerance = cad.SEWING_RTOL * network.bounding_box_diagonal()
    if quads is not None:
        faces = opencascade._make_quad_faces(occ, quads, 0.01 * tolerance, None)
    elif isinstance(network.patches, PatchSet):
        knots = cad.bezier_knots(1)
        fit = cad.BSplineFit(network.patches.convert("bezier").world_control(), knots, knots, 0.0)
        faces = opencascade._make_faces(occ, fit, 0.01 * tolerance, None)
    else:
        fit = cad.fit_bspline_surfaces(network)
        faces = opencascade._make_faces(occ, fit, 0.01 * tolerance, None)
    return opencascade._sew(occ, faces, tolerance)[1], quads is not None


def occ_angles(
    network: PatchNetwork, faces: list[object], quads: bool, monkeypatch: pytest.MonkeyPatch
) -> np.ndarray:
    """The G1 angles with every point evaluated by OCC (``BRepAdaptor_Surface::D1``), as before."""
    from g1patch.io.cad import measure, opencascade

    with monkeypatch.context() as patch:
        patch.setattr(measure, "_occ_bspline", lambda occ, face: None)
        return measure._occ_g1_angles(opencascade._occ(), faces, network, 17, None, quads)


def creased_cube(data: Path) -> PatchNetwork:
    """The creased cube's Gregory network, whose patches are bicubics: written as they are."""
    from g1patch.io.cad.method import _as_bicubics

    network = build_network(read_mesh(data / "catmark_cube_creases2.obj"), "gregory")
    return replace(network, patches=_as_bicubics(network.patches))


NETWORKS = {
    "cube split4 (two-span quads)": lambda data: split4_of_gregory(
        build_network(shapes.cube(), "gregory")
    ),
    "cube fitted (graded knots)": lambda data: build_network(shapes.cube(), "gregory"),
    "corner cube (Bézier faces)": lambda data: build_corner_network(shapes.cube()),
    "creased cube (degenerate corners)": creased_cube,
    "torus with seams (split4)": lambda data: split4_of_gregory(
        build_network(read_mesh(data / "catmark_torus_creases0.obj"), "gregory")
    ),
}


@pytest.mark.parametrize("name", list(NETWORKS))
def test_vectorised_g1_angles_are_occs_own(
    name: str, shared_data: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """On every shared edge and sample, the angle from the vectorised normals is OCC's per-point
    one to rounding; at degenerate points (the creased cube's corners, where OCC's S_u × S_v cancels
    to 0) both say 0, not a direction made of rounding."""
    from g1patch.io.cad import measure, opencascade

    network = NETWORKS[name](shared_data)
    faces, quads = sewn_faces(network)
    fast = measure._occ_g1_angles(opencascade._occ(), faces, network, 17, None, quads)
    reference = occ_angles(network, faces, quads, monkeypatch)
    assert fast.shape == reference.shape == (len(network.shared_edges()[0]), 17)
    np.testing.assert_allclose(fast, reference, rtol=0, atol=1e-9)


def test_normals_agree_with_occ_point_by_point_and_other_rows_go_to_occ() -> None:
    """Rows on iso-lines (every edge) are vectorised and equal OCC's normals to rounding, reversed
    faces included; a row on no iso-line is evaluated by OCC itself, bit for bit."""
    from g1patch.io.cad import measure, opencascade

    occ = opencascade._occ()
    faces, _ = sewn_faces(split4_of_gregory(build_network(shapes.cube(), "gregory")))
    reversed_faces = [face.Reversed() for face in faces[:2]]
    faces = [*faces, *[occ.TopoDS.Face(face) for face in reversed_faces]]
    rng = np.random.default_rng(3)
    t = np.sort(rng.random(9))
    rows = []
    for constant in (0.0, 0.25, 0.5, 0.7, 1.0):  # on and off the double knot at ½
        rows += [
            np.stack([np.full(9, constant), t], axis=-1),
            np.stack([t, np.full(9, constant)], axis=-1),
        ]
    face_of = np.repeat(np.arange(len(faces)), len(rows))
    uv = np.tile(np.stack(rows), (len(faces), 1, 1))
    uv[0] = rng.random((9, 2))  # a diagonal row: OCC's
    normals = measure._shape_normals(occ, faces, face_of, uv, None)
    for row in range(len(uv)):
        expected = measure._face_normals(occ, faces[face_of[row]], uv[row])
        if row == 0:
            np.testing.assert_array_equal(normals[row], expected)
        else:
            np.testing.assert_allclose(
                normals[row], expected, rtol=0, atol=1e-12 * np.abs(expected).max()
            )
    np.testing.assert_allclose(
        normals[face_of == len(faces) - 1], -normals[face_of == 1], rtol=0, atol=1e-15
    )


def test_a_face_that_disagrees_with_occ_is_measured_by_occ(monkeypatch: pytest.MonkeyPatch) -> None:
    """The cross-check per face is live: where vectorised and OCC's normal differ (here: any
    difference at all, or a misread pole), the face's every point is OCC's, bit for bit."""
    from g1patch.io.cad import measure, opencascade

    network = split4_of_gregory(build_network(shapes.cube(), "gregory"))
    faces, quads = sewn_faces(network)
    reference = occ_angles(network, faces, quads, monkeypatch)
    read = measure._occ_bspline

    def misread(occ: object, face: object) -> object:
        surface = read(occ, face)
        return surface._replace(poles=surface.poles * 1.001)

    monkeypatch.setattr(measure, "_occ_bspline", misread)
    np.testing.assert_array_equal(
        measure._occ_g1_angles(opencascade._occ(), faces, network, 17, None, quads), reference
    )


def test_an_inside_out_shell_becomes_an_outward_solid(tmp_path: Path) -> None:
    """Patches whose normals point inwards sew into an inside-out shell: the solid is reversed by
    the sign of its volume, so the volume and OCC's reading of the file are positive and agree."""
    from OCP.BRepGProp import BRepGProp
    from OCP.GProp import GProp_GProps

    from g1patch.io.cad import export_step, read_step_faces

    outward = build_corner_network(shapes.cube()).patches.convert("bezier")
    inward = PatchSet(
        np.ascontiguousarray(outward.world_control().transpose(0, 2, 1, 3)), "bezier"
    )  # u ↔ v
    results = [
        export_step(tmp_path / f"{name}.step", patches, g1_samples=0)
        for name, patches in (("out", outward), ("in", inward))
    ]
    for result in results:
        assert result.solid and result.valid and result.volume > 0
        props = GProp_GProps()
        BRepGProp.VolumeProperties_s(read_step_faces(result.path).shape, props)
        assert props.Mass() == pytest.approx(result.volume, rel=1e-9)
    assert results[0].volume == pytest.approx(results[1].volume, rel=1e-12)


def test_iso_rows_need_edge_parameters_to_be_iso_lines() -> None:
    """What the vectorised path relies on: every edge's samples keep u or v constant, also after
    the split4 quarter map 0.5 (uv + corner)."""
    t = np.linspace(0.0, 1.0, 33)
    for edge in range(4):
        for quarter in ([0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]):
            uv = 0.5 * (edge_parameters(np.array([edge])[:, None], t)[0] + np.array(quarter))
            assert (uv[:, 0] == uv[0, 0]).all() or (uv[:, 1] == uv[0, 1]).all()
