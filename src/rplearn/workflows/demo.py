"""The paper's whole evaluation on a simulated replica of its campaign (``rplearn demo``)."""

from __future__ import annotations

import os
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from rplearn._argtypes import check_types
from rplearn._atomic import atomic_open, dump_json
from rplearn.analysis.identifiability import IdentifiabilityStudy, identifiability_study
from rplearn.analysis.pattern_error import node_directions, pattern_errors_db
from rplearn.analysis.sweep import SweepResult, no_progress, order_sweep
from rplearn.core.metrics import Scores
from rplearn.data.units import samples_of
from rplearn.io.files import provenance, write_table
from rplearn.models.fit import FittedModel, evaluate_models, fit_model, scores_markdown
from rplearn.models.patterns import PatternSet
from rplearn.models.spec import ModelSpec
from rplearn.workflows.report import LTD_REPEATS, median_ltd

if TYPE_CHECKING:
    import pandas as pd

    from rplearn.data.tables import LinkSamples
    from rplearn.sim.flight import SimulationResult

Progress = Callable[[str], None]


DEMO_MODELS = ("m", "nn-400", "sh-10", "p-12", "bg-7")


@check_types
@dataclass
class DemoResult:
    """Everything the demo measured and wrote."""

    out_dir: str
    table: list[Scores]
    table_markdown: str
    pattern_error_db: dict[str, dict[str, float]]
    sweep: SweepResult
    study: IdentifiabilityStudy
    sync_text: str
    n_learn: int
    n_test: int
    noise_std_db: float
    files: dict[str, str] = field(default_factory=dict)
    elapsed_s: float = 0.0

    def summary(self) -> str:
        """Table I with the simulated noise, the SH sweep's best order, the identifiability
        ranks and where the report is."""
        sw = self.sweep
        lines = [
            f"\nTable I on the testing unit ({self.n_test:,} samples; learned on {self.n_learn:,}); "
            f"simulated noise {self.noise_std_db:.2f} dB; 'pattern err' = RMS error of the learned pattern "
            "against the true one over the covered directions (constant removed where two drones cannot identify it):\n",
            self.table_markdown,
            f"\nSH order sweep: lowest test RMSE {min(sw.rmse_db):.3f} dB at SH-{sw.best_order} "
            f"(orders {sw.orders[0]}..{sw.orders[-1]})",
            *(f"identifiability, {case}: rank {rank} of {cols} columns" for case, cols, rank in self.study.rank_cases),
            f"\nwrote {self.files.get('report', self.out_dir)} ({self.elapsed_s:.0f} s)",
        ]
        return "\n".join(lines)


