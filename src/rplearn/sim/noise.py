"""Coloured noise for the simulator: the AR(1) recursion of its Ornstein-Uhlenbeck processes
(:func:`rplearn.sim.flight.ou_process`), without ``scipy.signal``."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]


#: Samples per block of :func:`ar1_response`: its products cost ``2 * AR1_BLOCK`` flops a sample,
#: its Python loop one step a block.
AR1_BLOCK = 32


def ar1_response(drive: FloatArray, a: float, before: FloatArray) -> FloatArray:
    """The AR(1) recursion ``y[k] = a * y[k-1] + drive[k]`` from ``y[-1] = before``, per column.

    That is ``scipy.signal.lfilter([1], [1, -a], drive, axis=0, zi=a * before[None, :])[0]``
    to rounding (not bit for bit: the sums are grouped differently; the flights of the presets
    smoke, ground, tworay and pathloss come out with poses at most 3e-14 m apart and identical
    signal logs), without importing ``scipy.signal``, whose import (it pulls in ``scipy.stats``)
    cost every ``rplearn simulate`` 0.7-0.9 s of CPU on top of what it imports anyway.

    The samples are cut into blocks of :data:`AR1_BLOCK`: one matrix product gives every
    block's response from a zero state, ``sum_{j<=i} a^(i-j) drive[j]``; a loop over the blocks
    carries each block's last value into the next, and ``a^(i+1)`` times the carried state is
    added to sample ``i`` of a block. Every weight is a power of ``a`` in ``[0, 1]``, so nothing
    grows: a sample's rounding error is that of a sum of at most :data:`AR1_BLOCK` + 1 decaying
    terms plus the carried state's, which decays as in the recursion itself.

    Parameters
    ----------
    drive : ndarray, shape (n, dims)
        The input of each step.
    a : float
        Coefficient in ``[0, 1]`` (``exp(-dt / tau)`` for an Ornstein-Uhlenbeck process).
    before : ndarray, shape (dims,)
        The state before the first sample.

    Returns
    -------
    ndarray, shape (n, dims)
    """
    n, dims = drive.shape
    if n == 0:
        return np.empty((0, dims))
    size = AR1_BLOCK
    blocks = -(-n // size)
    padded = np.zeros((dims, blocks * size))
    padded[:, :n] = drive.T
    lag = np.arange(size)[None, :] - np.arange(size)[:, None]  # [j, i] = i - j
    weights = np.where(lag >= 0, a ** np.maximum(lag, 0).astype(np.float64), 0.0)  # a^(i-j), i >= j
    zero_state = (padded.reshape(dims * blocks, size) @ weights).reshape(dims, blocks, size)
    a_block = a ** float(size)
    ends = zero_state[:, :, -1].tolist()
    carried = np.empty((dims, blocks))
    for d in range(dims):
        state = float(before[d])
        row = [0.0] * blocks
        for m, end in enumerate(ends[d]):
            row[m] = state
            state = a_block * state + end
        carried[d] = row
    powers = a ** np.arange(1.0, size + 1.0)  # a^(i+1)
    out = zero_state + powers[None, None, :] * carried[:, :, None]
    return out.reshape(dims, blocks * size)[:, :n].T


__all__ = ["AR1_BLOCK", "ar1_response"]
