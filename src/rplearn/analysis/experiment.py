"""The paper's evaluation as library functions: model-order sweep, pattern error against the
truth, the identifiability study of Sec. V-A, link orientation, and the whole demo (Sec. V-C).

Every function returns a dataclass that the command line, the report and the tests share.
"""

from __future__ import annotations

import json
import os
import sys
import time
from dataclasses import dataclass, field
from typing import Any, Callable, Mapping, Sequence

import numpy as np
import pandas as pd

from rplearn._version import __version__
from rplearn.core.bases import SphericalHarmonics
from rplearn.data.tables import LinkSamples
from rplearn.io.files import write_table
from rplearn.errors import InputError
from rplearn.core.geometry import Directions, direction_in_body, quat_wxyz_from_yaw
from rplearn.models.fit import FittedModel, ModelSpec, evaluate_models, fit_model, samples_of, scores_markdown
from rplearn.core.metrics import Scores
from rplearn.models.patterns import PatternSet
from rplearn.core.solver import fit_joint, identifiability

Progress = Callable[[str], None]


def _noop(_: str) -> None:
    return None


# -------------------------------------------------------------------------------------------
# Model-order selection (paper Sec. V-C3, Fig. 10)


@dataclass
class SweepResult:
    """Test RMSE, AIC, LTD and condition number against the model order."""

    kind: str
    orders: list[int]
    rmse_db: list[float]
    aic: list[float]
    ltd_s: list[float]
    condition_number: list[float]
    n_params: list[int]

    @property
    def best_order(self) -> int:
        """Order with the lowest test RMSE."""
        return int(self.orders[int(np.argmin(self.rmse_db))])

    def to_frame(self) -> pd.DataFrame:
        return pd.DataFrame(
            {
                "order": self.orders,
                "n_params": self.n_params,
                "test_rmse_db": self.rmse_db,
                "aic": self.aic,
                "ltd_s": self.ltd_s,
                "condition_number": self.condition_number,
            }
        )


def order_sweep(
    learn: LinkSamples,
    test: LinkSamples,
    kind: str = "sh",
    orders: Sequence[int] = tuple(range(3, 21)),
    stop_after_rises: int | None = 3,
    progress: Progress = _noop,
) -> SweepResult:
    """Fit models of increasing order on ``learn`` and score each on ``test``.

    Stops early once the test error has risen above its minimum for ``stop_after_rises``
    consecutive orders (None: run every order).
    """
    out = SweepResult(kind, [], [], [], [], [], [])
    rises = 0
    for order in orders:
        spec = ModelSpec(kind, int(order))
        fitted = fit_model(learn, spec)
        row = evaluate_models([fitted], test)[0]
        out.orders.append(int(order))
        out.rmse_db.append(row.rmse_db)
        out.aic.append(row.aic)
        out.ltd_s.append(row.ltd_s)
        out.condition_number.append(fitted.condition_number)
        out.n_params.append(fitted.n_params)
        progress(f"{spec.label}: test RMSE {row.rmse_db:.3f} dB")
        rises = rises + 1 if row.rmse_db > min(out.rmse_db) else 0
        if stop_after_rises is not None and rises >= stop_after_rises:
            break
    return out


# -------------------------------------------------------------------------------------------
# Pattern error against the truth (what the paper could not measure)


