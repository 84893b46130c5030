"""Calibration trajectory units, campaigns and group schedules (paper Sec. IV-A, Fig. 3).

A trajectory *unit*: two drones start ``d`` apart at height ``z0`` with initial heading
``psi0``, and fly a vertical circle of diameter ``d`` centred between them, always at opposite
ends of a diameter, so they stay ``d`` apart and the line between them turns through a full
revolution per loop: the elevation of each drone seen from the other sweeps -90..90 deg. After
each of ``n`` loops the first drone turns by ``360/n`` deg; once it has swept all headings the
second drone does the same (``2 n`` loops in all). Between loops both drones hover at the start
points while the turning drone yaws.

Several units with different ``psi0`` make a *campaign* (the paper's default: learning units
``psi0 = 0, 24, 48`` deg and a testing unit ``psi0 = 36`` deg, Sec. V-C). For more than two
drones, :func:`pair_schedule` picks pairs whose link graph identifies absolute gains
(DESIGN.md: every connected part needs an odd cycle).

World frame ENU [m]; the circle lies in the vertical plane through the unit's centre along the
world azimuth ``line_azimuth_deg`` (0 = east). Yaw is ENU, counter-clockwise from east [deg in
files, rad in arrays named ``_rad``]; a drone with heading ``psi0 = 0`` relative to the line
faces along the line (the first drone then faces the second at the start).
"""

from __future__ import annotations

import os
from dataclasses import dataclass, replace
from typing import Iterable, Sequence

import numpy as np
import pandas as pd
from numpy.typing import NDArray

from rplearn.errors import InputError, PlanError

FloatArray = NDArray[np.float64]

#: Standard gravity [m/s^2].
G_M_S2 = 9.80665


#: Flags of ``rplearn trajectory`` for the fields of :class:`TrajectoryUnit` it exposes.
CLI_FLAGS: dict[str, str] = {
    "distance_m": "--distance",
    "height_m": "--height",
    "n_loops": "--loops",
    "speed_m_s": "--speed",
}


def _field(name: str) -> str:
    """How a message names a unit field: the CLI flag (if any) and the Python argument."""
    flag = CLI_FLAGS.get(name)
    return f"{flag} ({name})" if flag else name


_LIMIT_FLAGS: dict[str, str] = {
    "max_speed_m_s": " (--max-speed)",
    "max_accel_m_s2": " (--max-accel)",
    "max_flight_time_s": " (--max-flight-time)",
}

#: What brings each limited quantity down (from :meth:`TrajectoryUnit._loop_profile`,
#: :func:`summarize_unit` and :attr:`TrajectoryUnit.duration_s`).
_REMEDIES: dict[str, str] = {
    # peak speed = min(speed, sqrt(accel * pi * d))
    "max_speed_m_s": "lower the cruise speed (--speed, speed_m_s)",
    # |a| = hypot(accel, v^2 / (d / 2)): slower, or a wider circle
    "max_accel_m_s2": "lower the cruise speed (--speed, speed_m_s) or widen the circle (--distance, distance_m)",
    # 2 n loops of pi d / v each, plus the turns
    "max_flight_time_s": (
        "fly fewer headings (--loops, n_loops), a smaller circle (--distance, distance_m) "
        "or faster (--speed, speed_m_s)"
    ),
    # peak yaw rate = pi/2 * yaw_rate_deg_s
    "max_yaw_rate_deg_s": "lower the turn rate (yaw_rate_deg_s)",
}


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
        if len(self.nodes) != 2 or str(self.nodes[0]) == str(self.nodes[1]):
            raise InputError(f"unit nodes: expected two different node ids, got {self.nodes!r}")
        object.__setattr__(self, "nodes", (str(self.nodes[0]), str(self.nodes[1])))
        for name in ("distance_m", "height_m", "speed_m_s", "accel_m_s2", "yaw_rate_deg_s"):
            v = float(getattr(self, name))
            if not (np.isfinite(v) and v > 0):
                raise InputError(f"{_field(name)}: expected a positive finite number, got {v!r}")
        if self.height_m <= self.distance_m / 2.0:
            raise InputError(
                f"{_field('height_m')}: expected more than half the distance ({self.distance_m / 2:g} m) "
                f"so the circle stays above ground, got {float(self.height_m):g}"
            )
        if int(self.n_loops) != self.n_loops or self.n_loops < 1:
            raise InputError(f"{_field('n_loops')}: expected a positive integer, got {self.n_loops!r}")
        if self.role not in ("learning", "testing"):
            raise InputError(f"unit role: expected 'learning' or 'testing', got {self.role!r}")
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

    def sample(self, rate_hz: float, t_offset_s: float = 0.0) -> "UnitReference":
        """Time-parametrised references of both drones, sampled at ``rate_hz``.

        Parameters
        ----------
        rate_hz : float
            Sample rate [Hz].
        t_offset_s : float
            Time of the unit's start [s].
        """
        if not (rate_hz > 0):
            raise InputError(f"rate_hz: expected a positive sample rate, got {rate_hz!r}")
        t = np.arange(0.0, self.duration_s + 0.5 / rate_hz, 1.0 / rate_hz)
        t = t[t <= self.duration_s + 1e-9]
        return self.evaluate(t, t_offset_s)

    def evaluate(self, t_rel_s: NDArray[np.float64], t_offset_s: float = 0.0) -> "UnitReference":
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


