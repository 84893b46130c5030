"""The continuous optimal design over the candidate manoeuvres: a bound on any plan made of them.

From a posterior (:class:`~rplearn.analysis.manoeuvre_posterior.ManoeuvrePosterior`) and the
candidates the ranking offers from the current poses, each candidate ``i`` flown for ``t_i``
seconds adds ``t_i J_i`` to the precision (``J_i = w F_i^T F_i / (sigma^2 d_i)``: its feature rows
at ``w`` packets each, per second of its own duration ``d_i``) and, with a drifting error,
``t_i Q_i`` to the drift's middle factor (``Q_i``: its time blocks' sums, per second). The
covariance is then ``S + S W S`` with ``S = (P_0 + sum t_i J_i)^-1`` and
``W = W_0 + sum t_i Q_i`` (``W_0 = P_0 D_0 D_0^T P_0``: the drift factor so far, mapped back
through the current precision), and node ``k``'s spread is ``sqrt(tr(M_k Cov_kk))``.

:func:`optimal_design` chooses nonnegative times ``t_i`` of least total ``T = sum t_i`` such that
every node's spread is at most the target, ignoring the way between the manoeuvres and their
order: no plan made of these candidates (flown from these poses) reaches the target sooner
than the white-noise design (``drift=False``: convex in ``t``, so its optimum is a bound; the
drifting part adds variance, so it can only need more time). With the drift the criterion is
not convex everywhere and the design found is an estimate, not a bound.

The algorithm: the proportions ``t / T`` on the simplex, pairwise Frank-Wolfe steps (weight
moved from the worst candidate in the design to the best, by the gradient of the largest
node's variance over the target's square, smoothed by a log-sum-exp of sharpness ``BETA`` that
is never above the largest), and
after each step ``T`` solved again so that the smoothed criterion equals 1 (secant in log-log).
At the fixed point the proportions minimise the criterion at that ``T`` and it is 1 there, so
no design of a smaller total reaches the target. The Frank-Wolfe gap printed beside the result
measures how far from that point the iterations stopped.

:func:`end_gradient_scores` is a ranking that looks at the end of the flight: each candidate's
first-order reduction of that criterion at the *anticipated final* posterior (the current one
plus the optimal remaining design), per second of its flight including the way to its start
(:attr:`rplearn.analysis.manoeuvres.ManoeuvreOptions.design`).

Measured (``benchmarks/manoeuvres.py --bound``, its docstring has the table): the white-noise
bound is 0.01-0.18x of the reference flight's time in every cell (the drifting error, not the
white information, is what the flights wait for); with the drift the design found is local (in
three of twelve cells slower than the greedy plan under the same model), and neither ranking
above beat the rate ranking flown.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from rplearn.analysis.manoeuvre_posterior import ManoeuvrePosterior
from rplearn.core.lsq.products import spd_inverse
from rplearn.errors import InputError

#: Sharpness of the smooth maximum over the nodes (the criterion is at most log(K) / BETA below the largest,
#: never above it: a design that brings it to 1 takes no more time than one that brings the largest there).
BETA = 50.0


@dataclass(frozen=True)
class DesignProblem:
    """The design problem from one posterior (module docstring).

    Attributes
    ----------
    precision : ndarray
        ``P_0`` over the pattern columns.
    drift_middle : ndarray
        ``W_0`` (zeros without a drifting error).
    metrics : list of ndarray
        Per node, ``M_k`` over its block of ``p`` columns.
    information, drift_information : ndarray
        ``J_i`` and ``Q_i`` per second, shape ``(m, n, n)`` (the second all zeros without drift).
    durations_s, leads_s : ndarray
        Each candidate's own duration and the time to reach its start [s].
    target_var : float
        The target spread squared [dB^2].
    beta : float
        Sharpness of the smooth maximum over the nodes.
    """

    precision: np.ndarray
    drift_middle: np.ndarray
    metrics: list[np.ndarray]
    information: np.ndarray
    drift_information: np.ndarray
    durations_s: np.ndarray
    leads_s: np.ndarray
    target_var: float
    beta: float = BETA


@dataclass(frozen=True)
class Design:
    """An optimal design: seconds per candidate, their total, the spreads it leaves, its gap.

    ``certified_s``: a total below which no design reaches the target, from the Frank-Wolfe gap at
    the design's proportions (exact for the white-noise problem, which is convex; 0: none
    certified).
    """

    times_s: np.ndarray
    total_s: float
    spreads_db: np.ndarray
    gap: float
    iterations: int
    certified_s: float = 0.0


def design_problem(post: ManoeuvrePosterior, rows: Sequence[np.ndarray], durations_s: Sequence[float],
                   leads_s: Sequence[float], weight: float, target_db: float, drift: bool = True) -> DesignProblem:
    """The problem from ``post`` and the candidates' feature rows (``weight`` packets per row),
    own durations and leads; ``drift=False``: the white-noise posterior only (a bound)."""
    if not (np.isfinite(target_db) and target_db > 0):
        raise InputError(f"target_db: expected a positive spread [dB], got {target_db!r}", param="target_db")
    if not len(rows) or len(rows) != len(durations_s) or len(rows) != len(leads_s):
        raise InputError(f"rows: {len(rows)} candidates for {len(durations_s)} durations and {len(leads_s)} leads", param="rows")
    n = post.cov.shape[0]
    precision = spd_inverse(post.cov)
    with_drift = drift and post.drift_scale > 0
    k0 = precision @ post.drift if drift and post.drift.shape[1] else np.zeros((n, 0))
    info = np.zeros((len(rows), n, n))
    dinfo = np.zeros((len(rows), n, n))
    dur = np.asarray(durations_s, np.float64)
    for i, f in enumerate(rows):
        f = np.asarray(f, np.float64)
        info[i] = (weight / post.noise_var / dur[i]) * (f.T @ f)
        if with_drift and f.shape[0]:
            u = post.drift_scale * weight * np.add.reduceat(f, np.arange(0, f.shape[0], post.block_rows), axis=0).T
            dinfo[i] = (u @ u.T) / dur[i]
    return DesignProblem(precision, k0 @ k0.T, list(post.metrics), info, dinfo, dur, np.asarray(leads_s, np.float64),
                         float(target_db) ** 2)


def _state(problem: DesignProblem, times_s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``S`` and ``W`` at the times ``times_s``."""
    on = np.flatnonzero(times_s)  # the candidates flown only
    p = problem.precision + np.tensordot(times_s[on], problem.information[on], axes=1)
    w = problem.drift_middle + np.tensordot(times_s[on], problem.drift_information[on], axes=1)
    return spd_inverse(p), w


