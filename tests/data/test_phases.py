"""rplearn.data.phases and the phase options of sync: time window, airborne, max-gap advice,
calibration flight."""

from __future__ import annotations

import re

import numpy as np
import pandas as pd
import pytest

from rplearn.data.phases import calibration_problems, flight_phases, max_gap_advice, takeoff_altitude_m
from rplearn.data.poses import pose_tracks
from rplearn.data.streaming import synchronise_stream
from rplearn.data.sync import SyncOptions, SyncSummary, synchronise
from rplearn.errors import InputError

T0 = 1_381_700_000.0  # log time of the first pose (a telemetry log's epoch clock)


def hop_flight(armed=True):
    """Drone A: on the ground 0-10 s, climbs to 20 m by 20 s, flies to 80 s, lands by 90 s,
    on the ground to 100 s; armed 5-95 s. Station B static 30 m away. Signals every 0.1 s."""
    t = np.round(np.arange(0.0, 100.0, 0.05), 6)
    z = np.interp(t, [0, 10, 20, 80, 90, 100], [0.3, 0.3, 20.3, 20.3, 0.3, 0.3])
    s = np.clip(t, 10, 90)  # still on the ground, circling in the air
    a = pd.DataFrame({"t": T0 + t, "node": "A", "x": 10 * np.cos(s / 10), "y": 10 * np.sin(s / 10), "z": z,
                      "qw": 1.0, "qx": 0.0, "qy": 0.0, "qz": 0.0})
    if armed:
        a["armed"] = (t >= 5) & (t < 95)
    b = pd.DataFrame({"t": [T0], "node": "B", "x": [30.0], "y": [0.0], "z": [0.0], "qw": 1.0, "qx": 0.0, "qy": 0.0,
                      "qz": 0.0})
    ts = T0 + np.round(np.arange(0.025, 99.9, 0.1), 6)
    rng = np.random.default_rng(0)
    sig = pd.DataFrame({"t": ts, "tx": "A", "rx": "B", "rssi_dbm": rng.uniform(-80, -40, ts.size),
                        "tx_power_dbm": 20.0, "frequency_hz": 915e6})
    return pd.concat([a, b], ignore_index=True), sig


def test_window_drops_exactly_the_samples_outside_from_the_start_or_in_log_time():
    pose, sig = hop_flight()
    inside = (sig["t"] >= T0 + 20) & (sig["t"] <= T0 + 50.5)
    for opts in (SyncOptions(from_s=20, to_s=50.5), SyncOptions(from_s=T0 + 20, to_s=T0 + 50.5, window_clock="log")):
        res = synchronise(pose, sig, opts)
        assert res.summary.dropped["outside_window"] == int((~inside).sum())
        assert res.summary.n_out == int(inside.sum())
        np.testing.assert_array_equal(res.dataset["t"].to_numpy(), sig.loc[inside, "t"].to_numpy())
    assert "window: samples from 20 s to 50.5 s kept (seconds from the log start, t = 1381700000.000 s)" \
        in synchronise(pose, sig, SyncOptions(from_s=20, to_s=50.5)).summary.to_text()
    only_to = synchronise(pose, sig, SyncOptions(to_s=10))
    assert only_to.summary.n_out == int((sig["t"] <= T0 + 10).sum())
    with pytest.raises(InputError, match="to_s: expected a time after from_s=5"):
        SyncOptions(from_s=5, to_s=1)
    with pytest.raises(InputError, match="window_clock"):
        SyncOptions(window_clock="utc")


def _truth(pose, sig):
    """Armed and height above the take-off altitude (0.3 m) of A at each signal time, by hand."""
    a = pose[pose["node"] == "A"]
    z = np.interp(sig["t"], a["t"], a["z"])
    t = sig["t"].to_numpy() - T0
    return (t >= 5) & (t < 95), z - 0.3


def test_airborne_drops_disarmed_and_on_ground_samples_exactly():
    pose, sig = hop_flight()
    armed, height = _truth(pose, sig)
    res = synchronise(pose, sig, SyncOptions(airborne=True))
    s = res.summary
    assert s.dropped["disarmed"] == int((~armed).sum())
    assert s.dropped["on_ground"] == int((armed & ~(height > 2.0)).sum())
    assert s.n_out == int((armed & (height > 2.0)).sum()) > 0
    assert (res.dataset["tx_z"] - 0.3 > 2.0).all()
    assert "airborne only: armed (where the log says) and more than 2 m above the take-off altitude; vehicles: A " \
        "(take-off altitude z = 0.3 m, highest 20.0 m above it)" in s.to_text()
    # off (the default): nothing dropped, but the summary says how many were on the ground
    off = synchronise(pose, sig)
    assert off.summary.n_out == len(sig) and off.summary.ground_kept == s.dropped["disarmed"] + s.dropped["on_ground"]
    assert f"{off.summary.ground_kept} matched sample(s) were taken with an end on the ground" in off.summary.to_text()
    # without an armed column, height alone; a larger margin drops more
    no_arm, _ = hop_flight(armed=False)
    h = synchronise(no_arm, sig, SyncOptions(airborne=True, airborne_margin_m=10.0)).summary
    assert h.dropped["disarmed"] == 0 and h.dropped["on_ground"] == int((~(height > 10.0)).sum())
    # streamed alike
    total = SyncSummary()
    for part in synchronise_stream(pose, [sig.iloc[i:i + 101] for i in range(0, len(sig), 101)],
                                   SyncOptions(airborne=True)):
        total.merge(part.summary)
    assert total.dropped == s.dropped and total.notes == s.notes


