"""scikit-learn conformance of the estimators, and their use in model selection."""

from __future__ import annotations

import numpy as np
import pytest
from sklearn.model_selection import GridSearchCV, cross_val_score
from sklearn.utils.estimator_checks import parametrize_with_checks

from rplearn.core.bases import SphericalHarmonics
from rplearn.errors import InputError
from rplearn.models.estimators import JointKNNRegressor, MeanRegressor, PatternRegressor

# Checks that cannot apply, each with its reason. The pattern model and the joint k-NN take a
# fixed input layout (4 angle columns az_tx, el_tx, az_rx, el_rx, or 6 with node numbers):
# these checks generate data with 1, 2, 3, 5 or 10 arbitrary features, which are refused with
# an InputError naming the expected columns instead of being fitted as if they were angles.
_LAYOUT = "feeds an arbitrary number of features; the model takes exactly 4 angle columns (or 6 with node numbers)"
_FIXED_LAYOUT_CHECKS = [
    "check_dict_unchanged",
    "check_dont_overwrite_parameters",
    "check_dtype_object",
    "check_estimators_dtypes",
    "check_estimators_fit_returns_self",
    "check_estimators_nan_inf",
    "check_estimators_overwrite_params",
    "check_estimators_pickle",
    "check_estimators_pickle(readonly_memmap=True)",
    "check_f_contiguous_array_estimator",
    "check_fit2d_1feature",
    "check_fit2d_1sample",
    "check_fit2d_predict1d",
    "check_fit_check_is_fitted",
    "check_fit_idempotent",
    "check_fit_score_takes_y",
    "check_methods_sample_order_invariance",
    "check_methods_subset_invariance",
    "check_n_features_in",
    "check_pipeline_consistency",
    "check_readonly_memmap_input",
    "check_regressor_data_not_an_array",
    "check_regressors_int",
    "check_regressors_train",
    "check_regressors_train(readonly_memmap=True)",
    "check_regressors_train(readonly_memmap=True,X_dtype=float32)",
    "check_supervised_y_2d",
    "check_array_api_input",
]
_MEAN_XFAIL = {
    name: "the paper's M baseline predicts a constant, so it cannot reach the training R^2 > 0.5 this check asks"
    for name in (
        "check_regressors_train",
        "check_regressors_train(readonly_memmap=True)",
        "check_regressors_train(readonly_memmap=True,X_dtype=float32)",
    )
}


def _expected_failures(estimator):
    if isinstance(estimator, MeanRegressor):
        return _MEAN_XFAIL
    return {name: _LAYOUT for name in _FIXED_LAYOUT_CHECKS}


@parametrize_with_checks(
    [PatternRegressor(order=2), MeanRegressor(), JointKNNRegressor(n_neighbors=5)],
    expected_failed_checks=_expected_failures,
)
def test_sklearn_conformance(estimator, check):
    check(estimator)


def _two_node_data(n, rng, noise_db=1.0):
    basis = SphericalHarmonics(4)
    true = rng.normal(0, 3, (2, basis.n_coef))
    az = rng.uniform(-np.pi, np.pi, (n, 2))
    el = np.arcsin(rng.uniform(-1, 1, (n, 2)))
    y = basis.design(az[:, 0], el[:, 0]) @ true[0] + basis.design(az[:, 1], el[:, 1]) @ true[1]
    X = np.column_stack([az[:, 0], el[:, 0], az[:, 1], el[:, 1]])
    return X, y + rng.normal(0, noise_db, n)


def test_grid_search_selects_true_order():
    rng = np.random.default_rng(3)
    X, y = _two_node_data(3000, rng)
    search = GridSearchCV(PatternRegressor(), {"order": [2, 4, 8], "ridge": [1e-6, 1.0]}, cv=3)
    search.fit(X, y)
    assert search.best_params_["order"] == 4
    scores = cross_val_score(PatternRegressor(order=4), X, y, cv=3, scoring="neg_root_mean_squared_error")
    assert np.all(-scores < 1.1)  # noise is 1 dB


