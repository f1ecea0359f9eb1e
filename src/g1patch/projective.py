"""Homogeneous coordinates: the generalized cross product, and linear systems solved with it.

Conventions
-----------
A point is ``[x : w]`` with ``w`` last; ``w = 0`` is the point at infinity in direction ``x``.
A hyperplane is ``[a : d]``, the set ``a·x + d w = 0``: a line ``[a, b, c]`` of P², a plane
``[a, b, c, d]`` of P³. Every function takes and returns homogeneous vectors, batched over the
leading axes; only :func:`to_euclidean` divides. Use :func:`homogeneous` to append ``w = 1``.

The generalized cross product (paper, eqs. 7–9)
-----------------------------------------------
For ``n − 1`` vectors ``α_i ∈ R^n``, the rows of ``D`` ((n−1) × n),

    ξ = α_1 × … × α_{n−1} = det [[e_1 … e_n]; α_1; …; α_{n−1}]
    ξ_k = (−1)^(k+1) det(D with column k deleted)                      (k = 1..n)

``ξ`` is orthogonal to every ``α_i``, linear in each, changes sign when two rows swap, and is
zero iff the rows are linearly dependent: it is the null vector of ``D`` with no division and
no "set x_k = 1". Line through two points ``p = x1 × x2`` (eqs. 6–7), meet of two lines
``x = p1 × p2`` (eq. 8), plane through three points ``ρ = x1 × x2 × x3`` and meet of three planes
``x = ρ1 × ρ2 × ρ3`` (eq. 9, in E³).

``Ax = b`` is the same thing: with rows ``α_i = [a_i | −b_i]`` the unknown ``[x : w]`` satisfies
``α_i · [x : w] = 0``, so ``[x : w] ∝ α_1 × … × α_n``. Expanding the minors gives
``ξ_i = (−1)^n det A_i`` and ``ξ_w = (−1)^n det A`` (``A_i``: column i replaced by b) — Cramer's
rule without the division. :func:`solve` returns ``(−1)^n ξ``, so ``w = det A`` exactly.

Singular systems (``../shared/research/skala-patches.md`` B.2), told apart by :func:`classify`:

    ========================  ===============  ==========================================
    det A ≠ 0                 w ≠ 0            FINITE: x = ξ[:n] / w
    rank A = n−1, b ∉ ran A   w = 0, ξ ≠ 0     AT_INFINITY: direction ξ[:n] (null vector of A)
    rank [A | −b] < n         ξ = 0            DEGENERATE: ξ carries no information
    ========================  ===============  ==========================================

Nothing here raises or returns NaN on a singular system; a finite input gives a finite output
unless the determinants themselves overflow (rescale the rows first with :func:`rescale`).

Accuracy, honestly
------------------
``method="cofactor"`` (the default) evaluates the minors by closed forms (``np.cross`` for
n = 3, three cross products and a dot for n = 4) or by a division-free Laplace expansion
(``O(n 2^n)`` per vector, meant for small n). It is exact whenever every product and partial
sum is representable — integer data with ``Π ‖α_i‖₁ < 2^53`` — and otherwise obeys
``|ξ̂_k − ξ_k| ≤ N·eps·Π_i ‖α_i‖₁`` with ``N = m(m+1)/2``, ``m = n − 1``. That is an absolute
bound: cofactor expansion is not backward stable, and for ill-conditioned ``A`` it is much
less accurate than pivoted LU. Median relative error of x against exact rationals (note B.4,
reproduced with this module to within the sampling spread):

    ========  =========  ===============  ============
    n, cond   cofactor   LU determinants  LAPACK solve
    3, 1e2    6e-16      6e-16            5e-16
    3, 1e8    2.5e-7     3.7e-10          3.7e-10
    3, 1e12   2.3e-1     4.5e-6           4.5e-6
    4, 1e8    5.8e-6     4.2e-10          4.3e-10
    ========  =========  ===============  ============

``method="lu"`` computes each minor by partially pivoted LU (``scipy.linalg.det``): the same
homogeneous vector, about as accurate as ``np.linalg.solve``, for n LU factorisations of size
n − 1. The projective form's gains are a clean ``w = 0``, no branches, easy batching and
homogeneous output — not accuracy.
"""