def node_directions(samples: LinkSamples) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Directions each node saw the other in, over all samples (as tx and as rx) [rad]."""
    d = samples.directions
    out = {}
    for k, node in enumerate(samples.nodes):
        as_tx = samples.tx_index == k
        as_rx = samples.rx_index == k
        out[node] = (np.concatenate([d.az_tx[as_tx], d.az_rx[as_rx]]), np.concatenate([d.el_tx[as_tx], d.el_rx[as_rx]]))
    return out


def gauged_nodes(model: Any) -> set[str]:
    """Nodes whose constant the fit could not identify (named in the model's gauge notes)."""
    return {str(n) for g in getattr(model, "gauge", []) for n in g.get("nodes", [])}


def pattern_errors_db(
    model: Any, truth: Any, directions: Mapping[str, tuple[np.ndarray, np.ndarray]], remove_constant: bool | None = None
) -> dict[str, float]:
    """RMS difference between a learned and a true pattern over the covered directions [dB].

    The mean difference is removed first for nodes whose constant the fit could not identify
    (two nodes, or any bipartite link graph; paper Sec. V-A): there the constant is a
    convention, not an error. Nodes in a triangle of links are compared absolutely.
    ``remove_constant`` forces either behaviour for every node.
    """
    gauged = gauged_nodes(model)
    out = {}
    for node, (az, el) in directions.items():
        diff = np.asarray(model.evaluate(node, az, el)) - np.asarray(truth.evaluate(node, az, el))
        if remove_constant or (remove_constant is None and node in gauged):
            diff = diff - diff.mean()
        out[node] = float(np.sqrt(np.mean(diff**2)))
    return out


# -------------------------------------------------------------------------------------------
# Identifiability study (paper Sec. V-A, Figs. 5 and 6)


@dataclass
class IdentifiabilityStudy:
    """Epsilon sweep of a two-antenna fit and the ranks of two- and three-antenna problems."""

    order: int
    epsilons: list[float]
    rmse_db: list[float]
    rank_cases: list[tuple[str, int, int]]
    two_node_patterns: PatternSet
    truth: Any

    def to_dict(self) -> dict[str, Any]:
        return {
            "model": f"SH-{self.order}",
            "epsilon_sweep": [{"epsilon": e, "rmse_db": r} for e, r in zip(self.epsilons, self.rmse_db)],
            "ranks": [{"case": c, "columns": n, "rank": r} for c, n, r in self.rank_cases],
        }


@dataclass(frozen=True)
class _AntennaSet:
    """Surrogate antennas of the study: evaluate(node, az, el) like a ground truth."""

    antennas: Mapping[str, Any]

    @property
    def nodes(self) -> tuple[str, ...]:
        return tuple(self.antennas)

    def evaluate(self, node: str, az_rad, el_rad) -> np.ndarray:
        return self.antennas[node].gain_dbi(az_rad, el_rad)


def study_antennas() -> _AntennaSet:
    """The ITU-R F.1336-5 surrogates of the paper's Fig. 6: omni "O", sectoral "S", circular "C"."""
    from rplearn.sim.antennas import AntennaSpec, Mounting, NodeAntenna

    vertical = Mounting.named("vertical")
    return _AntennaSet(
        {
            "O": NodeAntenna(AntennaSpec("itu_omni_peak", g0_dbi=2.0, k=0.7), vertical, (), "ITU omni, 2 dBi"),
            "S": NodeAntenna(
                AntennaSpec("itu_sectoral_peak", g0_dbi=20.0, phi3_deg=45.0, theta3_deg=15.0), vertical, (), "ITU sectoral 45/15 deg, 20 dBi"
            ),
            "C": NodeAntenna(AntennaSpec("itu_omni_peak", g0_dbi=10.0, k=0.7), vertical, (), "ITU circular (omni) 10 dBi"),
        }
    )


def identifiability_study(order: int = 8, n_samples: int = 20000, seed: int = 0) -> IdentifiabilityStudy:
    """Reproduce paper Sec. V-A with SH of degrees < ``order``.

    The paper's Fig. 6 reports 192 columns for three antennas, i.e. 64 per antenna: SH-8 in
    DESIGN.md's labels (degrees 0..7), which is the default here.

    Pairwise transmissions at random directions between ITU antennas: with two antennas
    (C and S) the rank is one below the column count and +-epsilon on the two Y00 terms
    changes no prediction; with three antennas in a triangle the rank is full.
    """
    rng = np.random.default_rng(seed)
    ants = study_antennas()
    basis = SphericalHarmonics(order)

    def draw(pairs: np.ndarray, names: Sequence[str]):
        sel = pairs[rng.integers(0, len(pairs), n_samples)]
        az = rng.uniform(-np.pi, np.pi, (2, n_samples))
        el = np.arcsin(rng.uniform(-1, 1, (2, n_samples)))
        d = Directions(az[0], el[0], az[1], el[1])
        y = np.empty(n_samples)
        for t in range(len(names)):
            for r in range(len(names)):
                m = (sel[:, 0] == t) & (sel[:, 1] == r)
                if m.any():
                    y[m] = ants.evaluate(names[t], az[0][m], el[0][m]) + ants.evaluate(names[r], az[1][m], el[1][m])
        return d, sel[:, 0], sel[:, 1], y

    names2 = ["C", "S"]
    d, tx, rx, y = draw(np.array([[0, 1]]), names2)
    sol = fit_joint(d, tx, rx, y, 2, basis, names2)
    ft = basis.design(d.az_tx, d.el_tx)
    fr = basis.design(d.az_rx, d.el_rx)
    epsilons = [0.0] + [float(v) for v in np.logspace(-3, 6, 19)]
    rmses = []
    for eps in epsilons:
        c = sol.coef.copy()
        c[0, 0] += eps
        c[1, 0] -= eps
        rmses.append(float(np.sqrt(np.mean((ft @ c[0] + fr @ c[1] - y) ** 2))))
    names3 = ["O", "S", "C"]
    d3, tx3, rx3, _ = draw(np.array([[0, 1], [1, 2], [2, 0]]), names3)
    rep2 = sol.report
    rep3 = identifiability(d3, tx3, rx3, 3, basis, names3)
    patterns = PatternSet(basis, tuple(names2), sol.coef, gauge=[g.to_dict() for g in rep2.gauges], training=rep2.to_dict())
    cases = [("two antennas (C, S)", rep2.n_columns, rep2.rank), ("three antennas (O, S, C)", rep3.n_columns, rep3.rank)]
    return IdentifiabilityStudy(order, epsilons, rmses, cases, patterns, ants)


# -------------------------------------------------------------------------------------------
# Use of a learned model: best heading


@dataclass(frozen=True)
class OrientationResult:
    """Headings that maximise a link and the predicted joint gain there."""

    tx_yaw_deg: float
    rx_yaw_deg: float
    gain_db: float
    baseline_gain_db: float


def best_yaw(
    model: PatternSet,
    tx_node: str,
    rx_node: str,
    tx_position_xyz: Sequence[float],
    rx_position_xyz: Sequence[float],
    turn: str = "tx",
    tx_yaw_deg: float = 0.0,
    rx_yaw_deg: float = 0.0,
    step_deg: float = 1.0,
) -> OrientationResult:
    """Heading(s) of level drones at given ENU positions that maximise the predicted joint gain.

    Parameters
    ----------
    turn : {"tx", "rx", "both"}
        Which drone may turn; the other keeps its given yaw (ENU, ccw from east) [deg].
    """
    if turn not in ("tx", "rx", "both"):
        raise InputError(f"turn must be 'tx', 'rx' or 'both', got {turn!r}")
    if not (0 < step_deg <= 90):
        raise InputError(f"step_deg must be in (0, 90], got {step_deg}")
    grid = np.arange(-180.0, 180.0, step_deg)
    tx_p = np.asarray(tx_position_xyz, float)
    rx_p = np.asarray(rx_position_xyz, float)

    def gains(yaw_deg: np.ndarray, own: np.ndarray, other: np.ndarray, node: str) -> np.ndarray:
        q = quat_wxyz_from_yaw(np.radians(yaw_deg))
        az, el = direction_in_body(np.broadcast_to(own, (yaw_deg.size, 3)), q, np.broadcast_to(other, (yaw_deg.size, 3)))
        return model.evaluate(node, az, el)

    g_tx = gains(grid, tx_p, rx_p, tx_node) if turn in ("tx", "both") else gains(np.array([tx_yaw_deg]), tx_p, rx_p, tx_node)
    g_rx = gains(grid, rx_p, tx_p, rx_node) if turn in ("rx", "both") else gains(np.array([rx_yaw_deg]), rx_p, tx_p, rx_node)
    base = float(gains(np.array([tx_yaw_deg]), tx_p, rx_p, tx_node)[0] + gains(np.array([rx_yaw_deg]), rx_p, tx_p, rx_node)[0])
    i_tx = int(np.argmax(g_tx))
    i_rx = int(np.argmax(g_rx))
    best_tx = float(grid[i_tx]) if turn in ("tx", "both") else float(tx_yaw_deg)
    best_rx = float(grid[i_rx]) if turn in ("rx", "both") else float(rx_yaw_deg)
    return OrientationResult(best_tx, best_rx, float(g_tx[i_tx] + g_rx[i_rx]), base)


# -------------------------------------------------------------------------------------------
# The demo: the paper's whole evaluation on the simulated replica of its campaign


DEMO_MODELS = ("m", "nn-400", "sh-10", "p-12", "bg-7")


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


def provenance(command: str | None = None, **parameters: Any) -> dict[str, Any]:
    """What made an output: library version, command line, parameters, time."""
    return {
        "rplearn_version": __version__,
        "command": command if command is not None else " ".join(["rplearn", *sys.argv[1:]]),
        "parameters": parameters,
        "created_utc": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
    }


def run_demo(
    out_dir: str = "rplearn-demo",
    seed: int = 0,
    preset: str = "paper",
    models: Sequence[str] = DEMO_MODELS,
    progress: Progress = _noop,
    figures: bool = True,
) -> DemoResult:
    """Simulate the paper's campaign, learn M, NN-400, SH-10, P-12 and BG-7, and report.

    Steps: simulate the ``preset`` flight (raw pose and signal logs), synchronise them
    (link A -> B, as the paper), learn on the learning units and test on the testing unit
    (Table I), score each decoupling model's patterns against the true ones over the covered
    directions, sweep the SH order, run the identifiability study, then write figures and
    ``report.html`` into ``out_dir``.
    """
    from rplearn.sim.simulate import simulate
    from rplearn.data.sync import synchronise

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
    synced = synchronise(sim.pose_log, sim.signal_log, link=link)
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
        progress(f"learning {spec.label} on {len(learn):,} samples")
        f = fit_model(learn, spec, provenance=prov)
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
    with open(files["table_md"], "w") as fh:
        fh.write(md + "\n")
    files["table_json"] = os.path.join(out_dir, "table1.json")
    with open(files["table_json"], "w") as fh:
        json.dump(
            {"provenance": prov, "rows": [r.to_dict() for r in table], "pattern_error_db": perr, "noise_std_db": sim.noise_std_db},
            fh,
            indent=1,
            default=float,
        )
    files["sweep_csv"] = os.path.join(out_dir, "sweep.csv")
    sweep.to_frame().to_csv(files["sweep_csv"], index=False)
    files["identifiability_json"] = os.path.join(out_dir, "identifiability.json")
    with open(files["identifiability_json"], "w") as fh:
        json.dump({"provenance": prov, **study.to_dict()}, fh, indent=1)

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


def _demo_figures_and_report(result, sim, dataset, learn, test, fitted, prov) -> dict[str, str]:
    from rplearn.viz import plot
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
    files["fig_rssi"] = plot.plot_rssi_time(
        first_unit["t"].to_numpy() - first_unit["t"].iloc[0], first_unit["rssi_dbm"].to_numpy(), os.path.join(fig_dir, "rssi.png"),
        caption=f"Received signal strength over time during the first flight unit, {unit0} (paper Fig. 8b).",
    )
    sw = result.sweep
    files["fig_sweep"] = plot.plot_order_sweep(sw.orders, sw.rmse_db, sw.aic, sw.ltd_s, os.path.join(fig_dir, "sweep.png"))
    st = result.study
    files["fig_epsilon"] = plot.plot_epsilon_sweep(st.epsilons[1:], st.rmse_db[1:], os.path.join(fig_dir, "epsilon.png"))
    files["fig_rank"] = plot.plot_rank_study(st.rank_cases, os.path.join(fig_dir, "rank.png"))
    best = min((r for r in result.table if r.model in pattern_models), key=lambda r: r.rmse_db)
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
            "relative to its own sphere mean.",
            [files["fig_patterns"]],
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
            f"with two antennas; ranks: "
            + "; ".join(f"{c}: {r} of {n} columns" for c, n, r in st.rank_cases),
            [files["fig_epsilon"], files["fig_rank"]],
        ),
    ]
    files["report"] = write_report(out, "rplearn: radiation patterns learned from a calibration flight", result.table_markdown, sections, prov)
    return files
