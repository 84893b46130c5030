"""The first seconds of a manoeuvre: a unit cut where its information per second peaks.

A long candidate (a library unit, a loop sweep, an orbit of two laps) may teach most of what it
can in its first part, its later part repeating directions already learned. The next-best
ranking (:mod:`rplearn.analysis.manoeuvres`) therefore scores a candidate's prefixes too, and a
prefix that wins is flown as a :class:`PrefixUnit`: the references of the whole unit up to
``cut_s``, then held at the pose reached there (at rest: velocity and acceleration zero). The
vehicle stops where the cut falls and the ranking starts again from there.

The stop is counted: a cut mid-orbit or mid-turn leaves the reference at cruise speed or yaw
rate, and a real vehicle needs time to brake (at the default 1.5 m/s and 1 m/s^2, 1.5 s; a
30-deg/s turn at 60 deg/s^2, 0.5 s). :attr:`PrefixUnit.brake_s` is that time, from the unit's
speed and yaw rate at the cut and its acceleration limits (``accel_m_s2``,
``yaw_accel_deg_s2``; 1 m/s^2 and 60 deg/s^2 for units without them), and it is part of the
prefix's :attr:`~PrefixUnit.duration_s`, so that the ranking's time per manoeuvre, a plan's
clock and the benchmark's flight time all pay it. No samples are taken while braking
(:meth:`PrefixUnit.sample` ends at the cut): the directions seen then are near the cut's, and
counting them would credit a prefix with data its score did not predict.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from numpy.typing import NDArray

from rplearn._argtypes import check_types
from rplearn.errors import InputError
from rplearn.plan.manoeuvres import Candidate
from rplearn.plan.trajectory import UnitReference, sample_times_s

FloatArray = NDArray[np.float64]


@check_types
@dataclass(frozen=True)
class PrefixUnit:
    """The first ``cut_s`` seconds of ``unit`` (module docstring).

    Attributes
    ----------
    unit : ManoeuvreUnit, TrajectoryUnit or GroundPassUnit
        The whole unit (anything with ``nodes``, ``duration_s`` and ``evaluate``).
    cut_s : float
        Where it is cut [s], in ``(0, unit.duration_s]``.
    label, role : str
        The label (default the unit's with ``_first<cut>s``) and role (default the unit's).
    """

    unit: Any
    cut_s: float
    label: str = ""
    role: str = ""

    def __post_init__(self) -> None:
        whole = float(self.unit.duration_s)
        if not (np.isfinite(self.cut_s) and 0.0 < float(self.cut_s) <= whole):
            raise InputError(f"cut_s: expected a time in (0, {whole:g}] s of unit {self.unit.label}, got {self.cut_s!r}",
                             param="cut_s")
        if not self.label:
            object.__setattr__(self, "label", f"{self.unit.label}_first{float(self.cut_s):g}s")
        if not self.role:
            object.__setattr__(self, "role", str(getattr(self.unit, "role", "learning")))

    @property
    def nodes(self) -> tuple[str, ...]:
        """The whole unit's nodes (same order)."""
        return tuple(self.unit.nodes)

    @property
    def brake_s(self) -> float:
        """Time to come to rest after the cut [s] (module docstring): the largest of each
        node's speed over the unit's acceleration limit and yaw rate over its yaw-acceleration
        limit at the cut; 0 at the unit's end (its profile ends at rest)."""
        return braking_s(self.unit, float(self.cut_s))

    @property
    def duration_s(self) -> float:
        """Flight time of the prefix [s]: up to the cut, then braking (:attr:`brake_s`)."""
        return float(self.cut_s) + self.brake_s

    def sample(self, rate_hz: float, t_offset_s: float = 0.0) -> UnitReference:
        """References at ``rate_hz`` [Hz] over the prefix up to its cut (none while braking)."""
        return self.evaluate(sample_times_s(float(self.cut_s), rate_hz), t_offset_s)

    def evaluate(self, t_rel_s: FloatArray, t_offset_s: float = 0.0) -> UnitReference:
        """The whole unit's references at ``t_rel_s`` up to the cut, held at rest after it."""
        t = np.asarray(t_rel_s, np.float64)
        ref = self.unit.evaluate(np.clip(t, 0.0, float(self.cut_s)), t_offset_s)
        after = t > float(self.cut_s)
        vel, acc = ref.velocity_enu_m_s.copy(), ref.accel_enu_m_s2.copy()
        vel[after], acc[after] = 0.0, 0.0
        return replace(ref, unit=self, t_s=t + t_offset_s, velocity_enu_m_s=vel, accel_enu_m_s2=acc)

    def end_poses(self) -> dict[str, tuple[tuple[float, float, float], float]]:
        """Each node's position [m] and heading [deg] at the cut."""
        ref = self.unit.evaluate(np.array([float(self.cut_s)]))
        return {str(n): (tuple(float(v) for v in ref.position_enu_m[0, j]), float(np.degrees(ref.yaw_rad[0, j])))  # type: ignore[misc]
                for j, n in enumerate(self.unit.nodes)}


