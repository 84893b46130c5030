"""The copy rule of the radio reports (:func:`rplearn.io.mavlink_phases.repeated_readings`) in a
causal form with bounded state, for a ``.tlog`` read as it grows (:mod:`rplearn.io.tlog_window`).

The offline rule looks at the whole log twice: the report period is the median spacing of
consecutive distinct readings over the log, and copies (a report identical to one less than a
quarter period before it) are merged only when systematic (counts over the log). Here:

- every report's *gap* (the time since the last identical report, :data:`GAP_MEMORY_S` at most)
  is found when it arrives, from a dictionary of the readings of the last :data:`GAP_MEMORY_S`;
- the spacings and the gaps of all reports so far are counted in fixed logarithmic bins
  (:data:`BIN_RATIO` wide), so the report period, and so the quarter period ``q``, is known to lie
  in one band ``[q_lo, q_hi)`` (the bin or two bins of the median), and whether copies are
  systematic is known unless the band leaves it open;
- a report with a gap below ``q_lo`` (copies systematic) is a copy, one at or above ``q_hi`` (or
  copies not systematic) is not, exactly as the offline rule would judge it with the period of
  the log so far; one inside the band cannot be judged and is a counted drop
  (``uncertain_copy_reports``);
- reports already handed out are kept as counts per gap bin with the verdict they were given; when
  a later period or decision reverses the verdict of a bin, its reports are counted
  (``changed_copy_reports``).

All state is a few arrays of :data:`N_BINS` counts and the readings of the last
:data:`GAP_MEMORY_S`: it does not grow with the log.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from rplearn.io.mavlink_phases import DUPLICATE_FRACTION_OF_PERIOD

#: Bins of spacings and gaps [s]: ``BIN_FLOOR_S * BIN_RATIO**k`` for k < :data:`N_BINS`.
BIN_FLOOR_S = 1e-6
BIN_RATIO = 1.005
N_BINS = 4700  # up to about 1.6e4 s
#: A reading identical to one more than this long before it [s] has no copy gap (the offline
#: rule needs gaps up to half the report period: a radio reporting slower than every 60 s is
#: not judged exactly).
GAP_MEMORY_S = 30.0

_EDGES = BIN_FLOOR_S * BIN_RATIO ** np.arange(N_BINS)
_LO = np.concatenate([[0.0], _EDGES])  # bin i holds [_LO[i], _HI[i])
_HI = np.concatenate([_EDGES, [np.inf]])


def _bins(values: np.ndarray) -> np.ndarray:
    return np.searchsorted(_EDGES, np.asarray(values, np.float64), side="right")


def _kth_bin(counts: np.ndarray, k: int) -> int:
    """The bin holding the k-th smallest (0-based) of the values counted."""
    return int(np.searchsorted(np.cumsum(counts), k, side="right"))


class ReportCopies:
    """Running counts of the radio reports for the copy rule (module docstring)."""

    def __init__(self) -> None:
        self.n = 0
        self.spacing_change = np.zeros(N_BINS + 1, np.int64)
        self.spacing_all = np.zeros(N_BINS + 1, np.int64)
        self.gaps = np.zeros(N_BINS + 1, np.int64)
        self.behind_kept = np.zeros(N_BINS + 1, np.int64)
        self.behind_copied = np.zeros(N_BINS + 1, np.int64)
        self._last: tuple[float, tuple[float, ...]] | None = None
        self._seen: dict[tuple[float, ...], float] = {}

    def add(self, reports: np.ndarray) -> np.ndarray:
        """Count reports (rows ``t, values...`` sorted as the offline reader sorts them) that
        follow those counted before; their gaps [s] (inf: none within :data:`GAP_MEMORY_S`)."""
        gaps = np.full(len(reports), np.inf)
        spacing, change = [], []
        for i, row in enumerate(reports.tolist()):
            t, values = row[0], tuple(row[1:])
            if self._last is not None:
                d = t - self._last[0]
                spacing.append(d)
                change.append(values != self._last[1] and d > 0)
            before = self._seen.get(values)
            if before is not None and t - before < GAP_MEMORY_S:
                gaps[i] = t - before
            self._seen[values] = t
            self._last = (t, values)
        self.n += len(reports)
        if spacing:
            d, ch = np.asarray(spacing), np.asarray(change, bool)
            self.spacing_change += np.bincount(_bins(d[ch]), minlength=N_BINS + 1)
            self.spacing_all += np.bincount(_bins(d[d > 0]), minlength=N_BINS + 1)
        self.gaps += np.bincount(_bins(gaps), minlength=N_BINS + 1)
        if len(reports):
            newest = float(reports[-1, 0])
            self._seen = {v: t for v, t in self._seen.items() if newest - t < GAP_MEMORY_S}
        return gaps

    def period_band(self) -> tuple[float, float] | None:
        """Where the report period of the reports so far lies [s] (``report_period_s``'s
        branches on binned counts); None when it has none."""
        if self.n < 2:
            return None
        n_change = int(self.spacing_change.sum())
        if n_change >= max(3, 0.25 * self.n):
            counts, skip, m = self.spacing_change, 0, n_change
        else:
            total = int(self.spacing_all.sum())
            if not total:
                return None
            counts, skip, m = self.spacing_all, total // 2, total - total // 2
        lo = _kth_bin(counts, skip + (m - 1) // 2)
        hi = _kth_bin(counts, skip + m // 2)
        return float(_LO[lo]), float(_HI[hi])

    def rule(self) -> tuple[float, float, bool | None]:
        """``(q_lo, q_hi, systematic)``: the band of the quarter period and whether copies are
        systematic (None: the band leaves it open)."""
        band = self.period_band()
        if band is None:
            return 0.0, 0.0, False
        q_lo, q_hi = DUPLICATE_FRACTION_OF_PERIOD * band[0], DUPLICATE_FRACTION_OF_PERIOD * band[1]
        g = self.gaps
        close_min, close_max = g[_HI <= q_lo].sum(), g[_LO < q_hi].sum()
        next_min = g[(_LO >= q_hi) & (_HI <= 2 * q_lo)].sum()
        next_max = g[(_HI > q_lo) & (_LO < 2 * q_hi)].sum()
        surely, maybe = close_min > 3 * next_max + 3, close_max > 3 * next_min + 3
        return q_lo, q_hi, True if surely else (False if not maybe else None)

    @staticmethod
    def verdicts(gaps: np.ndarray, rule: tuple[float, float, bool | None]) -> tuple[np.ndarray, np.ndarray]:
        """Which reports (by gap [s]) are copies, and which cannot be judged."""
        q_lo, q_hi, systematic = rule
        gaps = np.asarray(gaps, np.float64)
        if systematic is False:
            return np.zeros(len(gaps), bool), np.zeros(len(gaps), bool)
        copy = (gaps < q_lo) & bool(systematic)
        return copy, (gaps < q_hi) & ~copy

    def behind(self, gaps: np.ndarray, rule: tuple[float, float, bool | None]) -> None:
        """Keep the verdicts of reports handed out and left behind (by gap bin)."""
        copy, uncertain = self.verdicts(gaps, rule)
        b = _bins(gaps)
        self.behind_copied += np.bincount(b[copy], minlength=N_BINS + 1)
        self.behind_kept += np.bincount(b[~copy & ~uncertain], minlength=N_BINS + 1)

    def reversed_behind(self, rule: tuple[float, float, bool | None]) -> int:
        """Reports left behind whose bin's verdict ``rule`` reverses (then given the new verdict)."""
        q_lo, q_hi, systematic = rule
        copy_now = (_HI <= q_lo) & (systematic is True)
        keep_now = (systematic is False) | (_LO >= q_hi)
        n = int(self.behind_kept[copy_now].sum() + self.behind_copied[keep_now].sum())
        self.behind_copied[copy_now] += self.behind_kept[copy_now]
        self.behind_kept[copy_now] = 0
        self.behind_kept[keep_now] += self.behind_copied[keep_now]
        self.behind_copied[keep_now] = 0
        return n

    def sizes(self) -> dict[str, Any]:
        """The length of every structure kept (for tests of bounded state)."""
        return {"copies.seen": len(self._seen), "copies.bins": len(self.gaps)}


__all__ = ["BIN_FLOOR_S", "BIN_RATIO", "GAP_MEMORY_S", "N_BINS", "ReportCopies"]
