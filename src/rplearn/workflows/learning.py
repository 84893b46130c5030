"""Learning pipelines on dataset files: fit, evaluate, predict and sweep (the report: :mod:`rplearn.workflows.report`).

Each reads its inputs, applies the one unit rule of :mod:`rplearn.data.units`, calls the
library and returns a result object with the notes a user should read; the command line only
prints it. Output paths are checked before any work.
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable, Sequence
from contextlib import nullcontext
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Any

from rplearn._argtypes import check_types
from rplearn._atomic import atomic_open
from rplearn.analysis.budget import check_dataset_budget
from rplearn.analysis.decoupling import certify
from rplearn.core.metrics import Scores
from rplearn.core.plausible import check_one_band
from rplearn.data.tables import QUATERNION_NORM_TOLERANCE
from rplearn.data.units import (
    TIME_UNITS,
    Stretches,
    UnitChoice,
    dataset_units,
    evaluation_units,
    is_stretch_label,
    learning_units,
    refuse_streamed_stretches,
    samples_of,
    select_units,
    split_units,
    stretch_samples,
    stretched,
    time_units,
    trained_units,
    whole_flight_note,
)
from rplearn.errors import InputError
from rplearn.io.files import check_output_kind, check_output_path, check_table_path, provenance, read_dataset, table_rows, write_json, write_table
from rplearn.io.partitions import dataset_parts, is_partitioned
from rplearn.io.resolve import check_outputs
from rplearn.models.fit import FittedModel, evaluate_models, fit_model, scores_markdown, scores_of_predictions
from rplearn.models.load import load_model, load_priors
from rplearn.models.options import FitOptions
from rplearn.models.patterns import PatternSet
from rplearn.models.predict import UNCOVERED_DEG, DatasetPrediction, check_model_band, check_model_nodes, distinct_labels, predict_dataset, uncovered_rows
from rplearn.models.robust import downweighted_notes, fit_huber
from rplearn.models.spec import ModelSpec, check_model_size
from rplearn.models.streamed import checked, fit_patterns_accumulated, weighted_median
from rplearn.models.terms import terms_text
from rplearn.workflows.fleet import accumulate_parts, dask_client, dataset_index, learning_times, parse_dask, predict_parts, selected_rows

if TYPE_CHECKING:  # order selection (models.auto, analysis.sweep) loads scipy: imported when used
    from rplearn.analysis.sweep import SweepResult
    from rplearn.core.lsq.selection import Selection

Progress = Callable[[str], None]


def no_progress(message: str) -> None:
    """The default progress callback: says nothing."""


@check_types
@dataclass
class FitOutcome:
    """A model learned from a dataset file.

    Attributes
    ----------
    fitted : FittedModel
    units : UnitChoice
        The learning units and the notes about them.
    n_samples : int
    output : str or None
        Model file written.
    non_unit_quaternions : int
        Learning samples whose tx or rx quaternion was not of unit norm (normalised).
    selection : Selection or None
        The automatic choice of order and smoothing and its validation curve (``auto=True``).
    outages : int
        Outage events of the learning units skipped (no RSSI: :mod:`rplearn.data.outages`).
    """

    fitted: FittedModel
    units: UnitChoice
    n_samples: int
    output: str | None = None
    non_unit_quaternions: int = 0
    selection: Selection | None = None
    wall_s: float | None = None
    robust_notes: list[str] = field(default_factory=list)
    outages: int = 0

    def summary(self) -> str:
        """What was learned, from how much, in how long; rank, conditioning and gauge."""
        training = self.fitted.model.training
        text = f"{self.fitted.label} learned from {self.n_samples:,} samples in {self.fitted.ltd_s:.3f} s"
        if self.output:
            text += f" -> {self.output}"
        if training.rank is not None:
            text += (
                f"\n  rank {training.rank} of {training.n_columns}, condition number "
                f"{training.condition_number:.2f}, training RMSE {training.rmse_db:.2f} dB"
            )
            text += "".join(f"\n  gauge: {g['text']}" for g in training.gauges or ())
        if self.selection is not None:
            sel = self.selection
            how = (f"grouped cross-validation over units {', '.join(sel.units)}" if sel.method == "grouped-cv"
                   else "generalised cross-validation (one unit)")
            text += (f"\n  chosen by {how}: order {sel.order}, smoothing {sel.smoothing:.1e}, "
                     f"validation RMSE {sel.rmse_db:.2f} dB; the curve:\n    "
                     + sel.curve_text().replace("\n", "\n    "))
            if training.variance_inflation is not None and sel.method == "grouped-cv":
                text += (f"\n  spread: within each held-out unit, the errors exceed the posterior's by "
                         f"x{training.variance_inflation:.2f} in variance (correlated packets, misfit); the covariance "
                         "is inflated to match")
                if training.flight_level_std_db is not None:
                    new_level = training.new_flight_level_std_db or 0.0
                    noise = training.noise_std_db if training.noise_std_db is not None else float("nan")
                    text += (f"\n  flight-to-flight level: {training.flight_level_std_db:.1f} dB (1 sigma) between units, "
                             f"{new_level:.1f} dB for a new flight's predictions; "
                             f"noise about a flight's level {noise:.1f} dB")
                if training.misfit_std_db:
                    text += (f"\n  misfit: held-out units err {training.misfit_std_db:.2f} dB (1 sigma, per node) beyond "
                             "what the posterior states, structure this order and smoothing cannot hold; added to "
                             "each pattern's spread everywhere")
            kept = training.extra.get("prior_kept")
            if isinstance(kept, dict) and kept.get("kept"):
                text += (f"\n  prior: its own degrees above order {sel.order} kept, to order {kept.get('model_order')} "
                         f"(validation RMSE {kept.get('kept_rmse_db', float('nan')):.2f} dB; cut to order "
                         f"{kept.get('cut_order')}: {kept.get('cut_rmse_db', float('nan')):.2f} dB)")
            elif isinstance(kept, dict):
                text += (f"\n  prior: cut to the chosen order {sel.order} (kept to order {kept.get('model_order')} it "
                         f"validated {kept.get('kept_rmse_db', float('nan')):.2f} dB, worse beyond noise)")
            spread = training.prior_std_db or {}
            if spread:
                values = ", ".join(f"{n} {v:.1f} dB" for n, v in spread.items())
                text += (f"\n  where the flight never looked each pattern may be off by (1 sigma): {values} "
                         f"({training.prior_std_source or ''})")
        text += "".join(f"\n  {line}" for line in terms_text(training))
        text += "".join(f"\n  {line}" for line in (training.decoupling or {}).get("summary", "").splitlines())
        text += "".join(f"\n  {line}" for line in self.robust_notes)
        if self.wall_s is not None and self.wall_s > 0:
            text += (f"\n  read, accumulated and solved in {self.wall_s:.1f} s "
                     f"({self.n_samples / self.wall_s:,.0f} samples/s)")
        if self.outages:
            text += f"\n  outage events skipped (link lost, no RSSI to learn from): {self.outages:,}"
        if self.non_unit_quaternions:
            text += (f"\n  samples with a non-unit quaternion (|norm - 1| > {QUATERNION_NORM_TOLERANCE:g}, "
                     f"normalised): {self.non_unit_quaternions:,}")
        return text

    @property
    def warnings(self) -> list[str]:
        return list(self.fitted.model.training.warnings or ())


@check_types
def fit_dataset(
    dataset: str,
    spec: ModelSpec,
    units: Sequence[str] | None = None,
    *,
    options: FitOptions | None = None,
    output: str | None = None,
    dask: str | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> FitOutcome:
    """Learn ``spec`` from a matched dataset file (``rplearn fit``).

    Parameters
    ----------
    dataset : str
        Matched dataset (CSV or Parquet), or a dataset in many files: a directory, a glob, a
        comma-separated list or an fsspec URL (:mod:`rplearn.io.partitions`); pattern models
        learn from such a dataset part by part.
    spec : ModelSpec
        The model; with ``options.auto`` its kind and ridge (and the order of BG, P).
    units : sequence of str, optional
        Learning units; default every unit not labelled ``test...`` (:func:`learning_units`).
    options : FitOptions, optional
        How to learn (:class:`rplearn.models.options.FitOptions`, checked against ``spec``
        here): the gauge, the environment term and link offsets, the loss (Huber: a pattern
        model of fixed order, the dataset in memory; the outcome says how many samples were
        down-weighted, in which units and stretches), the automatic choice of order and
        smoothing (:mod:`rplearn.models.auto`), and the priors (model files or models) with
        their level and spread.
    output : str, optional
        Model file to write (JSON).
    dask : str, optional
        Run on Dask (pattern models, least squares): ``"local"``, ``"local:N"`` (a local
        cluster of N workers) or a scheduler address ``"tcp://host:8786"``
        (:mod:`rplearn.workflows.fleet`): statistics per part, tree-reduced, solved here.
    progress : callable, optional
        Called with ``(parts done, parts)`` while a dataset is read part by part.
    """
    options = options or FitOptions()
    options.check(spec)
    if output is not None:
        check_output_path(output, [dataset, *options.prior_files()])
        check_output_kind(output, "model")
    options = load_priors(options)
    if dask is not None:
        parse_dask(dask)
        if not spec.decouples or options.loss != "ls":
            raise InputError(f"--dask: pattern models (sh, bg, poly) with least squares learn on a cluster, not "
                             f"{spec.label}{' with loss ' + options.loss if options.loss != 'ls' else ''}", param="dask")
        with dask_client(dask) as client:
            return _fit_streamed(dataset, spec, units, options, output, client=client, progress=progress)
    if spec.decouples and _is_big(dataset):
        if options.loss == "huber":
            raise InputError(f"{dataset}: loss huber keeps the samples in memory; this file is streamed "
                             f"(over {STREAM_FIT_ROWS:,} rows or {STREAM_FIT_BYTES // 2**20} MiB): write the "
                             "units to learn from into a smaller file", param="loss")
        return _fit_streamed(dataset, spec, units, options, output, progress=progress)
    df, stretch_note = stretched(read_dataset(dataset), units, dataset)
    choice = learning_units(df, units, dataset)
    if "frequency_hz" in df.columns:
        check_one_band(select_units(df, choice.units, dataset)["frequency_hz"].to_numpy("float64"), dataset)
    if stretch_note:
        choice = replace(choice, notes=[stretch_note, *choice.notes])
    elif "unit" not in df.columns:
        choice = replace(choice, notes=[whole_flight_note(dataset)])
    if options.auto:
        return _fit_auto(df, dataset, spec, choice, options, output)
    samples = samples_of(df, choice.units, dataset)
    prov = provenance(dataset=dataset, model=spec.label, ridge=spec.ridge, units=choice.units)
    notes: list[str] = []
    if options.loss == "huber":
        fitted, robust = fit_huber(samples, spec, options, provenance=prov)
        notes = downweighted_notes(select_units(df, choice.units, dataset), robust)
    else:
        fitted = fit_model(samples, spec, options, provenance=prov)
    check_dataset_budget(fitted.model, select_units(df, choice.units, dataset), dataset)
    _record_rows(fitted.model, select_units(df, choice.units, dataset))
    certify(fitted.model, samples)
    if output:
        fitted.model.save(output)
    return FitOutcome(fitted, choice, len(samples), output, samples.non_unit_quaternions, robust_notes=notes,
                      outages=samples.outages)


#: A pattern fit streams its dataset (:mod:`rplearn.models.streamed`) from this many rows of a
#: Parquet file, or this many bytes of a CSV file, on: memory then holds one chunk.
STREAM_FIT_ROWS = 2_000_000
STREAM_FIT_BYTES = 256 * 2**20
#: Rows read at a time by a streamed fit: :data:`rplearn.workflows.fleet.PART_CHUNK_ROWS`.


def _fit_auto(
    df: Any, dataset: str, spec: ModelSpec, choice: UnitChoice, options: FitOptions, output: str | None,
) -> FitOutcome:
    """:func:`fit_dataset` with ``auto=True`` on a dataset in memory: samples per learning unit."""
    from rplearn.models.auto import fit_auto
    learn: list[str | None] = list(choice.units) if choice.units is not None else (list(dataset_units(df)) or [None])
    part = select_units(df, choice.units, dataset)
    nodes = sorted(set(part["tx"].astype(str).unique()) | set(part["rx"].astype(str).unique()))  # not a set of every row
    if len(learn) == 1:  # one flight: cross-validate over contiguous stretches of it, not samples
        per_unit = stretch_samples(part, None if learn[0] is None else str(learn[0]), dataset, nodes)
    else:
        per_unit = {str(u): samples_of(df, None if u is None else [u], dataset, nodes=nodes) for u in learn}
    prov = provenance(dataset=dataset, model=f"{spec.kind}-auto", ridge=spec.ridge, units=choice.units)
    fitted, selection = fit_auto(per_unit, spec, options, provenance=prov)
    check_dataset_budget(fitted.model, part, dataset)
    _record_rows(fitted.model, part)
    certify(fitted.model, None, fitted.own_posterior, fitted.learning_gram)  # the selection's X^T X: no second pass
    fitted.learning_gram = None  # read: not kept (a swarm's is (nodes x coefficients)^2 values)
    if output:
        fitted.model.save(output)
    n = sum(len(s) for s in per_unit.values())
    return FitOutcome(fitted, choice, n, output, sum(s.non_unit_quaternions for s in per_unit.values()), selection,
                      outages=sum(s.outages for s in per_unit.values()))


def _band_counts(index: Any) -> dict[float, int]:
    """Rows per carrier [Hz] of a dataset's index (:func:`rplearn.workflows.fleet.dataset_index`)."""
    sums = index.groupby("frequency_hz")["n"].sum()
    return {float(f): int(n) for f, n in zip(sums.index.to_numpy("float64"), sums.to_numpy("int64"), strict=True)}


