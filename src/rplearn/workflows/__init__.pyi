# Public names of this package: read by type checkers and IDEs, and by lazy_loader.attach_stub
# in __init__.py, which imports each name's module on first use. Only `from .module import name
# as name` lines here (tests/test_public_api.py).

from .availability import AvailabilityOutcome as AvailabilityOutcome
from .availability import LinkFiles as LinkFiles
from .availability import swarm_links_availability as swarm_links_availability
from .demo import DEMO_MODELS as DEMO_MODELS
from .demo import DemoResult as DemoResult
from .demo import run_demo as run_demo
from .learning import EvaluationOutcome as EvaluationOutcome
from .learning import FitOutcome as FitOutcome
from .learning import evaluate_model_files as evaluate_model_files
from .learning import fit_dataset as fit_dataset
from .learning import predict_file as predict_file
from .learning import sweep_dataset as sweep_dataset
from .logs import LinksOutcome as LinksOutcome
from .logs import SyncOutcome as SyncOutcome
from .logs import reader_notes as reader_notes
from .logs import swarm_headings as swarm_headings
from .logs import swarm_links as swarm_links
from .logs import sync_logs as sync_logs
from .planning import CampaignOptions as CampaignOptions
from .planning import CampaignPlan as CampaignPlan
from .planning import draw_pattern_files as draw_pattern_files
from .planning import export_model_file as export_model_file
from .planning import orient_link as orient_link
from .planning import plan_campaign as plan_campaign
from .planning import reference_model_file as reference_model_file
from .report import PAPER_MODELS as PAPER_MODELS
from .report import ReportOutcome as ReportOutcome
from .report import learn_and_report as learn_and_report
