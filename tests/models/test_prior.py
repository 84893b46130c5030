"""``fit --prior`` on a flight that covers a few percent of the sphere (issue 11, acceptance 2):
the `ground` preset (a static ground station and one drone at 15 and 25 m, tested at 35 m)."""

from __future__ import annotations

import pytest
from simulated_flights import auto_fit, copy_files, synced

from rplearn.analysis.pattern_error import node_directions
from rplearn.core.coverage import covered_fraction
from rplearn.io.files import read_dataset
from rplearn.io.reference import read_reference_pattern
from rplearn.models import ModelSpec
from rplearn.models.auto import fit_auto
from rplearn.models.fit import FittedModel, evaluate_models, fit_model
from rplearn.models.options import FitOptions
from rplearn.models.reference import reference_model
from rplearn.sim import imperfect_reference


def ground_case(tmp_path, seed):
    """The `ground` flights of ``seed`` synced, their files copied into ``tmp_path`` (``f/``,
    ``m.parquet``; simulated and synced once per process: tests/simulated_flights.py), each node's
    imperfect reference written there (``ref_NODE.csv``): the learning units' samples (each, and
    all), the held-out samples, and the reference prior."""
    flight = synced("ground", seed)
    copy_files(flight, tmp_path)
    refs = {}
    for n in flight.learn.nodes:  # the true pattern, 2 dB RMS smooth error, mounted 10 degrees off
        imperfect_reference(flight.sim.ground_truth, n, 2.0, 10.0, seed=seed).to_csv(tmp_path / f"ref_{n}.csv", index=False)
        refs[n] = read_reference_pattern(tmp_path / f"ref_{n}.csv")
    return flight.per_unit, flight.learn, flight.test, reference_model(refs)


def rmse(model, test, spec=ModelSpec("sh", 3)):
    return evaluate_models([FittedModel(spec, model, 0.0)], test)[0].rmse_db


@pytest.mark.slow
@pytest.mark.parametrize("seed", [0, 1, pytest.param(2, marks=pytest.mark.xfail(strict=True, reason=(
    "known: at the 35 m test altitude the fit (4.77 dB) loses to the prior alone (4.71 dB); not a matter of "
    "coverage (98% of the test samples lie within 10 deg of learning directions): the correction that "
    "cross-validation between 15 and 25 m favours (0.37 dB better there) does not carry to 35 m. Seeds 0, 1, "
    "3, 4, 5 beat the prior by 0.08-0.48 dB")))])
def test_a_reference_prior_wins_where_the_flight_saw_little(tmp_path, seed):
    per_unit, learn, test, prior = ground_case(tmp_path, seed)
    for node, (az, el) in node_directions(learn).items():
        assert covered_fraction(az, el) < 0.10, node  # the flight saw under 10% of each antenna
    # calibrated power (the simulator's dBm) and a reference in true dBi: its absolute level is
    # information, which prior_level="prior" keeps (the default takes only its shape: seed 1 then
    # gives 4.56 dB, behind the prior alone's 4.51 and SH-7's 4.48; seeds 0-5 average 4.45 against
    # 4.39 dB with the prior's level, benchmarks and tests/models/test_level_free.py)
    with_prior, _ = fit_auto(per_unit, options=FitOptions(auto=True, priors={n: prior for n in prior.nodes}, prior_level="prior"))
    got = rmse(with_prior.model, test)
    others = {
        "prior alone": rmse(prior, test),
        "k-NN": rmse(fit_model(learn, ModelSpec("knn", 400)).model, test, ModelSpec("knn", 400)),
        "unregularised SH-7": rmse(fit_model(learn, ModelSpec("sh", 7)).model, test),
        "unregularised SH-10": rmse(fit_model(learn, ModelSpec("sh", 10)).model, test),
    }
    assert all(got < v for v in others.values()), (got, others)
    without_prior, _ = auto_fit("ground", seed)  # fit_auto(per_unit), once per process
    mean = rmse(fit_model(learn, ModelSpec("mean")).model, test, ModelSpec("mean"))
    assert rmse(without_prior.model, test) <= mean


