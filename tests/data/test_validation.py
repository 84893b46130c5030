"""Silent wrong answers refused where data are read (issue 10, class 5), in the library."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from rplearn.core.gauge import Gauge
from rplearn.data.sync import synchronise
from rplearn.data.tables import validate_matched, validate_signal_log
from rplearn.errors import InputError, RplearnError
from rplearn.io import ReaderOptions
from rplearn.models import ModelSpec, load_model

FIXTURES = Path(__file__).resolve().parents[1] / "fixtures" / "models_v1"


@pytest.fixture()
def matched() -> pd.DataFrame:
    return pd.read_csv(FIXTURES / "poses.csv", dtype={"tx": str, "rx": str, "unit": str})


@pytest.mark.parametrize(
    "column, value, needle",
    [
        ("tx", None, "column tx is empty at row 3"),
        ("rx", " ", "column rx is empty at row 3"),
        ("frequency_hz", 2412.0, "2412 looks like MHz"),
        ("frequency_hz", 1e30, "not a radio carrier"),
        ("tx_power_dbm", 1e6, "outside -40 to 60 dBm"),
        ("rssi_dbm", 25.0, "above tx_power_dbm"),
    ],
)
def test_a_matched_dataset_with_impossible_values_is_refused(matched, column, value, needle):
    matched.loc[3, column] = value
    with pytest.raises(InputError, match=needle):
        validate_matched(matched, "d.csv")


def test_a_signal_log_with_an_empty_node_or_a_mhz_frequency_is_refused(matched):
    signal = matched[["t", "tx", "rx", "rssi_dbm", "tx_power_dbm", "frequency_hz"]].copy()
    bad = signal.copy()
    bad.loc[0, "tx"] = np.nan
    with pytest.raises(InputError, match="column tx is empty"):
        validate_signal_log(bad, "s.csv")
    bad = signal.copy()
    bad["frequency_hz"] = 2412.0
    with pytest.raises(InputError, match="looks like MHz"):
        validate_signal_log(bad, "s.csv")


def test_sync_drops_and_counts_packets_stronger_than_sent():
    t = np.arange(0.0, 10.0, 0.1)
    poses = pd.DataFrame({"t": np.concatenate([t, t]), "node": ["A"] * t.size + ["B"] * t.size,
                          "x": [0.0] * t.size + [30.0] * t.size, "y": 0.0, "z": 20.0,
                          "qw": 1.0, "qx": 0.0, "qy": 0.0, "qz": 0.0})
    signal = pd.DataFrame({"t": [1.0, 2.0, 3.0], "tx": "A", "rx": "B", "rssi_dbm": [-50.0, 25.0, -60.0],
                           "tx_power_dbm": 20.0, "frequency_hz": 2.4e9})
    result = synchronise(poses, signal)
    assert len(result.dataset) == 2 and result.summary.dropped["implausible_rssi"] == 1


@pytest.mark.parametrize(
    "make, needle",
    [
        (lambda: ReaderOptions(frequency_hz=2412.0), "looks like MHz"),
        (lambda: ReaderOptions(tx_power_dbm=1e6), "tx_power_dbm"),
        (lambda: ModelSpec("sh", 3.7), "order: expected an integer"),
        (lambda: Gauge("A", float("nan")), "finite"),
        (lambda: load_model(FIXTURES / "sh5.json").evaluate("A", [0.0], [45.0]), "degrees by mistake"),
    ],
)
def test_values_that_cannot_be_meant_are_refused_by_the_api(make, needle):
    with pytest.raises(RplearnError, match=needle):
        make()


def test_a_negative_seed_is_refused():
    from rplearn.sim import simulate

    with pytest.raises(InputError, match="seed"):
        simulate("smoke", seed=-1)


def test_euler_columns_of_two_frames_are_refused_not_half_read(tmp_path):
    """roll_deg, pitch_deg with yaw_ned_deg would silently drop the tilt (level flight assumed)."""
    from rplearn.io.tables import read_pose_table

    path = tmp_path / "p.csv"
    pd.DataFrame({"t": [0.0, 1.0], "node": "A", "x": 0.0, "y": 0.0, "z": 10.0, "roll_deg": 5.0, "pitch_deg": 3.0,
                  "yaw_ned_deg": 90.0}).to_csv(path, index=False)
    with pytest.raises(InputError, match="mix frames: roll_deg, pitch_deg .ENU/FLU. with yaw_ned_deg"):
        read_pose_table(str(path))


def test_a_model_file_with_nan_is_refused_in_one_line(tmp_path):
    from rplearn.errors import ModelFileError

    text = (FIXTURES / "mean.json").read_text().replace('"n_samples": 1341', '"n_samples": NaN', 1)
    assert "NaN" in text
    (tmp_path / "nan.json").write_text(text)
    with pytest.raises(ModelFileError, match="NaN is not a JSON number"):
        load_model(tmp_path / "nan.json")
