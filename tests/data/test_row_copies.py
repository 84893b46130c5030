"""rplearn.data.row_copies: rows repeated across chunks and parts are found as the whole-table
check finds them, whatever the chunks and however the parts are merged."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from rplearn.data.readings import duplicate_rows
from rplearn.data.row_copies import RowCopies, SourceHashes, matched_row_hashes


def table(n: int = 200, seed: int = 0) -> pd.DataFrame:
    """``n`` distinct rows, many of them at one time."""
    rng = np.random.default_rng(seed)
    m = 2 * n
    frame = pd.DataFrame({
        "t": np.round(rng.uniform(0, 50, m), 1),  # many rows share a time
        "tx": rng.choice(["A", "B", "C"], m), "rx": rng.choice(["B", "C", "D"], m),
        "rssi_dbm": rng.integers(-90, -40, m).astype(float), "unit": rng.choice(["learn_0", "test_1"], m),
    })
    return frame.drop_duplicates().iloc[:n].reset_index(drop=True)


def copies_of(frame: pd.DataFrame, source: str, chunk_rows: int) -> RowCopies:
    hashes = SourceHashes(source)
    for start in range(0, len(frame), chunk_rows):
        hashes.add(frame.iloc[start:start + chunk_rows])
    return hashes.finish()


def test_equal_rows_hash_alike_and_rows_differing_in_one_cell_do_not():
    df = table()
    h = matched_row_hashes(df)
    assert np.array_equal(h, matched_row_hashes(df[df.columns[::-1]]))  # the columns' order does not matter
    ints = df.assign(rssi_dbm=df["rssi_dbm"].astype(int))
    assert np.array_equal(h, matched_row_hashes(ints))  # an integer column read from CSV: the same numbers
    assert np.array_equal(h, matched_row_hashes(df.assign(tx=df["tx"].astype(object))))
    for column, value in (("t", 0.05), ("rssi_dbm", 1.0)):
        assert not np.any(matched_row_hashes(df.assign(**{column: df[column] + value})) == h)
    assert not np.any(matched_row_hashes(df.assign(tx=df["tx"] + "x")) == h)
    assert not np.any(matched_row_hashes(df.assign(extra=1.0)) == h)  # another column: other rows
    zeros = pd.DataFrame({"a": [0.0, -0.0, np.nan, -np.float64(np.nan)], "b": ["x", "x", None, None]})
    zh = matched_row_hashes(zeros)
    assert zh[0] == zh[1] and zh[2] == zh[3]  # as pandas' duplicated: -0.0 is 0.0, NaN is NaN


@pytest.mark.parametrize("chunk_rows", [1, 7, 64, 1000])
def test_copies_in_other_chunks_are_counted_as_in_the_whole_table(chunk_rows):
    df = table()
    twice = pd.concat([df, df.iloc[::3], df.iloc[5:9]], ignore_index=True)
    whole = duplicate_rows(twice)
    found = copies_of(twice, "f.parquet", chunk_rows)
    assert found.count == int(whole.sum()) > 0
    assert found.first == int(np.flatnonzero(whole)[0])
    assert twice.iloc[found.earlier].equals(twice.iloc[found.first]) and found.earlier < found.first
    clean = copies_of(df, "f.parquet", chunk_rows)
    assert clean.count == 0 and clean.error() is None


def test_merging_parts_in_any_tree_gives_the_whole_table_count():
    df = table(300, seed=1)
    rows = pd.concat([df.iloc[:100], df.iloc[100:200], df.iloc[50:60], df.iloc[200:], df.iloc[150:155]],
                     ignore_index=True)
    bounds = [0, 100, 200, 210, 310, 315]
    parts = [copies_of(rows.iloc[a:b], f"p{k}.parquet", 13) for k, (a, b) in enumerate(zip(bounds, bounds[1:]))]
    left = parts[0]
    for p in parts[1:]:
        left = left.then(p)
    tree = (parts[0].then(parts[1])).then(parts[2].then(parts[3])).then(parts[4])
    whole = duplicate_rows(rows)
    for merged in (left, tree):
        assert merged.count == int(whole.sum()) == 15
        assert merged.place(merged.first) == ("p2.parquet", 0)
        assert merged.place(merged.earlier) == ("p0.parquet", 50)
        assert merged.holders == ("p2.parquet", "p4.parquet")
        message = str(merged.error())
        assert message.startswith("p2.parquet: 15 row(s) repeat an earlier row in every column (first at row 0, "
                                  "a copy of row 50 of p0.parquet; 2 files hold such rows)")
    assert parts[1].count == 0 and parts[1].hashes.size == 100  # merging changed no input


def test_parts_at_other_times_are_not_compared(monkeypatch):
    df = table()
    a, b = copies_of(df, "a.parquet", 50), copies_of(df.assign(t=df["t"] + 100.0), "b.parquet", 50)
    sorted_calls = []
    real = np.sort
    monkeypatch.setattr(np, "sort", lambda x, *k, **kw: (sorted_calls.append(len(x)), real(x, *k, **kw))[1])
    assert a.then(b).count == 0 and sorted_calls == []  # spans apart: no look-up at all
    assert a.then(copies_of(df, "c.parquet", 50)).count == len(df)


@pytest.mark.parametrize("column", [
    np.array([2**60, 2**60 + 1], np.int64),  # 64-bit ids a float64 rounds alike
    pd.array([2**62 + 1, 2**62], "Int64"),
    np.array([2**64 - 1, 2**64 - 2], np.uint64),
    np.array([1, "1"], object),  # a number and its text
])
def test_rows_the_whole_table_check_keeps_apart_hash_apart(column):
    frame = pd.DataFrame({"t": [1.0, 1.0], "rssi_dbm": [-50.0, -50.0], "tx": column})
    assert not duplicate_rows(frame).any()
    hashes = matched_row_hashes(frame)
    assert hashes[0] != hashes[1]
    assert copies_of(frame, "a.parquet", 1).error() is None


def test_large_integers_still_find_their_copies_and_match_floats_below_2_to_53():
    big = pd.DataFrame({"t": [1.0, 1.0, 2.0], "id": np.array([2**60 + 1, 2**60 + 1, 7], np.int64)})
    assert copies_of(big, "a.parquet", 1).count == 1
    as_int = matched_row_hashes(pd.DataFrame({"t": [1.0], "id": np.array([2**53], np.int64)}))
    as_float = matched_row_hashes(pd.DataFrame({"t": [1.0], "id": [float(2**53)]}))
    assert as_int[0] == as_float[0]