@dataclass(frozen=True)
class UnitReference:
    """References of a unit's two drones sampled in time.

    Attributes
    ----------
    unit : TrajectoryUnit
    t_s : ndarray, shape (n,)
        Times [s].
    position_enu_m, velocity_enu_m_s, accel_enu_m_s2 : ndarray, shape (n, 2, 3)
        Reference position [m], velocity [m/s], acceleration [m/s^2] of (first, second) drone.
    yaw_rad : ndarray, shape (n, 2)
        Reference heading, ENU ccw from east [rad], in (-pi, pi].
    loop_index : ndarray of int, shape (n,)
        Loop being flown, or -1 while turning between loops.
    """

    unit: TrajectoryUnit
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


def summarize_unit(unit: TrajectoryUnit, limits: PlanLimits | None = None) -> UnitSummary:
    """Duration, path length and the largest speed and acceleration a unit asks for.

    Raises
    ------
    PlanError
        When a limit of ``limits`` is exceeded, naming the limit, the value and the unit.
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
            ("max_speed_m_s", summary.max_speed_m_s, limits.max_speed_m_s, "m/s"),
            ("max_accel_m_s2", summary.max_accel_m_s2, limits.max_accel_m_s2, "m/s^2"),
            ("max_flight_time_s", summary.duration_s, limits.max_flight_time_s, "s"),
            ("max_yaw_rate_deg_s", summary.max_yaw_rate_deg_s, limits.max_yaw_rate_deg_s, "deg/s"),
        )
        for name, value, limit, unit_name in checks:
            if limit is not None and value > limit:
                raise PlanError(
                    f"unit {unit.label}: {name} is {value:.3g} {unit_name}, above the limit "
                    f"{limit:.3g} {unit_name}{_LIMIT_FLAGS.get(name, '')}; {_REMEDIES[name]}"
                )
    return summary


@dataclass(frozen=True)
class Campaign:
    """Trajectory units flown one after the other, with a gap (battery swap) between them.

    Attributes
    ----------
    units : tuple of TrajectoryUnit
    gap_s : float
        Time between the end of one unit and the start of the next [s].
    """

    units: tuple[TrajectoryUnit, ...]
    gap_s: float = 60.0

    def __post_init__(self) -> None:
        if not self.units:
            raise InputError("campaign units: expected at least one trajectory unit")
        labels = [u.label for u in self.units]
        if len(set(labels)) != len(labels):
            raise InputError(f"campaign units: labels must be unique, got {labels}")

    @property
    def nodes(self) -> tuple[str, ...]:
        """All node ids flying in the campaign, sorted."""
        return tuple(sorted({n for u in self.units for n in u.nodes}))

    def start_times_s(self) -> FloatArray:
        """Start time of every unit [s]."""
        d = np.array([u.duration_s for u in self.units])
        return np.concatenate([[0.0], np.cumsum(d + self.gap_s)[:-1]])

    @property
    def duration_s(self) -> float:
        """Time from the first unit's start to the last unit's end [s]."""
        return float(self.start_times_s()[-1] + self.units[-1].duration_s)

    def links(self) -> list[tuple[str, str]]:
        """Distinct pairs of nodes that fly a unit together (undirected, sorted)."""
        return sorted({tuple(sorted(u.nodes)) for u in self.units})  # type: ignore[misc]

    def with_role(self, role: str) -> "Campaign":
        """The sub-campaign of units with the given role."""
        units = tuple(u for u in self.units if u.role == role)
        if not units:
            raise InputError(f"campaign: no unit has role {role!r}")
        return replace(self, units=units)

    def summarize(self, limits: PlanLimits | None = None) -> list[UnitSummary]:
        """:func:`summarize_unit` of every unit (raises :class:`PlanError` on a violated limit)."""
        return [summarize_unit(u, limits) for u in self.units]


def paper_campaign(
    nodes: tuple[str, str] = ("A", "B"),
    learning_psi0_deg: Sequence[float] = (0.0, 24.0, 48.0),
    testing_psi0_deg: Sequence[float] = (36.0,),
    **unit_options: object,
) -> Campaign:
    """The paper's campaign (Sec. V-C): learning units psi0 = 0, 24, 48 deg, testing 36 deg."""
    units = [
        TrajectoryUnit(nodes=nodes, psi0_deg=float(p), role="learning", label=f"learn_{p:g}", **unit_options)  # type: ignore[arg-type]
        for p in learning_psi0_deg
    ] + [
        TrajectoryUnit(nodes=nodes, psi0_deg=float(p), role="testing", label=f"test_{p:g}", **unit_options)  # type: ignore[arg-type]
        for p in testing_psi0_deg
    ]
    return Campaign(tuple(units))


