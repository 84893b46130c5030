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
its module is imported on first use (``__init__.pyi``, lazy_loader).
"""

from __future__ import annotations

import lazy_loader

# The public names are those of __init__.pyi, each imported on first use.
__getattr__, __dir__, __all__ = lazy_loader.attach_stub(__name__, __file__)
