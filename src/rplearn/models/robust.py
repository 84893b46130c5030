"""Pattern fits that resist plateaus and dropouts: the Huber loss (``fit --loss huber``).

Real signal logs carry stretches that are not the link's gain: plateaus (a driver repeating its
last RSSI for seconds, paper Fig. 6b) and dropouts (a floor value while the radio lost the
link). Least squares lets each such sample pull the pattern by its full residual. The Huber loss
(Huber 1964) is quadratic up to ``k`` robust standard deviations and linear beyond, so a sample
far from the pattern pulls only as hard as one at ``k`` sigma.

The estimate is computed by the method of pseudo-observations (Huber 1981, Sec. 7.8): starting
from the least-squares fit, each iteration clips the residuals at ``k`` times their scale (the
median absolute deviation, times 1.4826) and refits least squares to the prediction plus the
clipped residuals. The design, and so the streamed normal-equation solver, is the same at
every iteration; only the observations change. It converges to the Huber M-estimate for the
final scale. The reported covariance is the last least-squares solve's.
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd

from rplearn._argtypes import check_types
from rplearn.core.lsq.normal_equations import NormalEquations
from rplearn.core.lsq.selection import penalty_scale, penalty_vector
from rplearn.core.lsq.solver import solve
from rplearn.data.tables import LinkSamples
from rplearn.errors import InputError
from rplearn.models.fit import FittedModel, node_coverage_grids, solve_patterns
from rplearn.models.options import LOSSES, FitOptions
from rplearn.models.spec import ModelSpec, check_model_size
from rplearn.models.terms import directed_counts

#: Huber's tuning constant in robust standard deviations: 95% efficiency for Gaussian noise.
HUBER_K = 1.345
#: Iterations at most, and the change of every prediction [dB] below which they stop.
MAX_ITERATIONS = 100
TOLERANCE_DB = 0.01
#: Smallest robust scale [dB]: far below any radio's resolution.
MIN_SCALE_DB = 1e-3

@check_types
@dataclass(frozen=True)
class RobustReport:
    """What the Huber fit did.

    Attributes
    ----------
    scale_db : float
        Robust standard deviation of the residuals (1.4826 MAD) [dB].
    k : float
        Clipping point, in ``scale_db`` units.
    downweighted : ndarray of bool
        Per sample: its residual lies beyond ``k * scale_db`` (it pulls less than least
        squares would).
    iterations : int
    converged : bool
    """

    scale_db: float
    k: float
    downweighted: np.ndarray
    iterations: int
    converged: bool

    def to_dict(self) -> dict[str, Any]:
        return {"loss": "huber", "k": self.k, "scale_db": self.scale_db, "iterations": self.iterations,
                "converged": self.converged, "downweighted": int(self.downweighted.sum()),
                "n_samples": int(self.downweighted.size)}


#: The features of every sample are kept across iterations up to this many bytes (else they
#: are computed again at each iteration, through the streamed solver).
FEATURE_BYTES = 512 * 2**20


def _features_fit(n_samples: int, n_coef: int) -> bool:
    return 2 * n_samples * n_coef * 8 <= FEATURE_BYTES


class _Features:
    """Both ends' basis features of every sample, to multiply by ``X`` and ``X^T`` cheaply."""

    def __init__(self, basis: Any, directions: Any, tx: np.ndarray, rx: np.ndarray, n_nodes: int) -> None:
        self.f_tx = basis.design(directions.az_tx, directions.el_tx)  # (n, p)
        self.f_rx = basis.design(directions.az_rx, directions.el_rx)
        self.tx, self.rx, self.n_nodes, self.p = tx, rx, n_nodes, basis.n_coef

    def times(self, coef: np.ndarray) -> np.ndarray:
        """``X c``: the joint gain of every sample [dB]."""
        c = np.asarray(coef).reshape(self.n_nodes, self.p)
        rows = np.arange(self.tx.size)
        return (self.f_tx @ c.T)[rows, self.tx] + (self.f_rx @ c.T)[rows, self.rx]

    def transpose_times(self, v: np.ndarray) -> np.ndarray:
        """``X^T v``, node blocks in order."""
        out = np.zeros((self.n_nodes, self.p))
        for k in range(self.n_nodes):
            out[k] = self.f_tx.T @ np.where(self.tx == k, v, 0.0) + self.f_rx.T @ np.where(self.rx == k, v, 0.0)
        return out.ravel()


def robust_scale_db(residual_db: np.ndarray) -> float:
    """1.4826 times the median absolute deviation: the standard deviation for Gaussian noise,
    unmoved by a minority of outliers [dB]; at least :data:`MIN_SCALE_DB` (more than half the
    residuals equal, or rounding errors of noise-free data, would make it 0)."""
    r = np.asarray(residual_db, np.float64)
    return float(max(1.4826 * np.median(np.abs(r - np.median(r))), MIN_SCALE_DB))


