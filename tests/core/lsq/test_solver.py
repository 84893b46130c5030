"""Joint solver: recovery, null space (paper Fig. 5), triangles (Fig. 6), streaming, errors."""

from __future__ import annotations

import numpy as np
import pytest

from rplearn.core.bases import BasisGrid, Polynomial, SphericalHarmonics
from rplearn.core.geometry import Directions
from rplearn.core.lsq.solver import JointFitOptions, NormalEquations, fit_joint, identifiability, link_components, solve
from rplearn.errors import IdentifiabilityError, InputError


def _dirs(rng, n):
    return rng.uniform(-np.pi, np.pi, n), np.arcsin(rng.uniform(-1, 1, n))


def _band_limited_patterns(rng, n_nodes, degree_max=6):
    b = SphericalHarmonics(degree_max + 1)
    coef = rng.normal(0, 1, (n_nodes, b.n_coef))
    degrees = np.floor(np.sqrt(np.arange(b.n_coef)))
    coef *= 4.0 / (1.0 + degrees)  # smooth, a few dB of structure
    coef[:, 0] += rng.uniform(-10, 10, n_nodes) * np.sqrt(4 * np.pi)  # distinct absolute levels
    return b, coef


def _simulate(rng, b, coef, pairs, n, noise_db):
    sel = pairs[rng.integers(0, len(pairs), n)]
    az_t, el_t = _dirs(rng, n)
    az_r, el_r = _dirs(rng, n)
    ft = b.design(az_t, el_t)
    fr = b.design(az_r, el_r)
    y = np.einsum("np,np->n", ft, coef[sel[:, 0]]) + np.einsum("np,np->n", fr, coef[sel[:, 1]])
    return Directions(az_t, el_t, az_r, el_r), sel[:, 0], sel[:, 1], y + rng.normal(0, noise_db, n) if noise_db else y


def _shape_rms_error(b, est, true, rng):
    az, el = _dirs(rng, 20000)
    e = b.design(az, el) @ (est - true)
    return float(np.sqrt(np.mean((e - e.mean()) ** 2)))


def _abs_rms_error(b, est, true, rng):
    az, el = _dirs(rng, 20000)
    e = b.design(az, el) @ (est - true)
    return float(np.sqrt(np.mean(e**2)))


@pytest.mark.parametrize("noise_db, tol_db", [(3.0, 0.3), (0.0, 1e-6)])
def test_two_node_recovery_of_shapes(noise_db, tol_db):
    rng = np.random.default_rng(10)
    b, true = _band_limited_patterns(rng, 2)
    d, tx, rx, y = _simulate(rng, b, true, np.array([[0, 1]]), 20000, noise_db)
    sol = fit_joint(d, tx, rx, y, 2, b, ["A", "B"], JointFitOptions(ridge=0.0 if noise_db == 0 else 1e-6))
    for k in range(2):
        err = _shape_rms_error(b, sol.coef[k], true[k], rng)
        assert err < tol_db, f"node {k}: {err} dB"
    # the joint level is identified even though the split is not
    assert abs(sol.coef[:, 0].sum() - true[:, 0].sum()) / np.sqrt(4 * np.pi) < max(10 * tol_db, 1e-6)
    assert sol.report.rank == sol.report.n_columns - 1 and sol.report.null_dim == 1
    assert sol.report.expected_null_dim == 1 and sol.report.decoupled
    assert "equal-mean" == sol.report.gauges[0].rule
    # the gauge holds exactly: both nodes have the same sphere-mean gain
    np.testing.assert_allclose(sol.coef[0, 0], sol.coef[1, 0], atol=1e-9)


