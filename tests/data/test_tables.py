"""rplearn.data.tables: the optional ``armed`` column of a pose log survives validation; a matched
dataset holding its rows twice is refused."""

from __future__ import annotations

import pandas as pd
import pytest

from rplearn.data.tables import MATCHED_COLUMNS, validate_matched, validate_pose_log
from rplearn.errors import InputError


def _pose(node: str, t: list[float], **extra) -> pd.DataFrame:
    n = len(t)
    return pd.DataFrame({"t": t, "node": node, "x": 0.0, "y": 0.0, "z": 1.0, "qw": 1.0, "qx": 0.0, "qy": 0.0,
                         "qz": 0.0, **extra}).head(n)


def test_a_coordinate_beyond_any_place_is_refused_naming_the_file_field_and_row():
    """Any reader's pose log with a sentinel coordinate (1e308): refused at the check every pose log
    passes, not matched into overflowing distances and infinite joint gains."""
    df = _pose("D", [0.0, 1.0, 2.0])
    df.loc[1, "z"] = 1e308
    with pytest.raises(InputError, match=r"^flight.bag: z 1e\+308 at row 1 is outside -1e\+08 to 1e\+08 m"):
        validate_pose_log(df, "flight.bag")


def test_armed_is_kept_and_sorted_with_its_rows():
    df = _pose("D", [3.0, 1.0, 2.0], armed=[True, False, True])
    out = validate_pose_log(df)
    assert out["t"].tolist() == [1.0, 2.0, 3.0] and out["armed"].tolist() == [False, True, True]
    assert out["armed"].dtype == bool
    assert "armed" not in validate_pose_log(_pose("D", [1.0, 2.0])).columns  # optional


def test_armed_is_missing_where_a_log_does_not_say():
    both = pd.concat([_pose("D", [1.0, 2.0], armed=[False, True]), _pose("G", [1.0])], ignore_index=True)
    out = validate_pose_log(both)
    assert str(out["armed"].dtype) == "boolean"
    assert out.loc[out["node"] == "D", "armed"].tolist() == [False, True]
    assert out.loc[out["node"] == "G", "armed"].isna().all()


def test_armed_values_that_are_not_booleans_are_refused():
    import pytest

    from rplearn.errors import InputError

    with pytest.raises(InputError, match="poses.csv: column armed"):
        validate_pose_log(_pose("D", [1.0, 2.0], armed=["yes", "no"]), "poses.csv")
    assert validate_pose_log(_pose("D", [1.0, 2.0], armed=[1, 0]))["armed"].tolist() == [True, False]


def _matched(n: int) -> pd.DataFrame:
    row = {c: 0.0 for c in MATCHED_COLUMNS} | {"tx": "A", "rx": "B", "rssi_dbm": -60.0, "tx_power_dbm": 20.0,
                                               "frequency_hz": 2.412e9, "tx_qw": 1.0, "rx_qw": 1.0, "rx_x": 30.0}
    return pd.DataFrame([row] * n).assign(t=[0.1 * k for k in range(n)])


def test_a_matched_dataset_in_the_file_twice_is_refused_naming_the_first_copy():
    once = _matched(5)
    assert len(validate_matched(once, "d.parquet")) == 5
    with pytest.raises(InputError, match=r"d.parquet: 5 row\(s\) repeat an earlier row in every column \(first at row 5\)"):
        validate_matched(pd.concat([once, once], ignore_index=True), "d.parquet")
    # rows at one time that differ (another link, another RSSI) are samples, not copies
    other = once.assign(rssi_dbm=-61.0)
    assert len(validate_matched(pd.concat([once, other], ignore_index=True), "d.parquet")) == 10
    # poses to predict from (no RSSI to learn from or score) may repeat: each gets its prediction
    assert len(validate_matched(pd.concat([once, once]), "d.parquet", require_rssi=False)) == 10
