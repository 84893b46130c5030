"""The spreads of ``fit --order auto`` (:mod:`rplearn.models.auto`): what a node's gain may be
off by where the flight looked (the posterior, inflated by the held-out misfit) and where it
never looked (the prior's spread, capped by what the data can show).

- :func:`prior_std_db`: each node's prior spread at a direction from the penalty weights;
- :func:`prior_misfit_var`, :func:`unseen_spread_cap_db`: how far a stated or learned prior is
  off the data, and the cap on the unseen spread;
- :func:`within_unit_noise_var`, :func:`held_out_misfit_var`: the noise and the misfit the held-out
  units show beyond the posterior;
- :func:`misfit_covariance`: that misfit as a covariance of the pattern coefficients;
- :func:`drift_std_db`: the error drifting over seconds the fit's time blocks show (for the
  next flight's plan, ``rplearn trajectory --optimize --from-model``); :func:`block_drift_std_db`
  from block sums already added up (a live session's).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from functools import lru_cache
from typing import Any

import numpy as np

from rplearn.core.lsq.block_sums import DEFAULT_BLOCK_S, MIN_BLOCKS, BlockSums, correlated_ratio, link_block_count, time_block_sums
from rplearn.core.lsq.normal_equations import NormalEquations
from rplearn.core.lsq.penalty import DEFAULT_PENALTY_POWER, nested_columns, penalty_vector, sub_statistics
from rplearn.core.sh import SphericalHarmonics
from rplearn.models.spec import ModelSpec

#: The spherical-harmonic order the drifting error is read at (:func:`drift_std_db`): the model
#: ``rplearn trajectory --optimize`` plans in by default, so that the plan reads the drift its
#: own posterior would show (a larger order takes more of a drift into the pattern: on the
#: ``paper`` preset 1.02, 0.76 and 0.63 dB at SH-9, 12 and 15).
PLANNING_ORDER = 10


def planning_basis(basis: Any) -> Any:
    """The basis :func:`drift_std_db` reads the drifting error in, for statistics of ``basis``:
    SH-:data:`PLANNING_ORDER` (or ``basis`` when of a smaller order, or not SH). Its
    coefficient count is what statistics need keep per time block
    (:attr:`~rplearn.core.lsq.normal_equations.NormalEquations.block_coefs`)."""
    if isinstance(basis, SphericalHarmonics):
        return ModelSpec("sh", min(PLANNING_ORDER, basis.order)).basis()
    return basis


def drift_std_db(units: Sequence[NormalEquations], total: NormalEquations, weight: float, ridge: float, power: float,
                 noise_std_db: float) -> float | None:
    """The block-offset spread of an error drifting over seconds [dB] (a heading estimate's
    wander: :mod:`rplearn.core.lsq.block_sums`), as
    :func:`rplearn.analysis.manoeuvres.correlated_error_std_db` reads it: ``sqrt(kappa)``
    times ``noise_std_db``, ``kappa`` estimated by moments from the sums per
    :data:`~rplearn.core.lsq.block_sums.DEFAULT_BLOCK_S` time block the units' statistics kept
    while they were accumulated (no sample re-read), at SH-:data:`PLANNING_ORDER` (or the
    statistics' order when smaller, or their basis when not SH) under a smoothness prior of
    absolute weight ``weight``. None when they kept none (samples without times; statistics
    streamed chunk by chunk keep them as in memory, :func:`rplearn.models.streamed.accumulate`)
    or no link whose samples fall in :data:`~rplearn.core.lsq.block_sums.MIN_BLOCKS` distinct
    blocks (:func:`~rplearn.core.lsq.block_sums.link_block_count`: a flight of a few seconds,
    however many stretches or links it is summed in, or every sample at one time: no drift
    measured, which a model file must not state as none); 0 with no excess scatter.

    Why per link and distinct blocks: the drift is the variance of a link's offsets from one
    block to the next, which the moments tell from the link's pattern and level only over
    several blocks; counting one vector per statistics, block and link (what the sums hold)
    counted a 7-s flight's 2 blocks, cut into the 5 stretches of its cross-validation, as 6
    and stored 11.7 dB (the same flight's first 25 s and more: 0.0 dB; its first 10, 12, 15
    and 20 s, in 2, 3, 3 and 4 blocks: 4.0, 0.22, 1.86, 0.66 dB).

    Parameters
    ----------
    units : sequence of NormalEquations
        The flight units' statistics, their ``block_directed`` filled.
    total : NormalEquations
        Their sum (shared columns appended or not).
    weight, ridge, power : float
        The prior: the penalty's absolute weight (units of ``X^T X``), the ridge and the
        roughness power.
    noise_std_db : float
        The noise the spread is a multiple of (the fit's noise times the square root of its
        variance inflation: the noise a plan is made with).
    """
    if link_block_count(units) < MIN_BLOCKS:
        return None
    blocks = time_block_sums(units, DEFAULT_BLOCK_S, planning_basis(total.basis).n_coef)
    return block_drift_std_db(blocks, total, weight, ridge, power, noise_std_db)


def block_drift_std_db(blocks: BlockSums | None, total: NormalEquations, weight: float, ridge: float, power: float,
                       noise_std_db: float) -> float | None:
    """:func:`drift_std_db` from block sums already added up over the units (each block of
    each unit once, every block closed, at the coefficients of ``total``'s
    :func:`planning_basis`): a live session's, kept as its batches came
    (:class:`rplearn.models.live_drift.DriftBlocks`, whose caller checks that one link's samples
    fall in :data:`~rplearn.core.lsq.block_sums.MIN_BLOCKS` distinct blocks). None without them
    or when no link's samples fall in that many distinct blocks (:attr:`BlockSums.link_blocks`)."""
    if blocks is None or blocks.link_blocks < MIN_BLOCKS:
        return None
    basis = planning_basis(total.basis)
    normal = sub_statistics(total, basis)
    prior = float(ridge) + penalty_vector(basis, total.n_nodes, float(weight), 1.0, float(power))
    return float(np.sqrt(correlated_ratio(normal, blocks, prior))) * float(noise_std_db)


def prior_std_db(basis: Any, nodes: Sequence[str], weights: np.ndarray, noise_var: float,
                 power: float = DEFAULT_PENALTY_POWER) -> dict[str, float]:
    """Prior standard deviation of each node's gain at a direction [dB], as the automatic fit
    reads its penalty: coefficients ``N(target, noise_var / weights_j)`` (``weights`` the ridge
    plus the penalty of every column), averaged over the sphere. The columns the roughness of
    ``power`` leaves unpenalised (the constant of a smoothness penalty) are left out: the data
    and the gauge fix them.

    Where the flight never looked, the predictive spread of a node's gain returns to this
    value; close to the data it is far smaller. With a prior pattern it is how far the truth
    may stray from the prior; without one, how far from its level (the data's) the pattern may be.
    """

    p = basis.n_coef
    keep = np.asarray(basis.roughness(power)) > 0
    squares = _kept_squares(basis, float(power))  # (directions, penalised columns)
    out = {}
    for k, node in enumerate(nodes):
        weight = np.asarray(weights[k * p:(k + 1) * p], np.float64)[keep]
        var = noise_var * squares @ (1.0 / np.maximum(weight, 1e-300))
        out[str(node)] = float(np.sqrt(np.mean(var))) if keep.any() else float("inf")
    return out


@lru_cache(maxsize=8)
def _design_squares(basis: Any) -> np.ndarray:
    """The squared design of ``basis`` on a Fibonacci grid of ``max(4 n_coef, 400)`` directions
    (the sphere averages of :func:`prior_std_db` and :func:`misfit_covariance`; once per basis
    and process), read-only."""
    from rplearn.core.bases import fibonacci_grid_nodes

    az, el = fibonacci_grid_nodes(max(4 * basis.n_coef, 400))
    squares = basis.design(az, el) ** 2
    squares.setflags(write=False)
    return squares


@lru_cache(maxsize=8)
def _kept_squares(basis: Any, power: float) -> np.ndarray:
    """The columns of :func:`_design_squares` that the roughness of ``power`` penalises (what
    :func:`prior_std_db` sums; once per basis and power, not per node and call), read-only."""
    kept = _design_squares(basis)[:, np.asarray(basis.roughness(power)) > 0]
    kept.setflags(write=False)
    return kept


@lru_cache(maxsize=8)
def _half_level(basis: Any) -> np.ndarray:
    """Coefficients of the constant 0.5 dB in ``basis`` (least squares on a Fibonacci grid; once
    per basis and process), read-only."""
    from rplearn.core.bases import fibonacci_grid_nodes

    az, el = fibonacci_grid_nodes(max(4 * basis.n_coef, 400))
    half = np.linalg.lstsq(basis.design(az, el), np.full(az.size, 0.5), rcond=None)[0]
    half.setflags(write=False)
    return half


def prior_misfit_var(normal: NormalEquations, target: np.ndarray, basis: Any) -> float:
    """Mean squared difference [dB^2] between the joint gains of the samples and those of the
    prior coefficients ``target``, after the best constant offset (a prior's absolute level is
    a convention the gauge does not share) and the best shared coefficients (a path-loss
    exponent, link offsets: the priors describe antennas, not the channel), from the
    statistics alone."""
    ones = np.tile(_half_level(basis), normal.n_nodes)  # X @ ones = 1 for every sample (half a dB from each end)
    pat = normal.n_pattern_columns
    g, r = normal.gram, normal.rhs
    target = np.asarray(target, np.float64)[:pat]
    # the free part: columns [X_p ones, X_shared], fitted to y - X_p target
    z = np.zeros((normal.n_columns, 1 + normal.n_columns - pat))
    z[:pat, 0] = ones
    z[pat:, 1:] = np.eye(normal.n_columns - pat)
    full_target = np.concatenate([target, np.zeros(normal.n_columns - pat)])
    free = np.linalg.lstsq(z.T @ g @ z, z.T @ (r - g @ full_target), rcond=None)[0]
    c = full_target + z @ free
    return float(max(normal.yty - 2.0 * c @ r + c @ g @ c, 0.0) / max(normal.n_samples, 1))


def within_unit_noise_var(stats: Mapping[str, NormalEquations], normal: NormalEquations, coef: np.ndarray,
                          rank: int) -> float:
    """Residual variance [dB^2] of the fit ``coef`` about each unit's own mean residual: the
    noise of one packet around its flight's level (the training residual variance with the
    flights' levels, which the patterns cannot know, taken out). Degrees of freedom: the
    samples less ``rank`` and the units' means beyond the common level."""
    c = np.asarray(coef, np.float64)
    sse = normal.yty - 2.0 * c @ normal.rhs + c @ normal.gram @ c
    for st in stats.values():
        if st.n_samples:
            a, sum_y = st.column_sums()
            idx = np.concatenate([nested_columns(st.basis, normal.basis, st.n_nodes),
                                  st.n_pattern_columns + np.arange(len(st.shared))])
            sse -= (sum_y - c @ a[idx]) ** 2 / st.n_samples
    units = sum(1 for st in stats.values() if st.n_samples)
    return max(float(sse), 0.0) / max(normal.n_samples - rank - (units - 1), 1)


def unseen_spread_cap_db(normal: NormalEquations, basis: Any) -> float:
    """The spread [dB, 1 sigma] a node's gain is given where the flight never looked (without a
    prior): the root mean square of the joint gains the flight measured about their best
    constant (and the path-loss and offset terms), noise and flights' levels included.

    Used as a floor too (not only a ceiling): the spread the cross-validated smoothing implies
    says how far the pattern may stray where the data are, not on the unseen sphere (measured
    on planner's flights where the ``campaign`` preset never looked: 0.7 dB implied, the truth
    12 dB off; ``ground``: 5.0 dB stated, 9.5 dB off). Both remain under the truth there: the
    flight says nothing of an unseen side brighter than anything it measured.

    Why this cap: far from every learning direction the penalised fit returns toward the
    pattern's level, so its error there is how far the pattern strays from that level, about
    which the flight says only how far the gains strayed where it looked. Nothing the flight
    measured varied by more than this (the joint gain of both ends, noise included, given to
    each end alone): a larger 1-sigma would only restate the smoothing's arbitrary prior
    variance (tens of dB once multiplied by a variance inflation), a number no user can act
    on; this one is generous (the pattern's own variation where seen is smaller). It is an
    assumption, stated: an antenna whose unseen side holds a deeper null than anything the
    flight measured is off by more there; the warning on uncovered predictions says where.
    """
    return float(np.sqrt(prior_misfit_var(normal, np.zeros(normal.n_pattern_columns), basis)))


def held_out_misfit_var(excess_db2: float, covariance: np.ndarray | None, normal: NormalEquations) -> float:
    """Variance [dB^2] of the joint gain's error that the model cannot represent, from the
    grouped cross-validation: the held-out units' mean square error per sample beyond the
    folds' within-unit noise (:attr:`Selection.held_out_excess_db2`), less what the final fit's
    (inflated) posterior states at the learning samples (``tr(C G) / n``), at least 0.

    Why: the held-out error beyond the noise is the fit's variance *and* its misfit (structure
    between the learned directions that the chosen order and smoothing cannot represent: a
    drone's fine lobes between two learned elevations). The variance inflation carries it into
    the posterior, which shrinks as units are added; the misfit does not shrink with more of
    the same flights. Where the final posterior already states the held-out error, this is 0
    (a model that represents the pattern, enough units); where it states less, the shortfall
    is error it does not count. It is split between the two ends of a link and added to each
    node's pattern covariance everywhere (:func:`misfit_covariance`), so the model's predictive
    spread (``predict``, availability, the swarm's draws) holds it.

    The decoupling certificate's per-node spread (:mod:`rplearn.models.own_posterior`) does
    not add it: its posterior is continued to the largest order, which carries the structure
    the chosen order misses, and the variance inflation already carries the held-out excess
    into each node's variance along the directions the flight cannot split. Measured
    (``benchmarks/split.py``): with it added there, ``paper``/``pathloss`` spread/error rose
    from 0.74-1.21 to 0.94-1.58 (``pathloss`` seed 2: 1.58), ``ground`` G from 0.64-0.87 to 0.71-0.95.
    On the joint gain it is what was missing (held-out flights, seed 0, median stated against
    RMS actual joint error: ``paper`` 0.63 -> 1.32 against 1.25 dB; ``ground`` at a learned
    elevation 0.20 -> 0.93 against 1.13 dB).
    """
    if covariance is None or not excess_db2 > 0 or normal.n_samples == 0:
        return 0.0
    c = np.asarray(covariance, np.float64)
    k = min(c.shape[0], normal.n_columns)
    stated = float(np.sum(c[:k, :k] * normal.gram[:k, :k])) / normal.n_samples
    return max(float(excess_db2) - stated, 0.0)


def misfit_covariance(basis: Any, n_nodes: int, node_var_db2: float) -> np.ndarray:
    """``(n_nodes * basis.n_coef)`` square diagonal: coefficients independent per node with the
    variance that gives each node's gain ``node_var_db2`` at a direction, averaged over the
    sphere (for spherical harmonics the same at every direction: the addition theorem)."""

    p = basis.n_coef
    per_coef = float(node_var_db2) / max(float(np.mean(np.sum(_design_squares(basis), axis=1))), 1e-300)
    return np.eye(n_nodes * p) * per_coef
