"""rplearn.models.robust and ``fit --loss huber`` (issue 12, item 4): plateaus and dropouts."""

from __future__ import annotations

import numpy as np
import pytest
from simulated_flights import synced

from rplearn.analysis.pattern_error import node_directions, pattern_errors_db
from rplearn.data.units import samples_of, split_units
from rplearn.errors import InputError
from rplearn.io.files import read_dataset
from rplearn.models import ModelSpec
from rplearn.models.fit import fit_model
from rplearn.models.robust import fit_huber, robust_scale_db


def spoiled(clean, share=0.05, seed=0):
    """``clean`` with ``share`` of its samples in 2 s windows that are plateaus (the RSSI of the
    window's first packet repeated) or dropouts (the radio's floor, -100 dBm), half each."""
    rng = np.random.default_rng(seed)
    bad = clean.copy()
    t = bad["t"].to_numpy()
    hit = np.zeros(len(bad), bool)
    while hit.mean() < share:
        start = rng.uniform(t.min(), t.max() - 2.0)
        window = (t >= start) & (t < start + 2.0)
        if window.any():
            first = bad["rssi_dbm"].to_numpy()[np.flatnonzero(window)[0]]
            bad.loc[window, "rssi_dbm"] = first if rng.random() < 0.5 else -100.0
            hit |= window
    return bad, hit


@pytest.fixture(scope="module")
def paper():
    """The paper campaign of seed 0 (A->B; simulated and synced once per process:
    tests/simulated_flights.py): its folder, simulation and learning rows in time order."""
    flight = synced("paper", 0, ("A", "B"))
    df = read_dataset(str(flight.folder / "m.parquet"))
    learn, _ = split_units(df, None, None)
    clean = df[df["unit"].isin(learn)].sort_values("t").reset_index(drop=True)
    return flight.folder, flight.sim, clean


@pytest.mark.slow
def test_huber_recovers_the_patterns_where_least_squares_does_not(paper):
    """Acceptance 4: 5% plateaus and dropouts; SH-10 pattern error against the truth."""
    _, sim, clean = paper
    bad, hit = spoiled(clean)
    nodes = ["A", "B"]
    covered = node_directions(samples_of(clean, None, "d", nodes=nodes))

    def error(model):
        return float(np.mean(list(pattern_errors_db(model, sim.ground_truth, covered).values())))

    spec = ModelSpec("sh", 10)
    reference = error(fit_model(samples_of(clean, None, "d", nodes=nodes), spec).model)
    least_squares = error(fit_model(samples_of(bad, None, "d", nodes=nodes), spec).model)
    fitted, robust = fit_huber(samples_of(bad, None, "d", nodes=nodes), spec)
    huber = error(fitted.model)
    assert huber - reference < 0.3 and least_squares - reference > 0.3, (reference, least_squares, huber)
    assert robust.converged and robust.downweighted[hit].mean() > 2 * robust.downweighted[~hit].mean()
    assert fitted.model.training["robust"]["downweighted"] == int(robust.downweighted.sum())


def test_fit_loss_huber_says_where_it_down_weighted(paper, tmp_path):
    d, _, clean = paper
    bad, _ = spoiled(clean.iloc[::4].reset_index(drop=True), seed=1)
    bad.to_parquet(tmp_path / "bad.parquet")
    from typer.testing import CliRunner

    from rplearn.cli import app

    def fit(*args: str):  # in this process: the exit codes and messages are checked, not the process boundary
        return CliRunner().invoke(app, ["fit", str(tmp_path / "bad.parquet"), *args], env={"COLUMNS": "400"})

    proc = fit("--degree", "6", "--loss", "huber", "-o", str(tmp_path / "h.json"))
    assert proc.exit_code == 0, proc.output
    assert "huber:" in proc.stdout and "by unit:" in proc.stdout and "longest stretches:" in proc.stdout, proc.stdout
    auto = fit("--loss", "huber", "-o", str(tmp_path / "a.json"))
    assert auto.exit_code == 1 and "fixed order" in auto.stderr, auto.output
    with pytest.raises(InputError, match="pattern models"):
        fit_huber(samples_of(clean.iloc[:500], None, "d", nodes=["A", "B"]), ModelSpec("knn", 5))


def test_the_robust_scale_ignores_a_minority_of_outliers():
    rng = np.random.default_rng(0)
    r = rng.normal(0.0, 2.0, 20_000)
    r[:1000] = -80.0
    assert robust_scale_db(r) == pytest.approx(2.0 * 1.06, rel=0.05)  # 5% outliers widen the MAD a little


def test_noise_free_data_is_not_reported_as_down_weighted():
    from rplearn.core.geometry import Directions
    from rplearn.core.sh import SphericalHarmonics
    from rplearn.data.tables import LinkSamples

    rng = np.random.default_rng(2)
    n = 3000
    az, el = rng.uniform(-np.pi, np.pi, (2, n)), np.arcsin(rng.uniform(-1, 1, (2, n)))
    basis = SphericalHarmonics(3)
    coef = rng.normal(0, 3, (2, basis.n_coef))
    y = np.einsum("ij,j->i", basis.design(az[0], el[0]), coef[0]) + np.einsum("ij,j->i", basis.design(az[1], el[1]), coef[1])
    samples = LinkSamples(Directions(az[0], el[0], az[1], el[1]), np.zeros(n, int), np.ones(n, int), ("A", "B"), y, np.full(n, 30.0))
    _, robust = fit_huber(samples, ModelSpec("sh", 3, ridge=0.0))
    assert robust.scale_db >= 1e-3 and robust.downweighted.sum() == 0
