"""Environment term and link offsets learned with the patterns (issue 12, items 1 and 2)."""

from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pytest

from rplearn.analysis.pattern_error import node_directions, pattern_errors_db
from rplearn.core.environment import PathLoss
from rplearn.data.sync import SyncOptions, synchronise
from rplearn.data.tables import link_samples
from rplearn.errors import IdentifiabilityError, InputError, ModelFileError
from rplearn.models import ModelSpec
from rplearn.models.auto import fit_auto
from rplearn.models.fit import fit_model
from rplearn.models.patterns import PatternSet
from rplearn.models.predict import predict_dataset
from rplearn.sim import simulate
from rplearn.sim.presets import PATHLOSS_EXPONENT, make_preset


def _campaign(config, seed=1, link=None):
    sim = simulate(config, seed=seed)
    ds = synchronise(sim.pose_log, sim.signal_log, SyncOptions(link=link)).dataset
    return sim, ds[ds["unit"].str.startswith("learn")], ds[ds["unit"].str.startswith("test")]


def _auto(learn, nodes, **kw):
    units = {u: link_samples(g, nodes=nodes) for u, g in learn.groupby("unit")}
    return fit_auto(units, **kw)[0].model


def _rmse(model, part, nodes):
    s = link_samples(part, nodes=nodes)
    return float(np.sqrt(np.mean((model.predict_gain(s) - s.joint_gain_db) ** 2)))


@pytest.fixture(scope="module")
def pathloss():
    return _campaign("pathloss", link=("A", "B"))


@pytest.mark.slow
def test_log_distance_exponent_and_patterns_are_recovered(pathloss):
    """Acceptance 1: exponent 3 within 0.1; patterns within 0.5 dB of the free-space case's."""
    sim, learn, test = pathloss
    nodes = ("A", "B")
    model = _auto(learn, nodes, path_loss=PathLoss("log-distance"))
    exponent, se = model.path_loss_exponent
    assert abs(exponent - PATHLOSS_EXPONENT) < 0.1
    assert 0 < se < 0.1
    covered = node_directions(link_samples(learn, nodes=nodes))
    errors = pattern_errors_db(model, sim.ground_truth, covered)
    free_config = make_preset("pathloss")
    free_config = replace(free_config, radio=replace(free_config.radio, path_loss_exponent=2.0))
    fsim, flearn, _ = _campaign(free_config, link=("A", "B"))
    reference = pattern_errors_db(_auto(flearn, nodes), fsim.ground_truth, node_directions(link_samples(flearn, nodes=nodes)))
    for node in nodes:
        assert errors[node] <= reference[node] + 0.5, (errors, reference)
    # free space on the exponent-3 flight: a worse test fit
    free = _auto(learn, nodes)
    assert _rmse(model, test, nodes) < _rmse(free, test, nodes)


@pytest.mark.slow
def test_exponent_at_constant_distance_is_refused():
    """Acceptance 1: the paper's circles at 10 m, in an exponent-3 channel."""
    config = make_preset("paper")
    config = replace(config, radio=replace(config.radio, path_loss_exponent=3.0))
    _, learn, _ = _campaign(config, link=("A", "B"))
    samples = link_samples(learn)
    with pytest.raises(IdentifiabilityError, match="path-loss exponent is not identifiable"):
        fit_model(samples, ModelSpec.parse("sh-8"), path_loss=PathLoss("log-distance"))
    with pytest.raises(IdentifiabilityError, match="path-loss exponent is not identifiable"):
        _auto(learn, samples.nodes, path_loss=PathLoss("log-distance"))


@pytest.mark.slow
def test_two_ray_predicts_a_low_link_better_than_free_space():
    """Acceptance 1: drones at 5-10 m over flat ground."""
    sim, learn, test = _campaign("tworay", link=("G", "D"))
    nodes = ("D", "G")
    two_ray = _auto(learn, nodes, path_loss=PathLoss("two-ray"))
    free = _auto(learn, nodes)
    assert _rmse(two_ray, test, nodes) < _rmse(free, test, nodes) - 0.1
    # the term is part of the prediction, and of the model file
    s = link_samples(test, nodes=nodes)
    known = PathLoss("two-ray").known_db(s.distance_m, s.tx_z_m, s.rx_z_m, s.frequency_hz)
    base = replace(two_ray, path_loss=PathLoss())
    np.testing.assert_allclose(two_ray.predict_gain(s) - base.predict_gain(s), known, atol=1e-9)
    again = PatternSet.from_dict(json.loads(json.dumps(two_ray.to_dict())))
    assert again.path_loss == PathLoss("two-ray")


