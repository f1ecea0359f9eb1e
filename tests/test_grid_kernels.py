"""The fast grid kernels (g1patch._grid) against a straightforward einsum reference.

Tolerances are ULP-scaled forward-error bounds, per entry:

* Values and derivatives. Both the kernel and the reference compute the same 16-term sum
  ``Σ_ij wu_i P_ij wv_j``, only associated differently. Along any path a term meets at most 8
  roundings (2 products, 3 + 3 additions), so each result is within γ_8 · A of the exact value,
  with ``A = Σ_ij |wu_i| |P_ij| |wv_j|`` (Higham, Accuracy and Stability, §3.1), and the two are
  within 2 γ_8 A ≤ 16 eps · A of each other.
* Normals. The kernel forms c = p_u × p_v along each grid row as Σ_jk C_jk wv_j dwv_k with
  C_jk = pu_i[j] pv_k[k] − pu_k[j] pv_i[k] from the u-contracted rows; the reference takes the
  cross product of the evaluated p_u, p_v. Either way a term of component d meets at most
  4 (u-contraction) + 3 (product, difference) + 1 (basis product) + 16 (sum over j, k) = 24
  roundings, and expands to the same terms, so |c_kernel − c_ref| ≤ 2 γ_24 |S| ≤ 48 eps |S| with
  S_d = |p_u|_i |p_v|_k + |p_u|_k |p_v|_i in absolute-value evaluations |p_u| = Σ |dwu_i| |P_ij| |wv_j|
  (and likewise |p_v|). Normalising turns an absolute error δ of c into ≤ 2 δ / |c| in direction,
  plus ≤ 4 eps for the two normalisations: tolerance 96 eps |S| / |c| + 4 eps.
"""

from __future__ import annotations

import numpy as np
import pytest

from g1patch import _grid
from g1patch.basis import FORMS, basis_values
from g1patch.errors import InputError
from g1patch.patches import PatchSet

EPS = np.finfo(np.float64).eps

#: block sizes: the default (whole patches per block), a few patches per block (a partial last
#: block when N is not a multiple), and less than one patch (row sub-blocks inside a patch grid)
BLOCKS = [_grid.BLOCK_POINTS, 300, 60]


def reference_contract(control, wu, wv):
    return np.einsum("ai,nijd,bj->nabd", wu, control, wv)


def abs_contract(control, wu, wv):
    return np.einsum("ai,nijd,bj->nabd", np.abs(wu), np.abs(control), np.abs(wv))


def reference_unit(vectors):
    length = np.sqrt(np.sum(vectors * vectors, axis=-1, keepdims=True))
    return np.divide(vectors, length, out=np.zeros_like(vectors), where=length > 0)


def make_control(n, seed=0):
    """Random nets at different scales (10^-3 .. 10^3), so that the tolerances are tested as relative."""
    rng = np.random.default_rng(seed)
    scale = 10.0 ** rng.integers(-3, 4, size=(n, 1, 1, 1))
    return rng.uniform(-1.0, 1.0, size=(n, 4, 4, 3)) * scale


def parameters(count, seed):
    """Sorted parameters in [0, 1] including both ends, with random interior spacing."""
    rng = np.random.default_rng(seed)
    return np.sort(np.concatenate([[0.0, 1.0], rng.uniform(0.0, 1.0, size=count - 2)]))


@pytest.fixture
def block_points(request, monkeypatch):
    monkeypatch.setattr(_grid, "BLOCK_POINTS", request.param)
    return request.param


def normal_tolerance(control, form, u, v):
    wu, dwu = basis_values(form, u), basis_values(form, u, 1)
    wv, dwv = basis_values(form, v), basis_values(form, v, 1)
    p_u, p_v = reference_contract(control, dwu, wv), reference_contract(control, wu, dwv)
    a_u, a_v = abs_contract(control, dwu, wv), abs_contract(control, wu, dwv)
    s = np.stack([a_u[..., i] * a_v[..., k] + a_u[..., k] * a_v[..., i] for i, k in ((1, 2), (2, 0), (0, 1))], -1)
    c = np.cross(p_u, p_v)
    with np.errstate(divide="ignore", invalid="ignore"):
        tol = 96 * EPS * np.linalg.norm(s, axis=-1) / np.linalg.norm(c, axis=-1) + 4 * EPS
    return reference_unit(c), tol


