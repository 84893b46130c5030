"""The one resolver of inputs and outputs (issue 29, classes 1 and 2; acceptance 2).

Random path specs of real files (lists, globs, directories, symbolic links, ``./``, ``..`` and
absolute spellings) with outputs among them, through the library's own entry points: no input
is ever overwritten or removed, no file is read twice, and nothing but a one-line
:class:`RplearnError` comes out.
"""

from __future__ import annotations

import glob
import hashlib
import os
import tempfile
from contextlib import contextmanager

import pandas as pd
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rplearn.errors import InputError, RplearnError
from rplearn.io.files import read_dataset, write_table
from rplearn.io.partitions import dataset_parts, file_identity
from rplearn.io.resolve import check_outputs, distinct_inputs, input_files
from rplearn.models.spec import ModelSpec
from rplearn.sim.flight import simulate
from rplearn.workflows.learning import fit_dataset

ROWS = {"a.parquet": 40, "b.parquet": 55, "sub/c.parquet": 70}
#: How each file may be spelled (the link is a symbolic link to a.parquet beside it).
SPELLINGS = {
    "a.parquet": ["a.parquet", "./a.parquet", "sub/../a.parquet", "{abs}/a.parquet", "link.parquet"],
    "b.parquet": ["b.parquet", "./b.parquet", "{abs}/b.parquet"],
    "sub/c.parquet": ["sub/c.parquet", "./sub/c.parquet", "{abs}/sub/c.parquet"],
}
PIECES = [s for spellings in SPELLINGS.values() for s in spellings] + ["sub", ".", "*.parquet", "sub/*.parquet",
                                                                       "{abs}/sub", "*/*.parquet"]
OUTPUTS = [*PIECES[:8], "link.parquet", "new.parquet", "sub/new.parquet", "out.json", "sub/out.json", "sub", "{abs}/new.csv"]


@pytest.fixture(scope="module")
def matched():
    return simulate("smoke", seed=3).matched_truth.drop(columns=["unit"], errors="ignore")


@contextmanager
def _folder(matched):
    """A fresh folder of three tables of distinct sizes and a link, as the working directory."""
    old = os.getcwd()
    with tempfile.TemporaryDirectory() as root:
        os.mkdir(os.path.join(root, "sub"))
        start = 0
        for name, n in ROWS.items():
            write_table(matched.iloc[start:start + n], os.path.join(root, name))
            start += n
        os.symlink("a.parquet", os.path.join(root, "link.parquet"))
        os.chdir(root)
        try:
            yield root
        finally:
            os.chdir(old)


def _digests(root):
    out = {}
    for folder, _, files in os.walk(root):
        for f in files:
            path = os.path.join(folder, f)
            if os.path.isfile(path):
                with open(path, "rb") as fh:
                    out[os.path.relpath(path, root)] = hashlib.sha256(fh.read()).hexdigest()
    return out


def _expected_files(pieces, root):
    """The files the pieces name, as the user means them (one entry per naming)."""
    named = []
    for piece in pieces:
        if glob.has_magic(piece):
            named += [p for p in sorted(glob.glob(piece)) if os.path.isfile(p)]
        elif os.path.isdir(piece):
            for folder, dirs, files in os.walk(piece):
                dirs.sort()
                named += [os.path.join(folder, f) for f in sorted(files) if f.endswith(".parquet")]
        else:
            named.append(piece)
    return named


def _rows_of(path):
    real = os.path.relpath(os.path.realpath(path))
    return ROWS[real.replace(os.sep, "/")]


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(pieces=st.lists(st.sampled_from(PIECES), min_size=1, max_size=3), output=st.sampled_from(OUTPUTS))
def test_random_path_specs_never_overwrite_an_input_nor_read_a_file_twice(matched, pieces, output):
    with _folder(matched) as root:
        pieces = [p.format(abs=root) for p in pieces]
        output = output.format(abs=root)
        spec = ",".join(pieces)
        named = _expected_files(pieces, root)
        ids = [file_identity(p) for p in named]
        twice = len(set(ids)) < len(ids)
        before = _digests(root)
        try:
            table = read_dataset(spec)
        except RplearnError as exc:
            assert twice, f"{spec}: refused without a file named twice: {exc}"
            assert "\n" not in str(exc) and "give it once" in str(exc)
        else:
            assert not twice, f"{spec}: a file named twice was read"
            assert len(table) == sum(_rows_of(p) for p in named)  # every file once
        inputs = {file_identity(p) for p in named}
        is_input = os.path.exists(output) and file_identity(output) in inputs
        try:
            fit_dataset(spec, ModelSpec("mean"), output=output)
        except RplearnError as exc:
            assert "\n" not in str(exc)
        else:
            assert not is_input and not twice, f"{spec} -o {output}: wrote over an input"
        after = _digests(root)
        for name, digest in before.items():  # no file removed; every input byte-identical
            assert name in after, f"{spec} -o {output}: {name} removed"
            if file_identity(os.path.join(root, name)) in inputs:
                assert after[name] == digest, f"{spec} -o {output}: input {name} overwritten"


