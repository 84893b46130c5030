"""`sync_logs` streams CSV/Parquet signal tables: the same samples and counts as matching the
whole log at once, duplicates found across chunks, and no file when a check fails at the end."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from rplearn.data.sync import SyncOptions, synchronise
from rplearn.errors import InputError
from rplearn.io import read_logs
from rplearn.sim import simulate
from rplearn.workflows import logs as wlogs
from rplearn.workflows.logs import sync_logs


@pytest.fixture(scope="module")
def flight(tmp_path_factory):
    d = tmp_path_factory.mktemp("flight")
    simulate("smoke", seed=3, out_dir=str(d / "f"))
    pose = str(d / "f" / "pose_log.parquet")
    sig = pd.read_parquet(d / "f" / "signal_log.parquet")
    # plant trouble: repeats far apart (other chunks), a sentinel and an implausible RSSI
    sig.loc[5, "rssi_dbm"] = -127.0
    sig.loc[9, "rssi_dbm"] = 25.0
    sig = pd.concat([sig, sig.iloc[[3, 100, 700]]], ignore_index=True).sort_values("t", kind="stable")
    csv = str(d / "signal.csv")
    sig.to_csv(csv, index=False)
    return d, pose, csv


@pytest.mark.parametrize("out_name", ["m.parquet", "m.csv", "m.csv.gz"])
def test_streamed_sync_equals_whole_log(flight, monkeypatch, out_name):
    d, pose, csv = flight
    monkeypatch.setattr(wlogs, "SYNC_CHUNK_ROWS", 97)  # many chunks, copies in other chunks
    out = str(d / out_name)
    outcome = sync_logs([pose], [csv], out)
    assert outcome.streamed
    logs, _ = read_logs([pose, csv])
    whole = synchronise(logs.pose, logs.signal)
    assert outcome.counts.n_in == whole.summary.n_in
    assert outcome.counts.dropped == whole.summary.dropped
    assert outcome.counts.dropped["duplicate"] == 3
    assert outcome.counts.dropped["sentinel_rssi"] >= 1 and outcome.counts.dropped["implausible_rssi"] >= 1
    back = pd.read_parquet(out) if out.endswith("parquet") else pd.read_csv(out)
    assert len(back) == outcome.counts.n_out == len(whole.dataset)
    num = [c for c in whole.dataset.columns if c not in ("tx", "rx", "unit")]
    np.testing.assert_allclose(back[num].to_numpy(float), whole.dataset[num].to_numpy(float), rtol=1e-12)
    assert (back["tx"].astype(str).to_numpy() == whole.dataset["tx"].to_numpy()).all()


def test_streamed_sync_checks_the_link_at_the_end_and_writes_nothing(flight, monkeypatch):
    d, pose, csv = flight
    monkeypatch.setattr(wlogs, "SYNC_CHUNK_ROWS", 97)
    out = d / "none.parquet"
    with pytest.raises(InputError, match=r"link A:Q: node Q is in no signal log"):
        sync_logs([pose], [csv], str(out), sync_options=SyncOptions(link=("A", "Q")))
    with pytest.raises(InputError, match=r"at least 1000000000 needed"):
        sync_logs([pose], [csv], str(out), sync_options=SyncOptions(min_samples=10**9))
    assert not out.exists() and not [p for p in d.iterdir() if p.name.startswith(".rplearn")]


def test_a_previous_output_survives_a_failed_streamed_sync(flight):
    d, pose, csv = flight
    out = d / "keep.csv"
    out.write_text("precious\n")
    with pytest.raises(InputError):
        sync_logs([pose], [csv], str(out), sync_options=SyncOptions(min_samples=10**9))
    assert out.read_text() == "precious\n"


@pytest.mark.parametrize("out_name", ["o.csv", "o.parquet"])
@pytest.mark.parametrize("order", ["AB", "BA", "CA"])
def test_files_with_different_extra_columns_keep_every_column(flight, monkeypatch, out_name, order):
    """Review finding: streamed files whose extra columns differ crashed, or lost a column."""
    d, pose, _ = flight
    monkeypatch.setattr(wlogs, "SYNC_CHUNK_ROWS", 300)
    sig = pd.read_parquet(d / "f" / "signal_log.parquet")
    files = {"A": sig.iloc[:1300].assign(snr_db=20.0), "B": sig.iloc[1300:].assign(noise_dbm=-95.0), "C": sig.iloc[1300:]}
    paths = []
    for key in order:
        files[key].to_csv(d / f"rx{key}.csv", index=False)
        paths.append(str(d / f"rx{key}.csv"))
    out = d / out_name
    outcome = sync_logs([pose], paths, str(out))
    back = pd.read_parquet(out) if out_name.endswith("parquet") else pd.read_csv(out)
    expected = {"A": {"snr_db"}, "B": {"noise_dbm"}, "C": set()}
    wanted = set().union(*(expected[k] for k in order))
    assert wanted <= set(back.columns) and len(back) == outcome.counts.n_out
    if "snr_db" in wanted:  # the values are kept, numbers as numbers
        assert back["snr_db"].dtype.kind == "f" and set(back["snr_db"].dropna().unique()) == {20.0}


def test_a_text_column_empty_at_first_and_duplicates_across_chunks(flight, monkeypatch):
    """Review finding: a column empty in the first chunk broke Parquet; its duplicates were missed."""
    d, pose, _ = flight
    sig = pd.read_parquet(d / "f" / "signal_log.parquet").iloc[:1000].copy()
    sig["note"] = np.where(np.arange(len(sig)) < 600, None, "x")
    pd.concat([sig, sig.iloc[:100]], ignore_index=True).to_csv(d / "note.csv", index=False)
    counts = []
    for rows in (10_000, 250):
        monkeypatch.setattr(wlogs, "SYNC_CHUNK_ROWS", rows)
        counts.append(sync_logs([pose], [str(d / "note.csv")], str(d / "note.parquet")).counts.dropped["duplicate"])
    assert counts == [100, 100]
    assert pd.read_parquet(d / "note.parquet")["note"].notna().sum() > 0


def test_rows_are_named_by_their_file(flight, monkeypatch):
    d, pose, _ = flight
    monkeypatch.setattr(wlogs, "SYNC_CHUNK_ROWS", 200)
    sig = pd.read_parquet(d / "f" / "signal_log.parquet").iloc[:1000].copy()
    sig.iloc[:10].to_csv(d / "first.csv", index=False)
    sig.loc[750, "tx"] = "Z"
    sig.to_csv(d / "unk.csv", index=False)
    with pytest.raises(InputError, match=r"^.*unk\.csv: field tx/rx: unknown node id\(s\) Z at row 750"):
        sync_logs([pose], [str(d / "first.csv"), str(d / "unk.csv")], str(d / "x.csv"),
                  sync_options=SyncOptions(on_unknown_node="error"))


def test_streamed_window_and_doubled_readings_equal_the_whole_log(flight, monkeypatch):
    """Readings written twice 2-6 ms apart, cut across chunks; a window: the streamed sync drops
    exactly what the whole-log match drops, and its summary says what the window kept."""
    d, pose, _ = flight
    sig = pd.read_parquet(d / "f" / "signal_log.parquet")
    one = sig[(sig["tx"] == "A")].iloc[::20].copy()  # a slow radio: one reading a second or so
    copies = one.assign(t=one["t"] + np.random.default_rng(0).uniform(0.002, 0.006, len(one)))
    doubled = pd.concat([one, copies]).sort_values("t", kind="stable")
    doubled.to_csv(d / "doubled.csv", index=False)
    monkeypatch.setattr(wlogs, "SYNC_CHUNK_ROWS", 7)  # many pairs cut apart
    opts = SyncOptions(from_s=10.0, to_s=60.0)
    outcome = sync_logs([pose], [str(d / "doubled.csv")], str(d / "doubled.parquet"), sync_options=opts)
    assert outcome.streamed
    logs, _ = read_logs([pose, str(d / "doubled.csv")])
    whole = synchronise(logs.pose, logs.signal, opts)
    assert outcome.counts.dropped == whole.summary.dropped
    inside = int(((one["t"] >= 10.0 + logs.pose["t"].min()) & (one["t"] <= 60.0 + logs.pose["t"].min())).sum())
    assert outcome.counts.dropped["duplicate_reading"] == inside > 0
    assert outcome.counts.dropped["outside_window"] == 2 * (len(one) - inside)
    assert "window: samples from 10 s to 60 s kept (seconds from the log start" in outcome.summary()


def test_what_the_signal_logs_reader_says_is_reported(tmp_path):
    """A signal log of another format than its poses (a capture cut off by power loss): its
    reader's damage and drops reach the outcome, as the pose logs' do (they were lost)."""
    from pathlib import Path

    cap = Path(__file__).resolve().parents[1] / "fixtures" / "radiotap-pcap" / "ieee802.11_exthdr.pcap"
    cut = tmp_path / "cut.pcap"
    cut.write_bytes(cap.read_bytes()[:2249])  # inside frame 13
    t = np.arange(1366203553.0, 1366203558.0, 0.01)
    pose = pd.concat([pd.DataFrame({"t": t, "node": "T", "x": 20 * np.cos(0.3 * t), "y": 20 * np.sin(0.3 * t), "z": 5.0,
                                    "qw": 1.0, "qx": 0.0, "qy": 0.0, "qz": 0.0}),
                      pd.DataFrame({"t": t[[0, -1]], "node": "R", "x": 10.0, "y": 5.0, "z": 2.0,
                                    "qw": 1.0, "qx": 0.0, "qy": 0.0, "qz": 0.0})])
    pose.to_csv(tmp_path / "pose.csv", index=False)
    from rplearn.io import ReaderOptions

    opts = ReaderOptions(receivers={str(cut): "R"}, address_map={"90:a4:de:c0:46:11": "T"}, tx_power_dbm=20.0)
    outcome = sync_logs([str(tmp_path / "pose.csv")], [str(cut)], str(tmp_path / "m.parquet"), opts,
                        SyncOptions(link=None))
    assert outcome.counts.n_out == 4
    cut_off = [n for n in outcome.notes if "cut off inside the message at byte 2,208" in n]
    assert len(cut_off) == 1 and cut_off[0].startswith(f"{cut}: ")
    assert f"{cut}: dropped 4 frame(s) (no_signal)" in outcome.notes


def test_one_log_given_as_poses_and_signals_is_read_once_with_the_same_result(tmp_path, monkeypatch):
    """A ``.tlog`` named by both --poses and --signals is parsed once (its signal log comes with
    its poses, as :func:`read_logs` gives them), with and without --estimate-offset (which
    read the log three times); the dataset is the match of the logs one read gives."""
    from rplearn.io import ReaderOptions
    from rplearn.io import mavlink as io_mavlink

    tlog = "tests/fixtures/ardupilot/mavlink-log_2013-10-13_18-31-24.tlog"
    options = ReaderOptions(tx_power_dbm=20.0, frequency_hz=915e6)
    sync = SyncOptions(max_gap_s=1.0)
    logs, _ = read_logs([tlog], options)
    expected = synchronise(logs.pose, logs.signal, sync).dataset.reset_index(drop=True)
    assert len(expected) > 500
    real, reads = io_mavlink.read_mavlink, []

    def counted(*args, **kwargs):
        reads.append(args[0])
        return real(*args, **kwargs)

    monkeypatch.setattr(io_mavlink, "read_mavlink", counted)
    for k, offset in enumerate((None, "sys1")):
        out = str(tmp_path / f"m{k}.parquet")
        outcome = sync_logs([tlog], [tlog], out, options, sync, estimate_offset=offset)
        assert reads == [tlog] and (offset is None) == (outcome.clock is None)
        pd.testing.assert_frame_equal(pd.read_parquet(out), expected, check_exact=True)
        reads.clear()


def test_a_signal_csv_with_extra_columns_is_scanned_for_header_lines_once(flight, monkeypatch):
    """Its extra columns are read first (which are numbers), then its rows: both through one scan of the file for
    header lines repeated mid-file (was two: a second full pass over the file); what is read is unchanged."""
    from rplearn.io import _csv_headers, tables

    d, pose, csv = flight
    table = pd.read_csv(csv).assign(snr_db=20.0, note="x")
    lines = table.to_csv(index=False).splitlines(keepends=True)
    path = d / "extra_again.csv"
    path.write_text("".join([*lines[:500], lines[0], *lines[500:]]))
    scanned: list[str] = []

    def counting(path: str, source: str, advice: str = _csv_headers.FILE_ADVICE) -> _csv_headers.HeaderScan:
        scanned.append(str(path))
        return _csv_headers.scan_csv_headers(path, source, advice)

    monkeypatch.setattr(wlogs, "scan_csv_headers", counting)
    monkeypatch.setattr(tables, "scan_csv_headers", counting)
    outcome = sync_logs([pose], [str(path)], str(d / "extra.parquet"))
    assert scanned == [str(path)]
    assert f"{path}: dropped 1 header line(s) repeated mid-file (repeated_header: line 501)" in outcome.notes
    back = pd.read_parquet(d / "extra.parquet")
    assert back["snr_db"].dtype.kind == "f" and set(back["note"].dropna()) == {"x"}
    assert outcome.counts.n_in == len(table)


def test_a_quote_left_open_in_a_csv_with_extra_columns_is_one_line_naming_the_files_line(flight, tmp_path):
    """The pass over the extra columns met it first and let pandas' own error out, naming the line, from 0, of the
    file without the header lines dropped (``EOF inside string starting at row 601``); now as the rows' reading says
    it: the file, and its line."""
    from rplearn.errors import LogFormatError

    _, pose, csv = flight
    lines = pd.read_csv(csv).assign(snr_db=20.0).to_csv(index=False).splitlines(keepends=True)
    cells = lines[601].split(",")
    cells[2] = '"' + cells[2]
    lines[601] = ",".join(cells)
    path = tmp_path / "quote.csv"
    path.write_text("".join([*lines[:300], lines[0], *lines[300:]]))  # the quote on the file's line 603
    with pytest.raises(LogFormatError, match=rf"^{path}: cannot read table \(ParserError: .*EOF inside string "
                                             r"starting at line 603\)$"):
        sync_logs([pose], [str(path)], str(tmp_path / "q.parquet"))