def node_variances(problem: DesignProblem, times_s: np.ndarray) -> np.ndarray:
    """Each node's spread squared after flying candidate ``i`` for ``times_s[i]`` [dB^2]."""
    return _variances(problem, *_state(problem, np.asarray(times_s, np.float64)))


def _variances(problem: DesignProblem, s: np.ndarray, w: np.ndarray) -> np.ndarray:
    p = problem.metrics[0].shape[0]
    out = []
    for k, m in enumerate(problem.metrics):
        sb = s[:, k * p:(k + 1) * p]
        out.append(float(np.sum(m * sb[k * p:(k + 1) * p])) + float(np.sum(m * (sb.T @ w @ sb))))
    return np.maximum(np.array(out), 0.0)


def _criterion(variances: np.ndarray, target_var: float, beta: float) -> tuple[float, np.ndarray]:
    """The smooth maximum of the variances over the target's square (never above the largest,
    at most ``log(K) / BETA`` below it), and its softmax weights."""
    z = beta * variances / target_var
    top = float(np.max(z))
    e = np.exp(z - top)
    return (top + float(np.log(np.sum(e) / z.size))) / beta, e / np.sum(e)


def criterion(problem: DesignProblem, times_s: np.ndarray) -> float:
    """The smoothed largest node variance over the target's square (1: the target reached or nearly)."""
    return _criterion(node_variances(problem, times_s), problem.target_var, problem.beta)[0]


def criterion_gradient(problem: DesignProblem, times_s: np.ndarray) -> tuple[float, np.ndarray]:
    """The criterion and its gradient in the candidates' times [1/s]."""
    t = np.asarray(times_s, np.float64)
    s, w = _state(problem, t)
    value, pi = _criterion(_variances(problem, s, w), problem.target_var, problem.beta)
    p = problem.metrics[0].shape[0]
    n = s.shape[0]
    g1 = np.zeros((n, n))  # sum_k pi_k S M_k S / T^2 (M_k on node k's block)
    for k, m in enumerate(problem.metrics):
        sb = s[:, k * p:(k + 1) * p]
        g1 += (pi[k] / problem.target_var) * (sb @ m @ sb.T)
    if np.any(w):
        grad = -(problem.information.reshape(t.size, n * n) @ (g1 + 2.0 * (g1 @ w @ s)).ravel())
        grad += problem.drift_information.reshape(t.size, n * n) @ g1.ravel()
    else:
        grad = -(problem.information.reshape(t.size, n * n) @ g1.ravel())
    return value, grad


