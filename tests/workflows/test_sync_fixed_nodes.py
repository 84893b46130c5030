"""`sync_logs` names the nodes it takes as fixed (a pose log of one row, or of identical rows: held still over the
log's span) and says what each is by where its poses came from: the ground station a MAVLink or DataFlash log places
(one row, fixed by design, its log not at fault), a pose table's node (log its poses if it moved)."""

from __future__ import annotations

from pathlib import Path

import pandas as pd
import pytest

from rplearn.data.sync import SyncOptions
from rplearn.io import ReaderOptions
from rplearn.sim import simulate
from rplearn.workflows.logs import sync_logs

REAL = Path(__file__).resolve().parents[1] / "fixtures" / "ardupilot"


@pytest.mark.parametrize("name", ["mavlink-log_2013-10-13_18-31-24.tlog", "pymavlink_test.BIN"])
def test_a_mavlink_or_dataflash_station_is_said_fixed_without_blaming_its_log(tmp_path, name):
    # was: the station held at its one row without a word in sync's summary
    log = str(REAL / name)
    outcome = sync_logs([log], [log], str(tmp_path / "m.parquet"), ReaderOptions(tx_power_dbm=20.0, frequency_hz=433e6),
                        SyncOptions(max_gap_s=1.0, min_samples=0))
    assert outcome.counts.fixed_nodes == ["gcs"]
    text = outcome.summary()
    assert "fixed node(s) (a pose log of one row, or of identical rows, is a node holding still at that pose): gcs at " \
           "every time (one pose row)" in text
    [advice] = [n for n in outcome.counts.notes if n.startswith("gcs is the ground station")]
    [reason] = [n.removeprefix(f"{log}: ") for n in outcome.notes if n.startswith(f"{log}: station placed at")]
    assert f'one pose row where the log placed it: "{reason}" ({log})' in advice  # the reader's words
    assert "ReaderOptions.station_geodetic places it if it stood elsewhere" in advice
    assert "log its poses" not in text and "not logged" not in advice


def test_a_pose_table_node_of_identical_rows_is_said_fixed_and_to_log_its_poses(tmp_path):
    # the smoke flight's station B logged with its first pose on every row (a logger that never updated it):
    # matched as standing still, said with the advice that fits a table the user wrote
    d = tmp_path / "f"
    simulate("smoke", seed=3, out_dir=str(d))
    pose = pd.read_parquet(d / "pose_log.parquet")
    b = pose["node"] == "B"
    first = pose[b].iloc[0]
    for c in ("x", "y", "z", "qw", "qx", "qy", "qz"):
        pose.loc[b, c] = first[c]
    pose.to_csv(tmp_path / "pose.csv", index=False)
    pd.read_parquet(d / "signal_log.parquet").to_csv(tmp_path / "signal.csv", index=False)
    outcome = sync_logs([str(tmp_path / "pose.csv")], [str(tmp_path / "signal.csv")], str(tmp_path / "m.parquet"))
    assert outcome.streamed and outcome.counts.fixed_nodes == ["B"]
    [advice] = [n for n in outcome.counts.notes if n.startswith("B: its pose table")]
    assert advice.endswith("if B moved, its motion was not logged: log its poses")
    assert "B from t = " in outcome.summary() and "ground station" not in advice


@pytest.fixture(scope="module")
def ground_tlog(tmp_path_factory) -> tuple[str, dict]:
    """The ``ground`` preset's first pass as a ``.tlog`` written by :func:`rplearn.io.tlog.write_tlog` (vehicle D,
    station G one static row; HOME_POSITION written) and what the writer says of it."""
    from rplearn.io._common import Logs
    from rplearn.io.tlog import write_tlog

    r = simulate("ground", seed=0)
    pose, sig = r.pose_log[r.pose_log["t"] < 85.0], r.signal_log[r.signal_log["t"] < 85.0]
    logs = Logs(pd.concat([pose[pose["node"] == "D"], pose[pose["node"] == "G"].iloc[[0]]], ignore_index=True),
                sig[["t", "tx", "rx", "rssi_dbm", "tx_power_dbm", "frequency_hz"]])
    path = str(tmp_path_factory.mktemp("tlog") / "ground.tlog")
    return path, write_tlog(logs, path, vehicle="D", station="G", origin_geodetic=(47.3977, 8.5456, 90.0))


def _station_advice(path: str, tmp_path, reader: ReaderOptions) -> str:
    outcome = sync_logs([path], [path], str(tmp_path / "m.parquet"), reader, SyncOptions(max_gap_s=1.0))
    assert outcome.counts.fixed_nodes == ["G"]
    [advice] = [n for n in outcome.counts.notes if n.startswith("G is the ground station")]
    return advice


def test_the_station_advice_quotes_the_logs_reason(ground_tlog, tmp_path):
    """Where the log placed its station, in the log reader's words (was: '(at the log's home, else the vehicle's
    first fix)', whichever it was)."""
    path, _ = ground_tlog
    advice = _station_advice(path, tmp_path, ReaderOptions(tx_power_dbm=20.0, frequency_hz=2.412e9, station="G"))
    assert f'"station placed at the vehicle\'s home from HOME_POSITION" ({path})' in advice
    assert "else the vehicle's first fix" not in advice
    assert "ReaderOptions.station_geodetic places it if it stood elsewhere" in advice
    assert "ReaderOptions.station_heading_deg says where its antenna faced" in advice


@pytest.mark.parametrize("heading_deg", [None, 80.0])
def test_a_station_the_user_placed_is_not_advised_to_be_placed(ground_tlog, tmp_path, heading_deg):
    """With the station's position given (``--station``), the advice says it stands where it was given, never
    that the position option places it (was: '... where ground.tlog places it (at the log's home ...)
    ReaderOptions.station_geodetic places it if it stood elsewhere', '--station LAT,LON,ALT places it' on the
    command line); its heading is advised only when not given."""
    path, written = ground_tlog
    lat, lon, alt = written["station_geodetic"]
    reader = ReaderOptions(tx_power_dbm=20.0, frequency_hz=2.412e9, station="G", station_geodetic=(lat, lon, alt),
                           station_heading_deg=heading_deg)
    advice = _station_advice(path, tmp_path, reader)
    assert f"at the position given for it ({lat:.6f}, {lon:.6f}, {alt:.1f} m)" in advice
    assert "station_geodetic" not in advice and "places it" not in advice and "log's home" not in advice
    if heading_deg is None:
        assert "ReaderOptions.station_heading_deg says where its antenna faced" in advice
    else:
        assert "station_heading_deg" not in advice and "heading 80 deg as given" in advice
