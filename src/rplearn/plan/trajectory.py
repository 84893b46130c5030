"""Calibration trajectory units: references, summaries and limits (paper Sec. IV-A, Fig. 3).

A trajectory *unit*: two drones start ``d`` apart at height ``z0`` with initial heading
``psi0``, and fly a vertical circle of diameter ``d`` centred between them, always at opposite
ends of a diameter, so they stay ``d`` apart and the line between them turns through a full
revolution per loop: the elevation of each drone seen from the other sweeps -90..90 deg. After
each of ``n`` loops the first drone turns by ``360/n`` deg; once it has swept all headings the
second drone does the same (``2 n`` loops in all). Between loops both drones hover at the start
points while the turning drone yaws.

:func:`summarize_unit` tells what a unit asks of the drones (speed, acceleration, flight time,
yaw rate) and refuses it when a :class:`PlanLimits` limit is exceeded. Several units make a
campaign (:mod:`rplearn.plan.campaign`).

World frame ENU [m]; the circle lies in the vertical plane through the unit's centre along the
world azimuth ``line_azimuth_deg`` (0 = east). Yaw is ENU, counter-clockwise from east [deg in
files, rad in arrays named ``_rad``]; a drone with heading ``psi0 = 0`` relative to the line
faces along the line (the first drone then faces the second at the start).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd
from numpy.typing import NDArray

from rplearn._argtypes import check_types
from rplearn.errors import InputError, PlanError

FloatArray = NDArray[np.float64]

#: Standard gravity [m/s^2].
G_M_S2 = 9.80665

#: What brings each limited quantity down, naming the :class:`TrajectoryUnit` fields (the
#: keyword arguments of :func:`~rplearn.plan.campaign.paper_campaign`) to change (from
#: :meth:`TrajectoryUnit._loop_profile`, :func:`summarize_unit` and
#: :attr:`TrajectoryUnit.duration_s`).
_REMEDIES: dict[str, str] = {
    # peak speed = min(speed, sqrt(accel * pi * d))
    "max_speed_m_s": "lower the cruise speed (speed_m_s)",
    # |a| = hypot(accel, v^2 / (d / 2)): slower, or a wider circle
    "max_accel_m_s2": "lower the cruise speed (speed_m_s) or widen the circle (distance_m)",
    # 2 n loops of pi d / v each, plus the turns
    "max_flight_time_s": "fly fewer headings (n_loops), a smaller circle (distance_m) or faster (speed_m_s)",
    # peak yaw rate = pi/2 * yaw_rate_deg_s
    "max_yaw_rate_deg_s": "lower the turn rate (yaw_rate_deg_s)",
}




def sample_times_s(duration_s: float, rate_hz: float) -> NDArray[np.float64]:
    """Times of a unit's references sampled at ``rate_hz`` [Hz]: from 0 every ``1 / rate_hz``
    up to its end ``duration_s`` [s] (included when on the grid).

    Parameters
    ----------
    duration_s : float
        The unit's duration [s].
    rate_hz : float
        The sample rate [Hz].

    Returns
    -------
    1-D float64 array
        The times [s], increasing from 0.

    Raises
    ------
    InputError
        When ``rate_hz`` is not positive (``param="rate_hz"``).
    """
    if not rate_hz > 0:
        raise InputError(f"rate_hz: expected a positive sample rate, got {rate_hz!r}", param="rate_hz")
    t = np.arange(0.0, duration_s + 0.5 / rate_hz, 1.0 / rate_hz)
    return t[t <= duration_s + 1e-9]


def check_unit_fields(unit: Any, positive: tuple[str, ...]) -> None:
    """Checks every kind of unit shares: two different node ids (stored as ``str``) and the
    named fields positive and finite."""
    nodes = unit.nodes
    if len(nodes) != 2 or str(nodes[0]) == str(nodes[1]):
        raise InputError(f"unit nodes: expected two different node ids, got {nodes!r}", param="nodes")
    object.__setattr__(unit, "nodes", (str(nodes[0]), str(nodes[1])))
    for name in positive:
        v = float(getattr(unit, name))
        if not (np.isfinite(v) and v > 0):
            raise InputError(f"{name}: expected a positive finite number, got {v!r}", param=name)


@check_types
@dataclass(frozen=True)
class TrajectoryUnit:
    """One calibration trajectory unit for a pair of drones (paper Sec. IV-A).

    Attributes
    ----------
    nodes : (str, str)
        The first drone (sweeps headings first) and the second.
    psi0_deg : float
        Initial heading of both drones relative to the line between them [deg].
    distance_m : float
        Distance between the drones = diameter of the circle ``d`` [m].
    height_m : float
        Height of the circle's centre (= start height) ``z0`` [m].
    n_loops : int
        Headings per drone ``n``; the heading step is ``360/n`` deg; the unit flies ``2 n`` loops.
    speed_m_s : float
        Cruise speed along the circle [m/s].
    accel_m_s2 : float
        Tangential acceleration used to start and stop each loop [m/s^2].
    yaw_rate_deg_s : float
        Mean yaw rate of the heading changes between loops [deg/s]; the turns follow a cosine
        profile whose peak rate is ``pi/2`` times this.
    center_enu_m : (float, float)
        Horizontal position (east, north) of the circle's centre [m].
    line_azimuth_deg : float
        World azimuth (ENU, ccw from east) of the line from the first to the second drone at
        the start [deg].
    label : str
        Unit label written in the ``unit`` column of signal logs.
    role : str
        ``"learning"`` or ``"testing"``.
    """

    nodes: tuple[str, str] = ("A", "B")
    psi0_deg: float = 0.0
    distance_m: float = 10.0
    height_m: float = 20.0
    n_loops: int = 5
    speed_m_s: float = 1.5
    accel_m_s2: float = 1.0
    yaw_rate_deg_s: float = 30.0
    center_enu_m: tuple[float, float] = (0.0, 0.0)
    line_azimuth_deg: float = 0.0
    label: str = ""
    role: str = "learning"

    def __post_init__(self) -> None:
        check_unit_fields(self, ("distance_m", "height_m", "speed_m_s", "accel_m_s2", "yaw_rate_deg_s"))
        if self.height_m <= self.distance_m / 2.0:
            raise InputError(
                f"height_m: expected more than half the distance ({self.distance_m / 2:g} m) "
                f"so the circle stays above ground, got {float(self.height_m):g}",
                param="height_m",
            )
        if int(self.n_loops) != self.n_loops or self.n_loops < 1:
            raise InputError(f"n_loops: expected a positive integer, got {self.n_loops!r}", param="n_loops")
        if self.role not in ("learning", "testing"):
            raise InputError(f"unit role: expected 'learning' or 'testing', got {self.role!r}", param="role")
        if not self.label:
            object.__setattr__(
                self, "label", f"{self.role[:5]}_{self.nodes[0]}{self.nodes[1]}_{self.psi0_deg:g}"
            )

    @property
    def heading_step_deg(self) -> float:
        """Heading change after each loop, ``360 / n`` [deg]."""
        return 360.0 / self.n_loops

    def heading_schedule_deg(self) -> FloatArray:
        """Headings relative to the line of both drones during each of the ``2 n`` loops [deg].

        Returns
        -------
        ndarray, shape (2 n, 2)
            Column 0 the first drone, column 1 the second. Loops ``0..n-1``: the first drone
            flies ``psi0 + i 360/n``, the second ``psi0``; loops ``n..2n-1``: the first is back
            at ``psi0`` (it completes the turn to 360) and the second flies ``psi0 + i 360/n``.
        """
        n = int(self.n_loops)
        steps = self.psi0_deg + self.heading_step_deg * np.arange(n)
        first = np.concatenate([steps, np.full(n, self.psi0_deg)])
        second = np.concatenate([np.full(n, self.psi0_deg), steps])
        return np.stack([first, second], axis=1)

    def _loop_profile(self) -> tuple[float, float, float, float]:
        """Trapezoidal arc-length profile of one loop: (length, t_ramp, t_cruise, peak speed)."""
        length = np.pi * self.distance_m
        v, a = self.speed_m_s, self.accel_m_s2
        if v * v / a >= length:  # triangular: never reaches cruise speed
            v = float(np.sqrt(a * length))
            return length, v / a, 0.0, v
        t_ramp = v / a
        return length, t_ramp, (length - v * v / a) / v, v

    def _segments(self) -> list[tuple[str, float, int]]:
        """Timeline: ("loop", duration, loop index) and ("turn", duration, loop index before)."""
        _, t_ramp, t_cruise, _ = self._loop_profile()
        t_loop = 2.0 * t_ramp + t_cruise
        sched = self.heading_schedule_deg()
        segs: list[tuple[str, float, int]] = []
        for i in range(sched.shape[0]):
            segs.append(("loop", t_loop, i))
            if i + 1 < sched.shape[0]:
                dpsi = np.abs(_turn_deg(sched[i], sched[i + 1]))
                t_turn = float(np.max(dpsi)) / self.yaw_rate_deg_s
                # a turn of at least 1 s lets the drones settle between loops
                segs.append(("turn", max(t_turn, 1.0), i))
        return segs

    @property
    def duration_s(self) -> float:
        """Flight time of the unit, loops and turns [s] (take-off and landing excluded)."""
        return float(sum(s[1] for s in self._segments()))

    @property
    def path_length_m(self) -> float:
        """Path length flown by each drone [m] (``2 n`` circumferences ``pi d``)."""
        return float(2 * self.n_loops * np.pi * self.distance_m)

    def sample(self, rate_hz: float, t_offset_s: float = 0.0) -> UnitReference:
        """Time-parametrised references of both drones, sampled at ``rate_hz``.

        Parameters
        ----------
        rate_hz : float
            Sample rate [Hz].
        t_offset_s : float
            Time of the unit's start [s].
        """
        return self.evaluate(sample_times_s(self.duration_s, rate_hz), t_offset_s)

    def evaluate(self, t_rel_s: NDArray[np.float64], t_offset_s: float = 0.0) -> UnitReference:
        """References of both drones at times ``t_rel_s`` since the unit's start [s]."""
        t_rel = np.clip(np.asarray(t_rel_s, np.float64), 0.0, self.duration_s)
        length, t_ramp, t_cruise, v_peak = self._loop_profile()
        a = v_peak / t_ramp
        t_loop = 2.0 * t_ramp + t_cruise
        segs = self._segments()
        starts = np.concatenate([[0.0], np.cumsum([s[1] for s in segs])[:-1]])
        kinds = np.array([s[0] == "loop" for s in segs])
        durs = np.array([s[1] for s in segs])
        loop_idx = np.array([s[2] for s in segs])
        k = np.clip(np.searchsorted(starts, t_rel, side="right") - 1, 0, len(segs) - 1)
        tau = t_rel - starts[k]
        in_loop = kinds[k]
        # arc length s(tau), speed, tangential acceleration within a loop
        tl = np.where(in_loop, np.clip(tau, 0.0, t_loop), 0.0)
        s = np.where(
            tl < t_ramp,
            0.5 * a * tl**2,
            np.where(
                tl < t_ramp + t_cruise,
                0.5 * a * t_ramp**2 + v_peak * (tl - t_ramp),
                length - 0.5 * a * np.maximum(t_loop - tl, 0.0) ** 2,
            ),
        )
        sd = np.where(tl < t_ramp, a * tl, np.where(tl < t_ramp + t_cruise, v_peak, a * np.maximum(t_loop - tl, 0)))
        sdd = np.where(tl < t_ramp, a, np.where(tl < t_ramp + t_cruise, 0.0, -a))
        sd = np.where(in_loop, sd, 0.0)
        sdd = np.where(in_loop, sdd, 0.0)
        s = np.where(in_loop, s, 0.0)
        r = self.distance_m / 2.0
        phi = s / r  # angle travelled on the circle [rad]
        phid = sd / r
        phidd = sdd / r
        # headings: piecewise constant during loops, cosine blend during turns
        sched = np.radians(self.heading_schedule_deg())
        cur = sched[loop_idx[k]]
        nxt = sched[np.minimum(loop_idx[k] + 1, sched.shape[0] - 1)]
        dturn = np.radians(_turn_deg(np.degrees(cur), np.degrees(nxt)))
        frac = np.where(in_loop, 0.0, np.clip(tau / durs[k], 0.0, 1.0))
        blend = 0.5 - 0.5 * np.cos(np.pi * frac)
        rel_yaw = cur + dturn * blend[:, None]
        line_az = np.radians(self.line_azimuth_deg)
        u = np.array([np.cos(line_az), np.sin(line_az), 0.0])  # horizontal unit along the line
        zhat = np.array([0.0, 0.0, 1.0])
        centre = np.array([self.center_enu_m[0], self.center_enu_m[1], self.height_m])
        pos = np.empty((t_rel.size, 2, 3))
        vel = np.empty_like(pos)
        acc = np.empty_like(pos)
        # first drone starts at angle pi (behind the centre), the second at 0 (ahead); both
        # advance by phi, so the first is always opposite the second.
        for j, phase in enumerate((np.pi, 0.0)):
            ang = phase + phi
            c, sn = np.cos(ang), np.sin(ang)
            pos[:, j, :] = centre + r * (c[:, None] * u + sn[:, None] * zhat)
            dp = r * (-sn[:, None] * u + c[:, None] * zhat)  # d pos / d ang
            ddp = -r * (c[:, None] * u + sn[:, None] * zhat)
            vel[:, j, :] = dp * phid[:, None]
            acc[:, j, :] = dp * phidd[:, None] + ddp * (phid**2)[:, None]
        yaw = np.angle(np.exp(1j * (rel_yaw + line_az)))
        return UnitReference(
            unit=self,
            t_s=t_rel + t_offset_s,
            position_enu_m=pos,
            velocity_enu_m_s=vel,
            accel_enu_m_s2=acc,
            yaw_rad=yaw,
            loop_index=np.where(in_loop, loop_idx[k], -1),
        )


