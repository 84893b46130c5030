"""Fitting and evaluating models on matched datasets: the library behind ``rplearn fit/evaluate``.

A model is named by a :class:`ModelSpec` (``"sh-10"``, ``"bg-7"``, ``"p-12"``, ``"nn-400"``, ``"m"``).
:func:`fit_model` learns it from :class:`~rplearn.data.tables.LinkSamples` and times the learning
(the paper's LTD); :func:`evaluate_models` scores models on held-out samples (Table I).
"""

from __future__ import annotations

import re
import time
from dataclasses import dataclass
from typing import Any, Mapping, Sequence, Union

import numpy as np
import pandas as pd

from rplearn.core.bases import make_basis
from rplearn.models.baselines import KNNModel, MeanModel
from rplearn.data.tables import LinkSamples, link_samples
from rplearn.errors import InputError
from rplearn.core.metrics import Scores, score
from rplearn.models.patterns import PatternSet
from rplearn.core.solver import DEFAULT_RIDGE, fit_joint

Model = Union[PatternSet, MeanModel, KNNModel]

MODEL_KINDS = ("sh", "bg", "poly", "mean", "knn")
_DEFAULT_ORDER = {"sh": 10, "bg": 7, "poly": 12, "knn": 400}
_ALIASES = {"m": "mean", "p": "poly", "nn": "knn", "bucketized": "bg"}


#: Default ridge per family (see :data:`rplearn.core.solver.DEFAULT_RIDGE`; the paper used 50).
DEFAULT_RIDGE_BY_KIND = {"sh": DEFAULT_RIDGE, "poly": DEFAULT_RIDGE, "bg": DEFAULT_RIDGE, "mean": 0.0, "knn": 0.0}


def default_ridge(kind: str) -> float:
    """Default ridge weight of a model family (see :data:`DEFAULT_RIDGE_BY_KIND`)."""
    return DEFAULT_RIDGE_BY_KIND.get(kind, DEFAULT_RIDGE)


@dataclass(frozen=True)
class ModelSpec:
    """A model family and its hyper-parameters.

    Attributes
    ----------
    kind : {"sh", "bg", "poly", "mean", "knn"}
    order : int or None
        SH-L, BG-k, P-k order, or k of NN-k.
    ridge : float or None
        Ridge weight of the pattern models; None picks :func:`default_ridge` of the kind.
    sigma_rad2 : float
        BG kernel variance [rad^2].
    grid : {"paper", "fibonacci"}
        BG node layout.
    """

    kind: str
    order: int | None = None
    ridge: float | None = None
    sigma_rad2: float = 0.5
    grid: str = "paper"

    def __post_init__(self) -> None:
        if self.ridge is None:
            object.__setattr__(self, "ridge", default_ridge(self.kind))
        if not (np.isfinite(self.ridge) and self.ridge >= 0):
            raise InputError(f"ridge must be a non-negative number, got {self.ridge!r}")
        if self.kind != "mean" and (self.order is None or int(self.order) < 1):
            raise InputError(f"model {self.kind}: order must be a positive integer, got {self.order!r}")

    @classmethod
    def parse(cls, text: str, **options: Any) -> "ModelSpec":
        """Parse ``"sh-10"``, ``"SH10"``, ``"bg-7"``, ``"p-12"``, ``"nn-400"``, ``"m"``, ``"knn"``..."""
        m = re.fullmatch(r"\s*([a-zA-Z]+)[-_ ]?(\d+)?\s*", str(text))
        if not m:
            raise InputError(f"unknown model {text!r}; expected one of sh, bg, poly, mean, knn (e.g. sh-10, nn-400)")
        kind = _ALIASES.get(m.group(1).lower(), m.group(1).lower())
        if kind not in MODEL_KINDS:
            raise InputError(f"unknown model {text!r}; expected one of {', '.join(MODEL_KINDS)} (e.g. sh-10, nn-400)")
        order = int(m.group(2)) if m.group(2) else options.pop("order", None)
        options.pop("order", None)
        if kind != "mean" and order is None:
            order = _DEFAULT_ORDER[kind]
        return cls(kind, None if kind == "mean" else int(order), **{k: v for k, v in options.items() if v is not None})

    @property
    def label(self) -> str:
        """The paper's label: M, NN-400, SH-10, P-12, BG-7."""
        return {"mean": "M", "knn": f"NN-{self.order}", "sh": f"SH-{self.order}", "poly": f"P-{self.order}", "bg": f"BG-{self.order}"}[self.kind]

    @property
    def decouples(self) -> bool:
        return self.kind in ("sh", "bg", "poly")

    def basis(self):
        if self.kind == "bg":
            return make_basis("bg", self.order, sigma_rad2=self.sigma_rad2, grid=self.grid)
        return make_basis(self.kind, self.order)


@dataclass
class FittedModel:
    """A learned model, its spec and its learning wall time (LTD) [s]."""

    spec: ModelSpec
    model: Model
    ltd_s: float

    @property
    def label(self) -> str:
        return self.model.label

    @property
    def n_params(self) -> int:
        return self.model.n_params

    @classmethod
    def from_model(cls, model: Model) -> "FittedModel":
        """Wrap a loaded model; its LTD comes from its training summary (NaN if absent)."""
        ltd = model.training.get("ltd_s")
        spec = ModelSpec.parse(model.label)
        return cls(spec, model, float("nan") if ltd is None else float(ltd))

    @property
    def condition_number(self) -> float:
        if isinstance(self.model, PatternSet):
            return float(self.model.training.get("condition_number") or np.nan)
        return float("nan")


