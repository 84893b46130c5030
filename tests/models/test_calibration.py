"""Calibration of the predictive spread (issue 11, acceptance 3): 90% intervals
``prediction +- 1.645 sqrt(gain_std^2 + rmse^2)`` of an automatic fit cover 85-95% of held-out
samples, inside and outside the covered directions."""

from __future__ import annotations

import numpy as np
import pytest

from rplearn.models.auto import fit_auto
from rplearn.models.predict import UNCOVERED_DEG, end_coverage_deg

from test_auto import campaign
from test_prior import ground_case


def interval_hits(model, test):
    """Per held-out sample: inside its 90% interval, and whether both ends are covered."""
    g = model.predict_gain(test)
    half = 1.645 * np.sqrt(model.predict_gain_std(test) ** 2 + model.training["rmse_db"] ** 2)
    tx, rx = end_coverage_deg(model, test)
    return np.abs(test.joint_gain_db - g) <= half, np.fmax(tx, rx) <= UNCOVERED_DEG


@pytest.mark.slow
def test_ground_with_a_prior_is_calibrated_inside_and_outside(tmp_path):
    per_unit, _, test, prior = ground_case(tmp_path, 0)
    fitted, _ = fit_auto(per_unit, prior={n: prior for n in prior.nodes})
    hit, covered = interval_hits(fitted.model, test)
    assert covered.sum() > 100 and (~covered).sum() > 100
    for name, part in (("all", hit), ("covered", hit[covered]), ("uncovered", hit[~covered])):
        assert 0.85 <= part.mean() <= 0.95, (name, part.mean(), part.size)


@pytest.mark.slow
def test_paper_is_calibrated_where_it_was_flown(tmp_path_factory):
    _, _, per_unit, _, test = campaign(tmp_path_factory, "paper", 0, link=("A", "B"))
    fitted, _ = fit_auto(per_unit)
    hit, covered = interval_hits(fitted.model, test)
    assert 0.85 <= hit.mean() <= 0.95 and 0.85 <= hit[covered].mean() <= 0.95, (hit.mean(), hit[covered].mean())