@pytest.fixture(scope="module")
def duplex():
    config = make_preset("paper")
    config = replace(config, radio=replace(config.radio, link_offsets_db=((("A", "B"), 3.0), (("B", "A"), -2.0))))
    return _campaign(config)


@pytest.mark.slow
def test_both_directions_with_offsets(duplex):
    """Acceptance 2: offsets +3 / -2 dB recovered (as the gauge sees them: +2.5 / -2.5, their
    common +0.5 dB in the joint level) within 0.2 dB; both directions' test RMSE no worse than
    learning each alone, and a lower pattern error."""
    sim, learn, test = duplex
    nodes = ("A", "B")
    both = _auto(learn, nodes)
    offsets = both.link_offsets_db()
    assert offsets["A->B"][0] == pytest.approx(2.5, abs=0.2)
    assert offsets["B->A"][0] == pytest.approx(-2.5, abs=0.2)
    assert offsets["A->B"][0] - offsets["B->A"][0] == pytest.approx(5.0, abs=0.2)
    assert 0 < offsets["A->B"][1] < 0.1
    covered = node_directions(link_samples(learn, nodes=nodes))
    err_both = pattern_errors_db(both, sim.ground_truth, covered)
    for tx in nodes:
        alone = _auto(learn[learn["tx"] == tx], nodes)
        assert alone.link_offsets_db() == {}
        part = test[test["tx"] == tx]
        assert _rmse(both, part, nodes) <= _rmse(alone, part, nodes) + 0.01
        err_alone = pattern_errors_db(alone, sim.ground_truth, covered)
        assert all(err_both[n] < err_alone[n] for n in nodes), (err_both, err_alone)
    # without offsets both directions are taken as reciprocal: a worse fit of each
    plain = _auto(learn, nodes, link_offsets=False)
    for tx in nodes:
        part = test[test["tx"] == tx]
        assert _rmse(both, part, nodes) < _rmse(plain, part, nodes) - 0.3


@pytest.mark.slow
def test_offsets_are_stored_applied_and_have_a_spread(duplex, tmp_path):
    _, learn, test = duplex
    samples = link_samples(learn)
    model = fit_model(samples, ModelSpec.parse("sh-6")).model
    path = tmp_path / "m.json"
    model.save(path)
    again = PatternSet.load(path)
    assert again.shared_names == ("offset:A->B",)
    for key, (value, se) in model.link_offsets_db().items():
        assert again.link_offsets_db()[key] == pytest.approx((value, se))
    t = link_samples(test, nodes=samples.nodes)
    np.testing.assert_allclose(again.predict_gain(t), model.predict_gain(t))
    # the offset is the difference between the two directions at the same geometry
    flipped = replace(t, tx_index=t.rx_index, rx_index=t.tx_index,
                      directions=type(t.directions)(t.directions.az_rx, t.directions.el_rx, t.directions.az_tx, t.directions.el_tx))
    np.testing.assert_allclose(model.predict_gain(t) - model.predict_gain(flipped),
                               2 * model.shared_coef[0] * np.where(t.tx_index == 0, 1.0, -1.0), atol=1e-9)
    std = model.predict_gain_std(t)
    assert np.all(np.isfinite(std)) and np.all(std > 0)
    # a tampered covariance of the wrong size is refused
    payload = model.to_dict()
    payload["covariance"] = np.asarray(payload["covariance"])[:-1, :-1].tolist()
    with pytest.raises(ModelFileError, match="covariance"):
        PatternSet.from_dict(payload)
    bad = model.to_dict()
    bad["shared"] = {"offset:A->Z": 1.0}
    with pytest.raises(ModelFileError, match="offset"):
        PatternSet.from_dict(bad)
    # a link direction the model never learned is predicted at offset 0, and said so
    one_way = fit_model(link_samples(learn[learn["tx"] == "A"]), ModelSpec.parse("sh-6")).model
    out = predict_dataset(one_way, test)
    assert any("B->A" in n and "never learned" in n for n in out.notes)
    assert predict_dataset(model, test).notes == ()


def test_baselines_take_no_environment_term():
    from rplearn.sim.flight import simulate as sim_

    sim = sim_("smoke", seed=0)
    ds = synchronise(sim.pose_log, sim.signal_log, SyncOptions(link=("A", "B"))).dataset
    with pytest.raises(InputError, match="baselines"):
        fit_model(link_samples(ds), ModelSpec.parse("m"), path_loss=PathLoss("log-distance"))
