"""G1 angles of what OpenCASCADE holds: the normals of sewn faces along every shared edge.

``n = ±(S_u × S_v)`` with the sign of the face's orientation, angle ``atan2(|n_L × n_R|,
n_L · n_R)``. Each sewn face's poles, knots and orientation are read back from OCC and its
B-spline evaluated vectorised along the edges; one point per face is evaluated by OCC itself
(``BRepAdaptor_Surface::D1``) as a check, and any face that disagrees, or is not a plain
B-spline, is evaluated by OCC at every point (:func:`_shape_normals`).
"""

from __future__ import annotations

from collections.abc import Sequence
from itertools import pairwise
from types import SimpleNamespace
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import NDArray

from ...network import PatchNetwork, edge_parameters
from .bspline import _QUARTER
from .opencascade import Progress

#: points per shared edge at which the exported surfaces' G1 angle is measured (as the check)
G1_SAMPLES = 33


def _face_normals(occ: SimpleNamespace, face: Any, uv: NDArray[np.float64]) -> NDArray[np.float64]:
    """``±(S_u × S_v)`` (not normalised) by ``BRepAdaptor_Surface::D1``, sign of the face
    orientation."""
    surface = occ.BRepAdaptor_Surface(face, False)
    point, d_u, d_v = occ.gp_Pnt(), occ.gp_Vec(), occ.gp_Vec()
    out = []
    for u, v in uv.tolist():
        surface.D1(u, v, point, d_u, d_v)
        out.append(d_u.Crossed(d_v).Coord())
    normals = np.array(out, dtype=np.float64).reshape(-1, 3)
    return -normals if face.Orientation() == occ.TopAbs_REVERSED else normals


class _OccBSpline(NamedTuple):
    """A face's surface as OCC holds it (``BRep_Tool::Surface``, location applied): a non-rational,
    non-periodic B-spline's poles (nu, nv, 3), full knot sequences and degrees; ``sign`` −1 for a
    reversed face."""

    poles: NDArray[np.float64]
    knots_u: tuple[float, ...]
    knots_v: tuple[float, ...]
    degree_u: int
    degree_v: int
    sign: float


def _occ_bspline(occ: SimpleNamespace, face: Any) -> _OccBSpline | None:
    """The B-spline data OCC holds for ``face`` (:class:`_OccBSpline`), None for any other
    surface."""
    surface = occ.BRep_Tool.Surface_s(face)
    if (
        not isinstance(surface, occ.Geom_BSplineSurface)
        or surface.IsURational()
        or surface.IsVRational()
        or surface.IsUPeriodic()
        or surface.IsVPeriodic()
    ):
        return None
    pole, count_u, count_v = surface.Pole, surface.NbUPoles(), surface.NbVPoles()
    net = np.array(
        [pole(i, j).Coord() for i in range(1, count_u + 1) for j in range(1, count_v + 1)],
        dtype=np.float64,
    ).reshape(count_u, count_v, 3)
    knots = [
        tuple(sequence.Value(i) for i in range(sequence.Lower(), sequence.Upper() + 1))
        for sequence in (surface.UKnotSequence(), surface.VKnotSequence())
    ]
    sign = -1.0 if face.Orientation() == occ.TopAbs_REVERSED else 1.0
    return _OccBSpline(net, knots[0], knots[1], surface.UDegree(), surface.VDegree(), sign)


