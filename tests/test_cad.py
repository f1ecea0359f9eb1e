"""CAD export: STEP/IGES round trips through OpenCASCADE, B-spline fitting, the enclosed volume.

The round trips read the written file back with OCC's own readers and compare with g1patch:
surface points (exact export: to rounding of the file's decimal reals), the solid's validity
(``BRepCheck_Analyzer``) and its volume (``BRepGProp::VolumeProperties``) against
:func:`network_volume`. Tests that need OCP skip, naming the extra, where it is not installed.
"""

from __future__ import annotations

import dataclasses
import sys
from pathlib import Path

import numpy as np
import pytest
from numpy.typing import ArrayLike, NDArray
from ocp_marks import HAVE_OCP, requires_ocp  # noqa: E402
from scipy.interpolate import BSpline
from scipy.spatial import cKDTree

from g1patch import shapes
from g1patch.construct.corner import build_corner_network
from g1patch.continuity import check
from g1patch.errors import ConstructionError, FormatError, InputError, MissingDependencyError
from g1patch.geometry import network_volume, volume_estimate
from g1patch.io import cad
from g1patch.io.bpt import read_bpt
from g1patch.io.cad import (
    bezier_knots,
    export_cad,
    export_iges,
    export_step,
    fit_bspline_surfaces,
    read_iges_faces,
    read_step_faces,
)
from g1patch.io.cad import export as cad_export
from g1patch.io.meshfile import read_mesh
from g1patch.network import PatchNetwork, network_from_patch_points
from g1patch.patches import PatchSet

#: closed meshes of the acceptance: generated ones and the shared files
CLOSED = {
    "cube": lambda data: shapes.cube(),
    "torus_8_6": lambda data: shapes.torus(8, 6),
    "catmark_cube": lambda data: read_mesh(data / "catmark_cube.obj"),
    "catmark_torus": lambda data: read_mesh(data / "catmark_torus.obj"),
    "spot": lambda data: read_mesh(data / "spot_quadrangulated.obj"),
}
SHARED = {"catmark_cube", "catmark_torus", "spot"}


def closed_network(name: str, request: pytest.FixtureRequest) -> PatchNetwork:
    data = request.getfixturevalue("shared_data") if name in SHARED else None
    return build_corner_network(CLOSED[name](data))


# --------------------------------------------------------------------------- a smooth
# non-polynomial surface


@dataclasses.dataclass(frozen=True)
class OnSphere:
    """Patches pushed onto the unit sphere, ``q = p / |p|``: smooth, not polynomial.

    ``q_u = (p_u − q (q · p_u)) / |p|`` (the chain rule). Neighbours share boundaries exactly,
    as the base patches do, and a closed base network star-shaped about 0 maps onto the whole
    sphere.
    """

    base: PatchSet

    def __len__(self) -> int:
        return len(self.base)

    @staticmethod
    def _push(p: NDArray[np.float64], dp: NDArray[np.float64] | None) -> NDArray[np.float64]:
        r = np.linalg.norm(p, axis=-1, keepdims=True)
        q = p / r
        if dp is None:
            return q
        return (dp - q * np.einsum("...d,...d->...", q, dp)[..., None]) / r

    def evaluate(self, uv: ArrayLike, du: int = 0, dv: int = 0) -> NDArray[np.float64]:
        assert du + dv <= 1
        p = self.base.evaluate(uv)
        return self._push(p, self.base.evaluate(uv, du, dv) if du + dv else None)

    def evaluate_grid(
        self, u: ArrayLike, v: ArrayLike | None = None, du: int = 0, dv: int = 0
    ) -> NDArray[np.float64]:
        assert du + dv <= 1
        p = self.base.evaluate_grid(u, v)
        return self._push(p, self.base.evaluate_grid(u, v, du, dv) if du + dv else None)


def sphere_network() -> PatchNetwork:
    network = build_corner_network(shapes.cube())
    return dataclasses.replace(network, patches=OnSphere(network.patches))


def evaluate_fit(
    fit: cad.BSplineFit, u: NDArray[np.float64], v: NDArray[np.float64]
) -> NDArray[np.float64]:
    """The fitted surfaces on the grid u × v, (N, len(u), len(v), 3), by SciPy's B-spline basis."""
    basis_u = BSpline.design_matrix(u, fit.knots_u, 3).toarray()
    basis_v = BSpline.design_matrix(v, fit.knots_v, 3).toarray()
    return np.einsum("ai,nijd,bj->nabd", basis_u, fit.control, basis_v)


