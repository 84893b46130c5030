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

The choices, argued:

- The prior is the cross-validated one, *not* capped at the spread of the measured gains
  (:func:`rplearn.models.auto_spread.unseen_spread_cap_db`). The cap bounds the predictive spread
  where the flight never looked; where it looked, the question is how loosely the data tie
  each node's share, which the cross-validated prior answers.
- Above :data:`MAX_OWN_COLUMNS` pattern columns (large swarms) the chosen fit's own posterior
  is used (uncapped likewise), and the note says so: the per-node spreads are then a lower
  bound where the chosen order is below the largest.
- The certificate reports the posterior variance about the *chosen* fit's pattern; the
  continued posterior's mean is not taken as a better centre (its difference from the chosen
  pattern is not added as an offset). That mean is the fit at the largest order with the
  chosen smoothing, a point the cross-validation itself scored worse (``ground``: 4.78-5.32 dB
  against at most 4.74 dB for the chosen fit), and its per-node pattern error is no smaller: over
  ``ground`` seeds 0-2 the chosen fit's errors are 1.30/1.53, 1.39/1.93 and 1.44/2.02 dB (D/G)
  against the mean's 1.65/1.80, 1.29/1.93 and 1.25/2.34. Were the mean the better centre, the
  chosen fit's error would exceed it by the offset (1.0-1.6 dB on D); it does not, so the offset
  overstated the error (D's spread 1.43-1.87 times its error with it, 0.87-1.44 without).
  A caller may still give an :class:`OwnPosterior` with a ``mean`` (the certificate then adds
  the offset).

- The posterior is averaged over the points of the order-and-smoothing search that the
  held-out units cannot tell from the best (:func:`tied_own_posterior`,
  :mod:`rplearn.core.lsq.ties`), each with its own variance inflation. The per-node spread
  where the flight looked is mostly the components the joint gain cannot split (97-98% of it on
  ``ground``), whose variance is the prior's: a point choice of the smoothing carries the
  validation's looseness straight into it. Measured on ``ground`` seed 1: SH-5 at 3.2e-5
  validates 4.524 dB, SH-4 at 1e-5 4.532 dB, and their own-pattern spreads are 1.20 and
  1.89 dB for errors alike; the prior's roughness exponent is pinned still less (seed 0,
  powers 1 to 3: validation 4.534-4.550 dB, spreads 3.39 to 0.76 dB).

Measured on the ``ground`` preset (seeds 0-2, ``benchmarks/split.py``; candidates up to SH-15,
chosen SH-4 or SH-5): the reported per-node spread against the actual per-node error over the
covered directions is D 1.02-1.38 and G 0.73-1.15 (0.87-1.44 and 0.62-1.26 from the chosen point
alone). What remains short on G is at the edge of the covered band on the horizon side, 3-8 deg
below the lowest learning direction (still within the 10 deg of "covered"), where the sectoral
antenna's gain rises steeply toward its horizontal beam (seed 1: 3.0 dB of error against 2.1 dB
of spread 6-10 deg from the nearest learning direction). No held-out unit measures that: the
folds extrapolate between the two flown altitudes (G's error there 0.4-1.0 dB on seed 1), never
beyond the lowest, so a misfit estimated from the folds as a function of the distance to the
nearest learning direction adds almost nothing there (seed 1's G 0.62 -> 0.65 from the held-out
joint residuals, 0.66 from the folds' per-node patterns, which push seed 0's D to 1.56). The truncation of the truth above SH-15 is 0.35 dB.
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Generator, Mapping, Sequence
from dataclasses import dataclass, replace
from typing import Any, cast

import numpy as np

from rplearn.core.basis_base import Basis
from rplearn.core.gauge import Gauge
from rplearn.core.lsq.normal_equations import NormalEquations
from rplearn.core.lsq.penalty import nested_columns, penalty_scale_of_diagonal
from rplearn.core.lsq.runtime import DEFAULT_RUNTIME
from rplearn.core.lsq.selection import penalty_vector
from rplearn.core.lsq.solver import penalised_inverse, solve

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
        ``(n_nodes, basis.n_coef)``: a posterior mean at ``basis`` to take as the centre instead
        of the model's pattern (the certificate then adds the square of their difference to the
        variance); None (what :func:`own_pattern_posterior` gives, see the module docstring):
        the model's pattern is the centre.
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


#: The noise-free part of a continued posterior (:func:`continued_parts`): the pattern block
#: and the residual variance it is to be divided by (None: read it with the noise as it is).
ContinuedParts = tuple[np.ndarray, float | None] | None