@check_types
def run_demo(
    out_dir: str = "rplearn-demo",
    seed: int = 0,
    preset: str = "paper",
    models: Sequence[str] = DEMO_MODELS,
    progress: Progress = no_progress,
    figures: bool = True,
) -> DemoResult:
    """Simulate the paper's campaign, learn M, NN-400, SH-10, P-12 and BG-7, and report.

    Steps: simulate the ``preset`` flight (raw pose and signal logs), synchronise them
    (link A -> B, as the paper), learn on the learning units and test on the testing unit
    (Table I), score each decoupling model's patterns against the true ones over the covered
    directions, sweep the SH order, run the identifiability study, then write figures and
    ``report.html`` into ``out_dir``.
    """
    from rplearn.data.sync import SyncOptions, synchronise
    from rplearn.sim.flight import simulate

    t_start = time.perf_counter()
    os.makedirs(out_dir, exist_ok=True)
    prov = provenance(preset=preset, seed=seed, models=list(models))
    files: dict[str, str] = {}

    progress(f"simulating the '{preset}' campaign (seed {seed})")
    sim = simulate(preset, seed=seed, out_dir=os.path.join(out_dir, "flight"))
    files.update({f"flight_{k}": v for k, v in sim.paths.items()})
    nodes = list(sim.ground_truth.nodes)
    # Two drones: one direction, as the paper does (non-reciprocal electronics). More drones:
    # every link, so that a triangle of links identifies absolute gains.
    link = (nodes[0], nodes[1]) if len(nodes) == 2 else None
    link_text = f"link {link[0]} -> {link[1]}" if link else "all links"
    progress(f"synchronising {len(sim.signal_log):,} packets with the pose logs ({link_text})")
    synced = synchronise(sim.pose_log, sim.signal_log, SyncOptions(link=link))
    dataset = synced.dataset
    files["dataset"] = os.path.join(out_dir, "dataset.parquet")
    write_table(dataset, files["dataset"])
    learn_units, test_units = sim.units("learning"), sim.units("testing")
    learn = samples_of(dataset, learn_units, "dataset")
    test = samples_of(dataset, test_units, "dataset", nodes=learn.nodes)

    fitted: list[FittedModel] = []
    models_dir = os.path.join(out_dir, "models")
    os.makedirs(models_dir, exist_ok=True)
    for name in models:
        spec = ModelSpec.parse(name)
        progress(f"learning {spec.label} on {len(learn):,} samples ({LTD_REPEATS} runs: LTD is their median)")
        f = median_ltd([fit_model(learn, spec, provenance=prov) for _ in range(LTD_REPEATS)])
        fitted.append(f)
        path = os.path.join(models_dir, f"{spec.label}.json")
        f.model.save(path)
        files[f"model_{spec.label}"] = path
    progress(f"testing on {len(test):,} samples")
    table = evaluate_models(fitted, test)
    covered = node_directions(learn)
    for node, (az, el) in node_directions(test).items():
        covered[node] = (np.concatenate([covered[node][0], az]), np.concatenate([covered[node][1], el]))
    perr = {
        f.label: pattern_errors_db(f.model, sim.ground_truth, covered) for f in fitted if isinstance(f.model, PatternSet)
    }
    extra = {label: {f"pattern err {n}/dB": v for n, v in errs.items()} for label, errs in perr.items()}
    md = scores_markdown(table, extra)

    progress("sweeping the SH order")
    sweep = order_sweep(learn, test, "sh", progress=progress)
    progress("identifiability study (ITU-R F.1336-5 antennas)")
    study = identifiability_study(seed=seed)

    files["table_md"] = os.path.join(out_dir, "table1.md")
    with atomic_open(files["table_md"], "w", encoding="utf-8") as fh:
        fh.write(md + "\n")
    files["table_json"] = os.path.join(out_dir, "table1.json")
    with atomic_open(files["table_json"], "w", encoding="utf-8") as fh:
        dump_json(
            {"provenance": prov, "rows": [r.to_dict() for r in table], "pattern_error_db": perr, "noise_std_db": sim.noise_std_db},
            fh,
            indent=1,
            default=float,
        )
    files["sweep_csv"] = os.path.join(out_dir, "sweep.csv")
    write_table(sweep.to_frame(), files["sweep_csv"])
    files["identifiability_json"] = os.path.join(out_dir, "identifiability.json")
    with atomic_open(files["identifiability_json"], "w", encoding="utf-8") as fh:
        dump_json({"provenance": prov, **study.to_dict()}, fh, indent=1)

    result = DemoResult(
        out_dir=out_dir,
        table=table,
        table_markdown=md,
        pattern_error_db=perr,
        sweep=sweep,
        study=study,
        sync_text=synced.summary.to_text(),
        n_learn=len(learn),
        n_test=len(test),
        noise_std_db=sim.noise_std_db,
        files=files,
    )
    if figures:
        progress("drawing figures and writing report.html")
        files.update(_demo_figures_and_report(result, sim, dataset, learn, test, fitted, prov))
    result.elapsed_s = time.perf_counter() - t_start
    return result


