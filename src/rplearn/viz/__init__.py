"""Figures and reports: pattern maps, coverage, the paper's charts, a self-contained HTML report.

===================  ===============================================================================
module               public names
===================  ===============================================================================
``plot``             :func:`plot_pattern_maps` (paper Fig. 9), :func:`plot_coverage` (Fig. 8a),
                     :func:`plot_pattern_3d`, :func:`plot_spread_maps` (each node's own-pattern
                     spread) and the figures behind them
``charts``           :func:`plot_rssi_time` (Fig. 8b), :func:`plot_order_sweep` (Fig. 10),
                     :func:`plot_epsilon_sweep` (Fig. 5a), :func:`plot_rank_study` (Fig. 6),
                     :func:`plot_swarm`
``model_figures``     one model on its dataset: :func:`plot_prediction_time` (measured and
                     predicted over time, 90 % band), :func:`plot_residuals`, :func:`plot_polar_cuts`
``images``           :func:`export_pattern_images` (one 3-D image per node)
``interactive``      :func:`pattern_3d_html` (a rotatable 3-D pattern for the report, plotly) and
                     :class:`InteractiveFigure`
``report``           :func:`write_report` with :class:`ReportSection`, :func:`screenshot_report`
===================  ===============================================================================

Every name of ``__all__`` can be imported from here (``from rplearn.viz import plot_coverage``);
its module, and matplotlib, are imported on first use (``__init__.pyi``, lazy_loader).
"""

from __future__ import annotations

import lazy_loader

# The public names are those of __init__.pyi, each imported on first use.
__getattr__, __dir__, __all__ = lazy_loader.attach_stub(__name__, __file__)
