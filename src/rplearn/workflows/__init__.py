"""Pipelines that the command line, the report and the tests share.

- :mod:`~rplearn.workflows.logs`: logs -> matched dataset; a swarm's links and headings.
- :mod:`~rplearn.workflows.learning`: fit, evaluate, predict, sweep, learn-and-report on files.
- :mod:`~rplearn.workflows.demo`: the paper's whole evaluation on a simulated campaign.
"""

from __future__ import annotations

from rplearn.workflows.demo import DEMO_MODELS, DemoResult, run_demo
from rplearn.workflows.learning import (
    EvaluationOutcome,
    FitOutcome,
    ReportOutcome,
    draw_pattern_files,
    evaluate_model_files,
    fit_dataset,
    learn_and_report,
    predict_file,
    sweep_dataset,
)
from rplearn.workflows.planning import CampaignPlan, export_model_file, orient_link, plan_campaign
from rplearn.workflows.logs import LinksOutcome, SyncOutcome, reader_notes, swarm_headings, swarm_links, sync_logs

__all__ = [
    "CampaignPlan",
    "DEMO_MODELS",
    "DemoResult",
    "EvaluationOutcome",
    "FitOutcome",
    "LinksOutcome",
    "ReportOutcome",
    "SyncOutcome",
    "draw_pattern_files",
    "evaluate_model_files",
    "export_model_file",
    "fit_dataset",
    "learn_and_report",
    "orient_link",
    "plan_campaign",
    "predict_file",
    "reader_notes",
    "run_demo",
    "swarm_headings",
    "swarm_links",
    "sweep_dataset",
    "sync_logs",
]
