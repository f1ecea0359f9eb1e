"""Tests of g1patch.projective: generalized cross product, homogeneous solves, join and meet.

Exactness: with integer entries in [-9, 9] every product and partial sum of a cofactor
expansion of an m×m minor is an integer bounded by the permanent of |minor| ≤ (9m)^m; for
m ≤ 8 that is below 2^53, so float64 computes it exactly and the tests compare with ``==``.

Float tolerances are a-priori bounds, not guesses:

* cofactor rounding (``projective`` module notes): |ξ̂_k − ξ_k| ≤ N·eps·Π_i ‖α_i‖₁,
  N = m(m+1)/2 roundings per term (one product and k−1 additions at level k of the expansion);
* a dot product of n terms adds at most n·eps·Σ|terms| (Higham, ASNA §3.1);
* solving by pivoted LU: ‖x̂ − x‖∞ / ‖x‖∞ ≲ 3n·u·ρ·cond∞(A) (ASNA §9.4, u = eps/2); the
  growth factor ρ is ≈ 1–2 for these small random matrices, so c = n·cond∞·eps holds with margin
  (measured worst case ≈ 0.15·cond∞·eps against exact rationals, up to cond 1e12).
"""

from __future__ import annotations

import math
import warnings
from fractions import Fraction

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from g1patch import projective as pj
from g1patch.errors import InputError
from g1patch.projective import Kind

EPS = float(np.finfo(np.float64).eps)
SMALL_INT = st.integers(-9, 9)


# --------------------------------------------------------------------------- exact references
def exact_det(matrix: list[list[Fraction]]) -> Fraction:
    """Determinant by Gaussian elimination in rational arithmetic."""
    rows = [[Fraction(x) for x in row] for row in matrix]
    n = len(rows)
    det = Fraction(1)
    for col in range(n):
        pivot = next((r for r in range(col, n) if rows[r][col] != 0), None)
        if pivot is None:
            return Fraction(0)
        if pivot != col:
            rows[col], rows[pivot] = rows[pivot], rows[col]
            det = -det
        det *= rows[col][col]
        for r in range(col + 1, n):
            factor = rows[r][col] / rows[col][col]
            rows[r] = [a - factor * b for a, b in zip(rows[r], rows[col], strict=True)]
    return det


def exact_cross(rows: np.ndarray) -> list[Fraction]:
    """ξ_k = (−1)^(k+1) det(D with column k deleted), 1-based k, in rationals."""
    data = [[Fraction(float(x)) for x in row] for row in rows]
    n = len(data[0])
    return [
        (-1) ** k * exact_det([[row[j] for j in range(n) if j != k] for row in data])
        for k in range(n)
    ]


def exact_cramer(A: np.ndarray, b: np.ndarray) -> tuple[list[Fraction], Fraction]:
    """(det A_1, …, det A_n), det A with A_i = A with column i replaced by b — no cross product."""
    a = [[Fraction(float(x)) for x in row] for row in A]
    rhs = [Fraction(float(x)) for x in b]
    n = len(a)
    replaced = [
        exact_det([[rhs[r] if c == i else a[r][c] for c in range(n)] for r in range(n)])
        for i in range(n)
    ]
    return replaced, exact_det(a)


def exact_solution(A: np.ndarray, b: np.ndarray) -> np.ndarray:
    minors, det = exact_cramer(A, b)
    return np.array([float(m / det) for m in minors])


def as_float(values: list[Fraction]) -> np.ndarray:
    return np.array([float(v) for v in values])


def int_matrix(rows: int, cols: int) -> st.SearchStrategy[np.ndarray]:
    return st.lists(
        st.lists(SMALL_INT, min_size=cols, max_size=cols), min_size=rows, max_size=rows
    ).map(lambda x: np.array(x, dtype=np.float64).reshape(rows, cols))


@st.composite
def int_rows(draw: st.DrawFn, min_n: int = 2, max_n: int = 6) -> np.ndarray:
    n = draw(st.integers(min_n, max_n))
    return draw(int_matrix(n - 1, n))


# Floats with no underflow in products of ≤ 8 factors, so the relative bounds hold.
FLOAT = st.floats(-1e3, 1e3, allow_nan=False, allow_infinity=False).map(
    lambda x: 0.0 if abs(x) < 1e-30 else x
)