def boundary_rows(control: NDArray[np.float64]) -> NDArray[np.float64]:
    """Boundary control rows of nets (N, c, c, 3) per edge k, counter-clockwise: (N, 4, c, 3)."""
    return np.stack(
        [control[:, :, 0], control[:, -1, :], control[:, ::-1, -1], control[:, 0, ::-1]], axis=1
    )


# ------------------------------------------------------------------------------------------------
# fitting


def test_fit_reproduces_bicubic_patches_with_the_bezier_knots() -> None:
    network = build_corner_network(shapes.torus(8, 6))
    bezier = network.patches.convert("bezier").world_control()
    diagonal = network.bounding_box_diagonal()
    for patches in (network, network.patches.convert("bspline")):
        fit = fit_bspline_surfaces(patches)
        assert fit.knots_u.tolist() == fit.knots_v.tolist() == [0, 0, 0, 0, 1, 1, 1, 1]
        assert fit.control.shape == (len(bezier), 4, 4, 3)
        assert fit.deviation <= 1e-14 * diagonal
        assert np.abs(fit.control - bezier).max() <= 1e-14 * diagonal


def test_fit_of_a_non_polynomial_surface_reaches_the_tolerance() -> None:
    network = sphere_network()
    tolerance = 1e-6 * network.bounding_box_diagonal()
    fit = fit_bspline_surfaces(network)
    spans = len(fit.knots_u) - 7
    assert spans > 1 and fit.deviation <= tolerance
    assert fit.control.shape == (6, spans + 3, spans + 3, 3)
    # measured independently, at parameters the fit never saw, including the borders
    rng = np.random.default_rng(7)
    u = np.sort(np.concatenate([[0.0, 1.0], rng.random(40)]))
    error = np.linalg.norm(
        evaluate_fit(fit, u, u) - network.patches.evaluate_grid(u, u), axis=-1
    ).max()
    assert error <= 1.5 * tolerance
    # a tighter tolerance needs more spans and meets it
    tighter = fit_bspline_surfaces(network, tolerance / 20)
    assert len(tighter.knots_u) > len(fit.knots_u) and tighter.deviation <= tolerance / 20


def test_fitted_boundaries_are_identical_between_neighbours() -> None:
    network = sphere_network()
    fit = fit_bspline_surfaces(network, 1e-5)
    rows = boundary_rows(fit.control)
    patch, edge = network.shared_edges()
    other, other_edge = network.neighbor[patch, edge], network.neighbor_edge[patch, edge]
    # the two sides run along the edge in opposite directions: bit-identical, reversed
    assert np.array_equal(rows[patch, edge], rows[other, other_edge][:, ::-1])
    # corners: every patch meeting at a vertex has the same control point there
    corners = fit.control[:, [0, -1, -1, 0], [0, 0, -1, -1]]  # (N, 4, 3), corners F0..F3
    for vertex in np.unique(network.corner_ids):
        at = corners[network.corner_ids == vertex]
        assert (at == at[0]).all()


def test_fit_without_a_network_matches_neighbours_to_rounding() -> None:
    network = sphere_network()
    fit = fit_bspline_surfaces(network.patches, 1e-5)
    rows = boundary_rows(fit.control)
    patch, edge = network.shared_edges()
    other, other_edge = network.neighbor[patch, edge], network.neighbor_edge[patch, edge]
    assert np.abs(rows[patch, edge] - rows[other, other_edge][:, ::-1]).max() <= 1e-14


def test_uniform_refinement_doubles_the_spans() -> None:
    network = sphere_network()
    fit = fit_bspline_surfaces(network, 1e-5, refine="uniform")
    spans = len(fit.knots_u) - 7
    assert spans & (spans - 1) == 0  # a power of two
    np.testing.assert_array_equal(fit.knots_u, bezier_knots(spans))
    adaptive = fit_bspline_surfaces(network, 1e-5)
    assert len(adaptive.knots_u) <= len(fit.knots_u)
    # adaptive knots stay symmetric under t -> 1 - t (the reversed-edge copy relies on it)
    np.testing.assert_array_equal(adaptive.knots_u, 1.0 - adaptive.knots_u[::-1])