def select_units(df: pd.DataFrame, units: Sequence[str] | None, source: str = "dataset") -> pd.DataFrame:
    """Rows whose ``unit`` label is among ``units`` (all rows when ``units`` is None)."""
    if not units:
        return df
    if "unit" not in df.columns:
        raise InputError(f"{source}: --units needs a 'unit' column, which this dataset lacks")
    wanted = [str(u) for u in units]
    known = sorted(df["unit"].astype(str).unique())
    unknown = [u for u in wanted if u not in known]
    if unknown:
        raise InputError(f"{source}: unknown unit(s) {', '.join(unknown)}; the dataset has {', '.join(known)}")
    return df[df["unit"].astype(str).isin(wanted)]


def fit_patterns(
    samples: LinkSamples, spec: ModelSpec, gauge: str | Mapping[str, Any] = "equal-mean", provenance: Mapping[str, Any] | None = None
) -> PatternSet:
    """Learn one pattern per node of the samples (paper Sec. IV-B, V-A)."""
    basis = spec.basis()
    sol = fit_joint(
        samples.directions,
        samples.tx_index,
        samples.rx_index,
        samples.joint_gain_db,
        len(samples.nodes),
        basis,
        node_names=samples.nodes,
        ridge=spec.ridge,
        gauge=gauge,
    )
    training = sol.report.to_dict()
    if samples.frequency_hz is not None:
        training["frequency_hz"] = float(np.median(samples.frequency_hz))
    return PatternSet(
        basis=basis,
        nodes=samples.nodes,
        coef=sol.coef,
        covariance=sol.covariance,
        gauge=[g.to_dict() for g in sol.report.gauges],
        training=training,
        provenance=dict(provenance or {}),
    )


def _warm_up(spec: ModelSpec, n_samples: int = 1) -> None:
    """Pay a model's one-off costs: imports, cached basis tables, the solver's block buffer
    (see :func:`fit_model`)."""
    if spec.kind == "knn":
        import sklearn.neighbors  # noqa: F401
    elif spec.decouples:
        from rplearn.core.solver import reserve_block_buffer

        basis = spec.basis()
        basis.evaluate(np.zeros(basis.n_coef), [0.0], [0.0])
        if basis.moment_shape is not None:
            basis.gram_from_moments(np.zeros(basis.moment_shape))
        reserve_block_buffer(basis, n_samples)


def fit_model(
    samples: LinkSamples,
    spec: ModelSpec,
    gauge: str | Mapping[str, Any] = "equal-mean",
    provenance: Mapping[str, Any] | None = None,
) -> FittedModel:
    """Learn a model of any kind and time it with ``time.perf_counter`` (the paper's LTD).

    One-off costs of the process (imports, the tables of a basis) are paid before the clock
    starts, so that the LTD of a model does not depend on whether it was the first one learned.
    """
    _warm_up(spec, len(samples))
    t0 = time.perf_counter()
    if spec.kind == "mean":
        model: Model = MeanModel.fit(samples)
    elif spec.kind == "knn":
        model = KNNModel.fit(samples, int(spec.order))
    else:
        model = fit_patterns(samples, spec, gauge)
    ltd = time.perf_counter() - t0
    model.provenance = {**dict(provenance or {}), "model": spec.label}
    model.training["ltd_s"] = ltd
    return FittedModel(spec, model, ltd)


def evaluate_models(fitted: Sequence[FittedModel], samples: LinkSamples) -> list[Scores]:
    """Table I: RMSE, MAE, Q95, |phi|, AIC, LTD and condition number of every model."""
    rows = []
    for f in fitted:
        pred = f.model.predict_samples(samples)
        rows.append(score(f.label, samples.joint_gain_db, pred, f.n_params, f.ltd_s, f.condition_number))
    return rows


def scores_markdown(rows: Sequence[Scores], extra: Mapping[str, Mapping[str, float]] | None = None) -> str:
    """Table I as Markdown (AIC in thousands, as the paper prints it)."""
    extra = extra or {}
    extra_cols = sorted({k for v in extra.values() for k in v})
    head = "| Method | RMSE/dB | MAE/dB | abs(phi) | AIC/1e3 | LTD/s | Q95/dB | cond |" + "".join(f" {c} |" for c in extra_cols)
    sep = "|---|---:|---:|---:|---:|---:|---:|---:|" + "---:|" * len(extra_cols)
    lines = [head, sep]
    for r in rows:
        cond = "" if not np.isfinite(r.condition_number) else f"{r.condition_number:.2f}"
        cells = [
            r.model,
            f"{r.rmse_db:.2f}",
            f"{r.mae_db:.2f}",
            f"{r.n_params:,}",
            f"{r.aic / 1e3:.2f}",
            f"{r.ltd_s:.4f}",
            f"{r.q95_db:.2f}",
            cond,
        ]
        for c in extra_cols:
            v = extra.get(r.model, {}).get(c)
            cells.append("" if v is None or not np.isfinite(v) else f"{v:.2f}")
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def samples_of(df: pd.DataFrame, units: Sequence[str] | None = None, source: str = "dataset", nodes: Sequence[str] | None = None) -> LinkSamples:
    """Learning-ready samples of the chosen units of a matched dataset."""
    part = select_units(df, units, source)
    if len(part) == 0:
        raise InputError(f"{source}: no samples selected")
    return link_samples(part, source, nodes=nodes)
