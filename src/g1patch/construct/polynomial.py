"""A Gregory network's targets, re-assembled polynomially (split4): exact G1 that CAD keeps.

A Gregory network (:mod:`g1patch.construct.gregory`) is exactly G1, but its patches are rational,
so CAD receives them fitted and the fit kinks (issue 15). Shape and exactness are separate jobs
(DESIGN §1), so the network's own surface is read back as :class:`~g1patch.targets.Targets` and
assembled again by :mod:`g1patch.construct.split4`, whose bicubic pieces a B-spline face holds
exactly. Per Gregory patch f (one per quad, patch edge k = half-edge ``4 f + k``):

* ``positions``: the corners ``P_k`` (local coordinates of the patches' frame);
* ``tangents``: slot of A → B at A (``slot_out[4f + k]``) ``t = 3 (E+_k − P_k)``, slot of B → A at
  B (``slot_in[4f + k]``) ``t = 3 (E-_{k+1} − P_{k+1})`` (the network is G0: both faces of an edge
  give the same numbers);
* ``interior``: the interior pairs ``(Fn_k, Fp_k)``, as the Gregory assembly made them;
* ``normals``: the network's vertex normals; ``corner_normals``: the patches' normals at their
  corners;
* ``seams``: the network's seams per mesh edge.

split4's interiors are then guided by a least-squares fit of each Gregory patch
(:func:`guide_nets`). A network with seams is re-assembled on its mesh *cut open* along them, as
split4 keeps seams (:mod:`~g1patch.construct.split4.seams`): one vertex per corner sector, each
seam two boundary edges, stars that keep every seam tangent exactly, so both sides of a seam compute
the same boundary curve, and the sub-patches connected on the uncut mesh with the seams marked.

The result is compared with the Gregory surface itself
(:func:`~g1patch.construct.deviation.surface_deviation`). split4's stars cannot hold every Gregory
fan (a V-shaped fan at a dart's end, unequal opposite tangents), and the difference lives within a
quad's size of those vertices, so the network's surface can also be re-assembled on its mesh
with every patch cut into n × n cells (:func:`grid_refinement`, :func:`refined_gregory_targets`:
the targets read off the Gregory patches at the cell corners): the export takes the fewest cells
that bring it within its bound.
"""

from __future__ import annotations

from dataclasses import replace
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from ..errors import ConstructionError, InputError
from ..frame import Frame
from ..gregory import INTERIOR_INDEX, GregoryPatchSet
from ..mesh import QuadMesh, QuadTopology
from ..network import PatchNetwork
from ..patches import CORNER_PARAMETERS
from ..targets import Targets, halfedge_slots
from .deviation import surface_deviation
from .split4 import (
    BSPLINE_KNOTS,
    split4_network_from_points,
    split4_network_from_targets,
    split4_patches,
    split4_star,
)
from .split4.seams import _paired_seams, seam_stars

__all__ = [
    "GridRefinement",
    "grid_refinement",
    "gregory_targets",
    "refined_gregory_targets",
    "split4_of_gregory",
    "surface_deviation",
]

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]


def _topology_of(network: PatchNetwork, cut: bool) -> QuadTopology:
    """The quad mesh a one-patch-per-quad network was built on (faces = ``corner_ids``); ``cut``:
    cut open along its seams, one vertex per corner *sector*
    (:meth:`PatchNetwork.corner_sectors`)."""
    if not isinstance(network.patches, GregoryPatchSet):
        raise InputError(f"network: expected Gregory patches, got {type(network.patches).__name__}")
    if not cut:
        return QuadTopology.from_faces(network.corner_ids, network.n_corners)
    labels, faces = np.unique(network.corner_sectors(), return_inverse=True)
    return QuadTopology.from_faces(faces.reshape(-1, 4), len(labels))


#: where a patch corner is degenerate (its two edge tangents parallel: the corner of a face between
#: two creases that run on smoothly through a vertex) its normal is the limit of the normals along
#: the corner's diagonal, taken this far inside (in parameter)
CORNER_INSET = 1e-6


def _corner_normals(patches: GregoryPatchSet) -> FloatArray:
    """(F, 4, 3) unit normals of the patches at their corners; at a degenerate corner (normal of
    zero length) the normal at :data:`CORNER_INSET` along its diagonal instead."""
    normals = patches.normals(CORNER_PARAMETERS)
    face, corner = np.nonzero(np.linalg.norm(normals, axis=-1) < 0.5)
    if face.size:
        inset = CORNER_PARAMETERS + CORNER_INSET * (0.5 - CORNER_PARAMETERS) * 2.0
        normals[face, corner] = patches.take(face).normals(inset[corner][:, None])[:, 0]
    return normals


