"""Basis families: sizes, scipy agreement, orthonormality, grids."""

import numpy as np
import pytest

from rplearn.core.bases import BasisGrid, Polynomial, SphericalHarmonics, basis_from_dict, make_basis, total_degree_exponents
from rplearn.core.geometry import great_circle_angle
from rplearn.core.sh import real_sh_reference, sh_index
from rplearn.errors import InputError, ModelFileError


def _random_directions(n, seed=0):
    rng = np.random.default_rng(seed)
    return rng.uniform(-np.pi, np.pi, n), np.arcsin(rng.uniform(-1, 1, n))


def test_model_sizes_match_the_paper():
    assert make_basis("sh", 10).n_coef == 100
    assert make_basis("poly", 12).n_coef == 91
    assert make_basis("bg", 7).n_coef == 98


@pytest.mark.parametrize("order", [1, 2, 5, 12])
def test_real_sh_match_scipy_sph_harm_y(order):
    az, el = _random_directions(500)
    az = np.concatenate([az, [0.0, np.pi, 1.0, -2.0]])
    el = np.concatenate([el, [np.pi / 2, -np.pi / 2, 0.0, 1e-9]])
    got = SphericalHarmonics(order).design(az, el)
    ref = real_sh_reference(order, az, el)  # scipy.special.sph_harm_y per (l, m)
    for l in range(order):
        for m in range(-l, l + 1):
            np.testing.assert_allclose(
                got[:, sh_index(l, m)], ref[:, sh_index(l, m)], atol=1e-12, err_msg=f"l={l} m={m}"
            )


def test_sh_are_orthonormal_over_the_sphere():
    b = SphericalHarmonics(8)
    x, w = np.polynomial.legendre.leggauss(40)
    az = -np.pi + (np.arange(80) + 0.5) * 2 * np.pi / 80
    A, X = np.meshgrid(az, x)
    W = np.repeat(w, 80) * (2 * np.pi / 80)
    F = b.design(A.ravel(), np.arcsin(X.ravel()))
    np.testing.assert_allclose(F.T @ (F * W[:, None]), np.eye(64), atol=1e-12)


def test_sphere_means():
    from rplearn.core.bases import Basis

    sh = SphericalHarmonics(5)
    quadrature = Basis.sphere_mean.func(sh)  # the generic rule the other bases use
    np.testing.assert_allclose(quadrature, sh.sphere_mean, atol=1e-13)
    np.testing.assert_allclose(sh.sphere_mean[0], 1 / np.sqrt(4 * np.pi))
    # the polynomial constant has mean 1; el^1 has mean 0 over the sphere (odd)
    p = Polynomial(2)
    np.testing.assert_allclose(p.sphere_mean[0], 1.0, atol=1e-12)
    np.testing.assert_allclose(p.sphere_mean[2], 0.0, atol=1e-12)


def test_bg_kernel_is_the_papers_form():
    b = BasisGrid(4, sigma_rad2=0.3)
    az, el = _random_directions(50, 2)
    naz, nel = b.nodes_rad
    theta = great_circle_angle(az[:, None], el[:, None], naz[None, :], nel[None, :])
    np.testing.assert_allclose(b.design(az, el), np.exp(-theta**2 / (2 * 0.3)), atol=1e-7)


def test_bg_grids():
    paper = BasisGrid(7)
    naz, nel = paper.nodes_rad
    assert naz.size == 98 and len(np.unique(np.round(nel, 9))) == 7 and len(np.unique(np.round(naz, 9))) == 14
    fib = BasisGrid(7, grid="fibonacci")
    faz, fel = fib.nodes_rad
    assert faz.size == 98
    # equal area: about the same number of nodes in the polar caps and in equal-area bands
    cap = np.sum(np.sin(fel) > 0.5)
    assert abs(cap - 98 / 4) <= 2
    # the paper's grid over-represents the poles: above 60 deg (6.7 % of the sphere's area)
    polar_share = (1 - np.sin(np.radians(60))) / 2
    assert abs(np.sum(fel > np.radians(60)) - 98 * polar_share) <= 2
    assert np.sum(nel > np.radians(60)) >= 2 * 98 * polar_share


