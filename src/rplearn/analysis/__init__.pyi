# Public names of this package: read by type checkers and IDEs, and by lazy_loader.attach_stub
# in __init__.py, which imports each name's module on first use. Only `from .module import name
# as name` lines here (tests/test_public_api.py).

from .budget import BudgetFinding as BudgetFinding
from .budget import LinkSummary as LinkSummary
from .budget import budget_findings as budget_findings
from .budget import check_dataset_budget as check_dataset_budget
from .budget import check_fit_budget as check_fit_budget
from .budget import link_summaries as link_summaries
from .clock import ClockOffsetEstimate as ClockOffsetEstimate
from .clock import estimate_clock_offset as estimate_clock_offset
from .decoupling import DecouplingCertificate as DecouplingCertificate
from .decoupling import certify as certify
from .decoupling import decoupling_certificate as decoupling_certificate
from .heading_options import SwarmHeadingOptions as SwarmHeadingOptions
from .heading_options import YawOptions as YawOptions
from .headings import OrientationResult as OrientationResult
from .headings import SwarmHeadings as SwarmHeadings
from .headings import best_swarm_headings as best_swarm_headings
from .headings import best_yaw as best_yaw
from .headings import heading_gain_tables as heading_gain_tables
from .headings import heading_std_tables as heading_std_tables
from .identifiability import IdentifiabilityStudy as IdentifiabilityStudy
from .identifiability import identifiability_study as identifiability_study
from .identifiability import study_antennas as study_antennas
from .pattern_error import gauged_nodes as gauged_nodes
from .pattern_error import node_directions as node_directions
from .pattern_error import pattern_errors_db as pattern_errors_db
from .swarm import DEFAULT_MIN_RSSI_DBM as DEFAULT_MIN_RSSI_DBM
from .swarm import SwarmOptions as SwarmOptions
from .swarm import SwarmPrediction as SwarmPrediction
from .swarm import connectivity_over_time as connectivity_over_time
from .swarm import predict_swarm as predict_swarm
from .swarm import spanning_bottleneck as spanning_bottleneck
from .sweep import SweepResult as SweepResult
from .sweep import order_sweep as order_sweep
