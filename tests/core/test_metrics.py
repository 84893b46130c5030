"""Metrics of paper Sec. V-C."""

import numpy as np
import pytest

from rplearn.core import metrics


def test_paper_table1_mean_row_aic():
    # Table I, M row: n = 24,087 test samples, RMSE = 11.15 dB, k = 1 -> AIC = 116.16e3.
    value = metrics.aic(24087, 11.15**2, 1)
    # The printed RMSE is rounded to 0.01 dB; n ln(MSE) moves 4.3e3 per dB of RMSE, so the
    # rounding alone allows +-0.022e3. With RMSE = 11.15 exactly the function gives 116.171e3.
    assert value / 1e3 == pytest.approx(116.16, abs=0.022)
    assert value == pytest.approx(24087 * np.log(124.3225) + 2, rel=1e-12)
    # an RMSE inside the rounding interval [11.145, 11.155) reproduces the printed 116.16e3
    assert round(metrics.aic(24087, 11.1478**2, 1) / 1e3, 2) == 116.16


def test_basic_errors():
    y = np.array([0.0, 1.0, 2.0, 3.0])
    p = np.array([1.0, 1.0, 0.0, 3.0])
    assert metrics.rmse(y, p) == pytest.approx(np.sqrt(5 / 4))
    assert metrics.mae(y, p) == pytest.approx(3 / 4)
    assert metrics.q95(y, p) == pytest.approx(np.percentile([1, 0, 2, 0], 95))
    s = metrics.score("x", y, p, n_params=3, ltd_s=0.5)
    assert s.aic == pytest.approx(4 * np.log(5 / 4) + 6)


def test_condition_number_ignores_exact_null_space():
    x = np.random.default_rng(0).normal(size=(100, 3))
    x = np.column_stack([x, x[:, 0] + x[:, 1]])
    s = np.linalg.svd(x, compute_uv=False)
    assert metrics.condition_number(x) == pytest.approx(s[0] / s[2])