@st.composite
def float_rows(draw: st.DrawFn, min_n: int = 2, max_n: int = 6) -> np.ndarray:
    n = draw(st.integers(min_n, max_n))
    values = draw(st.lists(FLOAT, min_size=n * (n - 1), max_size=n * (n - 1)))
    return np.array(values).reshape(n - 1, n)


def rounding_bound(rows: np.ndarray) -> float:
    """N·eps·Π ‖α_i‖₁ with N = m(m+1)/2: the cofactor method's worst-case absolute error."""
    m = rows.shape[-2]
    return m * (m + 1) / 2 * EPS * np.prod(np.abs(rows).sum(axis=-1), axis=-1)


# --------------------------------------------------------------------------- exactness: Cramer
@pytest.mark.parametrize("n", range(1, 7))
@settings(max_examples=40, deadline=None)
@given(data=st.data())
def test_solve_equals_cramer_exactly(n: int, data: st.DataObject) -> None:
    assert (9 * n) ** n < 2**53  # every intermediate is an exactly representable integer
    A = data.draw(int_matrix(n, n))
    b = data.draw(int_matrix(1, n))[0]
    minors, det = exact_cramer(A, b)
    expected = as_float(minors + [det])
    assert np.array_equal(pj.solve(A, b), expected)
    assert np.array_equal(pj.cross(*pj.augmented(A, b)) * (-1) ** n, expected)


@settings(max_examples=60, deadline=None)
@given(rows=int_rows(2, 9))
def test_generalized_cross_equals_exact_minors(rows: np.ndarray) -> None:
    # up to 8×8 minors: (9·8)^8 ≈ 7.2e14 < 2^53, still exact
    assert np.array_equal(pj.generalized_cross(rows), as_float(exact_cross(rows)))


@settings(max_examples=60, deadline=None)
@given(rows=int_rows(2, 7), data=st.data())
def test_cross_is_the_determinant_with_a_first_row(rows: np.ndarray, data: st.DataObject) -> None:
    """v·ξ = det[v; α_1; …; α_{n−1}] for every v: the definition, checked independently of
    minors."""
    n = rows.shape[1]
    v = data.draw(int_matrix(1, n))
    expected = exact_det([[Fraction(float(x)) for x in r] for r in np.vstack([v, rows])])
    assert float(v[0] @ pj.generalized_cross(rows)) == float(expected)


def test_closed_forms_sign_convention() -> None:
    # n = 3: e1 × e2 = e3; n = 4 with α = [n : d]: ξ[:3] = Σ d_i n_j × n_k, ξ[3] = −n1·(n2×n3)
    assert np.array_equal(pj.cross([1, 0, 0], [0, 1, 0]), [0, 0, 1])
    assert np.array_equal(pj.cross([1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0]), [0, 0, 0, -1])
    assert np.array_equal(pj.cross([1, 0, 0, 5], [0, 1, 0, 0], [0, 0, 1, 0]), [5, 0, 0, -1])
    assert np.array_equal(pj.cross([3, -1]), [-1, -3])  # n = 2: ξ = [α_2, −α_1]
    rng = np.random.default_rng(3)
    for n in (2, 3, 4):
        rows = rng.integers(-9, 10, (200, n - 1, n)).astype(float)
        laplace = pj._cross_laplace(rows)  # the general expansion, against the closed forms
        assert np.array_equal(pj.generalized_cross(rows), laplace)


# --------------------------------------------------------------------------- algebraic properties
@settings(max_examples=100, deadline=None)
@given(rows=int_rows())
def test_orthogonal_to_every_row(rows: np.ndarray) -> None:
    xi = pj.generalized_cross(rows)
    assert np.array_equal(rows @ xi, np.zeros(len(rows)))


@settings(max_examples=100, deadline=None)
@given(rows=int_rows(3, 7), data=st.data())
def test_swapping_two_rows_flips_the_sign(rows: np.ndarray, data: st.DataObject) -> None:
    i, j = data.draw(st.lists(st.integers(0, len(rows) - 1), min_size=2, max_size=2, unique=True))
    swapped = rows.copy()
    swapped[[i, j]] = rows[[j, i]]
    for method in pj.METHODS:
        expected = -pj.generalized_cross(rows, method=method)
        if method == "cofactor":
            assert np.array_equal(pj.generalized_cross(swapped, method=method), expected)
        # a different pivot order: equal up to LU rounding, ~n·eps of Π‖α_i‖ (Hadamard's bound on a
        # minor)
        else:
            scale = float(np.prod(np.linalg.norm(rows, axis=1)))
            assert np.allclose(
                pj.generalized_cross(swapped, method=method),
                expected,
                rtol=0,
                atol=64 * EPS * scale,
            )