def _turn_deg(from_deg: FloatArray, to_deg: FloatArray) -> FloatArray:
    """Signed heading change from one heading to the next, taken forward (>= 0) [deg].

    Heading steps of the schedule are always positive turns, so ``psi0 + (n-1) 360/n`` to
    ``psi0`` is a forward turn of ``360/n`` that completes the revolution.
    """
    return np.mod(np.asarray(to_deg, np.float64) - np.asarray(from_deg, np.float64), 360.0)


@check_types
@dataclass(frozen=True)
class UnitReference:
    """References of a unit's two drones sampled in time.

    Attributes
    ----------
    unit : TrajectoryUnit or GroundPassUnit
    t_s : ndarray, shape (n,)
        Times [s].
    position_enu_m, velocity_enu_m_s, accel_enu_m_s2 : ndarray, shape (n, 2, 3)
        Reference position [m], velocity [m/s], acceleration [m/s^2] of (first, second) drone.
    yaw_rad : ndarray, shape (n, 2)
        Reference heading, ENU ccw from east [rad], in (-pi, pi].
    loop_index : ndarray of int, shape (n,)
        Loop being flown, or -1 while turning between loops.
    """

    unit: Any  # TrajectoryUnit, or rplearn.plan.ground.GroundPassUnit
    t_s: FloatArray
    position_enu_m: FloatArray
    velocity_enu_m_s: FloatArray
    accel_enu_m_s2: FloatArray
    yaw_rad: FloatArray
    loop_index: NDArray[np.int_]

    def table(self, which: int) -> pd.DataFrame:
        """Reference of drone ``which`` (0 first, 1 second) as ``t, x, y, z, yaw_deg``."""
        p = self.position_enu_m[:, which, :]
        return pd.DataFrame(
            {
                "t": self.t_s,
                "x": p[:, 0],
                "y": p[:, 1],
                "z": p[:, 2],
                "yaw_deg": np.degrees(self.yaw_rad[:, which]),
            }
        )


