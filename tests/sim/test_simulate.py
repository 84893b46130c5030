"""Flight simulator: schemas, determinism, every effect switched on/off, and the paper preset."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pandas as pd
import pytest

from rplearn.core.geometry import euler_from_quat_wxyz
from rplearn.data.tables import MATCHED_COLUMNS, POSE_COLUMNS, SIGNAL_COLUMNS, link_samples, validate_pose_log, validate_signal_log
from rplearn.errors import InputError
from rplearn.io.files import read_table
from rplearn.sim.antennas import load_ground_truth
from rplearn.sim.config import EstimatorConfig, FlightConfig, RadioConfig, SimulationConfig
from rplearn.sim.flight import ou_process, simulate, with_effects_off
from rplearn.sim.noise import AR1_LOOP_MAX_SAMPLES, ar1_filter
from rplearn.sim.presets import PRESET_NAMES, make_preset


@pytest.fixture(scope="module")
def smoke():
    return simulate("smoke", seed=7)


def _residual_db(result, df: pd.DataFrame | None = None, include_offset: bool = True) -> np.ndarray:
    """Observed joint gain (eq. 5, true poses) minus the true joint gain [dB]."""
    df = result.matched_truth if df is None else df
    out = np.empty(len(df))
    for (tx, rx), idx in df.groupby(["tx", "rx"]).indices.items():
        s = link_samples(df.iloc[idx])
        d = s.directions
        pred = result.ground_truth.predict_joint_gain_db(
            tx, rx, d.az_tx, d.el_tx, d.az_rx, d.el_rx, include_link_offset=include_offset
        )
        out[idx] = s.joint_gain_db - pred
    return out


def test_smoke_logs_are_canonical(smoke) -> None:
    assert list(smoke.pose_log.columns) == list(POSE_COLUMNS)
    assert list(smoke.signal_log.columns) == list(SIGNAL_COLUMNS) + ["unit"]
    assert list(smoke.matched_truth.columns) == list(MATCHED_COLUMNS) + ["unit"]
    validate_pose_log(smoke.pose_log)
    validate_signal_log(smoke.signal_log)
    assert set(smoke.signal_log["unit"]) == {"learn_0", "test_90"}
    assert 1000 < len(smoke.signal_log) < 5000  # seconds long: a few thousand packets at most
    assert set(smoke.ground_truth.nodes) == {"A", "B"}
    rssi = smoke.signal_log["rssi_dbm"].to_numpy()
    assert np.all(rssi == np.round(rssi))
    np.testing.assert_array_equal(smoke.signal_log["t"], smoke.matched_truth["t"])
    assert np.all(np.diff(smoke.signal_log["t"].to_numpy()) >= 0)


def test_smoke_rates(smoke) -> None:
    cfg = smoke.config
    flown = sum(u.duration_s for u in cfg.campaign.units)
    for node, g in smoke.pose_log.groupby("node"):
        assert len(g) / flown == pytest.approx(cfg.estimator.pose_rate_hz, rel=0.02)
    for (tx, rx), g in smoke.signal_log.groupby(["tx", "rx"]):
        expected = cfg.radio.packet_rate_hz * (1 - cfg.radio.loss_probability)
        assert len(g) / flown == pytest.approx(expected, rel=0.1)


def test_deterministic_for_a_seed() -> None:
    a, b, c = simulate("smoke", seed=3), simulate("smoke", seed=3), simulate("smoke", seed=4)
    pd.testing.assert_frame_equal(a.signal_log, b.signal_log)
    pd.testing.assert_frame_equal(a.pose_log, b.pose_log)
    assert not a.signal_log["rssi_dbm"].equals(c.signal_log["rssi_dbm"]) or len(a.signal_log) != len(c.signal_log)


def test_written_files_load_back(tmp_path, smoke) -> None:
    res = simulate(smoke.config, seed=7, out_dir=str(tmp_path), log_format="csv")
    poses = read_table(res.paths["pose_log"])
    signals = read_table(res.paths["signal_log"])
    assert len(poses) == len(res.pose_log) and len(signals) == len(res.signal_log)
    assert "unit" in signals.columns
    gt = load_ground_truth(res.paths["ground_truth"])
    rng = np.random.default_rng(0)
    az, el = rng.uniform(-np.pi, np.pi, 300), rng.uniform(-1.5, 1.5, 300)
    for node in gt.nodes:
        np.testing.assert_array_equal(gt.evaluate(node, az, el), res.ground_truth.evaluate(node, az, el))
    refs = sorted(p.name for p in (tmp_path / "references").iterdir())
    assert refs == sorted(f"{u.label}_{n}.csv" for u in res.config.campaign.units for n in u.nodes)
    assert set(res.paths) == {"pose_log", "signal_log", "matched_truth", "ground_truth", "references"}


def test_everything_off_gives_the_exact_link_budget(smoke) -> None:
    ideal = simulate(with_effects_off(smoke.config), seed=1)
    assert ideal.noise_std_db == 0.0
    np.testing.assert_allclose(_residual_db(ideal), 0.0, atol=1e-9)
    assert ideal.realised_noise_std_db == pytest.approx(0.0, abs=1e-12)
    # exact estimates and perfect tracking: logged poses follow the references
    unit = ideal.config.campaign.units[0]
    log = ideal.pose_log[(ideal.pose_log.node == unit.nodes[1]) & (ideal.pose_log.t <= unit.duration_s)]
    ref = unit.evaluate(log["t"].to_numpy())
    np.testing.assert_allclose(log[["x", "y", "z"]].to_numpy(), ref.position_enu_m[:, 1], atol=2e-3)
    _, _, yaw = euler_from_quat_wxyz(log[["qw", "qx", "qy", "qz"]].to_numpy())
    np.testing.assert_allclose(np.angle(np.exp(1j * (yaw - ref.yaw_rad[:, 1]))), 0.0, atol=2e-3)


def test_fading_and_quantisation_set_the_noise_level(smoke) -> None:
    cfg = with_effects_off(smoke.config)
    for fading, quantize in ((2.0, False), (3.0, True), (0.0, True)):
        res = simulate(replace(cfg, radio=replace(cfg.radio, fading_std_db=fading, quantize=quantize)), seed=2)
        r = _residual_db(res)
        expected = np.sqrt(fading**2 + (1 / 12 if quantize else 0))
        assert res.noise_std_db == pytest.approx(expected)
        assert np.sqrt(np.mean(r**2)) == pytest.approx(expected, rel=0.06)
        assert res.realised_noise_std_db == pytest.approx(np.std(r), rel=1e-6, abs=1e-9)


def test_link_offsets_are_per_direction(smoke) -> None:
    cfg = with_effects_off(smoke.config)
    offsets = ((("A", "B"), 2.0), (("B", "A"), -3.0))
    res = simulate(replace(cfg, radio=replace(cfg.radio, link_offsets_db=offsets)), seed=2)
    r = _residual_db(res, include_offset=False)
    for (tx, rx), v in offsets:
        sel = ((res.matched_truth.tx == tx) & (res.matched_truth.rx == rx)).to_numpy()
        np.testing.assert_allclose(r[sel], v, atol=1e-9)
    assert res.ground_truth.link_offset_db("A", "B") == 2.0


def test_sensitivity_floor_and_saturation_plateau(smoke) -> None:
    cfg = with_effects_off(smoke.config)
    base = simulate(cfg, seed=2).signal_log["rssi_dbm"]
    lo, hi = np.percentile(base, [30, 70])
    res = simulate(replace(cfg, radio=replace(cfg.radio, sensitivity_dbm=float(lo), saturation_dbm=float(hi))), seed=2)
    rssi = res.signal_log["rssi_dbm"].to_numpy()
    assert rssi.min() >= lo and rssi.max() <= hi
    assert np.mean(rssi == hi) > 0.2  # a plateau, not a tail
    assert len(res.signal_log) == pytest.approx(0.7 * len(base), rel=0.05)  # no packet below the floor


def test_loss_and_dropouts(smoke) -> None:
    cfg = with_effects_off(smoke.config)
    n0 = len(simulate(cfg, seed=2).signal_log)
    lossy = simulate(replace(cfg, radio=replace(cfg.radio, loss_probability=0.25)), seed=2)
    assert len(lossy.signal_log) / n0 == pytest.approx(0.75, abs=0.04)
    drop = simulate(replace(cfg, radio=replace(cfg.radio, dropouts=1, dropout_duration_s=3.0)), seed=2)
    for _, g in drop.signal_log.groupby(["tx", "rx"]):
        gaps = np.diff(g["t"].to_numpy())
        within_unit = gaps < cfg.campaign.gap_s
        assert gaps[within_unit].max() >= 3.0 - 2.0 / cfg.radio.packet_rate_hz


def test_packet_jitter_spreads_intervals(smoke) -> None:
    cfg = with_effects_off(smoke.config)
    steady = simulate(cfg, seed=2).signal_log
    jittery = simulate(replace(cfg, radio=replace(cfg.radio, packet_jitter=0.3)), seed=2).signal_log
    for log, lo, hi in ((steady, 0.0, 1e-6), (jittery, 0.2, 0.4)):
        g = log[(log.tx == "A") & (log.unit == "learn_0")]
        dt = np.diff(g["t"].to_numpy())
        assert lo <= np.std(dt) * cfg.radio.packet_rate_hz <= hi


def _tilt_deg(df: pd.DataFrame, prefix: str = "") -> np.ndarray:
    q = df[[f"{prefix}q{c}" for c in "wxyz"]].to_numpy()
    roll, pitch, _ = euler_from_quat_wxyz(q)
    return np.degrees(np.arccos(np.cos(roll) * np.cos(pitch)))


def test_wind_tilts_the_drones_and_estimates_are_noisy(smoke) -> None:
    cfg = with_effects_off(smoke.config)
    calm = simulate(cfg, seed=2)
    windy_cfg = replace(cfg, flight=replace(cfg.flight, wind_speed_m_s=10.0, drag_per_m=0.021))
    windy = simulate(windy_cfg, seed=2)
    # steady 10 m/s wind: tilt about atan(c v^2 / g) = atan(2.1 / 9.81) = 12 deg (plus the
    # small tilt of the circle's own acceleration)
    expected = np.degrees(np.arctan(0.021 * 100 / 9.80665))
    unit = cfg.campaign.units[0]
    for log, tilt in ((windy.pose_log, expected), (calm.pose_log, 0.0)):
        a = log[(log.node == "A") & (log.t <= unit.duration_s)]
        ref = unit.evaluate(a["t"].to_numpy())
        hover = (np.linalg.norm(ref.velocity_enu_m_s[:, 0], axis=1) == 0) & (
            np.linalg.norm(ref.accel_enu_m_s2[:, 0], axis=1) == 0
        )
        assert hover.sum() > 100
        np.testing.assert_allclose(_tilt_deg(a[hover]), tilt, atol=0.05)
    assert np.median(_tilt_deg(windy.pose_log)) > np.median(_tilt_deg(calm.pose_log)) + 5.0
    noisy_cfg = replace(
        cfg,
        estimator=replace(cfg.estimator, horizontal_noise_std_m=0.02, vertical_noise_std_m=0.03, yaw_noise_std_deg=3.0),
        flight=replace(cfg.flight, tracking_std_m=0.2),
    )
    noisy = simulate(noisy_cfg, seed=2)
    # pose estimates differ from the truth at the same instants by the estimator's noise
    a = calm.pose_log[calm.pose_log.node == "A"]
    b = noisy.pose_log[noisy.pose_log.node == "A"]
    np.testing.assert_array_equal(a["t"], b["t"])
    err = np.hypot(a["x"].to_numpy() - b["x"].to_numpy(), a["y"].to_numpy() - b["y"].to_numpy())
    assert 0.05 < np.sqrt(np.mean(err**2)) < 0.6  # tracking error dominates RTK noise


def test_ou_process_statistics() -> None:
    rng = np.random.default_rng(0)
    x = ou_process(rng, 200_000, 0.01, 2.0, 0.5, dims=2)
    assert np.std(x) == pytest.approx(2.0, rel=0.05)
    lag = int(0.5 / 0.01)
    corr = np.corrcoef(x[:-lag, 0], x[lag:, 0])[0, 1]
    assert corr == pytest.approx(np.exp(-1), abs=0.05)
    assert not np.any(ou_process(rng, 10, 0.01, 0.0, 1.0))


@pytest.mark.parametrize(("a", "b"), [(0.0, 1.0), (0.37, 0.37), (float(np.exp(-0.005 / 30.0)), 2.5e3), (1.0, 1e-3)])
@pytest.mark.parametrize("n", [0, 1, 2, 1000, AR1_LOOP_MAX_SAMPLES // 2])
def test_ar1_filter_is_lfilter_bit_for_bit(n: int, a: float, b: float, monkeypatch) -> None:
    """The loop up to :data:`AR1_LOOP_MAX_SAMPLES` (two columns: the last size is the largest it
    takes) gives lfilter's numbers exactly, so a flight does not depend on which one ran."""
    import sys

    from scipy.signal import lfilter

    rng = np.random.default_rng(n)
    drive, before = rng.standard_normal((n, 2)), rng.standard_normal(2)
    ref = lfilter([b], [1.0, -a], drive, axis=0, zi=(a * before)[None, :])[0]
    monkeypatch.setitem(sys.modules, "scipy.signal", None)  # the loop ran, not lfilter
    assert np.array_equal(ar1_filter(drive, a, b, before), ref)