@settings(max_examples=100, deadline=None)
@given(rows=int_rows(), data=st.data())
def test_multilinear(rows: np.ndarray, data: st.DataObject) -> None:
    n = rows.shape[1]
    i = data.draw(st.integers(0, n - 2))
    other = data.draw(int_matrix(1, n))[0]
    s, t = data.draw(SMALL_INT), data.draw(SMALL_INT)
    combined, replaced = rows.copy(), rows.copy()
    combined[i] = s * rows[i] + t * other
    replaced[i] = other
    lhs = pj.generalized_cross(combined)
    rhs = s * pj.generalized_cross(rows) + t * pj.generalized_cross(replaced)
    assert np.array_equal(lhs, rhs)


@settings(max_examples=60, deadline=None)
@given(rows=int_rows(3, 7), data=st.data())
def test_dependent_rows_give_zero(rows: np.ndarray, data: st.DataObject) -> None:
    i, j = data.draw(st.lists(st.integers(0, len(rows) - 1), min_size=2, max_size=2, unique=True))
    rows[j] = data.draw(SMALL_INT) * rows[i]
    xi = pj.generalized_cross(rows)
    assert np.array_equal(xi, np.zeros_like(xi))
    assert pj.classify(xi, rows) == Kind.DEGENERATE


@settings(max_examples=100, deadline=None)
@given(rows=float_rows(2, 7))
def test_float_rounding_within_the_a_priori_bound(rows: np.ndarray) -> None:
    error = np.abs(pj.generalized_cross(rows) - as_float(exact_cross(rows)))
    assert error.max() <= rounding_bound(rows)


@settings(max_examples=100, deadline=None)
@given(rows=float_rows(2, 7))
def test_float_orthogonality_within_the_a_priori_bound(rows: np.ndarray) -> None:
    # ξ̂·α_i = (ξ̂ − ξ)·α_i + rounding of the dot; |ξ_k| ≤ Π‖α_j‖₁
    n = rows.shape[1]
    xi = pj.generalized_cross(rows)
    row_norms = np.abs(rows).sum(axis=1)
    bound = rounding_bound(rows) * row_norms + n * EPS * np.prod(row_norms) * row_norms
    assert np.all(np.abs(rows @ xi) <= bound)


# --------------------------------------------------------------------------- accuracy vs LAPACK
@pytest.mark.parametrize("method", pj.METHODS)
@pytest.mark.parametrize("n", range(1, 7))
def test_agrees_with_numpy_solve(n: int, method: str) -> None:
    rng = np.random.default_rng(100 + n)
    A = rng.standard_normal((2000, n, n))
    b = rng.standard_normal((2000, n))
    reference = np.linalg.solve(A, b[..., None])[..., 0]
    points, finite = pj.to_euclidean(pj.solve(A, b, method=method))
    assert finite.all()
    # both sides within ≈ n·u·cond of the truth (module docstring); c = 2n covers the sum
    bound = 2 * n * np.linalg.cond(A, np.inf) * EPS * np.abs(reference).max(axis=-1)
    assert np.all(np.abs(points - reference).max(axis=-1) <= bound)


def _ill_conditioned(
    rng: np.random.Generator, n: int, cond: float
) -> tuple[np.ndarray, np.ndarray]:
    u, _ = np.linalg.qr(rng.standard_normal((n, n)))
    v, _ = np.linalg.qr(rng.standard_normal((n, n)))
    return u @ np.diag(np.logspace(0, -math.log10(cond), n)) @ v.T, rng.standard_normal(n)


@pytest.mark.parametrize("n", [2, 3, 4])
@pytest.mark.parametrize("cond", [1e4, 1e8, 1e12])
def test_lu_method_is_condition_number_accurate(n: int, cond: float) -> None:
    rng = np.random.default_rng(int(n * math.log10(cond)))
    for _ in range(15):
        A, b = _ill_conditioned(rng, n, cond)
        exact = exact_solution(A, b)
        h = pj.solve(A, b, method="lu")
        error = np.abs(h[:-1] / h[-1] - exact).max() / np.abs(exact).max()
        assert error <= n * np.linalg.cond(A, np.inf) * EPS


