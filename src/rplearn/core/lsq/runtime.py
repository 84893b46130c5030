"""The process-wide resources of the streamed statistics, owned by one object.

Accumulating the normal equations (:mod:`rplearn.core.lsq.link_statistics`) keeps, between
fits, a float64 block buffer per thread and two worker threads that compute blocks of samples
ahead. :class:`StatisticsRuntime` owns them: the per-thread buffers, the pool (created on first
use), the lock that gives the pool, and the process-wide BLAS thread limit that goes with it,
to one caller at a time, and the fork hook that lets a forked child start afresh.
:data:`DEFAULT_RUNTIME` is the one the library uses.

Work that does not depend on the statistics (a fit's coverage grids) can ride along
(:meth:`StatisticsRuntime.overlapping`): it is queued on the workers behind the statistics'
last block, so it runs while a worker would otherwise wait (the last block of an odd count, the
caller's solve), and otherwise when its results are asked for.
"""

from __future__ import annotations

import os
import threading
import weakref
from collections import deque
from collections.abc import Callable, Iterable, Iterator, Sequence
from concurrent.futures import Future, ThreadPoolExecutor
from contextlib import contextmanager
from typing import Any, Generic, TypeVar

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]
T = TypeVar("T")


class Overlapped(Generic[T]):
    """Jobs that ride along with the statistics (:meth:`StatisticsRuntime.overlapping`).

    Their futures once queued on the workers behind a statistics pass's last block; their
    results (:meth:`results`) come from those futures, or from running the jobs then.
    """

    def __init__(self, runtime: StatisticsRuntime, jobs: Sequence[Callable[[], T]]) -> None:
        self._runtime = runtime
        self._jobs = list(jobs)
        self._futures: list[Future[T]] | None = None

    @property
    def started(self) -> bool:
        """Whether the jobs were queued on the workers (behind a statistics pass)."""
        return self._futures is not None

    def start(self, pool: ThreadPoolExecutor) -> None:
        """Queue the jobs on ``pool`` (once)."""
        if self._futures is None:
            self._futures = [pool.submit(job) for job in self._jobs]

    def results(self) -> list[T]:
        """Every job's result, in the jobs' order (an error of a job is raised here): waited for
        when queued, else computed now (on the workers when there are several)."""
        if self._futures is not None:
            return [f.result() for f in self._futures]
        self._futures = []  # no pass may queue them now: they are computed here
        try:
            return list(self._runtime.in_order(lambda job: job(), self._jobs))
        finally:
            self._futures = None

    def settle(self) -> None:
        """Cancel the queued jobs not yet running and wait for the others (errors dropped)."""
        for future in self._futures or ():
            future.cancel()
        for future in self._futures or ():
            if not future.cancelled():
                try:
                    future.result()
                except Exception:  # noqa: BLE001, S110  (the caller's own error is the one raised)
                    pass