@pytest.mark.parametrize("noise_db, tol_db", [(3.0, 0.3), (0.0, 1e-6)])
def test_triangle_recovers_absolute_patterns(noise_db, tol_db):
    rng = np.random.default_rng(11)
    b, true = _band_limited_patterns(rng, 3)
    pairs = np.array([[0, 1], [1, 2], [2, 0]])
    d, tx, rx, y = _simulate(rng, b, true, pairs, 30000, noise_db)
    sol = fit_joint(d, tx, rx, y, 3, b, ["A", "B", "C"], JointFitOptions(ridge=0.0 if noise_db == 0 else 1e-6))
    assert sol.report.rank == sol.report.n_columns == 147
    assert sol.report.gauges == ()
    for k in range(3):
        assert _abs_rms_error(b, sol.coef[k], true[k], rng) < tol_db


def test_null_space_epsilon_sweep_changes_no_prediction():
    rng = np.random.default_rng(12)
    b, true = _band_limited_patterns(rng, 2)
    d, tx, rx, y = _simulate(rng, b, true, np.array([[0, 1]]), 5000, 1.0)
    sol = fit_joint(d, tx, rx, y, 2, b, ["A", "B"])
    ft = b.design(d.az_tx, d.el_tx)
    fr = b.design(d.az_rx, d.el_rx)
    base = ft @ sol.coef[0] + fr @ sol.coef[1]
    for eps in [1e-3, 1.0, 25.0, 1e3, 1e5]:
        c = sol.coef.copy()
        c[0, 0] += eps
        c[1, 0] -= eps
        pred = ft @ c[0] + fr @ c[1]
        assert np.max(np.abs(pred - base)) <= 1e-9, eps


def test_even_cycle_leaves_one_constant_and_triangle_none():
    comps = link_components(4, [(0, 1), (1, 2), (2, 3), (3, 0)])
    assert comps == [([0, 1, 2, 3], [1, 3])]
    assert link_components(3, [(0, 1), (1, 2), (2, 0)]) == [([0, 1, 2], None)]
    rng = np.random.default_rng(13)
    b = SphericalHarmonics(3)
    pairs = np.array([[0, 1], [1, 2], [2, 3], [3, 0]])
    sel = pairs[rng.integers(0, 4, 4000)]
    d = Directions(*_dirs(rng, 4000), *_dirs(rng, 4000))
    rep = identifiability(d, sel[:, 0], sel[:, 1], 4, b, list("ABCD"))
    assert rep.null_dim == 1 == rep.expected_null_dim
    assert set(rep.gauges[0].side_a) == {"A", "C"} and set(rep.gauges[0].side_b) == {"B", "D"}


def test_fixed_node_gauge():
    rng = np.random.default_rng(14)
    b, true = _band_limited_patterns(rng, 2)
    d, tx, rx, y = _simulate(rng, b, true, np.array([[0, 1]]), 5000, 0.0)
    known = true[0, 0] / np.sqrt(4 * np.pi)
    sol = fit_joint(d, tx, rx, y, 2, b, ["A", "B"], JointFitOptions(ridge=0.0, gauge={"node": "A", "mean_gain_dbi": known}))
    np.testing.assert_allclose(sol.coef, true, atol=1e-8)  # absolute patterns once one level is known
    assert "fixed-mean:A" in sol.report.gauges[0].rule


def test_streaming_equals_one_shot_and_merge():
    rng = np.random.default_rng(15)
    b, true = _band_limited_patterns(rng, 2, 4)
    d, tx, rx, y = _simulate(rng, b, true, np.array([[0, 1], [1, 0]]), 9000, 2.0)
    one = fit_joint(d, tx, rx, y, 2, b, options=JointFitOptions(chunk_size=10**6))
    many = fit_joint(d, tx, rx, y, 2, b, options=JointFitOptions(chunk_size=977))
    np.testing.assert_allclose(many.coef, one.coef, atol=1e-9)
    a, c = NormalEquations(b, 2), NormalEquations(b, 2)
    a.add(Directions(*(x[:4000] for x in d)), tx[:4000], rx[:4000], y[:4000])
    c.add(Directions(*(x[4000:] for x in d)), tx[4000:], rx[4000:], y[4000:])
    np.testing.assert_allclose(solve(a.merge(c)).coef, one.coef, atol=1e-9)
    assert one.report.rmse_db == pytest.approx(2.0, rel=0.05)


