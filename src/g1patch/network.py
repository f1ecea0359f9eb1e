"""PatchNetwork: patches plus which patch edges and corners they share.

A network knows, for every patch edge ``(p, k)`` (edge k runs from corner k to corner k+1,
counter-clockwise, see :mod:`g1patch.patches`):

* ``edge_ids[p, k]``: the id of the shared curve; ``edge_reversed[p, k]`` is True when the
  patch runs along it against the curve's canonical direction;
* ``neighbor[p, k]`` / ``neighbor_edge[p, k]``: the patch and edge across it, or -1 on an open
  edge (and on a collapsed one);
* ``corner_ids[p, k]``: the id of the point at corner k, shared by all patches meeting there;
* ``seam[p, k]``: the shared edge is sharp on purpose (an infinitely sharp crease of the mesh):
  the two patches share the boundary curve (G0) but not the tangent plane. Both sides agree;
  open and collapsed edges are never seams.

* ``groups``: each patch's named group (:class:`~g1patch.mesh.groups.FaceGroups`: the group of
  the cage face it was made from, the mesh file's material or group), None without.

* ``hanging``: edges of a feature-adaptive network where a coarse patch meets several finer ones
  (:class:`HangingEdges`): each fine patch edge lies along a part of the coarse patch edge. Both
  sides have no neighbour in the arrays above and are not open edges.

On a consistently oriented network two neighbours run along their shared edge in opposite
directions; where they run the same way (a patch set with mixed orientation, e.g. a ``.bpt``
file) ``same_direction[p, k]`` is True and the check compares normals with a flipped sign.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from typing import Protocol

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .display import bbox_text, describe, patch_kind, picture, short_source
from .errors import G1PatchError, InputError, NonManifoldError, as_float_array, as_index_array
from .frame import Frame
from .gregory import GregoryPatchSet
from .mesh import QuadTopology
from .mesh.groups import FaceGroups
from .patches import PatchSet

__all__ = [
    "HangingEdges",
    "Patches",
    "PatchNetwork",
    "DISPLAY_RANGE",
    "display_frame",
    "unit_frame",
    "edge_parameters",
    "network_from_mesh",
    "network_from_patch_points",
    "patch_uvs",
]

#: the parameter corners (u, v) of a patch, corner k: (0,0), (1,0), (1,1), (0,1)
PARAMETER_CORNERS = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])


class Patches(Protocol):
    """What a network needs of its patches: a count and exact first derivatives anywhere."""

    def __len__(self) -> int: ...

    def take(self, indices: ArrayLike) -> Patches: ...

    def evaluate(self, uv: ArrayLike, du: int = 0, dv: int = 0) -> NDArray[np.float64]: ...

    def evaluate_grid(
        self, u: ArrayLike, v: ArrayLike | None = None, du: int = 0, dv: int = 0
    ) -> NDArray[np.float64]: ...

    def box(self, samples: int = ...) -> tuple[NDArray[np.float64], NDArray[np.float64]]: ...

    def corners(self) -> NDArray[np.float64]: ...

    def local_to(self, frame: Frame) -> Patches: ...


def edge_parameters(edge: NDArray[np.int64], t: NDArray[np.float64]) -> NDArray[np.float64]:
    """(u, v) of the point at fraction ``t`` along patch edge ``edge`` (counter-clockwise).

    Edge 0: (t, 0); edge 1: (1, t); edge 2: (1 − t, 1); edge 3: (0, 1 − t). ``edge`` and ``t``
    broadcast; returns ``broadcast shape + (2,)``.
    """
    edge, t = np.broadcast_arrays(np.asarray(edge), np.asarray(t, dtype=np.float64))
    start = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    direction = np.array([[1.0, 0.0], [0.0, 1.0], [-1.0, 0.0], [0.0, -1.0]])
    return start[edge] + t[..., None] * direction[edge]


@dataclass(frozen=True)
class HangingEdges:
    """Where a coarse patch edge is shared by several finer patch edges (a T-junction of a
    feature-adaptive network): per link, ``sides[i] = (fine patch, fine edge, coarse patch,
    coarse edge)`` and ``span[i] = (t0, t1)``, the fractions along the coarse edge (its own
    counter-clockwise direction) at the fine edge's start and end; the point at fraction ``s`` of
    the fine edge is the coarse edge's point at ``t0 + s (t1 − t0)`` (the two run opposite ways on
    an oriented network: ``t0 > t1``)."""

    sides: NDArray[np.int64]
    span: NDArray[np.float64]

    def __post_init__(self) -> None:
        sides = as_index_array("hanging sides", self.sides, (4,))
        span = as_float_array("hanging span", self.span, (2,))
        if len(span) != len(sides):
            raise InputError(
                f"hanging: {len(sides)} sides but {len(span)} spans; expected one of each per link"
            )
        wrong_span = ((span < 0.0) | (span > 1.0)).any(axis=1) | (span[:, 0] == span[:, 1])
        if wrong_span.any():
            bad = int(np.argmax(wrong_span))
            raise InputError(
                f"hanging: link {bad} spans {span[bad].tolist()} of its coarse edge; expected two "
                "different fractions in [0, 1]"
            )
        wrong_edge = ((sides[:, [1, 3]] < 0) | (sides[:, [1, 3]] > 3)).any(axis=1)
        if wrong_edge.any():
            bad = int(np.argmax(wrong_edge))
            raise InputError(
                f"hanging: link {bad} names patch edge {sides[bad].tolist()}; edges are 0…3"
            )
        object.__setattr__(self, "sides", sides)
        object.__setattr__(self, "span", span)

    def __len__(self) -> int:
        return len(self.sides)

    def mask(self, n_patches: int) -> NDArray[np.bool_]:
        """(P, 4) True on every patch edge that takes part in a link (fine or coarse side)."""
        out = np.zeros((n_patches, 4), dtype=bool)
        out[self.sides[:, 0], self.sides[:, 1]] = True
        out[self.sides[:, 2], self.sides[:, 3]] = True
        return out

    def coarse_parameters(self, s: NDArray[np.float64]) -> NDArray[np.float64]:
        """(H, len(s)) fractions along the coarse edges at fractions ``s`` of the fine ones."""
        t0, t1 = self.span[:, :1], self.span[:, 1:]
        return t0 + np.asarray(s, dtype=np.float64)[None, :] * (t1 - t0)

    def kept(self, kept: NDArray[np.bool_], index: NDArray[np.int64]) -> HangingEdges:
        """The links between patches where ``kept`` (P,) is True, renumbered by ``index``."""
        both = kept[self.sides[:, 0]] & kept[self.sides[:, 2]]
        sides = self.sides[both].copy()
        sides[:, [0, 2]] = index[sides[:, [0, 2]]]
        return HangingEdges(sides, self.span[both])


@dataclass(frozen=True)
class PatchNetwork:
    """Patches with their shared edges and corners (see the module docstring for the arrays)."""

    patches: Patches
    corner_ids: NDArray[np.int64]
    edge_ids: NDArray[np.int64]
    edge_reversed: NDArray[np.bool_]
    neighbor: NDArray[np.int64]
    neighbor_edge: NDArray[np.int64]
    same_direction: NDArray[np.bool_]
    edge_collapsed: NDArray[np.bool_]
    #: mesh vertex positions the network interpolates at ``corner_ids`` (None for patch files)
    vertices: NDArray[np.float64] | None = None
    #: unit normals of those vertices (the mesh's fan normals), the reference for folds
    vertex_normals: NDArray[np.float64] | None = None
    #: how the network was made: method and options, for reports and the file header
    provenance: dict[str, str] = field(default_factory=dict)
    #: (P, 4) patch edges that are sharp on purpose (None: none are); see the module docstring
    seam: NDArray[np.bool_] = None  # type: ignore[assignment]
    #: (P, 4, 2) texture coordinates at each patch's corners (u, v) = (0,0), (1,0), (1,1), (0,1),
    #: bilinear between (the mesh's ``vt``); None without
    uv: NDArray[np.float64] | None = None
    #: T-junctions between coarse and finer patches (None: the network is conforming)
    hanging: HangingEdges | None = None
    #: each patch's named group, that of its cage face (None without); see the module docstring
    groups: FaceGroups | None = None

    def __post_init__(self) -> None:
        count = len(self.patches)
        for name in ("corner_ids", "edge_ids", "neighbor", "neighbor_edge"):
            value = as_index_array(name, getattr(self, name), (4,))
            if value.shape != (count, 4):
                raise InputError(f"{name}: expected shape ({count}, 4), got {value.shape}")
            object.__setattr__(self, name, value)
        for name in ("edge_reversed", "same_direction"):
            value = np.ascontiguousarray(getattr(self, name), dtype=bool)
            if value.shape != (count, 4):
                raise InputError(f"{name}: expected shape ({count}, 4), got {value.shape}")
            object.__setattr__(self, name, value)
        object.__setattr__(
            self, "edge_collapsed", np.ascontiguousarray(self.edge_collapsed, dtype=bool)
        )
        for name in ("vertices", "vertex_normals"):
            if getattr(self, name) is not None:
                object.__setattr__(self, name, as_float_array(name, getattr(self, name), (3,)))
        object.__setattr__(self, "seam", self._checked_seam())
        if self.uv is not None:
            uv = as_float_array("uv", self.uv, (4, 2))
            if uv.shape != (count, 4, 2):
                raise InputError(f"uv: expected shape ({count}, 4, 2), got {uv.shape}")
            object.__setattr__(self, "uv", uv)
        if self.hanging is not None:
            self._check_hanging(self.hanging)
        if self.groups is not None and len(self.groups) != count:
            raise InputError(f"groups: expected one per patch ({count}), got {len(self.groups)}")

    def _check_hanging(self, hanging: HangingEdges) -> None:
        """Every link names patches of the network whose edges have no neighbour."""
        sides = hanging.sides
        if len(sides) and int(sides[:, [0, 2]].max()) >= self.n_patches:
            bad = int(np.argmax(sides[:, [0, 2]].max(axis=1)))
            raise InputError(
                f"hanging: link {bad} names patch {int(sides[bad, [0, 2]].max())}; the network has "
                f"{self.n_patches}"
            )
        for column in (0, 2):
            linked = self.neighbor[sides[:, column], sides[:, column + 1]] >= 0
            if linked.any():
                bad = int(np.argmax(linked))
                raise InputError(
                    f"hanging: link {bad}: patch {sides[bad, column]} edge "
                    f"{sides[bad, column + 1]} already has a neighbour"
                )

    def _checked_seam(self) -> NDArray[np.bool_]:
        """``seam`` as a (P, 4) bool array: True only on shared edges, equal on both sides."""
        count = len(self.patches)
        if self.seam is None:
            return np.zeros((count, 4), dtype=bool)
        seam = _as_bool("seam", self.seam, (count, 4))
        patch, edge = np.nonzero(seam)
        other = self.neighbor[patch, edge]
        lonely = np.flatnonzero(other < 0)
        if lonely.size:
            p, k = patch[lonely[0]], edge[lonely[0]]
            raise InputError(
                f"seam: patch {p} edge {k} is marked a seam but has no neighbour (open or "
                "collapsed edge)"
            )
        back = seam[other, self.neighbor_edge[patch, edge]]
        if not back.all():
            bad = int(np.argmin(back))
            raise InputError(
                f"seam: patch {patch[bad]} edge {edge[bad]} is a seam but its other side, patch "
                f"{other[bad]} "
                f"edge {self.neighbor_edge[patch[bad], edge[bad]]}, is not"
            )
        return seam

    def with_seams(self, seam_edges: ArrayLike) -> PatchNetwork:
        """This network with ``seam = seam_edges[edge_ids] & (neighbor ≥ 0)``: ``seam_edges``
        (n_edges,) bool marks curves by edge id; on open and collapsed edges it is ignored (they
        are sharp anyway)."""
        seam = _as_bool("seam_edges", seam_edges, (self.n_edges,))[self.edge_ids] & (
            self.neighbor >= 0
        )
        return replace(self, seam=seam)

    def take_patches(self, keep: ArrayLike) -> PatchNetwork:
        """The network of the patches where ``keep`` (P,) is True: an edge shared with a patch
        left out becomes open (no neighbour, no seam); corner and edge ids, points, UVs and groups
        of the kept patches stay as they are."""
        kept = _as_bool("keep", keep, (self.n_patches,))
        index = np.cumsum(kept) - 1
        neighbor = self.neighbor[kept]
        lost = neighbor >= 0
        lost[lost] = ~kept[neighbor[lost]]
        neighbor = np.where((neighbor >= 0) & ~lost, index[np.maximum(neighbor, 0)], -1)
        return replace(
            self,
            patches=self.patches.take(np.flatnonzero(kept)),
            corner_ids=self.corner_ids[kept],
            edge_ids=self.edge_ids[kept],
            edge_reversed=self.edge_reversed[kept],
            neighbor=neighbor,
            neighbor_edge=np.where(neighbor >= 0, self.neighbor_edge[kept], -1),
            same_direction=self.same_direction[kept],
            seam=self.seam[kept] & (neighbor >= 0),
            uv=None if self.uv is None else self.uv[kept],
            groups=None if self.groups is None else self.groups.take(kept),
            hanging=None if self.hanging is None else self.hanging.kept(kept, index),
        )

    @property
    def n_seams(self) -> int:
        """Number of shared edges that are seams (each counted once)."""
        return int(self.seam.sum()) // 2

    def corner_sectors(self) -> NDArray[np.int64]:
        """(P, 4) sector of every patch corner: the corners at one point that a walk around it
        reaches without crossing a seam share one id (the tangent plane they must agree on).

        Without seams, the corner ids. At a point where a seam ends, corners are joined across
        every shared edge that is not a seam (corner k of p is corner j + 1 of its neighbour q
        across edge (p, k) ↔ (q, j), corner j where both run the same way) and across collapsed
        edges (both corners are one point of the patch); elsewhere all corners of the point are
        one sector, as without seams. A dart (one seam ending at a point) leaves one sector there.
        """
        if not self.seam.any():
            return self.corner_ids
        from scipy.sparse import coo_matrix
        from scipy.sparse.csgraph import connected_components

        count = self.n_patches
        node = np.arange(4 * count).reshape(count, 4)
        patch, edge = np.nonzero((self.neighbor >= 0) & ~self.seam)
        other, other_edge = self.neighbor[patch, edge], self.neighbor_edge[patch, edge]
        same = self.same_direction[patch, edge]
        following = (other_edge + 1) % 4
        collapsed_patch, collapsed_edge = np.nonzero(self.edge_collapsed[self.edge_ids])
        ends = np.zeros(self.n_corners, dtype=bool)
        ends[self.corner_ids[self.seam | np.roll(self.seam, 1, axis=1)]] = (
            True  # edges k and k − 1 meet at corner k
        )
        free = ~ends[self.corner_ids]
        first = np.concatenate(
            [
                node[patch, edge],
                node[patch, (edge + 1) % 4],
                node[collapsed_patch, collapsed_edge],
                node[free],
            ]
        )
        second = np.concatenate(
            [
                node[other, np.where(same, other_edge, following)],
                node[other, np.where(same, following, other_edge)],
                node[collapsed_patch, (collapsed_edge + 1) % 4],
                4 * count + self.corner_ids[free],
            ]
        )
        size = 4 * count + self.n_corners
        graph = coo_matrix((np.ones(len(first)), (first, second)), shape=(size, size))
        labels = connected_components(graph, directed=False)[1]
        return labels[: 4 * count].reshape(count, 4).astype(np.int64)

    def __repr__(self) -> str:
        """``<PatchNetwork 6 gregory patches, interpolate, bbox (-1, -1, -1)…(1, 1, 1)>``: counts,
        method and shape (or source), seams, the surface's box (3 × 3 samples a patch); never the
        arrays."""
        return self.describe()

    def describe(self, name: str = "PatchNetwork", notes: Sequence[str] = ()) -> str:
        """The one-line repr under ``name``, with ``notes`` before the box."""
        provenance = self.provenance
        method = provenance.get("method")
        kind = method if method and method != "file" else patch_kind(self.patches)
        parts = [f"{self.n_patches} {kind} patches"]
        if provenance.get("shape"):
            parts.append(provenance["shape"])
        elif provenance.get("source"):
            parts.append(f"from {short_source(provenance['source'])}")
        if self.n_seams:
            parts.append(f"{self.n_seams} seams")
        if self.hanging is not None and len(self.hanging):
            parts.append(f"{len(self.hanging)} hanging edges")
        parts.extend(notes)
        if self.n_patches:
            parts.append(bbox_text(*self.patches.box()))
        return f"<{name} {', '.join(parts)}>"

    def _repr_png_(self) -> bytes | None:
        """A small shaded picture for Jupyter (None above
        :data:`g1patch.display.PREVIEW_MAX_PATCHES`)."""
        return picture("network", self, self.n_patches)

    @property
    def n_patches(self) -> int:
        return len(self.patches)

    @property
    def n_corners(self) -> int:
        return int(self.corner_ids.max()) + 1 if self.corner_ids.size else 0

    @property
    def n_edges(self) -> int:
        return int(self.edge_collapsed.shape[0])

    def shared_edges(self) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
        """Each interior edge once: ``(patch, edge)`` of its first side, arrays of shape (E,)."""
        patch = np.arange(len(self.neighbor))[:, None]
        first = (self.neighbor > patch) | (
            (self.neighbor == patch) & (self.neighbor_edge > np.arange(4))
        )
        patches, edges = np.nonzero(first)
        return patches.astype(np.int64), edges.astype(np.int64)

    def open_edges(self) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
        """``(patch, edge)`` of every edge with no neighbour that is not collapsed nor hanging."""
        open_ = (self.neighbor < 0) & ~self.edge_collapsed[self.edge_ids]
        if self.hanging is not None:
            open_ &= ~self.hanging.mask(self.n_patches)
        patches, edges = np.nonzero(open_)
        return patches.astype(np.int64), edges.astype(np.int64)

    def local_to(self, frame: Frame) -> PatchNetwork:
        """The same network in ``frame``'s local coordinates (patches and vertices)."""
        vertices = None if self.vertices is None else frame.to_local(self.vertices)
        return replace(self, patches=self.patches.local_to(frame), vertices=vertices)

    def bounding_box_diagonal(self) -> float:
        """Length of the diagonal of the box around the patch corners (the scale of G0 gaps)."""
        corners = self.patches.evaluate(
            np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
        ).reshape(-1, 3)
        return float(np.linalg.norm(corners.max(axis=0) - corners.min(axis=0)))


