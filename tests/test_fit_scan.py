"""What the fit takes from a scan: only the vertices its triangles use, and points inside its
large facets (:meth:`~g1patch.fitting.Scan.facet_samples`), so that a low-poly model is fitted to
its surface and not to a handful of corners."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from g1patch.fitting import (
    Scan,
    fit_network,
    holes_filled,
    manifold,
    oriented,
    used_only,
    without_islands,
)
from g1patch.fitting.scan_topology import boundary_edges, orientation_flips
from g1patch.shapes import bump_sphere_scan, cube

#: a triangle's corners: coordinates in a box of side 20, not all three collinear (checked)
corner_sets = arrays(np.float64, (3, 3), elements=st.floats(-10.0, 10.0, allow_nan=False))


def cube_triangles() -> Scan:
    """The cube [-1, 1]³ as 12 triangles (each quad cut along its diagonal 0–2), 8 vertices."""
    mesh = cube()
    quads = mesh.faces
    triangles = np.concatenate([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]])
    return Scan(np.asarray(mesh.vertices, dtype=np.float64), triangles, "cube.obj")


def test_vertices_no_triangle_uses_are_dropped_and_said() -> None:
    scan = cube_triangles()
    stray = np.array([[50.0, 50.0, 50.0], [-7.0, 0.0, 0.0]])
    padded = Scan(np.concatenate([stray[:1], scan.points, stray[1:]]), scan.triangles + 1, "c")
    kept = used_only(padded)
    np.testing.assert_array_equal(kept.points, scan.points)
    np.testing.assert_array_equal(kept.triangles, scan.triangles)
    assert kept.repairs == ("dropped 2 vertices no triangle uses",)
    assert used_only(scan) is scan


def test_specks_of_a_range_scan_are_dropped_and_said() -> None:
    """Parts narrower than 5 % of the scan's diagonal go (a range scan's specks); parts as large as
    the rest stay, and a scan of specks only is kept whole."""
    cube = cube_triangles()
    speck = Scan(cube.points * 0.01 + 0.5, cube.triangles)  # 0.02 across: 0.6 % of the diagonal
    twin = Scan(cube.points + 3.0, cube.triangles)
    joined = Scan(
        np.concatenate([cube.points, speck.points, twin.points]),
        np.concatenate([cube.triangles, speck.triangles + 8, twin.triangles + 16]),
        "scan.ply",
    )
    kept = without_islands(joined)
    np.testing.assert_array_equal(kept.points, np.concatenate([cube.points, twin.points]))
    np.testing.assert_array_equal(
        kept.triangles, np.concatenate([cube.triangles, cube.triangles + 8])
    )
    assert kept.repairs == ("dropped 1 island under 5% of the diagonal across (12 triangles)",)
    assert without_islands(speck) is speck and without_islands(cube) is cube


@settings(max_examples=60, deadline=None)
@given(corners=corner_sets, per_side=st.integers(1, 6))
def test_facet_samples_are_inside_evenly_spread_and_centred(
    corners: np.ndarray, per_side: int
) -> None:
    """m² samples (m = ⌊√(A / area)⌋) strictly inside, at the centroids of m² equal triangles: so
    their mean is the triangle's centroid, exactly up to rounding, and their normals its own."""
    scan = Scan(corners, np.array([[0, 1, 2]]))
    area = float(scan.areas[0])
    cross = np.cross(corners[1] - corners[0], corners[2] - corners[0])
    if area <= 1e-6 * float(np.sum((corners - corners.mean(axis=0)) ** 2)):
        return  # (near) collinear: no usable normal to compare with
    samples, normals = scan.facet_samples(area / per_side**2 * (1 - 1e-9))
    assert len(samples) == per_side**2
    scale = float(np.abs(corners).max()) + 1.0
    np.testing.assert_allclose(samples.mean(axis=0), corners.mean(axis=0), atol=1e-13 * scale)
    np.testing.assert_allclose(normals, np.tile(cross / np.linalg.norm(cross), (len(samples), 1)))
    # barycentric coordinates of every sample: all at least 1/(3m) (centroids of the small ones)
    edges = np.stack([corners[1] - corners[0], corners[2] - corners[0]], axis=1)
    uv = np.linalg.lstsq(edges, (samples - corners[0]).T, rcond=None)[0].T
    weights = np.column_stack([1.0 - uv.sum(axis=1), uv])
    assert weights.min() >= 1.0 / (3 * per_side) - 1e-9