def test_pattern_beats_baselines_and_counts_parameters():
    rng = np.random.default_rng(4)
    X, y = _two_node_data(4000, rng)
    Xtr, ytr, Xte, yte = X[:3000], y[:3000], X[3000:], y[3000:]
    rm = {}
    for est in (PatternRegressor(order=4), MeanRegressor(), JointKNNRegressor(n_neighbors=20)):
        est.fit(Xtr, ytr)
        rm[type(est).__name__] = np.sqrt(np.mean((est.predict(Xte) - yte) ** 2))
    assert rm["PatternRegressor"] < rm["JointKNNRegressor"] < rm["MeanRegressor"]
    assert PatternRegressor(order=4).fit(Xtr, ytr).n_params_ == 32
    assert JointKNNRegressor(n_neighbors=20).fit(Xtr, ytr).n_params_ == 3000


def test_six_columns_name_three_nodes():
    rng = np.random.default_rng(5)
    basis = SphericalHarmonics(3)
    true = rng.normal(0, 2, (3, basis.n_coef))
    n = 3000
    pairs = np.array([(0, 1), (1, 2), (2, 0)])[rng.integers(0, 3, n)]
    az = rng.uniform(-np.pi, np.pi, (n, 2))
    el = np.arcsin(rng.uniform(-1, 1, (n, 2)))
    ft = basis.design(az[:, 0], el[:, 0])
    fr = basis.design(az[:, 1], el[:, 1])
    y = np.einsum("np,np->n", ft, true[pairs[:, 0]]) + np.einsum("np,np->n", fr, true[pairs[:, 1]])
    X = np.column_stack([az[:, 0], el[:, 0], az[:, 1], el[:, 1], pairs])
    est = PatternRegressor(order=3, ridge=0.0).fit(X, y)
    assert est.report_.rank == est.report_.n_columns == 27
    np.testing.assert_allclose(est.coef_, true, atol=1e-8)  # absolute gains, no gauge needed


def test_wrong_layout_is_refused_with_clear_message():
    with pytest.raises(InputError, match="4 columns"):
        PatternRegressor(order=2).fit(np.zeros((50, 3)), np.zeros(50))


def test_joint_knn_refuses_more_neighbours_than_samples_like_the_model():
    from rplearn.data.tables import LinkSamples
    from rplearn.errors import IdentifiabilityError
    from rplearn.models.baselines import KNNModel
    from rplearn.models.estimators import samples_from_features

    rng = np.random.default_rng(6)
    X, y = _two_node_data(30, rng)
    with pytest.raises(IdentifiabilityError, match="n_neighbors = 31") as est_error:
        JointKNNRegressor(n_neighbors=31).fit(X, y)
    samples = samples_from_features(X, y, ("A", "B"))
    assert isinstance(samples, LinkSamples)
    with pytest.raises(IdentifiabilityError, match="n_neighbors = 31") as model_error:
        KNNModel.fit(samples, 31)
    assert est_error.value.param == model_error.value.param == "n_neighbors"
    with pytest.raises(InputError, match="n_neighbors must be a positive integer"):
        JointKNNRegressor(n_neighbors=0).fit(X, y)
    # at k = n both agree, and equal the training mean
    est = JointKNNRegressor(n_neighbors=30).fit(X, y)
    np.testing.assert_allclose(est.predict(X[:5]), KNNModel.fit(samples, 30).predict_gain(samples)[:5])
    np.testing.assert_allclose(est.predict(X[:5]), np.mean(y))


def test_estimators_agree_with_the_model_classes():
    from rplearn.models.baselines import MeanModel
    from rplearn.models.estimators import samples_from_features
    from rplearn.models.fit import fit_patterns
    from rplearn.models.spec import ModelSpec

    rng = np.random.default_rng(8)
    X, y = _two_node_data(800, rng)
    samples = samples_from_features(X, y, ("0", "1"))
    # M: the estimator is the one-link case of the per-link model
    assert MeanRegressor().fit(X, y).mean_ == MeanModel.fit(samples).means_db[("0", "1")]
    # patterns: the same solve, the same predictions
    est = PatternRegressor(order=3, ridge=0.5).fit(X, y)
    model = fit_patterns(samples, ModelSpec("sh", 3, ridge=0.5))
    np.testing.assert_array_equal(est.coef_, model.coef)
    np.testing.assert_array_equal(est.predict(X), model.predict_gain(samples))
    with pytest.raises(InputError, match="basis"):
        PatternRegressor(basis="mean").fit(X, y)
