"""The reliability diagram of predicted availability (``rplearn report --sensitivity``).

Per bin of predicted availability (:class:`rplearn.core.reliability.ReliabilityTable`), the
observed share of up samples against the bin's mean prediction: a reliable forecast lies on
the diagonal; below it, the model promised a link more often than it was up. A lower panel
gives the samples per bin (log scale), so that a bin of three samples is not read as a trend.
"""

from __future__ import annotations

import os

import numpy as np
from matplotlib.figure import Figure

from rplearn._argtypes import check_types
from rplearn.core.reliability import ReliabilityTable
from rplearn.viz.plot import new_figure, save_figure


@check_types
def reliability_figure(table: ReliabilityTable, label: str, sensitivity_dbm: float, skill: float | None = None) -> Figure:
    """The reliability diagram of ``table`` (module docstring) for the model ``label`` at
    ``sensitivity_dbm`` [dBm], its Brier skill in the title when given."""
    fig = new_figure(5.0, 5.6)
    top, bottom = fig.subplots(2, 1, height_ratios=[3, 1], sharex=True)
    top.plot([0, 1], [0, 1], color="0.6", linestyle="--", linewidth=1, label="perfectly reliable")
    filled = table.count > 0
    top.plot(table.mean_forecast[filled], table.observed_share[filled], "o-", color="tab:blue", label=label)
    top.set_xlim(0, 1)
    top.set_ylim(-0.02, 1.02)
    top.set_ylabel("observed share up")
    top.legend(loc="upper left", fontsize=8)
    title = f"availability at {sensitivity_dbm:.1f} dBm"
    top.set_title(title + (f", Brier skill {skill:.2f}" if skill is not None and np.isfinite(skill) else ""), fontsize=10)
    centres = 0.5 * (table.edges[:-1] + table.edges[1:])
    bottom.bar(centres, table.count, width=np.diff(table.edges) * 0.9, color="tab:blue", alpha=0.6)
    if np.any(table.count > 0):
        bottom.set_yscale("log")
    bottom.set_xlabel("predicted availability P(RSSI >= sensitivity)")
    bottom.set_ylabel("samples")
    return fig


@check_types
def plot_reliability(path: str | os.PathLike[str], table: ReliabilityTable, label: str, sensitivity_dbm: float,
                     skill: float | None = None) -> str:
    """Write :func:`reliability_figure` as a PNG; return the path."""
    caption = (f"Reliability of the predicted availability at {sensitivity_dbm:g} dBm on the held-out samples: per bin "
               "of predicted P(RSSI >= sensitivity), the share of samples that were up (a packet at or above it; an "
               "outage event counts as down) against the bin's mean prediction; the diagonal is a reliable forecast. "
               "Below: samples per bin.")
    return save_figure(reliability_figure(table, label, sensitivity_dbm, skill), path, caption)


__all__ = ["plot_reliability", "reliability_figure"]
