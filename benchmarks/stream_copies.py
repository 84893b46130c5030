"""Benchmark of the check for repeated rows across the chunks of a streamed fit.

A matched dataset read a chunk at a time has each row's 64-bit hash kept
(:mod:`rplearn.data.row_copies`), so that a dataset written twice into one file (its copies in
other chunks) is refused as the whole-dataset check refuses it. This prints, for a file of
``--rows`` rows (default 1,000,000: the ``smoke`` preset's matched dataset repeated at later
times, so that no row repeats another; half of them learning rows):

- the streamed SH-10 fit (``rplearn fit`` with every file streamed, chunks of 500,000 rows) with
  the check and without it (the check replaced by one that hashes nothing: the fit as before the
  check), timed alternately, best of ``--repeats``, as a ratio; and the check's own time within
  the fit over the fit's time (target < 0.10: a difference of two wall times on a shared machine
  is noisier than the check itself);
- that both give the same coefficients and covariance, bit for bit;
- the check alone on the file's chunks (hashing and the sort at the end): its time, the size of
  what it keeps (bytes a row) and its peak memory (tracemalloc, bytes a row);
- that the file written twice is refused, counting every copy.

Run: ``.venv/bin/python benchmarks/stream_copies.py`` (``--tiny``: 20,000 rows, once, targets
not enforced).
"""

from __future__ import annotations

import os
import sys
import tempfile
import time
import tracemalloc

import _stream_data
import numpy as np
import pandas as pd

from rplearn.data.row_copies import SourceHashes
from rplearn.errors import InputError
from rplearn.io.files import iter_table
from rplearn.models import streamed

TARGET = 0.10


class TimedCheck(SourceHashes):
    """The check, its own time summed over the fit [s]."""

    seconds = 0.0

    def add(self, chunk: pd.DataFrame) -> bool:
        t0 = time.perf_counter()
        try:
            return super().add(chunk)
        finally:
            TimedCheck.seconds += time.perf_counter() - t0

    def finish(self):  # noqa: ANN201 - as SourceHashes.finish
        t0 = time.perf_counter()
        try:
            return super().finish()
        finally:
            TimedCheck.seconds += time.perf_counter() - t0


class NoCheck(SourceHashes):
    """The fit as before the check: nothing hashed, no copy ever seen."""

    def add(self, chunk: pd.DataFrame) -> bool:
        return False

    def finish(self):  # noqa: ANN201 - None: no copies record, as before
        return None


def make_dataset(folder: str, rows: int) -> tuple[str, str]:
    """One file of ``rows`` distinct rows and the same written twice."""
    big = _stream_data.repeated_flight(folder, rows, "smoke", seed=4)
    path, twice = os.path.join(folder, "big.parquet"), os.path.join(folder, "twice.parquet")
    big.to_parquet(path, index=False)
    pd.concat([big, big], ignore_index=True).to_parquet(twice, index=False)
    return path, twice


def fit(path: str, check: bool):
    TimedCheck.seconds = 0.0
    streamed.SourceHashes = TimedCheck if check else NoCheck  # type: ignore[misc]
    try:
        wall, _, out = _stream_data.timed_fit(path, "sh-10")
        return wall, out
    finally:
        streamed.SourceHashes = SourceHashes  # type: ignore[misc]


def check_alone(path: str) -> tuple[float, int, int]:
    """Seconds, bytes kept and peak bytes of the check over the file's chunks (read beforehand)."""
    chunks = list(iter_table(path, streamed.PART_CHUNK_ROWS))
    t0 = time.perf_counter()
    hashes = SourceHashes(path)
    for chunk in chunks:
        hashes.add(chunk)
    kept = hashes.finish()
    seconds = time.perf_counter() - t0
    tracemalloc.start()
    hashes = SourceHashes(path)
    for chunk in chunks:
        hashes.add(chunk)
    kept = hashes.finish()
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    return seconds, kept.hashes.nbytes, peak


def main() -> int:
    opts = _stream_data.start(__doc__.splitlines()[0], "20,000 rows, once; targets not enforced")
    rows = opts.rows
    ok = True
    with tempfile.TemporaryDirectory() as folder:
        path, twice = make_dataset(folder, rows)

        def timed(check: bool):  # noqa: ANN202
            s, out = fit(path, check)
            return (s, TimedCheck.seconds), out

        best, last = _stream_data.best_alternating(timed, opts.repeats)
        (with_s, inside_s), (without_s, _) = best[True], best[False]
        checked, plain = last[True], last[False]
        a, b = checked.fitted.model, plain.fitted.model
        same = np.array_equal(a.coef, b.coef) and np.array_equal(a.covariance, b.covariance)
        ok &= same and checked.n_samples == plain.n_samples
        ratio = with_s / without_s
        print(f"streamed SH-10 fit of {rows:,} rows ({checked.n_samples:,} learning samples): {with_s:.2f} s with the "
              f"check, {without_s:.2f} s without: ratio {ratio:.3f}x")
        share = inside_s / with_s
        print(f"the check's own time within the fit: {inside_s:.3f} s, {share:.3f}x the fit's "
              f"(target < {TARGET:.2f}x) [{'ok' if share < TARGET else 'MISS'}]")
        print(f"coefficients and covariance {'equal bit for bit' if same else 'DIFFER'}")
        seconds, kept, peak = check_alone(path)
        print(f"check alone: {seconds:.3f} s ({seconds / with_s:.3f}x the fit), keeps {kept / rows:.1f} bytes a row, "
              f"peak {peak / rows:.1f} bytes a row (chunks of {streamed.PART_CHUNK_ROWS:,} rows)")
        try:
            fit(twice, True)
            refused = "not refused"
            ok = False
        except InputError as exc:
            refused = str(exc).split(" (first")[0]
            ok &= f"{rows:,} row(s)" in refused
        print(f"the file written twice: {refused}")
    if not opts.tiny and share >= TARGET:
        ok = False
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