from __future__ import annotations

import itertools
import math
from enum import IntEnum
from functools import cache
from typing import Literal

import numpy as np
import scipy.linalg
from numpy.typing import ArrayLike, NDArray

from .errors import InputError, as_float_array, check_choice

__all__ = [
    "Method",
    "METHODS",
    "Kind",
    "generalized_cross",
    "cross",
    "augmented",
    "solve",
    "null_vector",
    "default_rtol",
    "classify",
    "homogeneous",
    "to_euclidean",
    "rescale",
    "join_points_2d",
    "meet_lines_2d",
    "plane_through_points",
    "meet_planes",
]

Method = Literal["cofactor", "lu"]
METHODS: tuple[Method, ...] = ("cofactor", "lu")

_EPS = float(np.finfo(np.float64).eps)


class Kind(IntEnum):
    """What a homogeneous point ``[x : w]`` is (see :func:`classify`)."""

    FINITE = 0
    AT_INFINITY = 1
    DEGENERATE = 2


# --------------------------------------------------------------------------- checks
def _as_rows(name: str, value: ArrayLike) -> NDArray[np.float64]:
    """``(..., n−1, n)`` float64 rows with n ≥ 2."""
    rows = as_float_array(name, value, (None, None))
    if rows.shape[-1] != rows.shape[-2] + 1 or rows.shape[-1] < 2:
        raise InputError(
            f"{name}: expected shape (..., n-1, n) with n >= 2 (n-1 vectors of length n), got "
            f"{rows.shape}"
        )
    return rows


def _as_vectors(
    names: tuple[str, ...], values: tuple[ArrayLike, ...], length: int
) -> NDArray[np.float64]:
    """Check ``len(values)`` vectors of shape ``(..., length)``; broadcast and stack them as
    rows."""
    arrays = []
    for name, value in zip(names, values, strict=True):
        array = as_float_array(name, value, (None,))
        if array.shape[-1] != length:
            hint = " (append w with homogeneous())" if array.shape[-1] == length - 1 else ""
            raise InputError(f"{name}: expected shape (..., {length}), got {array.shape}{hint}")
        arrays.append(array)
    try:
        batch = np.broadcast_shapes(*(a.shape[:-1] for a in arrays))
    except ValueError:
        shapes = ", ".join(f"{n} {a.shape}" for n, a in zip(names, arrays, strict=True))
        raise InputError(f"batch shapes do not broadcast: {shapes}") from None
    return np.stack([np.broadcast_to(a, batch + (length,)) for a in arrays], axis=-2)


def _check_rtol(rtol: float | None, n: int) -> float:
    if rtol is None:
        return default_rtol(n)
    if isinstance(rtol, bool) or not isinstance(rtol, (int, float, np.floating, np.integer)):
        raise InputError(f"rtol: expected a non-negative number, got {rtol!r}")
    if not (math.isfinite(rtol) and rtol >= 0):
        raise InputError(f"rtol: expected a finite non-negative number, got {rtol!r}")
    return float(rtol)


def _norm(v: NDArray[np.float64]) -> NDArray[np.float64]:
    """Euclidean norm over the last axis, scaled so that squaring cannot overflow."""
    big = np.max(np.abs(v), axis=-1, initial=0.0)
    safe = np.where(big > 0, big, 1.0)
    return big * np.sqrt(np.sum((v / safe[..., None]) ** 2, axis=-1))


def _log2_product_of_norms(rows: NDArray[np.float64]) -> NDArray[np.float64]:
    """``log2 Π_i ‖rows_i‖`` (−inf if a row is zero): the Hadamard bound, free of overflow."""
    with np.errstate(divide="ignore"):
        return np.sum(np.log2(_norm(rows)), axis=-1)


