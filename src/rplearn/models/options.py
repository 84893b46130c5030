"""One fit request: how a model is learned, as one checked value.

A :class:`FitOptions` holds everything a fit needs besides the model (:class:`ModelSpec`)
and the data: the gauge, the environment term, the link offsets, the loss, whether the
order and smoothing are chosen from the data, and the priors with their level and spread.
It is made once (by ``rplearn fit`` from its flags, or by a Python caller), checked when
made (:meth:`FitOptions.__post_init__`) and against the model (:meth:`FitOptions.check`),
and passed down unchanged: no function below re-reads a flag or re-checks an option.
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from rplearn._argtypes import check_types
from rplearn.core.environment import PathLoss
from rplearn.core.gauge import Gauge
from rplearn.core.lsq.solver import PRIOR_LEVELS
from rplearn.errors import BadValueError, InputError

if TYPE_CHECKING:
    from rplearn.models.spec import ModelSpec

#: The losses a pattern fit may minimise: least squares, or Huber (:mod:`rplearn.models.robust`).
LOSSES: tuple[str, ...] = ("ls", "huber")


@check_types
@dataclass(frozen=True)
class FitOptions:
    """How a model is learned (everything but the model and the data).

    Attributes
    ----------
    gauge : Gauge
        How the constant a two-sided link graph cannot identify is fixed (default: equal
        sphere-mean gains). The legacy ``"equal-mean"`` or ``{"node", "mean_gain_dbi"}`` is
        read by :meth:`Gauge.of`.
    path_loss : PathLoss
        The environment term of pattern models (default free space).
    link_offsets : bool
        Pattern models: learn one electronics offset per link logged in both directions.
    loss : {"ls", "huber"}
        Least squares, or the Huber loss (a pattern model of fixed order, in memory).
    auto : bool
        Choose the order (SH) and the smoothing from the data by cross-validation over
        flight units (:mod:`rplearn.models.auto`).
    priors : mapping of node to model file or pattern model
        With ``auto``: shrink each named node's pattern toward this model's shape.
    prior_std_db : float or None
        How far [dB RMS] the priors may be from the truth (default: learned from their misfit).
    prior_level : {"data", "prior"}
        Where a prior's level comes from: the data (default) or its absolute dBi.

    Raises
    ------
    InputError
        On the first inconsistent option, naming it (``param``).
    """

    gauge: Gauge = field(default_factory=Gauge)
    path_loss: PathLoss = field(default_factory=PathLoss)
    link_offsets: bool = True
    loss: str = "ls"
    auto: bool = False
    priors: Mapping[str, Any] = field(default_factory=dict)
    prior_std_db: float | None = None
    prior_level: str = "data"

    def __post_init__(self) -> None:
        object.__setattr__(self, "gauge", Gauge.of(self.gauge))
        if self.path_loss is None:
            object.__setattr__(self, "path_loss", PathLoss())
        if not isinstance(self.path_loss, PathLoss):
            raise InputError(f"path_loss: expected a PathLoss, got {self.path_loss!r}", param="path_loss")
        # a copy (a plain dict: the options travel to Dask workers, and a read-only proxy does not pickle)
        object.__setattr__(self, "priors", {str(n): m for n, m in dict(self.priors or {}).items()})
        if self.loss not in LOSSES:
            raise BadValueError(f"loss: expected {' or '.join(LOSSES)}, got {self.loss!r}", param="loss")
        if self.prior_level not in PRIOR_LEVELS:
            raise BadValueError(f"prior level: expected {' or '.join(PRIOR_LEVELS)}, got {self.prior_level!r}",
                             param="prior_level")
        for node, prior in self.priors.items():
            if is_model_file(prior) and not os.fspath(prior).strip():
                raise InputError(f"priors: {node}= names no model file; give NODE=MODEL.json", param="priors")
        if self.priors and not self.auto:
            raise InputError("prior: a prior is weighed against the data by the automatic choice; use it with "
                             "order 'auto' (--order auto)", param="prior")
        if self.prior_level != "data" and not self.priors:
            raise InputError("prior_level: it says where a prior's level comes from; give priors too",
                             param="prior_level", related=("priors",))
        if self.prior_std_db is not None and not self.priors:
            raise InputError("prior_std_db: it states how far the prior patterns may be off; give priors too",
                             param="prior_std_db", related=("priors",))
        if self.prior_std_db is not None and not (np.isfinite(self.prior_std_db) and self.prior_std_db > 0):
            raise InputError(f"prior_std_db: expected a positive number of dB, got {self.prior_std_db!r}",
                             param="prior_std_db")
        if self.loss == "huber" and self.auto:
            raise InputError("loss huber: for a pattern model of fixed order (--model sh --order N, bg, poly), "
                             "not an automatic choice or a baseline", param="loss")

    def check(self, spec: ModelSpec) -> None:
        """Refuse options the model ``spec`` cannot honour (the baselines learn no patterns).

        Raises
        ------
        InputError
            Naming the option (``param``).
        """
        if spec.decouples:
            return
        if self.loss == "huber":
            raise InputError("loss huber: for a pattern model of fixed order (--model sh --order N, bg, poly), "
                             "not an automatic choice or a baseline", param="loss")
        if self.auto:
            raise InputError(f"order: 'auto' chooses the order of pattern models (sh, bg, poly), not of {spec.label}",
                             param="order")
        if self.path_loss.kind != "free":
            raise InputError(f"path loss {self.path_loss.kind}: the baselines ({spec.label}) learn no environment "
                             "term; fit them in free space", param="path_loss")
        if self.gauge.node is not None:
            raise InputError(f"gauge_node: not used by {spec.label}, a baseline without patterns", param="gauge_node")

    def prior_files(self) -> list[str]:
        """The priors given as model files (inputs a fit's output may not overwrite; they are
        read by :func:`rplearn.models.load.load_priors`)."""
        return [os.fspath(m) for m in self.priors.values() if is_model_file(m)]


def is_model_file(value: Any) -> bool:
    """Whether a prior is given as a model file (a path) rather than a model."""
    return isinstance(value, str) or hasattr(value, "__fspath__")


__all__ = ["LOSSES", "FitOptions"]
