"""rplearn.data.sync: a signal log whose RSSI is uncalibrated (radio units, a constant offset)
drops as implausible_rssi with the question said in the summary and in the refusal, and reads
with rssi_scale="relative"."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from rplearn.data.sync import SyncOptions, synchronise
from rplearn.errors import InputError


def _logs(offset_db: float, n: int = 40) -> tuple[pd.DataFrame, pd.DataFrame]:
    t = np.arange(n) * 0.1
    pose = pd.concat([pd.DataFrame({"t": t, "node": "A", "x": 50.0 + t, "y": 0.0, "z": 20.0, "qw": 1.0, "qx": 0.0,
                                    "qy": 0.0, "qz": 0.0}),
                      pd.DataFrame({"t": [0.0], "node": ["G"], "x": [0.0], "y": [0.0], "z": [1.0], "qw": [1.0],
                                    "qx": [0.0], "qy": [0.0], "qz": [0.0]})], ignore_index=True)
    rssi = -60.0 + offset_db + np.sin(t)
    signal = pd.DataFrame({"t": t[1:-1], "tx": "A", "rx": "G", "rssi_dbm": rssi[1:-1], "tx_power_dbm": 20.0,
                           "frequency_hz": 2.4e9})
    return pose, signal


def test_uncalibrated_rssi_is_refused_with_the_question_and_the_way_out():
    pose, signal = _logs(offset_db=130.0)  # +70 "dBm": a radio's own units
    with pytest.raises(InputError) as e:
        synchronise(pose, signal, source="sig.csv")
    msg = str(e.value)
    assert msg.startswith("sig.csv: only 0 signal sample(s) matched") and "\n" not in msg
    assert "100% of the samples have an RSSI outside -150 to 30 dBm" in msg and "rssi_scale='relative'" in msg
    assert len(synchronise(pose, signal, SyncOptions(rssi_scale="relative")).dataset) == len(signal)


def test_a_few_implausible_readings_are_counted_without_the_question():
    pose, signal = _logs(offset_db=0.0)
    signal.loc[signal.index[:3], "rssi_dbm"] = 45.0  # three corrupt fields
    summary = synchronise(pose, signal).summary
    assert summary.dropped["implausible_rssi"] == 3 and not any("uncalibrated" in n for n in summary.notes)
    signal.loc[signal.index[:20], "rssi_dbm"] = 45.0  # more than a quarter: asked
    assert any("uncalibrated power" in n for n in synchronise(pose, signal).summary.notes)
