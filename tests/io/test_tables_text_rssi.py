"""rplearn.io.tables: RSSI text that is no number in a CSV/Parquet signal file ("-70dBm",
"n/a") is counted by ``sync`` as ``unparsable_rssi``, as for a table given to ``synchronise``;
an empty cell stays ``nan_rssi``."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from rplearn.data.sync import synchronise
from rplearn.io.options import ReaderOptions
from rplearn.io.tables import canonical_signal, read_signal_table


def _messy(signal: pd.DataFrame) -> pd.DataFrame:
    """The signal log's RSSI as a logger writing text writes it, with rows 3 and 7 in text that is
    no number and row 5 empty."""
    rssi = signal["rssi_dbm"].map(lambda v: f"{v:g}").astype(object)
    rssi.iloc[3], rssi.iloc[5], rssi.iloc[7] = "-70dBm", "", "n/a"
    return signal.assign(rssi_dbm=rssi)


@pytest.mark.parametrize("ext", ["csv", "parquet"])
def test_text_rssi_in_a_file_is_unparsable_not_missing(tmp_path, flight, ext):
    from rplearn.workflows.logs import sync_logs

    pose, signal = flight
    pose_path, signal_path = tmp_path / f"pose.{ext}", tmp_path / f"signal.{ext}"
    messy = _messy(signal.iloc[:200])
    for df, path in ((pose, pose_path), (messy, signal_path)):
        df.to_csv(path, index=False) if ext == "csv" else df.to_parquet(path, index=False)
    outcome = sync_logs([str(pose_path)], [str(signal_path)], str(tmp_path / "m.csv"), ReaderOptions())
    assert outcome.counts.dropped["unparsable_rssi"] == 2 and outcome.counts.dropped["nan_rssi"] == 1
    assert "(unparsable_rssi): 2" in outcome.counts.to_text()
    logs, _ = read_signal_table(str(signal_path))
    assert logs["rssi_dbm"].iloc[3] == "-70dBm" and np.isnan(logs["rssi_dbm"].iloc[5])
    assert synchronise(pose, logs).summary.dropped["unparsable_rssi"] == 2


def test_a_numeric_rssi_column_stays_float(flight):
    _, signal = flight
    out = canonical_signal(signal.assign(rssi_dbm=signal["rssi_dbm"].astype(str).where(signal.index != 2, "")))
    assert out["rssi_dbm"].dtype == np.float64 and np.isnan(out["rssi_dbm"].iloc[2])


def test_the_live_csv_source_keeps_text_rssi_as_sync_reads_it(tmp_path, flight):
    from rplearn.io.live_sources import CsvTail

    pose, signal = flight
    pose_path, signal_path = tmp_path / "pose.csv", tmp_path / "signal.csv"
    pose.iloc[:50].to_csv(pose_path, index=False)
    _messy(signal.iloc[:10]).to_csv(signal_path, index=False)
    got = CsvTail(str(pose_path), str(signal_path)).poll().signals["rssi_dbm"]
    assert got.iloc[7] == "n/a" and got.iloc[3] == "-70dBm" and np.isnan(got.iloc[5])