# ---------------------------------------------------------------------------------------------
# Groups of more than two drones


def link_graph_identifies_gains(pairs: Iterable[tuple[str, str]]) -> bool:
    """Whether a link graph identifies absolute gains: every component has an odd cycle.

    A connected component without an odd cycle is bipartite, and an alternating ``+c/-c``
    constant on its two sides leaves every joint gain unchanged (DESIGN.md).
    """
    adj: dict[str, set[str]] = {}
    for a, b in pairs:
        if a == b:
            raise InputError(f"link graph: a node cannot link to itself ({a})")
        adj.setdefault(a, set()).add(b)
        adj.setdefault(b, set()).add(a)
    if not adj:
        return False
    colour: dict[str, int] = {}
    for start in adj:
        if start in colour:
            continue
        colour[start] = 0
        stack = [start]
        odd = False
        while stack:
            v = stack.pop()
            for w in adj[v]:
                if w not in colour:
                    colour[w] = 1 - colour[v]
                    stack.append(w)
                elif colour[w] == colour[v]:
                    odd = True
        if not odd:
            return False
    return True


def pair_schedule(nodes: Sequence[str]) -> list[tuple[str, str]]:
    """Pairs of drones to fly units with, so that the link graph identifies absolute gains.

    Three or more drones: a triangle on the first three, each further drone paired with the
    one before it (connected, one odd cycle, ``n`` pairs). Two drones: the single pair, which
    identifies only the shapes (paper Sec. V-A).
    """
    ids = [str(n) for n in nodes]
    if len(ids) < 2 or len(set(ids)) != len(ids):
        raise InputError(f"nodes: expected at least two distinct node ids, got {ids}")
    if len(ids) == 2:
        return [(ids[0], ids[1])]
    pairs = [(ids[0], ids[1]), (ids[1], ids[2]), (ids[2], ids[0])]
    pairs += [(ids[i - 1], ids[i]) for i in range(3, len(ids))]
    return pairs


def group_campaign(
    nodes: Sequence[str],
    learning_psi0_deg: Sequence[float] = (0.0, 24.0, 48.0),
    testing_psi0_deg: Sequence[float] = (36.0,),
    **unit_options: object,
) -> Campaign:
    """A campaign for a group: for each pair of :func:`pair_schedule`, the paper's units."""
    units: list[TrajectoryUnit] = []
    for a, b in pair_schedule(nodes):
        for role, psis in (("learning", learning_psi0_deg), ("testing", testing_psi0_deg)):
            for p in psis:
                units.append(
                    TrajectoryUnit(
                        nodes=(a, b),
                        psi0_deg=float(p),
                        role=role,
                        label=f"{'learn' if role == 'learning' else 'test'}_{a}{b}_{p:g}",
                        **unit_options,  # type: ignore[arg-type]
                    )
                )
    return Campaign(tuple(units))


def write_references(
    campaign: Campaign | TrajectoryUnit, out_dir: str, rate_hz: float = 10.0
) -> list[str]:
    """Write per-unit, per-drone references ``t, x, y, z, yaw_deg`` as CSV files.

    Files are named ``<unit label>_<node>.csv``; ``t`` starts at 0 for each unit [s].

    Returns
    -------
    list of str
        The paths written.
    """
    units = (campaign,) if isinstance(campaign, TrajectoryUnit) else campaign.units
    os.makedirs(out_dir, exist_ok=True)
    paths: list[str] = []
    for unit in units:
        ref = unit.sample(rate_hz)
        for j, node in enumerate(unit.nodes):
            path = os.path.join(out_dir, f"{unit.label}_{node}.csv")
            ref.table(j).to_csv(path, index=False, float_format="%.4f")
            paths.append(path)
    return paths


__all__ = [
    "Campaign",
    "PlanLimits",
    "TrajectoryUnit",
    "UnitReference",
    "UnitSummary",
    "group_campaign",
    "link_graph_identifies_gains",
    "pair_schedule",
    "paper_campaign",
    "summarize_unit",
    "write_references",
]

