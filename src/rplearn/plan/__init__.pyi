# Public names of this package: read by type checkers and IDEs, and by lazy_loader.attach_stub
# in __init__.py, which imports each name's module on first use. Only `from .module import name
# as name` lines here (tests/test_public_api.py).

from .campaign import Campaign as Campaign
from .campaign import group_campaign as group_campaign
from .campaign import link_graph_identifies_gains as link_graph_identifies_gains
from .campaign import pair_schedule as pair_schedule
from .campaign import paper_campaign as paper_campaign
from .campaign import still_nodes as still_nodes
from .campaign import write_references as write_references
from .check import CoverageMap as CoverageMap
from .check import NominalAttitude as NominalAttitude
from .check import PlanCheck as PlanCheck
from .check import check_plan as check_plan
from .check import coverage_map as coverage_map
from .check import plan_directions as plan_directions
from .ground import GroundPassUnit as GroundPassUnit
from .manoeuvres import Candidate as Candidate
from .manoeuvres import CandidateOptions as CandidateOptions
from .manoeuvres import ManoeuvreUnit as ManoeuvreUnit
from .manoeuvres import candidate_manoeuvres as candidate_manoeuvres
from .references import ReferenceUnit as ReferenceUnit
from .references import read_plan as read_plan
from .trajectory import PlanLimits as PlanLimits
from .trajectory import TrajectoryUnit as TrajectoryUnit
from .trajectory import UnitReference as UnitReference
from .trajectory import UnitSummary as UnitSummary
from .trajectory import summarize_unit as summarize_unit
