"""Local vertex rules every shape rule and the paper's construction share.

* ``fan_normals``: the area-weighted fan normal ``N_A = normalize(Σ (x_next − A) × (x_prev − A))``;
* ``least_squares_normals``: the paper's normal, the best plane through the vertex and its ring;
* ``corner_tangents``: a mesh edge projected onto the tangent plane, ``s = d − (n·d) n``, with the
  chord length or the circle-aware arc length ``2|d|²/(|d| + |s|)``;
* ``cross``, ``dot``, ``unit_rows`` on rows of 3-vectors, and the ring slots' vertices and
  half-edge tables (``slot_vertices``, ``slot_tables``).

The numba kernels beside the NumPy code they replace are compiled by
:func:`g1patch.kernels.jit_kernel`.
"""

from __future__ import annotations

from typing import Literal

import numpy as np
from numpy.typing import NDArray

from ..errors import ConstructionError, check_choice
from ..kernels import jit_kernel, use_kernels
from ..mesh import QuadMesh, QuadTopology
from .value import TANGENTS, TangentRule, halfedge_slots

__all__ = [
    "NORMALS",
    "TANGENTS",
    "NormalRule",
    "TangentRule",
    "corner_tangents",
    "cross",
    "dot",
    "fan_normals",
    "in_vertex_planes",
    "least_squares_normals",
    "slot_tables",
    "slot_vertices",
    "unit_rows",
]

NormalRule = Literal["fan", "paper"]
NORMALS: tuple[NormalRule, ...] = ("fan", "paper")


def cross(a: NDArray[np.float64], b: NDArray[np.float64]) -> NDArray[np.float64]:
    """``a × b`` along the last axis by components: the formulas and values of ``np.cross``,
    several times faster on large arrays of 3-vectors (no axis juggling)."""
    out = np.empty(np.broadcast_shapes(a.shape, b.shape))
    out[..., 0] = a[..., 1] * b[..., 2] - a[..., 2] * b[..., 1]
    out[..., 1] = a[..., 2] * b[..., 0] - a[..., 0] * b[..., 2]
    out[..., 2] = a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]
    return out


def dot(a: NDArray[np.float64], b: NDArray[np.float64]) -> NDArray[np.float64]:
    """``a · b`` along the last axis."""
    return np.einsum("...d,...d->...", a, b)


def unit_rows(v: NDArray[np.float64]) -> NDArray[np.float64]:
    """``v`` scaled to unit length along the last axis; zero rows stay zero."""
    length = np.linalg.norm(v, axis=-1, keepdims=True)
    return v / np.where(length > 0, length, 1.0)


def in_vertex_planes(
    tangents: NDArray[np.float64],
    normals: NDArray[np.float64],
    offsets: NDArray[np.int64],
    out: NDArray[np.float64] | None = None,
) -> NDArray[np.float64]:
    """Slot vectors moved into their vertex's tangent plane, ``t − (N·t) N`` (N the unit normal of
    the slot's vertex, slots ``offsets[v]:offsets[v + 1]``), by a numba kernel; ``out`` may be
    ``tangents``."""
    out = np.empty_like(tangents) if out is None else out
    if use_kernels(True):
        jit_kernel(_plane_kernel)(tangents, normals, offsets, out)
        return out
    n = normals[np.repeat(np.arange(offsets.size - 1), np.diff(offsets))]
    height = tangents[:, 0] * n[:, 0] + tangents[:, 1] * n[:, 1] + tangents[:, 2] * n[:, 2]
    out[:] = tangents - height[:, None] * n
    return out


def _plane_kernel(
    tangents: NDArray[np.float64],
    normals: NDArray[np.float64],
    offsets: NDArray[np.int64],
    out: NDArray[np.float64],
) -> None:
    """``out = t − (N·t) N`` slot by slot."""
    for v in range(offsets.size - 1):
        n0, n1, n2 = normals[v, 0], normals[v, 1], normals[v, 2]
        for s in range(offsets[v], offsets[v + 1]):
            t0, t1, t2 = tangents[s, 0], tangents[s, 1], tangents[s, 2]
            height = t0 * n0 + t1 * n1 + t2 * n2
            out[s, 0] = t0 - height * n0
            out[s, 1] = t1 - height * n1
            out[s, 2] = t2 - height * n2


def slot_vertices(topology: QuadTopology) -> NDArray[np.int64]:
    """The vertex of every ring slot, (S,)."""
    return np.repeat(np.arange(topology.n_vertices), np.diff(topology.neighbor_offsets))


