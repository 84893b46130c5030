"""Radiotap captures with defects: frames the card marked as failing their FCS check."""

from __future__ import annotations

import numpy as np
import pandas as pd

from rplearn.io import ReaderOptions, inspect_logs
from rplearn.io.pcap import F_BADFCS, RadiotapFields, parse_radiotap, read_pcap, read_radiotap_frames, write_radiotap_pcap

MACS = ["02:00:00:00:00:0a", "02:00:00:00:00:0b"]


def _capture(path, bad=None, n=40):
    t = 1_700_000_000.0 + 0.1 * np.arange(n)
    rssi = -60.0 - (np.arange(n) % 7)
    write_radiotap_pcap(str(path), t, rssi, [MACS[i % 2] for i in range(n)], 2.412e9, RadiotapFields(bad_fcs=bad))
    return path


def test_frames_failing_their_fcs_are_dropped_and_counted_by_name(tmp_path):
    bad = np.zeros(40, bool)
    bad[[3, 4, 17, 30]] = True  # damaged on the air: their bytes (the address too) cannot be trusted
    clean, _ = read_pcap(str(_capture(tmp_path / "clean.pcap")), "R", 20.0)
    sig, meta = read_pcap(str(_capture(tmp_path / "badfcs.pcap", bad)), "R", 20.0)
    assert meta["dropped"]["bad_fcs"] == 4 and sum(meta["dropped"].values()) == 4
    pd.testing.assert_frame_equal(sig, clean[~bad].reset_index(drop=True))
    frames = read_radiotap_frames(str(tmp_path / "badfcs.pcap"))
    assert frames["bad_fcs"].tolist() == bad.tolist()
    report = inspect_logs(tmp_path / "badfcs.pcap", ReaderOptions(receivers={str(tmp_path / "badfcs.pcap"): "R"},
                                                                   tx_power_dbm=20.0))
    assert report.files[0]["signal_dropped"]["bad_fcs"] == 4


def test_the_badfcs_flag_is_read_from_the_flags_field():
    # version 0, length 9, present = flags only; flags = BADFCS | FCS-at-end
    header = bytes([0, 0, 9, 0, 0b10, 0, 0, 0, F_BADFCS | 0x10])
    rt = parse_radiotap(header)
    assert rt.flags == F_BADFCS | 0x10 and rt.bad_fcs
    assert not parse_radiotap(bytes([0, 0, 9, 0, 0b10, 0, 0, 0, 0x10])).bad_fcs
    assert not parse_radiotap(bytes([0, 0, 8, 0, 0, 0, 0, 0])).bad_fcs  # no flags field


def test_the_sync_notes_call_a_captures_drops_frames(tmp_path):
    from rplearn.io import read_logs
    from rplearn.workflows.logs import reader_notes

    bad = np.zeros(40, bool)
    bad[[1, 2]] = True
    path = _capture(tmp_path / "badfcs.pcap", bad)
    _, meta = read_logs(path, ReaderOptions(receivers={str(path): "R"}, tx_power_dbm=20.0))
    notes = reader_notes(meta)
    assert any(n.endswith("badfcs.pcap: dropped 2 frame(s) (bad_fcs)") for n in notes), notes
    assert not any("pose row" in n for n in notes)