@check_types
@dataclass(frozen=True)
class PlanLimits:
    """Limits a plan must respect; ``None`` means unchecked.

    Attributes
    ----------
    max_speed_m_s : float or None
        Largest speed a drone may be asked to fly [m/s].
    max_accel_m_s2 : float or None
        Largest acceleration (tangential and centripetal) [m/s^2].
    max_flight_time_s : float or None
        Flight time per battery; each unit must fit in one battery [s].
    max_yaw_rate_deg_s : float or None
        Largest yaw rate [deg/s].
    """

    max_speed_m_s: float | None = None
    max_accel_m_s2: float | None = None
    max_flight_time_s: float | None = None
    max_yaw_rate_deg_s: float | None = None


@check_types
@dataclass(frozen=True)
class UnitSummary:
    """What a unit asks of the drones.

    Attributes
    ----------
    label : str
    duration_s : float
        Flight time [s].
    path_length_m : float
        Path length of each drone [m].
    max_speed_m_s : float
        Largest reference speed [m/s].
    max_accel_m_s2 : float
        Largest reference acceleration magnitude [m/s^2].
    max_yaw_rate_deg_s : float
        Largest yaw rate [deg/s].
    """

    label: str
    duration_s: float
    path_length_m: float
    max_speed_m_s: float
    max_accel_m_s2: float
    max_yaw_rate_deg_s: float


