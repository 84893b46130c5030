"""Thread control (threadpoolctl): one BLAS thread for small fits, and the limits around work that
runs threads of its own (the statistics' workers, scipy's BLAS in a large solve, k-d tree queries).

On a busy 2-core machine OpenBLAS's second thread makes a small problem slower and its time
erratic: a 1,333-sample SH-10 fit took 33-340 ms instead of 15 ms, and ``eigvalsh`` of a
200x200 matrix 35-40 ms instead of 2.4 ms, as the threads wait for each other. A fit whose
work (the Gram accumulation, ``n_samples * n_columns**2``, and the factorisations,
``n_columns**3``) is below :data:`SMALL_FIT_FLOPS` runs with one BLAS thread; bigger ones keep
every thread. The controller is built once (it scans the loaded libraries).

The policy (issue 30) looks at the cores actually free too: work of at least
:data:`SMALL_FIT_FLOPS` gets as many BLAS threads as :func:`free_cores` finds (the cores this
process may run on, less the load other processes put on them), work below it one thread.
With another process keeping one core of two busy, OpenBLAS's second thread made an SH-15 fit
9.7x slower and an SH-10 evaluation of 90,000 directions 4-7x slower than one thread. The
environment variable ``RPLEARN_THREADS`` (a positive count) overrides the policy everywhere:
fits, predictions and their spreads, the order sweep and the automatic selection.
"""

from __future__ import annotations

import os
import sys
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager, nullcontext
from functools import lru_cache
from typing import Any

#: Below this many floating-point operations (about 0.2 s on one core) a fit uses one BLAS thread.
SMALL_FIT_FLOPS = 2e9


#: Environment variable overriding the thread policy: a positive number of BLAS threads.
THREADS_ENV = "RPLEARN_THREADS"
#: Seconds a reading of the load average is reused (it is a one-minute average anyway).
_LOAD_TTL_S = 1.0
_load_cache: list[float] = [-1.0, 0.0]  # [monotonic time of the reading, cores free then]


def fit_flops(n_samples: int, n_columns: int) -> float:
    """Floating-point work of a fit: the Gram accumulation and the factorisations."""
    return float(n_samples) * n_columns**2 + 10.0 * float(n_columns) ** 3


def is_small_fit(n_samples: int, n_columns: int) -> bool:
    """Whether a fit of ``n_samples`` rows and ``n_columns`` columns is small enough for one thread."""
    return fit_flops(n_samples, n_columns) < SMALL_FIT_FLOPS


