"""Datasets in many files: directories, globs, lists, Hive folders, URLs (issue 13, item 3)."""

from __future__ import annotations

import os

import pandas as pd
import pytest

from rplearn.errors import InputError
from rplearn.io.files import check_output_path, iter_parts, read_dataset, write_table
from rplearn.io.partitions import dataset_parts, hive_columns, is_partitioned, is_url
from rplearn.sim.flight import simulate


@pytest.fixture(scope="module")
def matched():
    return simulate("smoke", seed=3).matched_truth


def _write_parts(root, df, k=4):
    """``df`` cut into ``k`` files under Hive folders ``day=N``, plus files to be skipped."""
    paths = []
    for i, part in enumerate(_split(df, k)):
        path = root / f"day={i}" / "part-0.parquet"
        path.parent.mkdir(parents=True)
        write_table(part, str(path))
        paths.append(str(path))
    (root / "_metadata").write_text("spark metadata")
    (root / ".hidden").mkdir()
    write_table(df.iloc[:5], str(root / ".hidden" / "x.parquet"))
    (root / "notes.txt").write_text("not a table")
    return paths


def _split(df, k):
    n = len(df)
    return [df.iloc[i * n // k:(i + 1) * n // k] for i in range(k)]


def test_a_directory_is_its_table_files_sorted_with_hive_columns_and_nothing_hidden(tmp_path, matched):
    paths = _write_parts(tmp_path, matched)
    parts = dataset_parts(str(tmp_path))
    assert [p.path for p in parts] == paths
    assert [dict(p.columns) for p in parts] == [{"day": str(i)} for i in range(4)]
    assert is_partitioned(str(tmp_path)) and not is_partitioned(paths[0])
    chunks = list(iter_parts(parts, chunk_rows=1000))
    whole = pd.concat(chunks, ignore_index=True)
    assert len(whole) == len(matched)
    assert whole["day"].tolist() == [str(i) for i, part in enumerate(_split(matched, 4)) for _ in range(len(part))]
    assert all(len(c) <= 1000 for c in chunks)


def test_globs_and_comma_lists_name_the_same_files(tmp_path, matched):
    paths = _write_parts(tmp_path, matched)
    assert [p.path for p in dataset_parts(str(tmp_path / "day=*" / "*.parquet"))] == paths
    assert [p.path for p in dataset_parts(",".join(paths[:2]))] == paths[:2]
    with pytest.raises(InputError, match="named twice"):
        dataset_parts(f"{paths[0]},{paths[0]}")


def test_read_dataset_reads_a_folder_whole_and_keeps_a_unit_column_over_the_folder_name(tmp_path, matched):
    root = tmp_path / "unit=folder"
    root.mkdir()
    for i, part in enumerate(_split(matched, 3)):
        write_table(part, str(root / f"p{i}.parquet"))
    df = read_dataset(str(tmp_path))
    assert len(df) == len(matched)
    assert sorted(df["unit"].astype(str).unique()) == sorted(matched["unit"].astype(str).unique())


def test_missing_and_empty_datasets_are_one_line_errors(tmp_path):
    with pytest.raises(InputError, match="nowhere: no such file"):
        dataset_parts(str(tmp_path / "nowhere"))
    (tmp_path / "empty").mkdir()
    with pytest.raises(InputError, match="no table files"):
        dataset_parts(str(tmp_path / "empty"))
    with pytest.raises(InputError, match="no such file"):
        dataset_parts(str(tmp_path / "*.parquet"))
    (tmp_path / "empty" / "a.txt").write_text("x")
    with pytest.raises(InputError, match="no table files"):
        dataset_parts(str(tmp_path / "empty" / "*"))


def test_a_corrupt_part_is_named(tmp_path, matched):
    _write_parts(tmp_path, matched, k=2)
    bad = tmp_path / "day=9" / "part-0.parquet"
    bad.parent.mkdir()
    bad.write_bytes(b"PAR1 not really")
    with pytest.raises(InputError, match=r"day=9.*cannot read table"):
        list(iter_parts(dataset_parts(str(tmp_path))))


def test_an_output_inside_a_dataset_folder_is_refused(tmp_path, matched):
    _write_parts(tmp_path, matched, k=2)
    with pytest.raises(InputError, match="dataset folder this command reads"):
        check_output_path(str(tmp_path / "day=0" / "pred.parquet"), [str(tmp_path)])
    assert check_output_path(str(tmp_path.parent / "pred.parquet"), [str(tmp_path)])


def test_hive_columns_and_urls():
    assert hive_columns("/d", "/d/a=1/b=x/f.parquet") == {"a": "1", "b": "x"}
    assert hive_columns("/d", "/d/f.parquet") == {}
    assert is_url("s3://bucket/x") and is_url("file:///tmp/x") and not is_url("/tmp/x") and not is_url("C:/x")


def test_a_file_url_is_read_through_fsspec(tmp_path, matched):
    if os.environ.get("CI") != "true":
        pytest.importorskip("fsspec")
    paths = _write_parts(tmp_path, matched)
    parts = dataset_parts(tmp_path.as_uri())
    assert [p.path for p in parts] == ["file://" + p for p in paths]
    assert [dict(p.columns) for p in parts] == [{"day": str(i)} for i in range(4)]
    df = read_dataset(tmp_path.as_uri())
    assert len(df) == len(matched)
    assert len(dataset_parts(tmp_path.as_uri() + "/day=*/*.parquet")) == 4