@pytest.mark.parametrize(
    "basis",
    [SphericalHarmonics(5), SphericalHarmonics(25), BasisGrid(3, 0.3, "fibonacci"), Polynomial(4)],
    ids=["SH moments", "SH-25 rank-k", "BG", "P"],
)
def test_accumulated_statistics_equal_the_explicit_design(basis, monkeypatch):
    """X^T X, X^T y and y^T y of three nodes with links both ways, over several blocks and chunks."""
    import rplearn.core.lsq.link_statistics as solver_module

    monkeypatch.setattr(solver_module, "BLOCK_SAMPLES", 1000)
    monkeypatch.setattr(solver_module, "FEATURE_CHUNK", 300)
    rng = np.random.default_rng(21)
    n = 2500
    pairs = np.array([[0, 1], [1, 0], [2, 0], [1, 2]])
    sel = pairs[rng.integers(0, len(pairs), n)]
    az_t, el_t = _dirs(rng, n)
    az_r, el_r = _dirs(rng, n)
    y = rng.normal(0, 5, n)
    p = basis.n_coef
    X = np.zeros((n, 3 * p))
    ft, fr = basis.design(az_t, el_t), basis.design(az_r, el_r)
    for i, (t, r) in enumerate(sel):
        X[i, t * p : (t + 1) * p] += ft[i]
        X[i, r * p : (r + 1) * p] += fr[i]
    normal = NormalEquations(basis, 3).add(Directions(az_t, el_t, az_r, el_r), sel[:, 0], sel[:, 1], y)
    scale = np.abs(X.T @ X).max()
    np.testing.assert_allclose(normal.gram, X.T @ X, rtol=0, atol=1e-12 * scale)
    np.testing.assert_allclose(normal.rhs, X.T @ y, rtol=0, atol=1e-12 * np.abs(X.T @ y).max())
    assert normal.yty == pytest.approx(float(y @ y), rel=1e-12)
    links, counts = np.unique(np.sort(sel, axis=1), axis=0, return_counts=True)
    assert normal.link_counts == {(int(a), int(b)): int(c) for (a, b), c in zip(links, counts)}


def test_condition_number_matches_svd_of_design():
    rng = np.random.default_rng(16)
    b = Polynomial(3)
    d = Directions(*_dirs(rng, 3000), *_dirs(rng, 3000))
    rep = identifiability(d, np.zeros(3000, int), np.ones(3000, int), 2, b)
    X = np.hstack([b.design(d.az_tx, d.el_tx), b.design(d.az_rx, d.el_rx)])
    s = np.linalg.svd(X, compute_uv=False)
    assert rep.rank == np.linalg.matrix_rank(X) == X.shape[1] - 1
    assert rep.condition_number == pytest.approx(s[0] / s[rep.rank - 1], rel=1e-6)


def test_uncertainty_is_honest():
    """The reported standard errors cover the truth at the nominal rate."""
    rng = np.random.default_rng(17)
    b, true = _band_limited_patterns(rng, 3, 3)
    pairs = np.array([[0, 1], [1, 2], [2, 0]])
    d, tx, rx, y = _simulate(rng, b, true, pairs, 6000, 3.0)
    sol = fit_joint(d, tx, rx, y, 3, b)
    z = (sol.coef.ravel() - true.ravel()) / np.sqrt(np.diag(sol.covariance))
    assert 0.7 < np.std(z) < 1.3
    assert np.sqrt(sol.residual_variance_db2) == pytest.approx(3.0, rel=0.05)