# --------------------------------------------------------------------------- kernels
@cache
def _laplace_plan(
    n: int,
) -> tuple[tuple[NDArray[np.intp], NDArray[np.intp], NDArray[np.float64]], ...]:
    """Index tables of the row-by-row Laplace expansion of the minors of an (n−1)×n matrix.

    Level k holds, for every k-subset S of the columns (in ``itertools.combinations`` order),
    the minor of rows 0..k−1 and columns S, expanded along row k−1:
    ``M_k[S] = Σ_t (−1)^(k−1+t) D[k−1, S_t] M_{k−1}[S \\ S_t]``.
    Each level is ``(columns, sub-minor indices, signs)``, arrays of shape ``(C(n, k), k)``.
    """
    plan = []
    previous: dict[tuple[int, ...], int] = {(): 0}
    for k in range(1, n):
        subsets = list(itertools.combinations(range(n), k))
        columns = np.array(subsets, dtype=np.intp)
        sub = np.array(
            [[previous[s[:t] + s[t + 1 :]] for t in range(k)] for s in subsets], dtype=np.intp
        )
        signs = np.array([[(-1.0) ** (k - 1 + t) for t in range(k)] for _ in subsets])
        plan.append((columns, sub, signs))
        previous = {s: i for i, s in enumerate(subsets)}
    return tuple(plan)


def _cross_laplace(rows: NDArray[np.float64]) -> NDArray[np.float64]:
    """Division-free minors by :func:`_laplace_plan`; exact on small integers."""
    n = rows.shape[-1]
    minors = np.ones(rows.shape[:-2] + (1,))
    for k, (columns, sub, signs) in enumerate(_laplace_plan(n), start=1):
        minors = np.sum(signs * rows[..., k - 1, columns] * minors[..., sub], axis=-1)
    # combinations(range(n), n−1) lists the subsets missing column n−1, n−2, …, 0.
    return _alternating(n) * minors[..., ::-1]


@cache
def _alternating(n: int) -> NDArray[np.float64]:
    """``(−1)^k`` for k = 0..n−1 (0-based form of ``(−1)^(k+1)``)."""
    signs = np.power(-1.0, np.arange(n), dtype=np.float64)
    signs.setflags(write=False)
    return signs


@cache
def _kept_columns(n: int) -> NDArray[np.intp]:
    """Row k lists every column of 0..n−1 except k."""
    kept = np.array([[j for j in range(n) if j != k] for k in range(n)], dtype=np.intp)
    kept.setflags(write=False)
    return kept


def _cross_lu(rows: NDArray[np.float64]) -> NDArray[np.float64]:
    """Minors as products of the pivots of partially pivoted LU, one per column-deleted matrix.

    ``scipy.linalg.det`` multiplies the pivots (``np.linalg.det`` goes through ``exp(log|det|)``
    and is a few ulps off even on a 1×1 matrix).
    """
    n = rows.shape[-1]
    # rows[..., i, kept[k, j]] has axes (..., i, k, j); put k in front of the square matrix.
    deleted = np.moveaxis(rows[..., _kept_columns(n)], -3, -2)
    return _alternating(n) * scipy.linalg.det(deleted, check_finite=False)


def _cross4(rows: NDArray[np.float64]) -> NDArray[np.float64]:
    """``α_i = [n_i : d_i]``: ``ξ[:3] = d1 n2×n3 + d2 n3×n1 + d3 n1×n2``, ``ξ[3] = −n1·(n2×n3)``."""
    n1, n2, n3 = rows[..., 0, :3], rows[..., 1, :3], rows[..., 2, :3]
    d1, d2, d3 = rows[..., 0, 3:], rows[..., 1, 3:], rows[..., 2, 3:]
    n23 = np.cross(n2, n3)
    result = np.empty(rows.shape[:-2] + (4,))
    result[..., :3] = d1 * n23 + d2 * np.cross(n3, n1) + d3 * np.cross(n1, n2)
    result[..., 3] = -np.sum(n1 * n23, axis=-1)
    return result


