"""``rplearn inspect`` names the nodes ``sync`` takes as fixed (a pose log of one row, or of identical rows: a ground
station, a parked drone), with the detection ``sync`` uses: in its text and Markdown, and in its strict JSON
(``fixed_nodes``, ``fixed_note``, a ``fixed`` flag per node)."""

from __future__ import annotations

import json
from pathlib import Path

import pandas as pd
import pytest

from rplearn.io import ReaderOptions
from rplearn.io.inspect import inspect_logs
from rplearn.io.inspect_json import inspect_to_json
from rplearn.workflows.logs import sync_logs

TLOG = Path(__file__).resolve().parents[1] / "fixtures" / "ardupilot" / "mavlink-log_2013-10-13_18-31-24.tlog"


@pytest.fixture(scope="module")
def flight(tmp_path_factory) -> tuple[Path, Path, Path]:
    """The smoke flight as CSV (written by the simulator's writers), and its pose log with station B's first pose on
    every row (a logger that never updated it)."""
    from rplearn.io.files import write_table
    from rplearn.sim import simulate

    out = tmp_path_factory.mktemp("flights")
    paths = simulate("smoke", seed=3, out_dir=str(out), log_format="csv").paths
    pose = pd.read_csv(paths["pose_log"], dtype={"node": str})
    b = pose["node"] == "B"
    for c in ("x", "y", "z", "qw", "qx", "qy", "qz"):
        pose.loc[b, c] = pose.loc[b, c].iloc[0]
    write_table(pose, str(out / "still.csv"))
    return Path(paths["pose_log"]), Path(paths["signal_log"]), out / "still.csv"


def _json(report) -> dict:
    return json.loads(inspect_to_json(report))


def test_a_node_logged_with_identical_rows_is_named_fixed_as_sync_names_it(flight, tmp_path):
    _, signal, still = flight
    report = inspect_logs([str(still), str(signal)])
    synced = sync_logs([str(still)], [str(signal)], str(tmp_path / "m.parquet"))
    assert report.fixed_nodes == synced.counts.fixed_nodes == ["B"]
    assert {n.node: n.fixed for n in report.nodes} == {"A": False, "B": True}
    assert report.fixed_note is not None and "B (identical pose rows" in report.fixed_note
    text = report.to_text()
    assert f"  {report.fixed_note}" in text.splitlines()
    assert [line for line in text.splitlines() if line.startswith("  B: ")][0].endswith(", fixed")
    md = report.to_markdown()
    assert report.fixed_note in md and "| fixed |" in md
    doc = _json(report)
    assert doc["fixed_nodes"] == ["B"] and doc["fixed_note"] == report.fixed_note
    assert {n["node"]: n["fixed"] for n in doc["nodes"]} == {"A": False, "B": True}
    assert report.ok  # a station standing still is no problem


def test_a_mavlink_station_of_one_row_is_fixed_and_a_moving_flight_has_none(flight):
    report = inspect_logs(str(TLOG), ReaderOptions(tx_power_dbm=20.0, frequency_hz=433e6))
    assert report.fixed_nodes == ["gcs"] and "gcs (one pose row" in report.fixed_note
    assert [n.node for n in report.nodes if n.fixed] == ["gcs"]
    pose, signal, _ = flight
    moving = inspect_logs([str(pose), str(signal)])
    assert moving.fixed_nodes == [] and moving.fixed_note is None
    assert "fixed" not in moving.to_text().replace(str(pose.parent), "")
    doc = _json(moving)
    assert doc["fixed_nodes"] == [] and doc["fixed_note"] is None and not any(n["fixed"] for n in doc["nodes"])


def test_a_fixed_node_logged_sparsely_raises_no_gap_or_rate_problem(flight, tmp_path):
    """Sync holds a node of identical rows still across the steps between them: no sample is dropped there, so
    inspect flags no pose gap or low pose rate for it (it did: 'most samples would drop')."""
    from rplearn.io.files import write_table

    _, signal, still = flight
    pose = pd.read_csv(still, dtype={"node": str})
    b = pose.index[pose["node"] == "B"]
    sparse = pose.drop(index=b[(b % 200 != b[0] % 200) & (b != b[-1])])  # B every 2 s, over the same span
    write_table(sparse, str(tmp_path / "sparse.csv"))
    report = inspect_logs([str(tmp_path / "sparse.csv"), str(signal)])
    assert report.fixed_nodes == ["B"] and not [p for p in report.problems if p.startswith("node B")]
    full = sync_logs([str(still)], [str(signal)], str(tmp_path / "full.parquet"))
    out = sync_logs([str(tmp_path / "sparse.csv")], [str(signal)], str(tmp_path / "sparse.parquet"))
    assert out.counts.n_out == full.counts.n_out and out.counts.fixed_nodes == ["B"]
