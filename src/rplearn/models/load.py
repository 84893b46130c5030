"""Loading any model file: the envelope is checked by :mod:`rplearn.io.modelfile`, the payload
is turned into the model of its type."""

from __future__ import annotations

import dataclasses
import os

from rplearn._argtypes import check_types
from rplearn.core.plausible import check_frequency_hz
from rplearn.errors import InputError
from rplearn.io.modelfile import read_model_file
from rplearn.models.base import Model, require_patterns
from rplearn.models.baselines import KNNModel, MeanModel
from rplearn.models.options import FitOptions, is_model_file
from rplearn.models.patterns import PatternSet


@check_types
def load_model(path: str | os.PathLike[str]) -> Model:
    """Load any model file: a PatternSet or a baseline model; its carrier frequency is checked
    (:func:`~rplearn.core.plausible.check_frequency_hz`), and a pattern model's covariance
    (:func:`~rplearn.core.plausible.check_covariance`)."""
    model_type, payload = read_model_file(path)
    name = os.fspath(path)
    model: Model
    if model_type == "patterns":
        model = PatternSet.from_dict(payload, source=name)
    elif model_type == "mean":
        model = MeanModel.from_dict(payload, source=name)
    else:
        model = KNNModel.from_dict(payload, source=name)
    if model.frequency_hz is not None:  # the one frequency check, as for every carrier read
        check_frequency_hz(float(model.frequency_hz), name, None, field="training.frequency_hz")
    return model


def load_priors(options: FitOptions) -> FitOptions:
    """``options`` with its priors as pattern models: model files loaded, every prior checked.

    Raises
    ------
    InputError
        A prior that is not a pattern model (``require_patterns``).
    """
    if not options.priors:
        return options
    priors = {n: load_model(m) if is_model_file(m) else m for n, m in options.priors.items()}
    for node, model in priors.items():
        given = options.priors[node]
        if model.kind != "patterns" and is_model_file(given):
            raise InputError(f"priors: {node}={os.fspath(given)} is a {model.kind} baseline ({model.label}); a prior is a "
                             "pattern model (sh, bg or poly)", param="priors")
        require_patterns(model, f"the prior of node {node}")
    return dataclasses.replace(options, priors=priors)
