"""A flight without units (a real ground station's .tlog): one naming of its stretches of time,
given by ``fit`` and accepted alike by ``fit --units``, ``evaluate --units`` and ``sweep``."""

from __future__ import annotations

import json
import re

import numpy as np
import pandas as pd
import pytest
from cli_helpers import REAL_TLOG, invoke

LOG = REAL_TLOG


@pytest.fixture(scope="module")
def matched(tmp_path_factory):
    d = tmp_path_factory.mktemp("tlog")
    path = d / "matched.parquet"
    invoke(["sync", "--poses", LOG, "--signals", LOG, "--tx-power", "20", "--frequency", "915e6", "--link", "all",
            "--max-gap", "1.0", "-o", path])
    return path


def test_a_tlog_model_is_scored_on_the_held_out_stretch_fit_names(matched, tmp_path):
    from rplearn.data.tables import link_samples
    from rplearn.data.units import time_units
    from rplearn.models.load import load_model

    # fit on the whole flight names its stretches (the folds of its cross-validation)
    whole = invoke(["fit", matched, "-o", tmp_path / "whole.json"]).output
    folds = re.search(r"grouped cross-validation over units (.*?): order", whole)
    assert folds, whole
    names = folds.group(1).split(", ")
    assert len(names) == 5 and names[-1] == "test[5/5]" and "no 'unit' column" in whole
    learn, held = names[:-1], names[-1]
    # fit learns from the first four by those names; evaluate scores the fifth by its name
    fit = invoke(["fit", matched, "--units", ",".join(learn), "-o", tmp_path / "m.json"]).output
    assert re.search(r"grouped cross-validation over units " + re.escape(", ".join(learn)) + ": order", fit), fit
    out = invoke(["evaluate", tmp_path / "m.json", matched, "--units", held, "--json", tmp_path / "ev.json"]).output
    assert "training scores" not in out
    rmse = json.loads((tmp_path / "ev.json").read_text())["rows"][0]["rmse_db"]
    # the score is that of exactly the rows of the held-out stretch
    df, _ = time_units(pd.read_parquet(matched))
    rows = df[df["unit"] == held]
    assert 0 < len(rows) < len(df) // 4
    samples = link_samples(rows)
    error = load_model(str(tmp_path / "m.json")).predict_gain(samples) - samples.joint_gain_db
    assert rmse == pytest.approx(float(np.sqrt(np.mean(error ** 2))), rel=1e-9)
    # by default evaluate picks the stretch no model learned from; a learned one is a training score
    default = invoke(["evaluate", tmp_path / "m.json", matched]).output
    assert f"scoring on units {held}, which no model learned from" in default
    assert "training scores" in invoke(["evaluate", tmp_path / "m.json", matched, "--units", learn[1]]).output
    # a name that is not a stretch is refused with the names there are
    bad = invoke(["evaluate", tmp_path / "m.json", matched, "--units", "flight[9/5]"], ok=False)
    assert bad.exit_code == 1 and ", ".join(names) in bad.output
    # sweep takes the same names
    sweep = invoke(["sweep", matched, "--orders", "2,3", "--learn-units", ",".join(learn), "--test-units", held]).output
    assert "lowest test RMSE at order" in sweep
    assert invoke(["sweep", matched, "--orders", "2", "--test-units", "flight[9/5]"], ok=False).exit_code == 1


def test_no_instant_of_the_real_log_is_split_across_stretches_or_folds(matched):
    from rplearn.data.units import Stretches, time_units

    df = pd.read_parquet(matched)
    t = df["t"].to_numpy(np.float64)
    assert len(np.unique(t)) < len(t)  # both directions of a telemetry report share their time
    cut, _ = time_units(df)
    assert (cut.groupby("t")["unit"].nunique() == 1).all()
    counts = cut["unit"].value_counts()
    assert counts.max() - counts.min() <= 2
    # a cut by row counts (as the folds were cut) splits some of these instants
    ordered = np.sort(t)
    blocks = np.array_split(ordered, 5)
    assert any(a[-1] == b[0] for a, b in zip(blocks[:-1], blocks[1:]))
    # the folds of a single unit are cut the same way
    folds = Stretches.of_times(t, 5, "u").label(t)
    assert (pd.Series(folds).groupby(t).nunique() == 1).all() and len(set(folds)) == 5


def test_evaluate_sensitivity_scores_the_held_out_availability_in_markdown_and_json(matched, tmp_path):
    names = [f"flight[{k}/5]" for k in range(1, 5)]
    invoke(["fit", matched, "--units", ",".join(names), "-o", tmp_path / "m.json"])
    out = invoke(["evaluate", tmp_path / "m.json", matched, "--units", "test[5/5]", "--sensitivity", "-70",
                  "--json", tmp_path / "ev.json", "--markdown", tmp_path / "ev.md"]).output
    doc = json.loads((tmp_path / "ev.json").read_text())
    [score] = doc["availability"]
    assert score["sensitivity_dbm"] == -70 and score["n_outages"] == 0 and score["brier_skill"] > 0
    assert sum(b["count"] for b in score["reliability"]) == score["n_samples"]
    assert "## Availability at -70 dBm" in out and "| predicted availability |" in (tmp_path / "ev.md").read_text()
    bad = invoke(["evaluate", tmp_path / "m.json", matched, "--units", "test[5/5]", "--sensitivity", "nan"], ok=False)
    assert bad.exit_code != 0 and "--sensitivity" in bad.output
