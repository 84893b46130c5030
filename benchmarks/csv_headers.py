"""Benchmark of the header scan of CSV logs (rplearn.io._csv_headers).

Every CSV log is scanned for its header line repeated mid-file (a logger restarted appending, files joined with
``cat``) before it is read. A signal CSV of about ``--mb`` MB (default 75; the smoke flight's packets repeated) is
written, and three things are timed alternately (best of ``--repeats``):

1. the scan alone (``scan_csv_headers``) on the clean file;
2. the reference: ``pandas.read_csv`` of the same file (what reading it costs anyway);
3. ``read_signal_table`` of the file with its header repeated mid-file (dropped through the skipping reader) and of
   the clean file;
4. ``sync``'s streamed reading of a signal CSV with extra columns (the clean file with a column ``snr_db`` added,
   besides its ``unit``: ``rplearn.workflows.logs``' chunks, whose extra columns are classified in a pass of their
   own first), against ``pandas.read_csv`` of that file; the scans of the file for header lines it makes are
   counted (one since stop 50; two before, the second a full pass over the file again).

Printed: the scan's seconds (target: well under 1 s for 75 MB) and its ratio to the reference; the two reads agree
row for row (exit 1 if not); the streamed reading's seconds, its ratio to the reference and its scans (exit 1 if
more than one).

Usage: ``python benchmarks/csv_headers.py [--mb 75] [--repeats 5]`` (``--tiny``: 1 MB, 2 repeats).
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time

import numpy as np
import pandas as pd


def write_signal_csv(path: str, megabytes: float) -> int:
    """A signal CSV of about ``megabytes`` MB (the smoke flight's packets, shifted in time, repeated); its rows."""
    from rplearn.io.files import write_table
    from rplearn.sim import simulate

    sig = simulate("smoke", seed=0).signal_log
    span_s = float(sig["t"].max()) + 1.0
    one = len(sig.to_csv(index=False).encode()) - len(",".join(sig.columns)) - 1
    copies = max(1, int(np.ceil(megabytes * 1e6 / one)))
    table = pd.concat([sig.assign(t=sig["t"] + k * span_s) for k in range(copies)], ignore_index=True)
    write_table(table, path)
    return len(table)


def with_header_again(path: str, out: str) -> None:
    """``path`` with its header line written again at its middle line."""
    with open(path, "rb") as fh:
        lines = fh.read().split(b"\n")
    mid = len(lines) // 2
    with open(out, "wb") as fh:
        fh.write(b"\n".join([*lines[:mid], lines[0], *lines[mid:]]))


def with_extra_column(path: str, out: str) -> None:
    """``path`` (a signal CSV) with a numeric column ``snr_db`` added: its header lines (repeated ones too) name it,
    its rows give 20."""
    with open(path, "rb") as fh:
        lines = fh.read().split(b"\n")
    header = lines[0]
    with open(out, "wb") as fh:
        fh.write(b"\n".join(line + b",snr_db" if line == header else line + b",20" if line else line for line in lines))


class ScanCounter:
    """Counts the scans for header lines that the table readers and ``sync`` make (their ``scan_csv_headers``)."""

    def __init__(self) -> None:
        from rplearn.io import _csv_headers, tables
        from rplearn.workflows import logs

        self.count, self._scan, self._modules = 0, _csv_headers.scan_csv_headers, (tables, logs)
        for module in self._modules:
            module.scan_csv_headers = self._counting  # type: ignore[attr-defined]

    def _counting(self, *args, **kwargs):
        self.count += 1
        return self._scan(*args, **kwargs)

    def close(self) -> None:
        for module in self._modules:
            module.scan_csv_headers = self._scan  # type: ignore[attr-defined]


def streamed_rows(path: str) -> int:
    """``sync``'s streamed reading of one signal CSV (extra columns classified, then the chunks): its rows."""
    from rplearn.io import ReaderOptions
    from rplearn.workflows.logs import _signal_chunks

    return sum(len(chunk) for chunk in _signal_chunks([path], ReaderOptions(), []))


def _once(func) -> float:
    t0 = time.perf_counter()
    func()
    return time.perf_counter() - t0


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--mb", type=float, default=75.0)
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--tiny", action="store_true", help="1 MB, 2 repeats (seconds)")
    args = ap.parse_args()
    if args.tiny:
        args.mb, args.repeats = 1.0, 2
    from rplearn.io._csv_headers import scan_csv_headers
    from rplearn.io.tables import read_signal_table

    with tempfile.TemporaryDirectory() as d:
        clean, again = os.path.join(d, "signal.csv"), os.path.join(d, "again.csv")
        extra = os.path.join(d, "extra.csv")
        rows = write_signal_csv(clean, args.mb)
        with_header_again(clean, again)
        with_extra_column(clean, extra)
        scan = ref = read_clean = read_again = ref_extra = streamed = np.inf
        for _ in range(args.repeats):  # alternately: the machine's speed drifts within a minute
            scan = min(scan, _once(lambda: scan_csv_headers(clean, clean)))
            ref = min(ref, _once(lambda: pd.read_csv(clean)))
            read_clean = min(read_clean, _once(lambda: read_signal_table(clean)))
            read_again = min(read_again, _once(lambda: read_signal_table(again)))
            ref_extra = min(ref_extra, _once(lambda: pd.read_csv(extra)))
            streamed = min(streamed, _once(lambda: streamed_rows(extra)))
        a, meta = read_signal_table(again)
        b, _ = read_signal_table(clean)
        agree = a.equals(b) and meta["dropped"]["repeated_header"] == 1
        counter = ScanCounter()
        try:
            agree_extra = streamed_rows(extra) == rows
        finally:
            counter.close()
        size_mb = os.path.getsize(clean) / 1e6
        extra_mb = os.path.getsize(extra) / 1e6
    print(f"signal CSV: {size_mb:.1f} MB, {rows:,} rows")
    print(f"header scan: {scan:.3f} s (best of {args.repeats}); reference pandas.read_csv of the file: {ref:.3f} s; "
          f"ratio scan / reference = {scan / ref:.2f}x")
    print(f"read_signal_table: clean {read_clean:.3f} s, header repeated mid-file {read_again:.3f} s "
          f"(ratio {read_again / read_clean:.2f}x); the same rows, the header counted once: {agree}")
    print(f"sync's streamed reading of a signal CSV with extra columns ({extra_mb:.1f} MB: unit and snr_db): "
          f"{streamed:.3f} s (best of {args.repeats}); reference pandas.read_csv of the file: {ref_extra:.3f} s; "
          f"ratio streamed / reference = {streamed / ref_extra:.2f}x; scans of the file for header lines: "
          f"{counter.count}; every row read: {agree_extra}")
    if not args.tiny:
        print(f"target: scan well under 1 s for 75 MB: {'met' if scan * 75.0 / size_mb < 0.5 else 'NOT met'}")
    if not agree or not agree_extra or counter.count != 1:
        raise SystemExit(1)


if __name__ == "__main__":
    main()
