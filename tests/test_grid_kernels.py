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
  S_d = |p_u|_i |p_v|_k + |p_u|_k |p_v|_i in absolute-value evaluations |p_u| = Σ |dwu_i| |P_ij|
  |wv_j| (and likewise |p_v|). Normalising turns an absolute error δ of c into ≤ 2 δ / |c| in
  direction, plus ≤ 4 eps for the two normalisations: tolerance 96 eps |S| / |c| + 4 eps.

The compiled kernels (``compiled=True``) compute the same 16-term sums, u first, then v (each term
≤ 8 roundings, as above), and c as the cross product of the evaluated tangents (≤ 8 + 2 roundings
a term, fewer than the 24 above); their normalisation is the reference's. So the same tolerances
hold for them against the einsum reference, and between them and the NumPy reference
(``compiled=False``): 16 eps · A for values, 96 eps |S| / |c| + 4 eps for unit normals. Both are
run on every test below that takes ``compiled``.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from g1patch import _grid, kernels
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
    """Random nets at different scales (10^-3 .. 10^3), so that the tolerances are tested as
    relative."""
    rng = np.random.default_rng(seed)
    scale = 10.0 ** rng.integers(-3, 4, size=(n, 1, 1, 1))
    return rng.uniform(-1.0, 1.0, size=(n, 4, 4, 3)) * scale


def parameters(count, seed):
    """Sorted parameters in [0, 1] including both ends, with random interior spacing."""
    rng = np.random.default_rng(seed)
    return np.sort(np.concatenate([[0.0, 1.0], rng.uniform(0.0, 1.0, size=count - 2)]))


COMPILED = pytest.mark.parametrize("compiled", [False, True], ids=["numpy", "compiled"])


@pytest.fixture
def block_points(request, monkeypatch):
    monkeypatch.setattr(_grid, "BLOCK_POINTS", request.param)
    return request.param


def normal_tolerance(control, form, u, v):
    wu, dwu = basis_values(form, u), basis_values(form, u, 1)
    wv, dwv = basis_values(form, v), basis_values(form, v, 1)
    p_u, p_v = reference_contract(control, dwu, wv), reference_contract(control, wu, dwv)
    a_u, a_v = abs_contract(control, dwu, wv), abs_contract(control, wu, dwv)
    s = np.stack(
        [
            a_u[..., i] * a_v[..., k] + a_u[..., k] * a_v[..., i]
            for i, k in ((1, 2), (2, 0), (0, 1))
        ],
        -1,
    )
    c = np.cross(p_u, p_v)
    with np.errstate(divide="ignore", invalid="ignore"):
        tol = 96 * EPS * np.linalg.norm(s, axis=-1) / np.linalg.norm(c, axis=-1) + 4 * EPS
    return reference_unit(c), tol


# ----------------------------------------------------------------------------------- values
@COMPILED
@pytest.mark.parametrize("block_points", BLOCKS, indirect=True)
@pytest.mark.parametrize("form", FORMS)
@pytest.mark.parametrize("du", [0, 1, 2])
@pytest.mark.parametrize("dv", [0, 1, 2])
def test_contract_matches_einsum(block_points, form, du, dv, compiled):
    control = make_control(37, seed=du + 3 * dv)  # 37: not a multiple of any block
    u, v = parameters(9, 1), parameters(14, 2)  # Gu ≠ Gv
    wu, wv = basis_values(form, u, du), basis_values(form, v, dv)
    got = _grid.contract(control, wu, wv, compiled=compiled)
    assert got.shape == (37, 9, 14, 3) and got.dtype == np.float64 and got.flags.c_contiguous
    err = np.abs(got - reference_contract(control, wu, wv))
    assert np.all(err <= 16 * EPS * abs_contract(control, wu, wv))


@COMPILED
@pytest.mark.parametrize("block_points", BLOCKS, indirect=True)
@pytest.mark.parametrize("form", FORMS)
def test_single_patch_and_wide_grids(block_points, form, compiled):
    control = make_control(1, seed=5)
    for u, v in (
        (parameters(2, 3), parameters(31, 4)),
        (parameters(23, 5), parameters(3, 6)),
        (np.array([0.25]), np.array([0.5])),
    ):
        wu, wv = basis_values(form, u, 1), basis_values(form, v)
        got = _grid.contract(control, wu, wv, compiled=compiled)
        assert got.shape == (1, u.size, v.size, 3)
        assert np.all(
            np.abs(got - reference_contract(control, wu, wv))
            <= 16 * EPS * abs_contract(control, wu, wv)
        )


