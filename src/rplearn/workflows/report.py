"""``rplearn report``: a report about one model on its dataset, and the paper's Table I on request.

:func:`learn_and_report` fits the default model (the cross-validated one ``rplearn fit``
learns: SH, order and smoothing chosen over the learning units) or takes a model file, scores
it on the held-out units and writes ``report.html`` with the figures an engineer looks at first
(:mod:`rplearn.viz.model_figures`): measured and predicted RSSI over time with the 90 % band,
residuals against distance, elevation and azimuth, polar cuts, the spread map, coverage, the
maps and the 3-D surfaces (faded where the flight never looked). The paper's fixed-order models
(M, NN-400, SH-10, P-12, BG-7; :data:`PAPER_MODELS`) are a section of their own when asked
(``paper_models``), their learning time the median of :data:`LTD_REPEATS` runs.
"""

from __future__ import annotations

import functools
import os
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from rplearn._argtypes import check_types
from rplearn._atomic import atomic_open
from rplearn._budget import Cost, check_work
from rplearn.analysis.pattern_error import node_directions
from rplearn.core.metrics import Scores
from rplearn.data.units import samples_of, select_units, split_units, time_units
from rplearn.errors import IdentifiabilityError, InputError
from rplearn.io.files import check_output_path, provenance, read_dataset, write_json
from rplearn.models.fit import FittedModel, evaluate_models, fit_model, scores_markdown
from rplearn.models.load import load_model
from rplearn.models.options import FitOptions
from rplearn.models.predict import predict_dataset
from rplearn.models.spec import ModelSpec
from rplearn.models.terms import terms_text
from rplearn.workflows.learning import fit_dataset

Progress = Callable[[str], None]

#: The paper's fixed-order models of Table I (``--paper-models paper``).
PAPER_MODELS: tuple[str, ...] = ("m", "nn-400", "sh-10", "p-12", "bg-7")
#: Learning runs per model of Table I; its learning time (LTD) is their median.
LTD_REPEATS = 5
#: Files :func:`learn_and_report` may write into its folder.
REPORT_FILES: tuple[str, ...] = (
    "coverage.png", "patterns.png", "time.png", "residuals.png", "polar.png", "spread.png", "table1.md", "table1.json",
    "model.json", "report.html", "reliability.png",
)


def _no_progress(message: str) -> None:
    """Say nothing."""


@check_types
@dataclass(frozen=True)
class ReportOptions:
    """What a report adds beyond the model on its held-out units.

    Attributes
    ----------
    repeats : int
        Learning runs per Table I model (its learning time is their median).
    sensitivity_dbm : float, optional
        Also score the model's predicted availability ``P(RSSI >= s)`` on the held-out units
        (outage events count as down) and draw the reliability diagram
        (:mod:`rplearn.models.availability_score`).

    Raises
    ------
    InputError
        Fewer than 1 run, or a non-finite sensitivity.
    """

    repeats: int = LTD_REPEATS
    sensitivity_dbm: float | None = None

    def __post_init__(self) -> None:
        if isinstance(self.repeats, bool) or not isinstance(self.repeats, int) or self.repeats < 1:
            raise InputError(f"repeats: expected at least 1 learning run per model, got {self.repeats}", param="repeats")
        if self.sensitivity_dbm is not None and not np.isfinite(self.sensitivity_dbm):
            raise InputError(f"sensitivity_dbm: expected a level in dBm, got {self.sensitivity_dbm!r}",
                             param="sensitivity_dbm")


@check_types
def paper_model_names(names: Sequence[str]) -> list[str]:
    """The Table I models asked for: ``paper`` stands for :data:`PAPER_MODELS`, ``auto`` for the
    cross-validated SH model; every other name is checked by :meth:`ModelSpec.parse`."""
    out: list[str] = []
    for name in (str(n).strip().lower() for n in names):
        if not name:
            continue
        for n in (PAPER_MODELS if name == "paper" else (name,)):
            if n != "auto":
                ModelSpec.parse(n)
            if n not in out:
                out.append(n)
    return out