def test_ar1_filter_uses_lfilter_once_scipy_signal_is_imported(monkeypatch) -> None:
    """Once the process has imported ``scipy.signal``, even a short series is filtered by
    ``lfilter`` (about 40 times faster than the loop; the same numbers)."""
    import sys
    import types

    calls: list[int] = []

    def lfilter(b, a, x, axis, zi):
        calls.append(len(x))
        return np.zeros_like(x), zi

    monkeypatch.setitem(sys.modules, "scipy.signal", types.SimpleNamespace(lfilter=lfilter))
    ar1_filter(np.ones((10, 1)), 0.5, 1.0, np.zeros(1))
    assert calls == [10]


def test_a_smoke_flight_imports_no_signal_processing_library() -> None:
    """``scipy.signal`` (which pulls in ``scipy.stats``) costs about 1 s of CPU to import: the
    smoke flight's short series are filtered without it."""
    import subprocess
    import sys

    code = ("import sys; from rplearn.sim import simulate; simulate('smoke', seed=0); "
            "print([m for m in ('scipy.signal', 'scipy.stats') if m in sys.modules])")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0 and proc.stdout.strip().splitlines()[-1] == "[]", proc.stdout + proc.stderr


def test_bad_inputs() -> None:
    with pytest.raises(InputError, match="preset"):
        simulate("moon")
    with pytest.raises(InputError, match="preset_or_config"):
        simulate(42)  # type: ignore[arg-type]
    cfg = make_preset("smoke")
    with pytest.raises(InputError, match="node_antennas"):
        SimulationConfig("x", cfg.campaign, {"A": cfg.node_antennas["A"]})
    with pytest.raises(InputError, match="loss_probability"):
        replace(cfg, radio=RadioConfig(loss_probability=1.5))
    with pytest.raises(InputError, match="log_format"):
        simulate(cfg, out_dir="/tmp", log_format="xlsx")
    assert set(PRESET_NAMES) == {"paper", "trio", "smoke", "ground", "pathloss", "tworay", "campaign"}
    assert isinstance(cfg.flight, FlightConfig) and isinstance(cfg.estimator, EstimatorConfig)


