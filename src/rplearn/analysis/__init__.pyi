# Public names of rplearn.analysis: read by type checkers and IDEs, and by lazy_loader.attach_stub in
# __init__.py, which imports each name's module on first use. Only `from .module import name as
# name` lines here (tests/test_public_api.py).

from .sweep import (
    SweepResult as SweepResult,
    order_sweep as order_sweep,
)
from .identifiability import (
    IdentifiabilityStudy as IdentifiabilityStudy,
    identifiability_study as identifiability_study,
    study_antennas as study_antennas,
)
from .pattern_error import (
    gauged_nodes as gauged_nodes,
    node_directions as node_directions,
    pattern_errors_db as pattern_errors_db,
)
from .decoupling import (
    DecouplingCertificate as DecouplingCertificate,
    certify as certify,
    decoupling_certificate as decoupling_certificate,
)
from .headings import (
    OrientationResult as OrientationResult,
    SwarmHeadings as SwarmHeadings,
    best_swarm_headings as best_swarm_headings,
    best_yaw as best_yaw,
    heading_gain_tables as heading_gain_tables,
    heading_std_tables as heading_std_tables,
)
from .clock import (
    ClockOffsetEstimate as ClockOffsetEstimate,
    estimate_clock_offset as estimate_clock_offset,
)
from .swarm import (
    DEFAULT_MIN_RSSI_DBM as DEFAULT_MIN_RSSI_DBM,
    SwarmPrediction as SwarmPrediction,
    connectivity_over_time as connectivity_over_time,
    predict_swarm as predict_swarm,
    spanning_bottleneck as spanning_bottleneck,
)
from .budget import (
    BudgetFinding as BudgetFinding,
    LinkSummary as LinkSummary,
    budget_findings as budget_findings,
    check_dataset_budget as check_dataset_budget,
    check_fit_budget as check_fit_budget,
    link_summaries as link_summaries,
)