def usable_cores() -> int:
    """Cores this process may run on (its CPU affinity; ``os.cpu_count()`` where there is none)."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except (AttributeError, OSError):  # pragma: no cover - platforms without affinity
        return max(1, os.cpu_count() or 1)


def free_cores_of(cores: int, load: float) -> int:
    """Cores free for this process's threads: ``cores`` less the runnable processes of the
    one-minute ``load`` other than this one (itself one), rounded, at least 1."""
    others = max(0.0, float(load) - 1.0)
    return max(1, min(cores, int(cores - others + 0.5)))


def free_cores() -> int:
    """Cores free now (:func:`free_cores_of` of :func:`usable_cores` and ``os.getloadavg``;
    read at most once a second)."""
    now = time.monotonic()
    if now - _load_cache[0] < _LOAD_TTL_S:
        return int(_load_cache[1])
    cores = usable_cores()
    try:
        free = free_cores_of(cores, os.getloadavg()[0])
    except (AttributeError, OSError):  # pragma: no cover - no load average (Windows)
        free = cores
    _load_cache[:] = [now, float(free)]
    return free


def thread_override() -> int | None:
    """The count ``RPLEARN_THREADS`` asks for, or None when it is unset or empty.

    Raises
    ------
    InputError
        When it is set to anything but a positive whole number.
    """
    raw = os.environ.get(THREADS_ENV, "").strip()
    if not raw:
        return None
    if not raw.isdigit() or int(raw) < 1:
        from rplearn.errors import InputError

        raise InputError(f"{THREADS_ENV}={raw!r}: expected a positive number of threads", param=THREADS_ENV)
    return int(raw)


def prediction_flops(n_rows: int, n_coef: int, spreads: bool = False) -> float:
    """Floating-point work of predicting ``n_rows`` links (both ends) from ``n_coef`` coefficients
    per pattern: the gains and, with ``spreads``, the quadratic forms ``f^T C f``."""
    per_end = 4.0 * n_coef + (2.0 * (2 * n_coef) ** 2 if spreads else 0.0)
    return float(n_rows) * 2.0 * per_end


def blas_thread_count(flops: float) -> int:
    """BLAS threads for work of ``flops`` floating-point operations: ``RPLEARN_THREADS`` when
    set, else 1 below :data:`SMALL_FIT_FLOPS` and :func:`free_cores` at or above it."""
    override = thread_override()
    if override is not None:
        return override
    if flops < SMALL_FIT_FLOPS:
        return 1
    return free_cores()


#: Modules whose thread pools a limit must reach once they are loaded (scipy has its own
#: OpenBLAS; pykdtree, for coverage, an OpenMP runtime).
BLAS_MODULES: tuple[str, ...] = ("numpy", "scipy.linalg", "pykdtree.kdtree")


def _controller() -> Any:
    """The controller of the BLAS libraries loaded now: numpy's, and scipy's once a module that
    uses it (:mod:`rplearn.models.auto`, :mod:`rplearn.analysis.sweep`) has imported it. A
    fixed-order fit imports no scipy, which costs 0.1-0.3 s to import."""
    import numpy  # noqa: F401  (the BLAS to control must be loaded before the scan)

    return _controller_of(tuple(m for m in BLAS_MODULES if m in sys.modules))


@lru_cache(maxsize=4)
def _controller_of(loaded: tuple[str, ...]) -> Any:
    from threadpoolctl import ThreadpoolController

    return ThreadpoolController()


#: Held by the thread whose BLAS limit is in force. A limit is process-wide and, when it ends,
#: restores the counts it found: two threads whose limits overlap could leave numpy on one thread
#: for good, or lift the other's limit while its work still runs. So one thread at a time
#: limits; a limit asked for meanwhile by another thread is skipped (its work runs with the
#: threads as they are), as :meth:`rplearn.core.lsq.runtime.StatisticsRuntime.in_order` does with its pool,
#: or waited for (``one_blas_thread(wait=True)``: long work beside short limited work).
_LIMIT_LOCK = threading.RLock()


@contextmanager
def _exclusive_limit(selection: Any, limits: int, wait: bool = False) -> Iterator[None]:
    """``selection.limit(limits)`` inside the block, unless another thread holds a limit (with
    ``wait``, once that one ends)."""
    if not _LIMIT_LOCK.acquire(blocking=wait):
        yield
        return
    try:
        with selection.limit(limits=limits):
            yield
    finally:
        _LIMIT_LOCK.release()


@contextmanager
def blas_threads(flops: float) -> Iterator[None]:
    """The BLAS threads of :func:`blas_thread_count` inside the block (no limit when that is
    every thread the libraries have and ``RPLEARN_THREADS`` is unset)."""
    count = blas_thread_count(flops)
    selection = _controller().select(user_api="blas")
    if thread_override() is None and all(lib.num_threads <= count for lib in selection.lib_controllers):
        with nullcontext():
            yield
        return
    with _exclusive_limit(selection, count):
        yield


@contextmanager
def blas_threads_for(n_samples: int, n_columns: int) -> Iterator[None]:
    """The BLAS threads for a fit of ``n_samples`` rows and ``n_columns`` columns
    (:func:`blas_threads` of :func:`fit_flops`): one when it is small (:func:`is_small_fit`)."""
    with blas_threads(fit_flops(n_samples, n_columns)):
        yield


@contextmanager
def one_blas_thread(wait: bool = False) -> Iterator[None]:
    """One BLAS thread inside the block (for work that runs its own threads, one per core).

    Parameters
    ----------
    wait : bool
        When another thread holds a limit: wait for it to end, then limit (True), or run the
        block with the threads as they are (False). Long work beside a loop whose short work
        limits now and then waits, so that it does not run whole on the other's limit.
    """
    with _exclusive_limit(_controller().select(user_api="blas"), 1, wait):
        yield


@contextmanager
def one_openmp_thread() -> Iterator[None]:
    """One OpenMP thread inside the block: pykdtree's queries are small, and OpenMP workers left
    spinning after them slowed the next small fit on a busy 2-core machine from 5 to 13 ms."""
    # only the OpenMP libraries: a limiter restores every library it holds when it ends, and the
    # BLAS count is process-wide (another thread may hold its own BLAS limit meanwhile)
    with _controller().select(user_api="openmp").limit(limits=1):
        yield


def _package_libraries(package: str) -> set[str]:
    """Paths of the loaded BLAS libraries shipped inside ``package`` (its folder or the wheel's
    ``<package>.libs`` folder beside it)."""
    module = sys.modules.get(package)
    where = getattr(module, "__file__", None)
    if not where:
        return set()
    import os

    folder = os.path.dirname(os.path.realpath(where))
    roots = (folder + os.sep, folder + ".libs" + os.sep)
    return {lib.filepath for lib in _controller().select(user_api="blas").lib_controllers
            if os.path.realpath(lib.filepath).startswith(roots)}


@contextmanager
def numpy_blas_one_thread() -> Iterator[None]:
    """One thread for numpy's BLAS inside the block, when scipy has a BLAS of its own (as the
    wheels do) that does the block's heavy work with every thread.

    Two OpenBLAS thread pools on two cores fight: after each call a pool's threads spin for a
    while, and the other pool's threads then wait for a core. In a 50-node solve (scipy's
    Cholesky and triangular solves, numpy's small QR factorisations of 5,000 x 8 blocks
    between them) that made each QR take 7-14 ms instead of 0.3 ms and the spectrum estimate
    0.35-0.5 s instead of 0.25 s. Without a separate scipy BLAS (one shared library), nothing
    is limited.
    """
    numpy_libs = _package_libraries("numpy") - _package_libraries("scipy")
    if not numpy_libs or "scipy.linalg" not in sys.modules:
        yield
        return
    with _exclusive_limit(_controller().select(filepath=sorted(numpy_libs)), 1):
        yield


def warm_up() -> None:
    """Build the controller now (its library scan is a one-off cost, kept out of the LTD)."""
    _controller()


__all__ = ["BLAS_MODULES", "SMALL_FIT_FLOPS", "THREADS_ENV", "blas_thread_count", "blas_threads", "blas_threads_for",
           "fit_flops", "free_cores", "free_cores_of", "is_small_fit", "numpy_blas_one_thread", "one_blas_thread",
           "one_openmp_thread", "prediction_flops", "thread_override", "usable_cores", "warm_up"]