@check_types
@dataclass
class ReportOutcome:
    """One model reported on its dataset (and the paper's Table I when asked).

    Attributes
    ----------
    fitted : FittedModel
        The model reported on (fitted here, or loaded: ``model_path``).
    rows : list of Scores
        Its scores on the held-out units (one row).
    markdown : str
        ``rows`` as a Markdown table.
    paper_rows : list of Scores
        Table I of the paper's models (empty unless asked), learning times the median of the runs.
    paper_markdown : str
    learn_units, test_units : list of str
    report_path : str
    log_start_s : float
        Time of the first sample [s, log time]; every time printed is relative to it.
    notes : list of str
    files : dict of str
        What was written, by name.
    model_text : str
        How the model was learned (the fit's summary), or where it came from.
    model_path : str or None
        The model file reported on (None: fitted here).
    availability : AvailabilityScore or None
        Its predicted availability scored on the held-out units (``ReportOptions.sensitivity_dbm``).
    """

    fitted: FittedModel
    rows: list[Scores]
    markdown: str
    paper_rows: list[Scores]
    paper_markdown: str
    learn_units: list[str]
    test_units: list[str]
    report_path: str
    log_start_s: float
    notes: list[str] = field(default_factory=list)
    files: dict[str, str] = field(default_factory=dict)
    model_text: str = ""
    model_path: str | None = None
    availability: Any = None

    def summary(self) -> str:
        """The log start (once), the model's held-out scores, Table I when asked, where the report is."""
        start = f"t = {self.log_start_s:.3f} s"
        lines = [] if any(start in n for n in self.notes) else [
            f"log start {start} (log time); times in the report are relative to it"]
        origin = f"from {self.model_path}" if self.model_path else f"learned on {', '.join(self.learn_units)}"
        lines += [f"model: {self.fitted.label}, {origin}; scored on the held-out {', '.join(self.test_units)}:",
                  self.markdown]
        if self.availability is not None:
            lines += [f"predicted availability at {self.availability.sensitivity_dbm:g} dBm on the held-out units:",
                      self.availability.markdown()]
        if self.paper_markdown:
            lines += ["Table I, the paper's models (learning time LTD: median of the runs):", self.paper_markdown]
        lines.append(f"wrote {self.report_path}")
        return "\n".join(lines)


def _default_model(dataset: str, learn: Sequence[str], options: FitOptions) -> tuple[FittedModel, str]:
    """The cross-validated SH model ``rplearn fit`` learns by default, on the learning units."""
    outcome = fit_dataset(dataset, ModelSpec.parse("sh"), list(learn), options=replace(options, auto=True))
    return outcome.fitted, outcome.summary()


def _held_out_notes(model: Any, model_path: str, test: Sequence[str]) -> list[str]:
    """What a given model's provenance says about the held-out units: learned from them, or unknown."""
    from rplearn.data.units import trained_units

    learned = trained_units([model.provenance])
    seen = [u for u in test if u in learned]
    if seen:
        return [f"{model_path} learned from {', '.join(seen)} too: its scores there are not held out (choose "
                "--test-units among the units it did not learn from)"]
    if not learned:
        return [f"{model_path} does not record its learning units (learned from the whole dataset?): its scores on "
                f"{', '.join(test)} may not be held out (fit --units ... learns without them)"]
    return []


@check_types
def median_ltd(runs: Sequence[FittedModel]) -> FittedModel:
    """The first run with its learning time replaced by the median over ``runs`` [s]."""
    return replace(runs[0], ltd_s=float(np.median([r.ltd_s for r in runs])))


@check_types
def paper_table(
    names: Sequence[str], ls: Any, ts: Any, prov: dict[str, Any], repeats: int = LTD_REPEATS,
    auto_fit: Callable[[], FittedModel] | None = None, options: FitOptions | None = None, progress: Progress = _no_progress,
) -> tuple[list[FittedModel], list[Scores], list[str]]:
    """Learn each Table I model ``repeats`` times on ``ls`` (its LTD the median), score on ``ts``.

    Returns the fitted models, their scores and the notes (a model the data cannot identify is a
    note; the others still go).
    """
    if repeats < 1:
        raise InputError(f"repeats: expected at least 1 learning run per model, got {repeats}", param="repeats")
    fitted, notes = [], []
    for name in names:
        progress(f"learning {name} ({repeats} runs)")
        try:
            if name == "auto":
                if auto_fit is None:
                    raise InputError("auto: no cross-validated fit available here", param="paper_models")
                learn_once = auto_fit
            else:
                spec = ModelSpec.parse(name)
                how = (options or FitOptions()) if spec.decouples else FitOptions()  # baselines: free space
                learn_once = functools.partial(fit_model, ls, spec, how, provenance=prov)
            started = time.perf_counter()
            runs = [learn_once()]
            once = time.perf_counter() - started  # the runs' cost, measured by the first
            check_work("repeats", repeats, lambda n: Cost(memory_bytes=0.0, seconds=n * once), f"runs of {name}")  # noqa: B023
            runs += [learn_once() for _ in range(repeats - 1)]
        except (InputError, IdentifiabilityError) as exc:  # too few samples for this model: the others still go
            if exc.param == "repeats":  # the work budget refuses the runs: no model is left out for it
                raise
            notes.append(f"{name.upper()} not learned: {exc}")
            continue
        fitted.append(median_ltd(runs))
    if not fitted:
        raise InputError(f"none of the models could be learned ({'; '.join(notes)})", param="paper_models")
    left_out: list[str] = []
    rows = evaluate_models(fitted, ts, left_out)
    return fitted, rows, notes + left_out


