"""Loading any model file: the envelope is checked by :mod:`rplearn.io.modelfile`, the payload
is turned into the model of its type."""

from __future__ import annotations

import os

from rplearn._argtypes import check_types
from rplearn.io.modelfile import read_model_file
from rplearn.models.base import Model
from rplearn.models.baselines import KNNModel, MeanModel
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
