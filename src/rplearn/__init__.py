"""rplearn: learn drone-with-antenna radiation patterns from calibration flights.

The method follows Zoula, Bonilla Licea, Faigl, Navrátil and Saska, "Orientation Matters:
Learning Radiation Patterns of Multi-Rotor UAVs In-Flight to Enhance Communication
Availability Modeling", arXiv:2604.02827, doi:10.48550/arXiv.2604.02827 (CITATION.cff): the
joint gain of a radio link is split into one radiation pattern per drone-with-antenna, each a
linear combination of basis functions of the direction (azimuth, elevation) in the drone's body
frame, identified by linear least squares over signal samples of a calibration flight.

The package is layered, bottom to top (ARCHITECTURE.md): :mod:`rplearn.core` (frames, link
budget, bases, solver, metrics), :mod:`rplearn.data` (canonical tables, pose-signal matching,
units), :mod:`rplearn.io` (log readers, table and model files, export), :mod:`rplearn.plan`
(calibration trajectories), :mod:`rplearn.sim` (simulated flights), :mod:`rplearn.models`
(patterns and baselines, fit, evaluate, load), :mod:`rplearn.analysis` (order sweep,
identifiability, headings, swarms), :mod:`rplearn.viz` (figures, report). Each subpackage
lists its public names in ``__all__``; the most used ones, every error class and
:func:`~rplearn.workflows.demo.run_demo` (the paper's whole evaluation) can also be imported
from here::

    from rplearn import ModelSpec, fit_model, read_table, samples_of

Names are resolved on first use (:mod:`rplearn._lazy`): ``import rplearn`` imports neither
pandas, scikit-learn nor matplotlib.
"""

from __future__ import annotations

from rplearn._lazy import lazy_exports
from rplearn._version import __version__ as __version__

_NAMES: dict[str, str] = {
    # errors
    "FarFieldError": "rplearn.errors",
    "IdentifiabilityError": "rplearn.errors",
    "InputError": "rplearn.errors",
    "LogFormatError": "rplearn.errors",
    "ModelFileError": "rplearn.errors",
    "PlanError": "rplearn.errors",
    "RplearnError": "rplearn.errors",
    # core: directions, link budget, bases, solver, metrics
    "Directions": "rplearn.core.geometry",
    "link_directions": "rplearn.core.geometry",
    "observed_joint_gain_db": "rplearn.core.link",
    "received_power_dbm": "rplearn.core.link",
    "make_basis": "rplearn.core.bases",
    "FitReport": "rplearn.core.lsq.solver",
    "fit_joint": "rplearn.core.lsq.solver",
    "identifiability": "rplearn.core.lsq.solver",
    "Scores": "rplearn.core.metrics",
    "score": "rplearn.core.metrics",
    # data: matched samples, matching, units
    "LinkSamples": "rplearn.data.tables",
    "link_samples": "rplearn.data.tables",
    "SyncOptions": "rplearn.data.sync",
    "SyncResult": "rplearn.data.sync",
    "synchronise": "rplearn.data.sync",
    "samples_of": "rplearn.data.units",
    # io: logs, tables, inspection, export
    "read_logs": "rplearn.io",
    "Logs": "rplearn.io._common",
    "ReaderOptions": "rplearn.io.options",
    "read_table": "rplearn.io.files",
    "write_table": "rplearn.io.files",
    "inspect_logs": "rplearn.io.inspect",
    "export_grid": "rplearn.io.export",
    "export_msi": "rplearn.io.msi",
    # plan
    "Campaign": "rplearn.plan.campaign",
    "paper_campaign": "rplearn.plan.campaign",
    "PlanLimits": "rplearn.plan.trajectory",
    "check_plan": "rplearn.plan.check",
    # sim
    "SimulationConfig": "rplearn.sim.config",
    "make_preset": "rplearn.sim.presets",
    "simulate": "rplearn.sim.flight",
    "GroundTruth": "rplearn.sim.antennas",
    "load_ground_truth": "rplearn.sim.antennas",
    # models
    "Model": "rplearn.models.base",
    "ModelSpec": "rplearn.models.spec",
    "PatternSet": "rplearn.models.patterns",
    "KNNModel": "rplearn.models.baselines",
    "MeanModel": "rplearn.models.baselines",
    "FittedModel": "rplearn.models.fit",
    "evaluate_models": "rplearn.models.fit",
    "fit_model": "rplearn.models.fit",
    "scores_markdown": "rplearn.models.fit",
    "load_model": "rplearn.models.load",
    "PatternRegressor": "rplearn.models.estimators",
    # analysis
    "order_sweep": "rplearn.analysis.sweep",
    "identifiability_study": "rplearn.analysis.identifiability",
    "pattern_errors_db": "rplearn.analysis.pattern_error",
    "best_swarm_headings": "rplearn.analysis.headings",
    "best_yaw": "rplearn.analysis.headings",
    "predict_swarm": "rplearn.analysis.swarm",
    # viz
    "plot_coverage": "rplearn.viz.plot",
    "plot_pattern_maps": "rplearn.viz.plot",
    "write_report": "rplearn.viz.report",
    # the paper's whole evaluation on a simulated campaign
    "run_demo": "rplearn.workflows.demo",
}

__all__ = sorted([*_NAMES, "__version__"])
__getattr__, __dir__ = lazy_exports(__name__, _NAMES)