def _demo_figures_and_report(result: DemoResult, sim: SimulationResult, dataset: pd.DataFrame, learn: LinkSamples,
                             test: LinkSamples, fitted: list[FittedModel], prov: dict[str, Any]) -> dict[str, str]:
    from rplearn.viz import charts, plot
    from rplearn.viz.interactive import pattern_3d_figures
    from rplearn.viz.report import ReportSection, write_report

    out = result.out_dir
    fig_dir = os.path.join(out, "figures")
    os.makedirs(fig_dir, exist_ok=True)
    files: dict[str, str] = {}
    learn_dirs = node_directions(learn)
    test_dirs = node_directions(test)
    pattern_models = {f.label: f.model for f in fitted if isinstance(f.model, PatternSet)}
    files["fig_patterns"] = plot.plot_pattern_maps(
        pattern_models, sim.ground_truth, list(learn.nodes), learn_dirs, os.path.join(fig_dir, "patterns.png"), center=True
    )
    files["fig_coverage"] = plot.plot_coverage(learn_dirs, test_dirs, os.path.join(fig_dir, "coverage.png"))
    unit0 = str(dataset["unit"].iloc[0])
    first_unit = dataset[dataset["unit"] == dataset["unit"].iloc[0]]
    files["fig_rssi"] = charts.plot_rssi_time(
        first_unit["t"].to_numpy() - first_unit["t"].iloc[0], first_unit["rssi_dbm"].to_numpy(), os.path.join(fig_dir, "rssi.png"),
        caption=f"Received signal strength over time during the first flight unit, {unit0} (paper Fig. 8b).",
    )
    sw = result.sweep
    files["fig_sweep"] = charts.plot_order_sweep(sw.orders, sw.rmse_db, sw.aic, sw.ltd_s, os.path.join(fig_dir, "sweep.png"))
    st = result.study
    files["fig_epsilon"] = charts.plot_epsilon_sweep(st.epsilons[1:], st.rmse_db[1:], os.path.join(fig_dir, "epsilon.png"))
    files["fig_rank"] = charts.plot_rank_study(st.rank_cases, os.path.join(fig_dir, "rank.png"))
    best = min((r for r in result.table if r.model in pattern_models), key=lambda r: r.rmse_db)
    views_3d, text_3d = pattern_3d_figures(pattern_models, list(learn.nodes), center=True)
    sections = [
        ReportSection(
            "Dataset",
            f"{result.n_learn:,} learning and {result.n_test:,} testing samples. "
            f"Simulated noise level {result.noise_std_db:.2f} dB.\n\n```\n{result.sync_text}\n```",
            [files["fig_coverage"], files["fig_rssi"]],
        ),
        ReportSection(
            "Learned radiation patterns (Fig. 9)",
            "Each model's two patterns in the azimuth-elevation domain, beside the true patterns, with the "
            "learning samples drawn over them. Two-node fits identify shapes only, so every map is shown "
            f"relative to its own sphere mean.\n\n{text_3d}",
            [files["fig_patterns"]],
            interactive=views_3d,
        ),
        ReportSection(
            "Model-order selection (Fig. 10)",
            f"SH orders {sw.orders[0]}..{sw.orders[-1]}; lowest test RMSE at SH-{sw.best_order} "
            f"({min(sw.rmse_db):.3f} dB). Best decoupling model of Table I: {best.model}.",
            [files["fig_sweep"]],
        ),
        ReportSection(
            "Identifiability (Sec. V-A, Figs. 5 and 6)",
            "Adding epsilon to one antenna's Y00 and subtracting it from the other's changes no prediction "
            "with two antennas; ranks: "
            + "; ".join(f"{c}: {r} of {n} columns" for c, n, r in st.rank_cases),
            [files["fig_epsilon"], files["fig_rank"]],
        ),
    ]
    files["report"] = write_report(out, "rplearn: radiation patterns learned from a calibration flight", result.table_markdown, sections, prov)
    return files
