"""Loading any model file: the envelope is checked by :mod:`rplearn.io.modelfile`, the payload
is turned into the model of its type."""

from __future__ import annotations

import dataclasses
import os

from rplearn._argtypes import check_types
from rplearn.errors import InputError
from rplearn.io.modelfile import read_model_file
from rplearn.models.base import Model, require_patterns
from rplearn.models.baselines import KNNModel, MeanModel
from rplearn.models.options import FitOptions, is_model_file
from rplearn.models.patterns import PatternSet


@check_types
def load_model(path: str | os.PathLike[str]) -> Model:
    """Load any model file: a PatternSet or a baseline model."""
    model_type, payload = read_model_file(path)
    name = os.fspath(path)
    if model_type == "patterns":
        return PatternSet.from_dict(payload, source=name)
    if model_type == "mean":
        return MeanModel.from_dict(payload, source=name)
    return KNNModel.from_dict(payload, source=name)


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
