"""Learned patterns against the truth: sample directions per node and the RMS pattern error over covered directions."""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any

import numpy as np

from rplearn._argtypes import check_types
from rplearn.data.tables import LinkSamples
from rplearn.models.patterns import PatternSet

Progress = Callable[[str], None]


@check_types
def node_directions(samples: LinkSamples) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Directions each node saw the other in, over all samples (as tx and as rx) [rad]."""
    d = samples.directions
    out = {}
    for k, node in enumerate(samples.nodes):
        as_tx = samples.tx_index == k
        as_rx = samples.rx_index == k
        out[node] = (np.concatenate([d.az_tx[as_tx], d.az_rx[as_rx]]), np.concatenate([d.el_tx[as_tx], d.el_rx[as_rx]]))
    return out


@check_types
def gauged_nodes(model: PatternSet) -> set[str]:
    """Nodes whose constant the fit could not identify (named in the model's gauge notes)."""
    return {str(n) for g in model.gauge for n in g.get("nodes", [])}


@check_types
def pattern_errors_db(
    model: PatternSet, truth: Any, directions: Mapping[str, tuple[np.ndarray, np.ndarray]], remove_constant: bool | None = None
) -> dict[str, float]:
    """RMS difference between a learned and a true pattern over the covered directions [dB].

    The mean difference is removed first for nodes whose constant the fit could not identify
    (two nodes, or any bipartite link graph; paper Sec. V-A): there the constant is a
    convention, not an error. Nodes in a triangle of links are compared absolutely.
    ``remove_constant`` forces either behaviour for every node.
    """
    gauged = gauged_nodes(model)
    out = {}
    for node, (az, el) in directions.items():
        diff = np.asarray(model.evaluate(node, az, el)) - np.asarray(truth.evaluate(node, az, el))
        if remove_constant or (remove_constant is None and node in gauged):
            diff = diff - diff.mean()
        out[node] = float(np.sqrt(np.mean(diff**2)))
    return out