def _cross_cofactor(rows: NDArray[np.float64]) -> NDArray[np.float64]:
    """Closed forms for n ≤ 4 (n = 2: ``ξ = [α_2, −α_1]``), the Laplace expansion above."""
    n = rows.shape[-1]
    if n == 2:
        return np.stack([rows[..., 0, 1], -rows[..., 0, 0]], axis=-1)
    if n == 3:
        return np.cross(rows[..., 0, :], rows[..., 1, :])
    if n == 4:
        return _cross4(rows)
    return _cross_laplace(rows)


def _cross(rows: NDArray[np.float64], method: Method) -> NDArray[np.float64]:
    check_choice("method", method, METHODS)
    return _cross_cofactor(rows) if method == "cofactor" else _cross_lu(rows)


# --------------------------------------------------------------------------- public API
def generalized_cross(rows: ArrayLike, *, method: Method = "cofactor") -> NDArray[np.float64]:
    """``ξ = α_1 × … × α_{n−1}`` for rows of shape ``(..., n−1, n)``; returns ``(..., n)``.

    ``ξ_k = (−1)^(k+1) det(D with column k deleted)`` (1-based k), ``D`` the stacked rows.
    ``method``: ``"cofactor"`` (division-free, exact on small integers) or ``"lu"``
    (pivoted LU; more accurate when the rows are nearly dependent). See the module notes.
    """
    return _cross(_as_rows("rows", rows), method)


def cross(*vectors: ArrayLike, method: Method = "cofactor") -> NDArray[np.float64]:
    """``α_1 × … × α_{n−1}`` of ``n − 1`` vectors of shape ``(..., n)`` (batch axes broadcast).

    ``cross(a, b)`` is the ordinary 3-D cross product, ``cross(a, b, c)`` the 4-D one.
    """
    if not vectors:
        raise InputError("vectors: expected at least one vector, got none")
    names = tuple(f"vectors[{i}]" for i in range(len(vectors)))
    return _cross(_as_vectors(names, vectors, len(vectors) + 1), method)


def augmented(A: ArrayLike, b: ArrayLike) -> NDArray[np.float64]:
    """Rows ``α_i = [a_i | −b_i]`` of the system ``Ax = b``: shape ``(..., n, n+1)``."""
    matrix = as_float_array("A", A, (None, None))
    if matrix.shape[-1] != matrix.shape[-2] or matrix.shape[-1] < 1:
        raise InputError(
            f"A: expected a square matrix, shape (..., n, n) with n >= 1, got {matrix.shape}"
        )
    n = matrix.shape[-1]
    rhs = as_float_array("b", b, (n,))
    try:
        batch = np.broadcast_shapes(matrix.shape[:-2], rhs.shape[:-1])
    except ValueError:
        raise InputError(
            f"A {matrix.shape} and b {rhs.shape}: batch shapes do not broadcast"
        ) from None
    rows = np.empty(batch + (n, n + 1))
    rows[..., :n] = matrix
    rows[..., n] = -rhs
    return rows


def solve(A: ArrayLike, b: ArrayLike, *, method: Method = "cofactor") -> NDArray[np.float64]:
    """Homogeneous solution ``[x : w]`` of ``Ax = b``, shape ``(..., n+1)``, with no division.

    ``[x : w] = (−1)^n α_1 × … × α_n`` with ``α_i = [a_i | −b_i]``, so ``x_i = det A_i`` and
    ``w = det A`` (Cramer's rule before its division). Singular ``A`` gives ``w = 0`` (no finite
    solution) or an all-zero vector (degenerate); see :func:`classify`, :func:`to_euclidean`.
    """
    rows = augmented(A, b)
    n = rows.shape[-2]
    xi = _cross(rows, method)
    return -xi if n % 2 else xi


def null_vector(A: ArrayLike, *, method: Method = "cofactor") -> NDArray[np.float64]:
    """A solution of ``Ax = 0``, ``A`` of shape ``(..., n−1, n)``: ``x = a_1 × … × a_{n−1}``.

    Zero when ``rank A < n − 1`` (the solution is not unique up to scale). Paper, eq. 11.
    """
    return _cross(_as_rows("A", A), method)