class StatisticsRuntime:
    """Per-thread block buffers and the worker pool of the statistics (see module docstring).

    Parameters
    ----------
    workers : int
        Worker threads of the pool (2: one per core of a 2-core machine).
    ahead : int
        Blocks the workers compute ahead of the caller (memory stays bounded).
    """

    def __init__(self, workers: int = 2, ahead: int = 3) -> None:
        self.workers, self.ahead = int(workers), int(ahead)
        self._buffers = threading.local()
        self._pool: ThreadPoolExecutor | None = None
        self._lock = threading.Lock()
        self._riders = threading.local()
        if hasattr(os, "register_at_fork"):
            ref = weakref.ref(self)

            def after_fork() -> None:
                runtime = ref()
                if runtime is not None:
                    runtime.forget_pool()

            os.register_at_fork(after_in_child=after_fork)

    def block_buffer(self, size: int) -> FloatArray:
        """A float64 scratch buffer of at least ``size`` values, reused by later fits in this thread.

        Fresh memory is slow on first touch (one page fault per 4 KiB; measured 20-30 ms for the
        52 MB block of an SH-10 fit on this kind of machine), so the block buffer is kept.
        """
        buf = getattr(self._buffers, "block", None)
        if buf is None or buf.size < size:
            self._buffers.block = None  # let the old one go first
            buf = np.empty(size)
            buf.fill(0.0)  # pay the page faults now, once, not inside the first rank-k update
            self._buffers.block = buf
        return buf[:size]

    def buffer_size(self) -> int:
        """Values held by this thread's block buffer (0 when it has none)."""
        buf = getattr(self._buffers, "block", None)
        return 0 if buf is None else int(buf.size)

    def release_buffer(self) -> None:
        """Drop this thread's block buffer (the next fit allocates it again)."""
        self._buffers.block = None

    def forget_pool(self) -> None:
        """Start afresh: a forked child inherits the pool object but not its threads."""
        self._pool = None
        self._lock = threading.Lock()

    @contextmanager
    def overlapping(self, jobs: Sequence[Callable[[], T]]) -> Iterator[Overlapped[T]]:
        """Let ``jobs`` (callables without arguments, independent of the statistics) ride along
        with the statistics computed in this thread inside the block.

        The first :meth:`in_order` of this thread inside the block that hands its blocks to the
        workers queues the jobs behind its last block; :meth:`Overlapped.results` (inside or
        after the block) gives their results, computing them then if no pass queued them. The
        jobs must not use this runtime's pool themselves. On an error inside the block the
        queued jobs are cancelled or waited for.
        """
        riders: Overlapped[T] = Overlapped(self, jobs)
        outer = getattr(self._riders, "pending", None)
        self._riders.pending = riders
        try:
            yield riders
        except BaseException:
            riders.settle()
            raise
        finally:
            self._riders.pending = outer

    def _start_riders(self, pool: ThreadPoolExecutor) -> None:
        """Queue this thread's riding jobs (:meth:`overlapping`) on ``pool``, once."""
        riders = getattr(self._riders, "pending", None)
        if riders is not None and not riders.started:
            riders.start(pool)

    @contextmanager
    def beside(self, jobs: Sequence[Callable[[], T]]) -> Iterator[Callable[[], list[T]]]:
        """Run ``jobs`` (callables without arguments) on the workers while the caller goes on
        with its own work inside the block; the callable yielded gives their results, in the
        jobs' order (waiting for them; an error of a job is raised there).

        The workers and the caller each have one BLAS thread inside the block (the limit is
        process-wide: a 2-core machine runs the caller's work and a job at once, one core
        each). When the pool is busy (another caller has it) or there is no job, the jobs run
        in the calling thread when their results are asked for, with the threads as they are.
        On leaving the block (an error included) the jobs not started are cancelled and the
        running ones waited for.
        """
        jobs = list(jobs)
        lock = self._lock
        if not jobs or not lock.acquire(blocking=False):
            done: list[list[T]] = []

            def compute() -> list[T]:
                if not done:
                    done.append([job() for job in jobs])
                return done[0]

            yield compute
            return
        from rplearn.core.threads import one_blas_thread

        futures: list[Future[T]] = []
        try:
            if self._pool is None:
                self._pool = ThreadPoolExecutor(max_workers=self.workers, thread_name_prefix="rplearn-stats")
            with one_blas_thread():
                futures = [self._pool.submit(job) for job in jobs]
                try:
                    yield lambda: [f.result() for f in futures]
                finally:
                    for future in futures:
                        future.cancel()
                    for future in futures:
                        if not future.cancelled():
                            try:
                                future.result()  # let a running job finish before the limit is lifted
                            except Exception:  # noqa: BLE001, S110  (the caller's error, or its own, was raised)
                                pass
        finally:
            lock.release()

    def in_order(self, work: Callable[[Any], T], starts: Iterable[Any], ahead: int | None = None) -> Iterator[T]:
        """``work(s)`` for every block start ``s``, yielded in order; ``ahead``: the jobs queued
        ahead of the one waited for (default :attr:`ahead`; a caller that keeps every result, as
        the order selection does, queues them all, so that no worker waits behind a long job).

        With two or more blocks, the worker threads compute them (:attr:`ahead` at most ahead,
        so memory stays bounded), each with one BLAS thread: computing the features is plain
        numpy, which uses one core (and releases the interpreter lock), so two blocks at a time
        use both cores of a 2-core machine, where one block with a 2-thread BLAS leaves one idle
        while the features are computed. The threads are kept between calls, with their block
        buffers.

        The BLAS thread limit is process-wide, so one caller at a time has the pool: a caller
        that finds it busy (another thread accumulating at the same time, e.g. a Dask worker's)
        computes its blocks itself, in order, leaving the BLAS threads as they are.
        """
        starts = list(starts)
        lock = self._lock
        if len(starts) < 2 or not lock.acquire(blocking=False):
            yield from (work(s) for s in starts)
            return
        from rplearn.core.threads import one_blas_thread

        pending: deque[Future[T]] = deque()
        try:
            if self._pool is None:
                self._pool = ThreadPoolExecutor(max_workers=self.workers, thread_name_prefix="rplearn-stats")
            pool = self._pool
            with one_blas_thread():
                for s in starts:
                    pending.append(pool.submit(work, s))
                    if len(pending) >= (self.ahead if ahead is None else max(int(ahead), 1)):
                        yield pending.popleft().result()
                self._start_riders(pool)  # behind the last block (overlapping)
                while pending:
                    yield pending.popleft().result()
        finally:
            for future in pending:  # an error (or a caller that stopped early): drop the rest
                future.cancel()
            for future in pending:
                if not future.cancelled():
                    try:
                        future.result()  # let a running block finish before the limit is lifted
                    except Exception:  # noqa: BLE001, S110  (the first error is the one raised)
                        pass
            lock.release()


#: The runtime the library's statistics use.
DEFAULT_RUNTIME = StatisticsRuntime()


__all__ = ["DEFAULT_RUNTIME", "Overlapped", "StatisticsRuntime"]