# ----------------------------------------------------------------------------------- values
@pytest.mark.parametrize("block_points", BLOCKS, indirect=True)
@pytest.mark.parametrize("form", FORMS)
@pytest.mark.parametrize("du", [0, 1, 2])
@pytest.mark.parametrize("dv", [0, 1, 2])
def test_contract_matches_einsum(block_points, form, du, dv):
    control = make_control(37, seed=du + 3 * dv)  # 37: not a multiple of any block
    u, v = parameters(9, 1), parameters(14, 2)  # Gu ≠ Gv
    wu, wv = basis_values(form, u, du), basis_values(form, v, dv)
    got = _grid.contract(control, wu, wv)
    assert got.shape == (37, 9, 14, 3) and got.dtype == np.float64 and got.flags.c_contiguous
    err = np.abs(got - reference_contract(control, wu, wv))
    assert np.all(err <= 16 * EPS * abs_contract(control, wu, wv))


@pytest.mark.parametrize("block_points", BLOCKS, indirect=True)
@pytest.mark.parametrize("form", FORMS)
def test_single_patch_and_wide_grids(block_points, form):
    control = make_control(1, seed=5)
    for u, v in ((parameters(2, 3), parameters(31, 4)), (parameters(23, 5), parameters(3, 6)), (np.array([0.25]), np.array([0.5]))):
        wu, wv = basis_values(form, u, 1), basis_values(form, v)
        got = _grid.contract(control, wu, wv)
        assert got.shape == (1, u.size, v.size, 3)
        assert np.all(np.abs(got - reference_contract(control, wu, wv)) <= 16 * EPS * abs_contract(control, wu, wv))


def test_large_grid_uses_row_blocks_and_matches():
    """One patch on a 200 × 150 grid: more points than a block, so the rows are split inside the patch."""
    assert 200 * 150 > _grid.BLOCK_POINTS
    control = make_control(2, seed=9)
    u, v = np.linspace(0.0, 1.0, 200), np.linspace(0.0, 1.0, 150)
    wu, wv = basis_values("bezier", u), basis_values("bezier", v)
    got = _grid.contract(control, wu, wv)
    assert np.all(np.abs(got - reference_contract(control, wu, wv)) <= 16 * EPS * abs_contract(control, wu, wv))
    normals = _grid.normals(control, "bezier", u, v)
    expected, tol = normal_tolerance(control, "bezier", u, v)
    assert np.all(np.linalg.norm(normals - expected, axis=-1) <= tol)


def test_out_is_filled_in_place_and_checked():
    control = make_control(3)
    wu = wv = basis_values("bezier", np.linspace(0.0, 1.0, 4))
    out = np.full((3, 4, 4, 3), np.nan)
    assert _grid.contract(control, wu, wv, out=out) is out
    assert np.all(np.abs(out - reference_contract(control, wu, wv)) <= 16 * EPS * abs_contract(control, wu, wv))
    with pytest.raises(InputError, match=r"^out: expected a C-contiguous float64 array of shape \(3, 4, 4, 3\)"):
        _grid.contract(control, wu, wv, out=np.empty((3, 4, 3, 3)))
    with pytest.raises(InputError, match="^out: "):
        _grid.contract(control, wu, wv, out=np.empty((3, 4, 4, 3))[::-1])
    with pytest.raises(InputError, match="^normals_out: "):
        _grid.positions_and_normals(control, "bezier", np.zeros(4), np.zeros(4), normals_out=np.empty((3, 4, 4, 3), np.float32))


def test_empty_batches_and_grids():
    wu = basis_values("bezier", np.linspace(0.0, 1.0, 5))
    assert _grid.contract(np.zeros((0, 4, 4, 3)), wu, wu).shape == (0, 5, 5, 3)
    positions, normals = _grid.positions_and_normals(make_control(2), "hermite", np.zeros(0), np.linspace(0, 1, 3))
    assert positions.shape == normals.shape == (2, 0, 3, 3)


# ---------------------------------------------------------------------------------- normals
@pytest.mark.parametrize("block_points", BLOCKS, indirect=True)
@pytest.mark.parametrize("form", FORMS)
def test_normals_match_unit_cross(block_points, form):
    control = make_control(23, seed=11)
    u, v = parameters(11, 7), parameters(6, 8)
    got = _grid.normals(control, form, u, v)
    assert got.shape == (23, 11, 6, 3) and got.flags.c_contiguous
    expected, tol = normal_tolerance(control, form, u, v)
    assert np.all(np.linalg.norm(got - expected, axis=-1) <= tol)
    np.testing.assert_allclose(np.linalg.norm(got, axis=-1), 1.0, rtol=0, atol=4 * EPS)