def default_rtol(n: int) -> float:
    """Default tolerance of :func:`classify` for ``ξ ∈ R^n``: ``N · m^(m/2) · eps``.

    With ``m = n − 1`` and ``N = m(m+1)/2`` this is the worst-case rounding error of an m×m
    cofactor expansion relative to its Hadamard bound ``Π ‖rows‖₂`` (the permanent of ``|A|``
    is at most ``Π ‖a_i‖₁ ≤ m^(m/2) Π ‖a_i‖₂``).
    n = 3: 1.3e-15, n = 4: 6.9e-15, n = 5: 3.6e-14, n = 6: 1.9e-13.
    """
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 2:
        raise InputError(f"n: expected an integer >= 2, got {n!r}")
    m = int(n) - 1
    return m * (m + 1) / 2 * m ** (m / 2) * _EPS


def classify(
    xi: ArrayLike, rows: ArrayLike | None = None, *, rtol: float | None = None
) -> NDArray[np.int8]:
    """Per-vector :class:`Kind` of homogeneous points ``ξ = [x : w]``: ``(..., n)`` → ``(...)``.

    With ``rows`` (the ``(..., n−1, n)`` rows ξ was computed from; for :func:`solve`, use
    :func:`augmented`) the tests compare against the Hadamard bounds, which scale like ξ:

    * DEGENERATE  if ``‖ξ‖ ≤ rtol · Π ‖α_i‖`` — the rows are dependent to within rounding;
    * AT_INFINITY if ``|w| ≤ rtol · Π ‖α_i[:−1]‖`` — ``|det A| / Π ‖a_i‖``, the sine-like volume
      ratio of the hyperplane normals, is at rounding level (parallel lines, for instance);
    * FINITE otherwise. For ξ from ``method="cofactor"`` and the default ``rtol`` this is
      certified: ``|w|`` exceeds the worst-case rounding error (:func:`default_rtol`), so the
      exact determinant of the given data is non-zero.

    Without ``rows`` only ξ is known: AT_INFINITY if ``|w| ≤ rtol · ‖ξ‖`` (the point lies beyond
    ``1/rtol`` in its own units), and DEGENERATE only if ξ is exactly zero — there is no scale to
    tell a rounding-level ξ from a small one. Prefer passing ``rows``.

    For a line or plane ``[a : d]`` only DEGENERATE is meaningful. Never tests ``w == 0`` on raw
    floats; the result compares with :class:`Kind` members (``kinds == Kind.AT_INFINITY``).
    """
    vectors = as_float_array("xi", xi, (None,))
    n = vectors.shape[-1]
    if n < 2:
        raise InputError(
            f"xi: expected homogeneous vectors of length >= 2, got shape {vectors.shape}"
        )
    tol = _check_rtol(rtol, n)
    size = _norm(vectors)
    w = np.abs(vectors[..., -1])
    if rows is None:
        degenerate = size == 0
        at_infinity = w <= tol * size
    else:
        array = _as_rows("rows", rows)
        if array.shape[-1] != n:
            raise InputError(
                f"rows: expected shape (..., {n - 1}, {n}) to match xi {vectors.shape}, got "
                f"{array.shape}"
            )
        try:
            np.broadcast_shapes(vectors.shape[:-1], array.shape[:-2])
        except ValueError:
            message = f"xi {vectors.shape} and rows {array.shape}: batch shapes do not broadcast"
            raise InputError(message) from None
        # Compare in log2 so that the Hadamard products can neither overflow nor underflow.
        with np.errstate(divide="ignore"):
            log_tol = math.log2(tol) if tol > 0 else -math.inf
            degenerate = np.log2(size) <= log_tol + _log2_product_of_norms(array)
            at_infinity = np.log2(w) <= log_tol + _log2_product_of_norms(array[..., :-1])
    kinds = np.where(
        degenerate, Kind.DEGENERATE, np.where(at_infinity, Kind.AT_INFINITY, Kind.FINITE)
    )
    return kinds.astype(np.int8)


