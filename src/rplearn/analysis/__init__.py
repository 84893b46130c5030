"""Studies on learned models: model order, identifiability, pattern error, headings, swarms.

===================  ===========================================================================
module               public names
===================  ===========================================================================
``sweep``            :func:`order_sweep` -> :class:`SweepResult` (paper Sec. V-C3, Fig. 10)
``identifiability``  :func:`identifiability_study` -> :class:`IdentifiabilityStudy`
                     (paper Sec. V-A), :func:`study_antennas`
``pattern_error``    :func:`pattern_errors_db` (learned against true patterns),
                     :func:`node_directions`
``headings``         :func:`best_yaw` -> :class:`OrientationResult` (one link),
                     :func:`best_swarm_headings` -> :class:`SwarmHeadings` (hovering swarm)
``swarm``            :func:`predict_swarm` -> :class:`SwarmPrediction` (every link over time,
                     connectivity), :func:`connectivity_over_time`
``decoupling``       :func:`decoupling_certificate` -> :class:`DecouplingCertificate` (each
                     node's own-pattern spread, the components a flight cannot split),
                     :func:`certify`
``clock``            :func:`estimate_clock_offset` -> :class:`ClockOffsetEstimate` (a node's
                     pose clock offset, from the signal)
``budget``           :func:`check_fit_budget`, :func:`budget_findings` -> :class:`BudgetFinding`
                     (an implausible link budget and the input most likely wrong)
===================  ===========================================================================

Every name of ``__all__`` can be imported from here (``from rplearn.analysis import
predict_swarm``); its module is imported on first use (``__init__.pyi``, lazy_loader).
"""

from __future__ import annotations

import lazy_loader

# The public names are those of __init__.pyi, each imported on first use.
__getattr__, __dir__, __all__ = lazy_loader.attach_stub(__name__, __file__)