def _record_rows(model: Any, rows: Any) -> None:
    """Record ``training["rssi_scale"] = "relative"`` when the learning rows are relative RSSI
    (``sync --rssi-scale relative``): nothing downstream then prints their levels as dBm; and the
    flight's layout, the nodes that held still and the radio's packet rate
    (:mod:`rplearn.data.flight_layout`), which the next flight's plan is made for."""
    from rplearn.data.flight_layout import fixed_nodes, is_relative_rssi, packet_rate_hz
    if is_relative_rssi(rows):
        model.training = model.training.replace(rssi_scale="relative")
    model.training = model.training.replace(fixed_nodes=fixed_nodes(rows), packet_rate_hz=packet_rate_hz(rows))


def _is_big(dataset: str) -> bool:
    """Whether a dataset is in many files or a file big enough to be streamed (see
    :data:`STREAM_FIT_ROWS`)."""
    if is_partitioned(dataset):
        return True
    if not os.path.isfile(dataset):
        return False
    rows = table_rows(dataset)
    return rows > STREAM_FIT_ROWS if rows is not None else os.path.getsize(dataset) > STREAM_FIT_BYTES


def _fit_streamed(
    dataset: str, spec: ModelSpec, units: Sequence[str] | None, options: FitOptions, output: str | None,
    client: Any = None, progress: Callable[[int, int], None] | None = None,
) -> FitOutcome:
    """:func:`fit_dataset` for a big file or a dataset in many files (:mod:`rplearn.io.partitions`):
    units, nodes and the model size from the id columns, then the patterns from the statistics
    of every part, a chunk at a time, here or on a Dask cluster (``client``;
    :mod:`rplearn.workflows.fleet`)."""
    parts = dataset_parts(dataset)
    index, per_part = dataset_index(parts, client)
    choice = learning_units(index, units, dataset)
    refuse_streamed_stretches(index, units, dataset)
    part = select_units(index, choice.units, dataset)
    if "frequency_hz" in part.columns:  # one band over every part, before any statistics
        check_one_band(_band_counts(part), dataset)
    nodes = sorted(set(part["tx"]) | set(part["rx"]))
    n = int(part["n"].sum())
    if n == 0:
        raise InputError(f"{dataset}: no samples selected", param="units")
    auto = options.auto
    if auto:
        from rplearn.models.auto import auto_orders, fit_from_statistics
        orders = auto_orders(spec.kind, n, len(nodes), spec.order if spec.kind != "sh" else None)
        spec = replace(spec, order=orders[-1])
    check_model_size(spec, n, len(nodes))
    t0 = time.perf_counter()
    if auto:
        learn: list[str | None] = [*(choice.units or dataset_units(index) or [])] or [None]
        stretches = Stretches.of_times(learning_times(parts, choice.units, client), TIME_UNITS, learn[0]) if len(learn) == 1 else None
        acc = checked(accumulate_parts(parts, spec, nodes, choice.units, options, stretches, client, progress), dataset)
        prov = provenance(dataset=dataset, model=f"{spec.kind}-auto", ridge=spec.ridge, units=choice.units)
        fitted, selection = fit_from_statistics(acc.stats, spec, orders, nodes, options,
                                                frequency_hz=weighted_median(acc.freq), provenance=prov)
        assert isinstance(fitted.model, PatternSet)  # fit_from_statistics learns patterns
        fitted.model.training = fitted.model.training.replace(coverage_deg=acc.grids or {}, **acc.layout.recorded())
        certify(fitted.model, None, fitted.own_posterior, fitted.learning_gram)  # the selection's X^T X: the samples were streamed
        fitted.learning_gram = None
        if output:
            fitted.model.save(output)
        return FitOutcome(fitted, choice, acc.n_samples, output, acc.non_unit, selection, wall_s=time.perf_counter() - t0)
    acc = checked(accumulate_parts(parts, spec, nodes, choice.units, options, client=client, progress=progress), dataset)
    fit = fit_patterns_accumulated(acc, spec, nodes, options)
    model = fit.patterns
    model.provenance = {**provenance(dataset=dataset, model=spec.label, ridge=spec.ridge, units=choice.units),
                        "model": spec.label}
    model.training = model.training.replace(ltd_s=fit.learn_s)
    fitted = FittedModel(spec, model, fit.learn_s)
    if output:
        model.save(output)
    return FitOutcome(fitted, choice, fit.n_samples, output, fit.non_unit_quaternions, wall_s=time.perf_counter() - t0)