@check_types
def learn_and_report(
    dataset: str,
    out_dir: str,
    model_path: str | None = None,
    paper_models: Sequence[str] = (),
    test_units: Sequence[str] | None = None,
    progress: Progress = _no_progress,
    options: FitOptions | None = None,
    report: ReportOptions | None = None,
) -> ReportOutcome:
    """Report one model on a dataset (``rplearn report``) into ``out_dir/report.html``.

    Parameters
    ----------
    dataset : str
        Matched dataset; without a ``unit`` column it is cut into stretches of time
        (``flight[1/5]``..``test[5/5]``).
    out_dir : str
        Output folder (created).
    model_path : str, optional
        The model to report on; default the cross-validated SH model learned here on the
        learning units (as ``rplearn fit``, order ``auto``), written to ``out_dir/model.json``.
    paper_models : sequence of str
        Also the paper's Table I of these models (``paper`` = :data:`PAPER_MODELS`, ``auto`` the
        cross-validated model), learned on the same units, each ``repeats`` times.
    test_units : sequence of str, optional
        Held-out units (default: labels starting with ``test``).
    options : FitOptions, optional
        How pattern models learn (gauge, environment term, link offsets;
        :func:`rplearn.workflows.learning.fit_dataset`); the baselines learn in free space.
    report : ReportOptions, optional
        Learning runs per Table I model, and the sensitivity [dBm] of the availability section
        (its reliability diagram); ``ReportOptions()`` by default.
    """
    from rplearn.viz import interactive
    from rplearn.viz.report import ReportSection, write_report

    names = paper_model_names(paper_models)  # refuse a bad name before any work
    report = report or ReportOptions()
    repeats = report.repeats
    for name in REPORT_FILES:  # the report's own files may not overwrite its inputs
        if os.path.lexists(os.path.join(out_dir, name)):
            check_output_path(os.path.join(out_dir, name), [dataset, model_path])
    df, unit_note = time_units(read_dataset(dataset), source=dataset)
    learn, test = split_units(df, None, test_units, dataset)
    t0 = float(np.nanmin(df["t"].to_numpy(np.float64)))
    options = replace(options or FitOptions(), auto=False)
    notes = [unit_note] if unit_note else []
    if model_path:
        model = load_model(model_path)
        fitted, model_text = FittedModel.from_model(model), f"{model.label} from {model_path}"
        notes += _held_out_notes(model, model_path, test)
    else:
        progress("learning the cross-validated model (as rplearn fit does by default)")
        fitted, model_text = _default_model(dataset, learn, options)
        model = fitted.model
    nodes = [str(n) for n in model.nodes]
    ls = samples_of(df, learn, dataset)
    ts = samples_of(df, test, dataset, nodes=ls.nodes)
    prov = provenance(dataset=dataset, model=model_path or "auto", paper_models=names, test_units=test, repeats=repeats)
    rows = evaluate_models([fitted], ts)
    paper_rows: list[Scores] = []
    paper_md = ""
    if names:  # before anything is written: a refusal of its runs (the work budget) leaves no folder behind
        _, paper_rows, paper_notes = paper_table(
            names, ls, ts, prov, repeats, auto_fit=lambda: _default_model(dataset, learn, options)[0],
            options=options, progress=progress)
        notes += paper_notes
        paper_md = scores_markdown(paper_rows)
    os.makedirs(out_dir, exist_ok=True)
    files: dict[str, str] = {}
    if not model_path:  # the model reported on, for predict, evaluate, plot
        files["model"] = os.path.join(out_dir, "model.json")
        model.save(files["model"])
    if names:
        files["table1_md"] = os.path.join(out_dir, "table1.md")
        with atomic_open(files["table1_md"], "w", encoding="utf-8") as fh:
            fh.write(paper_md + "\n")
        files["table1_json"] = os.path.join(out_dir, "table1.json")
        write_json(files["table1_json"], {"provenance": prov, "ltd_runs": repeats, "rows": [r.to_dict() for r in paper_rows]})
    progress("drawing the figures")
    sections = _figure_sections(_Data(df, learn, test, ls, ts, t0, dataset), model, fitted.label, nodes, out_dir, files)
    if report.sensitivity_dbm is not None:
        from rplearn.workflows.report_availability import availability_section
        section, availability = availability_section(model, df, test, report.sensitivity_dbm, out_dir, files)
        sections.append(section)
    views_3d, text_3d = interactive.pattern_3d_figures({fitted.label: model}, nodes, directions=node_directions(ls)) \
        if model.kind == "patterns" else ([], "")
    if views_3d:
        sections.append(ReportSection("The patterns in 3-D", text_3d, [], interactive=views_3d))
    lines = [f"- {line}" for line in terms_text(model.training)] if model.kind == "patterns" else []
    origin = f"from {model_path}" if model_path else f"learned on {', '.join(learn)}"
    about = (f"{fitted.label}, {origin}, scored on the held-out {', '.join(test)}. "
             f"Times are seconds after the log start, t = {t0:.3f} s.\n\n```\n{model_text}\n```")
    sections.insert(0, ReportSection("The model", about + ("\n\n" + "\n".join(lines) if lines else ""), []))
    if paper_md:
        sections.append(ReportSection(
            "Table I: the paper's fixed-order models",
            f"Learned on the same units and scored on the same held-out samples; the learning time LTD is the "
            f"median of {repeats} runs.\n\n{paper_md}", []))
    if notes:
        sections.insert(0, ReportSection("Notes", "\n".join(f"- {line}" for line in notes), []))
    md = scores_markdown(rows)
    path = write_report(out_dir, f"rplearn report: {os.path.basename(dataset)}", md, sections, prov,
                        table_title=f"{fitted.label} on the held-out samples")
    files["report"] = path
    return ReportOutcome(fitted, rows, md, paper_rows, paper_md, learn, test, path, t0, notes, files, model_text,
                         model_path, availability if report.sensitivity_dbm is not None else None)


