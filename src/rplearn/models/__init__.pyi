# Public names of rplearn.models: read by type checkers and IDEs, and by lazy_loader.attach_stub in
# __init__.py, which imports each name's module on first use. Only `from .module import name as
# name` lines here (tests/test_public_api.py).

from .base import (
    Model as Model,
    model_frequency_hz as model_frequency_hz,
    require_patterns as require_patterns,
)
from .spec import (
    DEFAULT_RIDGE_BY_KIND as DEFAULT_RIDGE_BY_KIND,
    MODEL_KINDS as MODEL_KINDS,
    ModelSpec as ModelSpec,
    check_fit_options as check_fit_options,
    default_ridge as default_ridge,
    gauge_of as gauge_of,
)
from .baselines import (
    KNNModel as KNNModel,
    MeanModel as MeanModel,
)
from .patterns import (
    PatternSet as PatternSet,
)
from .fit import (
    FittedModel as FittedModel,
    evaluate_models as evaluate_models,
    fit_model as fit_model,
    fit_patterns as fit_patterns,
    scores_markdown as scores_markdown,
    solve_patterns as solve_patterns,
)
from .robust import (
    RobustReport as RobustReport,
    fit_huber as fit_huber,
)
from .predict import (
    DatasetPrediction as DatasetPrediction,
    FrequencyMismatch as FrequencyMismatch,
    distinct_labels as distinct_labels,
    frequency_mismatch as frequency_mismatch,
    predict_dataset as predict_dataset,
    unlearned_directions as unlearned_directions,
)
from .terms import (
    directed_counts as directed_counts,
    regression_inputs as regression_inputs,
    terms_text as terms_text,
)
from .load import (
    load_model as load_model,
)
from .estimators import (
    ANGLE_COLUMNS as ANGLE_COLUMNS,
    JointKNNRegressor as JointKNNRegressor,
    MeanRegressor as MeanRegressor,
    PatternRegressor as PatternRegressor,
)