def gregory_targets(network: PatchNetwork, *, cut: bool = False) -> tuple[Targets, Frame]:
    """The :class:`Targets` a Gregory network interpolates (module docstring), in the local
    coordinates of its frame (``Frame.of_points`` of the corners where the patches carry none).
    With ``cut`` on the network's topology cut open along its seams (:func:`_topology_of`): a seam
    is two boundary edges, a vertex per sector with the sector's normal, and no seams are left."""
    topology = _topology_of(network, cut)
    patches: GregoryPatchSet = network.patches  # type: ignore[assignment]
    frame = patches.frame or Frame.of_points(patches.points[:, :4])
    points = patches.points if patches.frame is not None else frame.to_local(patches.points)
    corners = points[:, :4]
    positions = np.zeros((topology.n_vertices, 3))
    positions[topology.faces.reshape(-1)] = corners.reshape(-1, 3)
    slot_out, slot_in = halfedge_slots(topology)
    tangents = np.zeros((int(topology.neighbor_offsets[-1]), 3))
    tangents[slot_in] = (
        3.0 * (points[:, 5 + 2 * ((np.arange(4) + 1) % 4)] - np.roll(corners, -1, axis=1))
    ).reshape(-1, 3)
    tangents[slot_out] = (3.0 * (points[:, 4:12:2] - corners)).reshape(-1, 3)
    corner_normals = _corner_normals(patches)
    if (
        not cut
        and network.vertex_normals is not None
        and len(network.vertex_normals) == topology.n_vertices
    ):
        normals = network.vertex_normals
    else:
        normals = np.zeros((topology.n_vertices, 3))
        np.add.at(normals, topology.faces.reshape(-1), corner_normals.reshape(-1, 3))
        normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    seams = np.zeros(topology.n_edges, dtype=bool)
    if not cut:
        seams[topology.halfedge_edge] = network.seam.reshape(-1)
    targets = Targets(
        topology,
        positions,
        normals,
        tangents,
        points[:, 12:].reshape(-1, 4, 2, 3),
        seams=seams,
        rule="gregory network",
        corner_normals=corner_normals,
    )
    return targets, frame


class GridRefinement(NamedTuple):
    """Each quad of a topology cut into an n × n grid in its own parameters: refined face
    ``r = f n² + a n + b`` covers ``u ∈ [a/n, (a+1)/n]``, ``v ∈ [b/n, (b+1)/n]`` of face f, its
    corners in f's order (so it turns the same way); ``grid[f, a, b]`` is the vertex at ``(a/n,
    b/n)`` of face f."""

    topology: QuadTopology
    grid: NDArray[np.int64]
    n: int


def grid_refinement(topology: QuadTopology, n: int) -> GridRefinement:
    """:class:`GridRefinement` of ``topology``: vertices are the mesh's, then n − 1 per edge (from
    the origin of its first half-edge on), then (n − 1)² per face; an edge's points are shared by
    its faces."""
    faces, count = topology.faces, topology.n_faces
    grid = np.empty((count, n + 1, n + 1), dtype=np.int64)
    grid[:, [0, n, n, 0], [0, 0, n, n]] = faces
    k = np.arange(1, n)
    first = topology.edge_halfedges[topology.halfedge_edge, 0] == np.arange(topology.n_halfedges)
    h = 4 * np.arange(count)[:, None] + np.arange(4)  # (F, 4)
    base = topology.n_vertices + (n - 1) * topology.halfedge_edge[h]
    along = (
        np.where(first[h][..., None], k - 1, n - 1 - k) + base[..., None]
    )  # (F, 4, n − 1): point k/n from corner i
    grid[:, k, 0], grid[:, n, k], grid[:, n - k, n], grid[:, 0, n - k] = (
        along[:, i] for i in range(4)
    )
    inner = topology.n_vertices + (n - 1) * topology.n_edges
    grid[:, 1:n, 1:n] = inner + np.arange(count * (n - 1) ** 2).reshape(count, n - 1, n - 1)
    cells = np.stack(
        [grid[:, :-1, :-1], grid[:, 1:, :-1], grid[:, 1:, 1:], grid[:, :-1, 1:]], axis=-1
    )
    return GridRefinement(
        QuadTopology.from_faces(cells.reshape(-1, 4), inner + count * (n - 1) ** 2), grid, n
    )


