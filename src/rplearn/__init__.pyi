# Public names of rplearn: read by type checkers and IDEs, and by lazy_loader.attach_stub in
# __init__.py, which imports each name's module on first use. Only `from .module import name as
# name` lines here (tests/test_public_api.py).
# Each name comes from its layer's package (its own stub says which module defines it).

from .errors import (
    FarFieldError as FarFieldError,
    IdentifiabilityError as IdentifiabilityError,
    InputError as InputError,
    LogFormatError as LogFormatError,
    ModelFileError as ModelFileError,
    PlanError as PlanError,
    RplearnError as RplearnError,
)
from .core import (
    Directions as Directions,
    FitReport as FitReport,
    Scores as Scores,
    fit_joint as fit_joint,
    identifiability as identifiability,
    link_directions as link_directions,
    make_basis as make_basis,
    observed_joint_gain_db as observed_joint_gain_db,
    received_power_dbm as received_power_dbm,
    score as score,
)
from .data import (
    LinkSamples as LinkSamples,
    SyncOptions as SyncOptions,
    SyncResult as SyncResult,
    link_samples as link_samples,
    samples_of as samples_of,
    synchronise as synchronise,
)
from .io import (
    Logs as Logs,
    ReaderOptions as ReaderOptions,
    export_grid as export_grid,
    export_msi as export_msi,
    inspect_logs as inspect_logs,
    read_logs as read_logs,
    read_table as read_table,
    write_table as write_table,
)
from .plan import (
    Campaign as Campaign,
    PlanLimits as PlanLimits,
    check_plan as check_plan,
    paper_campaign as paper_campaign,
)
from .sim import (
    GroundTruth as GroundTruth,
    SimulationConfig as SimulationConfig,
    load_ground_truth as load_ground_truth,
    make_preset as make_preset,
    simulate as simulate,
)
from .models import (
    FittedModel as FittedModel,
    KNNModel as KNNModel,
    MeanModel as MeanModel,
    Model as Model,
    ModelSpec as ModelSpec,
    PatternRegressor as PatternRegressor,
    PatternSet as PatternSet,
    evaluate_models as evaluate_models,
    fit_model as fit_model,
    load_model as load_model,
    scores_markdown as scores_markdown,
)
from .analysis import (
    best_swarm_headings as best_swarm_headings,
    best_yaw as best_yaw,
    identifiability_study as identifiability_study,
    order_sweep as order_sweep,
    pattern_errors_db as pattern_errors_db,
    predict_swarm as predict_swarm,
)
from .viz import (
    plot_coverage as plot_coverage,
    plot_pattern_maps as plot_pattern_maps,
    write_report as write_report,
)
from .workflows import (
    run_demo as run_demo,
)
from ._version import (
    __version__ as __version__,
)