def test_fit_reports_an_unreachable_tolerance() -> None:
    with pytest.raises(ConstructionError, match="max_spans"):
        fit_bspline_surfaces(sphere_network(), 1e-12, max_spans=4)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"fit_tolerance": -1.0}, "tolerance"),
        ({"fit_tolerance": float("nan")}, "tolerance"),
        ({"max_spans": 0}, "max_spans"),
        ({"refine": "random"}, "refine"),
    ],
)
def test_fit_rejects_bad_arguments(kwargs: dict[str, object], match: str) -> None:
    with pytest.raises(InputError, match=match):
        fit_bspline_surfaces(sphere_network(), **kwargs)  # type: ignore[arg-type]


def test_fit_rejects_what_is_not_patches() -> None:
    with pytest.raises(InputError, match="patches"):
        fit_bspline_surfaces(np.zeros((2, 4, 4, 3)))  # type: ignore[arg-type]


# ------------------------------------------------------------------------------------------------
# volume


def flat_box(lower: ArrayLike, upper: ArrayLike) -> PatchSet:
    """The six faces of an axis-aligned box as flat Bézier patches, counter-clockwise from
    outside."""
    lo, hi = np.asarray(lower, float), np.asarray(upper, float)
    mesh = shapes.cube()  # corners (±1, ±1, ±1), faces oriented outwards
    x = lo + (mesh.vertices + 1.0) / 2.0 * (hi - lo)
    corners = x[mesh.faces]
    s = np.arange(4) / 3.0
    u, v = s[None, :, None, None], s[None, None, :, None]
    c0, c1, c2, c3 = (corners[:, k, None, None, :] for k in range(4))
    return PatchSet(
        (1 - u) * (1 - v) * c0 + u * (1 - v) * c1 + u * v * c2 + (1 - u) * v * c3, "bezier"
    )


def test_volume_of_a_box_is_exact() -> None:
    box = flat_box([1.0, 2.0, 3.0], [3.0, 5.0, 7.0])
    assert network_volume(box) == pytest.approx(2 * 3 * 4, rel=4 * np.finfo(float).eps)
    estimate = volume_estimate(box)
    assert estimate.exact and estimate.points == 5 and estimate.change == 0.0


def test_volume_is_exact_for_bicubic_patches_in_every_form() -> None:
    network = build_corner_network(shapes.torus(8, 6))
    reference = network_volume(network)
    # 5 Gauss-Legendre points integrate degree 9: more points change nothing
    more = cad_free_quadrature(network.patches, 9)
    assert reference == pytest.approx(more, rel=1e-14)
    for form in ("hermite", "bezier", "bspline"):
        assert network_volume(network.patches.convert(form)) == pytest.approx(reference, rel=1e-14)
    # translation changes nothing, scaling by 2 multiplies by 8
    moved = PatchSet(
        network.patches.convert("bezier").world_control() * 2.0 + [10.0, -5.0, 3.0], "bezier"
    )
    assert network_volume(moved) == pytest.approx(8.0 * reference, rel=1e-13)


def cad_free_quadrature(patches: PatchSet, points: int) -> float:
    """Σ w_a w_b (p · (p_u × p_v)) / 3 with ``points`` Gauss-Legendre nodes, about the origin."""
    nodes, weights = np.polynomial.legendre.leggauss(points)
    nodes, weights = (nodes + 1) / 2, weights / 2
    p = patches.evaluate_grid(nodes, nodes)
    normal = np.cross(
        patches.evaluate_grid(nodes, nodes, 1, 0), patches.evaluate_grid(nodes, nodes, 0, 1)
    )
    return float(np.einsum("a,b,nabd,nabd->", weights, weights, p, normal)) / 3.0


def test_volume_of_non_polynomial_patches_converges() -> None:
    estimate = volume_estimate(sphere_network(), rtol=1e-12)
    assert not estimate.exact and estimate.points > 8
    assert estimate.volume == pytest.approx(4.0 / 3.0 * np.pi, rel=1e-11)
    assert estimate.change <= 1e-12 * estimate.volume


def test_volume_rejects_what_is_not_patches() -> None:
    with pytest.raises(InputError, match="network"):
        network_volume(np.zeros(3))  # type: ignore[arg-type]


# ------------------------------------------------------------------------------------------------
# export


def matched_faces(model: cad.CadModel, network: PatchNetwork) -> list[int]:
    """For each patch the index of the read face with the same centre point."""
    centre = np.array([[0.5, 0.5]])
    faces = np.concatenate([face.evaluate(centre) for face in model.faces])
    distance, index = cKDTree(faces).query(network.patches.evaluate(centre)[:, 0])
    assert distance.max() <= 1e-6 * network.bounding_box_diagonal()
    assert len(set(index.tolist())) == len(network.patches)
    return index.tolist()


