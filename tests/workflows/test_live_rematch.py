"""A MAVLink session's last refit re-reads its recording whole; when that read is refused, the error named the
session's working file (``/tmp/rplearn-live-*/session.tlog``, deleted at the end) and dropped the rows learned in
flight (audit48): now a note naming the stream, and the rows learned in flight stay."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pandas as pd

from rplearn.models.options import FitOptions
from rplearn.models.spec import ModelSpec
from rplearn.workflows.live import LiveOptions, _Session


def test_a_refused_whole_read_of_the_recording_is_a_note_naming_the_stream(tmp_path):
    t = np.arange(200) * 0.1
    a = 2 * np.pi * t / 20.0
    pose = pd.concat([pd.DataFrame({"t": t, "node": "D", "x": 40 * np.cos(a), "y": 40 * np.sin(a), "z": 20.0, "qw": np.cos(a),
                                    "qx": 0.0, "qy": 0.0, "qz": np.sin(a)}),
                      pd.DataFrame({"t": [0.0], "node": ["G"], "x": [0.0], "y": [0.0], "z": [1.5], "qw": [1.0], "qx": [0.0],
                                    "qy": [0.0], "qz": [0.0]})], ignore_index=True)
    sig = pd.DataFrame({"t": t + 0.05, "tx": "D", "rx": "G", "rssi_dbm": -60.0 + np.random.default_rng(1).normal(0, 2, 200),
                        "tx_power_dbm": 20.0, "frequency_hz": 2.4e9})
    session = _Session(LiveOptions(spec=ModelSpec.parse("sh", order=2), fit=FitOptions(auto=False)), str(tmp_path / "m.json"),
                       str(tmp_path))
    session.feed(pose, sig)
    session.learn(final=True)
    learned = session.status.learned
    assert learned > 100
    recording = tmp_path / "session.tlog"
    recording.write_bytes(b"not a telemetry log at all" * 10)
    session.rematch_whole(SimpleNamespace(record_path=str(recording), name="udpin:0.0.0.0:14550"))
    note = session.status.notes[-1]
    assert note.startswith("last refit: the recorded stream matched whole was refused") and str(recording) not in note
    assert "the recording of udpin:0.0.0.0:14550" in note and session.status.learned == learned