def test_small_facets_are_not_sampled() -> None:
    """A triangle smaller than ``area``, or than ``least``, keeps only its vertices (a dense scan
    is its points)."""
    scan = cube_triangles()
    largest = float(scan.areas.max())
    for area, least in ((largest * 1.01, 0.0), (largest / 100, largest * 1.01)):
        samples, normals = scan.facet_samples(area, least)
        assert samples.shape == (0, 3) and normals.shape == (0, 3)
    assert len(scan.facet_samples(largest / 100, largest)[0]) == 12 * 10**2


def test_a_low_poly_cube_is_fitted_flat() -> None:
    """Twelve triangles: fitted to its eight corners alone the sides bowed out 4.1 % of the
    diagonal; fitted to its facets too, within the tolerance, every crease kept."""
    pytest.importorskip(
        "pynanoinstantmeshes", reason="the fit's remesher: pip install 'g1patch[fit]'"
    )
    _, report = fit_network(cube_triangles(), tolerance=2e-3)
    assert report.met, report.summary()
    assert report.to_scan[0] / report.diagonal <= 2e-3
    assert report.creases == 24


def test_the_folded_faces_and_a_ring_round_them_are_stiffened() -> None:
    """A folded patch of split4 (four a face, face after face) stiffens its face's vertices and
    the ring of faces round it by FOLD_STIFFNESS, compounding over refits, and nothing else."""
    from g1patch.build import build_network
    from g1patch.fitting import FOLD_STIFFNESS, _stiffened
    from g1patch.shapes import grid

    layout = grid(6, 6)
    network = build_network(layout, "split4", "limit", tolerance=None)
    folded = np.zeros(network.n_patches, dtype=bool)
    middle = 2 * 6 + 2  # face (2, 2) of the 6 × 6 grid of faces
    folded[4 * middle + 3] = True
    once = _stiffened(layout, network, folded, None)
    near = np.unique(
        layout.faces[
            [
                middle - 7,
                middle - 6,
                middle - 5,
                middle - 1,
                middle,
                middle + 1,
                middle + 5,
                middle + 6,
                middle + 7,
            ]
        ]
    )
    assert set(np.flatnonzero(once > 1.0)) == set(near.tolist())
    assert np.all(once[near] == FOLD_STIFFNESS)
    twice = _stiffened(layout, network, folded, once)
    assert np.all(twice[near] == FOLD_STIFFNESS**2) and np.all(twice[once == 1.0] == 1.0)


@pytest.mark.slow
def test_the_teapot_s_triangles_fit_without_a_fold(shared_data) -> None:
    """Newell's teapot as 6,320 triangles (thin handle and spout, a curled rim): its 3,073-quad
    fit folded 3 patches at the handle; fitted again fairer where it folds, none (the distance
    stays off the tolerance: the rim lip is finer than the face budget)."""
    from g1patch.fitting import scan_from_polygons
    from g1patch.io.meshfile import read_polygons

    path = shared_data / "teapot_triangulated.obj"
    _, report = fit_network(scan_from_polygons(*read_polygons(path), str(path)), tolerance=2e-3)
    assert report.folds == 0


@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), share=st.floats(0.0, 1.0))
def test_a_scan_s_winding_is_made_consistent(seed: int, share: float) -> None:
    """Any set of a sphere scan's triangles reversed (two copies, apart: two parts) is found
    again: in each part the fewer way round is turned back (a half-and-half part either way)."""
    points, triangles = bump_sphere_scan(400, height=0.0)
    flip = np.random.default_rng(seed).random(2 * len(triangles)) < share
    both = np.concatenate([triangles, triangles + len(points)])
    mixed = np.where(flip[:, None], both[:, ::-1], both)
    found = orientation_flips(mixed, 2 * len(points))
    for part in (slice(0, len(triangles)), slice(len(triangles), None)):
        turned = found[part]
        assert np.array_equal(turned, flip[part]) or np.array_equal(turned, ~flip[part])
        assert turned.sum() <= len(triangles) / 2  # the fewer way round


def test_an_edge_of_three_triangles_joins_nothing() -> None:
    """A fin (a third triangle on a sphere scan's edge, run the same way as one of the two): no
    error, the sphere stays as it was, and the fin is a part of its own (never turned). A lone
    triangle is a part of its own; of two that run their common edge the same way, the second
    is turned (a tie: the later one)."""
    points, triangles = bump_sphere_scan(200, height=0.0)
    a, b = triangles[0, :2]
    fin = np.concatenate([triangles, [[a, b, len(points)]]])
    assert not orientation_flips(fin, len(points) + 1).any()
    assert not orientation_flips(np.array([[0, 1, 2]]), 3).any()  # a lone triangle: no tree edge
    assert orientation_flips(np.array([[0, 1, 2], [1, 2, 3]]), 4).tolist() == [False, True]


