# Public names of rplearn.workflows: read by type checkers and IDEs, and by lazy_loader.attach_stub in
# __init__.py, which imports each name's module on first use. Only `from .module import name as
# name` lines here (tests/test_public_api.py).

from .demo import (
    DEMO_MODELS as DEMO_MODELS,
    DemoResult as DemoResult,
    run_demo as run_demo,
)
from .learning import (
    EvaluationOutcome as EvaluationOutcome,
    FitOutcome as FitOutcome,
    ReportOutcome as ReportOutcome,
    evaluate_model_files as evaluate_model_files,
    fit_dataset as fit_dataset,
    learn_and_report as learn_and_report,
    predict_file as predict_file,
    sweep_dataset as sweep_dataset,
)
from .planning import (
    CampaignPlan as CampaignPlan,
    draw_pattern_files as draw_pattern_files,
    export_model_file as export_model_file,
    orient_link as orient_link,
    plan_campaign as plan_campaign,
    reference_model_file as reference_model_file,
)
from .logs import (
    LinksOutcome as LinksOutcome,
    SyncOutcome as SyncOutcome,
    reader_notes as reader_notes,
    swarm_headings as swarm_headings,
    swarm_links as swarm_links,
    sync_logs as sync_logs,
)