def test_simulated_logs_synchronise_like_real_ones(smoke) -> None:
    sync = pytest.importorskip("rplearn.data.sync")
    out = sync.synchronise(smoke.pose_log, smoke.signal_log)
    ds = out.dataset
    assert len(ds) >= 0.98 * len(smoke.signal_log)
    merged = ds.merge(smoke.matched_truth, on=["t", "tx", "rx"], suffixes=("", "_true"))
    err = np.hypot(merged.tx_x - merged.tx_x_true, merged.tx_z - merged.tx_z_true)
    assert np.sqrt(np.mean(err**2)) < 0.1  # RTK-level position noise only


@pytest.mark.slow
def test_paper_preset_acceptance() -> None:
    """Paper preset: counts, truth RMSE = noise level (2%), baselines near the paper's."""
    from simulated_flights import simulated

    from rplearn.models.estimators import JointKNNRegressor, MeanRegressor

    _, res = simulated("paper", 0)  # simulate("paper", seed=0) with its files, once per process (shared)
    learn = res.matched("learning", "A", "B")
    test = res.matched("testing", "A", "B")
    assert len(learn) == pytest.approx(56_164, rel=0.03)
    assert len(test) == pytest.approx(24_087, rel=0.03)
    r = _residual_db(res, test)
    truth_rmse = float(np.sqrt(np.mean(r**2)))
    assert truth_rmse == pytest.approx(res.noise_std_db, rel=0.02)
    sl, st = link_samples(learn), link_samples(test)
    x_learn, x_test = np.column_stack(sl.directions), np.column_stack(st.directions)
    mean_rmse = float(np.sqrt(np.mean((MeanRegressor().fit(x_learn, sl.joint_gain_db).predict(x_test) - st.joint_gain_db) ** 2)))
    knn_pred = JointKNNRegressor(400).fit(x_learn, sl.joint_gain_db).predict(x_test)
    knn_rmse = float(np.sqrt(np.mean((knn_pred - st.joint_gain_db) ** 2)))
    assert 9.0 <= mean_rmse <= 13.0
    assert 4.0 <= knn_rmse <= 6.0
    assert knn_rmse > truth_rmse  # the truth is the best possible predictor
    # the flown (tilted, jittery) learning data decouple the patterns up to the one constant
    from rplearn.core.bases import make_basis
    from rplearn.core.lsq.solver import identifiability

    rep = identifiability(sl.directions, sl.tx_index, sl.rx_index, len(sl.nodes), make_basis("sh", 10))
    assert rep.rank == rep.n_columns - 1 == 199


