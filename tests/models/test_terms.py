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
from rplearn.models.options import FitOptions
from rplearn.models.patterns import PatternSet
from rplearn.models.predict import predict_dataset
from rplearn.sim import simulate
from rplearn.sim.presets import PATHLOSS_EXPONENT, make_preset


def _campaign(config, seed=1, link=None):
    sim = simulate(config, seed=seed)
    ds = synchronise(sim.pose_log, sim.signal_log, SyncOptions(link=link)).dataset
    return sim, ds[ds["unit"].str.startswith("learn")], ds[ds["unit"].str.startswith("test")]


def _units(learn, nodes):
    return {u: link_samples(g, nodes=nodes) for u, g in learn.groupby("unit")}


def _auto(learn, nodes, units=None, **kw):
    """The automatic fit of ``learn``'s units (``units``: their samples, when already read)."""
    return fit_auto(units or _units(learn, nodes), options=FitOptions(auto=True, **kw))[0].model


def _rmse(model, part, nodes):
    return _rmse_of(model, link_samples(part, nodes=nodes))


def _rmse_of(model, s):
    return float(np.sqrt(np.mean((model.predict_gain(s) - s.joint_gain_db) ** 2)))


class _TruthAt:
    """A true pattern set evaluated once at fixed directions per node: what
    :func:`pattern_errors_db` reads of it, for several models compared on the same directions."""

    def __init__(self, truth, directions):
        self._directions = directions
        self._values = {node: np.asarray(truth.evaluate(node, az, el)) for node, (az, el) in directions.items()}

    def evaluate(self, node, az, el):
        assert az is self._directions[node][0] and el is self._directions[node][1]
        return self._values[node]


@pytest.fixture(scope="module")
def pathloss():
    return _campaign("pathloss", link=("A", "B"))


@pytest.mark.slow
def test_log_distance_exponent_and_patterns_are_recovered(pathloss):
    """Acceptance 1: exponent 3 within 0.1; patterns within 0.5 dB of the free-space case's."""
    sim, learn, test = pathloss
    nodes = ("A", "B")
    units = _units(learn, nodes)  # read once: learned with and without the exponent
    model = _auto(learn, nodes, units, path_loss=PathLoss("log-distance"))
    exponent, se = model.path_loss_exponent
    assert abs(exponent - PATHLOSS_EXPONENT) < 0.1
    assert 0 < se < 0.1
    covered = node_directions(link_samples(learn, nodes=nodes))
    errors = pattern_errors_db(model, sim.ground_truth, covered)
    free_config = make_preset("pathloss")
    free_config = replace(free_config, radio=replace(free_config.radio, path_loss_exponent=2.0))
    # its learning units only: each unit draws from its own seed, so their rows are those of the
    # whole campaign (A 0.947 / B 0.958 dB either way); the testing unit was never read
    learning = tuple(u for u in free_config.campaign.units if u.role == "learning")
    free_config = replace(free_config, campaign=replace(free_config.campaign, units=learning))
    fsim, flearn, _ = _campaign(free_config, link=("A", "B"))
    reference = pattern_errors_db(_auto(flearn, nodes), fsim.ground_truth, node_directions(link_samples(flearn, nodes=nodes)))
    for node in nodes:
        assert errors[node] <= reference[node] + 0.5, (errors, reference)
    # free space on the exponent-3 flight: a worse test fit
    free = _auto(learn, nodes, units)
    assert _rmse(model, test, nodes) < _rmse(free, test, nodes)


@pytest.mark.slow
def test_exponent_at_constant_distance_is_refused():
    """Acceptance 1: the paper's circles at 10 m, in an exponent-3 channel. Its three learning
    units at 2 headings each, not 5, and no testing unit (its rows were never read): the distance
    spans 9.62-10.5 m and the part the directions leave varies by 0.07 / 0.05 dB (fixed / auto),
    against 9.57-10.4 m and 0.08 / 0.07 dB for the whole campaign; 0.5 dB is needed."""
    config = make_preset("paper")
    learning = tuple(replace(u, n_loops=2) for u in config.campaign.units if u.role == "learning")
    config = replace(config, campaign=replace(config.campaign, units=learning),
                     radio=replace(config.radio, path_loss_exponent=3.0))
    _, learn, _ = _campaign(config, link=("A", "B"))
    samples = link_samples(learn)
    with pytest.raises(IdentifiabilityError, match="path-loss exponent is not identifiable"):
        fit_model(samples, ModelSpec.parse("sh-8"), FitOptions(path_loss=PathLoss("log-distance")))
    with pytest.raises(IdentifiabilityError, match="path-loss exponent is not identifiable"):
        _auto(learn, samples.nodes, path_loss=PathLoss("log-distance"))


