"""``trajectory --optimize --from-model``: the plan's prior from an earlier flight's model file
(issue 27, item 3): its noise, smoothing and drift, explicit values over them, and the refusals."""

from __future__ import annotations

import numpy as np
import pytest
from simulated_flights import synced

from rplearn.analysis.manoeuvres import ManoeuvreOptions, prior_penalty_weight
from rplearn.core.lsq.block_sums import DEFAULT_BLOCK_S
from rplearn.errors import InputError
from rplearn.models import ModelSpec, load_model
from rplearn.models.options import FitOptions
from rplearn.workflows.calibration_plan import OptimizeOptions, optimize_plan, options_from_model
from rplearn.workflows.learning import fit_dataset

SPEC = ModelSpec.parse("sh-5")
# a 15-s budget (one manoeuvre: each step scores every candidate): what these tests read (the prior, its text,
# the start spread, that a plan is written) does not need a longer plan
PLAN = dict(model="sh-5", target_spread_db=2.5, budget_s=15.0)


@pytest.fixture(scope="module")
def earlier(tmp_path_factory):
    """``rplearn fit --order auto`` of a small simulated flight (smoke preset) written to a model
    file, and that model."""
    d = tmp_path_factory.mktemp("earlier")
    flight = synced("smoke", 5)
    path = str(d / "auto.json")
    outcome = fit_dataset(str(flight.folder / "m.parquet"), ModelSpec.parse("sh"), options=FitOptions(auto=True), output=path)
    assert outcome.fitted.model.training.drift_std_db is not None
    return path, load_model(path)


def test_the_options_are_the_models_noise_smoothing_and_drift(earlier):
    path, model = earlier
    t = model.training
    opts = options_from_model(path, ManoeuvreOptions(misfit_std_db=0.3, prior_variance_factor=2.0), SPEC)
    assert opts.noise_std_db == pytest.approx(t.noise_std_db * np.sqrt(t.variance_inflation), rel=1e-12)
    assert opts.penalty_weight == t.planning_penalty_weight > 0 and opts.power == t.penalty_power
    assert opts.correlated_std_db == t.drift_std_db and opts.correlation_s == DEFAULT_BLOCK_S
    assert t.drift_std_db >= 0 and np.isfinite(t.drift_std_db)
    assert opts.misfit_std_db == 0.0 and opts.prior_variance_factor == 1.0  # the inflated posterior, as live plans


def test_explicit_values_override_the_models(earlier):
    path, model = earlier
    opts = options_from_model(path, ManoeuvreOptions(), SPEC, noise_std_db=3.0, drift_std_db=0.25)
    assert opts.noise_std_db == 3.0 and opts.correlated_std_db == 0.25
    assert opts.penalty_weight == model.training.planning_penalty_weight
    stated = options_from_model(path, ManoeuvreOptions(), SPEC, noise_std_db=3.0, prior_std_db=5.0)
    assert stated.penalty_weight == pytest.approx(prior_penalty_weight(SPEC.basis(), 5.0, 3.0, SPEC.ridge_weight, 2.0))
    assert stated.correlated_std_db == model.training.drift_std_db


def test_the_plan_from_the_model_differs_from_the_nominal_prior_and_says_what_it_took(earlier, tmp_path):
    path, model = earlier
    plan = optimize_plan(str(tmp_path / "from_model"), OptimizeOptions(**PLAN, from_model=path))
    nominal = optimize_plan(str(tmp_path / "nominal"), OptimizeOptions(**PLAN))
    assert plan.prior is not None and nominal.prior is None
    assert f"drift {model.training.drift_std_db:.2f} dB per 5-s block" in plan.prior and "(stated)" not in plan.prior
    assert plan.start_spread_db != nominal.start_spread_db  # the model's smoothing, not the nominal 6-dB prior
    assert plan.paths and all(p.endswith(".csv") for p in plan.paths)
    noisy = optimize_plan(str(tmp_path / "noisy"), OptimizeOptions(**PLAN, from_model=path, noise_std_db=8.0, drift_std_db=0.0))
    assert "noise 8.00 dB (stated)" in noisy.prior and "drift 0.00 dB per 5-s block (stated)" in noisy.prior


