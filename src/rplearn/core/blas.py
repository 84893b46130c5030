"""One BLAS thread for small fits (threadpoolctl).

On a busy 2-core machine OpenBLAS's second thread makes a small problem slower and its time
erratic: a 1,333-sample SH-10 fit took 33-340 ms instead of 15 ms, and ``eigvalsh`` of a
200x200 matrix 35-40 ms instead of 2.4 ms, as the threads wait for each other. A fit whose
work (the Gram accumulation, ``n_samples * n_columns**2``, and the factorisations,
``n_columns**3``) is below :data:`SMALL_FIT_FLOPS` runs with one BLAS thread; bigger ones keep
every thread. The controller is built once (it scans the loaded libraries).
"""

from __future__ import annotations

import sys
from contextlib import contextmanager, nullcontext
from functools import lru_cache
from typing import Any, Iterator

#: Below this many floating-point operations (about 0.2 s on one core) a fit uses one BLAS thread.
SMALL_FIT_FLOPS = 2e9


def is_small_fit(n_samples: int, n_columns: int) -> bool:
    """Whether a fit of ``n_samples`` rows and ``n_columns`` columns is small enough for one thread."""
    return float(n_samples) * n_columns**2 + 10.0 * float(n_columns) ** 3 < SMALL_FIT_FLOPS


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


@contextmanager
def blas_threads_for(n_samples: int, n_columns: int) -> Iterator[None]:
    """One BLAS thread inside the block when the fit is small (:func:`is_small_fit`)."""
    if not is_small_fit(n_samples, n_columns):
        with nullcontext():
            yield
        return
    with _controller().limit(limits=1, user_api="blas"):
        yield


@contextmanager
def one_blas_thread() -> Iterator[None]:
    """One BLAS thread inside the block (for work that runs its own threads, one per core)."""
    with _controller().limit(limits=1, user_api="blas"):
        yield


@contextmanager
def one_openmp_thread() -> Iterator[None]:
    """One OpenMP thread inside the block: pykdtree's queries are small, and OpenMP workers left
    spinning after them slowed the next small fit on a busy 2-core machine from 5 to 13 ms."""
    # only the OpenMP libraries: a limiter restores every library it holds when it ends, and the
    # BLAS count is process-wide (another thread may hold its own BLAS limit meanwhile)
    with _controller().select(user_api="openmp").limit(limits=1):
        yield


def warm_up() -> None:
    """Build the controller now (its library scan is a one-off cost, kept out of the LTD)."""
    _controller()


__all__ = ["BLAS_MODULES", "SMALL_FIT_FLOPS", "blas_threads_for", "is_small_fit", "one_blas_thread", "one_openmp_thread",
           "warm_up"]
