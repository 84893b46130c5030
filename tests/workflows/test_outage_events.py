"""Outage events end to end (issue 28 item 4): a simulated flight written as a ground station's
``.tlog`` with lost links where its signal was weakest (TlogDefects.link_lost), read, synced,
learned from and scored (evaluate --sensitivity); and the README's real ``.tlog``, whose
predicted availability is scored on its held-out stretch (acceptance 3)."""

from __future__ import annotations

import os

import numpy as np
import pandas as pd
import pytest

from rplearn.core.geometry import quat_wxyz_from_yaw
from rplearn.data.units import time_units
from rplearn.io import ReaderOptions
from rplearn.io._common import Logs
from rplearn.io.files import read_dataset
from rplearn.io.mavlink import read_mavlink
from rplearn.io.tlog import TlogDefects, write_tlog
from rplearn.models import ModelSpec
from rplearn.models.options import FitOptions
from rplearn.workflows.learning import evaluate_model_files, fit_dataset
from rplearn.workflows.logs import sync_logs

ORIGIN = (47.3977, 8.5456, 90.0)
LEARN = ["flight[1/5]", "flight[2/5]", "flight[3/5]", "flight[4/5]"]
TEST = ["test[5/5]"]
#: lost-link windows [s]: long enough that reports in their middle are more than the reader's
#: 2 s stream timeout from the vehicle's last and next message
WINDOW_S = 10.0
REAL_TLOG = "tests/fixtures/ardupilot/mavlink-log_2013-10-13_16-58-51.tlog"


def _weakest_windows(signal: pd.DataFrame, pose_t: np.ndarray, n: int, within: tuple[float, float],
                     ) -> list[tuple[float, float]]:
    """``n`` disjoint windows where the vehicle -> station RSSI, averaged over a window, is
    weakest, each inside the vehicle's flight (no pose gap of a second or more in or around it)."""
    t0 = pose_t[0]
    gaps = [(a - t0, b - t0) for a, b in zip(pose_t[:-1], pose_t[1:]) if b - a >= 1.0]
    d = signal[signal["tx"] == "D"].sort_values("t")
    rel = d["t"].to_numpy() - t0
    mean = pd.Series(d["rssi_dbm"].to_numpy()).rolling(int(WINDOW_S / np.median(np.diff(rel))), center=True).mean()
    order = np.argsort(mean.fillna(np.inf).to_numpy())
    out: list[tuple[float, float]] = []
    for i in order:
        c = rel[i]
        clear = all(b < c - WINDOW_S or a > c + WINDOW_S for a, b in gaps)
        if clear and within[0] + WINDOW_S < c < within[1] - WINDOW_S and all(abs(c - (a + b) / 2) > 2 * WINDOW_S
                                                                              for a, b in out):
            out.append((c - WINDOW_S / 2, c + WINDOW_S / 2))
        if len(out) == n:
            return out
    raise AssertionError("no room for the windows")


@pytest.fixture(scope="module")
def flight(tmp_path_factory):
    """The ``ground`` preset (every 5th packet) written with 4 lost-link windows, 2 in the last fifth."""
    from rplearn.sim.flight import simulate

    sim = simulate("ground", seed=1)
    pose, signal = sim.pose_log, sim.signal_log.iloc[::5]
    g = pose[pose["node"] == "G"]
    q = quat_wxyz_from_yaw(0.0)
    station = pd.DataFrame({"t": [g["t"].min()], "node": ["G"], "x": [g["x"].median()], "y": [g["y"].median()],
                            "z": [g["z"].median()], "qw": [q[0]], "qx": [q[1]], "qy": [q[2]], "qz": [q[3]]})
    pose = pd.concat([pose[pose["node"] == "D"], station], ignore_index=True)
    signal = signal[["t", "tx", "rx", "rssi_dbm", "tx_power_dbm", "frequency_hz"]].sort_values("t", kind="stable")
    pose_t = np.sort(pose.loc[pose["node"] == "D", "t"].to_numpy())
    span = pose_t[-1] - pose_t[0]
    windows = (_weakest_windows(signal, pose_t, 2, (0.0, 0.75 * span))
               + _weakest_windows(signal, pose_t, 2, (0.82 * span, span)))
    folder = tmp_path_factory.mktemp("outages")
    path = folder / "flight.tlog"
    written = write_tlog(Logs(pose, signal), path, vehicle="D", station="G", origin_geodetic=ORIGIN,
                         defects=TlogDefects(link_lost=tuple(windows)))
    return folder, path, written, windows


