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
* ``normals``: the network's vertex normals; ``corner_normals``: the patches' normals at their corners;
* ``seams``: the network's seams per mesh edge.

The result is compared with the Gregory surface itself (:func:`surface_deviation`).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ..errors import InputError
from ..frame import Frame
from ..gregory import GregoryPatchSet
from ..mesh import QuadMesh, QuadTopology
from ..network import PatchNetwork
from ..patches import CORNER_PARAMETERS
from ..targets import Targets, halfedge_slots

__all__ = ["gregory_targets", "split4_of_gregory", "surface_deviation"]

FloatArray = NDArray[np.float64]


def _topology_of(network: PatchNetwork) -> QuadTopology:
    """The quad mesh a one-patch-per-quad network was built on: faces = ``corner_ids``."""
    if not isinstance(network.patches, GregoryPatchSet):
        raise InputError(f"network: expected Gregory patches, got {type(network.patches).__name__}")
    return QuadTopology.from_faces(network.corner_ids, network.n_corners)


def gregory_targets(network: PatchNetwork) -> tuple[Targets, Frame]:
    """The :class:`Targets` a Gregory network interpolates (module docstring), in the local
    coordinates of its frame (``Frame.of_points`` of the corners where the patches carry none)."""
    topology = _topology_of(network)
    patches: GregoryPatchSet = network.patches  # type: ignore[assignment]
    frame = patches.frame or Frame.of_points(patches.points[:, :4])
    points = patches.points if patches.frame is not None else frame.to_local(patches.points)
    corners = points[:, :4]
    positions = np.zeros((topology.n_vertices, 3))
    positions[topology.faces.reshape(-1)] = corners.reshape(-1, 3)
    slot_out, slot_in = halfedge_slots(topology)
    tangents = np.zeros((int(topology.neighbor_offsets[-1]), 3))
    tangents[slot_in] = (3.0 * (points[:, 5 + 2 * ((np.arange(4) + 1) % 4)] - np.roll(corners, -1, axis=1))).reshape(-1, 3)
    tangents[slot_out] = (3.0 * (points[:, 4:12:2] - corners)).reshape(-1, 3)
    corner_normals = patches.normals(CORNER_PARAMETERS)
    if network.vertex_normals is not None and len(network.vertex_normals) == topology.n_vertices:
        normals = network.vertex_normals
    else:
        normals = np.zeros((topology.n_vertices, 3))
        np.add.at(normals, topology.faces.reshape(-1), corner_normals.reshape(-1, 3))
        normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    seams = np.zeros(topology.n_edges, dtype=bool)
    seams[topology.halfedge_edge] = network.seam.reshape(-1)
    targets = Targets(topology, positions, normals, tangents, points[:, 12:].reshape(-1, 4, 2, 3),
                      seams=seams, rule="gregory network", corner_normals=corner_normals)
    return targets, frame


#: samples per direction and patch of the guide fit (:func:`guide_nets`): 2× the 6 unknowns, both ends
GUIDE_SAMPLES = 13


def guide_nets(patches: GregoryPatchSet, samples: int = GUIDE_SAMPLES) -> FloatArray:
    """Per patch the (F, 7, 7, 3) macro net of its least-squares C1 2×2 bicubic B-spline (knots
    ``[0,0,0,0,½,½,1,1,1,1]``) on a ``samples``² grid: ``X = B⁺ S B⁺ᵀ``, then the double knot at ½
    written out (row and column 3 the midpoints of their neighbours). Local coordinates."""
    from scipy.interpolate import BSpline

    from .split4 import BSPLINE_KNOTS

    t = np.linspace(0.0, 1.0, samples)
    inverse = np.linalg.pinv(BSpline.design_matrix(t, BSPLINE_KNOTS, 3).toarray())  # (6, samples)
    expand = np.zeros((7, 6))
    expand[[0, 1, 2, 4, 5, 6], [0, 1, 2, 3, 4, 5]] = 1.0
    expand[3, 2:4] = 0.5
    operator = expand @ inverse  # (7, samples)
    return np.einsum("ia,fabd,jb->fijd", operator, patches.local().evaluate_grid(t, t), operator, optimize=True)