def _refined_seams(
    topology: QuadTopology, seam_halfedges: NDArray[np.bool_], n: int
) -> NDArray[np.bool_]:
    """(R, 4) which half-edges of the :func:`grid_refinement` lie on the ``seam_halfedges`` (4F,) of
    ``topology``."""
    seam = seam_halfedges.reshape(-1, 4)
    refined = np.zeros((topology.n_faces, n, n, 4), dtype=bool)
    refined[:, :, 0, 0] = seam[:, 0, None]
    refined[:, n - 1, :, 1] = seam[:, 1, None]
    refined[:, :, n - 1, 2] = seam[:, 2, None]
    refined[:, 0, :, 3] = seam[:, 3, None]
    return refined.reshape(-1, 4)


def refined_gregory_targets(
    network: PatchNetwork, refinement: GridRefinement, *, cut: bool = False
) -> tuple[Targets, Frame, FloatArray]:
    """The targets of a Gregory network's own surface on a :func:`grid_refinement` of its mesh (cut
    or not: ``refinement.topology``'s faces are the patches' n × n cells), with the guide nets of
    the cells (:func:`guide_nets` of each cell's piece of its patch), in the local coordinates of
    the patches' frame: positions and unit normals ``p_u × p_v`` of the patch at each grid point (a
    point on an edge from one of its faces: the network is G0), the slot tangent of each cell edge
    the patch's derivative along it over n (its Hermite tangent), corner normals per cell corner
    (:func:`_corner_normals`' inset where a patch corner is degenerate), interior targets the
    interior points of each cell's least-squares bicubic. The mesh vertices keep the network's
    vertex normals unless ``cut``."""
    topology, grid, n = refinement
    patches: GregoryPatchSet = network.patches  # type: ignore[assignment]
    frame = patches.frame or Frame.of_points(patches.points[:, :4])
    local = (
        patches.local()
        if patches.frame is not None
        else GregoryPatchSet(frame.to_local(patches.points))
    )
    steps = np.linspace(0.0, 1.0, n + 1)
    uv = np.stack(np.meshgrid(steps, steps, indexing="ij"), axis=-1).reshape(
        -1, 2
    )  # (a, b) → a (n + 1) + b
    count = len(local)
    at = local.evaluate(uv).reshape(count, n + 1, n + 1, 3)
    d_u = local.evaluate(uv, 1, 0).reshape(count, n + 1, n + 1, 3) / n
    d_v = local.evaluate(uv, 0, 1).reshape(count, n + 1, n + 1, 3) / n
    normal = np.cross(d_u, d_v)
    length = np.linalg.norm(normal, axis=-1, keepdims=True)
    normal = normal / np.where(length > 0, length, 1.0)
    normal[:, [0, n, n, 0], [0, 0, n, n]] = _corner_normals(local)
    positions = np.empty((topology.n_vertices, 3))
    positions[grid.reshape(-1)] = at.reshape(-1, 3)
    cell = np.stack(np.meshgrid(np.arange(n), np.arange(n), indexing="ij"), axis=-1).reshape(
        -1, 2
    )  # (n², 2)
    corner_ab = cell[:, None] + np.array([[0, 0], [1, 0], [1, 1], [0, 1]])  # (n², 4, 2)
    face = np.repeat(np.arange(count), n * n)[:, None]
    a, b = np.tile(corner_ab[..., 0], (count, 1)), np.tile(corner_ab[..., 1], (count, 1))  # (R, 4)
    corner_normals = normal[face, a, b]
    # edge k of a cell runs +u, +v, −u, −v from corner k to corner k + 1
    nxt = (np.arange(4) + 1) % 4
    sign = np.array([1.0, 1.0, -1.0, -1.0])[:, None]
    along_u = np.array([True, False, True, False])
    derivative = np.where(
        along_u[None, :, None], d_u[face, a, b], d_v[face, a, b]
    )  # at corner k, along edge k's axis
    derivative_next = np.where(
        along_u[None, :, None], d_u[face, a[:, nxt], b[:, nxt]], d_v[face, a[:, nxt], b[:, nxt]]
    )
    slot_out, slot_in = halfedge_slots(topology)
    tangents = np.zeros((int(topology.neighbor_offsets[-1]), 3))
    tangents[slot_out.reshape(-1, 4)] = sign * derivative
    tangents[slot_in.reshape(-1, 4)] = -sign * derivative_next
    normals = np.zeros((topology.n_vertices, 3))
    np.add.at(normals, topology.faces.reshape(-1), corner_normals.reshape(-1, 3))
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    if (
        not cut
        and network.vertex_normals is not None
        and len(network.vertex_normals) == network.n_corners
    ):
        normals[: network.n_corners] = network.vertex_normals
    guide, bicubic = _cell_fits(local, n)
    interior = np.repeat(
        bicubic[:, INTERIOR_INDEX[:, 0], INTERIOR_INDEX[:, 1], None], 2, axis=2
    )  # (R, 4, 2, 3)
    targets = Targets(
        topology,
        positions,
        normals,
        tangents,
        interior,
        rule=f"gregory network, {n}×{n} per patch",
        corner_normals=corner_normals,
    )
    return targets, frame, guide