def test_cofactor_is_less_accurate_than_lu_when_ill_conditioned() -> None:
    """The documented caveat (note B.4): closed-form cofactors lose to pivoted LU at cond 1e8."""
    rng = np.random.default_rng(5)
    errors: dict[str, list[float]] = {"cofactor": [], "lu": []}
    for _ in range(30):
        A, b = _ill_conditioned(rng, 3, 1e8)
        exact = exact_solution(A, b)
        for method in errors:
            h = pj.solve(A, b, method=method)
            errors[method].append(np.abs(h[:-1] / h[-1] - exact).max() / np.abs(exact).max())
    assert np.median(errors["cofactor"]) > 10 * np.median(errors["lu"])


# --------------------------------------------------------------------------- singular systems
SINGULAR = [
    # (A, b, kind): rank A = n−1 with b outside its range → w = 0; rank [A|−b] < n → ξ = 0
    ([[1, 2], [2, 4]], [1, 3], Kind.AT_INFINITY),
    ([[1, 2], [2, 4]], [1, 2], Kind.DEGENERATE),
    ([[1, 2, 3], [4, 5, 6], [7, 8, 9]], [1, 0, 0], Kind.AT_INFINITY),
    ([[1, 2, 3], [4, 5, 6], [7, 8, 9]], [1, 2, 3], Kind.DEGENERATE),
    ([[1, 1, 1], [2, 2, 2], [3, 3, 3]], [1, 5, 7], Kind.DEGENERATE),  # rank A = 1: no information
    ([[0, 0], [0, 0]], [0, 0], Kind.DEGENERATE),
    ([[0.0]], [2.5], Kind.AT_INFINITY),
]


@pytest.mark.parametrize("method", pj.METHODS)
@pytest.mark.parametrize(("A", "b", "kind"), SINGULAR)
def test_singular_systems_never_raise_or_nan(A: list, b: list, kind: Kind, method: str) -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        h = pj.solve(A, b, method=method)
        rows = pj.augmented(A, b)
        points, finite = pj.to_euclidean(h, rows)
    assert np.isfinite(h).all() and np.isfinite(points).all()
    assert h[-1] == 0  # exact for these integer systems
    assert pj.classify(h, rows) == kind
    assert not finite
    if kind == Kind.AT_INFINITY:
        direction = h[:-1] / np.linalg.norm(h[:-1])
        matrix = np.asarray(A, float)  # the null vector of A, to rounding of the unit direction
        assert np.all(np.abs(matrix @ direction) <= 8 * EPS * np.abs(matrix).sum(axis=1))
        assert np.allclose(np.abs(points @ direction), 1.0)
    else:
        assert np.array_equal(points, np.zeros_like(points))


def test_nearly_singular_float_system_is_classified_with_rows() -> None:
    # rank-2 A built in floats: w is rounding noise, not zero; classify with rows sees through it
    rng = np.random.default_rng(11)
    u, v = rng.standard_normal((2, 3))
    A = np.stack([u, v, 0.1 * u + 0.7 * v])
    b = np.array([1.0, 2.0, 0.0])  # b_3 ≠ 0.1 b_1 + 0.7 b_2: no finite solution
    h = pj.solve(A, b)
    assert pj.classify(h, pj.augmented(A, b)) == Kind.AT_INFINITY
    b_consistent = np.array([1.0, 2.0, 0.1 * 1.0 + 0.7 * 2.0])
    h = pj.solve(A, b_consistent)
    assert pj.classify(h, pj.augmented(A, b_consistent)) == Kind.DEGENERATE


def test_null_vector_is_the_paper_normal() -> None:
    # paper eq. 11: [p_u; p_v] n = 0 is solved by n = p_u × p_v
    p_u, p_v = np.array([1.0, 0.5, -2.0]), np.array([0.25, 3.0, 1.0])
    n = pj.null_vector(np.stack([p_u, p_v]))
    assert np.array_equal(n, np.cross(p_u, p_v))
    assert np.array_equal(pj.null_vector([[1, 2, 3], [2, 4, 6]]), [0, 0, 0])  # rank 1: degenerate


# --------------------------------------------------------------------------- classify
def test_classify_scale_invariant() -> None:
    rows = np.array([[1.0, 2.0, 3.0, 4.0], [0.0, 1.0, 5.0, -1.0], [2.0, 4.0, 6.0, 1.0]])
    xi = pj.generalized_cross(rows)
    kinds = pj.classify(xi, rows)
    for factor in (1e-150, 1e-9, 3.7, 1e150):
        assert pj.classify(xi * factor, rows * factor ** (1 / 3)) == kinds
        assert pj.classify(-xi * factor) == pj.classify(xi)