def slot_tables(topology: QuadTopology) -> tuple[NDArray[np.int32], NDArray[np.int32]]:
    """:func:`g1patch.targets.halfedge_slots` by a numba kernel, as int32 (half the memory): the
    ring slot of each half-edge A → B at A (``slot_out``), and of B → A at B (``slot_in``; the last
    slot of B where A → B is a boundary half-edge)."""
    if not use_kernels(True):
        slot_out64, slot_in64 = halfedge_slots(topology)
        return slot_out64.astype(np.int32), slot_in64.astype(np.int32)
    slot_out = np.empty(topology.n_halfedges, dtype=np.int32)
    slot_in = np.empty(topology.n_halfedges, dtype=np.int32)
    jit_kernel(_slots_kernel)(
        topology.faces.reshape(-1),
        topology.twin,
        topology.ring_offsets,
        topology.ring_halfedges,
        topology.neighbor_offsets,
        slot_out,
        slot_in,
    )
    return slot_out, slot_in


def _slots_kernel(
    origin: NDArray[np.int64],
    twin: NDArray[np.int64],
    ring_offsets: NDArray[np.int64],
    ring_halfedges: NDArray[np.int64],
    neighbor_offsets: NDArray[np.int64],
    slot_out: NDArray[np.int32],
    slot_in: NDArray[np.int32],
) -> None:
    """Ring position j of the outgoing half-edge ``ring_halfedges[ring_offsets[v] + j]`` → slot
    ``neighbor_offsets[v] + j``; ``slot_in[h] = slot_out[twin[h]]``."""
    for v in range(ring_offsets.size - 1):
        for r in range(ring_offsets[v], ring_offsets[v + 1]):
            slot_out[ring_halfedges[r]] = neighbor_offsets[v] + r - ring_offsets[v]
    for h in range(origin.size):
        if twin[h] >= 0:
            slot_in[h] = slot_out[twin[h]]
        else:
            slot_in[h] = neighbor_offsets[origin[(h & ~3) | ((h + 1) & 3)] + 1] - 1


def _face_normal_sums(mesh: QuadMesh, vertices: NDArray[np.int64]) -> NDArray[np.float64]:
    """Per vertex in ``vertices`` the sum of its faces' area vectors ``(x_2 − x_0) × (x_3 − x_1)``
    (a quad's normal times twice its area, defined where a corner is straight)."""
    x, faces = mesh.vertices, mesh.faces
    area = cross(x[faces[:, 2]] - x[faces[:, 0]], x[faces[:, 3]] - x[faces[:, 1]])
    wanted = np.isin(faces.reshape(-1), vertices)
    corners = faces.reshape(-1)[wanted]
    face = np.flatnonzero(wanted) >> 2
    total = np.stack(
        [np.bincount(corners, area[face, d], minlength=len(x)) for d in range(3)], axis=1
    )
    return np.asarray(total[vertices], dtype=np.float64)


def _unit_or_fail(
    vectors: NDArray[np.float64], what: str, mesh: QuadMesh | None = None
) -> NDArray[np.float64]:
    """``vectors`` normalised; where one is zero (a boundary vertex whose one face has a straight
    corner there, corner normals that cancel) the sum of its faces' normals
    (:func:`_face_normal_sums`) stands in, given ``mesh``; where that is zero too, a
    :class:`ConstructionError` naming the vertex."""
    length = np.linalg.norm(vectors, axis=-1, keepdims=True)
    if mesh is not None and not (length > 0).all():
        vanished = np.flatnonzero(~(length[:, 0] > 0))
        vectors = vectors.copy()
        vectors[vanished] = _face_normal_sums(mesh, vanished)
        length = np.linalg.norm(vectors, axis=-1, keepdims=True)
    if not (length > 0).all():
        bad = int(np.argmin(length[:, 0]))
        raise ConstructionError(
            f"{what}: vertex {bad} has no defined normal (its faces are degenerate or cancel out)"
        )
    return vectors / length


def fan_normals(mesh: QuadMesh, *, compiled: bool = True) -> NDArray[np.float64]:
    """Unit fan normals ``N_A = normalize(Σ (x_next − A) × (x_prev − A))`` over the faces at A.

    In face f the corner A has a next and a previous vertex; the pair are consecutive ring
    neighbours of A, so the sum runs over consecutive ring edges (non-cyclic on a boundary).
    ``compiled``: one numba pass over the face corners (:func:`_fan_kernel`, the same sums in the
    same order), else NumPy.
    """
    compiled = use_kernels(compiled)  # NumPy where kernels cannot be cached
    faces = mesh.faces
    x = mesh.vertices
    if compiled:
        total = np.zeros_like(x)
        jit_kernel(_fan_kernel)(x, faces, total)
        return _unit_or_fail(total, "fan normal", mesh)
    here = x[faces]
    to_next = np.roll(here, -1, axis=1) - here
    to_prev = np.roll(here, 1, axis=1) - here
    corner_normals = cross(to_next, to_prev).reshape(-1, 3)
    corners = faces.reshape(-1)
    total = np.stack(
        [np.bincount(corners, corner_normals[:, d], minlength=len(x)) for d in range(3)], axis=1
    )
    return _unit_or_fail(total, "fan normal", mesh)