# : samples per direction and patch of the guide fit (:func:`guide_nets`): 2× the 6 unknowns, both
# ends
GUIDE_SAMPLES = 13


def _fit_operators(samples: int) -> tuple[FloatArray, FloatArray]:
    """Least-squares operators on ``samples`` equally spaced parameters of [0, 1]: (7, samples) to
    the macro row of the C1 2×2 cubic B-spline (knots ``[0,0,0,0,½,½,1,1,1,1]``, the double knot at
    ½ written out: row 3 the midpoint of its neighbours), and (4, samples) to one cubic's Bézier
    row."""
    from scipy.interpolate import BSpline

    t = np.linspace(0.0, 1.0, samples)
    inverse = np.linalg.pinv(BSpline.design_matrix(t, BSPLINE_KNOTS, 3).toarray())  # (6, samples)
    expand = np.zeros((7, 6))
    expand[[0, 1, 2, 4, 5, 6], [0, 1, 2, 3, 4, 5]] = 1.0
    expand[3, 2:4] = 0.5
    bernstein = np.linalg.pinv(
        BSpline.design_matrix(t, np.r_[np.zeros(4), np.ones(4)], 3).toarray()
    )
    return expand @ inverse, bernstein


def guide_nets(patches: GregoryPatchSet, samples: int = GUIDE_SAMPLES) -> FloatArray:
    """Per patch the (F, 7, 7, 3) macro net of its least-squares C1 2×2 bicubic B-spline (knots
    ``[0,0,0,0,½,½,1,1,1,1]``) on a ``samples``² grid: ``X = B⁺ S B⁺ᵀ``, then the double knot at ½
    written out (row and column 3 the midpoints of their neighbours). Local coordinates."""
    operator = _fit_operators(samples)[0]
    t = np.linspace(0.0, 1.0, samples)
    return np.einsum(
        "ia,fabd,jb->fijd", operator, patches.local().evaluate_grid(t, t), operator, optimize=True
    )


def _cell_fits(
    local: GregoryPatchSet, n: int, samples: int = GUIDE_SAMPLES
) -> tuple[FloatArray, FloatArray]:
    """Per cell r = f n² + a n + b of an n × n grid over each patch (local coordinates), the
    :func:`guide_nets` macro net (R, 7, 7, 3) and the least-squares bicubic Bézier net (R, 4, 4, 3)
    of the patch's piece over the cell, from ``samples``² points of the piece."""
    guide, bicubic = _fit_operators(samples)
    t = np.linspace(0.0, 1.0, n * (samples - 1) + 1)
    values = local.evaluate_grid(t, t)  # (F, m, m, 3)
    window = np.arange(n)[:, None] * (samples - 1) + np.arange(samples)  # (n, samples)
    pieces = values[
        :, window[:, None, :, None], window[None, :, None, :]
    ]  # (F, n, n, samples, samples, 3)
    pieces = pieces.reshape(-1, samples, samples, 3)
    return (
        np.einsum("ia,rabd,jb->rijd", guide, pieces, guide, optimize=True),
        np.einsum("ia,rabd,jb->rijd", bicubic, pieces, bicubic, optimize=True),
    )


def split4_of_gregory(
    network: PatchNetwork, *, guided: bool = True, refine: int = 1
) -> PatchNetwork:
    """:func:`_split4_of_gregory`, each of its patches in the group of the Gregory patch it covers
    (the 4 n² sub-patches of patch f are ``4 n² f`` on)."""
    converted = _split4_of_gregory(network, guided=guided, refine=refine)
    if network.groups is None:
        return converted
    return replace(converted, groups=network.groups.repeat(4 * int(refine) ** 2))