def test_classify_shapes_and_default_tolerance() -> None:
    assert pj.classify([1.0, 2.0, 3.0]).shape == ()
    assert pj.classify(np.zeros((4, 5, 3))).shape == (4, 5)
    assert pj.classify([1.0, 0.0, 0.0]) == Kind.AT_INFINITY
    assert pj.classify([0.0, 0.0, 0.0]) == Kind.DEGENERATE
    assert pj.classify([1.0, 0.0, 1e-20]) == Kind.AT_INFINITY  # farther than 1/rtol
    assert pj.classify([1.0, 0.0, 1e-20], rtol=0.0) == Kind.FINITE
    assert pj.default_rtol(2) == EPS
    assert pj.default_rtol(4) == pytest.approx(6 * 3**1.5 * EPS)


def test_to_euclidean_and_homogeneous_round_trip() -> None:
    points = np.random.default_rng(2).standard_normal((10, 3))
    out, finite = pj.to_euclidean(pj.homogeneous(4.0 * points, w=4.0))
    assert finite.all()
    assert np.array_equal(out, points)  # division by a power of two is exact


def test_rescale_is_exact() -> None:
    h = np.array([[3.0, -1e-300, 5.0], [0.0, 0.0, 0.0], [1e300, 2e300, -7e299]])
    scaled = pj.rescale(h)
    assert np.array_equal(scaled[1], [0, 0, 0])
    peaks = np.abs(scaled[[0, 2]]).max(axis=1)
    assert np.all((peaks >= 0.5) & (peaks < 1.0))
    ratios = scaled[[0, 2]] / h[[0, 2]]
    assert np.all(ratios[:, 0] == ratios[:, 2])
    assert np.all(np.frexp(ratios[:, 0])[0] == 0.5)  # a power of two


# --------------------------------------------------------------------------- P2 and P3
def test_paper_eqs_6_to_8() -> None:
    x1, x2 = pj.homogeneous([1.0, 2.0]), pj.homogeneous([3.0, 5.0])
    line = pj.join_points_2d(x1, x2)
    assert np.array_equal(line, [-3, 2, -1])  # −3x + 2y − 1 = 0
    assert np.array_equal(np.stack([x1, x2]) @ line, [0, 0])  # eq. 6: A p = 0
    point = pj.meet_lines_2d([1, 1, -3], [1, -1, -1])  # x + y = 3, x − y = 1
    assert np.array_equal(point, [-4, -2, -2])
    assert np.array_equal(pj.to_euclidean(point)[0], [2, 1])


def test_paper_eq_9() -> None:
    e = np.eye(3)
    plane = pj.plane_through_points(*pj.homogeneous(e))
    assert np.array_equal(plane, [1, 1, 1, -1])  # x + y + z − 1 = 0
    point = pj.meet_planes([1, 0, 0, -1], [0, 1, 0, -2], [0, 0, 1, -3])
    assert np.array_equal(point, [-1, -2, -3, -1])
    assert np.array_equal(pj.to_euclidean(point)[0], [1, 2, 3])


def test_parallel_lines_meet_at_infinity() -> None:
    l1, l2 = (
        np.array([2.0, 3.0, 1.0]),
        np.array([4.0, 6.0, 5.0]),
    )  # 2x + 3y + 1 = 0 ∥ 4x + 6y + 5 = 0
    point = pj.meet_lines_2d(l1, l2)
    assert point[2] == 0 and np.any(point[:2] != 0)
    assert pj.classify(point) == Kind.AT_INFINITY
    assert pj.classify(point, np.stack([l1, l2])) == Kind.AT_INFINITY
    direction, finite = pj.to_euclidean(point)
    assert not finite
    assert np.allclose(np.abs(direction @ [3, -2] / math.sqrt(13)), 1.0)  # along the lines


def test_parallel_float_lines_meet_at_infinity_with_rows() -> None:
    # l2 = s·l1 in its normal, in floats: w is rounding noise, the Hadamard test sees through it
    rng = np.random.default_rng(0)
    l1 = rng.standard_normal((1000, 3))
    l2 = l1 * rng.standard_normal((1000, 1))
    l2[:, 2] = rng.standard_normal(1000)
    points = pj.meet_lines_2d(l1, l2)
    assert np.mean(points[:, 2] != 0) > 0.2  # the noise is really there
    assert np.all(pj.classify(points, np.stack([l1, l2], axis=-2)) == Kind.AT_INFINITY)


