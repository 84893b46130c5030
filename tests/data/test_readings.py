"""rplearn.data.readings: one reading, one row; report periods and rates."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from rplearn.data.readings import REPEAT_FRACTION, repeated_readings, report_period_s, report_rate_hz
from rplearn.data.streaming import synchronise_stream
from rplearn.data.sync import SyncOptions, SyncSummary, synchronise

DATA = Path(__file__).resolve().parents[1] / "fixtures"


def doubled_radio(period_s=1.0, n=300, seed=0, links=(("A", "B"), ("B", "A"))):
    """A radio reporting every ``period_s`` (jittered), every reading written twice 2-6 ms apart;
    returns (signal, number of readings)."""
    rng = np.random.default_rng(seed)
    rows = []
    for tx, rx in links:
        t = np.cumsum(rng.uniform(0.95, 1.05, n) * period_s)
        rssi = np.round(rng.uniform(-90, -60, n))  # integer dBm: neighbours often equal
        second = t + rng.uniform(0.002, 0.006, n)
        for times in (t, second):
            rows.append(pd.DataFrame({"t": times, "tx": tx, "rx": rx, "rssi_dbm": rssi, "tx_power_dbm": 20.0,
                                      "frequency_hz": 915e6, "noise_dbm": -100.0}))
    sig = pd.concat(rows, ignore_index=True).sort_values("t", kind="stable").reset_index(drop=True)
    return sig, n * len(links)


def test_doubled_readings_are_one_row_each_and_the_period_is_the_report_period():
    sig, readings = doubled_radio()
    mask = repeated_readings(sig)
    assert mask.sum() == readings  # exactly the second copy of every reading
    kept = sig[~mask]
    assert (kept.groupby(["tx", "rx"]).size() == readings // 2).all()
    for _, g in sig.groupby(["tx", "rx"]):
        assert report_period_s(g["t"].to_numpy()) == pytest.approx(1.0, rel=0.05)
        assert report_rate_hz(g["t"].to_numpy(), repeated_readings(g)) == pytest.approx(1.0, rel=0.05)
        assert report_rate_hz(g["t"].to_numpy()) > 100.0  # counted row by row: the 128-173 Hz


def test_tripled_readings_and_readings_that_differ_are_kept_apart():
    sig, readings = doubled_radio(n=100, links=(("A", "B"),))
    third = sig.iloc[::2].assign(t=lambda d: d["t"] + 0.008)
    tripled = pd.concat([sig, third]).sort_values("t", kind="stable").reset_index(drop=True)
    assert repeated_readings(tripled).sum() == 2 * readings
    changed = sig.copy()
    changed.loc[1::2, "noise_dbm"] = -99.0  # the second row of each pair differs in one column
    pairs = changed.sort_values("t", kind="stable")
    assert repeated_readings(pairs).sum() == 0


@pytest.mark.parametrize("seed", range(5))
def test_fast_radios_are_never_merged(seed):
    rng = np.random.default_rng(seed)
    n = 4000
    steady = np.arange(n) * 1e-3 + rng.normal(0, 2e-5, n)  # 1 kHz, one RSSI value throughout
    poisson = np.cumsum(rng.exponential(0.02, n))  # random timing (Wi-Fi), one RSSI value
    for t in (steady, poisson):
        sig = pd.DataFrame({"t": t, "tx": "A", "rx": "B", "rssi_dbm": -50.0, "tx_power_dbm": 20.0,
                            "frequency_hz": 2.4e9})
        assert repeated_readings(sig).sum() == 0


def test_the_real_pcaps_and_telemetry_logs_have_nothing_merged():
    from rplearn.io import ReaderOptions, read_logs

    paths = sorted((DATA / "radiotap-pcap").glob("*.pcap")) + sorted((DATA / "ardupilot").glob("*.tlog"))
    seen = 0
    for path in paths:
        logs, _ = read_logs(str(path), ReaderOptions(tx_power_dbm=20.0, frequency_hz=915e6,
                                                     receivers={str(path): "mon"}))
        sig = logs.signal
        seen += len(sig)
        assert repeated_readings(sig).sum() == 0, path
        for _, g in sig.groupby(["tx", "rx"]):
            t = np.sort(g["t"].to_numpy())
            if t.size > 2 and path.suffix == ".tlog":  # no two readings closer than the repeat window
                assert np.diff(t).min() > REPEAT_FRACTION * report_period_s(t)
    assert seen > 1800


def test_sync_merges_repeats_counted_by_name_and_streams_alike():
    sig, readings = doubled_radio(n=120)
    t = np.arange(0.0, 130.0, 0.1)
    pose = pd.concat([
        pd.DataFrame({"t": t, "node": "A", "x": 50 * np.cos(t / 20), "y": 50 * np.sin(t / 20), "z": 30.0,
                      "qw": 1.0, "qx": 0.0, "qy": 0.0, "qz": 0.0}),
        pd.DataFrame({"t": [0.0], "node": "B", "x": 0.0, "y": 0.0, "z": 1.0, "qw": 1.0, "qx": 0.0, "qy": 0.0,
                      "qz": 0.0}),
    ], ignore_index=True)
    one = synchronise(pose, sig)
    assert one.summary.dropped["duplicate_reading"] == readings
    assert one.summary.n_out == len(sig) - readings
    assert "dropped (duplicate_reading): 240" in one.summary.to_text()
    # chunks that cut pairs apart find the same repeats
    chunks = [sig.iloc[i:i + 37] for i in range(0, len(sig), 37)]
    total = SyncSummary()
    for part in synchronise_stream(pose, chunks):
        total.merge(part.summary)
    assert total.dropped == one.summary.dropped
    kept = synchronise(pose, sig, SyncOptions(repeat_fraction=0))
    assert kept.summary.n_out == len(sig)


@pytest.mark.parametrize("seed", range(6))
def test_links_without_close_pairs_skip_the_period_and_mark_the_same_rows(seed):
    """Without a carry a link whose intervals bound its period by twice their mean, with too few
    pairs closer than that, skips its report period (issue 30): the mask is the full rule's."""
    rng = np.random.default_rng(seed)
    parts = []
    for k, (kind, n) in enumerate([("steady", 4000), ("doubled", 600), ("poisson", 3000), ("gappy", 2000),
                                   ("bursts", 1500), ("tripled", 900), ("few", 3)]):
        if kind == "steady":
            t = np.arange(n) / 80.0 + rng.uniform(0, 0.002, n)
        elif kind == "doubled":
            base = np.cumsum(rng.uniform(0.9, 1.1, n // 2))
            t = np.sort(np.r_[base, base + rng.uniform(0.002, 0.006, n // 2)])
        elif kind == "poisson":
            t = np.cumsum(rng.exponential(0.01, n))
        elif kind == "gappy":  # long silences: the mean is no bound on the period
            t = np.cumsum(np.where(rng.uniform(size=n) < 0.15, rng.uniform(5, 50, n), 0.01))
        elif kind == "bursts":  # pairs close together, a third of them
            t = np.cumsum(np.where(rng.uniform(size=n) < 0.33, 0.0005, rng.uniform(0.009, 0.011, n)))
        elif kind == "tripled":  # three copies 80 ms apart: twice the mean interval is below the period
            t = np.repeat(np.arange(n // 3, dtype=float), 3) + np.tile([0.0, 0.08, 0.16], n // 3)
        else:
            t = np.array([0.0, 1.0, 1.0004])
        rssi = rng.choice([-70.0, -71.0], t.size) if seed % 2 and kind not in ("doubled", "tripled") else np.full(t.size, -70.0)
        parts.append(pd.DataFrame({"t": t, "tx": f"T{k}", "rx": "R", "rssi_dbm": rssi, "tx_power_dbm": 20.0,
                                   "frequency_hz": 2.4e9}))
    sig = pd.concat(parts, ignore_index=True)
    sig.loc[rng.choice(len(sig), 5, replace=False), "t"] = np.nan
    for fraction in (0.1, 0.5):
        full = repeated_readings(sig, fraction, carry={})  # with a carry: every period computed
        assert np.array_equal(repeated_readings(sig, fraction), full)
    assert repeated_readings(sig, 0.5).any()  # the rule does find repeats here