def _basis_d1(
    knots: NDArray[np.float64], degree: int, x: NDArray[np.float64]
) -> tuple[NDArray[np.int64], NDArray[np.float64], NDArray[np.float64]]:
    """The ``degree + 1`` B-spline basis functions that are nonzero at each ``x`` and their first
    derivatives (Cox–de Boor, The NURBS Book A2.2/A2.3, over all x at once): the index of the
    first one (n,), values (n, p+1), derivatives (n, p+1). ``x`` is clamped into the knots'
    range."""
    p = degree
    x = np.clip(x, knots[p], knots[-p - 1])
    span = np.clip(np.searchsorted(knots, x, side="right") - 1, p, len(knots) - p - 2)
    steps = np.arange(1, p + 1)[:, None]
    left = x - knots[span + 1 - steps]  # left[j-1] = x − t[span + 1 − j], (p, n)
    right = knots[span + steps] - x  # right[j-1] = t[span + j] − x
    level = [np.ones_like(x)]
    for j in range(1, p + 1):
        lower, saved, level = level, np.zeros_like(x), []
        for r in range(j):
            temp = lower[r] / (right[r] + left[j - 1 - r])
            level.append(saved + right[r] * temp)
            saved = left[j - 1 - r] * temp
        level.append(saved)
    # N'_{i,p} = p N_{i,p-1} / (t[i+p] − t[i]) − p N_{i+1,p-1} / (t[i+p+1] − t[i+1]), i = span − p +
    # k
    below = np.stack(
        [np.zeros_like(x), *lower, np.zeros_like(x)], axis=1
    )  # N_{span-p+k, p-1}, k = 0 … p+1
    k = np.arange(p + 2)
    width = knots[span[:, None] + k] - knots[span[:, None] + k - p]
    scaled = np.divide(p * below, width, out=np.zeros_like(below), where=width > 0)
    return span - p, np.stack(level, axis=1), scaled[:, :-1] - scaled[:, 1:]


