# Public names of this package: read by type checkers and IDEs, and by lazy_loader.attach_stub
# in __init__.py, which imports each name's module on first use. Only `from .module import name
# as name` lines here (tests/test_public_api.py).

from .base import Model as Model
from .base import model_frequency_hz as model_frequency_hz
from .base import require_patterns as require_patterns
from .baselines import KNNModel as KNNModel
from .baselines import MeanModel as MeanModel
from .estimators import ANGLE_COLUMNS as ANGLE_COLUMNS
from .estimators import JointKNNRegressor as JointKNNRegressor
from .estimators import MeanRegressor as MeanRegressor
from .estimators import PatternRegressor as PatternRegressor
from .fit import FittedModel as FittedModel
from .fit import evaluate_models as evaluate_models
from .fit import fit_model as fit_model
from .fit import fit_patterns as fit_patterns
from .fit import scores_markdown as scores_markdown
from .fit import solve_patterns as solve_patterns
from .load import load_model as load_model
from .patterns import PatternSet as PatternSet
from .predict import DatasetPrediction as DatasetPrediction
from .predict import FrequencyMismatch as FrequencyMismatch
from .predict import distinct_labels as distinct_labels
from .predict import frequency_mismatch as frequency_mismatch
from .predict import predict_dataset as predict_dataset
from .predict import unlearned_directions as unlearned_directions
from .robust import RobustReport as RobustReport
from .robust import fit_huber as fit_huber
from .spec import DEFAULT_RIDGE_BY_KIND as DEFAULT_RIDGE_BY_KIND
from .spec import MODEL_KINDS as MODEL_KINDS
from .spec import ModelSpec as ModelSpec
from .spec import check_fit_options as check_fit_options
from .spec import default_ridge as default_ridge
from .spec import gauge_of as gauge_of
from .terms import directed_counts as directed_counts
from .terms import regression_inputs as regression_inputs
from .terms import terms_text as terms_text
