"""``trajectory --optimize``: the greedy information plan and its references (issue 27, item 5)."""

from __future__ import annotations

import os

import numpy as np
import pandas as pd
import pytest

from rplearn.errors import InputError
from rplearn.workflows.calibration_plan import OptimizeOptions, optimize_plan

SMALL = dict(model="sh-5", target_spread_db=2.5, budget_s=150.0, noise_std_db=4.0, prior_std_db=4.0)


@pytest.fixture(scope="module")
def white_plan(tmp_path_factory):
    """The plan of :data:`SMALL` under white noise, made once for the tests that only read it."""
    return optimize_plan(str(tmp_path_factory.mktemp("white") / "plan"), OptimizeOptions(**SMALL))


def test_the_plan_lowers_the_spread_within_its_budget_and_writes_the_trajectory_format(white_plan):
    plan = white_plan
    assert plan.steps and plan.duration_s <= 150.0
    worst = [max(plan.start_spread_db.values())] + [max(s.spread_db.values()) for s in plan.steps]
    assert all(b < a for a, b in zip(worst, worst[1:]))
    assert worst[0] == pytest.approx(4.0, rel=1e-3)  # the prior's stated spread
    assert worst[-1] <= 2.5 or plan.duration_s + 5.0 > 150.0
    labels = [u.label for u in plan.campaign.units]
    assert labels[0].startswith("01_") and len(plan.paths) == 2 * len(labels)
    for path in plan.paths:
        ref = pd.read_csv(path)
        assert list(ref.columns) == ["t", "x", "y", "z", "yaw_deg"] and ref["t"].iloc[0] == 0.0
        assert ref["t"].is_monotonic_increasing and ref["z"].min() >= 3.0 - 1e-6
    text = plan.summary()
    assert "(prior)" in text and plan.steps[0].manoeuvre.name in text


def test_a_station_never_moves(tmp_path):
    plan = optimize_plan(str(tmp_path / "plan"), OptimizeOptions(**SMALL, station=True, distance_m=30.0))
    station = [p for p in plan.paths if p.endswith("_G.csv")]
    assert station
    for path in station:
        ref = pd.read_csv(path)
        assert np.allclose(ref[["x", "y", "z"]].to_numpy(), ref[["x", "y", "z"]].to_numpy()[0])


def test_a_prior_pattern_must_be_a_pattern_model(tmp_path):
    bad = tmp_path / "not_a_model.json"
    bad.write_text("{}")
    with pytest.raises(Exception) as err:
        optimize_plan(str(tmp_path / "plan"), OptimizeOptions(**SMALL, prior_pattern=str(bad)))
    assert "not_a_model.json" in str(err.value)
    assert not os.path.exists(tmp_path / "plan")


@pytest.mark.parametrize(("kw", "param"), [(dict(budget_s=0.0), "budget_s"), (dict(target_spread_db=-1.0), "target_spread_db"),
                                           (dict(noise_std_db=float("nan")), "noise_std_db"),
                                           (dict(drift_std_db=-0.5), "drift_std_db")])
def test_bad_options_name_their_field(kw, param):
    with pytest.raises(InputError) as err:
        OptimizeOptions(**{**SMALL, **kw})
    assert err.value.param == param


def test_a_drifting_error_counts_a_manoeuvre_for_less(white_plan, tmp_path):
    """With an error drifting over seconds, a manoeuvre that sees its directions once leaves a
    larger expected spread than white noise says."""
    white = white_plan
    drift = optimize_plan(str(tmp_path / "drift"), OptimizeOptions(**SMALL, drift_std_db=0.8))
    assert drift.start_spread_db == white.start_spread_db  # before any flight nothing drifted
    assert drift.steps[0].manoeuvre.name == white.steps[0].manoeuvre.name
    assert all(drift.steps[0].spread_db[n] > white.steps[0].spread_db[n] for n in white.start_spread_db)


def test_the_guide_gives_noise_the_one_meaning_the_plan_gives_it():
    """``--noise`` (``OptimizeOptions.noise_std_db``, ``ManoeuvreOptions.noise_std_db``) is the noise of one RSSI
    reading about the model, each packet's error independent in the plan's posterior: the calibration-plan guide
    said so in one place ('the RSSI's scatter about the pattern') and 'not the RSSI's scatter' in another (review49)."""
    import re
    from pathlib import Path

    from rplearn.analysis.manoeuvres import ManoeuvreOptions

    assert "one RSSI reading about the model" in " ".join((ManoeuvreOptions.__doc__ or "").split())
    assert "one RSSI reading about the model" in " ".join((OptimizeOptions.__doc__ or "").split())
    guide = " ".join((Path(__file__).resolve().parents[2] / "docs" / "guides" / "calibration-plan.md").read_text().split())
    said = re.findall(r"`--noise`(?: is|:) ([^.]+)", guide)
    assert len(said) == 2, said
    assert all(s.startswith("the noise of one RSSI reading about the pattern, each packet's error taken as independent")
               for s in said), said
    assert "not the RSSI's scatter" not in guide