def _reader(path) -> ReaderOptions:
    return ReaderOptions(tx_power_dbm=20.0, frequency_hz=2.412e9, nodes={str(path): "D"}, station="G",
                         station_heading_deg=90.0, origin_geodetic=ORIGIN)


@pytest.fixture(scope="module")
def learned(flight):
    """The flight synced and SH-4 learned from its first four fifths."""
    folder, path, _, _ = flight
    out = folder / "matched.parquet"
    outcome = sync_logs([str(path)], [str(path)], str(out), _reader(path))
    fit = fit_dataset(str(out), ModelSpec.parse("sh-4"), LEARN, options=FitOptions(), output=str(folder / "m.json"))
    return out, outcome, fit, folder / "m.json"


def test_lost_links_written_into_a_tlog_become_outage_rows_kept_by_sync_and_skipped_by_fit(flight, learned):
    folder, path, written, windows = flight
    out, outcome, fit, _ = learned
    assert written["link_lost_reports"] > 0
    logs, meta = read_mavlink(path, 20.0, 2.412e9, "D", "G")
    lost = logs.signal[logs.signal["outage"]]
    # a report counts as link-lost when no vehicle message lies within 2 s: the middle of each window
    assert 0 < meta["signal"]["link_lost"] <= written["link_lost_reports"]
    assert len(lost) == 2 * meta["signal"]["link_lost"] and lost["rssi_dbm"].isna().all()
    counts = outcome.counts.outages
    # every outage lies inside the flight, across the vehicle's silence: all kept, none dropped
    assert counts["in"] == len(lost) and counts["kept"] == len(lost)
    assert "outage events (link lost, no RSSI)" in outcome.summary()
    df = read_dataset(str(out))
    assert df["outage"].dtype == bool and int(df["outage"].sum()) == len(lost)
    assert df.loc[df["outage"], "rssi_dbm"].isna().all() and df.loc[~df["outage"], "rssi_dbm"].notna().all()
    # the bridged poses of the outage events lie where the vehicle was in the windows
    assert np.isfinite(df.loc[df["outage"], ["tx_x", "rx_x", "tx_qw", "rx_qw"]].to_numpy()).all()
    # fit learns from the received packets only and counts the outage events it skipped
    stretched, _ = time_units(df)
    in_learning = int(stretched.loc[stretched["unit"].isin(LEARN), "outage"].sum())
    assert fit.outages == in_learning > 0
    assert f"outage events skipped (link lost, no RSSI to learn from): {in_learning:,}" in fit.summary()
    assert fit.n_samples == int((stretched["unit"].isin(LEARN) & ~stretched["outage"]).sum())


def test_evaluate_scores_predicted_availability_against_outages_and_threshold_crossings(flight, learned):
    folder = flight[0]
    out, _, _, model = learned
    df, _ = time_units(read_dataset(str(out)))
    learn = df[df["unit"].isin(LEARN) & ~df["outage"]]
    s = float(np.percentile(learn["rssi_dbm"], 10))
    ev = evaluate_model_files([str(model)], str(out), TEST, sensitivity_dbm=s, json_out=str(folder / "e.json"))
    [score] = ev.availability
    test = df[df["unit"].isin(TEST)]
    assert score.n_samples == len(test) and score.n_outages == int(test["outage"].sum()) > 0
    assert score.n_below == int((~test["outage"] & (test["rssi_dbm"] < s)).sum())
    assert score.base_rate == pytest.approx(float(np.mean(df.loc[df["unit"].isin(LEARN), "rssi_dbm"] >= s)))
    print(f"\nsimulated tlog with lost links, sensitivity {s:.1f} dBm: {score.n_outages} outage events, "
          f"{score.n_below} below; Brier {score.brier:.4f}, constant {score.base_rate:.3f} -> "
          f"{score.reference_brier:.4f}, skill {score.skill:.3f}\n{score.table.markdown()}")
    assert score.skill > 0.0 and score.brier < score.reference_brier
    # the outage events lie where the signal was weakest: their predicted availability is lower
    from rplearn.core.availability import link_availability
    from rplearn.models import load_model
    from rplearn.models.predict import predict_dataset

    pred = predict_dataset(load_model(str(model)), test, str(out)).table
    p = link_availability(pred["rssi_pred_dbm"], pred["rssi_pred_std_db"], s)
    assert p[test["outage"].to_numpy()].mean() < p[~test["outage"].to_numpy()].mean()
    assert sum(r["count"] for r in score.table.rows()) == len(test)
    assert "## Availability at" in ev.markdown and "| predicted availability |" in ev.markdown
    import json

    saved = json.loads((folder / "e.json").read_text())
    assert saved["availability"][0]["brier_skill"] == pytest.approx(score.skill)
    assert saved["availability"][0]["n_outages"] == score.n_outages


