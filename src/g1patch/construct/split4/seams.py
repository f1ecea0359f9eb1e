"""split4 with seams: an assembly that keeps infinitely sharp creases (targets' ``seams``).

split4's G1 systems know no seams, so the targets are assembled on their mesh *cut open* along
the seams (:func:`cut_along_seams`: one vertex per corner sector with the sector's normal, each
seam two boundary edges), with stars that keep every seam tangent exactly (:func:`seam_stars`;
a nearly straight crease first gets opposite tangents, a hairpin equal lengths,
:func:`_paired_seams`): both sides of a seam then compute the same boundary curve, bit for bit,
and the sub-patches are connected on the uncut mesh with those edges marked as seams
(:func:`split4_seam_patches`). A seam between two vertices that each have one sector (an
isolated sharp edge between two darts) cannot be cut open; it is built smooth (the build says
so).
"""

from __future__ import annotations

import logging
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from ...errors import ConstructionError
from ...mesh import QuadTopology
from ...mesh.vertex_sectors import lonely_seams, sectors
from ...targets import Targets, halfedge_slots
from .assembly import Split4Parts, split4_patches
from .stars import SplitStar, fan_walk, split4_star

__all__ = [
    "SIN_FLOOR",
    "STRAIGHT_CREASE_DEG",
    "SeamCut",
    "cut_along_seams",
    "seam_stars",
    "split4_seam_patches",
]

logger = logging.getLogger(__name__)

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]
BoolArray = NDArray[np.bool_]


class SeamCut(NamedTuple):
    """Targets cut open along their seams (:func:`cut_along_seams`)."""

    #: the targets on the cut topology (faces in the same order, corner k still corner k), no seams
    targets: Targets
    #: (4F,) the cut topology's boundary half-edges that were seams
    seam_halfedges: BoolArray
    #: (V',) the vertex of the uncut topology each vertex of the cut one is a sector of
    sector_vertex: IntArray
    #: (E,) an edge of the cut topology for each uncut edge (of a seam: one of its two sides)
    edge_of: IntArray
    #: (E,) the seams cut open: the targets' seams but those between two one-sector vertices
    seams: BoolArray


def cut_along_seams(targets: Targets) -> SeamCut:
    """``targets`` on their topology cut open along the seams: vertex v becomes one vertex per
    sector (:func:`~g1patch.mesh.vertex_sectors.sectors`) at v's position, with the sector's normal
    (``corner_normals``); every slot keeps its tangent (a seam slot's in both copies), every face
    corner its interior targets."""
    topology = targets.topology
    seams = targets.seams & ~lonely_seams(topology, targets.seams)
    split = sectors(topology, seams)
    corner_sector = np.empty(topology.n_halfedges, dtype=np.int64)
    corner_sector[topology.ring_halfedges] = split.label
    cut = QuadTopology.from_faces(corner_sector.reshape(-1, 4), split.vertex.size)
    slot_out, slot_in = halfedge_slots(topology)
    cut_out, cut_in = halfedge_slots(cut)
    tangents = np.empty((int(cut.neighbor_offsets[-1]), 3))
    tangents[cut_in] = targets.tangents[slot_in]
    tangents[cut_out] = targets.tangents[slot_out]
    normals = targets.normals[split.vertex]
    normals[corner_sector] = targets.corner_normals.reshape(-1, 3)
    cut_targets = Targets(
        cut,
        targets.positions[split.vertex],
        normals,
        tangents,
        targets.interior,
        fallback=targets.fallback[split.vertex],
        rule=targets.rule,
        corner_normals=targets.corner_normals,
    )
    edge_of = np.empty(topology.n_edges, dtype=np.int64)
    edge_of[topology.halfedge_edge] = cut.halfedge_edge
    seam_halfedges = (cut.twin < 0) & (topology.twin >= 0)
    return SeamCut(cut_targets, seam_halfedges, split.vertex, edge_of, seams)