def test_lines_through_the_same_two_points() -> None:
    x1, x2 = np.array([1.0, 2.0, 1.0]), np.array([3.0, 5.0, 1.0])
    line = pj.join_points_2d(x1, x2)
    other = pj.join_points_2d(2 * x1, -3 * x2)  # same points, other homogeneous weights
    assert np.array_equal(pj.cross(line, other), [0, 0, 0])  # proportional
    meet = pj.meet_lines_2d(line, other)
    assert pj.classify(meet) == Kind.DEGENERATE  # coincident lines share every point
    same = pj.join_points_2d(x1, 7 * x1)
    assert pj.classify(same, np.stack([x1, 7 * x1])) == Kind.DEGENERATE


def test_plane_through_collinear_points_is_degenerate() -> None:
    p, d = np.array([1.0, -2.0, 3.0]), np.array([2.0, 1.0, -1.0])
    rows = pj.homogeneous(np.stack([p, p + d, p - 3 * d]))
    plane = pj.plane_through_points(*rows)
    assert np.array_equal(plane, np.zeros(4))
    assert pj.classify(plane, rows) == Kind.DEGENERATE
    # inexact float data: not zero, but at rounding level relative to the Hadamard bound
    rng = np.random.default_rng(0)
    p, d, t = (
        100 * rng.standard_normal((1000, 3)),
        rng.standard_normal((1000, 3)),
        rng.standard_normal((1000, 3)),
    )
    rows = pj.homogeneous(p[:, None, :] + t[..., None] * d[:, None, :])
    planes = pj.plane_through_points(rows[:, 0], rows[:, 1], rows[:, 2])
    assert np.mean(np.any(planes != 0, axis=-1)) > 0.5
    assert np.all(pj.classify(planes, rows) == Kind.DEGENERATE)


@settings(max_examples=100, deadline=None)
@given(point=int_matrix(1, 3), normals=int_matrix(3, 3))
def test_meet_of_three_planes_through_a_known_point(point: np.ndarray, normals: np.ndarray) -> None:
    planes = np.hstack([normals, -(normals @ point[0])[:, None]])  # n_i·x − n_i·p = 0
    meet = pj.meet_planes(*planes)
    if np.linalg.matrix_rank(normals) == 3:
        assert pj.classify(meet, planes) == Kind.FINITE
        assert np.array_equal(pj.to_euclidean(meet)[0], point[0])  # exact: ξ[:3] = w·p
    else:
        assert pj.classify(meet, planes) != Kind.FINITE


def test_planes_without_a_common_point_and_with_a_common_line() -> None:
    # three planes whose normals are coplanar: a triangular prism → at infinity
    prism = pj.meet_planes([1, 0, 0, 0], [0, 1, 0, 0], [1, 1, 0, -1])
    assert prism[3] == 0 and pj.classify(prism) == Kind.AT_INFINITY
    # three planes of a pencil through the z axis → degenerate
    pencil = pj.meet_planes([1, 0, 0, 0], [0, 1, 0, 0], [1, 1, 0, 0])
    assert pj.classify(pencil) == Kind.DEGENERATE


def test_points_with_other_weights_need_no_conversion() -> None:
    line = pj.join_points_2d([2.0, 4.0, 2.0], [-6.0, -10.0, -2.0])  # (1, 2) and (3, 5)
    assert np.array_equal(line, -4 * np.array([-3.0, 2.0, -1.0]))


# --------------------------------------------------------------------------- batching
@pytest.mark.parametrize("method", pj.METHODS)
@pytest.mark.parametrize("n", [2, 3, 4, 5, 6])
def test_batched_equals_one_at_a_time(n: int, method: str) -> None:
    rows = np.random.default_rng(n).standard_normal((3, 4, n - 1, n))
    batched = pj.generalized_cross(rows, method=method)
    assert batched.shape == (3, 4, n)
    single = np.array([[pj.generalized_cross(r, method=method) for r in block] for block in rows])
    # same arithmetic per element; LAPACK may block a batch differently, so allow LU rounding
    tolerance = 0.0 if method == "cofactor" else n * EPS * rounding_bound(rows).max()
    assert np.all(np.abs(batched - single) <= tolerance)