def _dense_basis(
    knots: tuple[float, ...], degree: int, count: int, x: NDArray[np.float64]
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """All ``count`` basis functions and their derivatives at ``x`` (any shape): (…, count) each."""
    first, values, derivatives = _basis_d1(np.asarray(knots), degree, x.reshape(-1))
    rows, columns = np.arange(x.size)[:, None], first[:, None] + np.arange(degree + 1)
    dense_values, dense_derivatives = np.zeros((x.size, count)), np.zeros((x.size, count))
    dense_values[rows, columns], dense_derivatives[rows, columns] = values, derivatives
    return dense_values.reshape(*x.shape, count), dense_derivatives.reshape(*x.shape, count)


def _distinct_rows(rows: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """The distinct rows of a 2-D array (first seen first) and each row's index among them."""
    rows = np.ascontiguousarray(rows)
    seen: dict[bytes, int] = {}
    which = np.array([seen.setdefault(row.tobytes(), len(seen)) for row in rows], dtype=np.int64)
    first = np.zeros(len(seen), dtype=np.int64)
    first[which[::-1]] = np.arange(len(rows) - 1, -1, -1)
    return rows[first], which


def _cross(a: NDArray[np.float64], b: NDArray[np.float64]) -> NDArray[np.float64]:
    """``a × b`` for coordinates on axis 1, (n, 3, …)."""
    return np.stack(
        [
            a[:, 1] * b[:, 2] - a[:, 2] * b[:, 1],
            a[:, 2] * b[:, 0] - a[:, 0] * b[:, 2],
            a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0],
        ],
        axis=1,
    )


#: a normal ``S_u × S_v`` shorter than this share of ``|S_u| |S_v|`` is rounding (its tangents are
#: parallel: a degenerate point) and counts as zero, as OCC's exact cancellation there gives
DEGENERATE_NORMAL_RTOL = 64 * float(np.finfo(np.float64).eps)
#: rows (iso-line samples) :func:`_bspline_iso_normals` evaluates at once
_ROW_CHUNK = 1 << 14


def _bspline_iso_normals(
    surfaces: Sequence[_OccBSpline],
    face_of: NDArray[np.int64],
    uv: NDArray[np.float64],
    iso_u: NDArray[np.bool_],
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """``±(S_u × S_v)`` of ``surfaces[face_of[r]]`` at ``uv[r, k]``, (R, K, 3), and ``|S_u| |S_v|``
    (the scale of its rounding), (R, K), for rows on iso-lines: u constant along row r where
    ``iso_u[r]``, else v. Vectorised over rows of faces with equal knots, degrees and pole counts:
    each row's curve ``C(s) = Σ_a N_a(s) Σ_c N_c(c) P_ac`` and cross-derivative curve (``N'_c``)
    in one product with the constant parameter's basis, then both evaluated at the row's samples."""
    normals, scale = np.empty(uv.shape[:2] + (3,)), np.empty(uv.shape[:2])
    groups: dict[tuple[Any, ...], list[int]] = {}
    for f, s in enumerate(surfaces):
        groups.setdefault((s.knots_u, s.knots_v, s.degree_u, s.degree_v, s.poles.shape), []).append(
            f
        )
    for (knots_u, knots_v, p, q, _), members in groups.items():
        nets = np.stack([surfaces[f].poles for f in members])  # (F, nu, nv, 3)
        signs = np.array([surfaces[f].sign for f in members])
        slot = np.full(len(surfaces), -1)
        slot[members] = np.arange(len(members))
        for constant_u in (True, False):
            # along the row runs v (u constant: poles transposed to (along, cross)) or u
            poles = nets.transpose(0, 2, 1, 3) if constant_u else nets
            along, cross = (1, 0) if constant_u else (0, 1)
            (knots_a, p_a), (knots_c, p_c) = (
                ((knots_v, q), (knots_u, p)) if constant_u else ((knots_u, p), (knots_v, q))
            )
            rows = np.flatnonzero((slot[face_of] >= 0) & (iso_u == constant_u))
            for chunk in np.array_split(rows, -(-len(rows) // _ROW_CHUNK)) if rows.size else ():
                member = slot[face_of[chunk]]
                n_c, d_c = _dense_basis(knots_c, p_c, poles.shape[2], uv[chunk, 0, cross])
                curve = np.einsum("rc,racd->rda", n_c, poles[member])  # (rows, 3, along poles)
                cross_curve = np.einsum("rc,racd->rda", d_c, poles[member])
                samples, which = _distinct_rows(uv[chunk, :, along])
                n_a, d_a = _dense_basis(knots_a, p_a, poles.shape[1], samples)
                # (rows, 3, K): coordinates first, so that the cross product runs on contiguous rows
                s_along = np.matmul(curve, d_a.transpose(0, 2, 1)[which])
                s_cross = np.matmul(cross_curve, n_a.transpose(0, 2, 1)[which])
                normal = _cross(s_cross, s_along) if constant_u else _cross(s_along, s_cross)
                size = np.sqrt(
                    np.einsum("rdk,rdk->rk", s_along, s_along)
                    * np.einsum("rdk,rdk->rk", s_cross, s_cross)
                )
                # a degenerate point (tangents parallel to rounding): no direction, the zero normal
                degenerate = (
                    np.sqrt(np.einsum("rdk,rdk->rk", normal, normal))
                    <= DEGENERATE_NORMAL_RTOL * size
                )
                normal = np.where(
                    degenerate[:, None], 0.0, normal * signs[member, None, None]
                )  # +0: angle 0 to any normal
                normals[chunk] = normal.transpose(0, 2, 1)
                scale[chunk] = size
    return normals, scale


#: vectorised and OCC's own normals agree to this share of ``|S_u| |S_v|`` (:func:`_shape_normals`)
NORMAL_AGREEMENT_RTOL = 1e-9


def _shape_normals(
    occ: SimpleNamespace,
    faces: Sequence[Any],
    face_of: NDArray[np.int64],
    uv: NDArray[np.float64],
    progress: Progress | None,
) -> NDArray[np.float64]:
    """``±(S_u × S_v)`` of ``faces[face_of[r]]`` at ``uv[r, k]`` (R rows of K points), (R, K, 3), on
    the surfaces OCC holds.

    Rows on iso-lines (u or v constant along the row, as every edge is) of B-spline faces: the
    faces' poles, knots and orientation are read from OCC (:func:`_occ_bspline`) and evaluated
    vectorised (:func:`_bspline_iso_normals`); on every such face one point (the middle of its first
    row) is evaluated by OCC too
    (``BRepAdaptor_Surface::D1``, :func:`_face_normals`). A face where the two disagree beyond
    :data:`NORMAL_AGREEMENT_RTOL` of ``|S_u| |S_v|``, a face on another kind of surface, and any
    other row are evaluated by OCC at every point."""
    used = np.unique(face_of)
    surfaces = [_occ_bspline(occ, faces[f]) for f in used.tolist()]
    index = np.full(len(faces), -1)
    index[used] = np.arange(len(used))
    known = np.array([s is not None for s in surfaces], dtype=bool)
    iso_u = (uv[:, :, 0] == uv[:, :1, 0]).all(axis=1)
    fast = known[index[face_of]] & (iso_u | (uv[:, :, 1] == uv[:, :1, 1]).all(axis=1))
    normals = np.empty(uv.shape[:2] + (3,))
    if fast.any():
        rows = np.flatnonzero(fast)
        kept = [s for s in surfaces if s is not None]
        local = np.cumsum(known) - 1  # index among the kept surfaces
        normals[rows], scale = _bspline_iso_normals(
            kept, local[index[face_of[rows]]], uv[rows], iso_u[rows]
        )
        checked, first = np.unique(
            face_of[rows], return_index=True
        )  # one row per face: its middle point
        middle = uv.shape[1] // 2
        by_occ = np.concatenate(
            [
                _face_normals(occ, faces[f], uv[rows[r], middle : middle + 1])
                for f, r in zip(checked.tolist(), first.tolist(), strict=True)
            ]
        )
        off = (
            np.linalg.norm(by_occ - normals[rows[first], middle], axis=-1)
            > NORMAL_AGREEMENT_RTOL * scale[first, middle]
        )
        fast &= ~np.isin(face_of, checked[off])
    slow = np.flatnonzero(~fast)
    order = slow[np.argsort(face_of[slow], kind="stable")]
    starts = np.flatnonzero(np.diff(face_of[order], prepend=-1))
    for n, (start, end) in enumerate(pairwise([*starts.tolist(), len(order)])):
        chosen = order[start:end]
        face = faces[int(face_of[chosen[0]])]
        normals[chosen] = _face_normals(occ, face, uv[chosen].reshape(-1, 2)).reshape(
            len(chosen), -1, 3
        )
        if progress is not None and n % 256 == 0:
            progress("g1", n, len(starts))
    return normals


def _occ_g1_angles(
    occ: SimpleNamespace,
    faces: Sequence[Any],
    network: PatchNetwork,
    samples: int,
    progress: Progress | None,
    quads: bool = False,
) -> NDArray[np.float64]:
    """(E, samples) angles (degrees) between the two sewn faces' OCC normals along every shared
    edge. With ``quads`` the faces are a split4 network's quads (:func:`split4_quad_faces`):
    sub-patch ``4f + k`` is evaluated on its quarter of face f, so the seams inside a quad compare
    the one surface with itself (0), and every mesh edge compares the two quads' surfaces."""
    from ...continuity import angle_between

    patch, edge = network.shared_edges()
    other, other_edge = network.neighbor[patch, edge], network.neighbor_edge[patch, edge]
    t = np.linspace(0.0, 1.0, samples)
    t_other = np.where(network.same_direction[patch, edge][:, None], t, 1.0 - t)
    uv_a = edge_parameters(edge[:, None], t)  # (E, K, 2)
    uv_b = edge_parameters(other_edge[:, None], t_other)
    face_a, face_b = patch, other
    if quads:
        uv_a, uv_b = (
            0.5 * (uv_a + _QUARTER[patch % 4, None]),
            0.5 * (uv_b + _QUARTER[other % 4, None]),
        )
        face_a, face_b = patch // 4, other // 4
    normals = _shape_normals(
        occ, faces, np.concatenate([face_a, face_b]), np.concatenate([uv_a, uv_b]), progress
    )
    return angle_between(normals[: len(patch)], normals[len(patch) :])
