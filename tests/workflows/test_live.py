"""rplearn live: a replayed .tlog over UDP, a CSV being appended to, a killed session, the
prequential error against a later flight, the stop criteria and the manoeuvre hook."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import threading
import time
from dataclasses import replace
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from rplearn.core.lsq.normal_equations import NormalEquations
from rplearn.data.sync import synchronise
from rplearn.data.tables import link_samples
from rplearn.io.options import ReaderOptions
from rplearn.models.load import load_model
from rplearn.models.options import FitOptions
from rplearn.models.spec import ModelSpec
from rplearn.plan.campaign import Campaign
from rplearn.sim import make_preset, simulate
from rplearn.workflows.calibration_plan import OptimizeOptions, optimize_plan
from rplearn.workflows.learning import fit_dataset
from rplearn.workflows.live import LiveOptions, replay_session, run_live
from rplearn.workflows.logs import sync_logs

ROOT = Path(__file__).resolve().parents[2]
TLOG = ROOT / "tests" / "fixtures" / "ardupilot" / "mavlink-log_2013-10-13_16-58-51.tlog"
ALL_STRETCHES = ["flight[1/5]", "flight[2/5]", "flight[3/5]", "flight[4/5]", "test[5/5]"]
ENV = {**os.environ, "PYTHONPATH": str(ROOT / "src")}


def _rplearn(*args: str, **kw) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-m", "rplearn", *args], env=ENV, stdout=subprocess.PIPE,
                            stderr=subprocess.STDOUT, text=True, **kw)


def _offline(dataset: str, spec: ModelSpec, options: FitOptions):
    return fit_dataset(dataset, spec, ALL_STRETCHES, options=options).fitted.model


def _max_difference_db(a, b, dataset: str) -> float:
    rows = pd.read_parquet(dataset)
    s = link_samples(rows, dataset, nodes=b.nodes)
    return float(max(np.abs(a.predict_gain(s) - b.predict_gain(s)).max(),
                     np.abs(a.predict_gain_std(s) - b.predict_gain_std(s)).max()))


def _same_planning_fields(learned, offline) -> None:
    """What ``trajectory --optimize --from-model`` plans with: the live model file states the
    drift (it had none) and the planning weight of ``fit --order auto`` of the same log."""
    got, expected = learned.training, offline.training
    assert expected.drift_std_db is not None and expected.planning_penalty_weight is not None
    assert got.drift_std_db == pytest.approx(expected.drift_std_db, rel=1e-9)
    assert got.planning_penalty_weight == pytest.approx(expected.planning_penalty_weight, rel=1e-9)


def _free_port() -> int:
    import socket

    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def _wait_until_bound(port: int, process: subprocess.Popen, timeout_s: float = 60.0) -> None:
    """Wait until a UDP socket of this machine is bound to ``port`` (Linux: /proc/net/udp), so
    that no datagram is sent before ``live`` listens; elsewhere, 3 s."""
    table = Path("/proc/net/udp")
    if not table.exists():
        time.sleep(3.0)
        return
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline and process.poll() is None:
        if any(line.split()[1].endswith(f":{port:04X}") for line in table.read_text().splitlines()[1:]):
            return
        time.sleep(0.05)
    raise AssertionError(f"live never listened on UDP port {port}: {process.poll()=}")


def test_a_tlog_replayed_over_udp_at_20x_ends_with_the_offline_model(tmp_path):
    port = _free_port()
    model, record = str(tmp_path / "live.json"), str(tmp_path / "received.tlog")
    live = _rplearn("live", f"udpin:127.0.0.1:{port}", "--tx-power", "20", "--frequency", "433e6", "--idle", "3",
                    "--refit-s", "1", "--quiet", "--record", record, "-o", model)
    _wait_until_bound(port, live)
    # issue 27's acceptance 1 names 20x: the 571-s log in 29 s, a refit every second of it
    replay = _rplearn("replay", str(TLOG), "--to", f"127.0.0.1:{port}", "--speed", "20")
    assert replay.wait(timeout=300) == 0, replay.stdout.read()
    out, _ = live.communicate(timeout=300)
    assert live.returncode == 0, out
    assert "last refit: the recorded log matched whole" in out
    data = str(tmp_path / "data.parquet")
    sync_logs([record], [record], data, ReaderOptions(tx_power_dbm=20.0, frequency_hz=433e6))
    offline = _offline(data, ModelSpec.parse("sh"), FitOptions(auto=True))
    learned = load_model(model)
    assert learned.label == offline.label
    assert _max_difference_db(learned, offline, data) < 1e-6
    _same_planning_fields(learned, offline)


def _appender(pose: pd.DataFrame, sig: pd.DataFrame, folder: Path, speed: float,
              stop: threading.Event | None = None) -> threading.Thread:
    """A thread appending the logs to two CSVs in half-seconds of log time at ``speed`` times
    real time; it ends early once ``stop`` is set."""
    def write() -> None:
        pose.iloc[:0].to_csv(folder / "pose.csv", index=False)
        sig.iloc[:0].to_csv(folder / "signal.csv", index=False)
        t0, w0 = float(pose["t"].min()), time.monotonic()
        for a in np.arange(t0, float(pose["t"].max()) + 0.5, 0.5):
            while time.monotonic() - w0 < (a - t0) / speed:
                time.sleep(0.005)
            if stop is not None and stop.is_set():
                return
            pose[(pose["t"] >= a) & (pose["t"] < a + 0.5)].to_csv(folder / "pose.csv", mode="a", header=False, index=False)
            sig[(sig["t"] >= a) & (sig["t"] < a + 0.5)].to_csv(folder / "signal.csv", mode="a", header=False, index=False)

    th = threading.Thread(target=write)
    th.start()
    return th


@pytest.fixture(scope="module")
def smoke() -> tuple[pd.DataFrame, pd.DataFrame]:
    r = simulate("smoke", seed=0)
    return r.pose_log, r.signal_log.drop(columns=["unit"])


def _session_beside_appender(pose: pd.DataFrame, sig: pd.DataFrame, folder: Path, **kw):
    """``run_live`` on two CSVs appended to at 40x, with the silence that ends the stream 3 s
    (0.5 s of log time is written every 12.5 ms); a writer stalled longer by a loaded machine
    is still writing when the session ends (or the session received fewer signal rows than the
    log holds): then the session saw a cut stream and is run again in a fresh folder, waiting
    15 s of silence. The outcome and the folder."""
    for attempt, idle_s in enumerate((3.0, 15.0)):
        here = folder / f"attempt{attempt}"
        here.mkdir()
        writer = _appender(pose, sig, here, speed=40.0)
        source = f"{here / 'pose.csv'},{here / 'signal.csv'}"
        outcome = run_live(source, str(here / "live.json"), LiveOptions(refit_s=0.5, idle_s=idle_s),
                           html=str(here / "live.html"), **kw)
        stalled = writer.is_alive() or outcome.status.received < len(sig)
        writer.join()
        if not stalled:
            break
    return outcome, here


def test_a_csv_being_appended_to_ends_with_the_offline_model(smoke, tmp_path):
    pose, sig = smoke
    outcome, tmp_path = _session_beside_appender(pose, sig, tmp_path)
    page = str(tmp_path / "live.html")
    assert outcome.status.refits >= 2 and outcome.status.prequential_n > 0
    data = str(tmp_path / "data.parquet")
    sync_logs([str(tmp_path / "pose.csv")], [str(tmp_path / "signal.csv")], data)
    offline = _offline(data, ModelSpec.parse("sh"), FitOptions(auto=True))
    learned = load_model(str(tmp_path / "live.json"))
    assert learned.label == offline.label
    assert _max_difference_db(learned, offline, data) < 1e-6
    _same_planning_fields(learned, offline)
    # the next flight is planned from the live model file (refused before: "has no training.drift_std_db")
    plan = optimize_plan(str(tmp_path / "plan"), OptimizeOptions(model="sh-5", target_spread_db=2.5, budget_s=15.0,
                                                                 from_model=str(tmp_path / "live.json")))
    assert plan.prior is not None and f"drift {learned.training.drift_std_db:.2f} dB per 5-s block" in plan.prior
    assert plan.paths
    text = Path(page).read_text()
    assert "http-equiv='refresh'" in text and text.count("data:image/png;base64,") == 2
    assert "prequential RMSE" in text


def test_silence_before_the_first_message_does_not_end_the_session(smoke, tmp_path):
    """`live` started before the drones are up: the idle time counts from the first message."""
    pose, sig = smoke
    short = pose[pose["t"] <= pose["t"].min() + 60.0], sig[sig["t"] <= sig["t"].min() + 60.0]

    def late() -> None:
        time.sleep(3.0)  # three times the idle time before anything is written
        _appender(*short, tmp_path, speed=40.0).join()

    writer = threading.Thread(target=late)
    writer.start()
    source = f"{tmp_path / 'pose.csv'},{tmp_path / 'signal.csv'}"
    outcome = run_live(source, str(tmp_path / "live.json"), LiveOptions(refit_s=0.5, idle_s=1.0))
    writer.join()
    assert outcome.status.prequential_n > 0 and (tmp_path / "live.json").exists()
    assert outcome.status.stopped.startswith("end of stream")


def test_a_session_killed_mid_flight_leaves_a_valid_model(smoke, tmp_path):
    pose, sig = smoke
    stop = threading.Event()  # the writer stops once the session is killed (else it writes the 75 s flight at 4x)
    writer = _appender(pose, sig, tmp_path, speed=4.0, stop=stop)
    model = tmp_path / "live.json"
    live = _rplearn("live", f"{tmp_path / 'pose.csv'},{tmp_path / 'signal.csv'}", "--refit-s", "0.5", "--quiet",
                    "-o", str(model))
    try:
        deadline = time.monotonic() + 120
        while not model.exists() and time.monotonic() < deadline:
            time.sleep(0.2)
        assert model.exists(), "no model written in time"
        time.sleep(1.5)  # more refits: the file is being replaced while we kill
        os.kill(live.pid, signal.SIGKILL)
        live.wait(timeout=30)
    finally:
        stop.set()
        if live.poll() is None:
            live.kill()
        writer.join()
    learned = load_model(str(model))
    rows = synchronise(pose, sig).dataset
    s = link_samples(rows, "smoke", nodes=learned.nodes)
    assert np.isfinite(learned.predict_gain(s)).all()


def test_the_prequential_error_of_the_last_fifth_predicts_a_later_flights_error(tmp_path):
    cfg = make_preset("smoke")
    unit = replace(cfg.campaign.units[0], n_loops=4)
    cfg = replace(cfg, campaign=Campaign((unit, replace(unit, role="testing", label="test_0")), gap_s=5.0))
    r = simulate(cfg, seed=0)
    sig = r.signal_log
    first = sig[sig["unit"] == unit.label].drop(columns=["unit"])
    later = sig[sig["unit"] == "test_0"].drop(columns=["unit"])
    # batches as long as the refit period: each is predicted by the model of the rows before it, as
    # with 1-s batches (a refit every 5 s either way), in a fifth of the batches
    outcome = replay_session(r.pose_log, first, str(tmp_path / "m.json"), LiveOptions(refit_s=5.0), batch_s=5.0)
    model = outcome.fitted.model
    held = link_samples(synchronise(r.pose_log, later).dataset, "later flight", nodes=model.nodes)
    held_rmse = float(np.sqrt(np.mean((held.joint_gain_db - model.predict_gain(held)) ** 2)))
    prequential = outcome.prequential.rmse_db(0.2)
    print(f"prequential RMSE (last fifth) {prequential:.3f} dB, later flight {held_rmse:.3f} dB")
    assert abs(prequential / held_rmse - 1.0) < 0.15


def test_the_stop_criteria_and_the_manoeuvre_hook(smoke, tmp_path):
    pose, sig = smoke
    seen = []

    def ranker(stats, fitted, latest):
        seen.append((stats, fitted, latest))
        return [("orbit", 30.0, 1.5), ("yaw turn", 10.0, 1.2), ("climb", 20.0, 1.9), ("descent", 20.0, 2.5)]

    options = LiveOptions(refit_s=5.0, until_coverage_pct=20.0, manoeuvres=ranker)
    outcome = replay_session(pose, sig, str(tmp_path / "m.json"), options)
    assert "coverage at least 20%" in outcome.status.stopped
    assert outcome.status.learned < len(sig) / 2
    assert min(outcome.status.coverage_pct.values()) >= 20.0
    stats, fitted, latest = seen[-1]
    assert isinstance(stats, NormalEquations) and stats.n_samples == outcome.status.learned
    assert isinstance(fitted.spec, ModelSpec) and set(latest["node"]) == {"A", "B"}
    assert [m[0] for m in outcome.status.manoeuvres] == ["orbit", "yaw turn", "climb"]  # the ranker's order
    assert "next: orbit" in outcome.status.summary()
    assert load_model(str(tmp_path / "m.json")).label == outcome.fitted.model.label
