"""A geodetic pose log (``lat, lon, alt``) with a sentinel in one row (1e308, the largest float32, a value no place
has): a counted drop (``implausible_pose``) with ``nan_policy="drop"``, the other rows read as in the clean log;
by default a one-line error naming the file and the column. By ``read_pose_table``, ``sync`` and the live CSV tail
alike (was: refused whatever the policy, the altitude's refusal naming no column)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from rplearn.errors import InputError
from rplearn.io.options import ReaderOptions
from rplearn.io.tables import read_pose_table

ORIGIN = (47.3977, 8.5456, 488.0)
ROW = 1234  # the row (file order, from 0) that holds the sentinel


@pytest.fixture(scope="module")
def geodetic_flight(tmp_path_factory) -> tuple[Path, Path]:
    """The smoke preset's flight with its poses as latitude, longitude and altitude around :data:`ORIGIN`, both
    logs written by the project's table writer."""
    from rplearn.io.files import write_table
    from rplearn.io.geodetic import local_ned_to_geodetic
    from rplearn.sim import simulate

    sim = simulate("smoke", seed=2)
    pose = sim.pose_log
    ned = np.column_stack([pose["y"], pose["x"], -pose["z"]])
    lat, lon, alt = local_ned_to_geodetic(ned, ORIGIN)
    out = tmp_path_factory.mktemp("geodetic")
    table = pd.DataFrame({"t": pose["t"], "node": pose["node"], "lat": lat, "lon": lon, "alt": alt,
                          **{c: pose[c] for c in ("qw", "qx", "qy", "qz")}})
    write_table(table, str(out / "pose.csv"))
    write_table(sim.signal_log, str(out / "signal.csv"))
    return out / "pose.csv", out / "signal.csv"


def _with_sentinel(path: Path, out: Path, column: str, value: str) -> Path:
    table = pd.read_csv(path, dtype={"node": str})
    table[column] = table[column].astype(object)
    table.loc[ROW, column] = value
    table.to_csv(out, index=False)
    return out


SENTINELS = [("lat", "1e308"), ("lon", "-1e308"), ("alt", "1e308"), ("alt", "3.4028235e38"), ("lat", "1e30"),
             ("alt", "-9999999")]


@pytest.mark.parametrize(("column", "value"), SENTINELS)
def test_a_geodetic_sentinel_is_refused_naming_file_and_column_or_dropped(geodetic_flight, tmp_path, column, value):
    pose, _ = geodetic_flight
    path = _with_sentinel(pose, tmp_path / "pose.csv", column, value)
    with pytest.raises(InputError) as e:
        read_pose_table(str(path))
    line = str(e.value)
    assert "\n" not in line and line.startswith(f"{path}: field {column} has 1 row(s)") and f"row {ROW}" in line
    clean, clean_meta = read_pose_table(str(pose))
    read, meta = read_pose_table(str(path), nan_policy="drop")
    assert meta["dropped"]["implausible_pose"] == 1 and meta["dropped"]["nan_pose"] == 0
    assert meta["origin_geodetic"] == clean_meta["origin_geodetic"]  # the first fix, the sentinel's row not first
    gone = pd.read_csv(pose, dtype={"node": str}).iloc[ROW]
    expected = clean[~((clean["node"] == gone["node"]) & (clean["t"] == gone["t"]))].reset_index(drop=True)
    pd.testing.assert_frame_equal(read.reset_index(drop=True), expected)
    assert np.isfinite(read[["x", "y", "z"]].to_numpy()).all() and read[["x", "y", "z"]].abs().to_numpy().max() < 1e4


def test_sync_with_drop_matches_what_the_clean_log_matches(geodetic_flight, tmp_path):
    from rplearn.workflows.logs import sync_logs

    pose, signal = geodetic_flight
    path = _with_sentinel(pose, tmp_path / "pose.csv", "alt", "1e308")
    clean = sync_logs([str(pose)], [str(signal)], str(tmp_path / "clean.parquet"))
    with pytest.raises(InputError, match=rf"^{path}: field alt has 1 row\(s\)"):
        sync_logs([str(path)], [str(signal)], str(tmp_path / "refused.parquet"))
    out = sync_logs([str(path)], [str(signal)], str(tmp_path / "out.parquet"), ReaderOptions(nan_policy="drop"))
    assert out.counts.n_out == clean.counts.n_out > 2000
    assert f"{path}: dropped 1 pose row(s) (implausible_pose)" in out.notes


@pytest.mark.parametrize("policy", ["error", "drop"])
def test_the_live_csv_tail_drops_or_refuses_a_geodetic_sentinel_alike(geodetic_flight, tmp_path, policy):
    """The sentinel comes in a later poll, after the frame's origin was fixed by the first."""
    from rplearn.io.live_sources import CsvTail

    pose, _ = geodetic_flight
    lines = _with_sentinel(pose, tmp_path / "whole.csv", "lat", "1e308").read_text().splitlines(keepends=True)
    live, signal = tmp_path / "pose.csv", tmp_path / "signal.csv"
    live.write_text("".join(lines[:ROW + 1]))  # the header and the rows before the sentinel's: it begins the next poll
    signal.write_text("t,tx,rx,rssi_dbm,tx_power_dbm,frequency_hz\n")
    tail = CsvTail(str(live), str(signal), ReaderOptions(nan_policy=policy))
    first = tail.poll(final=True)
    with live.open("a") as fh:
        fh.write("".join(lines[ROW + 1:]))
    if policy == "error":
        with pytest.raises(InputError, match=rf"^{live}: field lat has 1 row\(s\).*first at row {ROW}"):
            tail.poll(final=True)
        return
    second = tail.poll(final=True)
    assert second.dropped.get("implausible_pose") == 1
    whole, _ = read_pose_table(str(tmp_path / "whole.csv"), nan_policy="drop")
    got = pd.concat([first.poses, second.poses]).sort_values(["node", "t"], kind="stable").reset_index(drop=True)
    np.testing.assert_allclose(got[["x", "y", "z"]].to_numpy(), whole[["x", "y", "z"]].to_numpy(), atol=1e-6)
