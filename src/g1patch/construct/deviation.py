"""How far a split4 re-assembly lies from the Gregory surface it re-assembles
(:func:`surface_deviation`, :func:`~g1patch.construct.polynomial.split4_of_gregory`): the
parametric distance, and the geometric one by foot points on the Gregory patches.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from ..errors import InputError
from ..frame import Frame
from ..gregory import GregoryPatchSet, gregory_weights
from ..network import PatchNetwork

if TYPE_CHECKING:
    from scipy.spatial import cKDTree

__all__ = ["FOOT_STARTS", "FOOT_STEPS", "SEARCH_SAMPLES", "surface_deviation"]

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

#: Gauss–Newton steps of :func:`surface_deviation`'s foot points
FOOT_STEPS = 3
#: foot-point searches per sample, from its nearest grid samples (:func:`surface_deviation`): a
#: search clamped to the edge of its patch overestimates where the foot point lies in the next
#: patch (catmark_xord_boundary: 1.8e-3 of the diagonal from one start, 1.0e-3 from four)
FOOT_STARTS = 4
#: samples per direction and Gregory patch from which the foot-point search starts
SEARCH_SAMPLES = 17


def _grid_starts(
    points: FloatArray, tree: cKDTree, t: FloatArray, count: int
) -> tuple[IntArray, FloatArray]:
    """Each point's ``count`` nearest samples of the :data:`SEARCH_SAMPLES`² grid ``t`` × ``t`` of
    every patch (``tree`` over them): their patches (P, count) and parameters (P, count, 2)."""
    nearest = tree.query(points, k=count)[1].reshape(len(points), count)
    patch, rest = np.divmod(nearest, len(t) ** 2)
    return patch, np.stack([t[rest // len(t)], t[rest % len(t)]], axis=-1)


def _foot_distances(
    points: FloatArray, local: FloatArray, patch: IntArray, at: FloatArray
) -> FloatArray:
    """Per point an upper bound of its distance to the Gregory surface of nets ``local`` (F, 20, 3):
    from each of its starts (patches ``patch`` (P, S), parameters ``at`` (P, S, 2))
    :data:`FOOT_STEPS` Gauss–Newton steps ``(JᵀJ) δ = Jᵀ (p − g)``, ``J = [g_u g_v]``, clamped to
    that patch; the nearest point seen."""
    starts = patch.shape[1]
    patch, at = patch.reshape(-1), at.reshape(-1, 2)
    points = np.repeat(points, starts, axis=0)
    nets = local[patch]

    def value(du: int = 0, dv: int = 0) -> FloatArray:
        return np.einsum(
            "nm,nmd->nd", gregory_weights(at[:, 0], at[:, 1], du, dv), nets, optimize=True
        )

    residual = points - value()  # at the current foot points, kept from step to step
    best = np.linalg.norm(residual, axis=-1)
    for _ in range(FOOT_STEPS):
        g_u, g_v = value(1, 0), value(0, 1)
        a, b, c = (np.einsum("nd,nd->n", x, y) for x, y in ((g_u, g_u), (g_u, g_v), (g_v, g_v)))
        r_u, r_v = np.einsum("nd,nd->n", g_u, residual), np.einsum("nd,nd->n", g_v, residual)
        det = a * c - b * b
        regular = det > 1e-300
        step = (
            np.stack([c * r_u - b * r_v, a * r_v - b * r_u], axis=-1)
            / np.where(regular, det, 1.0)[:, None]
        )
        at = np.clip(at + np.where(regular[:, None], step, 0.0), 0.0, 1.0)
        residual = points - value()
        best = np.minimum(best, np.linalg.norm(residual, axis=-1))  # a clamped step may lead away
    return best.reshape(-1, starts).min(axis=1)


def surface_deviation(
    network: PatchNetwork, split4: PatchNetwork, samples: int = 5
) -> tuple[float, float]:
    """How far the split4 surface ``s`` lies from the Gregory surface ``g``, model units:
    ``(parametric, geometric)``, maxima over a ``samples``² grid per quad (``samples`` odd;
    sub-patch ``4r + k`` covers ``((a, b) + (uv + corner_k) / 2) / n`` of patch f, for quad
    ``r = f n² + a n + b`` of a split4 network refined n × n, :func:`split4_of_gregory`).

    ``parametric = max |g(u, v) − s(u, v)|``. ``geometric`` = max distance of the samples of ``s``
    to their foot points on ``g`` (:func:`_foot_distances`): from the sample's own parameter (it
    may drift along the surface by more than a grid step); then, while a sample is at least half
    the largest distance, also from its :data:`FOOT_STARTS` nearest of :data:`SEARCH_SAMPLES`²
    samples per Gregory patch (any patch). Each distance is an upper bound, so is their maximum,
    and none is above its sample's parametric distance (the first start)."""
    from scipy.spatial import cKDTree

    if samples < 3 or samples % 2 == 0:
        raise InputError(f"samples: expected an odd number ≥ 3, got {samples!r}")
    gregory: GregoryPatchSet = network.patches  # type: ignore[assignment]
    frame = gregory.frame or Frame(np.zeros(3), 1.0)
    local = gregory.local().points  # (F, 20, 3)
    half = np.linspace(0.0, 1.0, (samples + 1) // 2)
    uv = np.stack(np.meshgrid(half, half, indexing="ij"), axis=-1).reshape(-1, 2)  # (K, 2)
    corner = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    points = frame.to_local(
        split4.patches.evaluate(uv).reshape(-1, 3)
    )  # sub-patch by sub-patch: (4R K, 3)
    n = math.isqrt(len(split4.patches) // (4 * len(local)))
    cell = np.stack(np.meshgrid(np.arange(n), np.arange(n), indexing="ij"), axis=-1).reshape(
        -1, 1, 1, 2
    )
    at = np.tile(
        (cell + 0.5 * (uv[None, None] + corner[None, :, None])) / n, (len(local), 1, 1, 1)
    ).reshape(-1, 2)
    patch = np.repeat(np.arange(len(local)), 4 * n * n * len(uv))

    def value(du: int = 0, dv: int = 0) -> FloatArray:
        return np.einsum(
            "nm,nmd->nd", gregory_weights(at[:, 0], at[:, 1], du, dv), nets, optimize=True
        )

    nets = local[patch]  # each sample's patch points, gathered once per patch assignment
    parametric = float(np.linalg.norm(points - value(), axis=-1).max())
    t = np.linspace(0.0, 1.0, SEARCH_SAMPLES)
    tree = cKDTree(gregory.local().evaluate_grid(t, t).reshape(-1, 3))
    best = _foot_distances(points, local, patch[:, None], at[:, None])
    refined = np.zeros(len(points), dtype=bool)
    while (chosen := ~refined & (best >= 0.5 * best.max())).any():  # the largest, from more starts
        starts = _grid_starts(points[chosen], tree, t, FOOT_STARTS)
        best[chosen] = np.minimum(best[chosen], _foot_distances(points[chosen], local, *starts))
        refined |= chosen
    return parametric * frame.scale, float(best.max()) * frame.scale
