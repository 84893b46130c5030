"""Outage events through pose-signal matching (rplearn.data.outages, rplearn.data.sync) and the
table checks (rplearn.data.tables): kept, bridged across the vehicle's silence, counted by
reason, left out of learning samples."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from rplearn.data.outages import OUTAGE_MAX_GAP_S, split_outages
from rplearn.data.sync import SyncOptions, synchronise
from rplearn.data.tables import link_samples, outage_mask, validate_matched, validate_signal_log
from rplearn.errors import InputError


def _logs():
    """A drone flying east at 1 m/s for 100 s (10 Hz), silent from 40 to 52 s (its link lost);
    a static station; packets each way at 1 Hz, outage rows at 44..48 s and after the flight."""
    t = np.arange(0.0, 100.0, 0.1)
    t = t[(t < 40.0) | (t >= 52.0)]
    drone = pd.DataFrame({"t": t, "node": "D", "x": 10.0 + t, "y": 0.0, "z": 20.0,
                          "qw": 1.0, "qx": 0.0, "qy": 0.0, "qz": 0.0})
    station = pd.DataFrame({"t": [0.0], "node": ["G"], "x": [0.0], "y": [0.0], "z": [0.0],
                            "qw": [1.0], "qx": [0.0], "qy": [0.0], "qz": [0.0]})
    ts = np.arange(0.5, 100.0, 1.0)
    lost = np.r_[np.arange(44.5, 49.0, 1.0), [120.5]]
    ts = np.setdiff1d(ts, lost)
    rows = []
    for tx, rx in (("D", "G"), ("G", "D")):
        rows.append(pd.DataFrame({"t": ts, "tx": tx, "rx": rx, "rssi_dbm": -60.0 - 0.1 * ts,
                                  "tx_power_dbm": 20.0, "frequency_hz": 2.4e9, "outage": False}))
        rows.append(pd.DataFrame({"t": lost, "tx": tx, "rx": rx, "rssi_dbm": np.nan,
                                  "tx_power_dbm": 20.0, "frequency_hz": 2.4e9, "outage": True}))
    signal = pd.concat(rows, ignore_index=True).sort_values("t", kind="stable").reset_index(drop=True)
    return pd.concat([drone, station], ignore_index=True), signal


def test_outage_events_are_kept_bridged_across_the_silence_and_counted():
    pose, signal = _logs()
    plain = synchronise(pose, signal[~signal["outage"]].drop(columns="outage"), SyncOptions(max_gap_s=0.5))
    res = synchronise(pose, signal, SyncOptions(max_gap_s=0.5))
    # the received packets match exactly as without the outage rows (pose gap 40..52 s dropped alike)
    assert (res.summary.n_in, res.summary.n_out, res.summary.dropped) == (
        plain.summary.n_in, plain.summary.n_out, plain.summary.dropped)
    assert res.summary.dropped["pose_gap"] > 0
    counts = res.summary.outages
    assert counts["in"] == 12 and counts["kept"] == 10 and counts["out_of_span"] == 2
    assert "outage events (link lost, no RSSI): 12 in, 10 kept" in res.summary.to_text()
    ds = res.dataset
    assert ds["outage"].dtype == bool and int(ds["outage"].sum()) == 10
    assert ds["t"].is_monotonic_increasing
    down = ds[ds["outage"]]
    assert down["rssi_dbm"].isna().all()
    # across the silence, the drone's position is interpolated linearly between 39.9 and 52 s
    at = down[down["tx"] == "D"]
    np.testing.assert_allclose(at["tx_x"], 10.0 + at["t"], atol=1e-9)
    pd.testing.assert_frame_equal(ds[~ds["outage"]].drop(columns="outage").reset_index(drop=True),
                                  plain.dataset.reset_index(drop=True), check_dtype=False)


def test_a_signal_log_in_the_file_twice_gives_each_outage_event_once_and_fit_takes_it():
    # review 38: sync dropped the copies of the packets but kept both copies of each outage
    # event, and validate_matched (fit, evaluate, report) then refused sync's own output
    pose, signal = _logs()
    once = synchronise(pose, signal, SyncOptions(max_gap_s=0.5))
    twice = synchronise(pose, pd.concat([signal, signal], ignore_index=True), SyncOptions(max_gap_s=0.5))
    assert twice.summary.outages["duplicate"] == 12 and twice.summary.outages["kept"] == once.summary.outages["kept"] == 10
    assert twice.summary.dropped["duplicate"] == len(signal) - 12
    pd.testing.assert_frame_equal(twice.dataset, once.dataset)
    validate_matched(twice.dataset, "twice")  # was: 10 row(s) repeat an earlier row in every column
    assert "dropped: duplicate 12" in twice.summary.to_text()


def test_outage_events_follow_the_link_and_window_and_a_long_silence_is_a_pose_gap():
    pose, signal = _logs()
    one = synchronise(pose, signal, SyncOptions(max_gap_s=0.5, link=("D", "G")))
    assert one.summary.outages["other_link"] == 6 and one.summary.outages["kept"] == 5
    early = synchronise(pose, signal, SyncOptions(max_gap_s=0.5, to_s=46.0))
    assert early.summary.outages["outside_window"] == 8 and early.summary.outages["kept"] == 4
    long_gap = pose[(pose["node"] == "G") | (pose["t"] < 40.0) | (pose["t"] > 40.0 + OUTAGE_MAX_GAP_S + 5)]
    gone = synchronise(long_gap, signal, SyncOptions(max_gap_s=0.5))
    assert gone.summary.outages["pose_gap"] == 10 and gone.summary.outages["kept"] == 0


def test_tables_tolerate_outage_rows_and_learning_samples_leave_them_out():
    pose, signal = _logs()
    up, down = split_outages(signal)
    assert len(down) == 12 and not outage_mask(up).any()
    assert validate_signal_log(signal)["outage"].sum() == 12
    ds = synchronise(pose, signal, SyncOptions(max_gap_s=0.5)).dataset
    checked = validate_matched(ds)
    assert checked["outage"].sum() == 10
    samples = link_samples(ds)
    assert samples.outages == 10 and len(samples) == int((~ds["outage"]).sum())
    assert np.isfinite(samples.joint_gain_db).all()
    # poses to predict: every row, outage events included (their observed gain NaN)
    both = link_samples(ds, require_rssi=False)
    assert len(both) == len(ds) and np.isnan(both.joint_gain_db).sum() == 10
    # a NaN RSSI without the outage flag is still refused; so is a flag that is no boolean
    bad = ds.copy()
    bad.loc[bad.index[0], "rssi_dbm"] = np.nan
    bad.loc[bad.index[0], "outage"] = False
    with pytest.raises(InputError, match="rssi_dbm"):
        validate_matched(bad)
    text = ds.astype({"outage": object})
    text["outage"] = np.where(ds["outage"], "true", "false")
    assert outage_mask(text).sum() == 10
    text.loc[text.index[0], "outage"] = "maybe"
    with pytest.raises(InputError, match="outage"):
        outage_mask(text, "d.csv")


def test_airborne_drops_outage_events_on_the_ground_as_it_drops_packets():
    pose, signal = _logs()
    low = pose.copy()
    low.loc[(low["node"] == "D") & (low["t"] > 30.0), "z"] = low["z"].min()  # landed from 30 s on: held still
    low.loc[(low["node"] == "D") & (low["t"] > 30.0), "x"] = 40.0
    res = synchronise(low, signal, SyncOptions(max_gap_s=0.5, airborne=True))
    kept_all = synchronise(low, signal, SyncOptions(max_gap_s=0.5))
    assert kept_all.summary.outages["kept"] == 10
    assert res.summary.outages["on_ground"] + res.summary.outages["disarmed"] == 10 and res.summary.outages["kept"] == 0
