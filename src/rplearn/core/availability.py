"""Availability of a link: the probability that its received power reaches a radio's sensitivity.

The predictive distribution of a link's RSSI [dBm] is taken as normal in dB, with the mean and the
standard deviation a model predicts (``rssi_pred_dbm``, ``rssi_pred_std_db``: the pattern
posterior, the environment terms and the residual spread of fading and noise). A link is *up*
when its RSSI is at or above the sensitivity, so its availability is
``P(RSSI >= s) = Phi((mean - s) / std)``; a zero spread makes it a step (1 at or above ``s``).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike
from scipy.special import ndtr

from rplearn._argtypes import check_types
from rplearn.errors import InputError


@check_types
def link_availability(rssi_mean_dbm: ArrayLike, rssi_std_db: ArrayLike, sensitivity_dbm: float) -> np.ndarray:
    """Probability that a link's RSSI is at or above ``sensitivity_dbm``.

    Parameters
    ----------
    rssi_mean_dbm : array_like
        Predicted mean RSSI [dBm].
    rssi_std_db : array_like
        Predicted standard deviation of the RSSI [dB], broadcast against the mean; non-negative.
    sensitivity_dbm : float
        The radio's sensitivity [dBm]: the lowest RSSI at which the link is up.

    Returns
    -------
    numpy.ndarray
        ``P(RSSI >= sensitivity_dbm)`` in [0, 1], of the broadcast shape; NaN where the mean or the
        spread is NaN.

    Raises
    ------
    InputError
        A non-finite sensitivity or a negative spread.
    """
    if not np.isfinite(sensitivity_dbm):
        raise InputError(f"sensitivity_dbm: expected a finite level in dBm, got {sensitivity_dbm!r}",
                         param="sensitivity_dbm")
    mean = np.asarray(rssi_mean_dbm, dtype=np.float64)
    std = np.asarray(rssi_std_db, dtype=np.float64)
    if np.any(std < 0):
        raise InputError("rssi_std_db: a standard deviation is negative", param="rssi_std_db")
    margin = mean - float(sensitivity_dbm)
    with np.errstate(divide="ignore", invalid="ignore"):
        z = np.where(std > 0, margin / np.where(std > 0, std, 1.0), np.where(margin >= 0, np.inf, -np.inf))
    out = ndtr(z)
    return np.where(np.isnan(margin) | np.isnan(std), np.nan, out)
