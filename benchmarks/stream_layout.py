"""Benchmark of the flight's layout summed up chunk by chunk in a streamed fit.

A streamed fit records who held still and the radio's packet rate (``training.fixed_nodes``,
``training.packet_rate_hz``) from a bounded :class:`~rplearn.data.flight_layout.LayoutSketch`
updated per chunk. This prints, for a file of ``--rows`` rows (default 1,000,000: the ``ground``
preset's matched dataset, a station and a drone, repeated at later times):

- the streamed SH-10 fit (``rplearn fit`` with every file streamed, chunks of 500,000 rows) with
  the sketch and without it (a sketch that sums up nothing: the fit as before), timed alternately,
  best of ``--repeats``, as ratios of wall time and of the process's CPU time (the target, < 1.05,
  on the CPU time: on a shared machine the wall time moves by more than the sketch costs), and the
  sketch's own time within the fit;
- that both give the same coefficients, bit for bit;
- the layout the streamed fit records against the one the same rows read in memory give
  (:func:`~rplearn.data.flight_layout.fixed_nodes`, :func:`~rplearn.data.flight_layout.packet_rate_hz`):
  the same nodes, the rates within 1 %;
- the sketch's size (bytes) after the fit.

Run: ``.venv/bin/python benchmarks/stream_layout.py`` (``--tiny``: 20,000 rows, once, targets
not enforced).
"""

from __future__ import annotations

import pickle
import sys
import tempfile
import time

import _stream_data
import numpy as np
import pandas as pd

from rplearn.data import flight_layout
from rplearn.data.flight_layout import LayoutSketch
from rplearn.data.units import select_units

TARGET = 1.05


class Timer:
    """The sketch's own time summed over a fit [s], and the last sketch merged into."""

    seconds = 0.0
    last: LayoutSketch | None = None


_OF_ROWS, _MERGE = LayoutSketch.of_rows.__func__, LayoutSketch.merge  # type: ignore[attr-defined]


def _timed_of_rows(cls, rows: pd.DataFrame) -> LayoutSketch:
    t0 = time.perf_counter()
    try:
        return _OF_ROWS(cls, rows)
    finally:
        Timer.seconds += time.perf_counter() - t0


def _timed_merge(self: LayoutSketch, later: LayoutSketch) -> LayoutSketch:
    t0 = time.perf_counter()
    try:
        Timer.last = self
        return _MERGE(self, later)
    finally:
        Timer.seconds += time.perf_counter() - t0


def _no_of_rows(cls, rows: pd.DataFrame) -> LayoutSketch:
    return cls()


def _no_merge(self: LayoutSketch, later: LayoutSketch) -> LayoutSketch:
    return self


def fit(path: str, sketch: bool):
    """The streamed fit with the sketch timed, or with one that sums up nothing (the fit as before)."""
    Timer.seconds, Timer.last = 0.0, None
    LayoutSketch.of_rows = classmethod(_timed_of_rows if sketch else _no_of_rows)  # type: ignore[method-assign,assignment]
    LayoutSketch.merge = _timed_merge if sketch else _no_merge  # type: ignore[method-assign]
    try:
        return _stream_data.timed_fit(path, "sh-10")
    finally:
        LayoutSketch.of_rows = classmethod(_OF_ROWS)  # type: ignore[method-assign,assignment]
        LayoutSketch.merge = _MERGE  # type: ignore[method-assign]


def main() -> int:
    opts = _stream_data.start(__doc__.splitlines()[0], "20,000 rows, once; targets not enforced")
    rows = opts.rows
    ok = True
    with tempfile.TemporaryDirectory() as folder:
        path = _stream_data.dataset_file(folder, rows, "ground", seed=0)

        def timed(sketch: bool):  # noqa: ANN202
            s, cpu, out = fit(path, sketch)
            return (s, cpu, Timer.seconds), (out, Timer.last)

        best, last = _stream_data.best_alternating(timed, opts.repeats)
        (with_s, with_cpu, inside_s), (without_s, without_cpu, _) = best[True], best[False]
        (sketched, kept), (plain, _) = last[True], last[False]
        a, b = sketched.fitted.model, plain.fitted.model
        same = np.array_equal(a.coef, b.coef)
        ok &= same
        ratio = with_cpu / without_cpu  # the process's CPU time: less moved by other processes than wall time
        print(f"streamed SH-10 fit of {rows:,} rows ({sketched.n_samples:,} learning samples): {with_s:.2f} s with the "
              f"layout sketch, {without_s:.2f} s without (wall: ratio {with_s / without_s:.3f}x); CPU {with_cpu:.2f} s "
              f"against {without_cpu:.2f} s: ratio {ratio:.3f}x (target < {TARGET:.2f}x) [{'ok' if ratio < TARGET else 'MISS'}]")
        print(f"the sketch's own time within the fit: {inside_s:.3f} s, {inside_s / with_s:.3f}x the fit's")
        print(f"coefficients {'equal bit for bit' if same else 'DIFFER'}")
        df = select_units(pd.read_parquet(path), sketched.units.units, path)
        memory = (flight_layout.fixed_nodes(df), flight_layout.packet_rate_hz(df))
        training = a.training
        rate_ok = memory[1] is not None and training.packet_rate_hz is not None and \
            abs(training.packet_rate_hz / memory[1] - 1.0) < 0.01
        ok &= training.fixed_nodes == memory[0] and rate_ok
        print(f"recorded streamed: fixed {training.fixed_nodes}, {training.packet_rate_hz:.4f} packets/s; in memory: "
              f"fixed {memory[0]}, {memory[1]:.4f} packets/s [{'ok' if ok else 'DIFFER'}]")
        if kept is not None:
            print(f"the sketch after the fit: {len(pickle.dumps(kept)):,} bytes ({len(kept.keys):,} rows of "
                  f"{kept.rows:,} kept, at most {flight_layout.LAYOUT_ROWS:,})")
    if not opts.tiny and ratio >= TARGET:
        ok = False
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