@COMPILED
def test_large_grid_uses_row_blocks_and_matches(compiled):
    """One patch on a 200 × 150 grid: more points than a block, so the rows are split inside the
    patch."""
    assert 200 * 150 > _grid.BLOCK_POINTS
    control = make_control(2, seed=9)
    u, v = np.linspace(0.0, 1.0, 200), np.linspace(0.0, 1.0, 150)
    wu, wv = basis_values("bezier", u), basis_values("bezier", v)
    got = _grid.contract(control, wu, wv, compiled=compiled)
    assert np.all(
        np.abs(got - reference_contract(control, wu, wv))
        <= 16 * EPS * abs_contract(control, wu, wv)
    )
    normals = _grid.normals(control, "bezier", u, v, compiled=compiled)
    expected, tol = normal_tolerance(control, "bezier", u, v)
    assert np.all(np.linalg.norm(normals - expected, axis=-1) <= tol)


@COMPILED
def test_out_is_filled_in_place_and_checked(compiled):
    control = make_control(3)
    wu = wv = basis_values("bezier", np.linspace(0.0, 1.0, 4))
    out = np.full((3, 4, 4, 3), np.nan)
    assert _grid.contract(control, wu, wv, out=out, compiled=compiled) is out
    assert np.all(
        np.abs(out - reference_contract(control, wu, wv))
        <= 16 * EPS * abs_contract(control, wu, wv)
    )
    with pytest.raises(
        InputError, match=r"^out: expected a C-contiguous float64 array of shape \(3, 4, 4, 3\)"
    ):
        _grid.contract(control, wu, wv, out=np.empty((3, 4, 3, 3)))
    with pytest.raises(InputError, match="^out: "):
        _grid.contract(control, wu, wv, out=np.empty((3, 4, 4, 3))[::-1])
    with pytest.raises(InputError, match="^normals_out: "):
        _grid.positions_and_normals(
            control,
            "bezier",
            np.zeros(4),
            np.zeros(4),
            normals_out=np.empty((3, 4, 4, 3), np.float32),
        )


@COMPILED
def test_empty_batches_and_grids(compiled):
    wu = basis_values("bezier", np.linspace(0.0, 1.0, 5))
    assert _grid.contract(np.zeros((0, 4, 4, 3)), wu, wu, compiled=compiled).shape == (0, 5, 5, 3)
    positions, normals = _grid.positions_and_normals(
        make_control(2), "hermite", np.zeros(0), np.linspace(0, 1, 3), compiled=compiled
    )
    assert positions.shape == normals.shape == (2, 0, 3, 3)


# ---------------------------------------------------------------------------------- normals
@COMPILED
@pytest.mark.parametrize("block_points", BLOCKS, indirect=True)
@pytest.mark.parametrize("form", FORMS)
def test_normals_match_unit_cross(block_points, form, compiled):
    control = make_control(23, seed=11)
    u, v = parameters(11, 7), parameters(6, 8)
    got = _grid.normals(control, form, u, v, compiled=compiled)
    assert got.shape == (23, 11, 6, 3) and got.flags.c_contiguous
    expected, tol = normal_tolerance(control, form, u, v)
    assert np.all(np.linalg.norm(got - expected, axis=-1) <= tol)
    np.testing.assert_allclose(np.linalg.norm(got, axis=-1), 1.0, rtol=0, atol=4 * EPS)


@COMPILED
@pytest.mark.parametrize("block_points", BLOCKS, indirect=True)
@pytest.mark.parametrize("form", FORMS)
def test_positions_and_normals_equal_the_separate_kernels(block_points, form, compiled):
    control = make_control(19, seed=12)
    u, v = parameters(7, 9), parameters(12, 10)
    positions, normals = _grid.positions_and_normals(control, form, u, v, compiled=compiled)
    wu, wv = basis_values(form, u), basis_values(form, v)
    np.testing.assert_array_equal(positions, _grid.contract(control, wu, wv, compiled=compiled))
    np.testing.assert_array_equal(normals, _grid.normals(control, form, u, v, compiled=compiled))


@COMPILED
@pytest.mark.parametrize("block_points", BLOCKS, indirect=True)
@pytest.mark.parametrize("form", ["bezier", "hermite"])
def test_collapsed_edge_gives_zero_normals_not_nan(block_points, form, compiled):
    """u = 0 edge collapsed to the origin: p_v(0, v) = 0 exactly, so the normal there is exactly
    zero.

    In Bézier form the edge is the control row i = 0; in Hermite form it is the rows i = 0
    (positions and v-derivatives along u = 0), so zeroing them collapses the edge exactly in both.
    """
    control = make_control(5, seed=13)
    control[:, 0] = 0.0
    control[2] = 0.0  # a patch collapsed to a single point: every normal is zero
    u, v = np.linspace(0.0, 1.0, 9), parameters(10, 14)
    positions, normals = _grid.positions_and_normals(control, form, u, v, compiled=compiled)
    assert np.isfinite(normals).all() and np.isfinite(positions).all()
    np.testing.assert_array_equal(normals[:, 0], 0.0)
    np.testing.assert_array_equal(normals[2], 0.0)
    alive = np.ones(5, bool)
    alive[2] = False
    np.testing.assert_allclose(
        np.linalg.norm(normals[alive, 1:], axis=-1), 1.0, rtol=0, atol=4 * EPS
    )
    expected, tol = normal_tolerance(control, form, u, v)
    live = np.isfinite(tol)
    assert np.all(np.linalg.norm(normals - expected, axis=-1)[live] <= tol[live])