def test_a_log_that_never_flies_is_all_on_ground_and_no_calibration_flight():
    pose, sig = hop_flight()
    drone = pose["node"] == "A"
    rng = np.random.default_rng(1)
    pose.loc[drone, ["x", "y"]] = 3.0 + rng.normal(0, 0.3, (drone.sum(), 2))  # GNSS noise on the ground
    pose.loc[drone, "z"] = 0.3 + rng.normal(0, 0.2, drone.sum())
    pose["armed"] = False
    with pytest.raises(InputError, match="only 0 signal sample"):
        synchronise(pose, sig, SyncOptions(airborne=True))
    tracks = pose_tracks(pose)
    phases = flight_phases(pose, tracks)
    assert phases.vehicles == ()
    lines = calibration_problems(phases, tracks, [("A", "B")], 915e6)
    assert lines[0].startswith("no calibration flight: no node ever rises more than 2 m above its take-off altitude")


def test_takeoff_altitude_is_where_the_node_holds_still():
    t = np.arange(0.0, 40.0, 0.1)
    z = np.interp(t, [0, 10, 20, 40], [5.0, 5.0, 30.0, 30.0])
    z[50] = 0.8  # a single low outlier on the ground
    xyz = np.c_[np.where(t < 10, 0.0, t), 0 * t, z]
    assert takeoff_altitude_m(t, xyz) == pytest.approx(5.0)
    circling = np.c_[20 * np.cos(t / 4), 20 * np.sin(t / 4), 10 + np.sin(t)]  # a simulated flight: never still
    assert np.isnan(takeoff_altitude_m(t, circling))


def test_takeoff_altitude_of_a_log_with_a_corrupt_time_sizes_nothing_by_its_span():
    """A time years off (a flipped byte of a DataFlash TimeUS, a sentinel) is one more pose, not
    a bin per second of the span (was a MemoryError of terabytes); a second without a pose still
    breaks a window of holding still."""
    t = np.arange(0.0, 40.0, 0.1)
    z = np.interp(t, [0, 10, 20, 40], [5.0, 5.0, 30.0, 30.0])
    xyz = np.c_[np.where(t < 10, 0.0, t), 0 * t, z]
    far = np.r_[t, 4e12]
    assert takeoff_altitude_m(far, np.r_[xyz, xyz[-1:]]) == pytest.approx(5.0)
    holed = (t < 4) | (t >= 5)  # no pose in the 5th second: no 10 s window on the ground
    assert np.isnan(takeoff_altitude_m(t[holed], xyz[holed]))


def test_calibration_distance_from_the_frequency():
    t = np.arange(0.0, 60.0, 0.1)
    near = pd.DataFrame({"t": t, "node": "A", "x": 3.0 * np.cos(t / 5), "y": 3.0 * np.sin(t / 5),
                         "z": 0.2 + np.clip(t - 10, 0, 1.0), "qw": 1.0, "qx": 0.0, "qy": 0.0, "qz": 0.0})
    far = near.assign(x=30.0 * np.cos(t / 5), z=np.clip(t - 10, 0, 20.0))
    gcs = pd.DataFrame({"t": [0.0], "node": "gcs", "x": 0.0, "y": 0.0, "z": 0.0, "qw": 1.0, "qx": 0.0, "qy": 0.0,
                        "qz": 0.0})
    for f in (915e6, 2.4e9, None):
        pose = pd.concat([near, gcs], ignore_index=True)
        tracks = pose_tracks(pose)
        lines = calibration_problems(flight_phases(pose, tracks), tracks, [("A", "gcs")], f)
        assert any(line.startswith("no calibration flight: nodes A and gcs never get farther apart than 3.2 m")
                   for line in lines), lines
        pose = pd.concat([far, gcs], ignore_index=True)
        tracks = pose_tracks(pose)
        assert calibration_problems(flight_phases(pose, tracks), tracks, [("A", "gcs")], f) == []


def test_max_gap_advice_on_a_1_2_hz_pose_log_keeps_most_samples(tmp_path):
    from rplearn.sim import simulate

    simulate("smoke", seed=5, out_dir=str(tmp_path))
    pose = pd.read_parquet(tmp_path / "pose_log.parquet")
    sig = pd.read_parquet(tmp_path / "signal_log.parquet")
    full = synchronise(pose, sig).summary.n_out
    slow = pd.concat([g.iloc[::83] for _, g in pose.groupby("node")], ignore_index=True)  # 100 Hz -> 1.2 Hz
    rate = 1.0 / np.median(np.diff(slow[slow["node"] == "A"]["t"]))
    assert rate == pytest.approx(1.2, rel=0.02)
    with pytest.raises(InputError) as err:
        synchronise(slow, sig)
    found = re.search(r"max_gap_s=([\d.]+) \(1.5 x that interval\)", str(err.value))
    assert found, str(err.value)
    value = float(found.group(1))
    res = synchronise(slow, sig, SyncOptions(max_gap_s=value))
    assert res.summary.dropped["pose_gap"] <= 0.02 * len(sig)  # only the 5 s pause between two units
    assert res.summary.n_out >= 0.95 * full
    assert max_gap_advice(pose_tracks(slow), value) is None  # the advice is not repeated once followed
    # many (not all) samples in gaps: a warning in the summary
    half = synchronise(slow, sig, SyncOptions(max_gap_s=0.83))
    assert 0 < half.summary.n_out and f"max_gap_s={value:g}" in half.summary.to_text()
