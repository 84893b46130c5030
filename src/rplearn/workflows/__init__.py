"""Pipelines that the command line, the report and the tests share.

- :mod:`~rplearn.workflows.logs`: logs -> matched dataset; a swarm's links and headings.
- :mod:`~rplearn.workflows.learning`: fit, evaluate, predict, sweep on files.
- :mod:`~rplearn.workflows.report`: the report about one model (and the paper's Table I on request).
- :mod:`~rplearn.workflows.demo`: the paper's whole evaluation on a simulated campaign.
"""

from __future__ import annotations

from rplearn._lazy import lazy_exports

_NAMES: dict[str, str] = {
    "DEMO_MODELS": "demo",
    "DemoResult": "demo",
    "run_demo": "demo",
    "EvaluationOutcome": "learning",
    "FitOutcome": "learning",
    "ReportOutcome": "report",
    "PAPER_MODELS": "report",
    "draw_pattern_files": "planning",
    "evaluate_model_files": "learning",
    "fit_dataset": "learning",
    "learn_and_report": "report",
    "predict_file": "learning",
    "sweep_dataset": "learning",
    "CampaignPlan": "planning",
    "export_model_file": "planning",
    "orient_link": "planning",
    "plan_campaign": "planning",
    "reference_model_file": "planning",
    "LinksOutcome": "logs",
    "SyncOutcome": "logs",
    "reader_notes": "logs",
    "swarm_headings": "logs",
    "swarm_links": "logs",
    "sync_logs": "logs",
}

__all__ = sorted(_NAMES)
__getattr__, __dir__ = lazy_exports(__name__, _NAMES)
