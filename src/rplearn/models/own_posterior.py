"""The posterior of each node's *own* pattern, for the decoupling certificate.

The automatic fit predicts with the order and smoothing that cross-validation chose; a smaller
order is a hard prior that every coefficient above it is exactly zero. For the joint
prediction that is harmless (cross-validation found the higher orders add nothing it can see),
but it is not a statement about each node's own pattern: where the flight cannot split a
change between the two ends of a link, or thins out at the edge of what it covered, the higher
orders carry pattern structure the data neither confirm nor exclude. The honest per-node
spread is therefore read from the posterior of the *same* smoothness prior continued to the
largest candidate order (the statistics are already accumulated there, so this costs one solve
and no sample read), with the noise and the variance inflation of the chosen fit.

Two choices, argued:

- The prior is the cross-validated one, *not* capped at the spread of the measured gains
  (:func:`rplearn.models.auto.unseen_spread_cap_db`). The cap bounds the predictive spread
  where the flight never looked; where it looked, the question is how loosely the data tie
  each node's share, which the cross-validated prior answers.
- Above :data:`MAX_OWN_COLUMNS` pattern columns (large swarms) the chosen fit's own posterior
  is used (uncapped likewise), and the note says so: the per-node spreads are then a lower
  bound where the chosen order is below the largest.
- The certificate reports the expected square error of the *chosen* fit's pattern under this
  posterior: its variance plus the square of the chosen pattern's difference from the
  posterior mean (:attr:`OwnPosterior.mean`). Where the chosen order truncates structure the
  larger order finds (the edge of the covered band), the difference is the part of the error
  the variance alone does not hold.

Measured on the ``ground`` preset (seeds 0-2, ``benchmarks/split.py``; the fit chooses SH-5 of
candidates up to SH-15): the reported per-node spread against the actual per-node error over
the covered directions went from 0.30-0.44 (the chosen SH-5's capped posterior) to 0.61-0.93
with the continued posterior's variance alone (D 0.87-0.93, G 0.61-0.79), and to 0.64-1.43
with the chosen fit's offset from its mean (D 1.25-1.43, G 0.64-0.87). On ``paper`` and
``pathloss`` the chosen order is the largest and nothing changes (0.72-1.22).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from rplearn.core.basis_base import Basis
from rplearn.core.gauge import Gauge
from rplearn.core.lsq.normal_equations import NormalEquations
from rplearn.core.lsq.selection import penalty_vector
from rplearn.core.lsq.solver import solve

#: Pattern columns above which the own-pattern posterior is not continued to the largest order.
MAX_OWN_COLUMNS = 1500


@dataclass(frozen=True)
class OwnPosterior:
    """Posterior covariance of the pattern coefficients, read per node by the certificate.

    Attributes
    ----------
    basis : Basis
        The basis of ``covariance``'s node blocks (the largest candidate order, or the model's).
    covariance : ndarray
        ``(n_nodes * basis.n_coef)`` square [dB^2]: the pattern columns only.
    note : str
        Empty, or why the model's own order was used.
    mean : ndarray or None
        ``(n_nodes, basis.n_coef)``: the posterior mean of each node's coefficients at ``basis``
        when it is larger than the model's (None when it is the model's). The reported pattern
        is the chosen fit's, not this mean, so its expected square error under the posterior
        adds the square of their difference to the posterior variance.
    """

    basis: Basis
    covariance: np.ndarray
    note: str = ""
    mean: np.ndarray | None = None


@dataclass(frozen=True)
class OwnPrior:
    """The chosen fit's prior, to be continued to a larger basis.

    Attributes
    ----------
    smoothing : float
        The cross-validated relative smoothing.
    scale : float
        The penalty's unit at the chosen basis (:func:`rplearn.core.lsq.selection.penalty_scale`),
        kept so that the shared low orders get exactly the chosen fit's prior.
    power : float
        Exponent of the roughness weights.
    ridge : float
    gauge : str or mapping
    target : ndarray or None
        Prior coefficients at the *largest* basis (``fit --prior``), or None.
    prior_level : str
    """

    smoothing: float
    scale: float
    power: float
    ridge: float
    gauge: Gauge | str | Mapping[str, Any]
    target: np.ndarray | None
    prior_level: str = "data"


def own_pattern_posterior(total: NormalEquations, chosen: Basis, nodes: Sequence[str], prior: OwnPrior,
                          noise_var_db2: float, fallback: np.ndarray | None) -> OwnPosterior | None:
    """The own-pattern posterior (module docstring).

    Parameters
    ----------
    total : NormalEquations
        The learning statistics at the largest candidate basis (shared columns appended).
    chosen : Basis
        The basis the fit chose.
    nodes : sequence of str
    prior : OwnPrior
    noise_var_db2 : float
        The chosen fit's noise variance times its variance inflation [dB^2].
    fallback : ndarray or None
        The chosen fit's posterior covariance (uncapped), used when the largest basis is the
        chosen one or too large; None when the fit has no covariance.
    """
    big = total.basis
    pat_big = big.n_coef * len(nodes)
    if big == chosen or pat_big > MAX_OWN_COLUMNS:
        if fallback is None:
            return None
        note = "" if big == chosen else (f"(per-node spreads at the chosen {chosen.label}: {pat_big} pattern columns at "
                                         f"{big.label}, above {MAX_OWN_COLUMNS}; a lower bound)")
        pat = chosen.n_coef * len(nodes)
        return OwnPosterior(chosen, np.asarray(fallback, np.float64)[:pat, :pat], note)
    penalty = penalty_vector(big, len(nodes), prior.smoothing, prior.scale, prior.power)
    wide = solve(total, list(nodes), ridge=prior.ridge, gauge=prior.gauge, penalty=penalty, penalty_target=prior.target,
                 prior_level=prior.prior_level)
    if wide.covariance is None or not wide.residual_variance_db2 > 0:
        return None if fallback is None else OwnPosterior(chosen, np.asarray(fallback, np.float64)[:chosen.n_coef * len(nodes),
                                                                                                   :chosen.n_coef * len(nodes)])
    cov = np.asarray(wide.covariance, np.float64)[:pat_big, :pat_big] * (noise_var_db2 / wide.residual_variance_db2)
    return OwnPosterior(big, cov, mean=np.asarray(wide.coef, np.float64).reshape(len(nodes), big.n_coef))


__all__ = ["MAX_OWN_COLUMNS", "OwnPosterior", "OwnPrior", "own_pattern_posterior"]