def occ_solid_figures(shape: object) -> tuple[bool, float, str]:
    """OCC's verdicts on a read shape: valid, volume, shape type."""
    from OCP.BRepCheck import BRepCheck_Analyzer
    from OCP.BRepGProp import BRepGProp
    from OCP.GProp import GProp_GProps

    props = GProp_GProps()
    BRepGProp.VolumeProperties_s(shape, props)
    return bool(BRepCheck_Analyzer(shape).IsValid()), float(props.Mass()), shape.ShapeType().name  # type: ignore[attr-defined]


@pytest.mark.slow
@requires_ocp
@pytest.mark.parametrize("name", list(CLOSED))
def test_step_round_trip_of_closed_meshes(
    name: str, request: pytest.FixtureRequest, tmp_path: Path
) -> None:
    network = closed_network(name, request)
    diagonal = network.bounding_box_diagonal()
    result = export_step(tmp_path / f"{name}.step", network)
    assert result.path.is_file() and [p.name for p in tmp_path.iterdir()] == [f"{name}.step"]
    assert result.faces == len(network.patches) and result.exact and result.spans == 1
    assert result.solid and result.valid and result.free_edges == 0
    assert result.fit_deviation == 0.0
    volume = network_volume(network)
    assert result.volume == pytest.approx(volume, rel=1e-9)

    model = read_step_faces(result.path)
    valid, read_volume, kind = occ_solid_figures(model.shape)
    assert valid and kind == "TopAbs_SOLID"
    assert read_volume == pytest.approx(volume, rel=1e-6)
    assert len(model.faces) == len(network.patches)
    # surfaces: exactly the Bézier control nets (to the file's decimals), evaluated on a grid
    order = matched_faces(model, network)
    bezier = network.patches.convert("bezier").world_control()
    t = np.linspace(0.0, 1.0, 3)
    uv = np.stack(np.meshgrid(t, t, indexing="ij"), axis=-1).reshape(-1, 2)
    expected = network.patches.evaluate(uv)
    worst_point = worst_pole = 0.0
    for patch, face in enumerate(order):
        read = model.faces[face]
        assert read.bounds == (0.0, 1.0, 0.0, 1.0)
        worst_point = max(worst_point, float(np.abs(read.evaluate(uv) - expected[patch]).max()))
        worst_pole = max(worst_pole, float(np.abs(read.poles() - bezier[patch]).max()))
    assert worst_point <= 1e-12 * diagonal and worst_pole <= 1e-12 * diagonal


@requires_ocp
@pytest.mark.parametrize("name", ["cube", "torus_8_6", "catmark_torus"])
def test_occ_measures_the_same_g1_angles_as_check(
    name: str, request: pytest.FixtureRequest, tmp_path: Path
) -> None:
    network = closed_network(name, request)
    result = export_step(tmp_path / "out.stp", network)
    report = check(network)
    assert result.max_g1_angle_deg == pytest.approx(report.max_edge_angle_deg, abs=1e-9)
    assert result.mean_g1_angle_deg == pytest.approx(report.mean_edge_angle_deg, abs=1e-9)


@requires_ocp
def test_iges_round_trip_of_the_cube(tmp_path: Path) -> None:
    network = build_corner_network(shapes.cube())
    diagonal = network.bounding_box_diagonal()
    result = export_iges(tmp_path / "cube.igs", network)
    assert result.format == "iges" and result.solid and result.valid and result.faces == 6
    model = read_iges_faces(result.path)
    valid, volume, kind = occ_solid_figures(model.shape)
    assert valid and kind == "TopAbs_SOLID"
    assert volume == pytest.approx(network_volume(network), rel=1e-6)
    # IGES writes reals with fewer digits than STEP: the poles come back to ~1e-10
    bezier = network.patches.convert("bezier").world_control()
    for patch, face in enumerate(matched_faces(model, network)):
        assert np.abs(model.faces[face].poles() - bezier[patch]).max() <= 1e-9 * diagonal