def test_a_scan_wound_every_which_way_fits_after_its_repair() -> None:
    """Every other triangle of a sphere scan reversed (an STL file's winding: the normals
    cancelled, every edge looked sharp, 35 folded patches and G1 18° before the repair): turned
    back with a note, it fits within the tolerance, no fold, no crease."""
    points, triangles = bump_sphere_scan(2000, height=0.0)
    triangles[::2] = triangles[::2, ::-1]
    scan = Scan(points, triangles, "mixed.stl")
    repaired = oriented(scan)
    assert repaired.repairs == ("turned 1998 triangles over to agree with their neighbours",)
    _, report = fit_network(scan, tolerance=2e-3)
    assert report.met and report.folds == 0 and report.creases == 0
    assert "turned 1998 triangles over" in " ".join(report.repairs)


def test_holes_under_a_layout_edge_are_filled() -> None:
    """A sphere scan without 10 triangles apart (one-triangle holes) and without a cap of
    polar angle 0.35 rad: each small hole gets a centre vertex and a fan of 3 triangles wound as
    its neighbours (no open edge left there, every edge of two triangles run both ways), the cap
    (wider than ``across``) stays open; a scan with no hole is returned as it is."""
    points, triangles = bump_sphere_scan(2000, height=0.0)
    centre = points[triangles].mean(axis=1)
    cap = centre[:, 2] > np.cos(0.35)
    apart = np.flatnonzero(~cap)[:: len(triangles) // 10][:10]
    kept = np.ones(len(triangles), dtype=bool)
    kept[apart] = False
    holed = Scan(points, triangles[kept & ~cap], "holed.obj")
    rim = len(boundary_edges(holed.triangles)) - 3 * len(apart)
    filled = holes_filled(holed, across=0.2)
    assert filled.repairs == ("filled 10 holes under a layout edge (0.2) across with 30 triangles",)
    assert len(filled.points) == len(points) + 10 and len(boundary_edges(filled.triangles)) == rim
    assert not orientation_flips(filled.triangles, len(filled.points)).any()
    np.testing.assert_allclose(  # each centre at its hole's corners' mean, near the sphere
        np.linalg.norm(filled.points[len(points) :], axis=1), 1.0, atol=0.02
    )
    whole = Scan(points, triangles)
    assert holes_filled(whole, across=0.2) is whole


def test_a_scan_with_small_holes_fits_within_the_tolerance() -> None:
    """The surface closes a hole under a layout edge; without the fill its surface lay the
    hole's radius from the scan's triangles (a sphere scan with one-triangle holes: 5.7e-3 of
    the diagonal, the tolerance 2e-3)."""
    points, triangles = bump_sphere_scan(2000, height=0.0)
    kept = np.ones(len(triangles), dtype=bool)
    kept[:: len(triangles) // 10] = False
    _, report = fit_network(Scan(points, triangles[kept], "holed.obj"), tolerance=2e-3)
    assert report.met and report.folds == 0
    assert any(note.startswith("filled ") for note in report.repairs)


def test_an_edge_of_more_than_two_triangles_keeps_the_two_joined_best() -> None:
    """A fin on a sphere scan's edge (a third triangle there, its other edges open): the fin
    goes, with its apex (the two sphere triangles there are joined on both other edges, it on
    none), and the sphere stays whole; a manifold scan is returned as it is."""
    points, triangles = bump_sphere_scan(200, height=0.0)
    a, b = triangles[0, :2]
    fin = Scan(
        np.concatenate([points, [[0.0, 0.0, 3.0]]]),
        np.concatenate([triangles, [[a, b, len(points)]]]),
    )
    kept = manifold(fin)
    assert kept.repairs == (
        "dropped 1 triangles at edges of more than two",
        "dropped 1 vertices no triangle uses",
    )
    np.testing.assert_array_equal(kept.triangles, triangles)
    whole = Scan(points, triangles)
    assert manifold(whole) is whole


def test_a_layout_face_of_almost_no_area_does_not_multiply_the_samples() -> None:
    """The facets nearest a layout face of almost no area are sampled as at a sixteenth of the
    layout's mean face (a flattened sphere: a million samples, minutes, where now seconds)."""
    from g1patch.fitting import SMALLEST_FACE, _sampled_areas
    from g1patch.mesh import QuadMesh

    scan = cube_triangles()
    quads = QuadMesh.from_arrays(
        np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [2, 0, 0], [2, 1e-6, 0]], float),
        [[0, 1, 2, 3], [1, 4, 5, 2]],
    )
    floor = SMALLEST_FACE * float(scan.areas.sum()) / 2  # 1/16 of the mean: 0.75
    areas = _sampled_areas(quads, scan)
    assert set(areas.tolist()) == {1.0, floor}  # the unit square's, and the sliver's floored


