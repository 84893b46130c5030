"""The numbers of a live session (``rplearn live``, :mod:`rplearn.workflows.live`): its status
after each refit, the prequential record, and their rows for the terminal view and the page.

The prequential record keeps running totals and at most :data:`PREQUENTIAL_BINS` bins of
consecutive batches, so that it does not grow with the session's length.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from rplearn._argtypes import check_types
from rplearn.data.sync import DROP_REASONS


@check_types
@dataclass
class LiveStatus:
    """The numbers of the live view, after each refit.

    Attributes
    ----------
    elapsed_s : float
    received, matched, pending : int
        Signal rows received, matched and waiting for their poses.
    dropped : dict of str to int
        Dropped rows by ``sync``'s reasons.
    dropped_where : dict of str to str
        Where some of them were, by reason, as said (``repeated_header``: ``pose.csv lines 604, 1210``).
    learned, refits : int
    model : str
        Label of the current model ('' before the first refit).
    refit_ms : float
        Wall time of the last refit [ms].
    prequential_rmse_db : float
        RMS error of every sample predicted before it was learned from [dB] (NaN before any).
    prequential_n : int
    noise_db : float
        The current model's noise level [dB] (NaN before the first refit).
    coverage_pct, spread_db, sphere_spread_db : dict of str to float
        Per node: covered share of the sphere [%], pattern spread over its covered directions
        and over the sphere [dB].
    budget : list of str
        The link budget's findings (empty: plausible).
    manoeuvres : list of (str, float, float)
        The next-best manoeuvres (name, duration [s], spread after [dB]), best first: the
        latest finished ranking.
    manoeuvres_refit : int
        The refit that ranking ranked (0: none yet).
    manoeuvres_age_s, ranking_s : float
        Wall time since that ranking finished, and what it took [s] (NaN: none yet).
    ranking_running : bool
        Whether a ranking is running beside the loop now.
    notes : list of str
    stopped : str
        Why the session ended ('' while it runs).
    """

    elapsed_s: float = 0.0
    received: int = 0
    matched: int = 0
    pending: int = 0
    dropped: dict[str, int] = field(default_factory=lambda: {r: 0 for r in DROP_REASONS})
    dropped_where: dict[str, str] = field(default_factory=dict)
    learned: int = 0
    refits: int = 0
    model: str = ""
    refit_ms: float = math.nan
    prequential_rmse_db: float = math.nan
    prequential_n: int = 0
    noise_db: float = math.nan
    coverage_pct: dict[str, float] = field(default_factory=dict)
    spread_db: dict[str, float] = field(default_factory=dict)
    sphere_spread_db: dict[str, float] = field(default_factory=dict)
    budget: list[str] = field(default_factory=list)
    manoeuvres: list[tuple[str, float, float]] = field(default_factory=list)
    manoeuvres_refit: int = 0
    manoeuvres_age_s: float = math.nan
    ranking_s: float = math.nan
    ranking_running: bool = False
    notes: list[str] = field(default_factory=list)
    stopped: str = ""

    def summary(self) -> str:
        """Plain text of the numbers (printed at the end of a session)."""
        lines = [f"{self.elapsed_s:.0f} s: {self.received} signal rows, {self.matched} matched, {self.learned} learned, "
                 f"{self.refits} refits (last {self.refit_ms:.0f} ms), model {self.model or '-'}"]
        lines += [f"  dropped ({r}): {n}{dropped_where(self, r)}" for r, n in self.dropped.items() if n]
        lines.append(f"  prequential RMSE {prequential_text(self)}, noise {self.noise_db:.2f} dB")
        for node in self.spread_db:
            lines.append(f"  {node}: coverage {self.coverage_pct[node]:.1f}%, spread {spread_text(self.spread_db[node])} covered, "
                         f"{spread_text(self.sphere_spread_db[node])} sphere")
        lines += [f"  budget: {b}" for b in self.budget]
        if self.manoeuvres:
            lines.append(f"  {ranking_text(self)}")
        lines += [f"  next: {n} ({d:.0f} s) -> {s:.2f} dB" for n, d, s in self.manoeuvres[:3]]
        lines += [f"  {n}" for n in self.notes]
        if self.stopped:
            lines.append(f"  stopped: {self.stopped}")
        return "\n".join(lines)


@check_types
def dropped_where(status: LiveStatus, reason: str) -> str:
    """`` (pose.csv lines 604, 1210)``: where some rows dropped for ``reason`` were ('' when not said)."""
    where = status.dropped_where.get(reason)
    return f" ({where})" if where else ""


#: Bins of the prequential record kept at most (its running totals are exact; the bins give the
#: RMSE over the last part of a session to within one bin, 1/128 of the samples or less).
PREQUENTIAL_BINS = 256


@check_types
@dataclass
class Prequential:
    """Squared errors of samples predicted before they were learned from.

    The totals are running sums; for the error over the last part of a session the batches are
    kept as at most ``max_bins`` bins of consecutive batches (when there are more, the two
    neighbours with the fewest samples are added into one), so memory does not grow with the
    session's length.
    """

    max_bins: int = PREQUENTIAL_BINS
    n_samples: int = 0
    sse: float = 0.0
    _n: list[int] = field(default_factory=list, repr=False)
    _sse: list[float] = field(default_factory=list, repr=False)

    def add(self, residual_db: np.ndarray) -> None:
        n, sse = int(residual_db.size), float(residual_db @ residual_db)
        self.n_samples += n
        self.sse += sse
        self._n.append(n)
        self._sse.append(sse)
        if len(self._n) > max(int(self.max_bins), 2):
            k = int(np.argmin(np.add(self._n[:-1], self._n[1:])))
            self._n[k] += self._n.pop(k + 1)
            self._sse[k] += self._sse.pop(k + 1)

    @property
    def bins(self) -> int:
        """Bins kept (at most ``max_bins``)."""
        return len(self._n)

    def rmse_db(self, last_fraction: float = 1.0) -> float:
        """RMSE over the last ``last_fraction`` of the predicted samples (whole bins: those whose
        middle falls in it) [dB]; over all of them, exact."""
        if not self.n_samples:
            return math.nan
        if last_fraction >= 1.0:
            return math.sqrt(self.sse / self.n_samples)
        n = np.asarray(self._n, np.float64)[::-1]
        keep = np.cumsum(n) <= last_fraction * n.sum() + 0.5 * n
        return float(np.sqrt(np.sum(np.asarray(self._sse)[::-1][keep]) / max(n[keep].sum(), 1)))


@check_types
def spread_text(spread_db: float) -> str:
    """A node's spread as the view shows it: ``"1.23 dB"``, or ``"not known yet"`` when the fit
    gives none (infinite: a fit at the search's largest smoothing, :mod:`rplearn.workflows.live`)."""
    return f"{spread_db:.2f} dB" if math.isfinite(spread_db) else "not known yet"


@check_types
def ranking_text(status: LiveStatus) -> str:
    """When the manoeuvres shown were ranked ('' before the first ranking)."""
    s = status
    if not s.manoeuvres_refit:
        return "ranking running" if s.ranking_running else ""
    text = f"ranked at refit {s.manoeuvres_refit}, {s.manoeuvres_age_s:.0f} s ago (took {s.ranking_s:.1f} s)"
    return text + ("; the next is running" if s.ranking_running else "")


def prequential_text(status: LiveStatus) -> str:
    """The prequential score in words: its RMSE [dB] over its samples, or why there is none yet
    (no batch was predicted before it was learned from: the stream came in one batch, or no
    model was fitted before the last one), never ``nan dB over 0 samples``."""
    if status.prequential_n == 0 or not math.isfinite(status.prequential_rmse_db):
        return ("no score yet: no batch was predicted before it was learned from "
                "(the first batch is learned from, not scored; a stream read in one batch is never scored)")
    return f"{status.prequential_rmse_db:.2f} dB over {status.prequential_n} samples"


@check_types
def page_rows(status: LiveStatus) -> tuple[list[tuple[str, str]], list[list[str]]]:
    """The numbers of :class:`LiveStatus` as (label, value) rows and a node table (header first)."""
    s = status
    rows = [("elapsed", f"{s.elapsed_s:.0f} s"), ("signal rows received", str(s.received)),
            ("matched", str(s.matched)), ("waiting for poses", str(s.pending)), ("learned", str(s.learned)),
            ("model", s.model or "-"), ("refits", f"{s.refits} (last {s.refit_ms:.0f} ms)"),
            ("prequential RMSE", prequential_text(s)),
            ("noise level", f"{s.noise_db:.2f} dB")]
    rows += [(f"dropped ({r})", f"{n}{dropped_where(s, r)}") for r, n in s.dropped.items() if n]
    rows += [("link budget", b) for b in s.budget] or [("link budget", "plausible")]
    if ranking_text(s):
        rows.append(("manoeuvre ranking", ranking_text(s)))
    rows += [(f"next manoeuvre {k + 1}", f"{n} ({d:.0f} s): spread {v:.2f} dB after")
             for k, (n, d, v) in enumerate(s.manoeuvres[:3])]
    rows += [("note", n) for n in s.notes]
    if s.stopped:
        rows.append(("stopped", s.stopped))
    nodes = [["node", "coverage", "spread where looked", "spread on the sphere"]]
    nodes += [[n, f"{s.coverage_pct[n]:.1f}%", spread_text(s.spread_db[n]), spread_text(s.sphere_spread_db[n])]
              for n in s.spread_db]
    return rows, nodes


__all__ = ["PREQUENTIAL_BINS", "LiveStatus", "Prequential", "dropped_where", "page_rows", "prequential_text", "ranking_text"]