def test_trio_preset_flies_a_triangle_of_different_antennas() -> None:
    cfg = make_preset("trio")
    kinds = {n: a.antenna.kind for n, a in cfg.node_antennas.items()}
    assert kinds == {"A": "itu_omni_average", "B": "itu_sectoral_peak", "C": "cosine_beam"}
    # a shortened triangle campaign (one short learning unit per pair) keeps the test fast
    short = tuple(
        replace(u, n_loops=2, speed_m_s=3.0, accel_m_s2=3.0) for u in cfg.campaign.units if u.psi0_deg == 0.0
    )
    res = simulate(replace(cfg, campaign=replace(cfg.campaign, units=short, gap_s=5.0)), seed=1)
    assert set(map(tuple, res.signal_log[["tx", "rx"]].drop_duplicates().to_numpy())) == {
        ("A", "B"), ("B", "A"), ("B", "C"), ("C", "B"), ("C", "A"), ("A", "C")
    }
    r = _residual_db(res)
    assert np.sqrt(np.mean(r**2)) == pytest.approx(res.noise_std_db, rel=0.05)


def test_campaign_preset_gives_every_flight_its_own_level() -> None:
    """The ``campaign`` preset: at least 8 learning flights, each role's levels at exactly the
    configured RMS about zero, drawn from the seed and stored; the levels are not noise."""
    from simulated_flights import simulated

    from rplearn.sim.presets import CAMPAIGN_LEVEL_STD_DB

    _, sim = simulated("campaign", 0)  # simulate("campaign", seed=0), once per process (shared)
    # the levels are the seed's, not the flights': the same flights passed once each draw them again
    cfg = make_preset("campaign")
    once = replace(cfg, campaign=replace(cfg.campaign, units=tuple(replace(u, n_passes=1) for u in cfg.campaign.units)))
    again = simulate(once, seed=0)
    assert len(again.signal_log) < len(sim.signal_log) / 2
    assert sim.unit_levels_db == again.unit_levels_db != simulate(once, seed=4).unit_levels_db
    assert sim.ground_truth.metadata["unit_levels_db"] == sim.unit_levels_db
    for role in ("learning", "testing"):
        levels = np.array([sim.unit_levels_db[u] for u in sim.units(role)])
        assert levels.size >= (8 if role == "learning" else 2)
        assert abs(levels.mean()) < 1e-9 and np.sqrt(np.mean(levels**2)) == pytest.approx(CAMPAIGN_LEVEL_STD_DB)
    assert sim.realised_noise_std_db < 1.1 * sim.noise_std_db  # the levels are in the clean power, not the noise
    assert set(simulate("smoke", seed=0).unit_levels_db.values()) == {0.0}


def test_both_drones_interpolated_at_once_equal_each_drone_alone_to_the_bit() -> None:
    from rplearn.sim.flight import _UnitTruth

    rng = np.random.default_rng(2)
    for n in (3, 5000):
        ts = np.cumsum(rng.uniform(0.001, 0.02, n))
        quats = rng.normal(size=(n, 2, 4))
        quats /= np.linalg.norm(quats, axis=-1, keepdims=True)
        truth = _UnitTruth(None, ts, rng.normal(0.0, 50.0, (n, 2, 3)), quats)  # type: ignore[arg-type]
        t = rng.uniform(ts[0] - 1.0, ts[-1] + 1.0, 3 * n)
        pos, q = truth._at(*truth._weights(t))
        for k in range(2):
            pos_k, q_k = truth.interpolate(t, k)
            assert np.ascontiguousarray(pos[:, k]).tobytes() == pos_k.tobytes()
            assert np.ascontiguousarray(q[:, k]).tobytes() == q_k.tobytes()
