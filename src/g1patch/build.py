"""Mesh → targets → assembly → network: the one call every front end uses (DESIGN §1).

``build_network(mesh, method, shape)`` picks a targets rule (``shape``: what the surface should
look like) and an assembly (``method``: how it is made exactly G1, or G1 at corners only) and runs
them in centred, unit-scaled coordinates ``x_local = (x − centre)/scale`` (bounding-box centre and
diagonal, :class:`~g1patch.frame.Frame`). The patches keep those local coordinates and carry the
frame, so what is stored is exactly G1 wherever the model sits (translated by 1e6, world
coordinates would round neighbouring control points apart by 1e-10 of a unit patch).

**Fold guard.** Any valid targets assemble exactly G1, but a local shape rule can still make a
patch turn back on itself, or bend more than it must, on a very coarse or irregular cage (a face
whose corners turn by more than a right angle). The faces at risk are compared with the faired
limit-interpolating surface of the same cage, solved on the part of the mesh round them
(:func:`~g1patch.targets.limit_interpolate.limit_interpolate_near`): where the rule's own surface
folds, or bends more than 1.1 × as far (the yardstick of issue 31), the vertices of the faces
that do take that surface's targets (:func:`~g1patch.targets.interpolate.retreat`), with their
rings where the seams between the two fold or bend; where the faired surface folds too, they move
towards the previous release's regular stars (:func:`~g1patch.targets.interpolate.retreat_to_star`).
The faired surface relaxes a vertex where passing through it would fold or pinch the surface;
such vertices are said (one warning line, the provenance's ``relaxed_vertices`` and
``relaxed_distance``). The provenance counts the vertices given the faired targets
(``faired_vertices``) and those moved towards stars (with the rule's own fallbacks,
``fallback_vertices``).
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import Generic, TypeVar

import numpy as np

from .adaptive import refine_adaptively
from .construct import ASSEMBLIES, DEFAULT_METHOD, METHODS, NetworkParts
from .construct.corner import TWISTS, TwistRule, build_corner_network
from .continuity import FOLD_SAMPLES, folded_patches, folds_and_bend
from .errors import BudgetError, ConstructionError, InputError, check_choice
from .fidelity import limit_distance
from .frame import Frame
from .kernels import use_kernels
from .memory import memory_budget
from .mesh import INFINITE_SHARPNESS, QuadMesh, QuadTopology
from .mesh.neighbourhood import grow
from .network import Patches, PatchNetwork, patch_uvs
from .subdivision import catmull_clark_cage
from .subdivision import refine as subdivide
from .targets import SHAPES, Targets, shape_targets
from .targets.interpolate import retreat, retreat_to_star
from .targets.limit_interpolate import interpolating_cage, limit_interpolate_near
from .targets.local import NORMALS, TANGENTS, NormalRule, TangentRule, slot_vertices

__all__ = [
    "METHODS",
    "BuildEstimate",
    "build_gregory_network",
    "build_network",
    "build_split4_network",
    "check_budget",
    "estimate_build",
    "memory_budget",
    "DEFAULT_TOLERANCE",
    "LIMIT_SHAPES",
    "MAX_TOLERANCE_STEPS",
]

#: whatever an assembly returns (its patches, or its patches and more)
A = TypeVar("A")
logger = logging.getLogger(__name__)


#: the shapes that are a Catmull–Clark limit, whose distance to it a build measures
LIMIT_SHAPES = ("limit", "limit-interpolate")
#: the largest distance from the exact Catmull–Clark limit a limit shape may have by default, of
#: the bounding-box diagonal (``--tolerance``)
DEFAULT_TOLERANCE = 1e-3
#: Catmull–Clark steps the tolerance may add at most (each one quarters the faces' size and roughly
#: halves the distance, which is largest at extraordinary vertices: ``catmark_xord_boundary`` needs
#: 6 for 1e-4 of the diagonal, 4,096× its patches); the memory budget usually stops a big cage first
MAX_TOLERANCE_STEPS = 6


#: a risky face whose largest normal turn exceeds this multiple of the faired surface's there is
#: given the faired targets (the bar of issue 31: the interpolant's 99th-percentile bend within
#: 1.1 × the limit-interpolating surface's)
BEND_RATIO = 1.1
#: grid per patch on which :func:`_face_turns` compares the bends
TURN_SAMPLES = 5
#: how far (of the diagonal) a vertex may move in the fold guard's faired targets and still count
#: as passed through (the solved cage's residual is below 1e-10)
RELAXED_DISTANCE = 1e-9
#: how far the fold guard moves the targets of faces that still fold towards regular stars, in
#: turn (:func:`~g1patch.targets.interpolate.retreat_to_star`)
STAR_WEIGHTS = (0.5, 1.0, 1.0)
#: the most faces at risk the fold guard compares with the faired surface (beyond, the folded
#: ones alone: its solve then follows the folds, not the mesh)
GUARD_COMPARED_FACES = 20_000
#: retreats the fold guard tries at most
GUARD_STEPS = 3
#: the vertex rings of faces round the retreated vertices' faces on which the guard solves the
#: faired targets (the part's rim is a boundary: its own rules reach two rings in)
FAIR_RINGS = 4
#: what puts a face at risk of folding (:func:`_faces_at_risk`)
RISK_TURN = np.radians(15.0)
RISK_TANGENT = np.radians(30.0)
RISK_LENGTH = (0.5, 1.6)


def semi_sharp_levels(mesh: QuadMesh) -> int:
    """Catmull–Clark steps after which no semi-sharp edge or vertex is left: ``⌈s⌉`` of the largest
    sharpness below infinite (0 if none). A semi-sharp crease is sharp for that many levels and then
    smooth (OpenSubdiv), a detail finer than one patch per cage face can follow, so the limit shapes
    refine that far first."""
    features = mesh.features
    values = np.concatenate([features.edge_sharpness, features.vertex_sharpness])
    semi = values[(values > 0) & (values < INFINITE_SHARPNESS)]
    return int(np.ceil(semi.max())) if semi.size else 0


#: the refinement's peak per refined face, bytes: the last step's arrays (~650 B, tracemalloc) and
#: the level before it (a quarter as many faces)
REFINE_BYTES_PER_FACE = 820
#: what a refined mesh holds per face while its network is built, bytes (~350 B measured)
MESH_BYTES_PER_FACE = 360


@dataclass(frozen=True)
class BuildEstimate:
    """What a build will make, known before it starts: Catmull–Clark ``steps``, ``faces`` after
    them, ``patches`` and the peak ``bytes`` it allocates (from the assembly's measured peak per
    face, :attr:`~g1patch.construct.stage.Assembly.peak_bytes_per_face`)."""

    steps: int
    faces: int
    patches: int
    bytes: int


def refine_steps(mesh: QuadMesh, shape: str, refine: int, semi_sharp_first: bool = True) -> int:
    """The Catmull–Clark steps a build takes: ``refine``, and for the limit shapes at least
    :func:`semi_sharp_levels` (unless ``semi_sharp_first`` is False: a Gregory limit build with a
    tolerance refines around semi-sharp features only, :func:`_local_refinement`)."""
    limit = shape in LIMIT_SHAPES and semi_sharp_first
    return max(int(refine), semi_sharp_levels(mesh) if limit else 0)


def _local_refinement(method: str, shape: str, tolerance: float | None) -> bool:
    """Whether the build refines where its network is off the limit only (Gregory limit networks
    measured against a tolerance: :mod:`g1patch.adaptive`), semi-sharp features included, rather
    than the whole cage."""
    return method == "gregory" and shape == "limit" and tolerance is not None


#: faces from which the estimate asks whether the kernels run (below, the per-face figures of
#: either path leave a build far under any budget)
_BUDGET_FACES = 10_000


def estimate_build(
    mesh: QuadMesh, method: str, shape: str, refine: int = 0, semi_sharp_first: bool = True
) -> BuildEstimate:
    """The size of :func:`build_network`'s result and its peak memory, from counts alone (the
    assembly's peak per face on the path that will run: the kernels', or NumPy's where numba has
    no writable cache); ``semi_sharp_first`` as :func:`refine_steps`."""
    assembly = ASSEMBLIES[method]
    steps = refine_steps(mesh, shape, refine, semi_sharp_first)
    faces = mesh.n_faces * 4**steps
    refined = faces * REFINE_BYTES_PER_FACE if steps else 0
    held = faces * MESH_BYTES_PER_FACE if steps else 0
    uncached = faces >= _BUDGET_FACES and not use_kernels(True)  # small builds: numba not loaded
    per_face = assembly.numpy_peak_bytes_per_face if uncached else assembly.peak_bytes_per_face
    peak = max(refined, held + faces * per_face)
    return BuildEstimate(steps, faces, faces * assembly.patches_per_face, peak)


def size_text(count: float) -> str:
    """``1.5 GB``, ``820 MB``, ``12 kB``: bytes in decimal units, 2–3 significant digits."""
    for unit, scale in (("TB", 1e12), ("GB", 1e9), ("MB", 1e6), ("kB", 1e3)):
        if count >= scale:
            return f"{count / scale:.3g} {unit}"
    return f"{int(count)} B"


def check_budget(
    estimate: BuildEstimate,
    method: str,
    max_memory: int | None = None,
    max_patches: int | None = None,
) -> None:
    """Refuse (:class:`BudgetError`) a build whose estimate is above ``max_memory`` bytes (default
    :func:`memory_budget`) or makes more than ``max_patches`` patches (where its result must fit
    a format, e.g. the network file's)."""
    budget = memory_budget() if max_memory is None else max_memory
    steps = f" after {estimate.steps} Catmull–Clark steps" if estimate.steps else ""
    if max_patches is not None and estimate.patches > max_patches:
        raise BudgetError(
            f"the build would make {estimate.patches:,} {method} patches{steps}, more than a "
            f"network file holds ({max_patches:,}): use fewer --refine steps{_other(method)}"
        )
    if estimate.bytes <= budget:
        return
    raise BudgetError(
        f"the build would make {estimate.patches:,} {method} patches{steps} and need about "
        f"{size_text(estimate.bytes)}, above the memory budget of {size_text(budget)} "
        f"(--max-memory; default half of this machine's RAM): use fewer --refine steps"
        f"{_other(method)} or a larger --max-memory"
    )


def _other(method: str) -> str:
    """``", --method gregory"`` (the leanest assembly) unless that is ``method``."""
    return "" if method == "gregory" else ", --method gregory"


def _provenance(
    mesh: QuadMesh,
    method: str,
    shape: str,
    tangents: str,
    targets: Targets,
    refine: int,
    repairs: tuple[str, ...],
) -> dict[str, str]:
    provenance = {
        "method": method,
        "shape": shape,
        "refine": str(refine),
        "fallback_vertices": str(targets.n_fallback),
    }
    if shape == "legacy":
        provenance["tangents"] = tangents
    if targets.seams.any():
        provenance["seams"] = str(int(targets.seams.sum()))
    if mesh.source:
        provenance["source"] = str(mesh.source)
    if repairs:
        provenance["repairs"] = ", ".join(repairs)
    return provenance


def _faces_at_risk(targets: Targets, *, compiled: bool = True) -> np.ndarray:
    """Faces whose targets are far from a smooth regular patch, where a fold is possible: a corner
    that needed a fallback, corner normals more than :data:`RISK_TURN` apart across an edge, or an
    edge tangent off its chord by more than :data:`RISK_TANGENT` in angle or outside
    :data:`RISK_LENGTH` × its length. On a fine smooth mesh no face is, and the guard costs nothing.
    ``compiled``: in :func:`_risk_kernel`, else NumPy."""
    compiled = use_kernels(compiled)  # NumPy where kernels cannot be cached
    from .targets import halfedge_slots

    topology = targets.topology
    faces = topology.faces
    if compiled:
        from .kernels import jit_kernel

        risky = np.zeros(topology.n_faces, dtype=bool)
        jit_kernel(_risk_kernel)(
            faces,
            topology.ring_offsets,
            topology.ring_halfedges,
            topology.neighbor_offsets,
            targets.positions,
            targets.tangents,
            targets.fallback,
            targets.corner_normals,
            np.cos(RISK_TURN),
            np.cos(RISK_TANGENT),
            RISK_LENGTH[0],
            RISK_LENGTH[1],
            risky,
        )
        return np.flatnonzero(risky)
    n = targets.corner_normals
    risky = np.asarray(targets.fallback[faces].any(axis=1))
    risky |= (np.einsum("fkd,fkd->fk", n, np.roll(n, -1, axis=1)) < np.cos(RISK_TURN)).any(axis=1)
    slot_out, _ = halfedge_slots(topology)
    x = targets.positions
    chord = x[topology.target(np.arange(topology.n_halfedges))] - x[faces.reshape(-1)]
    tangent = targets.tangents[slot_out]
    chord_length, tangent_length = np.linalg.norm(chord, axis=1), np.linalg.norm(tangent, axis=1)
    ratio = tangent_length / np.where(chord_length > 0, chord_length, 1.0)
    cosine = np.einsum("hd,hd->h", chord, tangent) / np.maximum(
        chord_length * tangent_length, np.finfo(float).tiny
    )
    off = (cosine < np.cos(RISK_TANGENT)) | (ratio < RISK_LENGTH[0]) | (ratio > RISK_LENGTH[1])
    risky |= off.reshape(-1, 4).any(axis=1)
    return np.flatnonzero(risky)


def _risk_kernel(
    faces: np.ndarray,
    ring_offsets: np.ndarray,
    ring_halfedges: np.ndarray,
    slot_offsets: np.ndarray,
    x: np.ndarray,
    tangents: np.ndarray,
    fallback: np.ndarray,
    corner_normals: np.ndarray,
    min_turn_cosine: float,
    min_tangent_cosine: float,
    shortest: float,
    longest: float,
    risky: np.ndarray,
) -> None:
    """:func:`_faces_at_risk` into ``risky`` (F,), all False on entry: per face the fallbacks and
    the corner normals' cosines ``n_k·n_{k+1}``; per vertex A and ring face i the tangent t of slot
    i (A → B) against the chord d = B − A, ``t·d / (|t||d|)`` and ``|t|/|d|``."""
    tiny = np.finfo(np.float64).tiny
    for f in range(faces.shape[0]):
        for k in range(4):
            n, m = corner_normals[f, k], corner_normals[f, (k + 1) & 3]
            if fallback[faces[f, k]] or n[0] * m[0] + n[1] * m[1] + n[2] * m[2] < min_turn_cosine:
                risky[f] = True
    for a in range(ring_offsets.size - 1):
        for i in range(ring_offsets[a + 1] - ring_offsets[a]):
            h = ring_halfedges[ring_offsets[a] + i]
            b = faces[h >> 2, ((h & 3) + 1) & 3]
            t = tangents[slot_offsets[a] + i]
            d0, d1, d2 = x[b, 0] - x[a, 0], x[b, 1] - x[a, 1], x[b, 2] - x[a, 2]
            chord = np.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
            length = np.sqrt(t[0] * t[0] + t[1] * t[1] + t[2] * t[2])
            ratio = length / (chord if chord > 0 else 1.0)
            size = chord * length
            cosine = (d0 * t[0] + d1 * t[1] + d2 * t[2]) / (size if size > tiny else tiny)
            if cosine < min_tangent_cosine or ratio < shortest or ratio > longest:
                risky[h >> 2] = True


class _Attempts(Generic[A]):
    """The fold guard's attempts, each measured as the check measures it
    (:func:`~g1patch.continuity.folds_and_bend`) on the faces ``scored`` (those a retreat can
    change): the best has the fewest degenerate normals, then the fewest folded faces, then the
    least 99th-percentile bend: never more of either than the rule's own."""

    def __init__(
        self,
        scored: np.ndarray,
        patches_per_face: int,
        patches_of: Callable[[A], Patches],
        diagonal: float,
    ) -> None:
        self.scored = scored
        self.diagonal = diagonal
        self.rows = (patches_per_face * scored[:, None] + np.arange(patches_per_face)).ravel()
        self.patches_per_face = patches_per_face
        self.patches_of = patches_of
        self.best: tuple[tuple[int, int], float, A, Targets, np.ndarray] | None = None
        #: the rule's own attempt (the first), and the best of the others
        self.own: tuple[tuple[int, int], float, A, Targets, np.ndarray] | None = None
        self.retreats: tuple[tuple[int, int], float, A, Targets, np.ndarray] | None = None

    def measure(self, attempt: A) -> tuple[tuple[int, int], float, np.ndarray]:
        """The defects (degenerate normals, folded faces), the bend and the folded faces of
        ``attempt`` on the scored faces."""
        folded, degenerate, bend = folds_and_bend(
            self.patches_of(attempt).take(self.rows), diagonal=self.diagonal
        )
        faces = np.unique(self.scored[np.flatnonzero(folded) // self.patches_per_face])
        return (degenerate, faces.size), bend, faces

    def add(self, attempt: A, targets: Targets) -> tuple[tuple[int, int], float, np.ndarray]:
        """Measure ``attempt`` (assembled from ``targets``) and keep it if it is the best."""
        count, bend, folded = self.measure(attempt)
        measured = (count, bend, attempt, targets, folded)
        if self.own is None:
            self.own = measured
        elif self.retreats is None or (count, bend) < self.retreats[:2]:
            self.retreats = measured
        if self.best is None or (count, bend) < self.best[:2]:
            self.best = measured
        return count, bend, folded


def _guarded(
    targets: Targets,
    mesh: QuadMesh,
    assemble: Callable[[Targets], A],
    patches_per_face: int,
    patches_of: Callable[[A], Patches] = lambda a: a,  # type: ignore[assignment,return-value]
) -> tuple[A, Targets]:
    """Assemble, and where faces fold or bend more than the faired limit-interpolating surface
    does, give their vertices its targets (module docstring). Only the faces at risk
    (:func:`_faces_at_risk`) are compared with that surface (the folded ones among them alone
    where more than :data:`GUARD_COMPARED_FACES` are). Its targets are solved on the part of the
    mesh round them (:func:`~g1patch.targets.limit_interpolate.limit_interpolate_near`); given
    to all their corners they are the first alternative, and each compared face's largest normal
    turn there (:func:`_face_turns`) is its yardstick. Where the rule's own surface folds nowhere
    and bends within :data:`BEND_RATIO` × the alternative's, it is kept. Else each step retreats
    (from the rule's own targets) the corners of the faces that fold or turn more than
    :data:`BEND_RATIO` × their yardstick, these with their 1-ring from the second step on (a
    retreated corner next to an untouched one can fold or bend the face between), until a step
    adds nothing or after :data:`GUARD_STEPS`; the faces that still fold in the best of these
    retreats then move towards regular stars (:func:`~g1patch.targets.interpolate.retreat_to_star`,
    :data:`STAR_WEIGHTS`). The best
    attempt (:class:`_Attempts`) is returned: never one that folds more than the rule's own. An
    assembly may return more than the patches (``patches_of`` finds them): the caller gets the
    chosen attempt's whole result."""
    topology = targets.topology
    assembled = assemble(targets)
    risky = _faces_at_risk(targets)
    if not risky.size:
        return assembled, targets
    compared = risky
    if risky.size > GUARD_COMPARED_FACES:  # the folded ones alone
        rows = (patches_per_face * risky[:, None] + np.arange(patches_per_face)).ravel()
        folded = folded_patches(patches_of(assembled).take(rows), FOLD_SAMPLES)
        compared = np.unique(risky[np.flatnonzero(folded) // patches_per_face])
        if not compared.size:
            return assembled, targets
    corner_points = patches_of(assembled).corners().reshape(-1, 3)
    attempts = _Attempts(
        np.flatnonzero(grow(topology, compared, GUARD_STEPS + 1)),
        patches_per_face,
        patches_of,
        float(np.linalg.norm(corner_points.max(axis=0) - corner_points.min(axis=0))) or 1.0,
    )
    count, bend, folded = attempts.add(assembled, targets)
    try:
        fair, covered = limit_interpolate_near(mesh, targets, compared, FAIR_RINGS)
    except (ConstructionError, InputError) as error:  # no faired surface (semi-sharp creases)
        logger.info("fold guard: no faired targets near the risky faces (%s)", error)
    else:
        corners = _corners(topology, compared)
        faired_targets = retreat(targets, fair, np.flatnonzero(corners & covered))
        faired = _assembled(assemble, faired_targets)
        if faired is None:  # the faired fans are not valid fans here (a ring winding twice)
            return _stars(attempts, assemble)
        yardstick = BEND_RATIO * _face_turns(patches_of(faired), compared, patches_per_face)
        if count == (0, 0) and bend <= BEND_RATIO * attempts.measure(faired)[1]:
            return assembled, targets  # the rule's own is fair enough
        del faired, faired_targets
        # the mesh's own vertices keep their places where a face only bends too far: the faired
        # surface may relax a vertex (move it off) only to mend a fold
        given = np.zeros(topology.n_vertices, dtype=bool)
        given[: len(mesh.cage.points) if mesh.cage is not None else topology.n_vertices] = True
        retreated = np.zeros(topology.n_vertices, dtype=bool)
        moving = np.zeros(topology.n_vertices, dtype=bool)
        for step in range(GUARD_STEPS):
            # the vertices the faired surface does not pass through
            relaxed = given & (
                np.linalg.norm(fair.positions - targets.positions, axis=1) > RELAXED_DISTANCE
            )
            worse = compared[
                _face_turns(patches_of(assembled), compared, patches_per_face) > yardstick
            ]
            corners = _corners(topology, worse, min(step, 1))
            at_folds = _corners(topology, folded, min(step, 1))
            if not ((corners | at_folds) & ~retreated).any() and not (at_folds & ~moving).any():
                break  # the same retreat again: the same patches
            retreated |= (corners & ~relaxed) | at_folds
            moving |= at_folds
            if not covered[retreated].all():
                around = np.flatnonzero(retreated[topology.faces].any(axis=1))
                try:
                    fair, covered = limit_interpolate_near(
                        mesh, targets, np.union1d(around, compared), FAIR_RINGS
                    )
                except (ConstructionError, InputError) as error:
                    logger.info("fold guard: no faired targets near the folds (%s)", error)
                    break
            guarded = retreat(
                targets, fair, np.flatnonzero(retreated & covered), anchored=given & ~moving
            )
            attempt = _assembled(assemble, guarded)
            if attempt is None:
                break
            assembled = attempt
            _, _, folded = attempts.add(assembled, guarded)
    return _stars(attempts, assemble)


def _corners(topology: QuadTopology, faces: np.ndarray, rings: int = 0) -> np.ndarray:
    """The corners of ``faces`` with their ``rings`` vertex rings, a (V,) mask."""
    chosen = np.zeros(topology.n_vertices, dtype=bool)
    chosen[topology.faces[faces]] = True
    slot_vertex = slot_vertices(topology)
    for _ in range(rings):
        chosen[topology.neighbors[chosen[slot_vertex]]] = True
    return chosen


def _assembled(assemble: Callable[[Targets], A], targets: Targets) -> A | None:
    """``assemble(targets)``, or None where a retreat's targets are not a valid fan."""
    try:
        return assemble(targets)
    except ConstructionError as error:
        logger.info("fold guard: an attempt is not assembled (%s)", error)
        return None


def _stars(attempts: _Attempts[A], assemble: Callable[[Targets], A]) -> tuple[A, Targets]:
    """The fold guard's last steps (:func:`_guarded`): from the rule's own attempt and from the
    best retreat, the faces that still fold (where the faired surface folds too) move towards
    regular stars, by :data:`STAR_WEIGHTS`, with their 1-ring from the second step on; the best
    attempt of all."""
    assert attempts.own is not None and attempts.best is not None
    for base, folded in {id(a): a[3:] for a in (attempts.own, attempts.retreats) if a}.values():
        topology = base.topology
        retreated = np.zeros(topology.n_vertices, dtype=bool)
        for step, weight in enumerate(STAR_WEIGHTS):
            if not folded.size:
                break
            retreated |= _corners(topology, folded, min(step, 1))
            guarded = retreat_to_star(base, np.flatnonzero(retreated), weight)
            attempt = _assembled(assemble, guarded)
            if attempt is None:
                break
            _, _, folded = attempts.add(attempt, guarded)
    return attempts.best[2], attempts.best[3]


def _face_turns(
    patches: Patches, faces: np.ndarray, patches_per_face: int, samples: int = TURN_SAMPLES
) -> np.ndarray:
    """The largest normal turn (radians) between neighbouring samples of a ``samples²`` grid on
    each of ``faces``' patches, per face: how far the surface bends within the face."""
    rows = (patches_per_face * faces[:, None] + np.arange(patches_per_face)).ravel()
    part = patches.take(rows)
    t = np.linspace(0.0, 1.0, samples)
    normals = np.cross(part.evaluate_grid(t, t, 1, 0), part.evaluate_grid(t, t, 0, 1))
    normals /= np.maximum(np.linalg.norm(normals, axis=-1, keepdims=True), np.finfo(float).tiny)

    def turn(a: np.ndarray, b: np.ndarray) -> np.ndarray:
        return np.arctan2(np.linalg.norm(np.cross(a, b), axis=-1), np.sum(a * b, axis=-1))

    along_u = turn(normals[:, 1:], normals[:, :-1]).reshape(len(rows), -1).max(axis=1)
    along_v = turn(normals[:, :, 1:], normals[:, :, :-1]).reshape(len(rows), -1).max(axis=1)
    return np.maximum(along_u, along_v).reshape(len(faces), patches_per_face).max(axis=1)


def build_network(
    mesh: QuadMesh,
    method: str = DEFAULT_METHOD,
    shape: str = "interpolate",
    *,
    tangents: TangentRule = "arc",
    twist: TwistRule = "bilinear",
    normals: NormalRule = "fan",
    refine: int = 0,
    max_memory: int | None = None,
    max_patches: int | None = None,
    tolerance: float | None = DEFAULT_TOLERANCE,
) -> PatchNetwork:
    """The patch network of ``mesh``: targets by ``shape``, assembled by ``method``.

    ``method`` (:data:`g1patch.construct.ASSEMBLIES`): ``split4`` (exact G1, 2×2 polynomial bicubics
    per quad: the default, exact in CAD), ``gregory`` (exact G1, rational interiors, the fairest),
    ``corner`` (the paper: G1 at corners only). ``shape`` (:data:`g1patch.targets.SHAPES`):
    ``interpolate`` (through the mesh vertices, with the fold guard), ``limit`` (the Catmull–Clark
    limit of the mesh as a control cage: through the limit points, without the fold guard, which
    would pull it off the limit), ``limit-interpolate`` or ``legacy`` (the previous release's, for
    comparison). ``tangents`` (``arc`` or ``chord``) applies to ``legacy`` only; ``corner`` with
    ``legacy`` is the paper's construction as the first release built it
    (:func:`build_corner_network`, world coordinates), with its ``twist`` and ``normals`` rules.
    ``refine``: Catmull–Clark steps applied to the mesh first (:func:`g1patch.subdivision.refine`);
    the limit shapes refine at least :func:`semi_sharp_levels` steps, so semi-sharp creases follow
    OpenSubdiv's limit (a Gregory ``limit`` build with a tolerance refines only where its network
    is off that limit, around semi-sharp creases too: :mod:`g1patch.adaptive`). The network's
    provenance records the choices (the steps actually taken) and how many vertices needed a
    fallback. A build whose :func:`estimate_build` is above
    ``max_memory`` bytes (default :func:`memory_budget`, half the RAM), or makes more than
    ``max_patches``, is refused before it starts (:class:`BudgetError`). ``tolerance`` (limit
    shapes; None: not measured): the largest distance from the exact Catmull–Clark limit allowed,
    relative to the bounding-box diagonal (:func:`_within_tolerance`); the provenance records the
    distance reached."""
    check_choice("method", method, METHODS)
    check_choice("shape", shape, tuple(SHAPES))
    check_choice("tangents", tangents, TANGENTS)
    check_choice("twist", twist, TWISTS)
    check_choice("normals", normals, NORMALS)
    if isinstance(refine, bool) or not isinstance(refine, (int, np.integer)) or refine < 0:
        raise InputError(f"refine: expected a number of Catmull–Clark steps ≥ 0, got {refine!r}")
    if tolerance is not None:
        check_tolerance(tolerance)
    if shape == "limit":  # the cage's limit: a polygon cage's first step by the Catmull–Clark rules
        mesh = catmull_clark_cage(mesh)
    local = _local_refinement(method, shape, tolerance)
    estimate = estimate_build(mesh, method, shape, refine, semi_sharp_first=not local)
    check_budget(estimate, method, max_memory, max_patches)
    if estimate.steps > refine:
        logger.info(
            "semi-sharp features: refining %d Catmull–Clark steps first (%s patches)",
            estimate.steps,
            f"{estimate.patches:,}",
        )
    refine = estimate.steps
    repairs = mesh.repairs
    if refine:
        mesh = subdivide(mesh, refine)
    if method == "corner" and shape == "legacy" and not refine:
        corner = build_corner_network(mesh, tangents=tangents, twist=twist, normals=normals)
        return _with_faces(corner, mesh, 1)
    network = _network(mesh, method, shape, tangents, refine, repairs)
    if tolerance is None or shape not in LIMIT_SHAPES:
        return network
    return _within_tolerance(
        network, mesh, method, shape, tolerance, refine, repairs, max_memory, max_patches
    )


def _network(
    mesh: QuadMesh,
    method: str,
    shape: str,
    tangents: TangentRule,
    refine: int,
    repairs: tuple[str, ...],
    through: tuple[np.ndarray, np.ndarray] | None = None,
) -> PatchNetwork:
    """The network of ``mesh`` (already refined ``refine`` steps): targets, the fold guard for
    ``interpolate``, assembly, the network with its UVs and groups. ``through``: (vertices, world
    points) those vertices' targets take exactly instead of the rule's (the limit of a refined
    interpolating cage passes through the original vertices, to the solve's residual: these make
    it exact)."""
    assembly = ASSEMBLIES[method]
    frame = Frame.of_points(mesh.vertices)
    local = mesh.with_vertices(frame.to_local(mesh.vertices))
    if mesh.cage is not None:  # the polygons too: limit-interpolate solves through their step
        polygons = mesh.cage._replace(points=frame.to_local(mesh.cage.points))
        local = replace(local, cage=polygons)
    targets = shape_targets(local, shape, tangents=tangents)
    if through is not None:
        positions = targets.positions.copy()
        positions[through[0]] = frame.to_local(through[1])
        targets = targets.with_changes(positions=positions)
    surface = mesh
    if shape == "limit-interpolate" and mesh.cage is not None:
        # the polygons' own vertices are passed through; the split's edge and face points are
        # not asked to be, the surface passes them at its limit points
        points = frame.to_world(targets.positions)
        points[: len(mesh.cage.points)] = mesh.cage.points
        surface = mesh.with_vertices(points)
    if shape == "limit":  # the points passed through
        points = frame.to_world(targets.positions)
        if through is not None:
            points[through[0]] = through[1]
        surface = mesh.with_vertices(points)
    provenance = _provenance(mesh, method, shape, tangents, targets, refine, repairs)
    if shape == "interpolate":  # the guard's best assembly is the network's: built once
        own = targets
        assembled, targets = _guarded(
            targets, local, assembly.assemble, assembly.patches_per_face, assembly.patches_of
        )
        provenance["fallback_vertices"] = str(targets.n_fallback)
        faired = (targets.normals != own.normals).any(axis=1) & ~targets.fallback
        if faired.any():
            provenance["faired_vertices"] = str(int(faired.sum()))
        _report_moved(own.positions, targets.positions, mesh, shape, provenance)
        del own
    else:
        if shape == "limit-interpolate":
            _report_moved(local.vertices, targets.positions, mesh, shape, provenance)
        assembled = assembly.assemble(targets)
    kept, provenance = assembly.keep(assembled, targets, provenance)
    # the network needs none of the rest: freed before its arrays are made (DESIGN §6)
    del assembled, targets, local
    network = assembly.network(kept, NetworkParts(mesh, surface, frame, provenance))
    return _with_faces(network, mesh, assembly.patches_per_face)


def _report_moved(
    own: np.ndarray, passed: np.ndarray, mesh: QuadMesh, shape: str, provenance: dict[str, str]
) -> None:
    """Where an interpolating shape gave up some of the mesh's own vertices (the faired surface
    relaxes them where passing through would fold or pinch it): their number and largest distance
    from the points passed, of the diagonal (``own`` and ``passed`` are unit-scaled positions), in
    the provenance (``relaxed_vertices``, ``relaxed_distance``) and one warning line."""
    given = len(mesh.cage.points) if mesh.cage is not None else len(own)
    moved = np.linalg.norm(passed[:given] - own[:given], axis=1)
    relaxed = np.flatnonzero(moved > RELAXED_DISTANCE)
    if not relaxed.size:
        return
    provenance["relaxed_vertices"] = str(relaxed.size)
    provenance["relaxed_distance"] = f"{moved.max():.3g}"
    logger.warning(
        "%s: passing through %d of %d vertices (first: %d) turns the surface inside out or "
        "pinches it; it passes them at up to %.3g of the diagonal, on the faired "
        "limit-interpolating surface there",
        shape,
        relaxed.size,
        given,
        relaxed[0],
        moved.max(),
    )


def _with_faces(network: PatchNetwork, mesh: QuadMesh, patches_per_face: int) -> PatchNetwork:
    """``network`` with what its patches take from their faces: the UVs
    (:func:`~g1patch.network.patch_uvs`, from the mesh's face-varying ones) and the groups (each
    of a face's patches in its group), the hole faces' left out where they have no patches; as it
    is without either."""
    if mesh.uv is None and mesh.groups is None:
        return network
    faces = np.arange(mesh.n_faces)
    if network.n_patches != mesh.n_faces * patches_per_face:  # hole faces without patches
        faces = np.flatnonzero(~mesh.features.holes)
    uv = None if mesh.uv is None else patch_uvs(mesh.uv[faces], patches_per_face)
    groups = None if mesh.groups is None else mesh.groups.take(faces).repeat(patches_per_face)
    return replace(network, uv=uv, groups=groups)


def build_gregory_network(
    mesh: QuadMesh, *, shape: str = "interpolate", tangents: TangentRule = "arc"
) -> PatchNetwork:
    """``build_network(mesh, "gregory", shape)``: exact G1, one rational Gregory patch per quad."""
    return build_network(mesh, "gregory", shape, tangents=tangents)


def build_split4_network(
    mesh: QuadMesh, *, shape: str = "interpolate", tangents: TangentRule = "arc"
) -> PatchNetwork:
    """``build_network(mesh, "split4", shape)``: exact G1, 2×2 polynomial bicubics per quad."""
    return build_network(mesh, "split4", shape, tangents=tangents)


def estimate_patches(method: str, patches: int) -> BuildEstimate:
    """The estimate of a build that makes ``patches`` one-patch faces of ``method`` out of a
    refined cage (a locally refined network, whose count is not ``faces · 4^steps``): per patch
    the refined mesh, its refinement and the assembly's peak, as :func:`estimate_build` counts
    them."""
    per_patch = MESH_BYTES_PER_FACE + REFINE_BYTES_PER_FACE + ASSEMBLIES[method].peak_bytes_per_face
    return BuildEstimate(0, patches, patches, patches * per_patch)


def _over_budget(
    estimate: BuildEstimate, method: str, max_memory: int | None, max_patches: int | None
) -> str:
    """Why the tolerance loop stops before a step of this ``estimate`` (it would exceed the
    budget, :func:`check_budget`) and what lets it through; empty when it is within."""
    try:
        check_budget(estimate, method, max_memory, max_patches)
    except BudgetError:
        return (
            f"another step would make about {estimate.patches:,} patches and need about "
            f"{size_text(estimate.bytes)}; a larger --max-memory or --tolerance lets it through"
        )
    return ""


def check_tolerance(tolerance: float) -> float:
    """``tolerance`` as a float in (0, 1), else :class:`InputError` naming it."""
    if isinstance(tolerance, bool) or not isinstance(tolerance, (int, float, np.floating)):
        raise InputError(f"tolerance: expected a number, got {tolerance!r}")
    if not 0.0 < float(tolerance) < 1.0:
        raise InputError(
            f"tolerance: expected a fraction of the bounding-box diagonal in (0, 1), got "
            f"{tolerance!r}"
        )
    return float(tolerance)


def _within_tolerance(
    network: PatchNetwork,
    mesh: QuadMesh,
    method: str,
    shape: str,
    tolerance: float,
    refine: int,
    repairs: tuple[str, ...],
    max_memory: int | None,
    max_patches: int | None,
) -> PatchNetwork:
    """``network`` (of ``mesh``, refined ``refine`` steps), or the network of a finer cage, within
    ``tolerance`` of the exact Catmull–Clark limit (:func:`~g1patch.fidelity.limit_distance`).

    The cage is ``mesh`` for ``limit``, the solved interpolating cage for ``limit-interpolate``
    (its limit passes through the vertices); while the distance is above the tolerance the cage
    takes another Catmull–Clark step (the same limit surface, faces a quarter the size) and is
    built again as its limit — Gregory networks only where they are off
    (:func:`~g1patch.adaptive.refine_adaptively`), split4 ones whole — up to
    :data:`MAX_TOLERANCE_STEPS` steps and as long as the build's estimate stays within
    ``max_memory`` and ``max_patches``. The provenance records the distance reached
    (``limit_distance``), the ``tolerance``, the steps it added (``tolerance_steps``) and, where it
    stopped short, why and what lets it through (``tolerance_stop``)."""
    assembly = ASSEMBLIES[method]
    cage, original = mesh, None
    if shape == "limit-interpolate":
        solution = interpolating_cage(mesh)
        cage, original = solution.mesh, solution.points

    def through(ids: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
        """The original vertices among a finer cage's (``ids``: their ids in ``cage``)."""
        if original is None:
            return None
        kept = np.flatnonzero(ids < len(original))
        return kept, original[ids[kept]]

    if method == "gregory":  # refined only where it is off: hanging edges between levels

        def allowed(patches: int) -> str:
            return _over_budget(estimate_patches(method, patches), method, max_memory, max_patches)

        adaptive = refine_adaptively(
            network,
            cage,
            lambda finer, ids: _network(
                finer, method, "limit", "arc", refine, repairs, through(ids)
            ),
            tolerance * network.bounding_box_diagonal(),
            max(MAX_TOLERANCE_STEPS, semi_sharp_levels(cage)),
            allowed,
        )
        network, steps, stop = adaptive.network, adaptive.steps, adaptive.stop
        relative = adaptive.distance / (network.bounding_box_diagonal() or 1.0)
    else:
        distance = limit_distance(network, cage, assembly.patches_per_face)
        steps, stop = 0, ""
        while distance.relative > tolerance:
            if steps == MAX_TOLERANCE_STEPS:
                stop = f"{MAX_TOLERANCE_STEPS} steps added; a larger --tolerance lets it through"
                break
            stop = _over_budget(
                estimate_build(cage, method, "limit", steps + 1), method, max_memory, max_patches
            )
            if stop:
                break
            steps += 1
            finer = subdivide(cage, steps)
            network = _network(
                finer,
                method,
                "limit",
                "arc",
                refine + steps,
                repairs,
                through(np.arange(finer.n_vertices)),
            )
            distance = limit_distance(network, finer, assembly.patches_per_face)
        relative = distance.relative
    logger.info(
        "distance to the Catmull–Clark limit: %.3g of the diagonal after %d added steps",
        relative,
        steps,
    )
    provenance = dict(network.provenance)
    provenance.update(
        shape=shape,
        refine=str(refine + steps),
        limit_distance=f"{relative:.6g}",
        tolerance=f"{tolerance:g}",
        tolerance_steps=str(steps),
    )
    if stop:
        provenance["tolerance_stop"] = stop
    return replace(network, provenance=provenance)
