"""B-spline surfaces for CAD export, before anything reaches OpenCASCADE.

Knot vectors (:func:`bezier_knots`), the least-squares fit of arbitrary patches on shared dyadic
knots (:func:`fit_bspline_surfaces`, :class:`BSplineFit`), and the exact faces of a split4
network, one per quad (:func:`split4_quad_faces`, :class:`QuadFaces`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal, NamedTuple, Protocol, cast

import numpy as np
from numpy.typing import NDArray

from ...errors import ConstructionError, InputError, check_choice
from ...frame import Frame
from ...geometry import grid_row_chunks
from ...network import Patches, PatchNetwork
from ...patches import CORNER_PARAMETERS, PatchSet

#: default fit tolerance, relative to the bounding-box diagonal
FIT_RTOL = 1e-6
#: least-squares samples per knot span and direction; the deviation is measured on twice as many
SAMPLES_PER_SPAN = 4


class _FramedPatches(Patches, Protocol):
    """Patches held in the local coordinates of a frame (:mod:`g1patch.frame`)."""

    def local(self) -> Patches: ...


class BSplineFit(NamedTuple):
    """Bicubic B-spline surfaces with common knot vectors (full, end knots of multiplicity 4)."""

    control: NDArray[np.float64]  # (N, nu, nv, 3)
    knots_u: NDArray[np.float64]  # (nu + 4,)
    knots_v: NDArray[np.float64]  # (nv + 4,)
    #: max |fit − patch| over a grid twice as fine as the samples, in model units
    deviation: float


def bezier_knots(spans: int = 1) -> NDArray[np.float64]:
    """Clamped uniform cubic knot vector on [0, 1]: ``[0, 0, 0, 0, 1/s, …, 1, 1, 1, 1]``."""
    return np.concatenate([np.zeros(3), np.linspace(0.0, 1.0, spans + 1), np.ones(3)])


def _design_matrix(x: NDArray[np.float64], knots: NDArray[np.float64]) -> NDArray[np.float64]:
    from scipy.interpolate import BSpline

    return BSpline.design_matrix(x, knots, 3).toarray()


@dataclass(frozen=True)
class _Sharing:
    """Which patch corners and edges are the same: ids per ``(patch, k)`` and a representative."""

    corner_ids: NDArray[np.int64]  # (N, 4)
    edge_reversed: NDArray[np.bool_]  # (N, 4)
    edge_rep: NDArray[np.int64]  # (E,) flat index 4 p + k of the side each edge is sampled on
    edge_of: NDArray[np.int64]  # (4 N,) edge number of every patch edge


def _sharing(network: PatchNetwork | None, count: int) -> _Sharing:
    if network is None:  # every patch on its own
        ids = np.arange(4 * count, dtype=np.int64)
        return _Sharing(ids.reshape(count, 4), np.zeros((count, 4), bool), ids, ids)
    _, rep, edge_of = np.unique(
        network.edge_ids.reshape(-1), return_index=True, return_inverse=True
    )
    return _Sharing(network.corner_ids, network.edge_reversed, rep, edge_of.reshape(-1))


def _boundary_control(
    patches: Patches,
    x: NDArray[np.float64],
    basis: NDArray[np.float64],
    inner_pinv: NDArray[np.floating],
    corner_points: NDArray[np.float64],
    share: _Sharing,
) -> NDArray[np.float64]:
    """Control nets ``(N, c, c, 3)`` whose boundary rows are the fitted edge curves (interior 0).

    Each shared edge is fitted once, on its representative side, with its ends fixed to the
    shared corner points: ``inner = B_I⁺ (s − B_0 a − B_last b)``; both sides then copy the same
    numbers (reversed where they run against it), so neighbours' boundaries are identical.
    """
    count = len(patches)
    along_u = patches.evaluate_grid(x, np.array([0.0, 1.0]))  # (N, m, 2, 3)
    along_v = patches.evaluate_grid(np.array([0.0, 1.0]), x)  # (N, 2, m, 3)
    # counter-clockwise edge samples; edges 2 and 3 run backwards, at parameters 1 − x[::-1] = x
    # (the samples are symmetric), so one basis fits all four
    samples = np.stack(
        [along_u[:, :, 0], along_v[:, 1], along_u[:, ::-1, 1], along_v[:, 0, ::-1]], axis=1
    )
    rep = share.edge_rep
    start = corner_points[share.corner_ids.reshape(-1)[rep]]
    end = corner_points[np.roll(share.corner_ids, -1, axis=1).reshape(-1)[rep]]
    residual = (
        samples.reshape(4 * count, -1, 3)[rep]
        - basis[:, 0, None] * start[:, None]
        - basis[:, -1, None] * end[:, None]
    )
    curves = np.concatenate(
        [start[:, None], np.einsum("im,emd->eid", inner_pinv, residual), end[:, None]], axis=1
    )
    flip = share.edge_reversed.reshape(-1)
    canonical = np.where(flip[rep, None, None], curves[:, ::-1], curves)
    ccw = canonical[share.edge_of]
    ccw = np.where(flip[:, None, None], ccw[:, ::-1], ccw).reshape(count, 4, -1, 3)
    size = basis.shape[1]
    control = np.zeros((count, size, size, 3))
    control[:, :, 0], control[:, -1, :] = ccw[:, 0], ccw[:, 1]
    control[:, :, -1], control[:, 0, :] = ccw[:, 2, ::-1], ccw[:, 3, ::-1]
    return control


def _span_samples(breaks: NDArray[np.float64], per_span: int) -> NDArray[np.float64]:
    """``per_span`` equal steps in every span between consecutive ``breaks``, ends included once."""
    steps = np.linspace(0.0, 1.0, per_span + 1)[:-1]
    inner = (breaks[:-1, None] + np.diff(breaks)[:, None] * steps).reshape(-1)
    return np.append(inner, breaks[-1])


def _fit_level(
    patches: Patches,
    breaks: NDArray[np.float64],
    corner_points: NDArray[np.float64],
    share: _Sharing,
) -> tuple[NDArray[np.float64], NDArray[np.float64], float, NDArray[np.float64]]:
    """Fit with the given knot ``breaks``: control ``(N, s+3, s+3, 3)``, knots, deviation, per-span
    deviation.

    Interior points by separable least squares with the boundary fixed, ``X = B_I⁺ R B_I⁺ᵀ`` with
    ``R = S − B C_boundary Bᵀ``, accumulated over row blocks of the sample grid. The deviation is
    measured on a grid with twice as many points per span; a span's deviation is the largest on
    the strips ``u ∈ span`` and ``v ∈ span`` (u and v share the knots).
    """
    spans = len(breaks) - 1
    knots = np.concatenate([np.zeros(3), breaks, np.ones(3)])
    x = _span_samples(breaks, SAMPLES_PER_SPAN)
    basis = _design_matrix(x, knots)
    inner_pinv = np.linalg.pinv(basis[:, 1:-1])
    control = _boundary_control(patches, x, basis, inner_pinv, corner_points, share)
    interior = np.zeros((len(patches), spans + 1, spans + 1, 3))
    for rows in grid_row_chunks(len(patches), len(x), len(x)):
        residual = patches.evaluate_grid(x[rows], x) - np.einsum(
            "ai,nijd,bj->nabd", basis[rows], control, basis, optimize=True
        )
        interior += np.einsum(
            "ia,nabd,jb->nijd", inner_pinv[:, rows], residual, inner_pinv, optimize=True
        )
    control[:, 1:-1, 1:-1] = interior

    check = _span_samples(breaks, 2 * SAMPLES_PER_SPAN)
    check_basis = _design_matrix(check, knots)
    error = np.zeros((len(check), len(check)))  # max over patches
    for rows in grid_row_chunks(len(patches), len(check), len(check)):
        difference = patches.evaluate_grid(check[rows], check) - np.einsum(
            "ai,nijd,bj->nabd", check_basis[rows], control, check_basis, optimize=True
        )
        error[rows] = np.sqrt(np.einsum("...d,...d->...", difference, difference).max(axis=0))
    # point k of the check grid lies in span k // (2 S) (the last point in the last span)
    span_of = np.minimum(np.arange(len(check)) // (2 * SAMPLES_PER_SPAN), spans - 1)
    strip = np.maximum(error.max(axis=1), error.max(axis=0))
    per_span = np.zeros(spans)
    np.maximum.at(per_span, span_of, strip)
    return control, knots, float(error.max()), per_span


def _corner_points(patches: Patches, corner_ids: NDArray[np.int64]) -> NDArray[np.float64]:
    """One position per corner id (the last patch listing it wins: all patches then share it)."""
    corners = patches.evaluate(CORNER_PARAMETERS)  # (N, 4, 3)
    points = np.zeros((int(corner_ids.max()) + 1 if corner_ids.size else 0, 3))
    points[corner_ids.reshape(-1)] = corners.reshape(-1, 3)
    return points


def _diagonal(points: NDArray[np.float64]) -> float:
    flat = points.reshape(-1, 3)
    return float(np.linalg.norm(flat.max(axis=0) - flat.min(axis=0))) if flat.size else 0.0


def fit_bspline_surfaces(
    patches: PatchNetwork | Patches,
    fit_tolerance: float | None = None,
    *,
    refine: Literal["adaptive", "uniform"] = "adaptive",
    max_spans: int = 64,
) -> BSplineFit:
    """Bicubic B-splines within ``fit_tolerance`` of arbitrary patches (``evaluate``,
    ``evaluate_grid``).

    All patches share one knot vector, the same in u and v, symmetric under t → 1 − t. Each span
    is sampled at 4 equal steps per direction. First the boundary: corners are interpolated, each
    edge curve is the least-squares fit of its samples with its ends fixed; then the interior
    control points, by least squares with the boundary fixed. The deviation ``max |fit − patch|`` is
    measured on a grid with twice the samples. While it exceeds ``fit_tolerance`` (default
    ``1e-6`` × the bounding-box diagonal) knots are inserted at span midpoints: with
    ``refine="uniform"`` in every span (s = 1, 2, 4, …), with ``"adaptive"`` only in spans whose
    strip ``u ∈ span`` or ``v ∈ span`` (or its mirror image) exceeds the tolerance. Gregory
    patches are C¹ but not C² at their corners, so the fit converges there as O(h²) only: adaptive
    refinement grades the knots towards the patch ends and needs 46 spans where uniform needs 128
    (cube, 1e-6). The first step, s = 1, is the Bézier knot vector, so bicubic patches are
    reproduced at once, up to rounding.

    Pass a :class:`PatchNetwork` to share boundaries: every shared edge is fitted once and copied to
    both sides (reversed where they run against each other: exact on symmetric dyadic knots), so
    neighbouring faces get bit-identical boundary control points. Bare patches are fitted each on
    its own (neighbours then agree to rounding). The arithmetic is batched over patches and chunked
    over grid rows. Raises :class:`ConstructionError` when ``max_spans`` spans do not reach the
    tolerance.

    Patches with a frame (:mod:`g1patch.frame`) are fitted in their local coordinates, with the
    tolerance ``fit_tolerance / s``; the poles are then mapped to world, ``c + s X`` (identical
    local numbers stay identical), and the deviation reported in world units.
    """
    network = patches if isinstance(patches, PatchNetwork) else None
    surfaces = patches.patches if isinstance(patches, PatchNetwork) else patches
    if not all(hasattr(surfaces, name) for name in ("evaluate", "evaluate_grid", "__len__")):
        raise InputError(
            "patches: expected patches with evaluate, evaluate_grid and len, got "
            f"{type(surfaces).__name__}"
        )
    check_choice("refine", refine, ("adaptive", "uniform"))
    if not (isinstance(max_spans, (int, np.integer)) and max_spans >= 1):
        raise InputError(f"max_spans: expected a positive integer, got {max_spans!r}")
    frame: Frame | None = getattr(surfaces, "frame", None)
    unit = 1.0
    if frame is not None:
        surfaces, unit = cast(_FramedPatches, surfaces).local(), frame.scale
    share = _sharing(network, len(surfaces))
    corner_points = _corner_points(surfaces, share.corner_ids)
    local_tolerance = _fit_tolerance(fit_tolerance, _diagonal(corner_points) * unit) / unit
    breaks = np.array([0.0, 1.0])
    while True:
        control, knots, deviation, per_span = _fit_level(surfaces, breaks, corner_points, share)
        if deviation <= local_tolerance:
            poles = control if frame is None else frame.to_world(control, out=control)
            return BSplineFit(poles, knots, knots.copy(), deviation * unit)
        # split symmetrically: a reversed edge curve is its reversed control points only on knots
        # symmetric under t → 1 − t (dyadic breaks keep that exact)
        split = (
            np.maximum(per_span, per_span[::-1]) > local_tolerance
            if refine == "adaptive"
            else np.ones(len(per_span), bool)
        )
        split |= not split.any()  # the deviation may sit only on span ends: split all
        if len(breaks) - 1 + int(split.sum()) > max_spans:
            raise ConstructionError(
                f"fit_bspline_surfaces: {len(breaks) - 1} knot spans per direction leave a "
                "deviation of "
                f"{deviation * unit:.3e}, above the tolerance {local_tolerance * unit:.3e}; raise "
                f"max_spans (now {max_spans}) or the tolerance"
            )
        breaks = np.sort(np.concatenate([breaks, 0.5 * (breaks[:-1] + breaks[1:])[split]]))


def _fit_tolerance(fit_tolerance: float | None, diagonal: float) -> float:
    """The fit tolerance in model units: ``fit_tolerance``, checked, or by default
    :data:`FIT_RTOL` × the bounding-box ``diagonal``."""
    if fit_tolerance is None:
        return FIT_RTOL * diagonal if diagonal > 0 else FIT_RTOL
    if not (
        isinstance(fit_tolerance, (int, float, np.floating))
        and fit_tolerance > 0
        and np.isfinite(fit_tolerance)
    ):
        raise InputError(f"fit_tolerance: expected a positive distance, got {fit_tolerance!r}")
    return float(fit_tolerance)


#: a split4 quad whose four sub-patches are one bicubic subdivided at ½, to within this share of
#: the control nets' bounding-box diagonal, is written as that bicubic: a single-span face
SINGLE_SPAN_RTOL = 1e-12
#: split4's sub-patches join C1 inside each quad (row and column 3 of its 7×7 net are the
#: midpoints of their neighbours) to within this share of the diagonal, or the network is written
#: one face per patch
_C1_RTOL = 1e-10
# a cubic's Bézier points from its two halves' seven: b0, 2 h1 − b0, 2 h5 − b3, b3
_EXTRACT = np.array(
    [[1.0, 0, 0, 0, 0, 0, 0], [-1, 2, 0, 0, 0, 0, 0], [0, 0, 0, 0, 0, 2, -1], [0, 0, 0, 0, 0, 0, 1]]
)
# sub-patch 4f + k covers (uv + _QUARTER[k]) / 2 of quad f
_QUARTER = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])


class QuadFaces(NamedTuple):
    """A split4 network written one face per quad, in quad order: ``single`` (F,) marks the quads
    that are one bicubic, written as it (``bezier``: 4×4 nets, knots :func:`bezier_knots`); the
    others are their two-span B-spline (``two_span``: 6×6 nets, knots ``[0,0,0,0,½,½,1,1,1,1]``).
    Poles in world coordinates."""

    single: NDArray[np.bool_]
    bezier: BSplineFit
    two_span: BSplineFit


#: quads whose macro nets :func:`split4_quad_faces` tests at once (~0.6 GB of temporaries)
_QUAD_CHUNK = 1 << 17


def _sandwich(m: NDArray[np.float64], nets: NDArray[np.float64]) -> NDArray[np.float64]:
    """``M N_f Mᵀ`` for every net ``N_f`` of ``nets`` (F, n, n, 3): two matrix products over all
    faces at once (einsum's four-operand loop took 3× as long on 32 k quads)."""
    faces, n, _, dims = nets.shape
    k = m.shape[0]
    rows = m @ nets.transpose(1, 2, 0, 3).reshape(n, -1)  # (k, n·F·3): a, then (j, f, d)
    both = m @ rows.reshape(k, n, -1).transpose(1, 0, 2).reshape(n, -1)  # b, then (a, f, d)
    return np.ascontiguousarray(both.reshape(k, k, faces, dims).transpose(2, 1, 0, 3))


def split4_quad_faces(network: PatchNetwork) -> QuadFaces | None:
    """The quads of a split4 network (sub-patch ``4f + k`` at corner k of quad f, its seams to
    ``4f + k ± 1`` joined C1: :mod:`g1patch.construct.split4`), or None for any other network.

    A quad is single-span when its 7×7 macro net is, to :data:`SINGLE_SPAN_RTOL` of the diagonal,
    the de Casteljau subdivision at ½ of the bicubic read off its corners (the Bézier points of each
    corner's 2×2 block, ``b1 = 2 h1 − b0``): then the four pieces are that bicubic and nothing is
    lost. The tests run in the patches' working coordinates (their frame), the poles are mapped to
    world.
    """
    from ...construct.split4 import _HALVE, BSPLINE_KNOTS, macro_nets

    patches = network.patches
    if not isinstance(patches, PatchSet) or not len(patches) or len(patches) % 4:
        return None
    p = np.arange(len(patches))
    k = p % 4
    seams = (network.neighbor[p, (k + 1) % 4] == p - k + (k + 1) % 4) & (
        network.neighbor[p, (k + 2) % 4] == p - k + (k + 3) % 4
    )
    if not seams.all():
        return None
    bezier = patches.convert("bezier")
    control = bezier.control
    flat = control.reshape(-1, 3)
    diagonal = float(np.linalg.norm(flat.max(axis=0) - flat.min(axis=0)))
    if not (np.isfinite(diagonal) and diagonal > 0):
        return None
    keep = np.array([0, 1, 2, 4, 5, 6])  # row and column 3 are midpoints: the double knot at ½
    singles, ones, twos = [], [], []
    for start in range(0, len(control) // 4, _QUAD_CHUNK):  # bounded temporaries
        nets = macro_nets(control[4 * start : 4 * (start + _QUAD_CHUNK)])
        c1_gap = max(
            float(np.abs(nets[:, 3] - 0.5 * (nets[:, 2] + nets[:, 4])).max()),
            float(np.abs(nets[:, :, 3] - 0.5 * (nets[:, :, 2] + nets[:, :, 4])).max()),
        )
        if not c1_gap <= _C1_RTOL * diagonal:
            return None
        cubic = _sandwich(_EXTRACT, nets)
        again = _sandwich(_HALVE, cubic)
        single = np.abs(again - nets).max(axis=(1, 2, 3)) <= SINGLE_SPAN_RTOL * diagonal
        singles.append(single)
        ones.append(cubic[single])
        twos.append(nets[~single][:, keep][:, :, keep])
    single = np.concatenate(singles)
    one, two_span = np.concatenate(ones), np.concatenate(twos)
    if bezier.frame is not None:
        one, two_span = (
            bezier.frame.to_world(one, out=one),
            bezier.frame.to_world(two_span, out=two_span),
        )
    knots = bezier_knots(1)
    return QuadFaces(
        single,
        BSplineFit(one, knots, knots.copy(), 0.0),
        BSplineFit(two_span, BSPLINE_KNOTS.copy(), BSPLINE_KNOTS.copy(), 0.0),
    )


def _quad_groups(quads: QuadFaces) -> list[BSplineFit]:
    """The non-empty groups of faces with one knot vector each, single-span first."""
    return [group for group in (quads.bezier, quads.two_span) if len(group.control)]