def test_errors_are_clear():
    rng = np.random.default_rng(18)
    b = SphericalHarmonics(10)
    d = Directions(*_dirs(rng, 50), *_dirs(rng, 50))
    with pytest.raises(IdentifiabilityError, match="50 samples cannot identify 200"):
        fit_joint(d, np.zeros(50, int), np.ones(50, int), np.zeros(50), 2, b)
    with pytest.raises(IdentifiabilityError, match="C appear in no sample"):
        fit_joint(d, np.zeros(50, int), np.ones(50, int), np.zeros(50), 3, SphericalHarmonics(1), ["A", "B", "C"])
    bad = np.zeros(50)
    bad[3] = np.nan
    with pytest.raises(InputError, match="joint_gain_db: 1 NaN"):
        fit_joint(d, np.zeros(50, int), np.ones(50, int), bad, 2, SphericalHarmonics(2))
    # all samples in one direction: a pattern with many coefficients is not identified
    one_dir = Directions(np.zeros(500), np.zeros(500), *_dirs(rng, 500))
    with pytest.raises(IdentifiabilityError, match="do not identify"):
        fit_joint(one_dir, np.zeros(500, int), np.ones(500, int), np.zeros(500), 2, SphericalHarmonics(3),
                  options=JointFitOptions(ridge=0.0))
    # ...but a ridge makes it solvable, as the paper did
    fit_joint(one_dir, np.zeros(500, int), np.ones(500, int), np.zeros(500), 2, SphericalHarmonics(3),
              options=JointFitOptions(ridge=1.0))


def test_bg_and_poly_fit_smooth_patterns():
    rng = np.random.default_rng(19)
    b, true = _band_limited_patterns(rng, 2, 3)
    d, tx, rx, y = _simulate(rng, b, true, np.array([[0, 1]]), 20000, 1.0)
    for basis in (BasisGrid(6, sigma_rad2=0.1, grid="fibonacci"), Polynomial(8)):
        sol = fit_joint(d, tx, rx, y, 2, basis, options=JointFitOptions(ridge=1e-3))
        pred = np.einsum("np,p->n", basis.design(d.az_tx, d.el_tx), sol.coef[0]) + basis.design(
            d.az_rx, d.el_rx
        ) @ sol.coef[1]
        assert np.sqrt(np.mean((pred - y) ** 2)) < 1.5


def test_gauge_on_an_identified_node_is_refused_and_poor_coverage_warns():
    rng = np.random.default_rng(20)
    b, true = _band_limited_patterns(rng, 3, 2)
    pairs = np.array([[0, 1], [1, 2], [2, 0]])
    d, tx, rx, y = _simulate(rng, b, true, pairs, 3000, 1.0)
    with pytest.raises(InputError, match="already identified"):
        fit_joint(d, tx, rx, y, 3, b, list("ABC"), JointFitOptions(gauge={"node": "A", "mean_gain_dbi": 10.0}))
    assert fit_joint(d, tx, rx, y, 3, b, list("ABC")).report.warnings == ()
    # samples from a narrow cone only: the fit works (ridge) but says it extrapolates
    n = 2000
    narrow = Directions(rng.uniform(-0.2, 0.2, n), rng.uniform(-0.1, 0.1, n), rng.uniform(-0.2, 0.2, n), rng.uniform(-0.1, 0.1, n))
    sol = fit_joint(narrow, np.zeros(n, int), np.ones(n, int), rng.normal(size=n), 2, SphericalHarmonics(4))
    assert any("condition number" in w for w in sol.report.warnings)


@pytest.mark.parametrize("bad, field", [({"ridge": -1.0}, "ridge"), ({"smoothing": float("nan")}, "smoothing"),
                                        ({"penalty_power": float("inf")}, "penalty_power"), ({"chunk_size": 0}, "chunk_size"),
                                        ({"gauge": {"node": ""}}, "gauge_node")])
def test_joint_fit_options_refuse_a_bad_value_naming_it(bad, field):
    with pytest.raises(InputError) as err:
        JointFitOptions(**bad)
    assert err.value.param == field and "\n" not in str(err.value)