@check_types
def fit_huber(
    samples: LinkSamples,
    spec: ModelSpec,
    options: FitOptions | None = None,
    provenance: Mapping[str, Any] | None = None,
    k: float = HUBER_K,
) -> tuple[FittedModel, RobustReport]:
    """Learn a pattern model with the Huber loss (module docstring).

    Parameters
    ----------
    samples : LinkSamples
    spec : ModelSpec
        A pattern model (sh, bg, poly) of fixed order.
    options : FitOptions, optional
        Gauge, environment term and link offsets, as :func:`rplearn.models.fit.solve_patterns`
        (a term beyond free space or link offsets: each iteration then refits in full); the
        loss is Huber whatever ``options.loss`` says.
    provenance : mapping, optional
    k : float
        Clipping point in robust standard deviations (:data:`HUBER_K`).

    Returns
    -------
    fitted : FittedModel
        LTD covers every iteration; ``training["robust"]`` holds the report's numbers.
    report : RobustReport
    """
    options = options or FitOptions()
    if not spec.decouples:
        raise InputError(f"loss huber: for pattern models (sh, bg, poly), not {spec.label}", param="loss")
    if not (np.isfinite(k) and k > 0):
        raise InputError(f"huber k: expected a positive number, got {k!r}", param="k")
    check_model_size(spec, len(samples), len(samples.nodes))
    y = np.asarray(samples.joint_gain_db, np.float64)
    t0 = time.perf_counter()
    basis, n_nodes = spec.basis(), len(samples.nodes)
    tx, rx = np.asarray(samples.tx_index), np.asarray(samples.rx_index)
    d = samples.directions
    gauge, path_loss = options.gauge, options.path_loss
    counts = directed_counts(samples)
    two_way = options.link_offsets and any((b, a) in counts for a, b in counts)
    plain = path_loss.kind == "free" and not two_way  # no shared columns: the fast pseudo-observation path
    normal = NormalEquations(basis, n_nodes).add(d, tx, rx, y)  # X^T X once: only X^T y changes
    penalty = None
    if spec.smoothing:
        penalty = penalty_vector(basis, n_nodes, spec.smoothing, penalty_scale(normal.gram))
    features = _Features(basis, d, tx, rx, n_nodes) if plain and _features_fit(len(samples), basis.n_coef) else None

    def refit(observed: np.ndarray) -> np.ndarray:
        """Least squares on ``observed`` with the same design; the new predictions."""
        if features is None:
            model, _ = solve_patterns(dataclasses.replace(samples, joint_gain_db=observed), spec, options)
            return model.predict_gain(samples)
        normal.rhs = features.transpose_times(observed)
        normal.yty = float(observed @ observed)
        coef = solve(normal, list(samples.nodes), ridge=spec.ridge_weight, gauge=gauge, penalty=penalty).coef
        return features.times(coef)

    fitted = refit(y)
    pseudo = y
    scale, converged, iterations = 0.0, False, 0
    for iterations in range(1, MAX_ITERATIONS + 1):  # noqa: B007 (the count is reported after the loop)
        residual = y - fitted
        scale = robust_scale_db(residual)
        pseudo = fitted + np.clip(residual, -k * scale, k * scale)
        new = refit(pseudo)
        change = float(np.max(np.abs(new - fitted)))
        fitted = new
        if change < TOLERANCE_DB:
            converged = True
            break
    model, report = solve_patterns(dataclasses.replace(samples, joint_gain_db=pseudo), spec, options)
    fitted = model.predict_gain(samples)
    ltd = time.perf_counter() - t0
    residual = y - fitted
    scale = robust_scale_db(residual)
    robust = RobustReport(scale, float(k), np.abs(residual) > k * scale, iterations, converged)
    model.training = model.training.replace(**{
        **report.to_dict(), "robust": robust.to_dict(), "rmse_db": float(np.sqrt(np.mean(residual**2))),
        "coverage_deg": node_coverage_grids(samples), "ltd_s": ltd,
    })
    model.provenance = {**dict(provenance or {}), "model": spec.label, "loss": "huber"}
    return FittedModel(spec, model, ltd), robust


def downweighted_notes(part: Any, robust: Any, stretches: int = 3) -> list[str]:
    """Where a Huber fit down-weighted samples: how many, by unit, and the longest stretches
    of consecutive down-weighted packets (plateaus and dropouts look like that)."""
    mask = np.asarray(robust.downweighted, bool)
    n = mask.size
    lines = [f"huber: {int(mask.sum()):,} of {n:,} samples ({100.0 * mask.mean():.1f}%) lie beyond "
             f"{robust.k:g} x {robust.scale_db:.2f} dB and pull less than least squares would "
             f"({robust.iterations} iterations{'' if robust.converged else ', not converged'})"]
    if not mask.any():
        return lines
    units = part["unit"].astype(str).to_numpy() if "unit" in part.columns else np.full(n, "all")
    t = part["t"].to_numpy(np.float64)
    counts = pd.Series(units[mask]).value_counts()
    lines.append("  by unit: " + ", ".join(f"{u} {c:,}" for u, c in counts.items()))
    order = np.lexsort((t, units))
    m, u, tt = mask[order], units[order], t[order]
    starts = np.flatnonzero(m & ~np.r_[False, m[:-1] & (u[1:] == u[:-1])])
    runs = []
    for s in starts:
        e = s
        while e + 1 < n and m[e + 1] and u[e + 1] == u[s]:
            e += 1
        runs.append((e - s + 1, u[s], tt[s], tt[e]))
    runs.sort(key=lambda r: -r[0])
    lines.append("  longest stretches: " + ", ".join(f"{c:,} samples in {un} at {a:.1f}-{b:.1f} s" for c, un, a, b in runs[:stretches]))
    return lines


__all__ = ["HUBER_K", "LOSSES", "MAX_ITERATIONS", "TOLERANCE_DB", "RobustReport", "downweighted_notes", "fit_huber", "robust_scale_db"]
