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
its module, and matplotlib, are imported on first use (:mod:`rplearn._lazy`).
"""

from __future__ import annotations

from rplearn._lazy import lazy_exports

_NAMES: dict[str, str] = {
    # pattern figures
    "PatternLike": "plot",
    "coverage_figure": "plot",
    "pattern_3d_figure": "plot",
    "pattern_maps_figure": "plot",
    "plot_coverage": "plot",
    "plot_pattern_3d": "plot",
    "plot_pattern_maps": "plot",
    "plot_spread_maps": "plot",
    "spread_maps_figure": "plot",
    "save_figure": "plot",
    # the paper's charts and swarm links
    "epsilon_sweep_figure": "charts",
    "order_sweep_figure": "charts",
    "plot_epsilon_sweep": "charts",
    "plot_order_sweep": "charts",
    "plot_rank_study": "charts",
    "plot_rssi_time": "charts",
    "plot_swarm": "charts",
    "rank_study_figure": "charts",
    "rssi_time_figure": "charts",
    # one model on its dataset
    "plot_polar_cuts": "model_figures",
    "plot_prediction_time": "model_figures",
    "plot_residuals": "model_figures",
    "polar_cuts_figure": "model_figures",
    "prediction_time_figure": "model_figures",
    "residuals_figure": "model_figures",
    # 3-D images
    "export_pattern_images": "images",
    # interactive figures (plotly, imported on first use)
    "InteractiveFigure": "interactive",
    "pattern_3d_figures": "interactive",
    "pattern_3d_html": "interactive",
    "pattern_3d_plotly": "interactive",
    "supported_gain_db": "interactive",
    # pattern surfaces and coverage on a grid
    "PatternSurface": "plot",
    "pattern_surface": "plot",
    "uncovered_directions": "plot",
    # the HTML report
    "ReportSection": "report",
    "ScreenshotError": "report",
    "render_report_html": "report",
    "screenshot_report": "report",
    "write_report": "report",
}

__all__ = sorted(_NAMES)
__getattr__, __dir__ = lazy_exports(__name__, _NAMES)