def split4_of_gregory(network: PatchNetwork, *, guided: bool = True) -> PatchNetwork:
    """The split4 network (:func:`~g1patch.construct.split4.split4_network_from_targets`) of a
    Gregory network's targets (:func:`gregory_targets`): exactly G1, polynomial, through the same
    corners; with ``guided`` its interiors follow the Gregory surface (:func:`guide_nets`).
    Provenance ``from = gregory``."""
    from .split4 import split4_network_from_targets

    targets, frame = gregory_targets(network)
    mesh = QuadMesh(frame.to_world(targets.positions), targets.topology)
    provenance = {**network.provenance, "method": "split4", "from": "gregory"}
    guide = guide_nets(network.patches) if guided else None  # type: ignore[arg-type]
    return split4_network_from_targets(mesh, targets, frame, provenance, guide=guide)


#: Gauss–Newton steps of :func:`surface_deviation`'s foot points
FOOT_STEPS = 3
#: samples per direction and Gregory patch from which the foot-point search starts
SEARCH_SAMPLES = 17


def surface_deviation(network: PatchNetwork, split4: PatchNetwork, samples: int = 5) -> tuple[float, float]:
    """How far the split4 surface ``s`` lies from the Gregory surface ``g``, model units:
    ``(parametric, geometric)``, maxima over a ``samples``² grid per quad (``samples`` odd;
    sub-patch ``4f + k`` covers ``(uv + corner_k) / 2`` of patch f).

    ``parametric = max |g(u, v) − s(u, v)|``. ``geometric`` = max distance of the samples of ``s``
    to their foot points on ``g``: start at the nearest of :data:`SEARCH_SAMPLES`² samples per
    Gregory patch (any patch), then :data:`FOOT_STEPS` Gauss–Newton steps ``(JᵀJ) δ = Jᵀ (p − g)``,
    ``J = [g_u g_v]``, clamped to that patch, the nearest point seen kept: an upper bound of the
    distance to the surface."""
    from scipy.spatial import cKDTree

    from ..gregory import gregory_weights

    if samples < 3 or samples % 2 == 0:
        raise InputError(f"samples: expected an odd number ≥ 3, got {samples!r}")
    gregory: GregoryPatchSet = network.patches  # type: ignore[assignment]
    frame = gregory.frame or Frame(np.zeros(3), 1.0)
    local = gregory.local().points  # (F, 20, 3)
    half = np.linspace(0.0, 1.0, (samples + 1) // 2)
    uv = np.stack(np.meshgrid(half, half, indexing="ij"), axis=-1).reshape(-1, 2)  # (K, 2)
    corner = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    points = frame.to_local(split4.patches.evaluate(uv).reshape(-1, 3))  # sub-patch by sub-patch: (4F K, 3)
    at = np.tile(0.5 * (uv[None] + corner[:, None]), (len(local), 1, 1)).reshape(-1, 2)
    patch = np.repeat(np.arange(len(local)), 4 * len(uv))

    def value(du: int = 0, dv: int = 0) -> FloatArray:
        return np.einsum("nm,nmd->nd", gregory_weights(at[:, 0], at[:, 1], du, dv), local[patch], optimize=True)

    parametric = float(np.linalg.norm(points - value(), axis=-1).max())
    t = np.linspace(0.0, 1.0, SEARCH_SAMPLES)
    grid = gregory.local().evaluate_grid(t, t).reshape(-1, 3)
    nearest = cKDTree(grid).query(points)[1]
    patch, rest = np.divmod(nearest, SEARCH_SAMPLES**2)
    at = np.stack([t[rest // SEARCH_SAMPLES], t[rest % SEARCH_SAMPLES]], axis=-1)
    best = np.linalg.norm(points - value(), axis=-1)
    for _ in range(FOOT_STEPS):
        residual, g_u, g_v = points - value(), value(1, 0), value(0, 1)
        a, b, c = (np.einsum("nd,nd->n", x, y) for x, y in ((g_u, g_u), (g_u, g_v), (g_v, g_v)))
        r_u, r_v = np.einsum("nd,nd->n", g_u, residual), np.einsum("nd,nd->n", g_v, residual)
        det = a * c - b * b
        regular = det > 1e-300
        step = np.stack([c * r_u - b * r_v, a * r_v - b * r_u], axis=-1) / np.where(regular, det, 1.0)[:, None]
        at = np.clip(at + np.where(regular[:, None], step, 0.0), 0.0, 1.0)
        best = np.minimum(best, np.linalg.norm(points - value(), axis=-1))  # a clamped step may lead away
    geometric = float(best.max())
    return parametric * frame.scale, min(geometric, parametric) * frame.scale