def _cli(*args: str):
    """``rplearn ARGS`` in this process (typer's ``CliRunner``; the process boundary is not what
    these checks are about): its exit code, stdout and stderr apart."""
    from typer.testing import CliRunner

    from rplearn.cli import app

    return CliRunner().invoke(app, list(args), env={"COLUMNS": "400"})


def test_fit_cli_takes_a_prior_per_node(tmp_path, monkeypatch):
    per_unit, _, _, _ = ground_case(tmp_path, 1)
    monkeypatch.chdir(tmp_path)
    proc = _cli("reference", "G=ref_G.csv", "D=ref_D.csv", "-o", "ref.json")
    assert proc.exit_code == 0, proc.output
    proc = _cli("fit", "m.parquet", "--prior", "G=ref.json", "--prior", "D=ref.json", "-o", "p.json")
    assert proc.exit_code == 0 and "chosen by grouped cross-validation" in proc.stdout, proc.output
    from rplearn.models import load_model

    assert set(load_model(tmp_path / "p.json").training["prior"]) == {"G", "D"}
    assert "where the flight never looked each pattern may be off by" in proc.stdout and "x" in proc.stdout
    proc = _cli("fit", "m.parquet", "--prior", "G=ref.json", "--prior", "D=ref.json", "--prior-std", "4", "-o", "s.json")
    assert proc.exit_code == 0 and "G 4.0 dB, D 4.0 dB" in proc.stdout.replace("D 4.0 dB, G 4.0 dB", "G 4.0 dB, D 4.0 dB"), proc.stdout
    stated = load_model(tmp_path / "s.json").training
    assert stated["prior_std_source"] == "stated" and stated["prior_std_db"]["G"] == pytest.approx(4.0)
    proc = _cli("fit", "m.parquet", "--prior-std", "4", "-o", "y.json")
    assert proc.exit_code == 1 and "give --prior too" in proc.stderr, proc.output
    assert load_model(tmp_path / "p.json").training["prior_level"] == "data"  # the prior gives its shape
    proc = _cli("fit", "m.parquet", "--prior", "G=ref.json", "--prior", "D=ref.json", "--prior-level", "prior", "-o", "a.json")
    assert proc.exit_code == 0 and load_model(tmp_path / "a.json").training["prior_level"] == "prior", proc.output
    proc = _cli("fit", "m.parquet", "--prior-level", "prior", "-o", "z.json")
    assert proc.exit_code == 1 and "--prior-level" in proc.stderr and "give --prior too" in proc.stderr, proc.output
    proc = _cli("fit", "m.parquet", "--prior", "X=ref.json", "-o", "x.json")
    assert proc.exit_code == 1 and "prior: node X is not in the learning data" in proc.stderr, proc.output


def test_predictions_say_where_the_flight_never_looked(tmp_path):
    """Coverage columns and a warning from predict; the Bayesian spread grows away from the data."""
    _, learn, test, _ = ground_case(tmp_path, 3)
    fitted, _ = auto_fit("ground", 3)  # fit_auto of the learning units, once per process
    import pandas as pd

    from rplearn.models.predict import UNCOVERED_DEG, predict_dataset

    df = read_dataset(str(tmp_path / "m.parquet"))
    pred = predict_dataset(fitted.model, df[df["unit"].str.startswith("test")])
    cov = pred.table[["tx_coverage_deg", "rx_coverage_deg"]].to_numpy().max(axis=1)
    assert pred.n_uncovered == int((cov > UNCOVERED_DEG).sum()) > 0 and "fly those directions" in pred.warnings[0]
    # far from every learning direction (the sky above the station, behind the drone) the spread is larger
    import numpy as np

    from rplearn.core.geometry import Directions
    from rplearn.data.tables import LinkSamples

    near = Directions(*(np.asarray(a)[:200] for a in learn.directions))
    far = Directions(np.full(200, np.pi), np.full(200, 1.2), np.full(200, np.pi), np.full(200, 1.2))
    std = {name: fitted.model.predict_gain_std(LinkSamples(d, learn.tx_index[:200], learn.rx_index[:200], learn.nodes,
                                                           np.zeros(200), np.full(200, 40.0)))
           for name, d in (("near", near), ("far", far))}
    assert np.median(std["far"]) > 3 * np.median(std["near"]), {k: float(np.median(v)) for k, v in std.items()}
    assert isinstance(pred.table, pd.DataFrame)