@check_types
@dataclass
class EvaluationOutcome:
    """Table I of some models on a dataset.

    Attributes
    ----------
    rows : list of Scores
        One row per model; labels made distinct by file name where two models share one.
    markdown : str
    units : UnitChoice
        The units scored on, with notes and warnings (training scores).
    provenance : dict
    """

    rows: list[Scores]
    markdown: str
    units: UnitChoice
    provenance: dict[str, Any] = field(default_factory=dict)
    availability: list[Any] = field(default_factory=list)

    def to_dict(self) -> dict[str, Any]:
        out = {"provenance": self.provenance, "rows": [r.to_dict() for r in self.rows]}
        return {**out, "availability": [a.to_dict() for a in self.availability]} if self.availability else out


@check_types
def evaluate_model_files(
    model_paths: Sequence[str],
    dataset: str,
    units: Sequence[str] | None = None,
    json_out: str | None = None,
    markdown_out: str | None = None,
    dask: str | None = None,
    progress: Callable[[int, int], None] | None = None,
    sensitivity_dbm: float | None = None,
) -> EvaluationOutcome:
    """Score model files on a dataset file (``rplearn evaluate``): Table I.

    With ``sensitivity_dbm``, also each model's predicted availability ``P(RSSI >= s)``
    against the observed up/down of the samples, outage events included
    (:mod:`rplearn.models.availability_score`): Brier score, skill, reliability table (a
    dataset read whole).

    Without ``units``, the models are scored on the units none of them learned from
    (:func:`rplearn.data.units.evaluation_units`). A dataset in many files
    (:mod:`rplearn.io.partitions`) is predicted part by part, here or on Dask (``dask``, as
    :func:`fit_dataset`); the errors are gathered, so the scores are those of one process.
    """
    if not model_paths:
        raise InputError("evaluate: give at least one model file and a dataset", param="model_paths")
    check_outputs({"json_out": json_out, "markdown_out": markdown_out}, [*model_paths, dataset])
    models = [load_model(p) for p in model_paths]
    fitted = [FittedModel.from_model(m) for m in models]
    if sensitivity_dbm is not None and (dask is not None or is_partitioned(dataset)):
        raise InputError(f"{dataset}: sensitivity: availability is scored on a dataset read whole, not part by part",
                         param="sensitivity_dbm")
    if dask is not None or is_partitioned(dataset):
        if dask is not None:
            parse_dask(dask)
        with (dask_client(dask) if dask is not None else nullcontext()) as client:
            parts = dataset_parts(dataset)
            index, _ = dataset_index(parts, client)
            refuse_streamed_stretches(index, units, dataset)
            choice = evaluation_units(index, units, [m.provenance for m in models], dataset)
            if selected_rows(index, choice.units) == 0:
                raise InputError(f"{dataset}: no samples selected", param="units")
            if "frequency_hz" in index.columns:  # each model at its band, before any prediction
                carriers = select_units(index, choice.units, dataset)
                for model, path in zip(models, model_paths, strict=True):
                    check_model_band(model, _band_counts(carriers), dataset, path)
            observed, predictions, uncovered = predict_parts(parts, models, choice.units, client, progress)
        rows = scores_of_predictions(fitted, observed, predictions, choice.warnings)
        n_eval = observed.size
    else:
        provs = [m.provenance for m in models]  # models learned on stretches: the dataset's stretches, unseen ones by default
        df, _ = stretched(read_dataset(dataset), units or [u for u in trained_units(provs) if is_stretch_label(u)], dataset)
        choice = evaluation_units(df, units, provs, dataset)
        samples = samples_of(df, choice.units, dataset)
        for model, path in zip(models, model_paths, strict=True):
            check_model_nodes(model, samples.nodes, dataset, path)
            if samples.frequency_hz is not None:
                check_model_band(model, samples.frequency_hz, dataset, path)
        rows = evaluate_models(fitted, samples, choice.warnings)
        uncovered = [uncovered_rows(m, samples) for m in models]
        n_eval = len(samples)
    labels = distinct_labels([r.model for r in rows], [os.path.basename(p) for p in model_paths])
    rows = [replace(r, model=label) for r, label in zip(rows, labels)]
    for n_out, label in zip(uncovered, labels):
        if n_out:
            choice.warnings.append(
                f"{label}: {n_out:,} of {n_eval:,} evaluation samples ({n_out / n_eval:.0%}) look more than "
                f"{UNCOVERED_DEG:g} deg from any direction the model's antennas were learned from; their errors "
                "measure extrapolation (or the prior), not the fit: fly those directions to learn them")
    outcome = EvaluationOutcome(rows, scores_markdown(rows), choice, provenance(dataset=dataset, models=list(model_paths)))
    if sensitivity_dbm is not None:
        from rplearn.models.availability_score import availability_markdown, score_models_availability
        outcome.availability = score_models_availability(models, df, choice.units, sensitivity_dbm, labels, dataset)
        outcome.markdown += "\n\n" + availability_markdown(outcome.availability)
    if markdown_out:
        with atomic_open(markdown_out, "w", encoding="utf-8") as fh:
            fh.write(outcome.markdown + "\n")
    if json_out:
        write_json(json_out, outcome.to_dict())
    return outcome