def _split4_of_gregory(
    network: PatchNetwork, *, guided: bool = True, refine: int = 1
) -> PatchNetwork:
    """The split4 network (:func:`~g1patch.construct.split4.split4_network_from_targets`) of a
    Gregory network's targets (:func:`gregory_targets`): exactly G1, polynomial, through the same
    corners; with ``guided`` its interiors follow the Gregory surface (:func:`guide_nets`). Its
    fans on the boundary and at odd valence are the nearest of equal sectors to the Gregory fans
    (``split4_star(equal_sectors=True)``), the regular stars elsewhere.
    ``refine`` n > 1: of the targets of the network's surface on its mesh with each quad cut into
    n × n (:func:`refined_gregory_targets`, always guided): split4's stars differ from the Gregory
    fans they replace only near the vertices, so the distance to the Gregory surface shrinks about
    as 1/n; quad ``r = f n² + a n + b`` of the result covers cell (a, b) of patch f.
    Seams: assembled on the topology cut along them (each side a boundary,
    :func:`~g1patch.construct.split4.seams.seam_stars` keeping the seam tangents, so both sides get
    the same boundary curve), connected on the uncut one with the seams marked. Provenance
    ``from = gregory``."""
    if not (isinstance(refine, (int, np.integer)) and refine >= 1):
        raise InputError(f"refine: expected an integer ≥ 1, got {refine!r}")
    provenance = {**network.provenance, "method": "split4", "from": "gregory"}
    if refine > 1:
        provenance["refine"] = str(refine)
    topology = _topology_of(network, cut=False)
    seams = network.seam.reshape(-1)
    cut = bool(seams.any())
    if refine == 1:
        guide = guide_nets(network.patches) if guided else None  # type: ignore[arg-type]
        targets, frame = gregory_targets(network, cut=cut)
    else:
        uncut = grid_refinement(topology, refine)
        seams = _refined_seams(topology, seams, refine).reshape(-1)
        cells = grid_refinement(_topology_of(network, cut=True), refine) if cut else uncut
        targets, frame, guide = refined_gregory_targets(network, cells, cut=cut)
        topology = uncut.topology
    if not cut:
        mesh = QuadMesh(frame.to_world(targets.positions), targets.topology)
        parts = split4_patches(
            targets,
            targets.positions,
            np.zeros(3),
            1.0,
            guide,
            split4_star(targets, equal_sectors=True),
        )
        return split4_network_from_targets(
            mesh, targets, frame, provenance, guide=guide, parts=parts
        )
    cut_topology = targets.topology
    seam_halfedges = (cut_topology.twin < 0) & (topology.twin >= 0)
    if not np.array_equal(seams, seam_halfedges):
        raise ConstructionError(
            "split4: cutting the network along its seams leaves a seam uncut "
            "(a seam edge whose both ends have one sector)"
        )
    targets = _paired_seams(targets, topology, seam_halfedges)
    patches, extra, extra_normals, stars = split4_patches(
        targets,
        targets.positions,
        np.zeros(3),
        1.0,
        guide,
        seam_stars(targets, seam_halfedges, equal_sectors=True),
    )
    patches = patches.with_frame(frame)
    edge_of = np.empty(topology.n_edges, dtype=np.int64)
    edge_of[topology.halfedge_edge] = cut_topology.halfedge_edge
    points = np.concatenate(
        [frame.to_world(extra[edge_of]), frame.to_world(extra[cut_topology.n_edges :])]
    )
    point_normals = np.concatenate([extra_normals[edge_of], extra_normals[cut_topology.n_edges :]])
    vertices = np.zeros((topology.n_vertices, 3))
    vertices[topology.faces.reshape(-1)] = frame.to_world(
        targets.positions[cut_topology.faces.reshape(-1)]
    )
    vertex_normals = np.zeros((topology.n_vertices, 3))
    vertex_normals[topology.faces.reshape(-1)] = targets.normals[
        cut_topology.faces.reshape(-1)
    ]  # one sector's
    if network.vertex_normals is not None and len(network.vertex_normals) == network.n_corners:
        vertex_normals[: network.n_corners] = network.vertex_normals
    seam_edges = np.zeros(topology.n_edges, dtype=bool)
    seam_edges[topology.halfedge_edge] = seams
    return split4_network_from_points(
        topology,
        patches,
        np.concatenate([vertices, points]),
        np.concatenate([vertex_normals, point_normals]),
        provenance,
        seam_edges,
    )