def test_broadcasting_and_empty_batches() -> None:
    points = pj.homogeneous(np.random.default_rng(0).standard_normal((5, 1, 2)))
    origin = pj.homogeneous(np.zeros((7, 2)))
    assert pj.join_points_2d(points, origin).shape == (5, 7, 3)
    A, b = np.eye(3), np.ones((6, 3))
    assert np.array_equal(pj.solve(A, b), np.tile([1.0, 1.0, 1.0, 1.0], (6, 1)))
    for method in pj.METHODS:
        assert pj.generalized_cross(np.zeros((0, 2, 3)), method=method).shape == (0, 3)
        assert pj.solve(np.zeros((0, 4, 4)), np.zeros((0, 4)), method=method).shape == (0, 5)
    assert pj.classify(np.zeros((0, 3))).shape == (0,)
    points, finite = pj.to_euclidean(np.zeros((0, 4)))
    assert points.shape == (0, 3) and finite.shape == (0,)


# --------------------------------------------------------------------------- bad input
P3 = [0.0, 0.0, 1.0]
P4 = [0.0, 0.0, 0.0, 1.0]
BAD_INPUT = [
    (
        pj.generalized_cross,
        ([[1.0, 2.0, 3.0]] * 3,),
        {},
        r"rows: expected shape \(\.\.\., n-1, n\).*\(3, 3\)",
    ),
    (pj.generalized_cross, ([1.0, 2.0],), {}, r"rows: expected shape"),
    (pj.generalized_cross, (np.zeros((0, 1)),), {}, r"rows: expected shape"),
    (
        pj.generalized_cross,
        ([[1.0, np.nan, 3.0], [1.0, 2.0, 3.0]],),
        {},
        r"rows: non-finite value nan",
    ),
    (
        pj.generalized_cross,
        ([[1.0, 2.0, 3.0], [1.0, np.inf, 3.0]],),
        {},
        r"rows: non-finite value inf",
    ),
    (
        pj.generalized_cross,
        ([["a", "b", "c"], ["d", "e", "f"]],),
        {},
        r"rows: expected an array of numbers",
    ),
    (
        pj.generalized_cross,
        ([[1.0, 2.0, 3.0], [1.0, 2.0, 4.0]],),
        {"method": "qr"},
        r"method: unknown value 'qr'",
    ),
    (pj.cross, (), {}, r"vectors: expected at least one vector"),
    (
        pj.cross,
        ([1.0, 2.0, 3.0], [1.0, 2.0]),
        {},
        r"vectors\[1\]: expected shape \(\.\.\., 3\), got \(2,\)",
    ),
    (
        pj.cross,
        ([1.0, 2.0, 3.0, 4.0], [1.0, 2.0, 3.0, 4.0]),
        {},
        r"vectors\[0\]: expected shape \(\.\.\., 3\)",
    ),
    (pj.cross, (np.zeros((2, 3)), np.zeros((5, 3))), {}, r"batch shapes do not broadcast"),
    (pj.cross, ([1.0, 2.0, 3.0], [np.nan, 0.0, 0.0]), {}, r"vectors\[1\]: non-finite"),
    (pj.augmented, (np.zeros((2, 3)), [1.0, 2.0]), {}, r"A: expected a square matrix.*\(2, 3\)"),
    (pj.solve, (np.zeros((2, 3)), [1.0, 2.0]), {}, r"A: expected a square matrix.*\(2, 3\)"),
    (pj.solve, (np.zeros((0, 0)), []), {}, r"A: expected a square matrix"),
    (pj.solve, (np.eye(2), [1.0, 2.0, 3.0]), {}, r"b: expected shape \(\.\.\., 2\), got \(3,\)"),
    (pj.solve, (np.eye(2), [1.0, np.nan]), {}, r"b: non-finite value nan at index \(1,\)"),
    (
        pj.solve,
        ([[1.0, np.inf], [0.0, 1.0]], [1.0, 2.0]),
        {},
        r"A: non-finite value inf at index \(0, 1\)",
    ),
    (
        pj.solve,
        (np.zeros((3, 2, 2)), np.zeros((4, 2))),
        {},
        r"A \(3, 2, 2\) and b \(4, 2\): batch shapes",
    ),
    (pj.solve, (np.eye(2), [1.0, 2.0]), {"method": "svd"}, r"method: unknown value 'svd'"),
    (pj.null_vector, (np.eye(3),), {}, r"A: expected shape \(\.\.\., n-1, n\).*\(3, 3\)"),
    (pj.null_vector, ([[np.nan, 0.0, 0.0], [0.0, 1.0, 0.0]],), {}, r"A: non-finite"),
    (pj.default_rtol, (1,), {}, r"n: expected an integer >= 2, got 1"),
    (pj.default_rtol, (3.0,), {}, r"n: expected an integer >= 2"),
    (pj.classify, ([1.0],), {}, r"xi: expected homogeneous vectors of length >= 2"),
    (pj.classify, (5.0,), {}, r"xi: expected shape \(\.\.\., N\), got \(\)"),
    (pj.classify, ([1.0, np.nan, 0.0],), {}, r"xi: non-finite value nan"),
    (pj.classify, (P3,), {"rtol": -1.0}, r"rtol: expected a finite non-negative number, got -1.0"),
    (pj.classify, (P3,), {"rtol": np.nan}, r"rtol: expected a finite non-negative number"),
    (pj.classify, (P3,), {"rtol": "tight"}, r"rtol: expected a non-negative number, got 'tight'"),
    (
        pj.classify,
        (P3, np.zeros((3, 4))),
        {},
        r"rows: expected shape \(\.\.\., 2, 3\) to match xi \(3,\)",
    ),
    (
        pj.classify,
        (np.zeros((2, 3)), np.zeros((5, 2, 3))),
        {},
        r"xi \(2, 3\) and rows \(5, 2, 3\): batch shapes",
    ),
    (pj.classify, (P3, [[1.0, np.inf, 0.0], [0.0, 1.0, 0.0]]), {}, r"rows: non-finite value inf"),
    (pj.homogeneous, ([1.0, np.inf],), {}, r"points: non-finite value inf"),
    (pj.homogeneous, (3.0,), {}, r"points: expected shape \(\.\.\., N\), got \(\)"),
    (pj.homogeneous, ([1.0, 2.0],), {"w": [1.0, 2.0]}, r"w: expected a scalar, got shape \(2,\)"),
    (pj.homogeneous, ([1.0, 2.0],), {"w": np.nan}, r"w: non-finite value nan"),
    (pj.to_euclidean, ([1.0, np.nan, 1.0],), {}, r"h: non-finite value nan"),
    (pj.to_euclidean, ([1.0],), {}, r"xi: expected homogeneous vectors of length >= 2"),
    (pj.to_euclidean, (P3,), {"rtol": -1}, r"rtol: expected a finite non-negative number"),
    (pj.rescale, ([1.0, np.inf],), {}, r"h: non-finite value inf"),
    (pj.rescale, (2.0,), {}, r"h: expected shape \(\.\.\., N\), got \(\)"),
    (pj.solve, (2.0, [1.0]), {}, r"A: expected shape \(\.\.\., N, N\), got \(\)"),
    (
        pj.join_points_2d,
        ([1.0, 2.0], P3),
        {},
        r"x1: expected shape \(\.\.\., 3\), got \(2,\) \(append w with homogeneous\(\)\)",
    ),
    (pj.join_points_2d, (P3, [1.0, np.nan, 1.0]), {}, r"x2: non-finite value nan"),
    (pj.meet_lines_2d, (P3, P4), {}, r"l2: expected shape \(\.\.\., 3\), got \(4,\)"),
    (pj.meet_lines_2d, (np.zeros((2, 3)), np.zeros((3, 3))), {}, r"l1 \(2, 3\), l2 \(3, 3\)"),
    (
        pj.plane_through_points,
        (P4, P4, [1.0, 2.0, 3.0]),
        {},
        r"x3: expected shape \(\.\.\., 4\), got \(3,\) \(append w",
    ),
    (pj.plane_through_points, (P4, [np.inf, 0, 0, 1], P4), {}, r"x2: non-finite value inf"),
    (pj.meet_planes, (P4, P4, P3), {}, r"p3: expected shape \(\.\.\., 4\), got \(3,\)"),
    (pj.meet_planes, ([np.nan, 0, 0, 1], P4, P4), {}, r"p1: non-finite value nan"),
]


@pytest.mark.parametrize(("function", "args", "kwargs", "message"), BAD_INPUT)
def test_bad_input_raises_input_error(function, args: tuple, kwargs: dict, message: str) -> None:
    with pytest.raises(InputError, match=message):
        function(*args, **kwargs)


def test_every_public_function_has_a_bad_input_case() -> None:
    covered = {function.__name__ for function, *_ in BAD_INPUT}
    functions = {
        name
        for name in pj.__all__
        if callable(getattr(pj, name)) and name not in {"Kind", "Method"}
    }
    assert functions <= covered, functions - covered
