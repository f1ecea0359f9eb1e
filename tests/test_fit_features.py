"""A scan's sharp features carried onto a quad layout (``g1patch.fitting.features``): which layout
edges become creases, and how a chain's gap is bridged. No remesher needed: the layouts here are
made by hand."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from g1patch.fitting.features import (
    SNAP_KEEP_AREA,
    boundary_corners,
    layout_corners,
    layout_creases,
    quad_areas,
    sharp_segments,
    snap_to_features,
    without_lonely_creases,
)
from g1patch.mesh import INFINITE_SHARPNESS, QuadMesh, Tag
from g1patch.shapes import cube_sphere


def roof(n: int = 8, lift: float = 0.0) -> QuadMesh:
    """A quad grid folded by 90° along its middle line x = 0 (a roof ridge, n + 1 vertices long),
    the ridge vertex in the middle moved off the ridge by ``lift`` edge lengths."""
    x = np.arange(-4, 5) / 4.0
    y = np.arange(n + 1) / 4.0
    gx, gy = np.meshgrid(x, y, indexing="ij")
    points = np.stack([gx, gy, -np.abs(gx)], axis=-1)
    points[4, n // 2, 0] += lift / 4.0
    index = np.arange(gx.size).reshape(gx.shape)
    quads = np.stack([index[:-1, :-1], index[1:, :-1], index[1:, 1:], index[:-1, 1:]], -1)
    return QuadMesh.from_arrays(points.reshape(-1, 3), quads.reshape(-1, 4))


def ridge_scan() -> tuple[np.ndarray, np.ndarray]:
    """The same roof finely triangulated (the scan): its ridge edges are its only sharp ones."""
    x = np.arange(-16, 17) / 16.0
    y = np.arange(33) / 16.0
    gx, gy = np.meshgrid(x, y, indexing="ij")
    points = np.stack([gx, gy, -np.abs(gx)], axis=-1).reshape(-1, 3)
    index = np.arange(gx.size).reshape(gx.shape)
    a, b, c, d = index[:-1, :-1], index[1:, :-1], index[1:, 1:], index[:-1, 1:]
    triangles = np.concatenate([np.stack([a, b, c], -1), np.stack([a, c, d], -1)]).reshape(-1, 3)
    return points, triangles


def ridge_edges(layout: QuadMesh) -> set[tuple[int, int]]:
    tagged = layout.features.edge_sharpness > 0
    return {tuple(sorted(edge)) for edge in layout.topology.edges[tagged].tolist()}


def test_the_ridge_is_sharp_and_nothing_else() -> None:
    points, triangles = ridge_scan()
    segments = sharp_segments(points, triangles, 60.0)
    assert len(segments) == 32 and np.allclose(segments[..., 0], 0.0)
    layout = roof()
    tagged = layout_creases(layout, segments)
    ridge = {tuple(sorted((4 * 9 + j, 4 * 9 + j + 1))) for j in range(8)}
    assert ridge_edges(tagged) == ridge
    assert sharp_segments(points, triangles, 100.0).shape == (0, 2, 3)
    assert layout_creases(layout, np.zeros((0, 2, 3))) is layout


def test_a_gap_in_the_chain_is_bridged() -> None:
    """The middle ridge vertex a quarter edge off the ridge: its two edges miss the strict test
    (samples within 15 % of the edge length), the chain ends on both sides, and the bridge tags
    them (within 40 %), so the crease runs the whole ridge."""
    points, triangles = ridge_scan()
    layout = roof(lift=0.25)
    tagged = layout_creases(layout, sharp_segments(points, triangles, 60.0))
    ridge = {tuple(sorted((4 * 9 + j, 4 * 9 + j + 1))) for j in range(8)}
    assert ridge_edges(tagged) == ridge
    far = roof(lift=0.6)  # too far off: the chain keeps its gap
    kept = ridge_edges(layout_creases(far, sharp_segments(points, triangles, 60.0)))
    assert kept < ridge and len(kept) == 6


def test_vertices_near_a_feature_are_snapped_onto_it() -> None:
    """The whole ridge row lifted 0.2 of an edge off the ridge (the remesher's row beside the
    L-bracket's concave edge: 0.16 off, no edge tagged, the fit rounded it): snapped onto the
    ridge, every ridge edge is a crease, and the vertex at a given corner is tagged a corner;
    rows farther off (the next ones, a whole edge) stay. A corner with no crease at its vertex
    is no corner."""
    points, triangles = ridge_scan()
    segments = sharp_segments(points, triangles, 60.0)
    layout = roof()
    lifted = layout.vertices.copy()
    lifted[4 * 9 : 5 * 9, 0] += 0.2 / 4.0
    far = QuadMesh.from_arrays(lifted, layout.faces)
    assert not ridge_edges(layout_creases(far, segments))
    corner = np.array([[0.0, 0.5, 0.0]])  # ridge vertex 4 * 9 + 2, lifted
    snapped = snap_to_features(far, segments, corner)
    ridge = {tuple(sorted((4 * 9 + j, 4 * 9 + j + 1))) for j in range(8)}
    tagged = layout_creases(snapped, segments, corner)
    assert ridge_edges(tagged) == ridge
    assert np.allclose(snapped.vertices[4 * 9 : 5 * 9, 0], 0.0)
    assert np.allclose(snapped.vertices[:36], layout.vertices[:36])  # the other rows stay
    assert np.flatnonzero(tagged.features.vertex_sharpness).tolist() == [4 * 9 + 2]
    off = np.array([[0.25, 0.5, -0.25]])  # a corner the remesher's vertex there has no crease to
    tagged = layout_creases(snap_to_features(far, segments, off), segments, off)
    assert not tagged.features.vertex_sharpness.any()
    assert snap_to_features(far, np.zeros((0, 2, 3)), corner) is far


def test_a_snap_that_would_crush_a_face_is_undone() -> None:
    """A row of thin quads (0.2 high) along a straight feature line 0.1 from both its sides:
    every one of its vertices is near enough to snap, which would leave those faces no area
    (pyvista's ant: its layout refused). Their snaps are undone; a vertex of the next row, near
    the line too, snaps and leaves its face most of its area."""
    x = np.arange(8.0)
    rows = np.array([0.0, 0.2, 1.2, 2.2])
    gx, gy = np.meshgrid(x, rows, indexing="ij")
    points = np.stack([gx, gy, np.zeros_like(gx)], -1).reshape(-1, 3)
    index = np.arange(gx.size).reshape(gx.shape)
    quads = np.stack([index[:-1, :-1], index[1:, :-1], index[1:, 1:], index[:-1, 1:]], -1)
    layout = QuadMesh.from_arrays(points, quads.reshape(-1, 4))
    t = np.linspace(-2.0, 9.0, 111)  # short segments along y = 0.1, as a scan's sharp edges are
    line = np.stack([t, np.full_like(t, 0.1), np.zeros_like(t)], -1)
    segments = np.stack([line[:-1], line[1:]], axis=1)
    snapped = snap_to_features(layout, segments, np.zeros((0, 3)))  # no zero-area error
    areas = quad_areas(snapped.vertices, snapped.faces)
    assert areas.min() >= SNAP_KEEP_AREA * quad_areas(layout.vertices, layout.faces).min()
    assert np.array_equal(snapped.vertices[index[:, :2].ravel()], points[index[:, :2].ravel()])


def test_the_gaps_left_in_the_feature_lines_are_measured() -> None:
    """``crease_gaps``: the share of the feature lines no crease follows. The whole ridge
    tagged: none. Its middle vertex too far off to bridge: the two ridge edges there, 2 of 8,
    less a quarter of an edge at both ends of the gap (within ``GAP_REACH`` of the creases
    that remain): (2 − 0.5) / 8 of the ridge; a layout with no crease at all: all of it."""
    from g1patch.fitting.features import crease_gaps

    points, triangles = ridge_scan()
    segments = sharp_segments(points, triangles, 60.0)
    assert crease_gaps(layout_creases(roof(), segments), segments) == 0.0
    gapped = layout_creases(roof(lift=0.6), segments)
    assert crease_gaps(gapped, segments) == 1.5 / 8
    assert crease_gaps(roof(), segments) == 1.0
    assert crease_gaps(roof(), np.zeros((0, 2, 3))) == 0.0


def test_a_layout_file_keeps_its_own_creases(tmp_path: Path) -> None:
    """``--layout`` with OpenSubdiv crease tags: the file's creases are the cage's even with the
    scan's feature detection off, and merged vertices carry them (the ridge row written twice,
    once per side, as a remesher's or a modeller's export may)."""
    import g1patch
    from g1patch.io.meshfile import write_triangles

    points, triangles = ridge_scan()
    write_triangles(tmp_path / "roof.obj", points, triangles)
    layout = roof()
    ridge = [4 * 9 + j for j in range(9)]
    vertices = np.concatenate([layout.vertices, layout.vertices[ridge]])
    faces = layout.faces.copy()
    right = np.isin(faces, ridge) & (layout.vertices[faces][..., 0] > -1e-12).all(axis=-1)[:, None]
    faces[right] = len(layout.vertices) + np.searchsorted(ridge, faces[right])  # a second copy
    lines = [f"v {x!r} {y!r} {z!r}" for x, y, z in vertices.tolist()]
    lines += ["f " + " ".join(str(i + 1) for i in face) for face in faces.tolist()]
    pairs = [(ridge[j], ridge[j + 1]) for j in range(8)]
    lines.append(f"t crease {2 * len(pairs)}/1/0 " + " ".join(f"{a} {b}" for a, b in pairs) + " 10")
    (tmp_path / "layout.obj").write_text("\n".join(lines) + "\n")
    result = g1patch.fit(tmp_path / "roof.obj", layout=tmp_path / "layout.obj", sharp_angle=None)
    assert result.report.creases == 8
    plain = g1patch.fit(tmp_path / "roof.obj", layout=layout, sharp_angle=None)
    assert plain.report.creases == 0


def test_a_layout_file_with_a_bad_tag_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A ``--layout`` file whose crease names a vertex it does not have: exit 2, one line
    naming the file, no output written."""
    from g1patch.cli import main
    from g1patch.io.meshfile import write_triangles

    points, triangles = ridge_scan()
    write_triangles(tmp_path / "roof.obj", points, triangles)
    layout = roof()
    lines = [f"v {x!r} {y!r} {z!r}" for x, y, z in layout.vertices.tolist()]
    lines += ["f " + " ".join(str(i + 1) for i in face) for face in layout.faces.tolist()]
    lines.append("t crease 2/1/0 0 999 10")
    (tmp_path / "bad.obj").write_text("\n".join(lines) + "\n")
    out = tmp_path / "out.npz"
    code = main(
        [
            "fit",
            str(tmp_path / "roof.obj"),
            "-o",
            str(out),
            "--layout",
            str(tmp_path / "bad.obj"),
            "-q",
        ]
    )
    assert code == 2 and not out.exists()
    error = capsys.readouterr().err.strip().splitlines()
    assert len(error) == 1 and "bad.obj: tag 'crease' names vertex 999" in error[0]


def flat_square(cells: int = 32, zigzag: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """A triangulated unit square in z = 0 whose rim vertices (but its four corners) are pushed
    in and out along the rim's normal by ``zigzag`` of a cell, alternately: a scanned rim."""
    x = np.arange(cells + 1) / cells
    gx, gy = np.meshgrid(x, x, indexing="ij")
    points = np.stack([gx, gy, np.zeros_like(gx)], axis=-1)
    sign = (-1.0) ** np.arange(cells + 1)
    shift = zigzag / cells * sign[1:-1]
    points[0, 1:-1, 0] += shift
    points[-1, 1:-1, 0] += shift
    points[1:-1, 0, 1] += shift
    points[1:-1, -1, 1] += shift
    index = np.arange(gx.size).reshape(gx.shape)
    a, b, c, d = index[:-1, :-1], index[1:, :-1], index[1:, 1:], index[:-1, 1:]
    triangles = np.concatenate([np.stack([a, b, c], -1), np.stack([a, c, d], -1)]).reshape(-1, 3)
    return points.reshape(-1, 3), triangles


def test_a_rim_s_corners_are_its_turns_at_the_layout_s_scale() -> None:
    """A square's four corners are corners at any scale; a rim zigzagging by 0.4 of a scan
    edge (turns of about 77° from edge to edge, a scanned rim) has no others at a layout edge of
    four scan edges, and the square's corners stay, each within a scan edge (and the zigzag)."""
    corners = np.array([[0.0, 0.0], [0.0, 1.0], [1.0, 0.0], [1.0, 1.0]])
    for zigzag in (0.0, 0.4):
        points, triangles = flat_square(zigzag=zigzag)
        for reach in (1 / 32, 4 / 32, 0.25):
            found = boundary_corners(points, triangles, 60.0, reach)
            if zigzag and reach < 2 / 32:
                assert len(found) > 4  # at a scan edge's scale the zigzag turns
                continue
            gap = np.linalg.norm(found[:, None, :2] - corners, axis=-1)
            assert len(found) == 4 and (gap.min(axis=0) <= 1.5 / 32).all(), (zigzag, reach)


def test_a_corner_on_a_hole_the_layout_bridges_is_not_tied_to_it() -> None:
    """A scan corner farther than a boundary edge of the layout from the layout's boundary (on a
    hole the layout spans) moves and tags nothing; one on its rim is tied to its nearest vertex."""
    layout = roof()
    inside = np.array([[0.0, 1.0, 0.0]])  # the ridge's middle: two edges from the rim
    assert layout_corners(layout, inside) is layout
    on_rim = np.array([[-1.0, 0.02, -1.0]])
    tied = layout_corners(layout, np.concatenate([inside, on_rim]))
    assert np.flatnonzero(tied.features.vertex_sharpness).tolist() == [0]
    assert np.allclose(tied.vertices[0], on_rim[0])
    assert np.allclose(np.delete(tied.vertices, 0, axis=0), np.delete(layout.vertices, 0, axis=0))


def test_a_long_sharp_edge_is_matched_in_pieces() -> None:
    """A CAD part's sharp edge may be one scan edge across a whole side (a sliver's): the ridge
    as one segment tags the same layout edges as the ridge in 32, and snaps and counts gaps the
    same. Its pieces are in order along it, no longer than PIECE of the median layout edge, and
    keep its ends exactly (chains meet there)."""
    from g1patch.fitting.features import PIECE, _pieces, crease_gaps, median_edge

    points, triangles = ridge_scan()
    short = sharp_segments(points, triangles, 60.0)
    whole = np.array([[short[0, 0], short[-1, 1]]])
    assert np.allclose(whole, [[[0.0, 0.0, 0.0], [0.0, 2.0, 0.0]]])
    layout = roof()
    assert ridge_edges(layout_creases(layout, whole)) == ridge_edges(layout_creases(layout, short))
    lifted = roof(lift=0.25)
    assert np.array_equal(
        snap_to_features(lifted, whole, np.zeros((0, 3))).vertices,
        snap_to_features(lifted, short, np.zeros((0, 3))).vertices,
    )
    assert crease_gaps(layout_creases(layout, whole), whole) == 0.0
    ends = layout.vertices[layout.topology.edges]
    median = float(np.median(np.linalg.norm(ends[:, 1] - ends[:, 0], axis=1)))
    assert median_edge(layout) == median
    pieces = _pieces(np.concatenate([whole, short[:3]]), median)
    longest = PIECE * median
    n = int(np.ceil(2.0 / longest))  # the 2-long ridge in n pieces; the 1/16-long kept whole
    assert len(pieces) == n + 3 and 0.0625 < longest
    assert np.linalg.norm(pieces[:, 1] - pieces[:, 0], axis=1).max() <= longest
    assert np.array_equal(pieces[0, 0], whole[0, 0]) and np.array_equal(
        pieces[n - 1, 1], whole[0, 1]
    )
    assert np.array_equal(pieces[1:n, 0], pieces[: n - 1, 1])  # in order, end to start
    assert np.array_equal(pieces[n:], short[:3])


def test_a_lonely_crease_edge_is_left_smooth_as_split4_builds_it() -> None:
    """split4 builds an isolated crease edge between two darts smooth, so the fit's layout drops
    its tag; a chain of two edges (its middle vertex cut in two sectors) keeps its tags."""
    sphere = cube_sphere(3)
    topology, points = sphere.topology, sphere.vertices
    ordinary = np.flatnonzero(topology.valence == 4)
    lonely = np.flatnonzero(~np.isin(topology.edges, np.flatnonzero(topology.valence != 4)).any(1))[
        0
    ]
    middle = ordinary[
        np.argmax(np.linalg.norm(points[ordinary] - points[topology.edges[lonely]].mean(0), axis=1))
    ]
    ring = np.flatnonzero((topology.edges == middle).any(axis=1))
    others = topology.edges[ring][topology.edges[ring] != middle]
    first = int(np.argmin((points[others] - points[middle]) @ (points[others[0]] - points[middle])))
    chain = ring[[0, first]]
    pairs = topology.edges[np.concatenate([[lonely], chain])]
    tagged = QuadMesh(
        points, topology, (Tag("crease", tuple(pairs.ravel().tolist()), (INFINITE_SHARPNESS,)),)
    )
    kept = without_lonely_creases(tagged)
    assert ridge_edges(kept) == {tuple(sorted(edge)) for edge in topology.edges[chain].tolist()}
    assert without_lonely_creases(kept) is kept
