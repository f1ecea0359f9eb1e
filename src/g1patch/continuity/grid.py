"""Degenerate normals, folds and fairness on a ``G × G`` grid of every patch
(:class:`_GridMeasures`, the NumPy reference and the glue of the grid kernel), and
:func:`fairness`, the fairness figures of a network alone."""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from .._grid import BLOCK_POINTS
from ..gregory import GregoryPatchSet, gregory_weights
from ..network import Patches, PatchNetwork
from .grid_kernels import _LANES, _gregory_grid_weights, _grid_kernel, _grid_tables, _turn_kernel
from .jit import _chunks, _compiled, _kernel_form
from .sampling import _blocks, _check_count, _corner_points, _diagonal, _local
from .turns import _BINS, _CODE_MIN, _EDGES, _chord_codes, _turn_deg
from .vectors import _angle3, _cross3, _dot3, _norm3, _planar

DEGENERATE_RTOL = 1e-13
"""|p_u × p_v| ≤ DEGENERATE_RTOL · diag² is a degenerate normal. At a collapsed edge the
derivative is a sum of equal points with weights summing to zero, ~1e-16 · diag, so the cross
product there is ~1e-16 · diag²; a real patch of a 1 M-quad mesh has |p_u × p_v| ~ 1e-6 · diag²."""

FOLD_SAMPLES = 17
"""Grid samples per patch side for folds, degenerate normals and fairness. Newell's teapot, the
tightest legitimate curls in the shared data, turns its normal by 115° between neighbouring
samples of a 9 × 9 grid (at the spout, patch 18), which the 90° rule would call a fold;
on the 17 × 17 grid its largest turn between neighbours is 69°."""

MAX_FOLD_LOCATIONS = 10
"""The report locates the first this many folded patches."""

_TURN_CANDIDATE_ATOL = 1e-10
"""Patches whose largest chord between neighbouring unit normals (tensor evaluation) is within
this distance of their block's largest have it recomputed as the reference computes it (see
:meth:`_GridMeasures._exact_turns`): 10⁵ times the rounding of a unit normal (~1e-15)."""

EXACT_TURN_CANDIDATES = 100_000
"""At most this many candidates per axis are recomputed as the reference computes them (~4 µs
each). Above it the patches tie within rounding by the hundred thousand, as every patch of a
large regular torus does along its tube (4 M patches: 16 s recomputing, twice the rest of the
check), and the turn maximum is the tensor evaluation's: the angle of a pair of normals that tie
with the reference's within their rounding, so within :data:`TENSOR_TURN_ATOL` of its value."""

TENSOR_TURN_ATOL = 2048 * float(np.finfo(np.float64).eps) * 180.0 / np.pi
"""Degrees: how far a turn maximum taken from the tensor evaluation may be from the reference's,
two normals each a few hundred ULP off the reference's (the tensor sums round differently:
measured ≤ 454 ε on the shared meshes' edge angles), so their angle by 2 × 1024 ε radians."""


def fairness(
    network: PatchNetwork,
    samples: int = FOLD_SAMPLES,
    degenerate_rtol: float = DEGENERATE_RTOL,
    *,
    compiled: bool | None = None,
) -> dict[str, float]:
    """The fairness figures of :func:`check` on a ``samples²`` grid per patch.

    Keys: ``turn_median_deg``, ``turn_p99_deg``, ``turn_max_deg`` (the normal turn between
    neighbouring grid samples along u and v, over all pairs of all patches) and ``thin_plate``
    (``Σ ∫∫ |p_uu|² + 2|p_uv|² + |p_vv|² du dv / diag²``).
    """
    grid, diagonal = _grid_measures(network.patches, samples, degenerate_rtol, compiled=compiled)
    return grid.fairness(diagonal)


def _grid_measures(
    patches: Patches,
    samples: int,
    degenerate_rtol: float,
    fairness: bool = True,
    *,
    compiled: bool | None = None,
    diagonal: float | None = None,
) -> tuple[_GridMeasures, float]:
    """The grid measures of every patch (``fairness`` False: folds and degenerate normals only),
    in local coordinates, and the bounding-box diagonal (``diagonal``: the one to measure by, e.g.
    the whole network's when ``patches`` are some of it)."""
    _check_count("samples", samples, 2)
    local = _local(patches)
    if diagonal is None:
        diagonal = _diagonal(_corner_points(local)) or 1.0
    grid = _GridMeasures(len(local), samples, degenerate_rtol * diagonal**2, fairness)
    form = _kernel_form(local, compiled)
    if form is not None:
        grid.add_compiled(*form, _patch_block(samples))
    else:
        for block in _blocks(len(local), _patch_block(samples)):
            grid.add(local, block)
    return grid, diagonal