def test_the_surface_is_pulled_to_the_facets_between_the_vertices() -> None:
    """A coarse torus scan (16 × 8 quads cut in two) fitted on its own quads: fitted to its
    vertices alone, the limit surface bulges off the facets between them by their sag (0.099 of
    the model; 0.0024 the other way). The surface → scan rows (``two_way``) trade a little of
    one way for the other: the larger of the two maxima falls by a sixth (measured 0.083)."""
    from g1patch.compare import mesh_distance
    from g1patch.fitting.solve import fit_cage, grid_triangles, vertex_normals
    from g1patch.shapes import torus_quads
    from g1patch.subdivision import limit_grid_matrix

    layout = torus_quads(16, 8, 2.0, 0.7)
    points, quads = layout.vertices, layout.faces
    triangles = np.concatenate([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]])
    normals = vertex_normals(points, triangles)

    def two_way_maximum(two_way: float) -> tuple[float, float]:
        cage = fit_cage(points, normals, layout, triangles, two_way=two_way).cage
        limit, grid = limit_grid_matrix(cage, 3)
        surface = limit @ cage.vertices
        to_scan = float(mesh_distance(surface, points, triangles).max())
        to_surface = float(mesh_distance(points, surface, grid_triangles(grid)).max())
        return to_scan, to_surface

    one_way, both_ways = two_way_maximum(0.0), two_way_maximum(0.5)
    assert one_way[1] < 0.1 * one_way[0]  # the bulge: the surface → scan distance
    assert both_ways[1] < both_ways[0] < 0.9 * one_way[0]


def test_a_grid_point_is_pulled_only_to_a_facet_facing_its_way_and_near_it() -> None:
    """The surface → scan rows (``_surface_rows``) of a flat grid 0.08 above a scan facet that
    faces up, under a thin part's underside 0.02 above it that faces down (the part's other side):
    the points under the underside, nearer to it, are not pulled there (nor anywhere); the
    others go to their feet on the facet below, unless it is farther than the gate."""
    import scipy.sparse as sp

    from g1patch.compare import NearestTriangles
    from g1patch.fitting.solve import _surface_rows, _Triangles

    x, y = np.meshgrid(np.linspace(0.0, 1.0, 5), np.linspace(0.0, 1.0, 5), indexing="ij")
    grid_points = np.stack([x.ravel(), y.ravel(), np.full(x.size, 0.08)], axis=1)
    index = np.arange(25).reshape(5, 5)
    a, b, c, d = index[:-1, :-1], index[1:, :-1], index[1:, 1:], index[:-1, 1:]
    grid_triangles = np.concatenate([np.stack([a, b, c], -1), np.stack([a, c, d], -1)])
    surface = _Triangles(grid_points, grid_triangles.reshape(-1, 3))  # normals +z
    below = [[-1.0, -1.0, 0.0], [3.0, -1.0, 0.0], [-1.0, 3.0, 0.0]]  # faces +z
    underside = [[-0.1, -0.1, 0.1], [-0.1, 0.6, 0.1], [0.6, -0.1, 0.1]]  # faces −z
    points = np.array(below + underside)
    facets = points[np.array([[0, 1, 2], [3, 4, 5]])]
    scan = NearestTriangles(points, np.array([[0, 1, 2], [3, 4, 5]]))
    limit = sp.identity(25, format="csr")
    everything = np.arange(25)
    under = grid_points[:, 0] + grid_points[:, 1] <= 0.5 + 1e-12  # the underside's shadow
    rows, targets = _surface_rows(scan, facets, limit, surface, everything, 1.0, 1.0)
    assert (np.diff(rows.indptr) == 1).all()  # one grid point a row
    pulled = rows.indices
    np.testing.assert_array_equal(np.sort(pulled), everything[~under])
    np.testing.assert_allclose(targets[:, 2], 0.0, atol=1e-15)
    np.testing.assert_allclose(targets[:, :2], grid_points[pulled, :2], atol=1e-15)
    rows, targets = _surface_rows(scan, facets, limit, surface, everything, 1.0, 0.05)
    assert rows.shape[0] == 0  # the facet below is 0.08 away: beyond the gate
