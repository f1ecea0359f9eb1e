"""Generated quad meshes for tests, demos and benchmarks; every face counter-clockwise seen from
outside.

All shapes are built with vectorised NumPy and validated through :meth:`QuadMesh.from_arrays`.
Planar shapes lie in z = 0 and face +z. :func:`subdivide` (one Catmull–Clark topology step with
linear positions) lives in :mod:`g1patch.mesh`, beside the splitting of non-quad faces it shares.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from itertools import combinations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .errors import InputError, as_float_array
from .mesh import QuadMesh, refine_polygons, subdivide

__all__ = [
    "cube",
    "cube_sphere",
    "grid",
    "strip",
    "torus",
    "large_torus",
    "fan",
    "boundary_fan",
    "genus2",
    "voxel_surface",
    "subdivide",
    "sphere_quads",
    "ellipsoid_quads",
    "torus_quads",
    "icosa_ellipsoid",
    "box_cage",
    "thin_slab",
    "noisy_sphere",
    "flat_fan",
    "bump_sphere_scan",
    "sphere_project",
    "ellipsoid_project",
    "torus_project",
]

HeightFunction = Callable[[NDArray[np.float64], NDArray[np.float64]], NDArray[np.float64]]
FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]


def _check_count(name: str, value: int, least: int) -> int:
    if int(value) != value or value < least:
        raise InputError(f"{name}: expected an integer >= {least}, got {value!r}")
    return int(value)


def cube() -> QuadMesh:
    """The cube [-1, 1]^3: 8 vertices (vertex ``4 x + 2 y + z`` for x, y, z ∈ {0, 1}), 6 outward
    quads."""
    bits = (np.arange(8)[:, None] >> np.array([2, 1, 0])) & 1
    faces = [
        [0, 1, 3, 2],  # x = -1
        [4, 6, 7, 5],  # x = +1
        [0, 4, 5, 1],  # y = -1
        [2, 3, 7, 6],  # y = +1
        [0, 2, 6, 4],  # z = -1
        [1, 5, 7, 3],  # z = +1
    ]
    return QuadMesh.from_arrays(2.0 * bits - 1.0, faces, strict=True)


def cube_sphere(level: int) -> QuadMesh:
    """The cube refined ``level`` times (6·4^level quads), vertices projected to the unit sphere."""
    mesh = cube()
    for _ in range(_check_count("level", level, 0)):
        mesh = subdivide(mesh)
    return mesh.with_vertices(mesh.vertices / np.linalg.norm(mesh.vertices, axis=1, keepdims=True))


def grid(
    nx: int,
    ny: int,
    *,
    size: tuple[float, float] = (1.0, 1.0),
    height: HeightFunction | None = None,
) -> QuadMesh:
    """An open nx × ny grid over [0, size_x] × [0, size_y].

    Vertex ``j (nx + 1) + i`` sits at (x_i, y_j, height(x_i, y_j)); faces are counter-clockwise
    about +z.
    """
    nx, ny = _check_count("nx", nx, 1), _check_count("ny", ny, 1)
    x, y = np.meshgrid(np.linspace(0.0, size[0], nx + 1), np.linspace(0.0, size[1], ny + 1))
    z = np.zeros_like(x) if height is None else np.broadcast_to(height(x, y), x.shape)
    i, j = np.meshgrid(np.arange(nx), np.arange(ny))
    corner = (j * (nx + 1) + i).ravel()
    faces = np.stack([corner, corner + 1, corner + nx + 2, corner + nx + 1], axis=1)
    return QuadMesh.from_arrays(np.stack([x, y, z], axis=-1).reshape(-1, 3), faces, strict=True)


def strip(n: int) -> QuadMesh:
    """An open row of ``n`` unit quads: ``grid(n, 1)`` over [0, n] × [0, 1]."""
    return grid(n, 1, size=(float(n), 1.0))


def torus(n_major: int, n_minor: int, R: float = 1.0, r: float = 0.25) -> QuadMesh:
    """The torus ((R + r cos v) cos u, (R + r cos v) sin u, r sin v) on an n_major × n_minor grid of
    (u, v).

    Vertex ``i n_minor + j`` sits at u = 2πi/n_major, v = 2πj/n_minor; every vertex has valence 4.
    """
    n_major, n_minor = _check_count("n_major", n_major, 3), _check_count("n_minor", n_minor, 3)
    u = np.linspace(0.0, 2.0 * np.pi, n_major, endpoint=False)[:, None]
    v = np.linspace(0.0, 2.0 * np.pi, n_minor, endpoint=False)[None, :]
    ring = R + r * np.cos(v)
    vertices = np.stack(
        np.broadcast_arrays(ring * np.cos(u), ring * np.sin(u), r * np.sin(v)), axis=-1
    )
    i, j = np.meshgrid(np.arange(n_major), np.arange(n_minor), indexing="ij")
    i1, j1 = (i + 1) % n_major, (j + 1) % n_minor
    faces = np.stack(
        [i * n_minor + j, i1 * n_minor + j, i1 * n_minor + j1, i * n_minor + j1], axis=-1
    )
    return QuadMesh.from_arrays(vertices.reshape(-1, 3), faces.reshape(-1, 4), strict=True)


def large_torus(n_quads: int) -> QuadMesh:
    """A torus of about ``n_quads`` quads (n_major ≈ 4 n_minor), for benchmarks: 1 M → 2000 ×
    500."""
    n_minor = max(3, round(np.sqrt(_check_count("n_quads", n_quads, 36) / 4.0)))
    return torus(max(3, round(n_quads / n_minor)), n_minor)


def _spokes(angles: NDArray[np.float64]) -> NDArray[np.float64]:
    return np.stack([np.cos(angles), np.sin(angles), np.zeros_like(angles)], axis=-1)


def fan(valence: int, rings: int = 1) -> QuadMesh:
    """A planar disk of ``rings`` rings of quads around vertex 0, an interior vertex of ``valence``.

    Ring 1 has the quads (0, e_i, e_i + e_{i+1}, e_{i+1}) with spokes e_i at angles 2πi/valence;
    ring m > 1 repeats the 2·valence outer vertices of ring 1 scaled by m and joins them with quads.
    """
    valence, rings = _check_count("valence", valence, 3), _check_count("rings", rings, 1)
    spokes = _spokes(2.0 * np.pi * np.arange(valence) / valence)
    outline = np.stack([spokes, spokes + np.roll(spokes, -1, axis=0)], axis=1).reshape(-1, 3)
    scale = np.arange(1, rings + 1, dtype=np.float64)[:, None, None]
    vertices = np.concatenate([np.zeros((1, 3)), (scale * outline).reshape(-1, 3)])

    k = np.arange(valence)
    inner = np.stack(
        [np.zeros_like(k), 1 + 2 * k, 2 + 2 * k, 1 + (2 * k + 2) % (2 * valence)], axis=1
    )
    m, j = np.meshgrid(np.arange(rings - 1), np.arange(2 * valence), indexing="ij")
    ring_start = 1 + 2 * valence * m
    step = (j + 1) % (2 * valence)
    bands = np.stack(
        [
            ring_start + j,
            ring_start + 2 * valence + j,
            ring_start + 2 * valence + step,
            ring_start + step,
        ],
        axis=-1,
    )
    return QuadMesh.from_arrays(
        vertices, np.concatenate([inner, bands.reshape(-1, 4)]), strict=True
    )


def boundary_fan(k: int) -> QuadMesh:
    """``k`` planar quads around boundary vertex 0 (valence k + 1): spokes e_i at angles iπ/(k + 1),
    i = 0..k, and quads (0, e_i, e_i + e_{i+1}, e_{i+1})."""
    k = _check_count("k", k, 1)
    spokes = _spokes(np.pi * np.arange(k + 1) / (k + 1))
    vertices = np.concatenate([np.zeros((1, 3)), spokes, spokes[:-1] + spokes[1:]])
    i = np.arange(k)
    faces = np.stack([np.zeros_like(i), 1 + i, k + 2 + i, 2 + i], axis=1)
    return QuadMesh.from_arrays(vertices, faces, strict=True)


def voxel_surface(filled: NDArray[np.bool_]) -> QuadMesh:
    """The outward boundary surface of the unit cubes ``filled[i, j, k]`` (cube [i, i+1] × [j, j+1]
    × [k, k+1]).

    One quad per pair of face-adjacent cubes with one filled. The surface is manifold unless two
    filled cubes touch only along an edge or at a corner (then a :class:`MeshError` says where).
    """
    solid = np.pad(np.asarray(filled, dtype=bool), 1)  # padded cell c is the cube [c - 1, c]
    lattice = np.array(solid.shape) + 1  # lattice point l sits at coordinate l - 1
    faces = []
    for axis in range(3):
        a, b = (axis + 1) % 3, (axis + 2) % 3
        cells = solid.transpose(axis, a, b)
        # the wall between cells p and p + 1 along ``axis`` is the lattice plane p + 1
        p, q, r = np.nonzero(cells[1:] != cells[:-1])
        point = np.empty((p.size, 4, 3), dtype=np.int64)
        point[:, :, axis] = p[:, None] + 1
        point[:, :, a] = q[:, None] + [0, 1, 1, 0]
        point[:, :, b] = r[:, None] + [0, 0, 1, 1]
        # these corners run counter-clockwise about +axis; reverse them where the solid is on the +
        # side
        inward = cells[p + 1, q, r]
        point[inward] = point[inward][:, ::-1]
        faces.append(point)
    points = np.concatenate(faces)
    index = np.ravel_multi_index(points.reshape(-1, 3).T, lattice)
    used, quads = np.unique(index, return_inverse=True)
    vertices = np.stack(np.unravel_index(used, lattice), axis=1).astype(np.float64) - 1.0
    return QuadMesh.from_arrays(vertices, quads.reshape(-1, 4), strict=True)


def filleted_box(cells: int = 8, radius: float = 0.375) -> QuadMesh:
    """The unit cube's surface gridded ``cells`` per side, with its vertical edge at x = y = 1
    rounded into a quarter cylinder of ``radius``: a CAD-like part with 11 sharp edges (90°)
    and one fillet whose grid edges turn by ``90° / (2 · cells · radius)`` each. Grid points in
    the corner square ``x, y > 1 − r`` move radially onto the cylinder (the top and bottom faces
    stay flat)."""
    _check_count("cells", cells, 2)
    if not 0 < radius < 1:
        raise InputError(f"radius: expected a fillet radius between 0 and 1, got {radius!r}")
    box = voxel_surface(np.ones((cells, cells, cells), dtype=bool))
    x = box.vertices / cells
    centre = 1.0 - radius
    offset = x[:, :2] - centre
    inside = (offset > 0).all(axis=1)
    # the corner square's two outer sides map onto the arc by angle: (1, y) and (x, 1) at even steps
    s_side = np.where(offset[:, 0] >= offset[:, 1], offset[:, 1], 2 * radius - offset[:, 0])[
        inside
    ] / (2 * radius)
    depth = np.maximum(offset[:, 0], offset[:, 1])[inside] / radius  # 1 on the outer sides
    angle = 0.5 * np.pi * s_side
    arc = np.stack([np.cos(angle), np.sin(angle)], axis=1) * radius
    x[inside, :2] = centre + depth[:, None] * arc
    return box.with_vertices(x)


def slotted_block(
    cells: tuple[int, int, int] = (6, 3, 3), slot: tuple[int, int] = (2, 4)
) -> QuadMesh:
    """A block of unit cubes ``cells`` with a slot through it along y: the cubes with
    ``slot[0] ≤ x < slot[1]`` in the top layer removed. Every edge is a 90° edge (convex or
    concave) or flat, the case ``--sharp-angle`` must separate exactly."""
    filled = np.ones(cells, dtype=bool)
    filled[slot[0] : slot[1], :, cells[2] - 1] = False
    return voxel_surface(filled)


def genus2() -> QuadMesh:
    """A closed genus-2 surface (Euler characteristic −2): a 5 × 3 × 1 slab of cubes with two holes,
    centred."""
    filled = np.ones((5, 3, 1), dtype=bool)
    filled[1, 1, 0] = filled[3, 1, 0] = False
    mesh = voxel_surface(filled)
    return mesh.with_vertices(mesh.vertices - np.array([2.5, 1.5, 0.5]))


# -- refinement families sampled from smooth surfaces ----------------------------------------------


def _unit_rows(points: FloatArray) -> FloatArray:
    return points / np.linalg.norm(points, axis=-1, keepdims=True)


def _check_axes(axes: Sequence[float]) -> FloatArray:
    values = as_float_array("axes", axes, (3,))
    if values.shape != (3,) or not (values > 0).all():
        raise InputError(f"axes: expected three positive semi-axis lengths, got {axes!r}")
    return values


def _split_projected(vertices: FloatArray, faces: IntArray, level: int) -> QuadMesh:
    """``vertices`` projected onto the unit sphere, then ``level`` times: every quad split 2×2
    (edge midpoints, face centroids) and every vertex projected onto the unit sphere again."""
    points = _unit_rows(vertices)
    for _ in range(_check_count("level", level, 0)):
        points, faces, _ = refine_polygons(
            points, faces.ravel(), np.full(len(faces), 4, dtype=np.int64)
        )
        points = _unit_rows(points)
    return QuadMesh.from_arrays(points, faces, strict=True)


def sphere_quads(level: int) -> QuadMesh:
    """The unit sphere from the cube: 6·4^level quads, projected onto the sphere after *each* 2×2
    split.

    Level 0 is the cube scaled by 1/√3. Unlike :func:`cube_sphere` (which projects only once,
    at the end) every split is made on the sphere, so the quads stay close to equal in size:
    this is the refinement sequence of ``research/shape-quality.md`` §4. The 8 cube corners
    have valence 3, every other vertex valence 4.
    """
    mesh = cube()
    return _split_projected(mesh.vertices, mesh.faces, level)


def ellipsoid_quads(level: int, axes: Sequence[float] = (1.0, 0.7, 0.5)) -> QuadMesh:
    """:func:`sphere_quads` scaled by the semi-axes ``axes`` along x, y, z (6·4^level quads).

    The vertices lie on the ellipsoid ``Σ (x_k / a_k)² = 1``; :func:`ellipsoid_project` gives
    its exact closest points and normals.
    """
    mesh = sphere_quads(level)
    return mesh.with_vertices(mesh.vertices * _check_axes(axes))


def torus_quads(n_major: int, n_minor: int, R: float = 2.0, r: float = 0.7) -> QuadMesh:
    """:func:`torus` with the proportions of the refinement study (R = 2, r = 0.7), all valences 4.

    Sequence 12×6, 24×12, 48×24, 96×48 halves the grid step at each level;
    :func:`torus_project` gives exact closest points and normals.
    """
    return torus(n_major, n_minor, R, r)


def _icosahedron() -> tuple[FloatArray, IntArray]:
    """The 12 vertices (0, ±1, ±φ) and cyclic permutations, and its 20 outward triangles.

    The triangles are the vertex triples with all three sides of the edge length 2.
    """
    phi = (1.0 + np.sqrt(5.0)) / 2.0
    signs = np.array([[1.0, 1.0], [1.0, -1.0], [-1.0, 1.0], [-1.0, -1.0]])
    block = np.column_stack([np.zeros(4), signs[:, 0], phi * signs[:, 1]])
    vertices = np.concatenate([block, np.roll(block, 1, axis=1), np.roll(block, 2, axis=1)])
    triples = np.array(list(combinations(range(len(vertices)), 3)))
    p = vertices[triples]
    sides = np.linalg.norm(p - np.roll(p, 1, axis=1), axis=-1)
    triangles = triples[np.isclose(sides, 2.0).all(axis=1)]
    p = vertices[triangles]
    inward = (
        np.einsum("ij,ij->i", np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), p.sum(axis=1)) < 0
    )
    triangles[inward] = triangles[inward][:, ::-1]
    return vertices, triangles


def icosa_ellipsoid(level: int, axes: Sequence[float] = (1.0, 0.7, 0.5)) -> QuadMesh:
    """An ellipsoid from the icosahedron: 60·4^level quads with vertex valences 3, 4 and 5.

    Each of the 20 triangles is split into 3 quads (its centroid and edge midpoints), the
    points are projected onto the unit sphere, then ``level`` 2×2 splits follow, each projected
    again (as :func:`sphere_quads`), and the result is scaled by ``axes``. The 12 icosahedron
    vertices keep valence 5, the 20 triangle centroids have valence 3, all others valence 4.
    """
    vertices, triangles = _icosahedron()
    points, quads, _ = refine_polygons(
        vertices, triangles.ravel(), np.full(len(triangles), 3, dtype=np.int64)
    )
    mesh = _split_projected(points, quads, level)
    return mesh.with_vertices(mesh.vertices * _check_axes(axes))


# -- cages that provoke folds
# -----------------------------------------------------------------------


def _box_surface(coordinates: Sequence[FloatArray]) -> QuadMesh:
    """The outward surface of the box grid with increasing grid coordinates along x, y and z."""
    lattice = voxel_surface(np.ones(tuple(len(c) - 1 for c in coordinates), dtype=bool))
    index = lattice.vertices.astype(np.int64)  # lattice points 0..n along each axis
    return lattice.with_vertices(
        np.stack([c[index[:, k]] for k, c in enumerate(coordinates)], axis=1)
    )


def _shortest_edge(mesh: QuadMesh) -> float:
    ends = mesh.vertices[mesh.topology.edges]
    return float(np.linalg.norm(ends[:, 1] - ends[:, 0], axis=1).min())


def _jittered(mesh: QuadMesh, amplitude: float, seed: int) -> QuadMesh:
    """Every coordinate moved by a uniform random amount in ±``amplitude`` (NumPy generator
    ``seed``)."""
    noise = np.random.default_rng(seed).uniform(-amplitude, amplitude, mesh.vertices.shape)
    return mesh.with_vertices(mesh.vertices + noise)


def box_cage(
    lengths: Sequence[float] = (4.0, 1.0, 0.3),
    divisions: Sequence[int] = (8, 4, 2),
    *,
    jitter_seed: int | None = None,
    jitter: float = 0.1,
) -> QuadMesh:
    """The surface of a centred box of side ``lengths``, gridded with alternating short and long
    edges.

    Along each axis the grid steps alternate 1 : 4 (short, long, short, …), so every vertex
    inside a grid line has one short and one long edge along it: the case where a tangent fan
    that treats opposite edges alike overshoots the short one. With ``jitter_seed`` every
    coordinate is moved by a uniform random amount in ±``jitter`` × the shortest edge.
    """
    size = as_float_array("lengths", lengths, (3,))
    if size.shape != (3,) or not (size > 0).all():
        raise InputError(f"lengths: expected three positive box sides, got {lengths!r}")
    if len(divisions) != 3:
        raise InputError(f"divisions: expected three counts (x, y, z), got {divisions!r}")
    coordinates = []
    for axis, (length, count) in enumerate(zip(size, divisions, strict=True)):
        steps = np.where(np.arange(_check_count(f"divisions[{axis}]", count, 1)) % 2 == 0, 1.0, 4.0)
        ends = np.concatenate([[0.0], np.cumsum(steps)])
        coordinates.append(length * (ends / ends[-1] - 0.5))
    mesh = _box_surface(coordinates)
    return (
        mesh if jitter_seed is None else _jittered(mesh, jitter * _shortest_edge(mesh), jitter_seed)
    )


def thin_slab(
    size: tuple[float, float] = (2.0, 1.0),
    thickness: float = 0.05,
    divisions: tuple[int, int] = (8, 4),
    rim: int = 2,
) -> QuadMesh:
    """A thin centred box ``size`` × ``thickness`` on a uniform grid: flat faces meeting at 90°
    rims.

    The top and bottom have ``divisions`` quads; ``rim`` quads run across the thickness of each
    side wall, so every rim vertex sees one long edge across the face and short edges down the wall.
    """
    if not thickness > 0 or not all(side > 0 for side in size):
        raise InputError(
            f"thin_slab: expected positive size and thickness, got {size!r}, {thickness!r}"
        )
    nx, ny = (
        _check_count("divisions[0]", divisions[0], 1),
        _check_count("divisions[1]", divisions[1], 1),
    )
    nz = _check_count("rim", rim, 1)
    return _box_surface(
        [
            np.linspace(-size[0] / 2, size[0] / 2, nx + 1),
            np.linspace(-size[1] / 2, size[1] / 2, ny + 1),
            np.linspace(-thickness / 2, thickness / 2, nz + 1),
        ]
    )


def noisy_sphere(level: int, noise: float = 0.08, seed: int = 0) -> QuadMesh:
    """:func:`sphere_quads` with each coordinate of each vertex moved by a uniform random amount
    in ±``noise`` × its shortest edge (NumPy generator ``seed``)."""
    if not 0 <= noise < 0.5:
        raise InputError(
            f"noise: expected a fraction of the shortest edge in [0, 0.5), got {noise!r}"
        )
    mesh = sphere_quads(level)
    return _jittered(mesh, noise * _shortest_edge(mesh), seed)


def flat_fan(valence: int) -> QuadMesh:
    """A planar disk of ``valence`` convex quads around vertex 0, an interior vertex of that
    valence.

    Spoke ends (vertices 1..n) sit at radius 0.9 at angles 2πi/n, rim points (n+1..2n) at radius
    1 halfway between them, and quad i is (0, spoke i, rim i, spoke i+1): a kite, convex and of
    area ≈ 0.9 sin(π/n) even at n = 360 (rim points inside the chord would make darts, whose
    bilinear parameterisation folds by itself). Spoke ends have valence 3, rim points 2.
    """
    n = _check_count("valence", valence, 3)
    angles = 2.0 * np.pi * np.arange(n) / n
    spokes = 0.9 * _spokes(angles)
    rim = _spokes(angles + np.pi / n)
    i = np.arange(n)
    faces = np.stack([np.zeros_like(i), 1 + i, 1 + n + i, 1 + (i + 1) % n], axis=1)
    return QuadMesh.from_arrays(np.concatenate([np.zeros((1, 3)), spokes, rim]), faces, strict=True)


# -- exact closest points and normals of the sampled surfaces
# ---------------------------------------

#: Newton steps of :func:`ellipsoid_project` at most; it converges in 3–6 near the surface
_ELLIPSOID_NEWTON_STEPS = 100


def sphere_project(points: ArrayLike, radius: float = 1.0) -> tuple[FloatArray, FloatArray]:
    """Closest points on the sphere of ``radius`` about the origin, and the outward unit normals
    there.

    ``points`` (..., 3), not at the centre; returns two arrays of the same shape.
    """
    normals = _unit_rows(as_float_array("points", points, (3,)))
    return radius * normals, normals


def ellipsoid_project(
    points: ArrayLike, axes: Sequence[float] = (1.0, 0.7, 0.5)
) -> tuple[FloatArray, FloatArray]:
    """Closest points on the ellipsoid ``Σ (x_k / a_k)² = 1`` and the outward unit normals there.

    The closest point to p is ``q_k = a_k² p_k / (a_k² + t)`` where t (> −min a_k²) is the root of
    ``f(t) = Σ (a_k p_k / (a_k² + t))² − 1``, decreasing and convex. Newton's method starts at
    ``t₀ = max_k (a_k |p_k| − a_k²)``, where the largest term is 1 so f(t₀) ≥ 0: from there
    every step stays left of the root and the iteration converges monotonically. The normal is
    ``p / (a² + t)`` normalised. ``points`` (..., 3), not at the centre.
    """
    a = _check_axes(axes)
    p = as_float_array("points", points, (3,))
    a2 = a * a
    t = np.max(a * np.abs(p) - a2, axis=-1, keepdims=True)
    for _ in range(_ELLIPSOID_NEWTON_STEPS):
        scaled = a * p / (a2 + t)
        f = (scaled * scaled).sum(axis=-1, keepdims=True) - 1.0
        slope = -2.0 * (scaled * scaled / (a2 + t)).sum(axis=-1, keepdims=True)
        step = -f / slope
        t = t + step
        if (np.abs(step) <= 4.0 * np.finfo(float).eps * (np.abs(t) + a2.max())).all():
            break
    denominator = a2 + t
    return a2 * p / denominator, _unit_rows(p / denominator)


def torus_project(
    points: ArrayLike, R: float = 2.0, r: float = 0.7
) -> tuple[FloatArray, FloatArray]:
    """Closest points on the torus of :func:`torus` (axis z, radii ``R`` > ``r``) and the outward
    normals.

    The closest point lies on the tube circle in the half-plane through p: ``c + r n`` with
    ``c`` the nearest point of the core circle and ``n = (p − c) / |p − c|``. ``points`` (..., 3),
    off the z axis and off the core circle.
    """
    p = as_float_array("points", points, (3,))
    if not 0 < r < R:
        raise InputError(f"torus_project: expected radii 0 < r < R, got R={R!r}, r={r!r}")
    planar = p * np.array([1.0, 1.0, 0.0])
    core = R * _unit_rows(planar)
    normals = _unit_rows(p - core)
    return core + r * normals, normals


def bump_sphere_scan(
    points: int = 60_000, height: float = 0.4, width: float = 0.1
) -> tuple[FloatArray, IntArray]:
    """A triangle scan of the unit sphere with a narrow bump at the pole z = 1: ``points``
    Fibonacci points, their convex hull (outward), moved to ``r = 1 + height exp(−(θ / width)²)``
    (θ the polar angle, radians). ``(points (N, 3), triangles (T, 3))``: a scan whose detail is
    local, for the fit's local refinement."""
    from scipy.spatial import ConvexHull

    index = np.arange(_check_count("points", points, 16)) + 0.5
    polar, azimuth = np.arccos(1.0 - 2.0 * index / points), np.pi * (1.0 + 5**0.5) * index
    unit = np.stack(
        [np.cos(azimuth) * np.sin(polar), np.sin(azimuth) * np.sin(polar), np.cos(polar)], 1
    )
    triangles = ConvexHull(unit).simplices.astype(np.int64)
    normal = np.cross(*(unit[triangles[:, k]] - unit[triangles[:, 0]] for k in (1, 2)))
    outward = (normal * unit[triangles].mean(axis=1)).sum(axis=1) > 0
    triangles = np.where(outward[:, None], triangles, triangles[:, ::-1])
    return unit * (1.0 + height * np.exp(-((polar / width) ** 2)))[:, None], triangles
