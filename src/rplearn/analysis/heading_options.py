"""The options of the heading searches of :mod:`rplearn.analysis.headings`, as checked values.

:class:`YawOptions` is how :func:`~rplearn.analysis.headings.best_yaw` searches one link,
:class:`SwarmHeadingOptions` how :func:`~rplearn.analysis.headings.best_swarm_headings`
searches a hovering swarm. Each is checked when made (``__post_init__``): a bad value raises
an :class:`~rplearn.errors.InputError` naming the field.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from rplearn._argtypes import check_types, is_finite_real
from rplearn.core.plausible import check_frequency_hz
from rplearn.errors import BadValueError, InputError

#: Default of :attr:`YawOptions.caution_z`: headings are ranked by the 10% lower bound of their
#: gain (prediction minus 1.28 standard errors of each end).
CAUTION_Z = 1.28


def _check_step(step_deg: Any) -> None:
    """A positive number (its range is checked by :func:`~rplearn.analysis.headings.yaw_grid_deg`)."""
    if not (is_finite_real(step_deg) and step_deg > 0):
        raise InputError(f"step_deg: expected a positive number of degrees, got {step_deg!r}", param="step_deg")


def check_optional_frequency(frequency_hz: Any) -> None:
    """The one frequency check (:func:`~rplearn.core.plausible.check_frequency_hz`), None allowed."""
    if frequency_hz is not None:
        if not is_finite_real(frequency_hz):
            raise InputError(f"frequency_hz: expected a positive frequency in Hz, got {frequency_hz!r}", param="frequency_hz")
        check_frequency_hz(float(frequency_hz), "frequency_hz")


def _check_risk(sensitivity_dbm: Any, min_availability: Any) -> None:
    """A finite sensitivity [dBm], and a required availability in (0, 1) only with one."""
    if sensitivity_dbm is not None and not is_finite_real(sensitivity_dbm):
        raise InputError(f"sensitivity_dbm: expected a finite level in dBm, got {sensitivity_dbm!r}",
                         param="sensitivity_dbm")
    if min_availability is not None:
        if not (is_finite_real(min_availability) and 0 < min_availability < 1):
            raise InputError(f"min_availability: expected a probability between 0 and 1, got {min_availability!r}",
                             param="min_availability")
        if sensitivity_dbm is None:
            raise InputError("min_availability: an availability needs the radio's sensitivity (sensitivity_dbm)",
                             param="sensitivity_dbm")


@check_types
@dataclass(frozen=True)
class YawOptions:
    """How :func:`~rplearn.analysis.headings.best_yaw` chooses the heading(s) of one link.

    Attributes
    ----------
    tx_yaw_deg, rx_yaw_deg : float
        Current yaws, ENU counter-clockwise from east [deg]; a drone that may not turn keeps it.
    step_deg : float
        Yaw grid [deg].
    tx_power_dbm : float, optional
        Transmit power [dBm]; given, the result carries the received power before and after
        (not for a model learned from relative RSSI, whose levels are not dBm: the joint gain).
    frequency_hz : float, optional
        Carrier for the received power [Hz]; by default the one the model was learned at.
    caution_z : float
        Standard errors subtracted when ranking (:data:`CAUTION_Z`: the 10% lower bound); 0
        ranks by the prediction alone. Ignored for a model without a covariance.
    sensitivity_dbm : float, optional
        Rank by the link's availability ``P(RSSI >= sensitivity_dbm)`` instead (needs
        ``tx_power_dbm``; :mod:`rplearn.analysis.risk_headings`).
    min_availability : float, optional
        With ``sensitivity_dbm``: the strongest heading whose availability reaches this (the
        most available one when none does).

    Raises
    ------
    InputError
        On the first invalid option, naming it (``param``).
    """

    tx_yaw_deg: float = 0.0
    rx_yaw_deg: float = 0.0
    step_deg: float = 1.0
    tx_power_dbm: float | None = None
    frequency_hz: float | None = None
    caution_z: float = CAUTION_Z
    sensitivity_dbm: float | None = None
    min_availability: float | None = None

    def __post_init__(self) -> None:
        _check_risk(self.sensitivity_dbm, self.min_availability)
        if self.sensitivity_dbm is not None and self.tx_power_dbm is None:
            raise InputError("sensitivity_dbm: ranking by availability needs the transmit power (tx_power_dbm)",
                             param="tx_power_dbm")
        for name in ("tx_yaw_deg", "rx_yaw_deg"):
            if not is_finite_real(getattr(self, name)):
                raise InputError(f"{name}: expected a finite number of degrees, got {getattr(self, name)!r}",
                                 param=name)
        _check_step(self.step_deg)
        if self.tx_power_dbm is not None and not is_finite_real(self.tx_power_dbm):
            raise InputError(f"tx_power_dbm: expected a finite number of dBm, got {self.tx_power_dbm!r}",
                             param="tx_power_dbm")
        check_optional_frequency(self.frequency_hz)
        if not (is_finite_real(self.caution_z) and self.caution_z >= 0):
            raise InputError(f"caution_z: expected a finite number >= 0, got {self.caution_z!r}", param="caution_z")


@check_types
@dataclass(frozen=True)
class SwarmHeadingOptions:
    """How :func:`~rplearn.analysis.headings.best_swarm_headings` searches a hovering swarm's yaws.

    Attributes
    ----------
    frequency_hz : float, optional
        Carrier [Hz]; by default the one the model was learned at.
    pattern_of : mapping, optional
        Drone -> learned node whose antenna it carries (default: its own id).
    start_yaw_deg : mapping, optional
        Current yaws, ENU counter-clockwise from east [deg] (default 0).
    fixed : sequence of str
        Drones that keep their current yaw.
    step_deg : float
        Yaw grid [deg].
    max_sweeps, restarts : int
        Limits of the coordinate ascent (four drones or more; any number when ranking by
        availability).
    sensitivity_dbm : float, optional
        Rank by availability: of the weakest link of the most available spanning tree
        (:mod:`rplearn.analysis.risk_headings`), instead of the bottleneck RSSI.
    min_availability : float, optional
        With ``sensitivity_dbm``: the largest bottleneck RSSI whose availability reaches this.

    Raises
    ------
    InputError
        On the first invalid option, naming it (``param``).
    """

    frequency_hz: float | None = None
    pattern_of: Mapping[str, str] | None = None
    start_yaw_deg: Mapping[str, float] | None = None
    fixed: Sequence[str] = ()
    step_deg: float = 5.0
    max_sweeps: int = 20
    restarts: int = 8
    sensitivity_dbm: float | None = None
    min_availability: float | None = None

    def __post_init__(self) -> None:
        _check_risk(self.sensitivity_dbm, self.min_availability)
        check_optional_frequency(self.frequency_hz)
        for name in ("pattern_of", "start_yaw_deg"):
            value = getattr(self, name)
            if value is not None and not isinstance(value, Mapping):
                raise InputError(f"{name}: expected a mapping keyed by drone, got {value!r}", param=name)
        if isinstance(self.fixed, str):
            raise InputError(f"fixed: expected a sequence of drone ids, got the string {self.fixed!r}", param="fixed")
        object.__setattr__(self, "fixed", tuple(str(d) for d in self.fixed))
        _check_step(self.step_deg)
        for name, least in (("max_sweeps", 1), ("restarts", 0)):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < least:
                raise InputError(f"{name}: expected an integer of at least {least}, got {value!r}", param=name)


def check_turn(turn: str) -> None:
    """Refuse a ``turn`` of :func:`rplearn.analysis.headings.best_yaw` other than ``tx``, ``rx`` or ``both``."""
    if turn not in ("tx", "rx", "both"):
        raise BadValueError(f"turn: expected 'tx', 'rx' or 'both', got {turn!r}", param="turn")


__all__ = ["CAUTION_Z", "SwarmHeadingOptions", "YawOptions", "check_turn"]
