"""Fitting and evaluating models on matched datasets: the library behind ``rplearn fit/evaluate``.

A model is named by a :class:`ModelSpec` (``"sh-10"``, ``"bg-7"``, ``"p-12"``, ``"nn-400"``, ``"m"``).
:func:`fit_model` learns it from :class:`~rplearn.data.tables.LinkSamples` and times the learning
(the paper's LTD); :func:`evaluate_models` scores models on held-out samples (Table I).
"""

from __future__ import annotations

import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from rplearn._argtypes import check_types
from rplearn.core.basis_base import Basis
from rplearn.core.lsq.solver import FitReport, JointFitOptions, JointSolution, fit_joint
from rplearn.core.metrics import Scores, score
from rplearn.core.threads import blas_threads_for, is_small_fit, one_blas_thread, thread_override
from rplearn.core.threads import warm_up as warm_up_blas
from rplearn.data.tables import LinkSamples
from rplearn.errors import InputError
from rplearn.models.base import Model, learned_frequency_hz
from rplearn.models.baselines import KNNModel, MeanModel
from rplearn.models.node_coverage import PARALLEL_COVERAGE_DIRECTIONS, CoverageWork, node_coverage_grids  # noqa: F401  (their old home)
from rplearn.models.options import FitOptions
from rplearn.models.patterns import PatternSet
from rplearn.models.spec import ModelSpec, check_model_size
from rplearn.models.terms import directed_counts, regression_inputs, shared_fields
from rplearn.models.training import TrainingSummary


@dataclass(frozen=True)
class LearningGram:
    """``X^T X`` of a fit's learning design, kept by an automatic fit (it accumulated it for the
    selection), so that the decoupling certificate's joint metric is read off it instead of
    the samples being read again, and is there too when they were streamed.

    Attributes
    ----------
    basis : Basis
        The basis of ``gram``'s pattern columns (the largest candidate order).
    n_nodes : int
        Node blocks of ``basis`` in ``gram``.
    gram : ndarray
        The pattern columns first (``n_nodes * basis.n_coef``), any shared columns after
        (not read); not copied from the fit's statistics.
    n_samples : int
        Samples summed in ``gram``.
    """

    basis: Basis
    n_nodes: int
    gram: np.ndarray
    n_samples: int

    def at(self, basis: Basis) -> np.ndarray:
        """The pattern columns' block of ``gram`` at ``basis`` (a nested basis of :attr:`basis`)."""
        from rplearn.core.lsq.penalty import nested_columns

        if basis == self.basis:
            pat = basis.n_coef * self.n_nodes
            return np.asarray(self.gram[:pat, :pat])
        idx = nested_columns(self.basis, basis, self.n_nodes)
        return np.asarray(self.gram[np.ix_(idx, idx)])


@check_types
@dataclass
class FittedModel:
    """A learned model, its spec and its learning wall time (LTD) [s].

    ``own_posterior`` (automatic fits): the posterior of each node's own pattern, continued to
    the largest candidate order (:mod:`rplearn.models.own_posterior`), which the decoupling
    certificate reads; not saved with the model (the certificate it gives is).
    ``learning_gram`` (automatic fits): the learning design's ``X^T X`` (:class:`LearningGram`),
    for the certificate; not saved either.
    ``phases_s`` (automatic fits in memory, :func:`rplearn.models.auto.fit_auto`): the wall time
    [s] of its phases, ``accumulation`` (the units' statistics), ``selection`` (the search, with
    the final solve run beside its last step), ``closing`` (the covariance, spreads, drift and own
    posteriors after it) and ``coverage`` (waiting for the coverage grids); not saved.
    """

    spec: ModelSpec
    model: Model
    ltd_s: float
    own_posterior: Any = None
    learning_gram: LearningGram | None = None
    phases_s: dict[str, float] | None = None

    @property
    def label(self) -> str:
        return self.model.label

    @property
    def n_params(self) -> int:
        return self.model.n_params

    @classmethod
    def from_model(cls, model: Model) -> FittedModel:
        """Wrap a loaded model; its LTD comes from its training summary (NaN if absent)."""
        ltd = model.training.ltd_s
        spec = ModelSpec.parse(model.label)
        return cls(spec, model, float("nan") if ltd is None else float(ltd))

    @property
    def condition_number(self) -> float:
        """Condition number of the fit's normal equations (NaN for the baselines, which have none)."""
        return float(self.model.training.condition_number or np.nan)


