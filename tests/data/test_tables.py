"""rplearn.data.tables: the optional ``armed`` column of a pose log survives validation."""

from __future__ import annotations

import pandas as pd

from rplearn.data.tables import validate_pose_log


def _pose(node: str, t: list[float], **extra) -> pd.DataFrame:
    n = len(t)
    return pd.DataFrame({"t": t, "node": node, "x": 0.0, "y": 0.0, "z": 1.0, "qw": 1.0, "qx": 0.0, "qy": 0.0,
                         "qz": 0.0, **extra}).head(n)


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