def test_a_streamed_fits_model_file_plans_as_the_in_memory_fits(earlier, tmp_path):
    """``fit --order auto`` of the same rows in many files (streamed part by part, a 5-s block
    cut by the files) writes the drift and planning weight the in-memory fit writes, and
    ``trajectory --optimize --from-model`` plans from its file (it was refused: "has no
    training.drift_std_db")."""
    import pandas as pd

    from rplearn.io.files import write_table

    path, model = earlier
    rows = pd.read_parquet(synced("smoke", 5).folder / "m.parquet")
    folder = tmp_path / "parts"
    folder.mkdir()
    n = len(rows)
    for i in range(3):
        write_table(rows.iloc[i * n // 3:(i + 1) * n // 3], str(folder / f"p{i}.parquet"))
    block = np.floor(rows["t"].to_numpy(np.float64) / DEFAULT_BLOCK_S)
    assert any(block[i * n // 3 - 1] == block[i * n // 3] for i in (1, 2))  # a block in two files
    streamed = str(tmp_path / "streamed.json")
    fit_dataset(str(folder), ModelSpec.parse("sh"), options=FitOptions(auto=True), output=streamed)
    got = load_model(streamed).training
    assert got.drift_std_db == pytest.approx(model.training.drift_std_db, rel=1e-9)
    assert got.planning_penalty_weight == pytest.approx(model.training.planning_penalty_weight, rel=1e-9)
    opts = options_from_model(streamed, ManoeuvreOptions(), SPEC)
    assert opts.correlated_std_db == got.drift_std_db and opts.penalty_weight == got.planning_penalty_weight
    plan = optimize_plan(str(tmp_path / "plan"), OptimizeOptions(**PLAN, from_model=streamed))
    assert plan.prior is not None and f"drift {got.drift_std_db:.2f} dB per 5-s block" in plan.prior
    assert plan.paths and all(p.endswith(".csv") for p in plan.paths)


def _saved(model, path, **changes):
    out = load_model(model)
    out.training = out.training.replace(**changes)
    out.save(str(path))
    return str(path)


def test_each_refusal_is_one_line_naming_the_file_and_what_to_do(earlier, tmp_path):
    path, _ = earlier
    flight = synced("smoke", 5)
    fixed = str(tmp_path / "sh4.json")
    fit_dataset(str(flight.folder / "m.parquet"), ModelSpec("sh", 4), output=fixed)
    mean = str(tmp_path / "mean.json")
    fit_dataset(str(flight.folder / "m.parquet"), ModelSpec.parse("mean"), output=mean)
    corrupt = tmp_path / "corrupt.json"
    corrupt.write_text("{")
    cases = [
        (str(tmp_path / "missing.json"), {}, "missing.json: no such"),
        (str(corrupt), {}, "corrupt.json: not a valid JSON model file"),
        (str(flight.folder / "m.parquet"), {}, "not a model file"),
        (mean, {}, "mean.json is a mean baseline"),
        (fixed, {}, "sh4.json is a fixed-order fit (SH-4)"),
        (_saved(path, tmp_path / "no_drift.json", drift_std_db=None), {}, "has no training.drift_std_db"),
        (_saved(path, tmp_path / "no_weight.json", planning_penalty_weight=None), {}, "has no training.planning_penalty_weight"),
        (_saved(path, tmp_path / "no_noise.json", variance_inflation=None), {}, "has no training.variance_inflation"),
        (_saved(path, tmp_path / "with_prior.json", prior={"A": "ref.json"}), {}, "was fitted with priors"),
        (path, {"spec": ModelSpec.parse("bg-7")}, "plan reads its spread at BG-7"),
        # a damaged weight (planned as 'nothing to fly'), and a fit at the search's largest smoothing (a 7-s flight's
        # 2.2e7, the same: its flight did not tell the patterns' shape from flat)
        (_saved(path, tmp_path / "weight_big.json", planning_penalty_weight=1e300), {},
         "weight_big.json: training.planning_penalty_weight is 1e+300, not a fit's smoothness penalty weight"),
        (_saved(path, tmp_path / "at_cap.json", smoothing=1e6), {}, "at_cap.json: training.smoothing is 1e+06, the largest"),
    ]
    for model, kw, text in cases:
        with pytest.raises(InputError) as err:
            options_from_model(model, ManoeuvreOptions(), kw.get("spec", SPEC))
        message = str(err.value)
        assert err.value.param == "from_model" and message.startswith("from_model: ") and "\n" not in message
        assert text in message, (text, message)
    # what the refusal says to do: the fit that writes the field, or the flag that replaces it
    with pytest.raises(InputError, match=r"rplearn fit DATASET --order auto .*or give --drift"):
        options_from_model(str(tmp_path / "no_drift.json"), ManoeuvreOptions(), SPEC)
    # a stated value stands in for the field the model lacks
    assert options_from_model(str(tmp_path / "no_drift.json"), ManoeuvreOptions(), SPEC, drift_std_db=0.4).correlated_std_db == 0.4
    assert options_from_model(str(tmp_path / "no_weight.json"), ManoeuvreOptions(), SPEC, prior_std_db=6.0).penalty_weight > 0
    for name in ("weight_big.json", "at_cap.json"):
        with pytest.raises(InputError, match=r"or give --prior-std|give --prior-std instead"):
            options_from_model(str(tmp_path / name), ManoeuvreOptions(), SPEC)
        assert options_from_model(str(tmp_path / name), ManoeuvreOptions(), SPEC, prior_std_db=6.0).penalty_weight > 0
    assert not (tmp_path / "plan").exists()


def test_the_penalty_weights_range_is_what_a_fit_of_its_samples_can_write(earlier):
    """A fit's weight is its relative smoothing (at most the search's largest) times the mean
    diagonal of its ``X^T X`` (for spherical harmonics ``1 / (2 pi nodes)`` per sample): the
    bound of a 2-node fit of n samples is ``1e6 n / (4 pi)``, which a fit at the cap reaches."""
    from rplearn.core.lsq.selection import MAX_SMOOTHING
    from rplearn.workflows.calibration_plan import penalty_weight_bound

    _, model = earlier
    bound = penalty_weight_bound(model)
    assert bound == pytest.approx(MAX_SMOOTHING * model.training.n_samples / (4.0 * np.pi), rel=1e-6)
    assert 0 < model.training.planning_penalty_weight < bound * 1e-6


def test_a_plan_says_the_models_nodes_and_whose_they_are_taken_for(earlier, tmp_path):
    """The model's nodes are named (they were not); a plan of other nodes (a station's D, G)
    says the model's figures stand for them."""
    path, model = earlier
    assert tuple(model.nodes) == ("A", "B")
    same = optimize_plan(str(tmp_path / "same"), OptimizeOptions(**PLAN, from_model=path))
    assert same.prior.startswith("a fit of nodes A, B: noise "), same.prior
    other = optimize_plan(str(tmp_path / "other"), OptimizeOptions(**PLAN, from_model=path, station=True))
    assert other.prior.startswith("a fit of nodes A, B, taken for the plan's D, G: noise "), other.prior


def test_a_stated_prior_the_ridge_caps_is_said_in_one_line(tmp_path):
    """--noise 1 --prior-std 6: the ridge alone allows 2.81 dB at SH-10 (a coefficient's prior
    variance is the noise's over ridge plus penalty), which the plan takes; it says so (it was
    shown only on the '(prior)' line). A stated prior the ridge allows is taken without a note."""
    # the note and the start spread come before any manoeuvre is scored: a 1-s budget, which none fits (the
    # greedy search scores the candidates once and takes none)
    capped = optimize_plan(str(tmp_path / "capped"), OptimizeOptions(noise_std_db=1.0, prior_std_db=6.0, budget_s=1.0))
    assert max(capped.start_spread_db.values()) == pytest.approx(2.81, abs=0.01)
    assert len(capped.notes) == 1 and "\n" not in capped.notes[0], capped.notes
    assert "stated prior spread 6 dB is more than SH-10's ridge" in capped.notes[0]
    assert "1-dB noise" in capped.notes[0] and "2.81 dB" in capped.notes[0]
    held = optimize_plan(str(tmp_path / "held"), OptimizeOptions(noise_std_db=4.2, prior_std_db=6.0, budget_s=1.0))
    assert held.notes == () and max(held.start_spread_db.values()) == pytest.approx(6.0, rel=0.05)


def test_a_rate_beyond_the_budget_is_refused_before_any_planning(tmp_path, monkeypatch):
    """The --rate work check came after the greedy search (seconds of work, then the refusal);
    it now comes first, at the budget's longest plan."""
    from rplearn.workflows import calibration_plan

    def searched(*args, **kwargs):
        raise AssertionError("the greedy search ran before the rate was checked")

    monkeypatch.setattr(calibration_plan, "greedy_plan", searched)
    monkeypatch.setattr(calibration_plan, "pattern_spreads", searched)
    with pytest.raises(InputError) as err:
        optimize_plan(str(tmp_path / "plan"), OptimizeOptions(budget_s=60.0), rate_hz=1e300)
    assert err.value.param == "rate_hz" and "1e+300 Hz would take" in str(err.value)
    assert not (tmp_path / "plan").exists()