def homogeneous(points: ArrayLike, w: float = 1.0) -> NDArray[np.float64]:
    """Append the coordinate ``w`` (default 1): ``(..., d)`` → ``(..., d+1)``."""
    array = as_float_array("points", points, (None,))
    if np.ndim(w) != 0:
        raise InputError(f"w: expected a scalar, got shape {np.shape(w)}")
    weight = as_float_array("w", w)[()]
    result = np.empty(array.shape[:-1] + (array.shape[-1] + 1,))
    result[..., :-1] = array
    result[..., -1] = weight
    return result


def to_euclidean(
    h: ArrayLike, rows: ArrayLike | None = None, *, rtol: float | None = None
) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
    """Euclidean points ``x / w`` from ``[x : w]`` (``(..., n)`` → ``(..., n−1)``) and a ``finite``
    mask.

    Where :func:`classify` (same ``rows`` and ``rtol``) does not say FINITE, the point is replaced
    by something explicit, never NaN: the unit direction ``x / ‖x‖`` for a point at infinity (its
    sign is arbitrary, as in P^n), zeros for a degenerate vector. ``finite`` is False there.
    """
    vectors = as_float_array("h", h, (None,))
    kinds = classify(vectors, rows, rtol=rtol)
    finite = kinds == Kind.FINITE
    spatial = vectors[..., :-1]
    length = _norm(spatial)
    at_infinity = (kinds == Kind.AT_INFINITY) & (length > 0)
    points = np.zeros(spatial.shape)
    np.divide(spatial, vectors[..., -1:], out=points, where=finite[..., None])
    np.divide(spatial, length[..., None], out=points, where=at_infinity[..., None])
    return points, finite


def rescale(h: ArrayLike) -> NDArray[np.float64]:
    """``h · 2^k`` per vector (last axis) with ``max |h_i|`` in [0.5, 1): exact, division-free.

    The same homogeneous point (or the same equation, for rows). Zero vectors stay zero.
    """
    vectors = as_float_array("h", h, (None,))
    _, exponent = np.frexp(np.max(np.abs(vectors), axis=-1, initial=0.0))
    return np.ldexp(vectors, -exponent[..., None])


def join_points_2d(x1: ArrayLike, x2: ArrayLike) -> NDArray[np.float64]:
    """Line ``[a, b, c]`` through homogeneous points ``[x, y : w]`` of shape ``(..., 3)``: ``x1 ×
    x2``.

    Paper, eqs. 6–7. Zero (DEGENERATE) when the points coincide.
    """
    return _cross_cofactor(_as_vectors(("x1", "x2"), (x1, x2), 3))


def meet_lines_2d(l1: ArrayLike, l2: ArrayLike) -> NDArray[np.float64]:
    """Intersection ``[x, y : w]`` of lines ``[a, b, c]`` of shape ``(..., 3)``: ``l1 × l2``.

    Paper, eq. 8. ``w = 0`` for parallel lines; zero for coincident ones.
    """
    return _cross_cofactor(_as_vectors(("l1", "l2"), (l1, l2), 3))


def plane_through_points(x1: ArrayLike, x2: ArrayLike, x3: ArrayLike) -> NDArray[np.float64]:
    """Plane ``[a, b, c, d]`` through homogeneous points ``[x, y, z : w]`` (``(..., 4)``): ``x1 × x2
    × x3``.

    Paper, eq. 9. Zero (DEGENERATE) when the points are collinear.
    """
    return _cross4(_as_vectors(("x1", "x2", "x3"), (x1, x2, x3), 4))


def meet_planes(p1: ArrayLike, p2: ArrayLike, p3: ArrayLike) -> NDArray[np.float64]:
    """Common point ``[x, y, z : w]`` of planes ``[a, b, c, d]`` (``(..., 4)``): ``p1 × p2 × p3``.

    Paper, eq. 9. ``w = 0`` when the normals are coplanar and the planes share no finite point;
    zero when the planes share a line.
    """
    return _cross4(_as_vectors(("p1", "p2", "p3"), (p1, p2, p3), 4))
