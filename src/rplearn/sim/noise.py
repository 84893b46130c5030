"""Coloured noise for the simulator: stationary Ornstein-Uhlenbeck processes (AR(1)) and their
filter, without importing ``scipy.signal`` for short series (:func:`ar1_filter`)."""

from __future__ import annotations

import sys

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]


def ou_process(rng: np.random.Generator, n: int, dt_s: float, std: float, tau_s: float, dims: int = 1) -> FloatArray:
    """Stationary Ornstein-Uhlenbeck samples (AR(1)), shape (n, dims).

    Parameters
    ----------
    std : float
        Stationary standard deviation; 0 gives zeros.
    tau_s : float
        Correlation time [s]; 0 gives white noise.
    """
    if std <= 0 or n == 0:
        return np.zeros((n, dims))
    eps = rng.standard_normal((n, dims))
    if tau_s <= 0:
        return std * eps
    a = float(np.exp(-dt_s / tau_s))
    b = std * np.sqrt(1.0 - a * a)
    x0 = std * eps[0]
    return np.vstack([x0[None, :], ar1_filter(eps[1:], a, b, x0)])


#: Samples (times columns) up to which :func:`ar1_filter` runs a plain loop rather than
#: ``scipy.signal.lfilter`` while ``scipy.signal`` is not imported yet: importing it (it pulls
#: in ``scipy.stats``) costs about 1 s of CPU, the loop about 0.4 s a million samples and
#: ``lfilter`` about 40 times less; the smoke preset's series hold at most 60,000, the paper
#: preset's up to 1.3 million. Once the process has imported ``scipy.signal`` (a fit's
#: statistics, a report, a test session), ``lfilter`` filters every series.
AR1_LOOP_MAX_SAMPLES = 200_000


def ar1_filter(drive: FloatArray, a: float, b: float, before: FloatArray) -> FloatArray:
    """``y[k] = b * drive[k] + a * y[k-1]`` from ``y[-1] = before``, per column: what
    ``scipy.signal.lfilter([b], [1, -a], drive, axis=0, zi=a * before[None, :])[0]`` gives,
    bit for bit for finite values (the same floating-point operations in the same order), by a plain loop for
    up to :data:`AR1_LOOP_MAX_SAMPLES` samples while ``scipy.signal`` is not imported, and by
    ``lfilter`` beyond or once it is (a paper-preset flight: 1.4 s less CPU of about 6).

    Parameters
    ----------
    drive : ndarray, shape (n, dims)
    a, b : float
        The feedback and input coefficients.
    before : ndarray, shape (dims,)
        The state before the first sample.
    """
    n, dims = drive.shape
    if n * dims > AR1_LOOP_MAX_SAMPLES or sys.modules.get("scipy.signal") is not None:
        from scipy.signal import lfilter

        return np.asarray(lfilter([b], [1.0, -a], drive, axis=0, zi=(a * before)[None, :])[0], np.float64)
    out = np.empty((n, dims))
    for d in range(dims):
        state, column = float(before[d]), []
        for value in drive[:, d].tolist():
            state = b * value + a * state
            column.append(state)
        out[:, d] = column
    return out


__all__ = ["AR1_LOOP_MAX_SAMPLES", "ar1_filter", "ou_process"]