def test_polynomial_spans_the_monomials():
    az, el = _random_directions(400, 3)
    leg = Polynomial(6).design(az, el)
    mono = Polynomial(6, polynomial="monomial").design(az, el)
    lit = np.column_stack([az**i * el**j for i, j in total_degree_exponents(6)])
    for basis in (leg, mono):
        coef, *_ = np.linalg.lstsq(basis, lit, rcond=None)
        np.testing.assert_allclose(basis @ coef, lit, atol=1e-8 * np.abs(lit).max())
    assert np.linalg.cond(leg) < np.linalg.cond(mono)


def test_specs_round_trip_and_bad_specs():
    for b in (SphericalHarmonics(4), BasisGrid(3, 0.2, "fibonacci"), Polynomial(5, "monomial")):
        assert basis_from_dict(b.to_dict()) == b
    with pytest.raises(InputError, match="unknown basis"):
        make_basis("zernike", 3)
    with pytest.raises(InputError):
        make_basis("sh", 0)
    with pytest.raises(ModelFileError):
        basis_from_dict({"kind": "bg", "order": 3, "sigma_rad2": -1})


def test_half_angle_cos_sin_is_exact_to_rounding():
    from rplearn.core.basis_base import cos_sin_half_angle

    rng = np.random.default_rng(3)
    special = np.pi / 2 * np.arange(-8, 9)
    a = np.concatenate([rng.uniform(-20, 20, 200_000), special, special + 1e-12, [0.0, -0.0, 1e-300]])
    cos, sin = cos_sin_half_angle(a)
    np.testing.assert_allclose(cos, np.cos(a), rtol=0, atol=1e-15)
    np.testing.assert_allclose(sin, np.sin(a), rtol=0, atol=1e-15)


@pytest.mark.parametrize("order", [20, 40])
def test_high_order_sh_stay_accurate(order):
    az, el = _random_directions(300, seed=order)
    got = SphericalHarmonics(order).design(az, el)
    ref = real_sh_reference(order, az, el)
    assert np.abs(got - ref).max() < 1e-12 * order


def test_row_order_is_a_permutation_of_the_natural_columns():
    b = SphericalHarmonics(7)
    az, el = _random_directions(50)
    rows = np.empty((b.n_coef, 50))
    b.design_rows_into(az, el, rows)
    assert sorted(b.row_order) == list(range(b.n_coef))
    np.testing.assert_array_equal(rows, b.design_t(az, el)[b.row_order])
    for other in (BasisGrid(3), Polynomial(4)):
        assert other.row_order is None and other.moment_shape is None
        with pytest.raises(TypeError, match="no Gram moments"):
            other.gram_from_moments(np.zeros((3, 3)))


@pytest.mark.parametrize("order", [1, 2, 3, 6, 10, 15])
def test_gram_from_moments_equals_the_feature_gram(order):
    """The moments give F F^T exactly (up to rounding), for 1-D and stacked (2, n) samples."""
    b = SphericalHarmonics(order)
    rng = np.random.default_rng(order)
    az = rng.uniform(-np.pi, np.pi, (2, 1500))
    el = np.arcsin(rng.uniform(-1, 1, (2, 1500)))
    el[0, :5] = [np.pi / 2, -np.pi / 2, 0.0, 1e-9, np.pi / 2 - 1e-9]  # poles and the equator
    rows = np.empty((b.n_coef, 2, 1500))
    moments = np.zeros((2, *b.moment_shape))
    b.design_rows_into(az[:, :700], el[:, :700], rows[:, :, :700], moments)  # accumulates
    b.design_rows_into(az[:, 700:], el[:, 700:], rows[:, :, 700:], moments)
    for end in range(2):
        gram = rows[:, end] @ rows[:, end].T
        np.testing.assert_allclose(b.gram_from_moments(moments[end]), gram, rtol=0, atol=1e-13 * np.abs(gram).max())
    one = np.zeros(b.moment_shape)
    flat = np.empty((b.n_coef, 1500))
    b.design_rows_into(az[1], el[1], flat, one)
    np.testing.assert_allclose(one, moments[1], rtol=1e-12, atol=1e-9)


