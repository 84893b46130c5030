"""Brier score, skill and reliability table of probability forecasts (rplearn.core.reliability)."""

from __future__ import annotations

import numpy as np
import pytest

from rplearn.core.reliability import brier_score, brier_skill, reliability_table
from rplearn.errors import InputError


def test_brier_score_and_skill_by_hand():
    p = np.array([0.9, 0.8, 0.3, 0.1])
    o = np.array([1, 1, 0, 0])
    assert brier_score(p, o) == pytest.approx((0.01 + 0.04 + 0.09 + 0.01) / 4)
    # the constant 0.5 scores 0.25; the skill is 1 - 0.0375 / 0.25
    assert brier_skill(p, o, 0.5) == pytest.approx(1 - 0.0375 / 0.25)
    assert brier_skill(np.full(4, 0.5), o, 0.5) == pytest.approx(0.0)
    assert brier_skill(o.astype(float), o, 0.5) == pytest.approx(1.0)
    # a reference equal to every outcome scores 0: no skill can be measured against it
    assert np.isnan(brier_skill(p, np.ones(4), 1.0))


def test_calibrated_forecasts_lie_on_the_diagonal_of_the_table():
    rng = np.random.default_rng(0)
    p = rng.uniform(0, 1, 200_000)
    o = rng.uniform(0, 1, p.size) < p  # outcomes drawn with the forecast probability
    table = reliability_table(p, o, bins=10)
    assert table.count.sum() == p.size and (table.count > 0).all()
    np.testing.assert_allclose(table.observed_share, table.mean_forecast, atol=0.01)
    np.testing.assert_allclose(table.mean_forecast, np.arange(10) / 10 + 0.05, atol=0.01)
    # an over-confident forecast (pushed toward 0 and 1) has a table flatter than the diagonal
    sharp = reliability_table(np.clip(1.5 * (p - 0.5) + 0.5, 0, 1), o)
    first, last = np.flatnonzero(sharp.count)[[0, -1]]
    assert sharp.observed_share[first] > sharp.mean_forecast[first] and sharp.observed_share[last] < sharp.mean_forecast[last]
    assert "| predicted availability |" in table.markdown() and len(table.rows()) == 10


def test_edges_empty_bins_nan_forecasts_and_bad_input():
    table = reliability_table([0.0, 1.0, 1.0, np.nan], [0, 1, 0, 1], bins=4)
    assert table.count.tolist() == [1, 0, 0, 2]  # 1 falls in the last bin; NaN forecasts are left out
    assert np.isnan(table.mean_forecast[1]) and table.observed_share[3] == pytest.approx(0.5)
    assert [r["count"] for r in table.rows()] == [1, 2]
    with pytest.raises(InputError, match="forecast"):
        brier_score([1.2], [1])
    with pytest.raises(InputError, match="outcome"):
        brier_score([0.5], [2])
    with pytest.raises(InputError, match="outcome"):
        brier_score([0.5, 0.5], [1])
    with pytest.raises(InputError, match="reference"):
        brier_skill([0.5], [1], 1.5)
    with pytest.raises(InputError, match="bins"):
        reliability_table([0.5], [1], bins=0)
