"""rplearn.models.streamed: a pattern fit that reads its dataset a chunk at a time gives the model
the whole-dataset fit gives, checks the model size before reading the data, and names the rows of
a bad chunk (issue 10: big CSV datasets were read whole)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from rplearn.core.lsq.block_sums import DEFAULT_BLOCK_S
from rplearn.errors import InputError, RplearnError
from rplearn.io.files import read_dataset
from rplearn.models import ModelSpec
from rplearn.models import streamed as streamed_module
from rplearn.models.options import FitOptions
from rplearn.models.streamed import weighted_median
from rplearn.sim import simulate
from rplearn.workflows import fleet, learning
from rplearn.workflows.logs import sync_logs


@pytest.fixture(scope="module")
def dataset(tmp_path_factory):
    d = tmp_path_factory.mktemp("streamfit")
    simulate("smoke", seed=4, out_dir=str(d / "f"))
    sync_logs([str(d / "f" / "pose_log.parquet")], [str(d / "f" / "signal_log.parquet")], str(d / "m.parquet"))
    df = pd.read_parquet(d / "m.parquet")
    df.loc[7, "tx_qw"] *= 1.5  # one non-unit quaternion, counted by both paths
    df.loc[df.index % 3 == 0, "frequency_hz"] = 2.437e9  # two channels: the median is taken over both
    df.to_parquet(d / "m.parquet", index=False)
    df.to_csv(d / "m.csv", index=False)
    return d


def streamed(monkeypatch, chunk_rows=97):
    monkeypatch.setattr(learning, "STREAM_FIT_ROWS", 0)
    monkeypatch.setattr(learning, "STREAM_FIT_BYTES", 0)
    monkeypatch.setattr(fleet, "PART_CHUNK_ROWS", chunk_rows)  # the id columns and the times
    monkeypatch.setattr(streamed_module, "PART_CHUNK_ROWS", chunk_rows)  # the statistics


@pytest.mark.parametrize("name", ["m.parquet", "m.csv"])
@pytest.mark.parametrize("label", ["sh-4", "bg-3", "poly-3"])
def test_streamed_fit_equals_the_whole_fit(dataset, monkeypatch, name, label):
    path = str(dataset / name)
    whole = learning.fit_dataset(path, ModelSpec.parse(label))
    streamed(monkeypatch)
    chunked = learning.fit_dataset(path, ModelSpec.parse(label))
    a, b = whole.fitted.model, chunked.fitted.model
    np.testing.assert_allclose(b.coef, a.coef, rtol=1e-8, atol=1e-8)
    np.testing.assert_allclose(b.covariance, a.covariance, rtol=1e-6, atol=1e-10)
    assert b.nodes == a.nodes and chunked.n_samples == whole.n_samples
    assert b.training["rmse_db"] == pytest.approx(a.training["rmse_db"], rel=1e-9)
    assert b.training["frequency_hz"] == a.training["frequency_hz"]
    assert chunked.units.units == whole.units.units and chunked.units.notes == whole.units.notes
    assert chunked.non_unit_quaternions == whole.non_unit_quaternions == 1


def test_streamed_fit_checks_the_size_before_reading_the_data(dataset, monkeypatch):
    streamed(monkeypatch)
    read = []
    real = fleet.iter_parts
    for module in (fleet, streamed_module):  # the index, and the statistics
        monkeypatch.setattr(module, "iter_parts", lambda *a, **k: (read.append(k.get("columns")), real(*a, **k))[1])
    with pytest.raises(RplearnError, match="the largest sh order that fits is"):
        learning.fit_dataset(str(dataset / "m.csv"), ModelSpec("sh", 1000))
    assert read == [("tx", "rx", "unit", "frequency_hz")]  # only the id columns and the carrier (its band) were read


def test_a_bad_row_is_named_by_its_place_in_the_file(dataset, monkeypatch, tmp_path):
    df = pd.read_csv(dataset / "m.csv")
    df.loc[250, "rx_x"] = np.nan
    df.to_csv(tmp_path / "bad.csv", index=False)
    streamed(monkeypatch, chunk_rows=100)
    with pytest.raises(InputError, match=r"bad.csv \(rows 200 to 299\).*rx_x.*row 50"):
        learning.fit_dataset(str(tmp_path / "bad.csv"), ModelSpec("sh", 3))


def test_weighted_median():
    assert weighted_median({}) is None
    assert weighted_median({2.412e9: 3, 2.437e9: 1}) == 2.412e9
    assert weighted_median({2.40e9: 1, 2.42e9: 1}) == 2.41e9
    assert weighted_median({2.40e9: 1, 2.41e9: 1, 2.42e9: 1}) == np.median([2.40e9, 2.41e9, 2.42e9])
    with pytest.raises(InputError, match=r"carriers of 2 bands: 2.412 GHz \(3 samples\), 5.8 GHz \(1 samples\)"):
        weighted_median({2.412e9: 3, 5.8e9: 1})  # one band per model


@pytest.mark.parametrize("name", ["m.parquet", "m.csv"])
def test_streamed_auto_fit_equals_the_whole_auto_fit(dataset, monkeypatch, name):
    path = str(dataset / name)
    whole = learning.fit_dataset(path, ModelSpec("sh", 3), options=FitOptions(auto=True))
    streamed(monkeypatch)
    chunked = learning.fit_dataset(path, ModelSpec("sh", 3), options=FitOptions(auto=True))
    a, b = whole.fitted.model, chunked.fitted.model
    assert (chunked.selection.order, chunked.selection.smoothing) == (whole.selection.order, whole.selection.smoothing)
    np.testing.assert_allclose(b.coef, a.coef, rtol=1e-7, atol=1e-7)
    assert b.training["coverage_deg"] == a.training["coverage_deg"]
    # the certificate's unsplit components from the selection's X^T X: there although the pairs of
    # directions were streamed, and the same as read from the samples in memory
    whole_cert, chunked_cert = a.training.decoupling, b.training.decoupling
    assert "components" in chunked_cert and chunked_cert["n_unsplit"] == whole_cert["n_unsplit"]
    assert chunked_cert["unsplit_db"] == pytest.approx(whole_cert["unsplit_db"], rel=1e-6)
    assert not any("not kept" in note for note in chunked_cert["notes"])


def test_streamed_auto_fit_stores_the_in_memory_fits_drift_and_planning_weight_whatever_the_chunks(dataset, monkeypatch):
    """``fit --order auto`` streamed a chunk at a time stores the drifting error
    (``training.drift_std_db``) and the planning prior (``training.planning_penalty_weight``) of
    the in-memory fit of the same rows, whatever the chunk size: each unit's sums per 5-s block
    are kept in the statistics' own pass and added up by block across chunks, a block cut by a
    chunk boundary included (streamed fits stored no drift: ``trajectory --from-model`` refused
    their model files)."""
    path = str(dataset / "m.parquet")
    whole = learning.fit_dataset(path, ModelSpec.parse("sh"), options=FitOptions(auto=True)).fitted.model.training
    assert whole.drift_std_db is not None and whole.drift_std_db > 0 and whole.planning_penalty_weight > 0
    t = pd.read_parquet(path)["t"].to_numpy(np.float64)
    block = np.floor(t / DEFAULT_BLOCK_S)
    for rows in (97, 1000, 500_000):
        straddled = np.any(block[rows::rows] == block[rows - 1:-1:rows])  # a block on both sides of a chunk boundary
        assert straddled or rows >= len(t)
        streamed(monkeypatch, rows)
        for name in ("m.parquet", "m.csv") if rows == 97 else ("m.parquet",):
            chunked = learning.fit_dataset(str(dataset / name), ModelSpec.parse("sh"), options=FitOptions(auto=True))
            got = chunked.fitted.model.training
            assert got.drift_std_db == pytest.approx(whole.drift_std_db, rel=1e-9), (rows, name)
            assert got.planning_penalty_weight == pytest.approx(whole.planning_penalty_weight, rel=1e-9), (rows, name)


def test_streamed_unit_statistics_keep_the_same_time_block_sums_whatever_the_chunks(dataset):
    """The per-block sums an automatic fit's units keep: one vector per unit, 5-s block and
    directed link (their count set by the flight's duration, not by its rows or its chunks) of
    SH-10's coefficients only (what the drift is read at, whatever the largest order), equal to
    rounding between one chunk and chunks of 97 rows; a fixed-order fit keeps none."""
    df = read_dataset(str(dataset / "m.parquet"))
    nodes = sorted(set(df["tx"].astype(str)) | set(df["rx"].astype(str)))
    spec = ModelSpec("sh", 12)
    one, *_ = streamed_module.unit_statistics_streamed([df], spec, nodes)
    many, *_ = streamed_module.unit_statistics_streamed((df.iloc[i:i + 97] for i in range(0, len(df), 97)), spec, nodes)
    assert set(one) == set(many)
    for unit, st in one.items():
        other = many[unit]
        assert st.block_directed and set(st.block_directed) == set(other.block_directed)
        for label, links in st.block_directed.items():
            assert set(links) == set(other.block_directed[label])
            for key, sums in links.items():
                np.testing.assert_allclose(other.block_directed[label][key], sums, rtol=1e-9, atol=1e-9)
        rows = df[df["unit"].astype(str) == unit]
        kept = rows.assign(b=np.floor(rows["t"] / DEFAULT_BLOCK_S)).groupby(["b", "tx", "rx"]).ngroups
        assert sum(len(links) for links in st.block_directed.values()) == kept
        assert {v.size for links in st.block_directed.values() for v in links.values()} == {2 * 100 + 3}
    fixed = streamed_module.accumulate([df], spec, nodes, None, "d", by_unit=False)
    assert not fixed.stats["all"].block_directed


def _refusal(call) -> str:
    with pytest.raises(InputError) as info:
        call()
    return str(info.value)


@pytest.mark.parametrize("chunk_rows", [97, 1000, 500_000])
@pytest.mark.parametrize("name", ["twice.parquet", "twice.csv"])
def test_a_dataset_written_twice_is_refused_streamed_as_in_memory(dataset, monkeypatch, tmp_path, name, chunk_rows):
    """The copies of a dataset written twice into one file are in different chunks: the check
    runs over the whole file, and says what the in-memory check says (file, count, first row).
    Every other row of the flight (1,321 rows, both units): still more than 1,000, so that each
    chunk size keeps the two copies of every row in different chunks, or (500,000) in one."""
    df = pd.read_parquet(dataset / "m.parquet").iloc[::2].reset_index(drop=True)
    assert len(df) > 1000 and df["unit"].nunique() == 2
    path = str(tmp_path / name)
    twice = pd.concat([df, df], ignore_index=True)
    twice.to_parquet(path, index=False) if name.endswith(".parquet") else twice.to_csv(path, index=False)
    whole = _refusal(lambda: learning.fit_dataset(path, ModelSpec("sh", 3)))
    assert whole.startswith(f"{path}: {len(df):,} row(s) repeat an earlier row in every column (first at row {len(df)})")
    assert "\n" not in whole
    streamed(monkeypatch, chunk_rows)
    assert _refusal(lambda: learning.fit_dataset(path, ModelSpec("sh", 3))) == whole
    auto = _refusal(lambda: learning.fit_dataset(path, ModelSpec("sh", 3), options=FitOptions(auto=True)))
    assert auto == whole


def test_part_files_holding_the_same_rows_are_refused_naming_both(dataset, monkeypatch, tmp_path):
    df = pd.read_parquet(dataset / "m.parquet")
    folder = tmp_path / "parts"
    folder.mkdir()
    df.to_parquet(folder / "a.parquet", index=False)
    later = df.iloc[100:].copy()  # a later file repeating part of the first, then rows of its own
    later["t"] = later["t"].where(later.index < 500, later["t"] + 1e4)
    later.to_csv(folder / "b.csv", index=False)
    streamed(monkeypatch, 97)
    message = _refusal(lambda: learning.fit_dataset(str(folder), ModelSpec("sh", 3)))
    assert message.startswith(f"{folder / 'b.csv'}: 400 row(s) repeat an earlier row in every column "
                              f"(first at row 0, a copy of row 100 of {folder / 'a.parquet'}")
    assert "\n" not in message
    streamed(monkeypatch, 500_000)  # one chunk a file: the same message
    assert _refusal(lambda: learning.fit_dataset(str(folder), ModelSpec("sh", 3))) == message


def test_part_files_holding_the_same_rows_are_not_scored_twice(dataset, monkeypatch, tmp_path):
    """``evaluate`` of a dataset in many files predicts part by part: rows repeated in another
    file (or later in the same file) are refused with the fit's message, not scored twice
    (Table I's AIC doubled and every sample weighed double). Every other row of the flight
    (1,321 rows, both units, still 14 chunks of 97): the copies are found whatever the size."""
    df = pd.read_parquet(dataset / "m.parquet").iloc[::2].reset_index(drop=True)
    model = str(tmp_path / "m.json")
    learning.fit_dataset(str(dataset / "m.parquet"), ModelSpec("sh", 3), output=model)
    folder = tmp_path / "parts"
    folder.mkdir()
    df.to_parquet(folder / "a.parquet", index=False)
    df.iloc[100:600].to_csv(folder / "b.csv", index=False)  # a later file repeating rows of the first
    streamed(monkeypatch, 97)
    fitted = _refusal(lambda: learning.fit_dataset(str(folder), ModelSpec("sh", 3)))
    assert _refusal(lambda: learning.evaluate_model_files([model], str(folder))) == fitted
    assert _refusal(lambda: read_dataset(str(folder))) == fitted  # read whole (sweep, report): the same line
    assert fitted.startswith(f"{folder / 'b.csv'}: 500 row(s) repeat an earlier row in every column "
                             f"(first at row 0, a copy of row 100 of {folder / 'a.parquet'}")
    (folder / "b.csv").unlink()
    pd.concat([df.iloc[:50], df], ignore_index=True).to_csv(folder / "b.csv", index=False)  # copies within a file
    message = _refusal(lambda: learning.evaluate_model_files([model], str(folder)))
    assert message.startswith(f"{folder / 'b.csv'}: ") and "repeat an earlier row in every column" in message
    (folder / "b.csv").unlink()  # one file left: scored once, as the file read whole
    assert (learning.evaluate_model_files([model], str(folder)).rows[0].n_samples
            == learning.evaluate_model_files([model], str(folder / "a.parquet")).rows[0].n_samples)


def test_rows_that_differ_in_one_column_are_not_copies(dataset, monkeypatch, tmp_path):
    """Two files at the same times, their rows differing in one column only (another link, or
    another reading), are learned from: the check compares whole rows."""
    df = pd.read_parquet(dataset / "m.parquet")
    folder = tmp_path / "parts"
    folder.mkdir()
    df.to_parquet(folder / "a.parquet", index=False)
    other = df.copy()
    other["rssi_dbm"] = other["rssi_dbm"] + 0.5
    other.to_parquet(folder / "b.parquet", index=False)
    streamed(monkeypatch, 97)
    fit = learning.fit_dataset(str(folder), ModelSpec("sh", 3))
    single = learning.fit_dataset(str(dataset / "m.parquet"), ModelSpec("sh", 3))
    assert fit.n_samples == 2 * single.n_samples


def test_a_streamed_fit_records_the_flights_layout_as_a_fit_in_memory(dataset):
    """``training.fixed_nodes`` and ``training.packet_rate_hz`` of :func:`fit_patterns_streamed`
    (whatever the chunks) and of two parts' statistics merged in order, as the rows read in memory
    give them (:mod:`rplearn.data.flight_layout`); before, a streamed fit recorded neither."""
    from rplearn.data.flight_layout import fixed_nodes, packet_rate_hz
    df = read_dataset(str(dataset / "m.parquet"))
    nodes = sorted(set(df["tx"].astype(str)) | set(df["rx"].astype(str)))
    spec = ModelSpec("sh", 3)
    expected = (fixed_nodes(df), packet_rate_hz(df))
    assert expected[0] == () and expected[1] == pytest.approx(19.6, rel=0.01)  # two drones at 20 packets/s
    for rows in (len(df), 97):
        fit = streamed_module.fit_patterns_streamed((df.iloc[i:i + rows] for i in range(0, len(df), rows)), spec, nodes)
        got = fit.patterns.training
        assert got.fixed_nodes == expected[0] and got.packet_rate_hz == pytest.approx(expected[1], rel=1e-12)  # exact intervals
    half = len(df) // 2
    a = streamed_module.accumulate([df.iloc[:half]], spec, nodes, None, "a", by_unit=False)
    b = streamed_module.accumulate([df.iloc[half:]], spec, nodes, None, "b", by_unit=False)
    merged = a.combined(b).layout
    assert merged.rows == len(df) and merged.recorded() == {"fixed_nodes": (), "packet_rate_hz": pytest.approx(expected[1], rel=1e-12)}