@requires_ocp
def test_step_export_of_fitted_non_polynomial_patches(tmp_path: Path) -> None:
    network = sphere_network()
    diagonal = network.bounding_box_diagonal()
    progress: list[str] = []
    result = export_step(
        tmp_path / "sphere.step",
        network,
        progress=lambda stage, done, total: progress.append(stage),
    )
    assert not result.exact and result.spans > 1
    assert 0.0 < result.fit_deviation <= result.fit_tolerance == pytest.approx(1e-6 * diagonal)
    assert result.solid and result.valid and result.free_edges == 0
    assert {"fit", "faces", "sew", "solid", "g1", "write"} <= set(progress)
    # the surface is the unit sphere, smooth: the only kinks are the fit's, about
    # deviation / span length (3.5e-6 / ~0.05 rad ≈ 0.004°: measured 0.005°)
    assert 0.0 < result.max_g1_angle_deg < 0.02
    sphere = 4.0 / 3.0 * np.pi
    model = read_step_faces(result.path)
    valid, volume, _ = occ_solid_figures(model.shape)
    assert valid and volume == pytest.approx(sphere, rel=1e-5)
    assert network_volume(network) == pytest.approx(sphere, rel=1e-11)
    # the read surfaces stay within the fit tolerance of the patches
    uv = np.random.default_rng(3).random((20, 2))
    expected = network.patches.evaluate(uv)
    for patch, face in enumerate(matched_faces(model, network)):
        assert (
            np.linalg.norm(model.faces[face].evaluate(uv) - expected[patch], axis=-1).max()
            <= 1.5 * result.fit_tolerance
        )


@pytest.mark.slow
@requires_ocp
@pytest.mark.parametrize("name", ["cube", "torus_8_6", "catmark_torus"])
def test_step_round_trip_of_gregory_networks(
    name: str, request: pytest.FixtureRequest, tmp_path: Path
) -> None:
    """Rational Gregory patches fitted (method "fit"): a valid closed solid within the export
    tolerance."""
    from g1patch.build import build_gregory_network

    data = request.getfixturevalue("shared_data") if name in SHARED else None
    network = build_gregory_network(CLOSED[name](data))
    result = export_step(tmp_path / f"{name}.step", network, method="fit")
    assert (
        not result.exact and result.method == "fit" and result.fit_deviation <= result.fit_tolerance
    )
    assert result.deviation == result.fit_deviation
    assert result.solid and result.valid and result.free_edges == 0
    model = read_step_faces(result.path)
    valid, volume, kind = occ_solid_figures(model.shape)
    assert valid and kind == "TopAbs_SOLID"
    # The fit moves the surface by ≤ tolerance = 1e-6 diag, so the volume by ≤ area · 1e-6 diag:
    # ~1e-6 relative for these shapes.
    assert volume == pytest.approx(network_volume(network), rel=1e-6)
    uv = np.random.default_rng(4).random((16, 2))
    expected = network.patches.evaluate(uv)
    for patch, face in enumerate(matched_faces(model, network)):
        assert (
            np.linalg.norm(model.faces[face].evaluate(uv) - expected[patch], axis=-1).max()
            <= 1.5 * result.fit_tolerance
        )


@pytest.mark.slow
@requires_ocp
@pytest.mark.parametrize("name", ["catmark_cube", "spot"])
def test_split4_step_export_is_the_surface_itself(
    name: str, request: pytest.FixtureRequest, tmp_path: Path
) -> None:
    """Polynomial exact G1 (split4) survives STEP exactly: OCC's own normals agree across faces."""
    from g1patch.build import build_split4_network

    network = build_split4_network(CLOSED[name](request.getfixturevalue("shared_data")))
    diagonal = network.bounding_box_diagonal()
    result = export_step(tmp_path / f"{name}.step", network)
    # one face per cage quad (its four pieces as one B-spline), an exact, valid solid
    assert (
        result.faces == len(network.patches) // 4 and result.exact and result.solid and result.valid
    )
    assert result.free_edges == 0
    # OCC evaluates D1 in double precision from the file's poles: its angles sit at rounding level
    assert result.max_g1_angle_deg <= 1e-7
    model = read_step_faces(result.path)
    middles = np.concatenate([face.evaluate(np.array([[0.5, 0.5]])) for face in model.faces])
    distance, order = cKDTree(middles).query(
        network.patches.evaluate(np.array([[1.0, 1.0]]))[::4, 0]
    )
    assert distance.max() <= 1e-9 * diagonal and len(set(order.tolist())) == result.faces
    uv = np.random.default_rng(5).random((8, 2))
    quarter = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    worst = max(
        float(
            np.abs(
                model.faces[i].evaluate(0.5 * (uv + quarter[k]))
                - network.patches.take([4 * f + k]).evaluate(uv)[0]
            ).max()
        )
        for f, i in enumerate(order.tolist())
        for k in range(4)
    )
    assert worst <= 1e-12 * diagonal