@pytest.mark.parametrize("order", [1, 2, 5, 10, 15])
def test_feature_sums_from_moments_equal_the_summed_rows(order):
    """``F 1`` from the moments (the per-block sums of the drifting error's estimate, with no pass
    of their own), per range of samples too, poles included."""
    b = SphericalHarmonics(order)
    rng = np.random.default_rng(10 + order)
    az = rng.uniform(-np.pi, np.pi, (2, 900))
    el = np.arcsin(rng.uniform(-1, 1, (2, 900)))
    el[0, :3] = [np.pi / 2, -np.pi / 2, 0.0]
    rows = np.empty((b.n_coef, 2, 900))
    bounds = np.array([0, 250, 251, 900])
    moments = (np.zeros((3, *b.moment_shape)), np.zeros((3, *b.moment_shape)))
    b.design_rows_into(az, el, rows, moments, (bounds, bounds))
    for end in range(2):
        sums = b.sums_from_moments(moments[end])
        for j in range(3):
            want = rows[:, end, bounds[j]:bounds[j + 1]].sum(axis=1)
            np.testing.assert_allclose(sums[j], want, rtol=0, atol=1e-12 * max(1.0, np.abs(want).max()))


def test_very_high_sh_orders_fall_back_to_the_plain_gram():
    from rplearn.core.sh import SH_MOMENTS_MAX_ORDER

    assert SphericalHarmonics(SH_MOMENTS_MAX_ORDER).moment_shape is not None
    high = SphericalHarmonics(SH_MOMENTS_MAX_ORDER + 1)
    assert high.moment_shape is None
    with pytest.raises(TypeError, match="no Gram moments"):
        high.gram_from_moments(np.zeros((3, 3)))
    with pytest.raises(TypeError, match="no Gram moments"):
        high.sums_from_moments(np.zeros((3, 3)))


def test_shared_sh_tables_cannot_be_corrupted_by_a_caller():
    order = SphericalHarmonics(3).row_order
    with pytest.raises(ValueError):
        order[0] = 5
    np.testing.assert_array_equal(sorted(SphericalHarmonics(3).row_order), np.arange(9))


def test_chunked_evaluation_equals_the_design_matrix(monkeypatch):
    import rplearn.core.basis_base as bases_module

    monkeypatch.setattr(bases_module, "EVAL_CHUNK", 300)  # several chunks and a partial one
    az, el = _random_directions(2000, seed=5)
    rng = np.random.default_rng(5)
    for b in (SphericalHarmonics(6), BasisGrid(3, 0.3), Polynomial(4)):
        F = b.design(az, el)
        np.testing.assert_allclose(F, real_sh_reference(6, az, el) if b.kind == "sh" else F, atol=1e-13)
        coef = rng.normal(size=(3, b.n_coef))
        np.testing.assert_allclose(b.evaluate(coef, az, el), coef @ F.T, atol=1e-12)
        np.testing.assert_allclose(b.evaluate(coef[0], az, el), F @ coef[0], atol=1e-12)
        m = rng.normal(size=(b.n_coef, b.n_coef))
        np.testing.assert_allclose(b.quadratic_form(m, az, el), np.einsum("ni,ij,nj->n", F, m, F), atol=1e-10)
    with pytest.raises(InputError, match="coefficients"):
        SphericalHarmonics(3).evaluate(np.zeros(8), az, el)


@pytest.mark.parametrize("order", [1, 2, 7, 24, 50])
def test_the_numpy_legendre_recurrence_equals_scipy_at_azimuth_zero(order):
    """The SH tables are built without scipy.special (issue 13, item 4): same values as it gives."""
    from rplearn.core.sh import legendre_factors, real_sh_reference

    x = np.concatenate([[-1.0, 1.0], np.random.default_rng(order).uniform(-1, 1, 40)])
    ours = legendre_factors(order, x)
    ref = real_sh_reference(order, np.zeros(x.size), np.arcsin(x))
    assert np.max(np.abs(ours - ref)) < 1e-13 * max(1.0, np.max(np.abs(ref)))
