"""``rplearn live`` names the nodes it took as fixed as ``sync`` does: the summary's note (a pose log of one row,
or of identical rows, holding still) and what each node is by where its poses came from (``fixed_node_advice``):
a CSV table's station, a MAVLink log's ground station (was: not a word from live, while sync of the same files
said both)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from rplearn.data.sync import SyncOptions
from rplearn.io import ReaderOptions
from rplearn.models.options import FitOptions
from rplearn.models.spec import ModelSpec
from rplearn.sim import simulate
from rplearn.workflows.live import LiveOptions, run_live
from rplearn.workflows.logs import sync_logs

PASS_S = 85.0  # the ground preset's first pass


@pytest.fixture(scope="module")
def ground() -> tuple[pd.DataFrame, pd.DataFrame]:
    r = simulate("ground", seed=0)
    pose, sig = r.pose_log, r.signal_log
    return (pose[pose["t"] < PASS_S].reset_index(drop=True),
            sig[sig["t"] < PASS_S][["t", "tx", "rx", "rssi_dbm", "tx_power_dbm", "frequency_hz"]].reset_index(drop=True))


def _fixed_lines(notes: list[str]) -> list[str]:
    return [n for n in notes if n.startswith(("fixed node(s)", "G is the ground station", "G: "))]


def _live(source: str, output: str, reader: ReaderOptions, sync: SyncOptions) -> list[str]:
    options = LiveOptions(spec=ModelSpec.parse("sh-2"), fit=FitOptions(), reader=reader, sync=sync, refit_s=60.0, idle_s=1.0)
    return run_live(source, output, options).status.notes


def test_a_csv_station_of_identical_rows_is_named_as_sync_names_it(ground, tmp_path):
    pose, sig = ground
    g = pose[pose["node"] == "G"].iloc[[0]]
    times = np.arange(0.0, PASS_S, 1.0)
    station = pd.concat([g] * times.size, ignore_index=True).assign(t=times)
    pose = pd.concat([pose[pose["node"] == "D"], station]).sort_values("t", kind="stable")
    pose.to_csv(tmp_path / "pose.csv", index=False)
    sig.to_csv(tmp_path / "signal.csv", index=False)
    said = sync_logs([str(tmp_path / "pose.csv")], [str(tmp_path / "signal.csv")], str(tmp_path / "m.parquet"))
    expected = _fixed_lines(said.counts.notes)
    assert len(expected) == 2 and expected[1].startswith("G: its pose table")
    notes = _live(f"{tmp_path / 'pose.csv'},{tmp_path / 'signal.csv'}", str(tmp_path / "live.json"), ReaderOptions(),
                  SyncOptions())
    assert _fixed_lines(notes) == expected


def test_a_mavlink_station_is_named_as_sync_names_it(ground, tmp_path):
    from rplearn.io._common import Logs
    from rplearn.io.tlog import write_tlog

    pose, sig = ground
    logs = Logs(pd.concat([pose[pose["node"] == "D"], pose[pose["node"] == "G"].iloc[[0]]], ignore_index=True), sig)
    path = str(tmp_path / "ground.tlog")
    write_tlog(logs, path, vehicle="D", station="G", origin_geodetic=(47.3977, 8.5456, 90.0))
    reader = ReaderOptions(tx_power_dbm=20.0, frequency_hz=2.412e9, station="G")
    said = sync_logs([path], [path], str(tmp_path / "m.parquet"), reader, SyncOptions(max_gap_s=1.0))
    expected = _fixed_lines(said.counts.notes)
    assert len(expected) == 2 and expected[1].startswith("G is the ground station, one pose row where the log placed it")
    notes = _live(path, str(tmp_path / "live.json"), reader, SyncOptions(max_gap_s=1.0))
    assert _fixed_lines(notes) == expected  # the stream named, never live's working copy of it
