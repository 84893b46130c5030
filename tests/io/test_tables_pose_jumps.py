"""rplearn.io.tables: in-range sentinels and positions before the fix in canonical pose tables
(the rule of the MAVLink readers, at each node's own top speed), and coordinates beyond any place counted as what they are."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from rplearn.errors import InputError
from rplearn.io.tables import read_pose_table


def _flight_csv(path: Path, xyz: np.ndarray, dt_s: float = 0.1) -> str:
    n = len(xyz)
    df = pd.DataFrame({"t": np.arange(n) * dt_s, "node": "D", "x": xyz[:, 0], "y": xyz[:, 1], "z": xyz[:, 2],
                       "qw": 1.0, "qx": 0.0, "qy": 0.0, "qz": 0.0})
    station = pd.DataFrame({"t": [0.0], "node": ["G"], "x": [0.0], "y": [0.0], "z": [1.5], "qw": [1.0],
                            "qx": [0.0], "qy": [0.0], "qz": [0.0]})
    pd.concat([df, station], ignore_index=True).to_csv(path, index=False)
    return str(path)


def _track(n: int = 40, speed_m_s: float = 10.0, dt_s: float = 0.1) -> np.ndarray:
    """A circle of radius 200 m around (300, 0) flown at ``speed_m_s``, 30 m up."""
    a = np.arange(n) * speed_m_s * dt_s / 200.0
    return np.stack([300 + 200 * np.cos(a), 200 * np.sin(a), np.full(n, 30.0)], axis=-1)


def test_an_in_range_altitude_sentinel_is_refused_naming_file_node_and_row(tmp_path):
    xyz = _track()
    xyz[17, 2] = -1000.0
    p = _flight_csv(tmp_path / "pose.csv", xyz)
    with pytest.raises(InputError) as e:
        read_pose_table(p)
    msg = str(e.value)
    assert "\n" not in msg and msg.startswith(f"{p}: fields x, y, z of node D jump")
    assert "first at row 17" in msg and "nan_policy='drop'" in msg
    pose, meta = read_pose_table(p, nan_policy="drop")
    assert meta["dropped"]["position_jump"] == 1 and len(pose) == 40 and pose["z"].min() > 0
    assert "1 of its 40 row(s)" in meta["notes"][0]


def test_zeros_before_the_fix_are_a_counted_named_drop(tmp_path):
    xyz = _track()
    xyz[:6] = 0.0  # the logger wrote the origin until the GPS fix was valid
    pose, meta = read_pose_table(_flight_csv(tmp_path / "pose.csv", xyz), nan_policy="drop")
    d = pose[pose["node"] == "D"]
    assert meta["dropped"]["position_jump"] == 6 and len(d) == 34 and d["t"].iloc[0] == pytest.approx(0.6)


def test_a_wrong_side_as_long_as_the_flight_is_refused_even_with_drop(tmp_path):
    xyz = _track()
    xyz[:20] = 0.0
    with pytest.raises(InputError, match=r"20 of its 40 row\(s\).*which side is valid is unclear"):
        read_pose_table(_flight_csv(tmp_path / "pose.csv", xyz), nan_policy="drop")


@pytest.mark.parametrize(("speed_m_s", "dt_s"), [(35.0, 0.1), (35.0, 1.0), (15.0, 5.0)])
def test_real_fast_or_sparse_flight_passes(tmp_path, speed_m_s, dt_s):
    xyz = _track(speed_m_s=speed_m_s, dt_s=dt_s)
    xyz[:, 2] += np.linspace(0, 10 * dt_s * 39, 40)  # climbing at 10 m/s
    pose, meta = read_pose_table(_flight_csv(tmp_path / "pose.csv", xyz, dt_s))
    assert len(pose) == 41 and meta["dropped"]["position_jump"] == 0


def test_a_coordinate_beyond_any_place_is_counted_as_implausible_not_nan(tmp_path):
    xyz = _track()
    xyz[5, 0], xyz[9, 1] = 3e9, np.nan
    pose, meta = read_pose_table(_flight_csv(tmp_path / "pose.csv", xyz), nan_policy="drop")
    assert meta["dropped"] == {"nan_pose": 1, "implausible_pose": 1, "duplicate_pose": 0, "conflicting_pose": 0,
                                 "position_jump": 0, "repeated_header": 0} and len(pose) == 39


def test_inspect_says_the_jump_sync_would_drop(tmp_path):
    from rplearn.io.inspect import inspect_logs

    xyz = _track()
    xyz[17, 2] = -1000.0
    text = inspect_logs([_flight_csv(tmp_path / "pose.csv", xyz)]).to_text()
    assert "dropped on reading: 1 pose row(s) (position_jump)" in text and "fields x, y, z of node D jump" in text


def test_a_sentinel_at_the_end_is_the_piece_dropped_not_the_flight(tmp_path):
    xyz = _track(n=60)
    xyz[-1] = 0.0  # a logger writing zeros at shutdown
    p = _flight_csv(tmp_path / "pose.csv", xyz)
    with pytest.raises(InputError, match=r"1 of its 60 row\(s\) lie on the wrong side of a jump, first at row 59"):
        read_pose_table(p)
    pose, meta = read_pose_table(p, nan_policy="drop")
    d = pose[pose["node"] == "D"]
    assert meta["dropped"]["position_jump"] == 1 and len(d) == 59 and d["z"].min() == pytest.approx(30.0)


@pytest.mark.parametrize(("speed_m_s", "dt_s"), [(70.0, 0.2), (120.0, 0.1), (60.0, 1.0)])
def test_a_vehicle_faster_than_a_multicopter_passes(tmp_path, speed_m_s, dt_s):
    xyz = _track(n=80, speed_m_s=speed_m_s, dt_s=dt_s)
    pose, meta = read_pose_table(_flight_csv(tmp_path / "pose.csv", xyz, dt_s))
    assert len(pose) == 81 and meta["dropped"]["position_jump"] == 0
    xyz[40, 2] = -1000.0  # and a sentinel in it is still found
    with pytest.raises(InputError, match=r"top speed \(\d+ m/s across.*first at row 40"):
        read_pose_table(_flight_csv(tmp_path / "pose2.csv", xyz, dt_s))


def test_sentinels_at_both_ends_are_dropped_and_the_flight_kept(tmp_path):
    xyz = _track(n=100)
    xyz[:5] = 0.0  # before the fix
    xyz[-3:, 2] = -1000.0  # and at shutdown
    pose, meta = read_pose_table(_flight_csv(tmp_path / "pose.csv", xyz), nan_policy="drop")
    d = pose[pose["node"] == "D"]
    assert meta["dropped"]["position_jump"] == 8 and len(d) == 92 and d["z"].min() == pytest.approx(30.0)


@pytest.mark.parametrize("every", [2, 3, 4])
def test_frequent_sentinels_are_not_taken_for_speed(tmp_path, every):
    xyz = _track(n=120)
    xyz[::every, 2] = -1000.0
    with pytest.raises(InputError, match="fields x, y, z of node D jump"):
        read_pose_table(_flight_csv(tmp_path / "pose.csv", xyz))


def test_a_fast_flight_after_long_ground_time_is_kept(tmp_path):
    ground = np.tile([[300.0 + 200.0, 0.0, 0.5]], (320, 1))  # 320 s idle at the take-off point, 1 Hz
    flight = _track(n=80, speed_m_s=70.0, dt_s=1.0)
    flight[:, 2] = 30.0
    xyz = np.vstack([ground, flight])
    pose, meta = read_pose_table(_flight_csv(tmp_path / "pose.csv", xyz, dt_s=1.0))
    assert meta["dropped"]["position_jump"] == 0 and len(pose) == 401