@requires_ocp
def test_open_networks_export_as_shells(shared_data: Path, tmp_path: Path) -> None:
    disks = build_corner_network(read_mesh(shared_data / "catmark_xord_interior.obj"))
    result = export_step(tmp_path / "disks.step", disks)
    assert not result.solid and result.volume is None and result.valid
    assert result.free_edges == len(disks.open_edges()[0])
    model = read_step_faces(result.path)
    assert len(model.faces) == len(disks.patches)


@requires_ocp
def test_patch_sets_export_through_their_shared_control_points(
    shared_data: Path, tmp_path: Path
) -> None:
    teapot = read_bpt(shared_data / "teapot.bpt")
    result = export_step(tmp_path / "teapot.step", teapot)
    assert result.faces == len(teapot) and result.exact
    report = check(network_from_patch_points(teapot))
    assert result.max_g1_angle_deg == pytest.approx(report.max_edge_angle_deg, abs=1e-6)
    assert len(read_step_faces(result.path).faces) == len(teapot)


# ------------------------------------------------------------------------------------------------
# bad input


@pytest.mark.parametrize("name", ["out.obj", "out.stl", "out", "out.step.tmp"])
def test_unsupported_extension_writes_nothing(name: str, tmp_path: Path) -> None:
    with pytest.raises(FormatError, match="unsupported extension"):
        export_cad(tmp_path / name, build_corner_network(shapes.cube()))
    assert list(tmp_path.iterdir()) == []


def test_extension_must_match_the_format(tmp_path: Path) -> None:
    network = build_corner_network(shapes.cube())
    with pytest.raises(FormatError, match=r"\.step"):
        export_step(tmp_path / "cube.igs", network)
    with pytest.raises(FormatError, match=r"\.iges"):
        export_iges(tmp_path / "cube.step", network)
    assert list(tmp_path.iterdir()) == []


def test_missing_ocp_is_one_clear_error_before_writing(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    monkeypatch.setitem(sys.modules, "OCP", None)  # `import OCP` now raises ImportError
    network = build_corner_network(shapes.cube())
    for export, name in ((export_step, "cube.step"), (export_iges, "cube.iges")):
        with pytest.raises(MissingDependencyError, match=r"pip install 'g1patch\[cad\]'"):
            export(tmp_path / name, network)
    with pytest.raises(MissingDependencyError, match="cad"):
        read_step_faces(tmp_path / "cube.step")
    assert list(tmp_path.iterdir()) == []


@requires_ocp
def test_a_failing_writer_leaves_no_file(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    def half_written(occ: object, shape: object, path: Path, kind: str) -> None:
        path.write_text("ISO-10303-21;\nHEADER;\n")
        raise OSError("disk full")

    monkeypatch.setattr(cad_export, "_write", half_written)
    with pytest.raises(OSError, match="disk full"):
        export_step(tmp_path / "cube.step", build_corner_network(shapes.cube()))
    assert list(tmp_path.iterdir()) == []


@requires_ocp
def test_reading_bad_files_raises_format_errors(tmp_path: Path) -> None:
    with pytest.raises(FormatError, match="no such file"):
        read_step_faces(tmp_path / "missing.step")
    garbage = tmp_path / "garbage.step"
    garbage.write_text("this is not STEP\n")
    with pytest.raises(FormatError, match="garbage.step"):
        read_step_faces(garbage)
    with pytest.raises(FormatError, match="unsupported extension"):
        read_step_faces(tmp_path / "cube.obj")
    with pytest.raises(FormatError, match="STEP"):
        read_step_faces(tmp_path / "cube.iges")


def test_export_rejects_what_is_not_a_network(tmp_path: Path) -> None:
    if not HAVE_OCP:
        pytest.skip("OCP is not installed (extra 'cad')")
    with pytest.raises(InputError, match="network"):
        export_step(tmp_path / "x.step", np.zeros((1, 4, 4, 3)))  # type: ignore[arg-type]
    with pytest.raises(InputError, match="g1_samples"):
        export_step(tmp_path / "x.step", build_corner_network(shapes.cube()), g1_samples=1)
    assert list(tmp_path.iterdir()) == []