def own_pattern_posterior(total: NormalEquations, chosen: Basis, nodes: Sequence[str], prior: OwnPrior,
                          noise_var_db2: float, fallback: np.ndarray | None,
                          parts: Callable[[], ContinuedParts] | None = None) -> OwnPosterior | None:
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
    parts : callable, optional
        Gives :func:`continued_parts` of ``prior`` at ``total``'s basis, computed beforehand
        (:func:`continued_jobs`: beside the final solve); by default computed here.
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
    cov = read_continued(continued_parts(total, nodes, prior) if parts is None else parts(), noise_var_db2)
    if cov is None:
        return None if fallback is None else OwnPosterior(chosen, np.asarray(fallback, np.float64)[:chosen.n_coef * len(nodes),
                                                                                                   :chosen.n_coef * len(nodes)])
    return OwnPosterior(big, cov)  # centred on the chosen pattern (module docstring)


def continued_parts(total: NormalEquations, nodes: Sequence[str], prior: OwnPrior) -> ContinuedParts:
    """The pattern block of the posterior covariance of ``prior`` at ``total``'s basis before it
    is read with a noise (:func:`read_continued`; None when the solve gives none): the
    constrained inverse of the penalised normal matrix
    (:func:`rplearn.core.lsq.solver.penalised_inverse`: one Cholesky factor, no solve), or a
    whole solve's covariance and residual variance when that matrix is not positive definite.
    Independent of the noise and of the chosen fit's solve: any thread, beside that solve."""
    penalty = penalty_vector(total.basis, len(nodes), prior.smoothing, prior.scale, prior.power)
    pat = total.basis.n_coef * len(nodes)
    inverse = penalised_inverse(total, list(nodes), prior.ridge, prior.gauge, penalty)
    if inverse is not None:
        return inverse[:pat, :pat], None
    wide = solve(total, list(nodes), ridge=prior.ridge, gauge=prior.gauge, penalty=penalty, penalty_target=prior.target,
                 prior_level=prior.prior_level)
    if wide.covariance is None or not wide.residual_variance_db2 > 0:
        return None
    return np.asarray(wide.covariance, np.float64)[:pat, :pat], float(wide.residual_variance_db2)


def read_continued(parts: ContinuedParts, noise_var_db2: float) -> np.ndarray | None:
    """The continued posterior covariance (:func:`continued_parts`) read with the noise
    ``noise_var_db2`` [dB^2] (None when there is none)."""
    if parts is None:
        return None
    block, residual_var = parts
    return block * noise_var_db2 if residual_var is None else block * (noise_var_db2 / residual_var)


def tied_groups(total: NormalEquations, prior: OwnPrior, ties: Sequence[tuple[int, float, float]],
                make_basis: Callable[[int], Basis]) -> list[tuple[OwnPrior, float]]:
    """The tied points (:func:`tied_own_posterior`) grouped by their prior continued to
    ``total``'s basis, each group with the sum of its points' variance inflations, in the order
    of the points' first appearance.

    Continued to the largest basis, a point's prior depends on its order only through the
    penalty's unit (for spherical harmonics the same at every order: the addition theorem),
    so points of one (smoothing, unit) share one solve.
    """
    groups: dict[tuple[float, float], tuple[OwnPrior, float]] = {}
    diagonal = np.diag(total.gram)
    for order, smoothing, inflation in ties:
        # the penalty's unit at that order (penalty_scale of its sub-block, read off the diagonal)
        d = diagonal[nested_columns(total.basis, make_basis(int(order)), total.n_nodes)]
        point = replace(prior, smoothing=float(smoothing), scale=penalty_scale_of_diagonal(d))
        key = (point.smoothing, point.scale)
        groups[key] = (groups[key][0], groups[key][1] + float(inflation)) if key in groups else (point, float(inflation))
    return list(groups.values())


def continued_jobs(total: NormalEquations, chosen: Basis, nodes: Sequence[str], prior: OwnPrior,
                   ties: Sequence[tuple[int, float, float]],
                   make_basis: Callable[[int], Basis]) -> tuple[bool, list[Callable[[], ContinuedParts]]]:
    """The heavy work of :func:`own_pattern_posterior` and :func:`tied_own_posterior`, as jobs
    to run beside the chosen fit's final solve (they do not depend on it): whether the first
    job is the chosen point's (the largest basis is not the chosen one), then one job per
    group of :func:`tied_groups` (when there are two tied points or more). No job above
    :data:`MAX_OWN_COLUMNS` pattern columns. A job's result is :func:`continued_parts`; the
    two functions read them with their ``parts`` arguments."""
    own, points = continued_points(total, chosen, len(nodes), prior, ties, make_basis)
    return own, [functools.partial(continued_parts, total, list(nodes), g) for g in points]