@COMPILED
def test_point_patch_away_from_origin_is_finite(compiled):
    """Collapsed to a point that is not the origin, p_u and p_v are rounding noise: finite, never
    NaN."""
    control = np.broadcast_to(np.array([0.3, -1.7, 2.9]), (2, 4, 4, 3)).copy()
    for form in FORMS:
        _, normals = _grid.positions_and_normals(
            control, form, np.linspace(0.0, 1.0, 17), np.linspace(0.0, 1.0, 5), compiled=compiled
        )
        assert np.isfinite(normals).all()
        length = np.linalg.norm(normals, axis=-1)
        assert np.all(length <= 1.0 + 4 * EPS)


# ------------------------------------------------------------ compiled against the reference
@settings(max_examples=40, deadline=None)
@given(
    count=st.integers(1, 9),
    gu=st.integers(1, 40),
    gv=st.integers(1, 40),
    form=st.sampled_from(FORMS),
    seed=st.integers(0, 2**32 - 1),
)
def test_compiled_kernels_match_the_numpy_reference(count, gu, gv, form, seed):
    """The compiled kernels against ``compiled=False`` within the ULP bounds of the module
    docstring: 16 eps · A for positions, 96 eps |S| / |c| + 4 eps for unit normals (any sizes: odd
    row lengths leave a scalar tail after the vectorised part of each row)."""
    control = make_control(count, seed=seed % 1000)
    u, v = parameters(max(gu, 2), seed % 997)[:gu], parameters(max(gv, 2), seed % 991)[:gv]
    positions, normals = _grid.positions_and_normals(control, form, u, v, compiled=True)
    ref_positions, ref_normals = _grid.positions_and_normals(control, form, u, v, compiled=False)
    wu, wv = basis_values(form, u), basis_values(form, v)
    assert np.all(np.abs(positions - ref_positions) <= 16 * EPS * abs_contract(control, wu, wv))
    _, tol = normal_tolerance(control, form, u, v)
    assert np.all(np.linalg.norm(normals - ref_normals, axis=-1) <= tol)


def test_compiled_ranges_cover_every_patch(monkeypatch):
    """Split over several ranges per worker (more than the patches of a short batch): every patch
    written, by exactly one range, so the result equals one range over all of them bit for bit."""
    from g1patch import kernels

    control = make_control(7, seed=21)
    u, v = parameters(13, 22), parameters(17, 23)
    monkeypatch.setattr(kernels, "workers", lambda: 1)
    one = _grid.positions_and_normals(control, "bezier", u, v, compiled=True)
    for workers in (2, 3, 8):
        monkeypatch.setattr(kernels, "workers", lambda workers=workers: workers)
        split = _grid.positions_and_normals(control, "bezier", u, v, compiled=True)
        np.testing.assert_array_equal(split[0], one[0])
        np.testing.assert_array_equal(split[1], one[1])


def test_patchset_uses_the_compiled_kernels_from_the_threshold(monkeypatch):
    """``compiled=None`` (what PatchSet calls): the kernels from KERNEL_POINTS grid points on, the
    reference below; frames still applied afterwards."""
    patches = PatchSet(make_control(4, seed=24), "hermite")
    u = parameters(9, 25)
    below = patches.evaluate_grid_with_normals(u), patches.evaluate_grid(u, u, 1, 0)
    monkeypatch.setattr(_grid, "KERNEL_POINTS", 4 * 9 * 9)
    monkeypatch.setattr(kernels, "kernels_cached", lambda: True)  # NumPy where it is not
    calls = []
    real = _grid._compiled
    monkeypatch.setattr(
        _grid, "_compiled", lambda kernel: calls.append(kernel.__name__) or real(kernel)
    )
    above = patches.evaluate_grid_with_normals(u), patches.evaluate_grid(u, u, 1, 0)
    assert calls == ["_normals_kernel", "_contract_kernel"]
    wu, dwu = basis_values("hermite", u), basis_values("hermite", u, 1)
    assert np.all(
        np.abs(above[0][0] - below[0][0]) <= 16 * EPS * abs_contract(patches.control, wu, wu)
    )
    assert np.all(np.abs(above[1] - below[1]) <= 16 * EPS * abs_contract(patches.control, dwu, wu))
    _, tol = normal_tolerance(patches.control, "hermite", u, u)
    assert np.all(np.linalg.norm(above[0][1] - below[0][1], axis=-1) <= tol)


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