#: Acceleration limits [m/s^2, deg/s^2] of units that state none (those of a manoeuvre unit's defaults).
DEFAULT_ACCEL_M_S2, DEFAULT_YAW_ACCEL_DEG_S2 = 1.0, 60.0
#: Time step [s] of the yaw rate's finite difference at a cut.
_YAW_STEP_S = 0.01


def braking_s(unit: Any, t_s: float) -> float:
    """Seconds for ``unit``'s nodes to come to rest from their reference speed and yaw rate at
    ``t_s`` [s] into it, at the unit's acceleration limits (:data:`DEFAULT_ACCEL_M_S2`,
    :data:`DEFAULT_YAW_ACCEL_DEG_S2` when it states none); 0 at or after its end."""
    whole = float(unit.duration_s)
    if t_s >= whole:
        return 0.0
    t0 = max(t_s - _YAW_STEP_S, 0.0)
    ref = unit.evaluate(np.array([t0, t_s]))
    speed_m_s = float(np.max(np.linalg.norm(ref.velocity_enu_m_s[1], axis=-1), initial=0.0))
    turn = np.angle(np.exp(1j * (ref.yaw_rad[1] - ref.yaw_rad[0])))  # wrapped to (-pi, pi]
    yaw_rate_deg_s = float(np.degrees(np.max(np.abs(turn), initial=0.0))) / max(t_s - t0, 1e-9)
    accel = float(getattr(unit, "accel_m_s2", DEFAULT_ACCEL_M_S2))
    yaw_accel = float(getattr(unit, "yaw_accel_deg_s2", DEFAULT_YAW_ACCEL_DEG_S2))
    return max(speed_m_s / accel, yaw_rate_deg_s / yaw_accel)


@check_types
def prefix_cuts(n_rows: int, rate_hz: float, parts: int, block_s: float) -> list[int]:
    """Row counts of the prefixes of a manoeuvre sampled at ``rate_hz`` [Hz] (``n_rows`` rows) a
    ranking scores: the whole, and its first ``k / parts`` (``k < parts``), each rounded down to
    whole blocks of ``block_s`` seconds (the drifting error's blocks start with the manoeuvre)
    and at least two blocks long; ``parts=1``: the whole only."""
    if int(parts) != parts or parts < 1:
        raise InputError(f"parts: expected a whole number of at least 1, got {parts!r}", param="parts")
    block = max(int(round(block_s * rate_hz)), 1)
    cuts = {(int(n_rows * k / parts) // block) * block for k in range(1, int(parts))}
    return sorted(c for c in cuts if 2 * block <= c < n_rows) + [int(n_rows)]


@check_types
def cut_candidate(candidate: Candidate, cut_s: float) -> Candidate:
    """A :class:`~rplearn.plan.manoeuvres.Candidate` flown only to ``cut_s`` of its unit: its
    unit a :class:`PrefixUnit`, its name saying so, its moved nodes' poses those at the cut."""
    unit = PrefixUnit(candidate.unit, float(cut_s))
    at = unit.end_poses()
    ends = {n: at[n] for n in candidate.ends}
    whole = float(candidate.unit.duration_s)
    return replace(candidate, name=f"{candidate.name}, its first {float(cut_s):.0f} of {whole:.0f} s", unit=unit, ends=ends)


__all__ = ["DEFAULT_ACCEL_M_S2", "DEFAULT_YAW_ACCEL_DEG_S2", "PrefixUnit", "braking_s", "cut_candidate", "prefix_cuts"]
