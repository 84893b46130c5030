"""Metrics of paper Sec. V-C and docs/conventions.md: RMSE, MAE, Q95, AIC, LTD, condition number."""

from __future__ import annotations

import time
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from rplearn._argtypes import check_types
from rplearn.errors import InputError


def _errors(y_true: ArrayLike, y_pred: ArrayLike) -> np.ndarray:
    a = np.asarray(y_true, np.float64).ravel()
    b = np.asarray(y_pred, np.float64).ravel()
    if a.shape != b.shape:
        raise InputError(f"y_true has {a.size} values, y_pred has {b.size}")
    if a.size == 0:
        raise InputError("no samples to evaluate")
    return b - a


@check_types
def rmse(y_true: ArrayLike, y_pred: ArrayLike) -> float:
    """Root mean squared error [dB]."""
    e = _errors(y_true, y_pred)
    return float(np.sqrt(np.mean(e * e)))


@check_types
def mae(y_true: ArrayLike, y_pred: ArrayLike) -> float:
    """Mean absolute error [dB]."""
    return float(np.mean(np.abs(_errors(y_true, y_pred))))


@check_types
def q95(y_true: ArrayLike, y_pred: ArrayLike) -> float:
    """95th percentile of the absolute error [dB] (the paper's Q95)."""
    return float(np.percentile(np.abs(_errors(y_true, y_pred)), 95.0))


@check_types
def aic(n_samples: int, mse: float, n_params: int) -> float:
    """Akaike information criterion ``n ln(MSE) + 2k`` on the evaluation set (paper Table I).

    ``k`` counts the coefficients of all antennas (docs/conventions.md). Example: the paper's M row,
    ``aic(24087, 11.15**2, 1)`` = 116.17e3 (the paper prints 116.16e3 from the unrounded RMSE).
    """
    if n_samples <= 0 or not mse > 0:
        raise InputError(f"AIC needs n > 0 and MSE > 0, got n={n_samples}, MSE={mse}")
    return float(n_samples * np.log(mse) + 2 * n_params)


@check_types
def condition_number(design: ArrayLike) -> float:
    """Largest / smallest non-zero singular value of a design matrix."""
    s = np.linalg.svd(np.asarray(design, np.float64), compute_uv=False)
    if s.size == 0 or s[0] == 0:
        return float("inf")
    tol = s[0] * max(np.shape(design)) * np.finfo(np.float64).eps
    nz = s[s > tol]
    return float(nz[0] / nz[-1])


@check_types
@dataclass
class Stopwatch:
    """Wall time of a block, the paper's LTD (``time.perf_counter``) [s]."""

    seconds: float = field(default=float("nan"))

    @contextmanager
    def run(self) -> Iterator[Stopwatch]:
        start = time.perf_counter()
        try:
            yield self
        finally:
            self.seconds = time.perf_counter() - start


@check_types
@dataclass(frozen=True)
class Scores:
    """One row of the paper's Table I, plus MAE and the condition number."""

    model: str
    rmse_db: float
    mae_db: float
    q95_db: float
    n_params: int
    aic: float
    ltd_s: float
    n_samples: int
    condition_number: float = float("nan")

    def to_dict(self) -> dict:
        return dict(self.__dict__)


@check_types
def score(model: str, y_true: ArrayLike, y_pred: ArrayLike, n_params: int, ltd_s: float, cond: float = float("nan")) -> Scores:
    """All Table I metrics of one model on an evaluation set."""
    e = _errors(y_true, y_pred)
    mse = float(np.mean(e * e))
    return Scores(
        model=model,
        rmse_db=float(np.sqrt(mse)),
        mae_db=float(np.mean(np.abs(e))),
        q95_db=float(np.percentile(np.abs(e), 95.0)),
        n_params=int(n_params),
        aic=aic(e.size, mse, n_params),
        ltd_s=float(ltd_s),
        n_samples=int(e.size),
        condition_number=float(cond),
    )