@check_types
def predict_file(model_path: str, dataset: str, output: str, sensitivity_dbm: float | None = None) -> DatasetPrediction:
    """Predict every row of a dataset of poses and write it with the predictions (``rplearn predict``).

    See :func:`rplearn.models.predict.predict_dataset` for the added columns; with
    ``sensitivity_dbm`` also ``availability``, ``P(RSSI >= sensitivity_dbm)``
    (:func:`rplearn.analysis.availability.link_availability_column`).
    """
    check_table_path(output)
    check_output_path(output, [model_path, dataset])
    model = load_model(model_path)
    prediction = predict_dataset(model, read_dataset(dataset, require_rssi=False), dataset)
    if sensitivity_dbm is not None:
        from rplearn.analysis.availability import link_availability_column

        prediction.table["availability"] = link_availability_column(prediction.table, model, sensitivity_dbm)
    write_table(prediction.table, output)
    return prediction


@check_types
def sweep_dataset(
    dataset: str,
    kind: str,
    orders: Sequence[int],
    learn_units: Sequence[str] | None = None,
    test_units: Sequence[str] | None = None,
    progress: Progress = no_progress,
    output: str | None = None,
    plot_path: str | None = None,
) -> SweepResult:
    """Model-order sweep on a dataset file (``rplearn sweep``, paper Fig. 10).

    Learning and testing units default to the unit rule (:func:`split_units`); every order
    is learned and tested (no early stop).
    """
    from rplearn.analysis.sweep import order_bounds, order_sweep, validation_sweep
    if not orders or order_bounds(orders)[0] < 1:
        raise InputError(f"orders: expected positive orders, got {list(orders)!r}", param="orders")
    check_outputs({"output": output, "plot_path": plot_path}, [dataset])
    if output:
        check_table_path(output)
    if plot_path is not None:
        check_output_kind(plot_path, "png", "plot_path")
    df, unit_note = time_units(read_dataset(dataset), source=dataset)
    learn, test = split_units(df, learn_units, test_units, dataset)
    ls = samples_of(df, learn, dataset)
    ts = samples_of(df, test, dataset, nodes=ls.nodes)
    orders = orders if isinstance(orders, range) else [int(o) for o in orders]  # a range stays one (order_bounds)
    result = order_sweep(ls, ts, kind, orders, stop_after_rises=None, progress=progress)
    result.notes = [unit_note] if unit_note else []
    if kind == "sh":
        progress("cross-validating the orders over the learning units")
        per_unit = {str(u): samples_of(df, [u], dataset, nodes=ls.nodes) for u in learn}
        result.selection, result.validation_rmse_db = validation_sweep(per_unit, result.orders)
    if output:
        write_table(result.to_frame(), output)
    if plot_path:
        from rplearn.viz.charts import plot_order_sweep

        plot_order_sweep(result.orders, result.rmse_db, result.aic, result.ltd_s, plot_path,
                         validation_rmse_db=result.validation_rmse_db,
                         chosen=None if result.selection is None else (result.selection.order, result.selection.smoothing))
    return result
