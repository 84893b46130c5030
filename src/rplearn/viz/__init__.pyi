# Public names of this package: read by type checkers and IDEs, and by lazy_loader.attach_stub
# in __init__.py, which imports each name's module on first use. Only `from .module import name
# as name` lines here (tests/test_public_api.py).

from .charts import epsilon_sweep_figure as epsilon_sweep_figure
from .charts import order_sweep_figure as order_sweep_figure
from .charts import plot_epsilon_sweep as plot_epsilon_sweep
from .charts import plot_order_sweep as plot_order_sweep
from .charts import plot_rank_study as plot_rank_study
from .charts import plot_rssi_time as plot_rssi_time
from .charts import plot_swarm as plot_swarm
from .charts import rank_study_figure as rank_study_figure
from .charts import rssi_time_figure as rssi_time_figure
from .images import export_pattern_images as export_pattern_images
from .interactive import InteractiveFigure as InteractiveFigure
from .interactive import pattern_3d_figures as pattern_3d_figures
from .interactive import pattern_3d_html as pattern_3d_html
from .interactive import pattern_3d_plotly as pattern_3d_plotly
from .plot import PatternLike as PatternLike
from .plot import PatternSurface as PatternSurface
from .plot import coverage_figure as coverage_figure
from .plot import pattern_3d_figure as pattern_3d_figure
from .plot import pattern_maps_figure as pattern_maps_figure
from .plot import pattern_surface as pattern_surface
from .plot import plot_coverage as plot_coverage
from .plot import plot_pattern_3d as plot_pattern_3d
from .plot import plot_pattern_maps as plot_pattern_maps
from .plot import plot_spread_maps as plot_spread_maps
from .plot import save_figure as save_figure
from .plot import spread_maps_figure as spread_maps_figure
from .plot import uncovered_directions as uncovered_directions
from .report import ReportSection as ReportSection
from .report import ScreenshotError as ScreenshotError
from .report import render_report_html as render_report_html
from .report import screenshot_report as screenshot_report
from .report import write_report as write_report