def _as_bool(name: str, value: ArrayLike, shape: tuple[int, ...]) -> NDArray[np.bool_]:
    """``value`` as a contiguous bool array of ``shape``: booleans, or integers 0 and 1."""
    array = np.asarray(value)
    if array.shape != shape:
        raise InputError(f"{name}: expected shape {shape}, got {array.shape}")
    if array.dtype != bool and not (
        np.issubdtype(array.dtype, np.integer) and np.isin(array, (0, 1)).all()
    ):
        raise InputError(f"{name}: expected booleans (or 0 and 1), got an array of {array.dtype}")
    return np.ascontiguousarray(array, dtype=bool)


def _cluster_points(points: NDArray[np.float64], tolerance: float) -> NDArray[np.int64]:
    """Ids that are equal for points closer than ``tolerance`` (connected components)."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components
    from scipy.spatial import cKDTree

    pairs = cKDTree(points).query_pairs(tolerance, output_type="ndarray")
    graph = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(len(points),) * 2)
    _, labels = connected_components(graph, directed=False)
    return labels.astype(np.int64)


def network_from_patch_points(
    patches: PatchSet, *, source: str = "patches", rtol: float = 1e-9
) -> PatchNetwork:
    """Build a network from patches nobody here built, by matching their boundary control points.

    Control points closer than ``rtol`` × the bounding-box diagonal are the same point. Two
    boundary curves are the same edge when their four control points match, in either order;
    a curve whose four points coincide is a collapsed edge (a triangular patch's pole). An edge
    used by more than two patches raises :class:`NonManifoldError`.
    """
    bezier = patches.convert("bezier").control  # boundary rows are control points in Bézier form
    count = len(patches)
    rows = np.stack(
        [bezier[:, :, 0], bezier[:, 3, :], bezier[:, ::-1, 3], bezier[:, 0, ::-1]], axis=1
    )  # (N, 4 edges, 4 points, 3), counter-clockwise
    flat = bezier.reshape(-1, 3)
    scale = float(np.linalg.norm(flat.max(axis=0) - flat.min(axis=0))) or 1.0
    labels = _cluster_points(rows.reshape(-1, 3), rtol * scale).reshape(count, 4, 4)
    corner_ids = np.unique(labels[:, :, 0], return_inverse=True)[1].reshape(count, 4)

    backward = labels[:, :, ::-1]
    is_reversed = _lexicographically_greater(labels, backward)
    canonical = np.where(is_reversed[..., None], backward, labels).reshape(-1, 4)
    unique_keys, edge_of, multiplicity = np.unique(
        canonical, axis=0, return_inverse=True, return_counts=True
    )
    edge_of = edge_of.reshape(-1)
    collapsed = (unique_keys == unique_keys[:, :1]).all(axis=1)
    overused = (multiplicity > 2) & ~collapsed
    if overused.any():
        bad = int(np.argmax(overused))
        users = np.nonzero(edge_of == bad)[0]
        raise NonManifoldError(
            f"{source}: a boundary curve is shared by {multiplicity[bad]} patches "
            f"(patches {', '.join(str(int(u) // 4) for u in users)}); at most 2 may share one"
        )

    neighbor = np.full(count * 4, -1, dtype=np.int64)
    order = np.argsort(edge_of, kind="stable")
    sorted_edges = edge_of[order]
    pair_start = np.nonzero(
        (sorted_edges[:-1] == sorted_edges[1:]) & ~collapsed[sorted_edges[:-1]]
    )[0]
    first, second = order[pair_start], order[pair_start + 1]
    neighbor[first], neighbor[second] = second, first
    slot = np.where(neighbor >= 0, neighbor, 0)
    same_direction = (neighbor >= 0) & (is_reversed.reshape(-1) == is_reversed.reshape(-1)[slot])
    return PatchNetwork(
        patches=patches,
        corner_ids=corner_ids,
        edge_ids=edge_of.reshape(count, 4),
        edge_reversed=is_reversed,
        neighbor=np.where(neighbor >= 0, neighbor // 4, -1).reshape(count, 4),
        neighbor_edge=np.where(neighbor >= 0, neighbor % 4, -1).reshape(count, 4),
        same_direction=same_direction.reshape(count, 4),
        edge_collapsed=collapsed,
        provenance={"source": source, "method": "file"},
    )


def _lexicographically_greater(a: NDArray[np.int64], b: NDArray[np.int64]) -> NDArray[np.bool_]:
    """``a > b`` comparing the last axis lexicographically."""
    differs = a != b
    first = np.argmax(differs, axis=-1)
    a_first = np.take_along_axis(a, first[..., None], axis=-1)[..., 0]
    b_first = np.take_along_axis(b, first[..., None], axis=-1)[..., 0]
    return differs.any(axis=-1) & (a_first > b_first)


def check_consistent(network: PatchNetwork) -> None:
    """Raise :class:`G1PatchError` if the neighbour arrays do not describe each other."""
    patch, edge = np.nonzero(network.neighbor >= 0)
    other, other_edge = network.neighbor[patch, edge], network.neighbor_edge[patch, edge]
    back = (network.neighbor[other, other_edge] == patch) & (
        network.neighbor_edge[other, other_edge] == edge
    )
    if not back.all():
        bad = int(np.argmin(back))
        raise G1PatchError(
            f"network: patch {patch[bad]} edge {edge[bad]} points to patch {other[bad]} edge "
            f"{other_edge[bad]}, which does not point back"
        )


def patch_uvs(face_uv: ArrayLike, patches_per_face: int) -> NDArray[np.float64]:
    """Each patch's corner UVs (P, 4, 2) from the faces' ``face_uv`` (F, 4, 2), bilinear
    ``uv(s, t) = (1−s)(1−t) u_0 + s(1−t) u_1 + s t u_2 + (1−s) t u_3``: one patch per face, its
    corner k at face corner k; four (split4), sub-patch ``4f + k`` covering ``(s, t) = ((u, v) +
    c_k)/2`` with ``c_k`` the face's parameter corner k. Corners on face corners are copied
    exactly (the weights there are 0 and 1)."""
    face_uv = np.asarray(face_uv, dtype=np.float64)
    if patches_per_face == 1:
        return np.ascontiguousarray(face_uv)
    if patches_per_face != 4:
        raise InputError(f"patches_per_face: expected 1 or 4, got {patches_per_face}")
    st = 0.5 * (PARAMETER_CORNERS[None, :, :] + PARAMETER_CORNERS[:, None, :])  # [k, corner]
    s, t = st[..., 0], st[..., 1]
    weights = np.stack([(1 - s) * (1 - t), s * (1 - t), s * t, (1 - s) * t], axis=-1)
    return np.einsum("kjc,fcd->fkjd", weights, face_uv).reshape(-1, 4, 2)


def network_from_mesh(
    topology: QuadTopology,
    patches: Patches,
    vertices: ArrayLike,
    vertex_normals: ArrayLike | None = None,
    provenance: dict[str, str] | None = None,
    seam_edges: ArrayLike | None = None,
) -> PatchNetwork:
    """The network of one patch per quad: patch f's edge k is the mesh half-edge ``4 f + k``.

    Canonical edge direction is ``edges[e, 0] → edges[e, 1]``; every interior edge is run in
    opposite directions by its two patches (the mesh is consistently oriented). ``seam_edges``
    (E,) bool, in ``topology.edges`` order, marks the mesh edges that are sharp on purpose; both
    patch edges on each become seams (:meth:`PatchNetwork.with_seams`: boundary edges are ignored).
    """
    faces = topology.faces
    twin = topology.twin.reshape(-1, 4)
    edge_ids = topology.halfedge_edge.reshape(-1, 4)
    network = PatchNetwork(
        patches=patches,
        corner_ids=faces,
        edge_ids=edge_ids,
        edge_reversed=faces != topology.edges[edge_ids, 0],
        neighbor=np.where(twin >= 0, twin // 4, -1),
        neighbor_edge=np.where(twin >= 0, twin % 4, -1),
        same_direction=np.zeros(faces.shape, dtype=bool),
        edge_collapsed=np.zeros(topology.n_edges, dtype=bool),
        vertices=np.asarray(vertices, dtype=np.float64),
        vertex_normals=None
        if vertex_normals is None
        else np.asarray(vertex_normals, dtype=np.float64),
        provenance=dict(provenance or {}),
    )
    return network if seam_edges is None else network.with_seams(seam_edges)


def network_of(
    patches: PatchNetwork | PatchSet | GregoryPatchSet, name: str = "surface"
) -> PatchNetwork:
    """A network itself, or the network of a :class:`~g1patch.patches.PatchSet` or
    :class:`~g1patch.gregory.GregoryPatchSet` (shared edges found by matching boundary control
    points, :func:`network_from_patch_points`; a Gregory set's boundary curves are its Bézier net's
    boundary rows, and the Gregory patches are kept). Anything else raises :class:`InputError`."""
    if isinstance(patches, PatchNetwork):
        return patches
    if isinstance(patches, PatchSet):
        return network_from_patch_points(patches, source="PatchSet")
    if isinstance(patches, GregoryPatchSet):
        bezier = PatchSet(patches.to_bezier_control(), "bezier", patches.frame)
        matched = network_from_patch_points(bezier, source="GregoryPatchSet")
        return replace(matched, patches=patches)
    raise InputError(
        f"{name}: expected a PatchNetwork, PatchSet or GregoryPatchSet, got {describe(patches)}"
    )


#: a picture's or page's surfaces are drawn in their own unit box when their size or distance from
#: the origin leaves ``[1 / DISPLAY_RANGE, DISPLAY_RANGE]`` (float32 and the drawing's absolute
#: tolerances hold well inside it); inside it they are drawn as they are
DISPLAY_RANGE = 1e6


def unit_frame(low: NDArray[np.float64], high: NDArray[np.float64]) -> Frame | None:
    """The frame ``c = (low + high) / 2``, ``s = |high − low|`` of the box ``low``, ``high`` when
    the box leaves the range ``1/R ≤ s ≤ R``, ``|c|∞ ≤ R s`` (``R =`` :data:`DISPLAY_RANGE`), else
    None (also for a box that is a point or not finite). Frame-free patches are measured, and
    triangle meshes drawn, in it: there ``|p_u × p_v| ~ s²`` neither overflows nor underflows, so
    a surface 1e-150 in size is measured as at size 1, not as patches of zero area."""
    scale = float(np.linalg.norm(high - low))
    centre = 0.5 * (low + high)
    if not (np.isfinite(scale) and scale > 0.0) or (
        1.0 / DISPLAY_RANGE <= scale <= DISPLAY_RANGE
        and float(np.abs(centre).max()) <= DISPLAY_RANGE * scale
    ):
        return None
    return Frame(centre, scale)


def display_frame(networks: Sequence[PatchNetwork]) -> Frame | None:
    """The frame (:func:`unit_frame` of all ``networks``' corners) to draw them in, or None when
    their size is within :data:`DISPLAY_RANGE`: a surface 1e-25 or 1e25 in size gives the same
    picture as at size 1."""
    corners = np.concatenate([network.patches.corners().reshape(-1, 3) for network in networks])
    return unit_frame(corners.min(axis=0), corners.max(axis=0))
