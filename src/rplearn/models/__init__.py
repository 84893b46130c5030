"""Learned models of the joint gain of links: per-node patterns and the paper's baselines.

===============  ===============================================================================
module           public names
===============  ===============================================================================
``base``         :class:`Model`, the protocol every model kind implements (``predict_gain``,
                 ``predict_gain_std``, ``save``, ...); :func:`model_frequency_hz`
``spec``         :class:`ModelSpec` (``"sh-10"``, ``"bg-7"``, ``"p-12"``, ``"nn-400"``, ``"m"``)
``options``      :class:`FitOptions`, how a model is learned (with :class:`Gauge`); checked once
``training``     :class:`TrainingSummary`, what a fit says about itself (``model.training``)
``patterns``     :class:`PatternSet`, one radiation pattern per node
``baselines``    :class:`MeanModel` (M), :class:`KNNModel` (NN-k)
``fit``          :func:`fit_model` -> :class:`FittedModel`, :func:`fit_patterns`,
                 :func:`evaluate_models` (Table I), :func:`scores_markdown`
``predict``      :func:`predict_dataset` -> :class:`DatasetPrediction`, :func:`unlearned_directions`
``terms``        the environment term and link offsets learned beside the patterns:
                 :func:`regression_inputs`, :func:`directed_counts`, :func:`terms_text`
``load``         :func:`load_model` (any model file)
``estimators``   scikit-learn estimators :class:`PatternRegressor`, :class:`MeanRegressor`,
                 :class:`JointKNNRegressor`
===============  ===============================================================================

Every name of ``__all__`` can be imported from here (``from rplearn.models import fit_model``);
its module, and pandas or scikit-learn, are imported on first use (:mod:`rplearn._lazy`).
"""

from __future__ import annotations

from rplearn._lazy import lazy_exports

_NAMES: dict[str, str] = {
    # what every model offers
    "Model": "base",
    "model_frequency_hz": "base",
    "require_patterns": "base",
    # naming a model
    "DEFAULT_RIDGE_BY_KIND": "spec",
    "MODEL_KINDS": "spec",
    "ModelSpec": "spec",
    "check_fit_options": "spec",
    # how a model is learned (one fit request)
    "FitOptions": "options",
    "LOSSES": "options",
    "TrainingSummary": "training",
    "default_ridge": "spec",
    # model kinds
    "KNNModel": "baselines",
    "MeanModel": "baselines",
    "PatternSet": "patterns",
    # learning, evaluating, predicting, loading
    "FittedModel": "fit",
    "evaluate_models": "fit",
    "fit_model": "fit",
    "fit_huber": "robust",
    "RobustReport": "robust",
    "fit_patterns": "fit",
    "scores_markdown": "fit",
    "solve_patterns": "fit",
    "DatasetPrediction": "predict",
    "predict_dataset": "predict",
    "FrequencyMismatch": "predict",
    "frequency_mismatch": "predict",
    "distinct_labels": "predict",
    "unlearned_directions": "predict",
    "directed_counts": "terms",
    "regression_inputs": "terms",
    "terms_text": "terms",
    "load_model": "load",
    # scikit-learn estimators
    "ANGLE_COLUMNS": "estimators",
    "JointKNNRegressor": "estimators",
    "MeanRegressor": "estimators",
    "PatternRegressor": "estimators",
}

__all__ = sorted(_NAMES)
__getattr__, __dir__ = lazy_exports(__name__, _NAMES)