def _total_for(problem: DesignProblem, share: np.ndarray, total_s: float, max_s: float) -> float:
    """The total ``T`` at which the criterion of ``T * share`` is 1 (secant in log-log); ``inf``
    if it stays above 1 up to ``max_s``."""
    t0 = max(total_s, 1e-3)
    h0 = criterion(problem, t0 * share)
    t1 = t0 * min(max(h0, 0.5), 2.0)
    for _ in range(40):
        h1 = criterion(problem, t1 * share)
        if abs(h1 - 1.0) < 1e-6:
            break
        if h1 == h0 or not np.isfinite(h1):
            t2 = t1 * h1
        else:
            slope = (np.log(h1) - np.log(h0)) / (np.log(t1) - np.log(t0))
            t2 = t1 * float(np.exp(np.clip(-np.log(h1) / slope, -3.0, 3.0))) if slope < -1e-6 else t1 * 2.0
        t0, h0 = t1, h1
        t1 = float(np.clip(t2, t1 / 4.0, t1 * 4.0))
        if t1 > max_s:
            return float("inf") if criterion(problem, max_s * share) > 1.0 else _bisect(problem, share, t0, max_s)
    return float(t1)


def _bisect(problem: DesignProblem, share: np.ndarray, lo: float, hi: float) -> float:
    for _ in range(50):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if criterion(problem, mid * share) > 1.0 else (lo, mid)
    return hi


def _line(problem: DesignProblem, share: np.ndarray, direction: np.ndarray, top: float, total_s: float) -> float:
    """The step in ``[0, top]`` along ``direction`` minimising the criterion at ``total_s`` (golden section)."""
    lo, hi = 0.0, top
    g = 0.5 * (np.sqrt(5.0) - 1.0)
    a, b = hi - g * (hi - lo), lo + g * (hi - lo)
    fa, fb = (criterion(problem, total_s * (share + x * direction)) for x in (a, b))
    for _ in range(10):
        if fa <= fb:
            hi, b, fb = b, a, fa
            a = hi - g * (hi - lo)
            fa = criterion(problem, total_s * (share + a * direction))
        else:
            lo, a, fa = a, b, fb
            b = lo + g * (hi - lo)
            fb = criterion(problem, total_s * (share + b * direction))
    return 0.5 * (lo + hi)