def test_one_file_given_twice_is_refused_naming_both_spellings(matched):
    with _folder(matched) as root:
        for spec in ("a.parquet,./a.parquet", f"a.parquet,{root}/a.parquet", ".", "a.parquet,link.parquet"):
            with pytest.raises(InputError, match="are one file") as err:
                dataset_parts(spec)
            assert "link.parquet" in str(err.value) or "./a.parquet" in str(err.value) or root in str(err.value)
        with pytest.raises(InputError, match=r"a\.parquet and \./a\.parquet are one file"):
            distinct_inputs(["a.parquet", "./a.parquet"], param="pose_paths")
        distinct_inputs(["a.parquet", "b.parquet"])


def test_every_output_is_checked_against_every_file_folder_and_glob_of_the_inputs(matched):
    with _folder(matched):
        refused = [
            ({"output": "b.parquet"}, ["a.parquet,b.parquet"], "is also an input"),
            ({"output": "sub/c.parquet"}, ["sub/*.parquet"], "is also an input"),
            ({"output": "sub/x.parquet"}, ["sub/*.parquet"], "would join"),
            ({"output": "sub/x.json"}, ["sub"], "inside sub"),
            ({"output": "link.parquet"}, ["a.parquet"], "is also an input"),
            ({"output": "a.json", "plot_path": "./a.json"}, ["b.parquet"], "is also given as output"),
        ]
        for outputs, inputs, words in refused:
            with pytest.raises(InputError, match=words):
                check_outputs(outputs, inputs)
        check_outputs({"output": "sub/x.json", "plot_path": "x.png"}, ["sub/*.parquet", "a.parquet"])
        check_outputs({"output": "sub/model.json"}, ["sub/*"])  # matches the glob, but is no table: never read
        assert sorted(input_files(["sub,b.parquet"])) == ["b.parquet", "sub", "sub/c.parquet"]


def test_a_hive_folder_named_after_a_measurement_is_refused_naming_it(matched):
    with _folder(matched) as root:
        folder = os.path.join(root, "h", "rssi_dbm=-50")
        os.makedirs(folder)
        write_table(matched.iloc[:30], os.path.join(folder, "x.parquet"))
        write_table(matched.iloc[:30].drop(columns=["rssi_dbm"]), os.path.join(root, "h", "rssi_dbm=-50", "y.csv"))
        with pytest.raises(InputError, match=r"rssi_dbm=-50: a folder named after the measurement rssi_dbm"):
            read_dataset("h")
        unit = os.path.join(root, "u", "unit=folder")
        os.makedirs(unit)
        write_table(matched.iloc[:30].assign(unit="learn_0"), os.path.join(unit, "x.parquet"))
        assert set(read_dataset("u")["unit"].astype(str)) == {"learn_0"}  # the file's column is kept


def test_a_glob_that_matches_nothing_is_a_one_line_error(matched):
    with _folder(matched):
        with pytest.raises(InputError, match="no such file"):
            read_dataset("nothing/*.parquet")
        assert pd.read_parquet("a.parquet").shape[0] == ROWS["a.parquet"]


def test_read_logs_refuses_one_log_named_twice(matched):
    from rplearn.io import read_logs

    with _folder(matched):
        pd.DataFrame({"t": [0.0, 1.0], "node": ["A", "A"], "x": 0.0, "y": 0.0, "z": 1.0, "qw": 1.0, "qx": 0.0,
                      "qy": 0.0, "qz": 0.0}).to_csv("pose.csv", index=False)
        assert len(read_logs(["pose.csv"])[0].pose) == 2
        with pytest.raises(InputError, match=r"pose\.csv and \./pose\.csv are one file"):
            read_logs(["pose.csv", "./pose.csv"])