def continued_points(total: NormalEquations, chosen: Basis, n_nodes: int, prior: OwnPrior,
                     ties: Sequence[tuple[int, float, float]],
                     make_basis: Callable[[int], Basis]) -> tuple[bool, list[OwnPrior]]:
    """The priors whose :func:`continued_parts` :func:`continued_jobs` computes, in its order:
    whether the first is the chosen point's, then one per group of :func:`tied_groups` (when
    there are two tied points or more); none above :data:`MAX_OWN_COLUMNS` pattern columns."""
    if total.basis.n_coef * n_nodes > MAX_OWN_COLUMNS:
        return False, []
    own = total.basis != chosen
    points = [prior] if own else []
    if len(ties) >= 2:
        points += [g for g, _ in tied_groups(total, prior, ties, make_basis)]
    return own, points


def solved_parts(prior: OwnPrior, point: OwnPrior, covariance: np.ndarray | None, residual_var_db2: float,
                 n_pattern_columns: int) -> ContinuedParts | bool:
    """:func:`continued_parts` of ``point`` read off the chosen fit's own solve (of ``prior``,
    at the largest basis: its covariance and residual variance), when ``point`` is that very
    system: the same smoothing and penalty unit (the other fields are the chosen fit's in
    every point of :func:`tied_groups`); False when it is another (its inverse is needed).
    The solve's covariance is ``residual_var_db2 M`` with ``M`` the constrained inverse
    :func:`continued_parts` would form again (the penalty read as a prior: no sandwich)."""
    if point.smoothing != prior.smoothing or point.scale != prior.scale or covariance is None or not residual_var_db2 > 0:
        return False
    return np.asarray(covariance, np.float64)[:n_pattern_columns, :n_pattern_columns], float(residual_var_db2)


def tied_own_posterior(own: OwnPosterior | None, total: NormalEquations, nodes: Sequence[str], prior: OwnPrior,
                       ties: Sequence[tuple[int, float, float]], within_var_db2: float,
                       make_basis: Callable[[int], Basis], parts: Sequence[ContinuedParts] | None = None,
                       ) -> OwnPosterior | None:
    """The own-pattern posterior averaged over the points the cross-validation cannot tell
    apart (:attr:`rplearn.core.lsq.selection.Selection.ties`; :mod:`rplearn.core.lsq.ties`
    says why): the mean of their covariances, each the prior of that order and smoothing
    continued to ``total``'s basis and read with ``within_var_db2`` times that point's variance
    inflation, centred on the chosen pattern as ``own`` is. ``own`` itself when there is one
    point, or when ``own`` is not at ``total``'s basis (too many columns, see
    :data:`MAX_OWN_COLUMNS`).

    Parameters
    ----------
    own : OwnPosterior or None
        The chosen point's (:func:`own_pattern_posterior`).
    total : NormalEquations
        The learning statistics at the largest candidate basis (shared columns appended).
    nodes : sequence of str
    prior : OwnPrior
        The chosen fit's; each point's smoothing and penalty unit replace its own.
    ties : sequence of (order, smoothing, variance inflation)
    within_var_db2 : float
        The chosen fit's noise about each flight's level [dB^2] (before inflation).
    make_basis : callable
        ``make_basis(order)`` -> the basis of that order (nested in ``total``'s).
    parts : sequence, optional
        :func:`continued_parts` of each group of :func:`tied_groups`, computed beforehand
        (:func:`continued_jobs`); by default computed here, on the statistics' workers.
    """
    if own is None or len(ties) < 2 or own.basis != total.basis or total.basis.n_coef * len(nodes) > MAX_OWN_COLUMNS:
        return own
    points = tied_groups(total, prior, ties, make_basis)
    total_cov: np.ndarray | None = None  # running sum: a few solves' matrices held at a time
    # on the statistics' workers, a few at a time (the runtime keeps at most its ``ahead`` pending);
    # closed here so that the pool is given back at once, also when a point has no posterior
    matrices = cast(Generator[np.ndarray | None, None, None],  # in_order is a generator
                    (read_continued(p, 1.0) for p in parts) if parts is not None else
                    DEFAULT_RUNTIME.in_order(lambda g: read_continued(continued_parts(total, nodes, g[0]), 1.0), points))
    try:
        for (_, inflations), cov in zip(points, matrices, strict=True):
            if cov is None:
                return own
            cov *= within_var_db2 * inflations
            total_cov = cov if total_cov is None else np.add(total_cov, cov, out=total_cov)
    finally:
        matrices.close()
    assert total_cov is not None
    return OwnPosterior(own.basis, total_cov / len(ties), own.note, own.mean)


__all__ = ["MAX_OWN_COLUMNS", "ContinuedParts", "OwnPosterior", "OwnPrior", "continued_jobs", "continued_parts",
           "continued_points", "own_pattern_posterior", "read_continued", "solved_parts", "tied_groups", "tied_own_posterior"]
