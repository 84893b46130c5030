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
    assert f"one pose row where {log} places it" in advice and "ReaderOptions.station_geodetic" in advice
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