def test_the_readme_tlog_keeps_its_matched_samples_and_scores_its_held_out_availability(tmp_path):
    """Acceptance 3: the README's real flight. Its 57 link-lost reports come after the vehicle's
    last message (landed, disarmed, switched off): no pose, dropped as out_of_span and counted;
    the received packets match as before (974 of 1,026). The held-out fifth is scored against
    threshold crossings at the 10th and 30th percentile of its RSSI (as acceptance 1)."""
    out = tmp_path / "matched.parquet"
    outcome = sync_logs([REAL_TLOG], [REAL_TLOG], str(out),
                        ReaderOptions(tx_power_dbm=20.0, frequency_hz=915e6), _sync_options())
    assert (outcome.counts.n_in, outcome.counts.n_out) == (1026, 974)
    assert outcome.counts.outages == {"in": 114, "kept": 0, "duplicate": 0, "invalid_value": 0, "outside_window": 0,
                                      "tx_equals_rx": 0, "other_link": 0, "unknown_node": 0, "out_of_span": 114,
                                      "pose_gap": 0, "near_field": 0, "disarmed": 0, "on_ground": 0}
    fit = fit_dataset(str(out), ModelSpec.parse("sh-8"), LEARN, options=FitOptions(auto=True),
                      output=str(tmp_path / "sik.json"))
    df, _ = time_units(read_dataset(str(out)))
    held_out = df.loc[df["unit"].isin(TEST), "rssi_dbm"]
    for pct in (10, 30):  # as acceptance 1: percentiles of the held-out RSSI (the base rate is the learning data's)
        s = float(np.percentile(held_out, pct))
        [score] = evaluate_model_files([str(tmp_path / "sik.json")], str(out), TEST, sensitivity_dbm=s).availability
        print(f"\nREADME tlog, {fit.fitted.label}, sensitivity {s:.1f} dBm (held-out {pct}th pct): "
              f"Brier {score.brier:.4f}, constant {score.base_rate:.3f} -> {score.reference_brier:.4f}, "
              f"skill {score.skill:.3f}\n{score.table.markdown()}")
        assert score.n_samples == int(df["unit"].isin(TEST).sum()) and score.n_outages == 0
        assert score.skill > 0.0


def _sync_options():
    from rplearn.data.sync import SyncOptions

    return SyncOptions(max_gap_s=1.0)


def test_report_with_a_sensitivity_draws_the_reliability_diagram_of_the_held_out_units(flight, learned):
    from rplearn.workflows.report import ReportOptions, learn_and_report

    folder = flight[0]
    out, _, _, model = learned
    df, _ = time_units(read_dataset(str(out)))
    s = float(np.percentile(df.loc[~df["outage"], "rssi_dbm"], 20))
    rep = learn_and_report(str(out), str(folder / "report"), model_path=str(model), test_units=TEST,
                           report=ReportOptions(repeats=1, sensitivity_dbm=s))
    score = rep.availability
    assert score is not None and score.n_outages == int(df.loc[df["unit"].isin(TEST), "outage"].sum()) > 0
    assert os.path.getsize(rep.files["reliability"]) > 10_000
    html = (folder / "report" / "report.html").read_text()
    assert f"Availability at {s:g} dBm" in html and "observed share up" in html
    assert score.markdown() in rep.summary()
    # the measured-vs-predicted figures leave the outage events out, and are drawn
    assert os.path.exists(rep.files["time"]) and os.path.exists(rep.files["residuals"])
