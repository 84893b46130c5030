"""``rplearn inspect`` says what ``sync`` will refuse: a node holding still at one pose and later at another, with
no pose between (a station moved between flights). Was: not a word, the node neither fixed nor flagged when the move
fell in a pause of the signals, and ``sync`` of the same logs refused them."""

from __future__ import annotations

import json

import pandas as pd
import pytest

from rplearn.errors import InputError
from rplearn.io.inspect import inspect_logs
from rplearn.io.inspect_json import inspect_to_json
from rplearn.workflows.logs import sync_logs


def test_a_station_moved_between_flights_is_a_problem_as_sync_refuses_it(tmp_path):
    from rplearn.io.files import write_table
    from rplearn.sim import simulate

    paths = simulate("smoke", seed=3, out_dir=str(tmp_path / "f"), log_format="csv").paths
    pose = pd.read_csv(paths["pose_log"], dtype={"node": str})
    b = pose["node"] == "B"
    for c in ("x", "y", "z", "qw", "qx", "qy", "qz"):
        pose.loc[b, c] = pose.loc[b, c].iloc[0]
    pose = pose[~(b & (pose["t"] >= 30.0) & (pose["t"] < 40.0))].copy()  # no pose of B for 10 s
    pose.loc[(pose["node"] == "B") & (pose["t"] >= 40.0), "x"] += 5.0
    moved = str(tmp_path / "moved.csv")
    write_table(pose, moved)
    with pytest.raises(InputError, match="a station moved between flights") as refused:
        sync_logs([moved], [paths["signal_log"]], str(tmp_path / "m.parquet"))
    report = inspect_logs([moved, paths["signal_log"]])
    said = [p for p in report.problems if "a station moved between flights" in p]
    assert len(said) == 1 and said[0].startswith(f"{moved}: node B holds still at") and "sync refuses" in said[0], report.problems
    assert str(refused.value).split(": ", 1)[1] in said[0]  # sync's own words, the file named
    assert not report.ok and report.fixed_nodes == []
    assert said[0] in json.loads(inspect_to_json(report))["problems"]
    assert said[0] in report.to_text()
