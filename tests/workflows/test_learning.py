"""Learning workflows on datasets without trajectory units (a telemetry log) and with models the
data cannot identify (the report: tests/workflows/test_report.py)."""

from __future__ import annotations

import pytest

from rplearn.errors import InputError
from rplearn.workflows.learning import sweep_dataset


@pytest.fixture(scope="module")
def no_units(tmp_path_factory):
    from rplearn.sim.flight import simulate

    path = tmp_path_factory.mktemp("nounits") / "flight.parquet"
    simulate("smoke", seed=2).matched_truth.drop(columns=["unit"]).to_parquet(path)
    return str(path)


def test_sweep_says_how_it_split_a_flight_without_units(no_units):
    result = sweep_dataset(no_units, "sh", [2, 3])
    assert result.orders == [2, 3] and len(result.notes) == 1 and "stretches of time" in result.notes[0]


@pytest.mark.parametrize("baseline", ["m", "nn-5"])
def test_a_baseline_with_an_environment_term_is_refused_once_by_fit_model(no_units, baseline, monkeypatch):
    """The one check that baselines learn no environment term is fit_model's: fit_dataset passes
    the terms on and says the same (issue 25: it was checked twice)."""
    from rplearn.core.environment import PathLoss
    from rplearn.models import fit as fit_module
    from rplearn.models.spec import ModelSpec
    from rplearn.workflows.learning import fit_dataset

    calls = []
    real = fit_module.fit_model
    monkeypatch.setattr("rplearn.workflows.learning.fit_model", lambda *a, **k: (calls.append(k), real(*a, **k))[1])
    with pytest.raises(InputError, match="learn no environment term") as err:
        fit_dataset(no_units, ModelSpec.parse(baseline), path_loss=PathLoss("log-distance"))
    assert err.value.param == "path_loss" and calls and calls[0]["path_loss"].kind == "log-distance"
    with pytest.raises(InputError, match="learn no environment term"):
        real(*_samples(no_units), ModelSpec.parse(baseline), path_loss=PathLoss("two-ray"))
    assert fit_dataset(no_units, ModelSpec.parse(baseline)).fitted.model.kind != "patterns"  # free space: learned


def _samples(path):
    import pandas as pd

    from rplearn.data.units import samples_of

    return (samples_of(pd.read_parquet(path)),)