@pytest.mark.parametrize("block_points", BLOCKS, indirect=True)
@pytest.mark.parametrize("form", FORMS)
def test_positions_and_normals_equal_the_separate_kernels(block_points, form):
    control = make_control(19, seed=12)
    u, v = parameters(7, 9), parameters(12, 10)
    positions, normals = _grid.positions_and_normals(control, form, u, v)
    np.testing.assert_array_equal(positions, _grid.contract(control, basis_values(form, u), basis_values(form, v)))
    np.testing.assert_array_equal(normals, _grid.normals(control, form, u, v))


@pytest.mark.parametrize("block_points", BLOCKS, indirect=True)
@pytest.mark.parametrize("form", ["bezier", "hermite"])
def test_collapsed_edge_gives_zero_normals_not_nan(block_points, form):
    """u = 0 edge collapsed to the origin: p_v(0, v) = 0 exactly, so the normal there is exactly zero.

    In Bézier form the edge is the control row i = 0; in Hermite form it is the rows i = 0 (positions and
    v-derivatives along u = 0), so zeroing them collapses the edge exactly in both.
    """
    control = make_control(5, seed=13)
    control[:, 0] = 0.0
    control[2] = 0.0  # a patch collapsed to a single point: every normal is zero
    u, v = np.linspace(0.0, 1.0, 9), parameters(10, 14)
    positions, normals = _grid.positions_and_normals(control, form, u, v)
    assert np.isfinite(normals).all() and np.isfinite(positions).all()
    np.testing.assert_array_equal(normals[:, 0], 0.0)
    np.testing.assert_array_equal(normals[2], 0.0)
    alive = np.ones(5, bool)
    alive[2] = False
    np.testing.assert_allclose(np.linalg.norm(normals[alive, 1:], axis=-1), 1.0, rtol=0, atol=4 * EPS)
    expected, tol = normal_tolerance(control, form, u, v)
    live = np.isfinite(tol)
    assert np.all(np.linalg.norm(normals - expected, axis=-1)[live] <= tol[live])


def test_point_patch_away_from_origin_is_finite():
    """Collapsed to a point that is not the origin, p_u and p_v are rounding noise: finite, never NaN."""
    control = np.broadcast_to(np.array([0.3, -1.7, 2.9]), (2, 4, 4, 3)).copy()
    for form in FORMS:
        _, normals = _grid.positions_and_normals(control, form, np.linspace(0.0, 1.0, 17), np.linspace(0.0, 1.0, 5))
        assert np.isfinite(normals).all()
        length = np.linalg.norm(normals, axis=-1)
        assert np.all(length <= 1.0 + 4 * EPS)


# ---------------------------------------------------------------------------- PatchSet API
def test_patchset_methods_use_the_kernels():
    patches = PatchSet(make_control(6, seed=15), "bspline")
    u, v = parameters(8, 16), parameters(5, 17)
    positions, normals = patches.evaluate_grid_with_normals(u, v)
    np.testing.assert_array_equal(positions, patches.evaluate_grid(u, v))
    np.testing.assert_array_equal(normals, patches.normals_grid(u, v))
    square_positions, square_normals = patches.evaluate_grid_with_normals(u)
    np.testing.assert_array_equal(square_positions, patches.evaluate_grid(u, u))
    np.testing.assert_array_equal(square_normals, patches.normals_grid(u))
    assert positions.flags.c_contiguous and normals.flags.c_contiguous


def test_public_methods_write_into_given_arrays() -> None:
    rng = np.random.default_rng(11)
    patches = PatchSet(rng.normal(size=(5, 4, 4, 3)), "bezier")
    u = np.linspace(0.0, 1.0, 7)
    positions, normals = np.empty((5, 7, 7, 3)), np.empty((5, 7, 7, 3))
    returned = patches.evaluate_grid_with_normals(u, out=positions, normals_out=normals)
    assert returned[0] is positions and returned[1] is normals
    expected = patches.evaluate_grid_with_normals(u)
    np.testing.assert_array_equal(positions, expected[0])
    np.testing.assert_array_equal(normals, expected[1])
    assert patches.evaluate_grid(u, out=positions) is positions
    with pytest.raises(InputError, match="out"):
        patches.evaluate_grid(u, out=np.empty((5, 7, 6, 3)))
