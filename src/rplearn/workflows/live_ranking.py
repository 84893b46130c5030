"""The next-best manoeuvre ranking of a live session, run beside its loop.

A ranking (:func:`rplearn.analysis.manoeuvres.rank_manoeuvres` through the session's hook,
:class:`rplearn.workflows.live_advice.ManoeuvreAdvisor`) scores some 300 candidates with rank-k
posterior updates: seconds of work, about 12 s on a loaded 2-core machine (measured with whole
manoeuvres, the default; scoring their best prefixes too,
:attr:`~rplearn.analysis.manoeuvres.ManoeuvreOptions.prefixes` 4, makes a ranking about 1.4x as long). Run in the loop, it
stopped the refits, the prequential score and the reading of the source for that long. So
:class:`RankingWorker` runs it on a thread of its own (the factorisations and products release
the GIL), handed a snapshot of the statistics (their sum, a copy the loop never touches again,
with a closed copy of the time-block sums), the fitted model of that refit (never changed
after it is made) and the latest poses. At most one ranking runs at a time: a refit while one
runs starts none. The loop shows the latest finished ranking, with its age and the refit it
ranked.

A stop (the end of the stream, a stop criterion, Ctrl-C, an error) closes the worker: a
running ranking is not waited for (a thread cannot be interrupted inside numpy; the thread is a
daemon, so the process exits without it) and its result is dropped. At the end of the stream or
a stop criterion, :func:`rplearn.workflows.live.run_live` first waits for it up to
:data:`rplearn.workflows.live.STOP_RANKING_WAIT_S`, so that the last refit does not run under
its BLAS limit. ``beside=False`` ranks in
the caller's thread at once, as the loop did before (the reference of the tests).

The ranking holds the process's BLAS limit of one thread while it runs
(:func:`rplearn.core.threads.one_blas_thread`, taken by the worker, waiting for a refit that
holds a limit to end rather than ranking whole with that refit's threads); a refit meanwhile runs with the threads as they
are, so a refit large enough for two BLAS threads gets one then: slower, and equal to the
policy's result to rounding only. A small refit (the live case: a few hundred columns) uses one
thread anyway, and its result is the same bits.
"""

from __future__ import annotations

import math
import threading
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import pandas as pd

from rplearn._argtypes import check_types
from rplearn.core.threads import one_blas_thread

#: The hook's rows: (name, duration [s], spread after [dB]), best first.
Rows = tuple[tuple[str, float, float], ...]


@check_types
@dataclass(frozen=True)
class Ranking:
    """A finished ranking.

    Attributes
    ----------
    rows : tuple of (str, float, float)
        The manoeuvres (name, duration [s], spread after [dB]), best first (empty after an error).
    refit : int
        The refit whose statistics and model were ranked (1 for the first).
    started_s, finished_s : float
        Monotonic clock [s] at its start and end.
    error : str
        Why the ranking failed ('' when it did not): advice must not end the session.
    """

    rows: Rows
    refit: int
    started_s: float
    finished_s: float
    error: str = ""

    @property
    def took_s(self) -> float:
        """Wall time of the ranking [s]."""
        return self.finished_s - self.started_s


def _rows(raw: Sequence[Any]) -> Rows:
    return tuple((str(n), float(d), float(v)) for n, d, v in raw)


@check_types
class RankingWorker:
    """Runs a manoeuvre hook beside the live loop, one ranking at a time (module docstring).

    Parameters
    ----------
    ranker : callable
        ``(statistics, fitted, latest poses) -> rows`` (:data:`rplearn.workflows.live.ManoeuvreRanker`).
    beside : bool
        Rank on a thread of its own (True) or in the caller's thread (False).
    every_s : float
        Seconds of wall time at least between the starts of two rankings.
    clock : callable
        The monotonic clock [s] (tests).
    """

    def __init__(self, ranker: Callable[..., Sequence[Any]], beside: bool = True, every_s: float = 0.0,
                 clock: Callable[[], float] = time.monotonic) -> None:
        self.ranker, self.beside, self.every_s, self.clock = ranker, bool(beside), float(every_s), clock
        self._lock = threading.Lock()
        self._thread: threading.Thread | None = None
        self._done: Ranking | None = None  # finished and not yet collected
        self._last_start = -math.inf
        self._closed = False
        #: Rankings started and finished so far.
        self.started = 0
        self.finished = 0

    @property
    def running(self) -> bool:
        """Whether a ranking is running now."""
        return self._thread is not None and self._thread.is_alive()

    @property
    def closed(self) -> bool:
        return self._closed

    def due(self) -> bool:
        """Whether :meth:`submit` would start a ranking now (none running, the period passed)."""
        return not self._closed and not self.running and self.clock() - self._last_start >= self.every_s

    def submit(self, snapshot: Callable[[], tuple[Any, Any, pd.DataFrame]], refit: int) -> bool:
        """Start a ranking of ``snapshot()`` (statistics, fitted, latest poses) when one is
        :meth:`due`; the snapshot is taken only then. Returns whether one started."""
        if not self.due():
            return False
        args = snapshot()
        start = self.clock()
        self._last_start = start
        self.started += 1
        if not self.beside:
            self._run(args, refit, start)
            return True
        self._thread = threading.Thread(target=self._run, args=(args, refit, start), name="rplearn-live-ranking",
                                        daemon=True)
        self._thread.start()
        return True

    def _run(self, args: tuple[Any, Any, pd.DataFrame], refit: int, start: float) -> None:
        try:
            with one_blas_thread(wait=True):  # not the threads of a refit's limit (module docstring)
                rows = _rows(self.ranker(*args))
            done = Ranking(rows, refit, start, self.clock())
        except Exception as exc:  # the ranking is advice: its failure must not end the session
            done = Ranking((), refit, start, self.clock(), f"{type(exc).__name__}: {exc}")
        with self._lock:
            if not self._closed:
                self._done = done
                self.finished += 1

    def collect(self) -> Ranking | None:
        """The ranking finished since the last call, if any."""
        with self._lock:
            done, self._done = self._done, None
        return done

    def wait(self, timeout_s: float | None = None) -> bool:
        """Wait for the running ranking (at most ``timeout_s``); whether none runs after."""
        thread = self._thread
        if thread is not None:
            thread.join(timeout_s)
        return not self.running

    def close(self) -> None:
        """No more rankings; a running one is not waited for and its result is dropped."""
        with self._lock:
            self._closed = True
            self._done = None


__all__ = ["Ranking", "RankingWorker"]