@pytest.mark.slow
def test_two_ray_predicts_a_low_link_better_than_free_space():
    """Acceptance 1: drones at 5-10 m over flat ground."""
    sim, learn, test = _campaign("tworay", link=("G", "D"))
    nodes = ("D", "G")
    units = _units(learn, nodes)
    two_ray = _auto(learn, nodes, units, path_loss=PathLoss("two-ray"))
    free = _auto(learn, nodes, units)
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
    learning each alone, and a pattern error no higher."""
    sim, learn, test = duplex
    nodes = ("A", "B")
    units = _units(learn, nodes)  # read once: both directions with and without offsets
    both = _auto(learn, nodes, units)
    offsets = both.link_offsets_db()
    assert offsets[("A", "B")][0] == pytest.approx(2.5, abs=0.2)
    assert offsets[("B", "A")][0] == pytest.approx(-2.5, abs=0.2)
    assert offsets[("A", "B")][0] - offsets[("B", "A")][0] == pytest.approx(5.0, abs=0.2)
    assert 0 < offsets[("A", "B")][1] < 0.1
    assert both.n_params == both.coef.size + 1  # the offset counts in |phi| and the AIC
    covered = node_directions(link_samples(learn, nodes=nodes))
    truth = _TruthAt(sim.ground_truth, covered)  # the same directions for the three models
    err_both = pattern_errors_db(both, truth, covered)
    parts = {tx: link_samples(test[test["tx"] == tx], nodes=nodes) for tx in nodes}
    for tx in nodes:
        alone = _auto(learn[learn["tx"] == tx], nodes)
        assert alone.link_offsets_db() == {}
        assert _rmse_of(both, parts[tx]) <= _rmse_of(alone, parts[tx]) + 0.01
        err_alone = pattern_errors_db(alone, truth, covered)
        # no worse: since the selection keeps the least smoothing within noise (issue 24, item 5)
        # the A->B link alone reaches the same split (1.464 against 1.466 dB; 1.618 before)
        assert all(err_both[n] <= err_alone[n] + 0.02 for n in nodes), (err_both, err_alone)  # level-free: 0.010 dB apart
    # without offsets both directions are taken as reciprocal: a worse fit of each
    plain = _auto(learn, nodes, units, link_offsets=False)
    for tx in nodes:
        assert _rmse_of(both, parts[tx]) < _rmse_of(plain, parts[tx]) - 0.3


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
    for shared in ({"offset:A->Z": 1.0}, {"offset:A->A": 1.0}, {"offset:A->B": 1.0, "offset:B->A": -1.0}):
        bad = model.to_dict()
        bad.pop("covariance")
        bad["shared"] = shared
        with pytest.raises(ModelFileError, match="offset"):
            PatternSet.from_dict(bad)
    bad = model.to_dict()
    bad["path_loss"] = "log-distance"
    with pytest.raises(ModelFileError, match="path loss"):
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
        fit_model(link_samples(ds), ModelSpec.parse("m"), FitOptions(path_loss=PathLoss("log-distance")))


@pytest.mark.slow
def test_units_that_each_fly_one_direction_cross_validate_like_reciprocal_ones(duplex):
    """A fold whose learning units lack a direction cannot identify that link's offset: it is
    pinned to the whole-data estimate, so the held-out unit is not charged a made-up error
    (review of issue 12: SH-9 and an inflation of 15 instead of SH-15 and 2.3)."""
    _, learn, test = duplex
    nodes = ("A", "B")
    units = sorted(learn["unit"].unique())
    one_way = learn[((learn["unit"] == units[0]) & (learn["tx"] == "A")) |
                    ((learn["unit"] != units[0]) & (learn["tx"] == "B"))]
    parts = {u: link_samples(g, nodes=nodes) for u, g in one_way.groupby("unit")}
    fitted, selection = fit_auto(parts)
    reference = fit_auto({u: link_samples(g[g["tx"] == "B"], nodes=nodes) for u, g in learn.groupby("unit")})[1]
    assert fitted.model.shared_names == ("offset:A->B",)
    assert selection.rmse_db < reference.rmse_db + 0.3, (selection.rmse_db, reference.rmse_db)
    assert selection.variance_inflation < 2 * reference.variance_inflation + 1


def test_node_ids_with_arrows_and_offsets():
    rng = np.random.default_rng(7)
    from rplearn.core.bases import make_basis
    from rplearn.core.geometry import Directions
    from rplearn.data.tables import LinkSamples

    basis = make_basis("sh", 3)
    n = 3000
    az, el = rng.uniform(-np.pi, np.pi, (2, n)), rng.uniform(-1.4, 1.4, (2, n))
    tx = rng.integers(0, 2, n)
    rx = 1 - tx
    nodes = ("uav->1", "uav->2")
    y = rng.normal(size=n) + np.where(tx == 0, 1.0, -1.0)
    samples = LinkSamples(Directions(az[0], el[0], az[1], el[1]), tx, rx, nodes, y, np.full(n, 10.0))
    model = fit_model(samples, ModelSpec.parse("sh-3")).model
    assert model.shared_names == ("offset:uav->1->uav->2",)
    assert model.link_offsets_db()[("uav->1", "uav->2")][0] == pytest.approx(1.0, abs=0.1)
    again = PatternSet.from_dict(json.loads(json.dumps(model.to_dict())))
    np.testing.assert_allclose(again.predict_gain(samples), model.predict_gain(samples))
    del basis


def test_ridge_does_not_shrink_the_offsets():
    """Exact data, few samples, the paper's ridge of 50: the offset is not pulled toward 0."""
    from rplearn.core.geometry import Directions
    from rplearn.data.tables import LinkSamples

    rng = np.random.default_rng(8)
    n = 40
    az, el = rng.uniform(-np.pi, np.pi, (2, n)), rng.uniform(-1.4, 1.4, (2, n))
    tx = np.repeat([0, 1], n // 2)
    samples = LinkSamples(Directions(az[0], el[0], az[1], el[1]), tx, 1 - tx, ("A", "B"),
                          np.where(tx == 0, 2.0, -2.0), np.full(n, 10.0))
    model = fit_model(samples, ModelSpec.parse("sh-2", ridge=50.0)).model
    assert model.link_offsets_db()[("A", "B")][0] == pytest.approx(2.0, abs=1e-6)


def test_two_ray_rows_below_the_ground_are_not_predicted_and_said_so():
    sim, learn, test = _campaign("tworay", link=("G", "D"))
    nodes = ("D", "G")
    model = fit_model(link_samples(learn, nodes=nodes), ModelSpec.parse("sh-4"), FitOptions(path_loss=PathLoss("two-ray"))).model
    low = test.copy()
    low.loc[low.index[:5], "rx_z"] = 0.0
    out = predict_dataset(model, low)
    assert int(np.isnan(out.table["gain_pred_db"]).sum()) == 5
    assert np.isfinite(out.rmse_db)
    assert any("5 of" in n and "ground level" in n for n in out.notes)
    from rplearn.models.fit import FittedModel, evaluate_models

    notes: list[str] = []
    rows = evaluate_models([FittedModel.from_model(model)], link_samples(low, nodes=nodes), notes)
    assert np.isfinite(rows[0].rmse_db) and any("5 of" in n for n in notes)


def test_estimator_takes_link_offsets_as_a_hyper_parameter():
    from rplearn.models.estimators import PatternRegressor

    rng = np.random.default_rng(9)
    n = 2000
    X = np.column_stack([rng.uniform(-np.pi, np.pi, n), rng.uniform(-1.4, 1.4, n), rng.uniform(-np.pi, np.pi, n),
                         rng.uniform(-1.4, 1.4, n), rng.integers(0, 2, n)])
    X = np.column_stack([X, 1 - X[:, 4]])
    y = rng.normal(size=n) + np.where(X[:, 4] == 0, 1.0, -1.0)
    plain = PatternRegressor(order=3).fit(X, y)
    assert plain.get_params()["link_offsets"] is False and plain.patterns_.shared_names == ()
    with_offsets = PatternRegressor(order=3, link_offsets=True).fit(X, y)
    assert with_offsets.n_params_ == plain.n_params_ + 1