def split4_seam_patches(targets: Targets) -> tuple[Split4Parts, BoolArray]:
    """split4's parts (:func:`~g1patch.construct.split4.split4_patches`, in the targets' own
    coordinates) of targets with seams, assembled cut open along them (module docstring), with the
    midpoints and centres in the uncut topology's order (E + F) and the stars' flags per uncut
    vertex; and the seams kept (per edge)."""
    cut = cut_along_seams(targets)
    lonely = int(np.count_nonzero(targets.seams & ~cut.seams))
    if lonely:
        logger.warning(
            "split4: %d sharp edges between two darts cannot be cut open: built smooth "
            "(use --method gregory to keep them)",
            lonely,
        )
    length = np.linalg.norm(cut.targets.normals, axis=1)
    undefined = np.flatnonzero(~(np.abs(length - 1.0) <= 1e-6))
    if undefined.size:
        vertex = int(cut.sector_vertex[undefined[0]])
        raise ConstructionError(
            f"split4: vertex {vertex} has a sector between sharp edges without a defined normal "
            f"(a degenerate face corner there; {undefined.size} sectors affected)"
        )
    cut_targets = _paired_seams(cut.targets, targets.topology, cut.seam_halfedges)
    patches, extra, extra_normals, stars = split4_patches(
        cut_targets,
        cut_targets.positions,
        np.zeros(3),
        1.0,
        None,
        seam_stars(cut_targets, cut.seam_halfedges),
    )
    n_cut_edges = cut_targets.topology.n_edges
    extra = np.concatenate([extra[cut.edge_of], extra[n_cut_edges:]])
    extra_normals = np.concatenate([extra_normals[cut.edge_of], extra_normals[n_cut_edges:]])
    n_vertices = targets.topology.n_vertices
    slot_out, _ = halfedge_slots(targets.topology)
    cut_out, _ = halfedge_slots(cut_targets.topology)
    star = targets.tangents.copy()  # the uncut boundary's virtual slots: their targets
    cosine = np.zeros(len(star))
    star[slot_out], cosine[slot_out] = stars.star[cut_out], stars.cosine[cut_out]
    factor = np.ones(n_vertices)
    np.minimum.at(factor, cut.sector_vertex, stars.factor)
    uncut = SplitStar(
        star,
        cosine,
        np.bincount(cut.sector_vertex, stars.refitted, minlength=n_vertices) > 0,
        np.bincount(cut.sector_vertex, stars.shrunk, minlength=n_vertices) > 0,
        factor,
    )
    return (patches, extra, extra_normals, uncut), cut.seams


#: two seams whose tangents are this close to parallel (the sine of their angle) bound a hairpin
#: sector: their lengths are made equal (:func:`_paired_seams`)
SIN_FLOOR = 0.2
#: a sector between two different seams takes its star's second axis from both seam tangents
#: when the sine of its turn is at least this (else, a straightened crease, by least squares)
SIN_EXACT = 1e-6


#: a vertex whose two seams' tangents are at least this far apart (degrees) is a straight crease
STRAIGHT_CREASE_DEG = 150.0


def _paired_seams(
    targets: Targets, topology: QuadTopology, seam_halfedges: NDArray[np.bool_]
) -> Targets:
    """The two seams that bound a sector of two or more faces made such that the sector's regular
    star through both exists and stays short, in every copy (both sides still share them):

    * nearly straight (:data:`STRAIGHT_CREASE_DEG`): opposite, ``±(t_1 − t_2)/2`` (its turn is
      then π): a straight crease through a vertex, the straight bar of a T where a third crease
      ends on it;
    * nearly parallel (a hairpin, the sine of their angle below :data:`SIN_FLOOR`, the sector
      turning by nearly 2π): of equal length, ``√(|t_1| |t_2|)``, which keeps the star's second
      axis ``(t_2 − t_1 cos Φ) / sin Φ`` as long as t_1 where sin Φ is small.

    A seam that two such sectors would pair with different partners (three seams nearly a
    straight line apart) keeps its tangent."""
    cut = targets.topology
    slot_out, slot_in = halfedge_slots(cut)
    h = np.flatnonzero(seam_halfedges)
    seam_key = np.full(len(targets.tangents), -1, dtype=np.int64)  # (original vertex, seam edge)
    seam_key[np.concatenate([slot_out[h], slot_in[h]])] = np.concatenate(
        [topology.faces.reshape(-1)[h], topology.target(h)]
    ) * topology.n_edges + np.tile(topology.halfedge_edge[h], 2)
    offsets = cut.neighbor_offsets
    first, last = offsets[:-1], offsets[1:] - 1
    bounded = (
        (cut.face_count >= 2)
        & (seam_key[first] >= 0)
        & (seam_key[last] >= 0)
        & (seam_key[first] != seam_key[last])
    )
    first, last = first[bounded], last[bounded]
    t1, t2 = targets.tangents[first], targets.tangents[last]
    lengths = np.linalg.norm(t1, axis=1) * np.linalg.norm(t2, axis=1)
    cosine = np.divide(
        np.einsum("nd,nd->n", t1, t2), lengths, out=np.ones_like(lengths), where=lengths > 0
    )
    straight = cosine <= np.cos(np.radians(STRAIGHT_CREASE_DEG))
    hairpin = cosine >= np.sqrt(1.0 - SIN_FLOOR**2)
    paired = (straight | hairpin) & (lengths > 0)  # a zero tangent (a collapsed edge) pairs none
    ends = np.sort(np.stack([seam_key[first], seam_key[last]], axis=1)[paired], axis=1)
    pairs, one = np.unique(ends, axis=0, return_index=True)  # both sectors of a 2-seam vertex
    keys, count = np.unique(pairs, return_counts=True)
    alone = np.isin(pairs, keys[count == 1]).all(axis=1)
    if not alone.any():
        return targets
    which = np.flatnonzero(paired)[one[alone]]
    t1, t2 = targets.tangents[first[which]], targets.tangents[last[which]]
    mean = np.sqrt(lengths[which])[:, None]
    half = 0.5 * (t1 - t2)
    key_of = np.concatenate([seam_key[first[which]], seam_key[last[which]]])
    value = np.where(
        np.tile(straight[which], 2)[:, None],
        np.concatenate([half, -half]),
        np.concatenate(
            [t1 / np.linalg.norm(t1, axis=1)[:, None], t2 / np.linalg.norm(t2, axis=1)[:, None]]
        )
        * np.tile(mean, (2, 1)),
    )
    order = np.argsort(key_of)  # the keys are distinct: each seam in one pair
    slots = np.flatnonzero(seam_key >= 0)
    position = np.minimum(np.searchsorted(key_of[order], seam_key[slots]), len(order) - 1)
    moved = key_of[order[position]] == seam_key[slots]
    tangents = targets.tangents.copy()
    tangents[slots[moved]] = value[order[position[moved]]]
    return targets.with_changes(tangents=tangents)


