"""Calibration flights before flying them: trajectory units, campaigns and the plan check.

==============  ================================================================================
module          public names
==============  ================================================================================
``trajectory``  :class:`TrajectoryUnit` (paper Sec. IV-A), :class:`PlanLimits`,
                :func:`summarize_unit` -> :class:`UnitSummary`
``campaign``    :func:`paper_campaign` -> :class:`Campaign`, :func:`pair_schedule`,
                :func:`group_campaign`, :func:`write_references`
``check``       :func:`check_plan` -> :class:`PlanCheck` (coverage, rank, condition number; a
                :class:`NominalAttitude` of wind and tilt),
                :func:`coverage_map`, :func:`plan_directions`
==============  ================================================================================

Every name of ``__all__`` can be imported from here (``from rplearn.plan import check_plan``);
its module is imported on first use (:mod:`rplearn._lazy`).
"""

from __future__ import annotations

from rplearn._lazy import lazy_exports

_NAMES: dict[str, str] = {
    # trajectory units
    "PlanLimits": "trajectory",
    "TrajectoryUnit": "trajectory",
    "UnitReference": "trajectory",
    "UnitSummary": "trajectory",
    "summarize_unit": "trajectory",
    # campaigns
    "Campaign": "campaign",
    "GroundPassUnit": "ground",
    "group_campaign": "campaign",
    "link_graph_identifies_gains": "campaign",
    "pair_schedule": "campaign",
    "paper_campaign": "campaign",
    "write_references": "campaign",
    # the plan check
    "CoverageMap": "check",
    "PlanCheck": "check",
    "check_plan": "check",
    "NominalAttitude": "check",
    "coverage_map": "check",
    "plan_directions": "check",
}

__all__ = sorted(_NAMES)
__getattr__, __dir__ = lazy_exports(__name__, _NAMES)