@pytest.mark.parametrize("offsets", [False, True])
def test_the_penalised_inverse_is_the_solves_covariance_over_its_residual_variance(offsets):
    """``penalised_inverse`` (one Cholesky factor, the gauge by a Schur complement) gives the
    same constrained inverse as the KKT inverse of :func:`solve`, with and without shared
    (unpenalised) columns."""
    from rplearn.core.lsq.selection import penalty_scale, penalty_vector
    from rplearn.core.lsq.solver import penalised_inverse

    rng = np.random.default_rng(21)
    b, coef = _band_limited_patterns(rng, 2, degree_max=4)
    d, tx, rx, y = _simulate(rng, b, coef, np.array([[0, 1], [1, 0]]), 4000, 1.0)
    normal = NormalEquations(b, 2).add(d, tx, rx, y)
    if offsets:
        normal = normal.with_shared(normal.two_way_links())
        assert normal.n_columns > normal.n_pattern_columns
    penalty = penalty_vector(b, 2, 1e-4, penalty_scale(normal.gram, normal.n_pattern_columns))
    sol = solve(normal, ["A", "B"], ridge=0.5, penalty=penalty)
    got = penalised_inverse(normal, ["A", "B"], 0.5, "equal-mean", penalty)
    expected = sol.covariance / sol.residual_variance_db2
    assert got.shape == expected.shape
    np.testing.assert_allclose(got, expected, rtol=0, atol=1e-9 * np.abs(expected).max())


def _two_node_statistics(seed=22, n=1500):
    rng = np.random.default_rng(seed)
    b, coef = _band_limited_patterns(rng, 2, degree_max=3)
    d, tx, rx, y = _simulate(rng, b, coef, np.array([[0, 1], [1, 0]]), n, 1.0)
    return b, NormalEquations(b, 2).add(d, tx, rx, y)


@pytest.mark.parametrize("bad", [-1.0, np.nan, np.inf])
def test_the_penalised_inverse_refuses_a_penalty_the_solve_refuses(bad):
    from rplearn.core.lsq.solver import penalised_inverse

    b, normal = _two_node_statistics()
    penalty = np.full(normal.n_columns, 1.0)
    penalty[3] = bad
    with pytest.raises(InputError, match="penalty: expected"):
        solve(normal, ["A", "B"], ridge=0.5, penalty=penalty)
    with pytest.raises(InputError, match="penalty: expected"):
        penalised_inverse(normal, ["A", "B"], 0.5, "equal-mean", penalty)
    with pytest.raises(InputError, match="penalty: expected"):
        penalised_inverse(normal, ["A", "B"], 0.5, "equal-mean", np.ones(normal.n_columns + 1))


@pytest.mark.parametrize("ridge", [1e-12, 1e-6])
def test_the_penalised_inverse_gives_none_where_the_solve_finds_no_identification(ridge):
    """Every sample of node A in one direction: with a ridge of 1e-12 the KKT matrix is
    conditioned beyond what the solve accepts (it refuses), and the inverse by one factor gives
    none rather than the factor's rounding; with 1e-6 both give an answer."""
    from rplearn.core.lsq.solver import penalised_inverse

    rng = np.random.default_rng(18)
    one_dir = Directions(np.zeros(500), np.zeros(500), *_dirs(rng, 500))
    normal = NormalEquations(SphericalHarmonics(4), 2).add(one_dir, np.zeros(500, int), np.ones(500, int),
                                                          rng.standard_normal(500))
    got = penalised_inverse(normal, ["A", "B"], ridge, "equal-mean", np.zeros(normal.n_columns))
    if ridge < 1e-9:
        with pytest.raises(IdentifiabilityError, match="do not identify"):
            solve(normal, ["A", "B"], ridge=ridge)
        assert got is None
    else:
        solve(normal, ["A", "B"], ridge=ridge)
        assert got is not None and np.all(np.isfinite(got))
