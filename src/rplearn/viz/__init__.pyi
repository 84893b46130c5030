# Public names of rplearn.viz: read by type checkers and IDEs, and by lazy_loader.attach_stub in
# __init__.py, which imports each name's module on first use. Only `from .module import name as
# name` lines here (tests/test_public_api.py).

from .plot import (
    PatternLike as PatternLike,
    PatternSurface as PatternSurface,
    coverage_figure as coverage_figure,
    pattern_3d_figure as pattern_3d_figure,
    pattern_maps_figure as pattern_maps_figure,
    pattern_surface as pattern_surface,
    plot_coverage as plot_coverage,
    plot_pattern_3d as plot_pattern_3d,
    plot_pattern_maps as plot_pattern_maps,
    plot_spread_maps as plot_spread_maps,
    save_figure as save_figure,
    spread_maps_figure as spread_maps_figure,
    uncovered_directions as uncovered_directions,
)
from .charts import (
    epsilon_sweep_figure as epsilon_sweep_figure,
    order_sweep_figure as order_sweep_figure,
    plot_epsilon_sweep as plot_epsilon_sweep,
    plot_order_sweep as plot_order_sweep,
    plot_rank_study as plot_rank_study,
    plot_rssi_time as plot_rssi_time,
    plot_swarm as plot_swarm,
    rank_study_figure as rank_study_figure,
    rssi_time_figure as rssi_time_figure,
)
from .images import (
    export_pattern_images as export_pattern_images,
)
from .interactive import (
    InteractiveFigure as InteractiveFigure,
    pattern_3d_figures as pattern_3d_figures,
    pattern_3d_html as pattern_3d_html,
    pattern_3d_plotly as pattern_3d_plotly,
)
from .report import (
    ReportSection as ReportSection,
    ScreenshotError as ScreenshotError,
    render_report_html as render_report_html,
    screenshot_report as screenshot_report,
    write_report as write_report,
)