def _max_yaw_rate_deg_s(unit: TrajectoryUnit) -> float:
    """Peak yaw rate of the cosine-profile turns: ``pi/2 * turn / duration`` [deg/s]."""
    sched = unit.heading_schedule_deg()
    rates = [
        0.5 * np.pi * float(np.max(_turn_deg(sched[i], sched[i + 1]))) / duration
        for kind, duration, i in unit._segments()
        if kind == "turn"
    ]
    return max(rates, default=0.0)


@check_types
def summarize_unit(unit: TrajectoryUnit, limits: PlanLimits | None = None) -> UnitSummary:
    """Duration, path length and the largest speed and acceleration a unit asks for.

    Raises
    ------
    PlanError
        When a limit of ``limits`` is exceeded, naming the limit, the value and the unit, and
        the fields of :class:`TrajectoryUnit` that bring the value down; its ``param`` is the
        name of the :class:`PlanLimits` field exceeded (e.g. ``"max_speed_m_s"``).
    """
    _, t_ramp, _, v_peak = unit._loop_profile()
    r = unit.distance_m / 2.0
    a_t = v_peak / t_ramp
    # |a|^2 = a_t^2 + (v^2/r)^2 is largest at the end of the ramp (v = v_peak, a_t = a)
    max_acc = float(np.hypot(a_t, v_peak**2 / r))
    summary = UnitSummary(
        label=unit.label,
        duration_s=unit.duration_s,
        path_length_m=unit.path_length_m,
        max_speed_m_s=float(v_peak),
        max_accel_m_s2=max_acc,
        max_yaw_rate_deg_s=_max_yaw_rate_deg_s(unit),
    )
    if limits is not None:
        checks = (
            ("max_speed_m_s", "peak speed", summary.max_speed_m_s, limits.max_speed_m_s, "m/s"),
            ("max_accel_m_s2", "peak acceleration", summary.max_accel_m_s2, limits.max_accel_m_s2, "m/s^2"),
            ("max_flight_time_s", "flight time", summary.duration_s, limits.max_flight_time_s, "s"),
            ("max_yaw_rate_deg_s", "peak yaw rate", summary.max_yaw_rate_deg_s, limits.max_yaw_rate_deg_s, "deg/s"),
        )
        for name, what, value, limit, unit_name in checks:
            if limit is not None and value > limit:
                raise PlanError(
                    f"unit {unit.label}: {what} is {value:.3g} {unit_name}, above the limit "
                    f"{limit:.3g} {unit_name} ({name}); {_REMEDIES[name]}",
                    param=name,
                )
    return summary


__all__ = [
    "G_M_S2",
    "PlanLimits",
    "TrajectoryUnit",
    "UnitReference",
    "UnitSummary",
    "summarize_unit",
]