@check_types
def solve_patterns(
    samples: LinkSamples, spec: ModelSpec, options: FitOptions | None = None,
) -> tuple[PatternSet, FitReport]:
    """Learn one pattern per node of the samples (paper Sec. IV-B, V-A), with the solver's report.

    The one code path from a :class:`ModelSpec` to patterns: the basis of the spec, the joint
    least-squares solve, the training summary (with the samples' carrier frequency, when known).
    :func:`fit_patterns` and :class:`rplearn.models.estimators.PatternRegressor` both use it.

    ``options`` (:class:`FitOptions`, default: its defaults) gives the gauge, the environment
    term (:mod:`rplearn.models.terms`) and whether one electronics offset is learned per link
    logged in both directions.

    Returns
    -------
    patterns : PatternSet
        Without provenance.
    report : FitReport
        Rank, null-space dimension, condition number, gauge notes.
    """
    options = options or FitOptions()
    basis = spec.basis()
    y, env = regression_inputs(samples, options)
    sol = fit_joint(
        samples.directions,
        samples.tx_index,
        samples.rx_index,
        y,
        len(samples.nodes),
        basis,
        samples.nodes,
        JointFitOptions(ridge=spec.ridge_weight, gauge=options.gauge, smoothing=spec.smoothing, environment=env,
                        link_offsets=options.link_offsets),
    )
    frequency_hz = learned_frequency_hz(samples)
    entries = {} if frequency_hz is None else {"frequency_hz": frequency_hz}
    patterns = pattern_set_of_solution(sol, spec, basis, samples.nodes, options, directed_counts(samples), entries)
    return patterns, sol.report


def pattern_set_of_solution(
    sol: JointSolution, spec: ModelSpec, basis: Basis, nodes: Sequence[str], options: FitOptions,
    counts: Mapping[tuple[str, str], int], entries: Mapping[str, Any],
) -> PatternSet:
    """The patterns a joint solution gives (:func:`solve_patterns`, and the same from streamed
    statistics).

    Parameters
    ----------
    sol : JointSolution
        The solver's result for ``nodes`` in ``basis``, fitted with ``options``.
    spec : ModelSpec
        Its smoothing is recorded in the training summary when not 0.
    basis : Basis
    nodes : sequence of str
    options : FitOptions
        The link terms learned beside the patterns (:func:`~rplearn.models.terms.shared_fields`).
    counts : mapping of (tx, rx) to int
        Samples per directed link.
    entries : mapping
        Further training-summary entries, written last in their order (``coverage_deg``,
        ``frequency_hz``).

    Returns
    -------
    PatternSet
        Coefficients, covariance and gauge of ``sol``; a training summary of the solver's report,
        the link terms, the smoothing and ``entries``; no provenance.
    """
    fields, terms = shared_fields(sol, nodes, options, counts)
    training = sol.report.to_dict()
    training.update(terms)
    if spec.smoothing:
        training["smoothing"] = spec.smoothing
    training.update(entries)
    return PatternSet(
        basis=basis, nodes=tuple(nodes), coef=sol.coef, covariance=sol.covariance,
        gauge=[g.to_dict() for g in sol.report.gauges], training=TrainingSummary.from_dict(training), **fields,
    )


@check_types
def fit_patterns(
    samples: LinkSamples, spec: ModelSpec, options: FitOptions | None = None,
    provenance: Mapping[str, Any] | None = None,
) -> PatternSet:
    """Learn one pattern per node of the samples (paper Sec. IV-B, V-A); see :func:`solve_patterns`."""
    patterns, _ = solve_patterns(samples, spec, options)
    patterns.provenance = dict(provenance or {})
    return patterns


#: Bases whose one-off tables :func:`_warm_up` has built in this process.
_WARM_BASES: set[Any] = set()


def _warm_up(spec: ModelSpec, n_samples: int = 1, options: FitOptions | None = None) -> None:
    """Pay a model's one-off costs: imports, cached basis tables, the solver's block buffer
    (see :func:`fit_model`); the BLAS controller last, once every library a fit uses is loaded."""
    if spec.kind == "knn":
        import sklearn.neighbors  # noqa: F401  (loads scipy's BLAS too)
    elif spec.decouples:
        from rplearn.core.lsq.link_statistics import reserve_block_buffer

        if options is not None and options.path_loss.learns_exponent:
            import scipy.linalg.blas  # noqa: F401  (the exponent's identifiability check solves through it)
        basis = spec.basis()
        if basis not in _WARM_BASES:  # once per basis and process: its tables are cached
            basis.evaluate(np.zeros(basis.n_coef), [0.0], [0.0])
            if basis.moment_shape is not None:
                basis.gram_from_moments(np.zeros(basis.moment_shape))
            _WARM_BASES.add(basis)
        reserve_block_buffer(basis, n_samples)
    warm_up_blas()


