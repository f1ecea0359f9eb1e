"""Generated quad meshes for tests, demos and benchmarks; every face counter-clockwise seen from outside.

All shapes are built with vectorised NumPy and validated through :meth:`QuadMesh.from_arrays`.
Planar shapes lie in z = 0 and face +z. :func:`subdivide` (one Catmull–Clark topology step with
linear positions) lives in :mod:`g1patch.mesh`, beside the splitting of non-quad faces it shares.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

from .errors import InputError
from .mesh import QuadMesh, subdivide

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
]

HeightFunction = Callable[[NDArray[np.float64], NDArray[np.float64]], NDArray[np.float64]]


def _check_count(name: str, value: int, least: int) -> int:
    if int(value) != value or value < least:
        raise InputError(f"{name}: expected an integer >= {least}, got {value!r}")
    return int(value)


def cube() -> QuadMesh:
    """The cube [-1, 1]^3: 8 vertices (vertex ``4 x + 2 y + z`` for x, y, z ∈ {0, 1}), 6 outward quads."""
    bits = (np.arange(8)[:, None] >> np.array([2, 1, 0])) & 1
    faces = [
        [0, 1, 3, 2],  # x = -1
        [4, 6, 7, 5],  # x = +1
        [0, 4, 5, 1],  # y = -1
        [2, 3, 7, 6],  # y = +1
        [0, 2, 6, 4],  # z = -1
        [1, 5, 7, 3],  # z = +1
    ]
    return QuadMesh.from_arrays(2.0 * bits - 1.0, faces)


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

    Vertex ``j (nx + 1) + i`` sits at (x_i, y_j, height(x_i, y_j)); faces are counter-clockwise about +z.
    """
    nx, ny = _check_count("nx", nx, 1), _check_count("ny", ny, 1)
    x, y = np.meshgrid(np.linspace(0.0, size[0], nx + 1), np.linspace(0.0, size[1], ny + 1))
    z = np.zeros_like(x) if height is None else np.broadcast_to(height(x, y), x.shape)
    i, j = np.meshgrid(np.arange(nx), np.arange(ny))
    corner = (j * (nx + 1) + i).ravel()
    faces = np.stack([corner, corner + 1, corner + nx + 2, corner + nx + 1], axis=1)
    return QuadMesh.from_arrays(np.stack([x, y, z], axis=-1).reshape(-1, 3), faces)


def strip(n: int) -> QuadMesh:
    """An open row of ``n`` unit quads: ``grid(n, 1)`` over [0, n] × [0, 1]."""
    return grid(n, 1, size=(float(n), 1.0))


def torus(n_major: int, n_minor: int, R: float = 1.0, r: float = 0.25) -> QuadMesh:
    """The torus ((R + r cos v) cos u, (R + r cos v) sin u, r sin v) on an n_major × n_minor grid of (u, v).

    Vertex ``i n_minor + j`` sits at u = 2πi/n_major, v = 2πj/n_minor; every vertex has valence 4.
    """
    n_major, n_minor = _check_count("n_major", n_major, 3), _check_count("n_minor", n_minor, 3)
    u = np.linspace(0.0, 2.0 * np.pi, n_major, endpoint=False)[:, None]
    v = np.linspace(0.0, 2.0 * np.pi, n_minor, endpoint=False)[None, :]
    ring = R + r * np.cos(v)
    vertices = np.stack(np.broadcast_arrays(ring * np.cos(u), ring * np.sin(u), r * np.sin(v)), axis=-1)
    i, j = np.meshgrid(np.arange(n_major), np.arange(n_minor), indexing="ij")
    i1, j1 = (i + 1) % n_major, (j + 1) % n_minor
    faces = np.stack([i * n_minor + j, i1 * n_minor + j, i1 * n_minor + j1, i * n_minor + j1], axis=-1)
    return QuadMesh.from_arrays(vertices.reshape(-1, 3), faces.reshape(-1, 4))


def large_torus(n_quads: int) -> QuadMesh:
    """A torus of about ``n_quads`` quads (n_major ≈ 4 n_minor), for benchmarks: 1 M → 2000 × 500."""
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
    inner = np.stack([np.zeros_like(k), 1 + 2 * k, 2 + 2 * k, 1 + (2 * k + 2) % (2 * valence)], axis=1)
    m, j = np.meshgrid(np.arange(rings - 1), np.arange(2 * valence), indexing="ij")
    ring_start = 1 + 2 * valence * m
    step = (j + 1) % (2 * valence)
    bands = np.stack(
        [ring_start + j, ring_start + 2 * valence + j, ring_start + 2 * valence + step, ring_start + step], axis=-1
    )
    return QuadMesh.from_arrays(vertices, np.concatenate([inner, bands.reshape(-1, 4)]))


def boundary_fan(k: int) -> QuadMesh:
    """``k`` planar quads around boundary vertex 0 (valence k + 1): spokes e_i at angles iπ/(k + 1), i = 0..k,
    and quads (0, e_i, e_i + e_{i+1}, e_{i+1})."""
    k = _check_count("k", k, 1)
    spokes = _spokes(np.pi * np.arange(k + 1) / (k + 1))
    vertices = np.concatenate([np.zeros((1, 3)), spokes, spokes[:-1] + spokes[1:]])
    i = np.arange(k)
    faces = np.stack([np.zeros_like(i), 1 + i, k + 2 + i, 2 + i], axis=1)
    return QuadMesh.from_arrays(vertices, faces)


def voxel_surface(filled: NDArray[np.bool_]) -> QuadMesh:
    """The outward boundary surface of the unit cubes ``filled[i, j, k]`` (cube [i, i+1] × [j, j+1] × [k, k+1]).

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
        # these corners run counter-clockwise about +axis; reverse them where the solid is on the + side
        inward = cells[p + 1, q, r]
        point[inward] = point[inward][:, ::-1]
        faces.append(point)
    points = np.concatenate(faces)
    index = np.ravel_multi_index(points.reshape(-1, 3).T, lattice)
    used, quads = np.unique(index, return_inverse=True)
    vertices = np.stack(np.unravel_index(used, lattice), axis=1).astype(np.float64) - 1.0
    return QuadMesh.from_arrays(vertices, quads.reshape(-1, 4))


def genus2() -> QuadMesh:
    """A closed genus-2 surface (Euler characteristic −2): a 5 × 3 × 1 slab of cubes with two holes, centred."""
    filled = np.ones((5, 3, 1), dtype=bool)
    filled[1, 1, 0] = filled[3, 1, 0] = False
    mesh = voxel_surface(filled)
    return mesh.with_vertices(mesh.vertices - np.array([2.5, 1.5, 0.5]))
