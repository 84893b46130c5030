"""Benchmark of the time-block sums a streamed ``fit --order auto`` keeps for its drifting error.

A streamed automatic fit (:mod:`rplearn.models.streamed`) keeps, beside each unit's statistics,
the sums of every 5-s time block (``NormalEquations.block_directed``), from which it stores the
next plan's drifting error (``training.drift_std_db``) as the in-memory fit does. This prints,
for a file of ``--rows`` rows (default 1,000,000: the ``smoke`` preset's matched dataset
repeated at later times, its units spread over four labels, so that no row repeats another):

- the streamed automatic fit (``rplearn fit --order auto`` with every file streamed, chunks of
  500,000 rows) with the sums and without them (the time blocks not given to the statistics:
  the fit as before, which stores no drift), timed alternately, best of ``--repeats``, wall and
  CPU of the process, as ratios (after one fit not timed: a process's first pays its warm-up);
- the drift each stores, whether they chose the same order and smoothing, and the largest
  coefficient difference between the two (relative to the largest coefficient; the sums take
  another path through the statistics, which rounds differently);
- the memory the sums take: vectors (one per unit, block and directed link), bytes, bytes a row;
- the accumulation alone (the file's chunks read beforehand, the SH-15 statistics of every unit)
  with and without the sums, alternating, best of ``--repeats``, CPU of the process, as a ratio.

Run: ``.venv/bin/python benchmarks/stream_drift.py`` (``--tiny``: 20,000 rows, once).
"""

from __future__ import annotations

import sys
import tempfile
import time

import _stream_data
import numpy as np

from rplearn.core.lsq.normal_equations import NormalEquations
from rplearn.io.files import iter_table
from rplearn.models import auto, streamed
from rplearn.models.options import FitOptions
from rplearn.models.spec import ModelSpec


class NoBlocks(NormalEquations):
    """The statistics as before the sums: the time blocks not kept."""

    def add(self, *args, time_block=None, **kwargs):  # noqa: ANN001, ANN002, ANN003, ANN201, ARG002
        return super().add(*args, **kwargs)


KEPT: dict[str, int] = {}


def recording(fit_from_statistics):  # noqa: ANN001, ANN201
    """``fit_from_statistics`` that first records the size of the block sums it is given."""

    def wrapped(stats, *args, **kwargs):  # noqa: ANN001, ANN002, ANN003, ANN202
        vectors = [v for st in stats.values() for links in st.block_directed.values() for v in links.values()]
        KEPT.update(vectors=len(vectors), bytes=sum(v.nbytes for v in vectors))
        return fit_from_statistics(stats, *args, **kwargs)

    return wrapped


def fit(path: str, blocks: bool):  # noqa: ANN201
    streamed.NormalEquations = NormalEquations if blocks else NoBlocks  # type: ignore[misc]
    KEPT.clear()
    try:
        return _stream_data.timed_fit(path, "sh", FitOptions(auto=True))
    finally:
        streamed.NormalEquations = NormalEquations  # type: ignore[misc]


def accumulate_cpu(chunks: list, nodes: list[str], path: str, blocks: bool) -> float:
    """CPU seconds of the SH-15 statistics of every unit of ``chunks``, with the block sums or without."""
    streamed.NormalEquations = NormalEquations if blocks else NoBlocks  # type: ignore[misc]
    try:
        c0 = time.process_time()
        streamed.accumulate(chunks, ModelSpec("sh", 15), nodes, None, path, by_unit=True)
        return time.process_time() - c0
    finally:
        streamed.NormalEquations = NormalEquations  # type: ignore[misc]


def main() -> int:
    opts = _stream_data.start(__doc__.splitlines()[0], "20,000 rows, once")
    rows, repeats = opts.rows, opts.repeats
    auto.fit_from_statistics = recording(auto.fit_from_statistics)  # type: ignore[assignment]
    ok = True
    with tempfile.TemporaryDirectory() as folder:
        path = _stream_data.dataset_file(folder, rows, "smoke", seed=4)
        fit(path, False)  # not timed: the first fit of a process pays imports and warm-up

        def timed(blocks: bool):  # noqa: ANN202
            wall, cpu, out = fit(path, blocks)
            return (wall, cpu), (out, dict(KEPT))

        best, last = _stream_data.best_alternating(timed, repeats)
        (a, kept), (b, kept_without) = last[True], last[False]
        drift, none = a.fitted.model.training.drift_std_db, b.fitted.model.training.drift_std_db
        ca, cb = np.asarray(a.fitted.model.coef), np.asarray(b.fitted.model.coef)
        diff = float(np.max(np.abs(ca - cb)) / np.max(np.abs(cb)))
        same = (a.selection.order, a.selection.smoothing) == (b.selection.order, b.selection.smoothing)
        ok &= drift is not None and none is None and same and diff < 1e-6 and a.n_samples == b.n_samples
        print(f"streamed fit --order auto of {rows:,} rows ({a.n_samples:,} learning samples, SH-{a.selection.order} "
              f"chosen), best of {repeats} alternating: with the block sums {best[True][0]:.2f} s wall, "
              f"{best[True][1]:.2f} s CPU; without {best[False][0]:.2f} s wall, {best[False][1]:.2f} s CPU: "
              f"ratio {best[True][0] / best[False][0]:.3f}x wall, {best[True][1] / best[False][1]:.3f}x CPU")
        print(f"drift_std_db: {drift if drift is None else f'{drift:.4f}'} dB with the sums, {none} without; "
              f"the same order and smoothing: {same}; coefficients differ by {diff:.1e} of the largest at most")
        n_kept, size = kept.get("vectors", 0), kept.get("bytes", 0)
        print(f"block sums kept: {n_kept:,} vectors (unit x 5-s block x directed link), {size / 2**20:.2f} MiB, "
              f"{size / max(rows, 1):.1f} bytes a row; without: {kept_without.get('vectors', 0)}")
        chunks = list(iter_table(path, streamed.PART_CHUNK_ROWS))
        nodes = sorted(set(chunks[0]["tx"].astype(str)) | set(chunks[0]["rx"].astype(str)))
        alone, _ = _stream_data.best_alternating(lambda blocks: ((accumulate_cpu(chunks, nodes, path, blocks),), None), repeats)
        print(f"the accumulation alone (SH-15, every unit): {alone[True][0]:.2f} s CPU with the sums, {alone[False][0]:.2f} s "
              f"without: ratio {alone[True][0] / alone[False][0]:.3f}x")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
