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
its module, and pandas or scikit-learn, are imported on first use (``__init__.pyi``, lazy_loader).
"""

from __future__ import annotations

import lazy_loader

# The public names are those of __init__.pyi, each imported on first use.
__getattr__, __dir__, __all__ = lazy_loader.attach_stub(__name__, __file__)
