"""``fit --order auto --prior``: the order search on the *deviation* from a reference prior, the
prior's own degrees above the chosen order kept.

A reference pattern (a vendor's sheet, a chamber's measurement) holds the structure the learning
flights never looked at; its higher degrees shape it there. The automatic fit's statistics are
accumulated at the largest candidate order ``K``; with ``s`` the prior's shape at ``K`` (its
coefficients, each node's sphere mean dropped: :func:`rplearn.core.lsq.level.pattern_shape`,
tapered by :data:`PRIOR_TAPER_RESOLUTION` against the ringing of a series cut at ``K``), the
model at a candidate order ``k`` is

    ``c = s + [d_{<=k}, 0]``, minimising ``||y - X s - X_k d||^2 + ||d - d0||^2_R``

(``R`` the ridge and the plain-ridge penalty of the cross-validated smoothing; ``d0`` the data's
level per node, or with ``prior_level="prior"`` the prior's own level; link offsets and the
path-loss exponent free as ever). That is the existing order-and-smoothing search run on the
statistics of ``y - X s`` (:func:`rplearn.core.lsq.shifted.shifted_statistics`, per unit, so the
folds stay exact) with a zero shape: the search is unchanged, and above ``k`` the model's
coefficients are the prior's. Before, a prior was cut to the chosen order (SH-4 to SH-9 on the
planner's tests), so its higher degrees were lost exactly where the flights never looked.

Why the shape and not the prior itself: the gauge constrains the nodes' sphere means, which the
shape leaves at zero, so the gauge holds on the model as on the deviation; the level comes from
the data (or the prior's, as the target of the deviation's constant with ``prior_level="prior"``).
Untapered, at ``k = K`` the model is the one the search on the prior cut to ``k`` gives (the
same penalised least squares).

Kept or cut: the held-out units can check the prior's higher degrees only where the flights
looked. So the search also runs as before, on the prior cut to its chosen order, and the kept
prior is taken unless the units find it worse beyond noise (:func:`kept_within_noise`, the rule
of :mod:`rplearn.core.lsq.ties`). Measured (seeds 0-2, the planner's tests): an imperfect
reference (mounted 10 deg off) kept validates far worse where the flights looked (``ground``
5.29 / 5.04 / 4.95 dB against 4.32 / 4.37 / 4.33 cut; ``campaign`` 5.81 / 5.58 / 5.26 against
5.64 / 5.47 / 5.17), its fine structure misplaced, and is cut; a near-exact one (0.5 dB) is kept
on ``ground`` seeds 0 and 1 (4.273 against 4.298, 4.303 against 4.295 dB) and cut on seed 2.

The posterior covariance is that of the same prior at ``K`` (:func:`rplearn.models.auto.fit_from_statistics`): every
coefficient of the deviation, up to ``K``, ``N(0, v)`` with ``v`` such that a node's gain strays
by its unseen spread (``prior_std_db``: learned, stated, or the measured gains' spread) over the
sphere, the data's information added (one constrained inverse at ``K``). So where the flights
never looked the spread is the prior's, all degrees together; near them the degrees up to ``k``
are pinned by the data and those above by what the data say of them too (the covariance is
read about the chosen model, as the own-pattern posterior is,
:mod:`rplearn.models.own_posterior`).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from rplearn.core.basis_base import Basis
from rplearn.core.lsq.level import pattern_shape
from rplearn.core.lsq.normal_equations import NormalEquations
from rplearn.core.lsq.penalty import nested_columns
from rplearn.core.lsq.selection_evaluator import FoldEvaluator
from rplearn.core.lsq.selection_result import Selection
from rplearn.core.lsq.shifted import shifted_statistics
from rplearn.core.lsq.ties import MIN_NOISE_UNITS, WITHIN_NOISE_FRACTION, WITHIN_NOISE_SE
from rplearn.core.sh import SphericalHarmonics

#: Width of the Gaussian taper of the kept prior's degrees, as a fraction of the largest order's
#: resolution (``pi / K`` rad): each degree ``l`` times ``exp(-l (l + 1) sigma^2 / 2)``, ``sigma``
#: 3 deg at SH-15 (0.75 at its degree 14, 0.96 at degree 5). A reference cut at ``K`` rings (the
#: Gibbs oscillation) beside its sharp features; on ``ground`` the gimbal's shadow is one, where
#: the learning flights looked, and there the held-out units found the near-exact
#: reference kept untapered worse than cut, beyond noise, on seeds 1 and 2 (4.361 against 4.295,
#: 4.422 against 4.308 dB). Tapered, seed 1 is kept (4.303 against 4.295) and its planner's
#: skill rises from -0.313 / 0.132 to 0.250 / 0.453 (the oracle's 0.282 / 0.473); seed 0 alike
#: (0.369 / 0.343); seed 2 is still cut (4.344 against 4.308). A Lanczos taper (``sinc(l / K)``)
#: kept all three but smoothed away what the planner needs (skill 0.17-0.34 at q10, bins 0.15-0.25).
PRIOR_TAPER_RESOLUTION = 0.25
#: Pattern columns at the largest order up to which the prior is kept above the chosen order
#: (its covariance is one constrained inverse at that order; beyond, a large swarm, the prior is
#: cut to the chosen order as before).
MAX_KEPT_COLUMNS = 1500


@dataclass(frozen=True)
class DeviationProblem:
    """The statistics the order search reads when a prior is kept above the chosen order.

    Attributes
    ----------
    units : mapping of unit label to NormalEquations
        Every unit's statistics of ``y - X shape``.
    total : NormalEquations
        Their sum.
    shape : ndarray
        The prior's shape at the largest order, one value per pattern column.
    target : ndarray or None
        What the deviation shrinks toward: None (its shape zero, its level the data's), or with
        ``prior_level="prior"`` the prior's level (the prior less its shape).
    """

    units: Mapping[str, NormalEquations]
    total: NormalEquations
    shape: np.ndarray
    target: np.ndarray | None


def keeps_prior(kind: str, target: np.ndarray | None, big: Any, n_nodes: int) -> bool:
    """Whether the prior is kept above the chosen order: spherical harmonics (whose orders
    nest) with a prior, up to :data:`MAX_KEPT_COLUMNS` pattern columns at the largest order."""
    return target is not None and kind == "sh" and big.n_coef * n_nodes <= MAX_KEPT_COLUMNS


def deviation_problem(units: Mapping[str, NormalEquations], total: NormalEquations, target: np.ndarray,
                      prior_level: str) -> DeviationProblem:
    """The statistics of the data less the prior's shape (module docstring)."""
    basis, n_nodes = total.basis, total.n_nodes
    prior = np.asarray(target, np.float64)[:total.n_pattern_columns]
    shape = pattern_shape(prior, basis, n_nodes)
    level = prior - shape  # each node's constant: the prior's level
    assert isinstance(basis, SphericalHarmonics)  # keeps_prior: only spherical harmonics nest
    degrees = np.asarray(basis.degrees, np.float64)
    sigma = PRIOR_TAPER_RESOLUTION * np.pi / max(float(degrees.max()) + 1.0, 1.0)
    shape = shape * np.tile(np.exp(-0.5 * degrees * (degrees + 1.0) * sigma**2), n_nodes)  # the ringing tapered
    shifted = {u: shifted_statistics(st, shape) for u, st in units.items()}
    return DeviationProblem(shifted, shifted_statistics(total, shape), shape,
                            level if prior_level == "prior" else None)


def kept_prior_target(target: np.ndarray, shape: np.ndarray, basis: Basis, n_nodes: int) -> np.ndarray:
    """The prior a kept model holds: each node's level of ``target`` with the tapered ``shape``
    (:func:`deviation_problem`) in place of the prior's own shape (pattern columns only)."""
    prior = np.asarray(target, np.float64)[:n_nodes * basis.n_coef]
    return prior - pattern_shape(prior, basis, n_nodes) + np.asarray(shape, np.float64)


def kept_prior_coef(shape: np.ndarray, deviation: np.ndarray, big: Any, chosen: Any, n_nodes: int) -> np.ndarray:
    """``(n_nodes, big.n_coef)``: the prior's shape plus the deviation (of ``chosen``'s columns)."""
    out = np.array(shape, np.float64).reshape(n_nodes, big.n_coef)
    out.reshape(-1)[nested_columns(big, chosen, n_nodes)] += np.asarray(deviation, np.float64).ravel()
    return out


def held_out_errors(units: Mapping[str, NormalEquations], make_basis: Callable[[int], Basis], point: Selection,
                    ridge: float, target: np.ndarray | None, prior_level: str) -> np.ndarray:
    """Each held-out unit's squared error (summed over its samples) [dB^2] of the chosen point of
    a search, as :func:`rplearn.core.lsq.selection.select_order_and_smoothing` validated it on
    ``units`` (empty without held-out units)."""
    ev = FoldEvaluator({u: st for u, st in units.items() if st.n_samples}, make_basis, ridge, point.power,
                    target, prior_level)
    ev.rmse(int(point.order), float(point.smoothing))
    return np.asarray(ev.fold_sse.get((int(point.order), float(point.smoothing)), np.empty(0)), np.float64)


def kept_within_noise(kept: Selection, cut: Selection, kept_sse: np.ndarray, cut_sse: np.ndarray, n_samples: int) -> bool:
    """Whether the held-out units cannot tell the search with the prior kept from the search with
    it cut to the chosen order, or prefer the kept one: the rule of
    :func:`rplearn.core.lsq.ties.within_noise` (from :data:`~rplearn.core.lsq.ties.MIN_NOISE_UNITS`
    units, the paired difference within :data:`~rplearn.core.lsq.ties.WITHIN_NOISE_SE` standard
    errors and :data:`~rplearn.core.lsq.ties.WITHIN_NOISE_FRACTION` of the mean square; with fewer,
    the fraction alone, as the spread's ties take it)."""
    if kept.rmse_db <= cut.rmse_db:
        return True
    if kept_sse.size >= MIN_NOISE_UNITS and kept_sse.size == cut_sse.size:
        d = (kept_sse - cut_sse) / max(n_samples, 1)
        se = float(np.sqrt(d.size * np.var(d, ddof=1)))
        return float(d.sum()) <= min(WITHIN_NOISE_SE * se, WITHIN_NOISE_FRACTION * float(cut_sse.sum()) / max(n_samples, 1))
    return kept.rmse_db ** 2 <= (1.0 + WITHIN_NOISE_FRACTION) * cut.rmse_db ** 2


__all__ = ["MAX_KEPT_COLUMNS", "PRIOR_TAPER_RESOLUTION", "DeviationProblem", "deviation_problem", "held_out_errors", "keeps_prior",
           "kept_prior_coef", "kept_prior_target", "kept_within_noise"]