def _fan_kernel(
    x: NDArray[np.float64], faces: NDArray[np.int64], total: NDArray[np.float64]
) -> None:
    """``total[A] += (x_next − A) × (x_prev − A)`` for every face corner A, in corner order."""
    for f in range(faces.shape[0]):
        for k in range(4):
            a, b, c = faces[f, k], faces[f, (k + 1) & 3], faces[f, (k + 3) & 3]
            nx, ny, nz = x[b, 0] - x[a, 0], x[b, 1] - x[a, 1], x[b, 2] - x[a, 2]
            px, py, pz = x[c, 0] - x[a, 0], x[c, 1] - x[a, 1], x[c, 2] - x[a, 2]
            total[a, 0] += ny * pz - nz * py
            total[a, 1] += nz * px - nx * pz
            total[a, 2] += nx * py - ny * px


def least_squares_normals(mesh: QuadMesh) -> NDArray[np.float64]:
    """The paper's normal: the normal of the plane that best fits the vertex and its ring.

    For a vertex with two neighbours this is the plane through three points, the generalized
    cross product ``ρ = x_1 × x_2 × x_3`` of eq. (9); with more neighbours the system is
    over-determined and its least-squares solution is the eigenvector of the points' covariance
    ``Σ d d^T / m − μ μ^T`` (``d = x_w − x_A`` over the vertex itself and its m − 1 neighbours)
    with the smallest eigenvalue. Oriented to agree with the fan normal. Fragile on coarse
    curved meshes: where the ring is far from planar (a torus with few segments) the best plane
    can tilt away from the surface.
    """
    edges = mesh.topology.edges
    x = mesh.vertices
    d = x[edges[:, 1]] - x[edges[:, 0]]
    outer = d[:, :, None] * d[:, None, :]
    second_moment = np.zeros((len(x), 3, 3))
    first_moment = np.zeros((len(x), 3))
    np.add.at(second_moment, edges[:, 0], outer)
    np.add.at(second_moment, edges[:, 1], outer)
    np.add.at(first_moment, edges[:, 0], d)
    np.add.at(first_moment, edges[:, 1], -d)
    points = (mesh.topology.valence + 1.0)[:, None]
    mean = first_moment / points
    covariance = second_moment / points[:, :, None] - mean[:, :, None] * mean[:, None, :]
    normals = np.linalg.eigh(covariance)[1][:, :, 0]
    fan = fan_normals(mesh)
    return normals * np.where(np.einsum("vd,vd->v", normals, fan) < 0, -1.0, 1.0)[:, None]


def corner_tangents(
    origin: NDArray[np.float64],
    target: NDArray[np.float64],
    normal: NDArray[np.float64],
    rule: TangentRule,
    labels: NDArray[np.int64] | None = None,
) -> NDArray[np.float64]:
    """Tangent at ``origin`` towards ``target`` in the plane ⊥ ``normal`` (unit), batched.

    Direction: ``s = d − (n·d) n``. Length: ``chord`` → |d|; ``arc`` → |d| / cos²(φ/2) with φ
    the angle between d and the plane: a circular arc through both ends tangent to the plane
    spans θ = 2φ, and the cubic Hermite tangent that best reproduces it is |d| / cos²(θ/4).
    As cos φ = |s|/|d|, that is ``2|d|² / (|d| + |s|)``, with no trigonometry.
    ``labels[..., 2]`` (origin and target vertex ids) name the edge in an error.
    """
    check_choice("tangents", rule, TANGENTS)
    d = target - origin
    height = np.einsum("...d,...d->...", d, normal)
    s = d - height[..., None] * normal
    in_plane = np.linalg.norm(s, axis=-1)
    chord = np.linalg.norm(d, axis=-1)
    if not (in_plane > 0).all():
        where = np.argwhere(~(in_plane > 0))[0]
        edge = "" if labels is None else f" {labels[tuple(where)][0]}→{labels[tuple(where)][1]}"
        raise ConstructionError(
            f"tangents: mesh edge{edge} is parallel to its vertex normal; its tangent is undefined"
        )
    length = 2.0 * chord**2 / (chord + in_plane) if rule == "arc" else chord
    return s * (length / in_plane)[..., None]