def seam_stars(
    targets: Targets, seam_halfedges: NDArray[np.bool_], *, equal_sectors: bool = False
) -> SplitStar:
    """split4's stars on a topology cut along seams (``seam_halfedges``: the cut's boundary
    half-edges that were seams), where both sides of a seam must keep its tangents exactly.

    Elsewhere :func:`~g1patch.construct.split4.split4_star` (``equal_sectors`` passed on). At a
    vertex copy with k ≥ 2 faces and a seam slot e (0 or k): the regular star ``t_j = t_e cos φ_j +
    b sin φ_j``, ``φ_j = |j − e| θ``, ``θ = Φ / k`` (Φ the fan's turn from slot 0 to slot k about
    the sector normal), b from the other end's seam tangent, ``b = (t_k − t_0 cos Φ) / sin Φ``,
    where both ends are different seams and ``|sin Φ| ≥`` :data:`SIN_EXACT` (the two made ready
    for it by :func:`_paired_seams`), else by least squares over the other slots (a dart's end,
    a straightened crease: there ``t_k = t_0 cos Φ`` already); ``c_v = cos θ``, no length
    safeguard. A one-face sector keeps its tangents (as split4 does).
    """
    topology = targets.topology
    base = split4_star(targets, equal_sectors=equal_sectors)
    star, cosine, factor = base.star.copy(), base.cosine.copy(), base.factor.copy()
    offsets = topology.neighbor_offsets
    origin = topology.faces.reshape(-1)
    seam_at = np.zeros(int(offsets[-1]), dtype=bool)
    slot_out, slot_in = halfedge_slots(topology)
    seam_at[slot_out[seam_halfedges]] = True
    seam_at[slot_in[seam_halfedges]] = True
    copies = np.unique(
        np.concatenate([origin[seam_halfedges], topology.target(np.flatnonzero(seam_halfedges))])
    )
    k = topology.face_count[copies]
    first, last = offsets[copies], offsets[copies + 1] - 1
    single = copies[k == 1]
    star[offsets[single][:, None] + np.arange(2)] = targets.tangents[
        offsets[single][:, None] + np.arange(2)
    ]
    factor[single] = 1.0
    many = k >= 2
    copies, k, first, last = copies[many], k[many], first[many], last[many]
    if not copies.size:
        return SplitStar(star, cosine, base.refitted, base.shrunk & (factor < 1.0), factor)
    owner, j, slot, t, total = fan_walk(targets, copies)
    theta = total / k
    anchor_last = ~seam_at[first] & seam_at[last]  # the seam is slot k only
    e = np.where(anchor_last, k, 0)
    anchor = targets.tangents[np.where(anchor_last, last, first)]
    phi = np.abs(j - e[owner]) * theta[owner]
    c, sn = np.cos(phi), np.sin(phi)
    residual = t - c[:, None] * anchor[owner]
    free = j != e[owner]
    b = np.asarray(
        np.stack(
            [
                np.bincount(owner, np.where(free, sn * residual[:, d], 0.0), minlength=copies.size)
                for d in range(3)
            ],
            axis=1,
        ),
        dtype=np.float64,
    )
    b /= np.maximum(
        np.bincount(owner, np.where(free, sn * sn, 0.0), minlength=copies.size), 1e-300
    )[:, None]
    both = seam_at[first] & seam_at[last]
    different = (targets.tangents[first] != targets.tangents[last]).any(axis=1)
    sin_total = np.sin(total)
    exact = both & different & (np.abs(sin_total) >= SIN_EXACT)
    b[exact] = (
        targets.tangents[last[exact]] - np.cos(total[exact])[:, None] * anchor[exact]
    ) / sin_total[exact, None]
    fitted = c[:, None] * anchor[owner] + sn[:, None] * b[owner]
    fitted[seam_at[slot]] = t[
        seam_at[slot]
    ]  # the seams' own tangents, bit for bit: both sides share them
    star[slot] = fitted
    cosine[slot] = np.cos(theta)[owner]
    factor[copies] = 1.0
    return SplitStar(star, cosine, base.refitted, base.shrunk & (factor < 1.0), factor)