@check_types
def fit_model(
    samples: LinkSamples,
    spec: ModelSpec,
    options: FitOptions | None = None,
    provenance: Mapping[str, Any] | None = None,
) -> FittedModel:
    """Learn a model of any kind and time it with ``time.perf_counter`` (the paper's LTD).

    Pattern models follow ``options`` (:class:`FitOptions`: gauge, environment term, link
    offsets; :func:`solve_patterns`); the baselines, kept per directed link, need none of them
    (:meth:`FitOptions.check` refuses what they cannot honour). The Huber loss is
    :func:`rplearn.models.robust.fit_huber`, the automatic choice
    :func:`rplearn.models.auto.fit_auto` (they need more than one sample set or report more).

    One-off costs of the process (imports, the tables of a basis) are paid before the clock
    starts, so that the LTD of a model does not depend on whether it was the first one learned.
    """
    options = options or FitOptions()
    options.check(spec)
    if options.loss != "ls" or options.auto:
        raise InputError(f"fit_model: least squares of a fixed order; loss {options.loss!r} is fit_huber's and an "
                         "automatic choice fit_auto's", param="options")
    check_model_size(spec, len(samples), len(samples.nodes))
    _warm_up(spec, len(samples), options)
    columns = spec.basis().n_coef * len(samples.nodes) if spec.decouples else 0
    if spec.kind in ("mean", "knn"):
        with blas_threads_for(len(samples), columns):
            t0 = time.perf_counter()
            if spec.kind == "mean":
                model: MeanModel | KNNModel | PatternSet = MeanModel.fit(samples)
            else:
                model = KNNModel.fit(samples, int(spec.order or 0))  # ModelSpec refuses a knn without an order
            ltd = time.perf_counter() - t0
        coverage = model.training.coverage_deg
    else:
        model, ltd, coverage = _fit_patterns_with_coverage(samples, spec, options, columns)
    model.provenance = {**dict(provenance or {}), "model": spec.label}
    model.training = model.training.replace(ltd_s=ltd, coverage_deg=coverage)
    return FittedModel(spec, model, ltd)


def _fit_patterns_with_coverage(
    samples: LinkSamples, spec: ModelSpec, options: FitOptions, columns: int
) -> tuple[PatternSet, float, dict[str, list[float]]]:
    """:func:`fit_patterns`, its learning time [s] and the nodes' coverage grids
    (:func:`node_coverage_grids`).

    When the statistics go through the runtime's workers (a basis with Gram moments) and the
    solve is small (:func:`~rplearn.core.threads.is_small_fit` of the columns alone), the grids'
    jobs ride along (:meth:`~rplearn.core.lsq.runtime.StatisticsRuntime.overlapping`): queued
    behind the last block of samples, they run while a worker would otherwise wait for the last
    block or for the solve, which then keeps to one BLAS thread (the workers' cores are busy;
    ``RPLEARN_THREADS`` still decides when set). The grids are the same, whichever thread makes
    them.
    """
    from rplearn.core.lsq.runtime import DEFAULT_RUNTIME

    work = CoverageWork(samples)
    basis = spec.basis()
    ride = work.parallel and basis.moment_shape is not None and basis.stacked_samples and is_small_fit(0, columns)
    limit = one_blas_thread() if ride and thread_override() is None else blas_threads_for(len(samples), columns)
    with DEFAULT_RUNTIME.overlapping(work.jobs if ride else []) as riding, limit:
        t0 = time.perf_counter()
        model = fit_patterns(samples, spec, options)
        ltd = time.perf_counter() - t0
    return model, ltd, work.grids(riding.results()) if ride else work.run()


@check_types
def evaluate_models(fitted: Sequence[FittedModel], samples: LinkSamples, notes: list[str] | None = None) -> list[Scores]:
    """Table I: RMSE, MAE, Q95, |phi|, AIC, LTD and condition number of every model.

    Every model is scored on the same samples: those every model predicts (a two-ray model
    predicts nothing for an antenna at or below its ground level). How many were left out is
    appended to ``notes`` when given; when every sample would be left out, it is an error.
    """
    predictions = [np.asarray(f.model.predict_gain(samples), np.float64) for f in fitted]
    return scores_of_predictions(fitted, np.asarray(samples.joint_gain_db, np.float64), predictions, notes)


def scores_of_predictions(
    fitted: Sequence[FittedModel], observed: np.ndarray, predictions: Sequence[np.ndarray], notes: list[str] | None = None,
) -> list[Scores]:
    """:func:`evaluate_models` from the observed joint gains [dB] and each model's predictions
    (gathered from the parts of a dataset, say)."""
    keep = np.ones(observed.size, bool)
    for pred in predictions:
        keep &= np.isfinite(pred)
    if not keep.all():
        missing = [f.label for f, pred in zip(fitted, predictions) if not np.all(np.isfinite(pred))]
        if not keep.any():
            raise InputError(f"no sample could be predicted by {', '.join(missing)} (an antenna at or below the two-ray "
                             "ground level?)", param="units")
        if notes is not None:
            notes.append(f"{int((~keep).sum()):,} of {observed.size:,} samples are left out of the scores: {', '.join(missing)} "
                         "predict(s) nothing there (an antenna at or below the two-ray ground level)")
    rows = []
    for f, pred in zip(fitted, predictions):
        rows.append(score(f.label, observed[keep], pred[keep], f.n_params, f.ltd_s, f.condition_number))
    return rows


@check_types
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