def test_orient_cautions_when_the_best_heading_looks_where_the_flight_never_did():
    from rplearn.analysis.headings import YawOptions, best_yaw

    model = auto_fit("ground", 4)[0].model  # fit_auto of the learning units, once per process
    # the station kept at its flown heading (10 deg), a drone on the flown arc: the station end is covered
    seen = best_yaw(model, "G", "D", (0.0, 0.0, 1.5), (40.0, 7.0, 20.0), turn="rx", options=YawOptions(tx_yaw_deg=10.0))
    assert seen.coverage_deg is not None and seen.coverage_deg[0] < 10
    # a drone behind the station and high up: nothing like it was flown
    unseen = best_yaw(model, "G", "D", (0.0, 0.0, 1.5), (-40.0, 0.0, 60.0), turn="tx")
    assert max(unseen.coverage_deg) > 30 and "fly those directions" in unseen.summary()


def test_swarm_links_carry_their_coverage(tmp_path):
    import pandas as pd

    from rplearn.analysis.swarm import SwarmOptions, predict_swarm

    ground_case(tmp_path, 5)
    model = auto_fit("ground", 5)[0].model  # fit_auto of the learning units, once per process
    poses = pd.read_parquet(tmp_path / "f" / "pose_log.parquet")
    far = poses.assign(x=poses["x"] * -1.0)  # the drone flown behind the station: never learned
    seen, unseen = (predict_swarm(model, p, 20.0, SwarmOptions(step_s=5.0)) for p in (poses, far))
    for pred in (seen, unseen):
        assert {"tx_coverage_deg", "rx_coverage_deg"} <= set(pred.links.columns)
    assert (seen.links[["tx_coverage_deg", "rx_coverage_deg"]].max(axis=1) <= 10).mean() > 0.8
    assert any("more than 10 deg from any direction" in n for n in unseen.notes)


def test_orient_prefers_headings_the_flight_saw():
    """Ranked by the 10% lower bound, the chosen headings face directions nearer the flown ones
    and are surer than the headings the prediction alone picks, for little predicted gain."""
    import numpy as np

    from rplearn.analysis.headings import YawOptions, best_yaw

    model = auto_fit("ground", 4)[0].model  # fit_auto of the learning units, once per process
    rng = np.random.default_rng(0)
    nearer = surer = 0
    lost = []
    for _ in range(20):
        drone = (rng.uniform(-60, 60), rng.uniform(-60, 60), rng.uniform(10, 60))
        bold = best_yaw(model, "G", "D", (0.0, 0.0, 1.5), drone, turn="tx", options=YawOptions(caution_z=0.0))
        safe = best_yaw(model, "G", "D", (0.0, 0.0, 1.5), drone, turn="tx")
        nearer += safe.coverage_deg[0] <= bold.coverage_deg[0]
        surer += safe.gain_std_db <= bold.gain_std_db + 1e-9
        lost.append(bold.gain_db - safe.gain_db)
    assert nearer >= 18 and surer == 20, (nearer, surer)
    assert 0 <= np.median(lost) < 1.0, lost
    with pytest.raises(Exception, match="caution_z"):
        best_yaw(model, "G", "D", (0.0, 0.0, 1.5), (30.0, 0.0, 20.0), options=YawOptions(caution_z=-1.0))