@dataclass(frozen=True)
class _Data:
    """The dataset a report is about: its table, learning and held-out units, their samples,
    the log start [s] and its name."""

    df: Any
    learn: Sequence[str]
    test: Sequence[str]
    ls: Any
    ts: Any
    t0: float
    dataset: str


def _figure_sections(data: _Data, model: Any, label: str, nodes: list[str], out_dir: str,
                     files: dict[str, str]) -> list[Any]:
    """The figures about one model, written into ``out_dir`` and grouped in report sections."""
    df, learn, test, ls, ts, t0, dataset = data.df, data.learn, data.test, data.ls, data.ts, data.t0, data.dataset
    from rplearn.data.tables import link_samples, outage_mask
    from rplearn.viz import model_figures as mf
    from rplearn.viz import plot
    from rplearn.viz.report import ReportSection

    part = select_units(df, [*learn, *test], dataset)
    part = part[~outage_mask(part, dataset)]  # outage events: no RSSI to draw (the availability section scores them)
    predicted = predict_dataset(model, part, dataset).table
    units = part["unit"].astype(str).to_numpy()
    held_out = np.isin(units, [str(u) for u in test])
    spread = predicted["rssi_pred_std_db"].to_numpy(np.float64) if "rssi_pred_std_db" in predicted else None
    files["time"] = mf.plot_prediction_time(
        os.path.join(out_dir, "time.png"), part["t"].to_numpy(np.float64) - t0, part["rssi_dbm"].to_numpy(np.float64),
        predicted["rssi_pred_dbm"].to_numpy(np.float64), spread, list(units), list(test),
        links=list(part["tx"].astype(str) + "->" + part["rx"].astype(str)))
    samples = link_samples(part, dataset)
    d = samples.directions
    residual = samples.joint_gain_db - predicted["gain_pred_db"].to_numpy(np.float64)
    files["residuals"] = mf.plot_residuals(
        os.path.join(out_dir, "residuals.png"), residual, samples.distance_m,
        (np.degrees(d.el_tx), np.degrees(d.el_rx)), (np.degrees(d.az_tx), np.degrees(d.az_rx)), held_out)
    sections = [ReportSection("Measured and predicted", "", [files["time"], files["residuals"]])]
    files["coverage"] = plot.plot_coverage(node_directions(ls), node_directions(ts), os.path.join(out_dir, "coverage.png"))
    images: list[str | os.PathLike[str]] = [files["coverage"]]
    if model.kind == "patterns":
        files["polar"] = mf.plot_polar_cuts(model, os.path.join(out_dir, "polar.png"), nodes, label)
        files["patterns"] = plot.plot_pattern_maps({label: model}, None, nodes, node_directions(ls),
                                                   os.path.join(out_dir, "patterns.png"))
        images += [files["polar"], files["patterns"]]
        if getattr(model, "covariance", None) is not None:
            files["spread"] = plot.plot_spread_maps({label: model}, os.path.join(out_dir, "spread.png"), nodes)
            images.append(files["spread"])
    sections.append(ReportSection("Patterns, coverage and spread", "", images))
    return sections


__all__ = ["LTD_REPEATS", "PAPER_MODELS", "REPORT_FILES", "ReportOptions", "ReportOutcome", "learn_and_report", "median_ltd",
           "paper_model_names", "paper_table"]
