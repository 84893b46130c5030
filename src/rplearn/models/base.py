"""What every model kind offers: the :class:`Model` protocol and the helpers built on it.

A model is learned patterns (:class:`~rplearn.models.patterns.PatternSet`) or one of the
paper's baselines (:class:`~rplearn.models.baselines.MeanModel`,
:class:`~rplearn.models.baselines.KNNModel`). Callers use the protocol's attributes instead of
probing a model's class or attributes: ``model.kind == "patterns"`` says whether it decouples
the joint gain into per-node patterns, ``model.frequency_hz`` the carrier it learned at.
"""

from __future__ import annotations

import math
import os
from collections.abc import Mapping
from typing import TYPE_CHECKING, Any, Protocol, runtime_checkable

import numpy as np
from numpy.typing import NDArray

from rplearn._argtypes import check_types
from rplearn.core.plausible import check_frequency_hz, check_one_band, check_same_band
from rplearn.errors import InputError
from rplearn.models.training import TrainingSummary

if TYPE_CHECKING:  # annotations only: the protocol needs no pandas at import time
    from rplearn.data.tables import LinkSamples

@runtime_checkable
class Model(Protocol):
    """A learned model of the joint gain of links (paper eq. 1).

    Attributes
    ----------
    kind : {"patterns", "mean", "knn"}
        ``"patterns"``: one pattern per node (SH, BG, P); the others are baselines.
    label : str
        The paper's label, e.g. ``SH-10``, ``M``, ``NN-400``.
    nodes : tuple of str
        Node ids the model knows.
    frequency_hz : float or None
        Carrier frequency the model learned at [Hz], from its training summary; None when
        the training data did not state it.
    training : TrainingSummary
        Training summary (samples, RMSE [dB], rank, condition number, LTD [s], ...).
    provenance : dict
        Library version, command and parameters that made the model.
    n_params : int
        Parameters of the model (the paper's |phi| column of Table I).
    """

    @property
    def kind(self) -> str: ...

    @property
    def label(self) -> str: ...

    @property
    def nodes(self) -> tuple[str, ...]: ...

    @property
    def frequency_hz(self) -> float | None: ...

    @property
    def training(self) -> TrainingSummary: ...

    @property
    def provenance(self) -> dict[str, Any]: ...

    @property
    def n_params(self) -> int: ...

    def predict_gain(self, samples: LinkSamples) -> NDArray[np.float64]:
        """Joint gain ``G_tx + G_rx`` predicted for every sample [dB]."""
        ...

    def predict_gain_std(self, samples: LinkSamples) -> NDArray[np.float64] | None:
        """Standard error of :meth:`predict_gain` from the coefficients [dB]; None without one."""
        ...

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready payload of the model file (without the checksum envelope)."""
        ...

    def save(self, path: str | os.PathLike[str]) -> None:
        """Write the JSON model file."""
        ...


def frequency_from_training(training: TrainingSummary | Mapping[str, Any]) -> float | None:
    """Carrier frequency recorded in a training summary [Hz] (None: not recorded)."""
    f = TrainingSummary.from_dict(training).frequency_hz
    return None if f is None else float(f)


def learned_frequency_hz(samples: LinkSamples) -> float | None:
    """Carrier frequency to record for a model learned from ``samples``: their median [Hz].

    None when the samples do not state their frequency.
    """
    if samples.frequency_hz is None or len(samples.frequency_hz) == 0:
        return None
    check_one_band(samples.frequency_hz, "the samples")
    return float(np.median(samples.frequency_hz))


@check_types
def model_frequency_hz(model: Model, frequency_hz: float | None = None) -> float:
    """The carrier frequency to use with a model: ``frequency_hz`` if given, else the model's [Hz].

    Raises
    ------
    InputError
        (``param="frequency_hz"``) when neither is known, the frequency is not a radio carrier
        (:func:`~rplearn.core.plausible.check_frequency_hz`), or ``frequency_hz`` is of another
        band than the model's (:func:`~rplearn.core.plausible.check_same_band`).
    """
    f = model.frequency_hz if frequency_hz is None else frequency_hz
    if f is None:
        raise InputError(
            f"the {model.label} model does not state the carrier frequency it learned at; give it (frequency_hz)",
            param="frequency_hz",
        )
    if not (math.isfinite(float(f)) and float(f) > 0):
        raise InputError(f"frequency_hz: expected a positive frequency in Hz, got {f!r}", param="frequency_hz")
    check_frequency_hz(float(f), "frequency_hz")
    if frequency_hz is not None and model.frequency_hz is not None:
        check_same_band(float(frequency_hz), float(model.frequency_hz), "frequency_hz", f"the {model.label} model")
    return float(f)


@check_types
def relative_levels(model: Model) -> bool:
    """Whether ``model`` learned from relative RSSI (``sync --rssi-scale relative``, recorded as
    ``training["rssi_scale"]``): its levels are not dBm."""
    return bool(model.training.get("rssi_scale") == "relative")


@check_types
def require_calibrated(model: Model, purpose: str) -> None:
    """Refuse a model learned from relative RSSI (:func:`relative_levels`) where absolute
    received powers [dBm] are asked for."""
    if relative_levels(model):
        raise InputError(f"tx_power_dbm: the {model.label} model learned from relative RSSI (sync --rssi-scale relative): "
                         f"its levels are not dBm, so {purpose} cannot give received powers; learn from calibrated RSSI",
                         param="tx_power_dbm")


@check_types
def require_patterns(model: Model, purpose: str) -> None:
    """Refuse a baseline where per-node patterns are needed.

    Parameters
    ----------
    model : Model
    purpose : str
        What needs the patterns, for the message (e.g. ``"predicting a swarm's links"``).

    Raises
    ------
    InputError
        When ``model.kind`` is not ``"patterns"``.
    """
    if model.kind != "patterns":
        raise InputError(f"{purpose} needs a pattern model (sh, bg or poly), not {model.label!r}")
