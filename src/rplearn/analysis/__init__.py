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
predict_swarm``); its module is imported on first use (:mod:`rplearn._lazy`).
"""

from __future__ import annotations

from rplearn._lazy import lazy_exports

_NAMES: dict[str, str] = {
    # model order
    "SweepResult": "sweep",
    "order_sweep": "sweep",
    # identifiability (paper Sec. V-A)
    "IdentifiabilityStudy": "identifiability",
    "identifiability_study": "identifiability",
    "study_antennas": "identifiability",
    # learned against true patterns
    "gauged_nodes": "pattern_error",
    "node_directions": "pattern_error",
    "pattern_errors_db": "pattern_error",
    # decoupling certificate
    "DecouplingCertificate": "decoupling",
    "certify": "decoupling",
    "decoupling_certificate": "decoupling",
    # headings
    "OrientationResult": "headings",
    "SwarmHeadings": "headings",
    "best_swarm_headings": "headings",
    "best_yaw": "headings",
    "SwarmHeadingOptions": "heading_options",
    "YawOptions": "heading_options",
    # clock offsets
    "ClockOffsetEstimate": "clock",
    "estimate_clock_offset": "clock",
    "heading_gain_tables": "headings",
    "heading_std_tables": "headings",
    # swarm links over time
    "DEFAULT_MIN_RSSI_DBM": "swarm",
    "SwarmOptions": "swarm",
    "SwarmPrediction": "swarm",
    "connectivity_over_time": "swarm",
    "predict_swarm": "swarm",
    "spanning_bottleneck": "swarm",
    # plausible link budgets
    "BudgetFinding": "budget",
    "LinkSummary": "budget",
    "budget_findings": "budget",
    "check_dataset_budget": "budget",
    "check_fit_budget": "budget",
    "link_summaries": "budget",
}

__all__ = sorted(_NAMES)
__getattr__, __dir__ = lazy_exports(__name__, _NAMES)
