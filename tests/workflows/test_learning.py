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
def test_a_baseline_with_an_environment_term_is_refused_once_by_fit_model(no_units, baseline):
    """The one check that baselines learn no environment term is the fit request's
    (``FitOptions.check``, which fit_dataset and fit_model both go through): issue 25, it was
    checked twice; the message is one, in one place of the source."""
    from pathlib import Path

    from rplearn.core.environment import PathLoss
    from rplearn.models.options import FitOptions
    from rplearn.models.spec import ModelSpec
    from rplearn.workflows.learning import fit_dataset

    options = FitOptions(path_loss=PathLoss("log-distance"))
    with pytest.raises(InputError, match="learn no environment term") as err:
        fit_dataset(no_units, ModelSpec.parse(baseline), options=options)
    assert err.value.param == "path_loss"
    with pytest.raises(InputError, match="learn no environment term"):
        FitOptions(path_loss=PathLoss("two-ray")).check(ModelSpec.parse(baseline))
    assert fit_dataset(no_units, ModelSpec.parse(baseline)).fitted.model.kind != "patterns"  # free space: learned
    src = Path(__file__).resolve().parents[2] / "src" / "rplearn"
    said = [p for p in src.rglob("*.py") if "learn no environment" in p.read_text(encoding="utf-8")]
    assert [p.name for p in said] == ["options.py"], said


def _samples(path):
    import pandas as pd

    from rplearn.data.units import samples_of

    return (samples_of(pd.read_parquet(path)),)
