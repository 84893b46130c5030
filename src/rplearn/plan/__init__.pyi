# Public names of rplearn.plan: read by type checkers and IDEs, and by lazy_loader.attach_stub in
# __init__.py, which imports each name's module on first use. Only `from .module import name as
# name` lines here (tests/test_public_api.py).

from .trajectory import (
    PlanLimits as PlanLimits,
    TrajectoryUnit as TrajectoryUnit,
    UnitReference as UnitReference,
    UnitSummary as UnitSummary,
    summarize_unit as summarize_unit,
)
from .campaign import (
    Campaign as Campaign,
    group_campaign as group_campaign,
    link_graph_identifies_gains as link_graph_identifies_gains,
    pair_schedule as pair_schedule,
    paper_campaign as paper_campaign,
    write_references as write_references,
)
from .ground import (
    GroundPassUnit as GroundPassUnit,
)
from .check import (
    CoverageMap as CoverageMap,
    PlanCheck as PlanCheck,
    check_plan as check_plan,
    coverage_map as coverage_map,
    plan_directions as plan_directions,
)