def optimal_design(problem: DesignProblem, max_iter: int = 80, gap_tol: float = 1e-4,
                   max_total_s: float = 1e5, start: np.ndarray | None = None, multiplicative: int = 40) -> Design:
    """The least total flight time whose best split over the candidates reaches the target
    (module docstring); ``start``: proportions to start from (a previous design's), else uniform.
    A target no design reaches within ``max_total_s`` gives ``total_s = inf``."""
    m = problem.durations_s.size
    if criterion(problem, np.zeros(m)) <= 1.0:
        return Design(np.zeros(m), 0.0, np.sqrt(node_variances(problem, np.zeros(m))), 0.0, 0)
    share = np.full(m, 1.0 / m) if start is None or not np.sum(start) > 0 else np.asarray(start, np.float64) / np.sum(start)
    total = _total_for(problem, share, 100.0, max_total_s)
    if not np.isfinite(total) and start is not None:
        share = np.full(m, 1.0 / m)
        total = _total_for(problem, share, 100.0, max_total_s)
    if not np.isfinite(total):
        return Design(np.full(m, np.inf), float("inf"), np.sqrt(node_variances(problem, max_total_s * share)), float("inf"), 0)
    gap, it = float("inf"), 0
    final = problem
    for it in range(1, max_iter + 1):
        # continuation: a smoother maximum first (faster steps), the final sharpness for the last half
        problem = replace(final, beta=final.beta * min(1.0, 0.1 + 0.9 * it / max(max_iter // 2, 1)))
        if it == max_iter // 2 + 1:
            total = _total_for(problem, share, total, max_total_s)
        _, grad = criterion_gradient(problem, total * share)
        grad = grad * total  # per unit of share
        best = int(np.argmin(grad))
        support = np.flatnonzero(share > 0)
        worst = int(support[np.argmax(grad[support])])
        gap = float(grad @ share - grad[best])
        if gap <= gap_tol or best == worst:
            break
        if it <= multiplicative:  # every weight at once, by its share of the criterion's reduction
            new = share * np.sqrt(np.maximum(-grad, 0.0))
            new[new < 1e-12 * np.max(new)] = 0.0
        else:  # pairwise: weight from the worst candidate in the design to the best
            direction = np.zeros(m)
            direction[best], direction[worst] = 1.0, -1.0
            new = share + _line(problem, share, direction, float(share[worst]), total) * direction
            new[new < 1e-12] = 0.0
        if not np.sum(new) > 0:
            break
        new /= np.sum(new)
        again = _total_for(problem, new, total, max_total_s)
        if np.isfinite(again):  # a step that leaves a node untaught is not taken
            share, total = new, again
        elif it > multiplicative:
            break
    problem = final
    total = _total_for(problem, share, total, max_total_s) if np.isfinite(total) else total
    times = total * share
    return Design(times, float(total), np.sqrt(node_variances(problem, times)), gap, it, _certified(problem, share, total))


def _certified(problem: DesignProblem, share: np.ndarray, total_s: float) -> float:
    """The largest of a few totals below ``total_s`` at which even the best proportions leave the
    criterion above 1: ``h(T w) - gap(T w) > 1`` (convexity: the best is at least that)."""
    for factor in (0.995, 0.99, 0.98, 0.95, 0.9, 0.8, 0.6):
        value, grad = criterion_gradient(problem, factor * total_s * share)
        grad = grad * factor * total_s
        if value - float(grad @ share - np.min(grad)) > 1.0:
            return factor * total_s
    return 0.0


def end_gradient_scores(problem: DesignProblem, design: Design) -> np.ndarray:
    """Each candidate's reduction of the criterion at the anticipated final posterior (the
    current one plus ``design``) if flown whole, per second of its flight with its lead [1/s]."""
    times = design.times_s if np.isfinite(design.total_s) else np.zeros(problem.durations_s.size)
    _, grad = criterion_gradient(problem, times)
    return -grad * problem.durations_s / (problem.durations_s + problem.leads_s)


def scored_design(post: ManoeuvrePosterior, scored: Sequence[Any], weight: float, target_db: float,
                  drift: bool = True, max_iter: int = 80) -> tuple[DesignProblem, Design]:
    """:func:`design_problem` and :func:`optimal_design` (``max_iter`` steps, half of them
    multiplicative) over scored candidates (``(ranked, (rows, ends))``)."""
    rows = [r for _, (r, _) in scored]
    durations = [float(c.candidate.unit.duration_s) for c, _ in scored]
    leads = [float(c.candidate.lead_s) for c, _ in scored]
    problem = design_problem(post, rows, durations, leads, weight, target_db, drift)
    return problem, optimal_design(problem, max_iter=max_iter, multiplicative=max_iter // 2)


#: For ``design_order(..., "support")``: the share of its duration the optimal design must fly a candidate
#: for, as a fraction of the largest such share among the candidates.
SUPPORT_FRACTION = 0.25


def design_order(post: ManoeuvrePosterior, scored: Sequence[Any], weight: float, target_db: float, mode: str,
                 max_iter: int = 30) -> list[Any]:
    """``scored`` (best rate first) reordered by the optimal remaining design from ``post``:
    ``"end"``, by :func:`end_gradient_scores` (the criterion's reduction per second at the
    anticipated final posterior); ``"support"``, first the candidates the design flies for a
    share of their duration at least ``SUPPORT_FRACTION`` times the largest share, each group in
    rate order."""
    problem, design = scored_design(post, scored, weight, target_db, max_iter=max_iter)
    if mode == "end":
        scores = end_gradient_scores(problem, design)
        return [scored[k] for k in sorted(range(len(scored)), key=lambda k: (-scores[k], k))]
    if mode != "support":
        raise InputError(f"mode: expected 'end' or 'support', got {mode!r}", param="mode")
    times = design.times_s if np.isfinite(design.total_s) else np.zeros(len(scored))
    share = times / problem.durations_s
    wanted = (share >= SUPPORT_FRACTION * np.max(share)) & (share > 0)
    return [s for k, s in enumerate(scored) if wanted[k]] + [s for k, s in enumerate(scored) if not wanted[k]]


__all__ = ["BETA", "Design", "DesignProblem", "SUPPORT_FRACTION", "criterion", "criterion_gradient", "design_order", "design_problem", "end_gradient_scores",
           "node_variances", "optimal_design", "scored_design"]