def _patch_block(resolution: int) -> int:
    """Patches per block of the grid measures: about :data:`g1patch._grid.BLOCK_POINTS` grid
    samples, so the block's arrays stay in the L2 cache and its GEMMs below the size at which
    OpenBLAS splits them over threads (measured: 33 µs per patch at 17² samples in blocks of 64
    patches, 83 µs in blocks of 467)."""
    return max(1, BLOCK_POINTS // resolution**2)


class _GridMeasures:
    """Degenerate normals (and the patches with no other: ``zero_area``), folds and fairness on a
    ``resolution²`` grid per patch, accumulated block by block.

    Folds are flagged per patch, located at the first offending sample (row-major, u first). The
    turns go into a histogram (see ``_EDGES``), their maximum is exact (``atan2`` of the worst
    pair), and the thin-plate energy is summed once over per-patch energies, so the figures do not
    depend on the blocks.
    """

    def __init__(
        self, count: int, resolution: int, degenerate_level: float, fairness: bool = True
    ) -> None:
        self.grid = np.linspace(0.0, 1.0, resolution)
        self.fairness_wanted = fairness
        self.degenerate_level = degenerate_level
        self.degenerate = 0
        #: patches whose every grid sample is degenerate (no area anywhere)
        self.zero_area = np.zeros(count, dtype=bool)
        self.folded = np.zeros(count, dtype=bool)
        self.locations: list[tuple[int, float, float]] = []
        self.histogram = np.zeros(_BINS, dtype=np.int64)
        self.max_turn_deg = 0.0
        self.energy = np.zeros(count)
        # trapezoid weights across the differences: ∫∫|∂_u f|² ≈ Σ_ij w_j |f_(i+1)j − f_ij|²
        # (midpoint rule
        # along u, the h = 1/(G − 1) of the difference quotient and of both rules cancel)
        self.weights = np.ones(resolution)
        self.weights[[0, -1]] = 0.5
        self.gregory_weights: list[NDArray[np.float64]] | None = None

    def add(self, patches: Patches, block: slice) -> None:
        """Measure the patches ``block`` of ``patches``."""
        p_u, p_v = self._tangents(
            patches.take(np.arange(block.start, block.stop))
        )  # (3, B, G, G) each
        normal = _cross3(p_u, p_v)
        length = _norm3(normal)  # (B, G, G)
        usable = length > self.degenerate_level
        self.degenerate += int(usable.size - np.count_nonzero(usable))
        self.zero_area[block] = ~usable.any(axis=(1, 2))
        unit = normal * (1.0 / np.maximum(length, np.finfo(float).tiny))

        offending = np.zeros(length.shape, dtype=bool)
        last = len(self.grid) - 1
        for corner_u, corner_v in ((0, 0), (last, 0), (last, last), (0, last)):
            # the corner's grid cell: a patch turned over at its corner
            step_u, step_v = (1 if corner_u == 0 else -1), (1 if corner_v == 0 else -1)
            corner = normal[:, :, corner_u, corner_v]
            for i, j in (
                (corner_u + step_u, corner_v),
                (corner_u, corner_v + step_v),
                (corner_u + step_u, corner_v + step_v),
            ):
                against = _dot3(normal[:, :, i, j], corner) < 0
                offending[:, i, j] |= against & usable[:, i, j] & usable[:, corner_u, corner_v]
        worst_chord2, worst_pair = -1.0, None
        for axis in (1, 2):  # neighbours along u, along v
            ahead = tuple(slice(1, None) if a == axis else slice(None) for a in range(3))
            behind = tuple(slice(None, -1) if a == axis else slice(None) for a in range(3))
            chord = unit[(slice(None), *ahead)] - unit[(slice(None), *behind)]
            chord2 = _dot3(chord, chord)  # |n̂_a − n̂_b|² = 4 sin²(θ/2): > 2 where θ > 90°
            paired = usable[ahead] & usable[behind]
            offending[behind] |= (chord2 > 2.0) & paired
            if not self.fairness_wanted:
                continue
            bins = _chord_codes(chord2) - (_CODE_MIN - 1)
            np.clip(bins, 0, _BINS - 1, out=bins)
            if paired.all():
                self.histogram += np.bincount(bins.reshape(-1), minlength=_BINS)
            else:
                self.histogram += np.bincount(bins[paired], minlength=_BINS)
                chord2[~paired] = -1.0
            index = int(np.argmax(chord2))
            if chord2.reshape(-1)[index] > worst_chord2:
                worst_chord2 = float(chord2.reshape(-1)[index])
                position = np.unravel_index(index, chord2.shape)
                following = tuple(p + (a == axis) for a, p in enumerate(position))
                sample: tuple[Any, ...] = (slice(None), *position)
                neighbour: tuple[Any, ...] = (slice(None), *following)
                worst_pair = (normal[sample][:, None], normal[neighbour][:, None])
        if worst_pair is not None:
            self.max_turn_deg = max(self.max_turn_deg, float(_angle3(*worst_pair)[0]))

        folded = offending.any(axis=(1, 2))
        self.folded[block] = folded
        for patch in np.flatnonzero(folded)[: MAX_FOLD_LOCATIONS - len(self.locations)]:
            row, column = np.unravel_index(int(np.argmax(offending[patch])), offending.shape[1:])
            self.locations.append(
                (block.start + int(patch), float(self.grid[row]), float(self.grid[column]))
            )

        if not self.fairness_wanted:
            return
        energy = self.energy[block]
        for derivative in (p_u, p_v):
            along_u = derivative[:, :, 1:] - derivative[:, :, :-1]
            along_v = derivative[:, :, :, 1:] - derivative[:, :, :, :-1]
            energy += _dot3(along_u, along_u).sum(axis=1) @ self.weights
            energy += _dot3(along_v, along_v).sum(axis=2) @ self.weights

    def add_compiled(self, points: NDArray[np.float64], form: str, block: int) -> None:
        """Measure all patches ``points`` (:func:`_evaluation_form`) in :func:`_grid_kernel`.

        The kernel keeps each patch's largest squared chord along u and along v with the angle of
        its pair; the reference's maximum turn (per ``block`` of patches: the first largest chord
        along u, replaced by the first along v if larger) is picked from those, so it is the angle
        of the same pair of normals as :meth:`add` over blocks of ``block`` patches finds.
        """
        count, resolution = len(points), len(self.grid)
        if not count:
            return
        chunks = _chunks(count)
        location = np.empty(count, dtype=np.int64)
        degenerate = np.zeros(chunks, dtype=np.int64)
        zero_area = np.empty(count, dtype=bool)
        histogram = np.zeros((chunks if self.fairness_wanted else 1, _BINS), dtype=np.int64)
        best = np.empty((count if self.fairness_wanted else 0, 4))
        _compiled(_grid_kernel)(
            points,
            *_grid_tables(form, self.grid),
            self.weights,
            self.degenerate_level,
            self.fairness_wanted,
            _CODE_MIN,
            _LANES,
            chunks,
            location,
            degenerate,
            zero_area,
            histogram,
            best,
            self.energy,
        )
        self.degenerate += int(degenerate.sum())
        self.zero_area, self.folded = zero_area, location >= 0
        for patch in np.flatnonzero(self.folded)[: MAX_FOLD_LOCATIONS - len(self.locations)]:
            i, j = divmod(int(location[patch]), resolution)
            self.locations.append((int(patch), float(self.grid[i]), float(self.grid[j])))
        if not self.fairness_wanted:
            return
        self.histogram += histogram.sum(axis=0)
        if form == "gregory":
            self._exact_turns(points, best)
        blocks = -(-count // block)
        padded: NDArray[np.float64] = np.full((blocks * block, 4), -1.0)
        padded[:count] = best
        padded = padded.reshape(blocks, block, 4)
        rows = np.arange(blocks)
        along_u = padded[rows, np.argmax(padded[:, :, 0], axis=1), :2]
        along_v = padded[rows, np.argmax(padded[:, :, 2], axis=1), 2:]
        use_v = along_v[:, 0] > along_u[:, 0]
        chord2 = np.where(use_v, along_v[:, 0], along_u[:, 0])
        angle = np.where(use_v, along_v[:, 1], along_u[:, 1])[chord2 > -1.0]
        self.max_turn_deg = max(self.max_turn_deg, float(angle.max(initial=0.0)))

    def _exact_turns(self, points: NDArray[np.float64], best: NDArray[np.float64]) -> None:
        """Replace the largest chords of Gregory patches (tensor sums in the kernel) by the
        reference's (:func:`_turn_kernel`) where a patch's could decide the maximum turn: its chord
        ``√chord²`` within :data:`_TURN_CANDIDATE_ATOL` of the largest of all patches (the two
        evaluations' chords differ by rounding, ~1e-15). The other patches' are set to −1: their
        blocks' pairs turn less than the largest either way, and a patch that wins its block
        among the candidates is its block's winner whenever that block can hold the maximum. (A
        threshold per block, as before, recomputed nearly every patch of a regular mesh, whose
        patches tie within rounding: 29 s of a 1 M-patch check.) Where more than
        :data:`EXACT_TURN_CANDIDATES` patches are candidates along an axis, their tensor chords and
        angles stand for that axis."""
        largest = np.sqrt(max(float(best[:, [0, 2]].max(initial=0.0)), 0.0))
        for axis in (0, 1):
            chord = np.sqrt(np.maximum(best[:, 2 * axis], 0.0))
            candidate = (best[:, 2 * axis] > -1.0) & (chord >= largest - _TURN_CANDIDATE_ATOL)
            if np.count_nonzero(candidate) > EXACT_TURN_CANDIDATES:
                continue
            patches = np.flatnonzero(candidate)
            chord2, angle = np.empty(len(patches)), np.empty(len(patches))
            if len(patches):
                exact = np.ascontiguousarray(
                    np.swapaxes(_gregory_grid_weights(self.grid), 1, 2)
                )  # (2, 20, G²)
                _compiled(_turn_kernel)(
                    points,
                    exact,
                    self.degenerate_level,
                    patches,
                    np.full(len(patches), axis),
                    _chunks(len(patches)),
                    chord2,
                    angle,
                )
            best[:, 2 * axis] = -1.0
            best[patches, 2 * axis], best[patches, 2 * axis + 1] = chord2, angle

    def _tangents(self, group: Patches) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """``p_u`` and ``p_v`` of ``group`` on the grid, planar ``(3, B, G, G)``.

        Gregory patches without a frame: ``p[d, n] = P[d, n] @ W``, the points ``(20,)`` of every
        coordinate and patch times the weights ``W`` ``(20, G²)``, a planar result (their
        ``evaluate_grid`` multiplies interleaved values by a Kronecker factor of two thirds zeros).
        """
        if not (isinstance(group, GregoryPatchSet) and getattr(group, "frame", None) is None):
            return _planar(group.evaluate_grid(self.grid, self.grid, 1, 0)), _planar(
                group.evaluate_grid(self.grid, self.grid, 0, 1)
            )
        if self.gregory_weights is None:
            u, v = self.grid[:, None], self.grid[None, :]
            self.gregory_weights = [
                gregory_weights(u, v, du, dv).reshape(-1, 20).T.copy()
                for du, dv in ((1, 0), (0, 1))
            ]
        points = np.ascontiguousarray(np.moveaxis(group.points, -1, 0))  # (3, B, 20)
        shape = (3, len(group), len(self.grid), len(self.grid))
        p_u, p_v = (np.matmul(points, weights).reshape(shape) for weights in self.gregory_weights)
        return p_u, p_v

    def fairness(self, diagonal: float) -> dict[str, float]:
        """Median, p99 and max turn (degrees) and the thin-plate energy divided by ``diagonal²``."""
        return {
            "turn_median_deg": self._percentile(0.5),
            "turn_p99_deg": self._percentile(0.99),
            "turn_max_deg": self.max_turn_deg,
            "thin_plate": float(self.energy.sum() / diagonal**2),
        }

    def _percentile(self, q: float) -> float:
        """The turn of rank ``q (M − 1)`` of the M pairs, interpolated linearly in s inside its bin
        (capped by the exact maximum); 0 without pairs."""
        total = int(self.histogram.sum())
        if not total:
            return 0.0
        rank = q * (total - 1)
        cumulative = np.cumsum(self.histogram)
        b = int(np.searchsorted(cumulative, rank, side="right"))
        fraction = (rank - (cumulative[b] - self.histogram[b]) + 0.5) / self.histogram[b]
        chord2 = _EDGES[b] + fraction * (_EDGES[b + 1] - _EDGES[b])
        return min(_turn_deg(chord2), self.max_turn_deg)
