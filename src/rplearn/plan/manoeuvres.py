"""Manoeuvres one vehicle can fly from where it is, while another node holds still.

A :class:`ManoeuvreUnit` is a short flight of one drone (the *mover*) in front of another node
(the *anchor*: the ground station, or the peer drone hovering): a yaw turn in place, a climb or
descent to another elevation seen from the anchor (optionally followed by a turn), or an orbit
of the anchor at the current or another elevation, keeping the distance, with a heading fixed
in the world (so that the mover sees the anchor from every body azimuth and the anchor sees the
mover from every one of its azimuths). It has the interface the simulator and the reference
writer use (``nodes``, ``label``, ``role``, ``duration_s``, ``sample``, ``evaluate`` returning a
:class:`~rplearn.plan.trajectory.UnitReference`; node 0 is the anchor and stands still), so a
sequence of them is a :class:`~rplearn.plan.campaign.Campaign`.

:func:`candidate_manoeuvres` lists the candidates from the nodes' current poses: every
manoeuvre above for every movable node and anchor, and the trajectory units of the plan
library placed where the drones are (the paper's unit for two drones, ground passes in front
of a static station), each with the time to reach its start. A hovering anchor may turn in place
meanwhile (both nodes then see the other from every body azimuth in the same seconds), and no
candidate brings two nodes nearer than ``min_separation_m``.

Moves and orbits follow a trapezoidal profile (``accel_m_s2``, cruise at ``speed_m_s``), turns
a trapezoidal yaw profile (``yaw_accel_deg_s2``, cruise at ``yaw_rate_deg_s``). ENU [m], yaw
ccw from east [deg in fields, rad in arrays named ``_rad``].
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
from numpy.typing import NDArray

from rplearn._argtypes import check_types
from rplearn.errors import InputError
from rplearn.plan.ground import GroundPassUnit
from rplearn.plan.sweeps import loop_sweeps
from rplearn.plan.trajectory import TrajectoryUnit, UnitReference, sample_times_s

FloatArray = NDArray[np.float64]

#: Smallest height change of a climb or descent candidate [m] (a smaller one is where the drone is).
MIN_CLIMB_M = 2.0
#: Manoeuvre kinds of :class:`ManoeuvreUnit`.
MANOEUVRE_KINDS = ("yaw", "climb", "climb_turn", "spiral", "orbit", "arc")


def _trapezoid(length: float, v: float, a: float) -> tuple[float, float, float, float]:
    """(duration, ramp time, cruise time, peak rate) of a trapezoidal profile over ``length``."""
    if length <= 0:
        return 0.0, 0.0, 0.0, 0.0
    if v * v / a >= length:
        vp = float(np.sqrt(a * length))
        return 2.0 * vp / a, vp / a, 0.0, vp
    return 2.0 * v / a + (length - v * v / a) / v, v / a, (length - v * v / a) / v, v


def _profile(tau: FloatArray, length: float, v: float, a: float) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Progress, rate and acceleration of a trapezoidal profile at times ``tau`` in it."""
    dur, tr, tc, vp = _trapezoid(length, v, a)
    if dur == 0.0:
        z = np.zeros_like(tau)
        return z, z, z
    acc = vp / tr
    t = np.clip(tau, 0.0, dur)
    s = np.where(t < tr, 0.5 * acc * t**2,
                 np.where(t < tr + tc, 0.5 * acc * tr**2 + vp * (t - tr), length - 0.5 * acc * (dur - t) ** 2))
    sd = np.where(t < tr, acc * t, np.where(t < tr + tc, vp, acc * (dur - t)))
    sdd = np.where(t < tr, acc, np.where(t < tr + tc, 0.0, -acc))
    sdd = np.where(np.asarray(tau) > dur, 0.0, sdd)  # held at the end
    return s, sd, sdd


@check_types
@dataclass(frozen=True)
class ManoeuvreUnit:
    """One drone's manoeuvre in front of a node that holds still (module docstring).

    Attributes
    ----------
    nodes : (str, str)
        The anchor (station or hovering peer, node 0) and the mover.
    kind : str
        ``"yaw"`` (turn in place by ``turn_deg``), ``"climb"`` (to ``elevation_deg`` seen from
        the anchor, horizontal distance kept), ``"climb_turn"`` (the climb, then a turn by
        ``turn_deg``), ``"spiral"`` (the climb and the turn at once) or ``"orbit"`` (to
        ``elevation_deg`` at the same distance, then ``laps`` full
        circles around the anchor's vertical, the heading fixed in the world) or ``"arc"`` (to
        ``distance_m`` at the current elevation and bearing, then along the vertical circle of
        that radius about the anchor, in the plane of anchor and mover, by ``sweep_deg``:
        positive over the anchor's zenith, negative under its nadir, turning by ``turn_deg``
        meanwhile; both nodes see the other's poles in a few seconds).
    anchor_enu_m, start_enu_m : (float, float, float)
        Positions of the anchor and of the mover at the start [m].
    anchor_yaw_deg, start_yaw_deg : float
        Headings of the anchor and of the mover at the start [deg].
    elevation_deg : float or None
        Target elevation of the mover seen from the anchor [deg]; None keeps the current one.
    turn_deg : float
        Yaw turn of ``yaw``, ``climb_turn`` and ``spiral`` [deg] (signed).
    distance_m : float or None
        Distance from the anchor of an orbit [m]; None keeps the current one.
    sweep_deg : float
        Angle an arc turns the mover about the anchor in the vertical plane [deg] (signed:
        positive upward; 180 - 2 el over the zenith to the mirrored elevation).
    laps : int
        Circles of an orbit (2: every direction of the ring seen again a lap later).
    speed_m_s, accel_m_s2 : float
        Cruise speed [m/s] and acceleration [m/s^2] of moves and orbits.
    yaw_rate_deg_s, yaw_accel_deg_s2 : float
        Cruise yaw rate [deg/s] and yaw acceleration [deg/s^2] of turns.
    anchor_turn_deg : float
        A turn of the anchor in place during the manoeuvre [deg] (signed; 0: it holds its
        heading): a hovering peer turning while the mover flies sees the mover from every body
        azimuth in the same seconds (never for a ground station). The manoeuvre lasts until both
        have finished; the mover holds its last pose meanwhile.
    label, role : str
    """

    nodes: tuple[str, str]
    kind: str
    anchor_enu_m: tuple[float, float, float]
    start_enu_m: tuple[float, float, float]
    anchor_yaw_deg: float = 0.0
    start_yaw_deg: float = 0.0
    elevation_deg: float | None = None
    turn_deg: float = 360.0
    distance_m: float | None = None
    laps: int = 1
    sweep_deg: float = 0.0
    speed_m_s: float = 1.5
    accel_m_s2: float = 1.0
    yaw_rate_deg_s: float = 30.0
    yaw_accel_deg_s2: float = 60.0
    anchor_turn_deg: float = 0.0
    label: str = ""
    role: str = "learning"
    _segments: tuple[tuple[Any, ...], ...] = field(init=False, repr=False, compare=False, default=())

    def __post_init__(self) -> None:
        if len(self.nodes) != 2 or str(self.nodes[0]) == str(self.nodes[1]):
            raise InputError(f"manoeuvre nodes: expected two different node ids, got {self.nodes!r}", param="nodes")
        object.__setattr__(self, "nodes", (str(self.nodes[0]), str(self.nodes[1])))
        if self.kind not in MANOEUVRE_KINDS:
            raise InputError(f"manoeuvre kind: expected one of {', '.join(MANOEUVRE_KINDS)}, got {self.kind!r}", param="kind")
        for name in ("speed_m_s", "accel_m_s2", "yaw_rate_deg_s", "yaw_accel_deg_s2"):
            v = float(getattr(self, name))
            if not (np.isfinite(v) and v > 0):
                raise InputError(f"{name}: expected a positive finite number, got {v!r}", param=name)
        for name in ("anchor_enu_m", "start_enu_m"):
            p = np.asarray(getattr(self, name), np.float64)
            if p.shape != (3,) or not np.all(np.isfinite(p)):
                raise InputError(f"{name}: expected three finite coordinates [m], got {getattr(self, name)!r}", param=name)
        if self.distance_m is not None and not (np.isfinite(self.distance_m) and self.distance_m >= 1.0):
            raise InputError(f"distance_m: expected at least 1 m, got {self.distance_m!r}", param="distance_m")
        if int(self.laps) != self.laps or self.laps < 1:
            raise InputError(f"laps: expected a whole number of circles, at least 1, got {self.laps!r}", param="laps")
        if self.elevation_deg is not None and not -89.0 <= float(self.elevation_deg) <= 89.0:
            raise InputError(f"elevation_deg: expected -89..89 deg, got {self.elevation_deg!r}", param="elevation_deg")
        if self.role not in ("learning", "testing"):
            raise InputError(f"role: expected 'learning' or 'testing', got {self.role!r}", param="role")
        if not self.label:
            el = "" if self.elevation_deg is None else f"_el{self.elevation_deg:+g}"
            el += "" if self.distance_m is None else f"_{self.distance_m:g}m"
            el += "" if self.laps == 1 else f"_x{self.laps}"
            el += "" if self.kind != "arc" else f"_sweep{self.sweep_deg:+g}"
            el += "" if self.turn_deg == 360.0 or self.kind not in ("yaw", "climb_turn", "spiral", "arc") else f"_turn{self.turn_deg:g}"
            el += "" if self.anchor_turn_deg == 0 else f"_{self.nodes[0]}_turning"
            object.__setattr__(self, "label", f"{self.kind}_{self.nodes[1]}_about_{self.nodes[0]}{el}")
        if np.hypot(self.start_enu_m[0] - self.anchor_enu_m[0], self.start_enu_m[1] - self.anchor_enu_m[1]) < 0.5 \
                and self.kind in ("climb", "climb_turn", "spiral", "orbit", "arc"):
            raise InputError("start_enu_m: the mover is above the anchor; a climb or an orbit needs a horizontal distance",
                             param="start_enu_m")
        if self.kind == "arc" and not (np.isfinite(self.sweep_deg) and 0.0 < abs(float(self.sweep_deg)) <= 360.0):
            raise InputError(f"sweep_deg: an arc turns by a non-zero angle of at most 360 deg, got {self.sweep_deg!r}",
                             param="sweep_deg")
        object.__setattr__(self, "_segments", self._plan())

    def _target_position(self) -> FloatArray:
        a, p = np.asarray(self.anchor_enu_m, float), np.asarray(self.start_enu_m, float)
        d = p - a
        horiz = float(np.hypot(d[0], d[1]))
        if self.kind == "arc":  # the arc's start: the current bearing and elevation at its radius
            return p if self.distance_m is None else a + d / float(np.linalg.norm(d)) * float(self.distance_m)
        if self.elevation_deg is None:
            return p
        el = np.radians(float(self.elevation_deg))
        if self.kind == "orbit":  # keep the distance, or take the one given
            dist = float(np.linalg.norm(d)) if self.distance_m is None else float(self.distance_m)
            r = dist * np.cos(el)
            return np.array([a[0] + d[0] / horiz * r, a[1] + d[1] / horiz * r, a[2] + dist * np.sin(el)])
        return np.array([p[0], p[1], a[2] + horiz * np.tan(el)])

    def _plan(self) -> tuple[tuple[Any, ...], ...]:
        """Segments: ("move", p0, p1, yaw), ("turn", p, yaw0, dyaw), ("arc", centre, r, a0, yaw, laps),
        ("spiral", p0, p1, yaw0, dyaw), ("vert", centre, r, bearing, el0, sweep, yaw0, dyaw) [rad]."""
        p0 = np.asarray(self.start_enu_m, float)
        yaw0 = np.radians(float(self.start_yaw_deg))
        segs: list[tuple[Any, ...]] = []
        if self.kind == "yaw":
            return (("turn", p0, yaw0, np.radians(float(self.turn_deg))),)
        p1 = self._target_position()
        if self.kind == "spiral":
            return (("spiral", p0, p1, yaw0, np.radians(float(self.turn_deg))),)
        if np.linalg.norm(p1 - p0) > 1e-6:
            segs.append(("move", p0, p1, yaw0))
        if self.kind == "climb_turn":
            segs.append(("turn", p1, yaw0, np.radians(float(self.turn_deg))))
        elif self.kind == "arc":
            a = np.asarray(self.anchor_enu_m, float)
            d = p1 - a
            horiz = float(np.hypot(d[0], d[1]))
            segs.append(("vert", a, float(np.linalg.norm(d)), float(np.arctan2(d[1], d[0])), float(np.arctan2(d[2], horiz)),
                         np.radians(float(self.sweep_deg)), yaw0, np.radians(float(self.turn_deg))))
        elif self.kind == "orbit":
            a = np.asarray(self.anchor_enu_m, float)
            d = p1 - a
            segs.append(("arc", np.array([a[0], a[1], p1[2]]), float(np.hypot(d[0], d[1])), float(np.arctan2(d[1], d[0])), yaw0,
                         int(self.laps)))
        return tuple(segs)

    def _segment_duration(self, seg: tuple[Any, ...]) -> float:
        if seg[0] == "move":
            return _trapezoid(float(np.linalg.norm(seg[2] - seg[1])), self.speed_m_s, self.accel_m_s2)[0]
        if seg[0] == "turn":
            return _trapezoid(abs(float(np.degrees(seg[3]))), self.yaw_rate_deg_s, self.yaw_accel_deg_s2)[0]
        if seg[0] == "vert":
            return max(_trapezoid(abs(float(seg[5])) * seg[2], self.speed_m_s, self.accel_m_s2)[0],
                       _trapezoid(abs(float(np.degrees(seg[7]))), self.yaw_rate_deg_s, self.yaw_accel_deg_s2)[0])
        if seg[0] == "spiral":
            return max(_trapezoid(float(np.linalg.norm(seg[2] - seg[1])), self.speed_m_s, self.accel_m_s2)[0],
                       _trapezoid(abs(float(np.degrees(seg[4]))), self.yaw_rate_deg_s, self.yaw_accel_deg_s2)[0])
        return _trapezoid(2.0 * np.pi * seg[2] * seg[5], self.speed_m_s, self.accel_m_s2)[0]

    def _anchor_turn_s(self) -> float:
        return _trapezoid(abs(float(self.anchor_turn_deg)), self.yaw_rate_deg_s, self.yaw_accel_deg_s2)[0]

    @property
    def duration_s(self) -> float:
        """Flight time of the manoeuvre [s]."""
        return float(max(sum(self._segment_duration(s) for s in self._segments), self._anchor_turn_s()))

    def anchor_end_yaw_deg(self) -> float:
        """The anchor's heading at the end [deg]."""
        return float(np.degrees(np.angle(np.exp(1j * np.radians(float(self.anchor_yaw_deg) + float(self.anchor_turn_deg))))))

    def end_pose(self) -> tuple[tuple[float, float, float], float]:
        """The mover's position [m] and heading [deg] at the end."""
        ref = self.evaluate(np.array([self.duration_s]))
        return tuple(float(v) for v in ref.position_enu_m[0, 1]), float(np.degrees(ref.yaw_rad[0, 1]))  # type: ignore[return-value]

    def sample(self, rate_hz: float, t_offset_s: float = 0.0) -> UnitReference:
        """References of the anchor (node 0) and the mover at ``rate_hz`` [Hz]."""
        return self.evaluate(sample_times_s(self.duration_s, rate_hz), t_offset_s)

    def evaluate(self, t_rel_s: FloatArray, t_offset_s: float = 0.0) -> UnitReference:
        """References at times ``t_rel_s`` since the manoeuvre's start [s]."""
        t = np.clip(np.asarray(t_rel_s, np.float64), 0.0, self.duration_s)
        n = t.size
        pos, vel, acc = np.zeros((n, 2, 3)), np.zeros((n, 2, 3)), np.zeros((n, 2, 3))
        pos[:, 0] = np.asarray(self.anchor_enu_m, float)
        yaw = np.zeros((n, 2))
        yaw[:, 0] = np.radians(float(self.anchor_yaw_deg))
        if self.anchor_turn_deg != 0:
            s, _, _ = _profile(t, abs(float(self.anchor_turn_deg)), self.yaw_rate_deg_s, self.yaw_accel_deg_s2)
            yaw[:, 0] += np.sign(self.anchor_turn_deg) * np.radians(s)
        pos[:, 1] = np.asarray(self.start_enu_m, float)
        yaw[:, 1] = np.radians(float(self.start_yaw_deg))
        start = 0.0
        for seg in self._segments:
            dur = self._segment_duration(seg)
            m = t >= start if seg is self._segments[-1] else (t >= start) & (t < start + dur)
            tau = t[m] - start
            if seg[0] == "spiral":  # the move and the turn together, each at its own profile
                length = float(np.linalg.norm(seg[2] - seg[1]))
                u = (seg[2] - seg[1]) / max(length, 1e-12)
                s, sd, sdd = _profile(tau, length, self.speed_m_s, self.accel_m_s2)
                pos[m, 1] = seg[1] + s[:, None] * u
                vel[m, 1] = sd[:, None] * u
                acc[m, 1] = sdd[:, None] * u
                s, _, _ = _profile(tau, abs(float(np.degrees(seg[4]))), self.yaw_rate_deg_s, self.yaw_accel_deg_s2)
                yaw[m, 1] = seg[3] + np.sign(seg[4]) * np.radians(s)
            elif seg[0] == "vert":  # along the vertical circle about the anchor, turning meanwhile
                centre, r, bearing, el0, sweep = seg[1], seg[2], seg[3], seg[4], seg[5]
                s, sd, sdd = _profile(tau, abs(sweep) * r, self.speed_m_s, self.accel_m_s2)
                sign = float(np.sign(sweep))
                th, w, wd = el0 + sign * s / r, sign * sd / r, sign * sdd / r
                h, z = np.array([np.cos(bearing), np.sin(bearing), 0.0]), np.array([0.0, 0.0, 1.0])
                c, sn = np.cos(th)[:, None], np.sin(th)[:, None]
                pos[m, 1] = centre + r * (c * h + sn * z)
                vel[m, 1] = r * w[:, None] * (-sn * h + c * z)
                acc[m, 1] = r * wd[:, None] * (-sn * h + c * z) - r * (w**2)[:, None] * (c * h + sn * z)
                s, _, _ = _profile(tau, abs(float(np.degrees(seg[7]))), self.yaw_rate_deg_s, self.yaw_accel_deg_s2)
                yaw[m, 1] = seg[6] + np.sign(seg[7]) * np.radians(s)
            elif seg[0] == "move":
                length = float(np.linalg.norm(seg[2] - seg[1]))
                u = (seg[2] - seg[1]) / length
                s, sd, sdd = _profile(tau, length, self.speed_m_s, self.accel_m_s2)
                pos[m, 1] = seg[1] + s[:, None] * u
                vel[m, 1] = sd[:, None] * u
                acc[m, 1] = sdd[:, None] * u
                yaw[m, 1] = seg[3]
            elif seg[0] == "turn":
                s, _, _ = _profile(tau, abs(float(np.degrees(seg[3]))), self.yaw_rate_deg_s, self.yaw_accel_deg_s2)
                pos[m, 1] = seg[1]
                yaw[m, 1] = seg[2] + np.sign(seg[3]) * np.radians(s)
            else:
                centre, r, a0, y = seg[1], seg[2], seg[3], seg[4]
                s, sd, sdd = _profile(tau, 2.0 * np.pi * r * seg[5], self.speed_m_s, self.accel_m_s2)
                ang, w, wd = a0 + s / r, sd / r, sdd / r
                c, sn = np.cos(ang), np.sin(ang)
                pos[m, 1] = centre + r * np.column_stack([c, sn, np.zeros_like(c)])
                vel[m, 1] = r * np.column_stack([-sn * w, c * w, np.zeros_like(c)])
                acc[m, 1] = r * np.column_stack([-sn * wd - c * w**2, c * wd - sn * w**2, np.zeros_like(c)])
                yaw[m, 1] = y
            start += dur
        yaw = np.angle(np.exp(1j * yaw))
        return UnitReference(self, t + t_offset_s, pos, vel, acc, yaw, np.zeros(n, np.int_))


@check_types
@dataclass(frozen=True)
class CandidateOptions:
    """What the candidate manoeuvres may be.

    Attributes
    ----------
    elevations_deg : tuple of float
        Elevations seen from the anchor for climbs and orbits [deg] (the current one is added).
    fixed_nodes : tuple of str
        Nodes that cannot move (a ground station); the others are drones.
    speed_m_s, accel_m_s2, yaw_rate_deg_s : float
        The vehicles' cruise speed [m/s], acceleration [m/s^2] and yaw rate [deg/s]. A faster
        turn sweeps more azimuths per 5-s block of the drifting heading error (45 deg/s, near
        the paper units' 47-deg/s peak: 225 deg a block, against 150 at 30); flown in the
        simulator (``benchmarks/manoeuvres.py --yaw-rate 45``, 12 cells) it cut the mean time
        to 2 dB (paper 0.66 -> 0.63x of the reference's, ground 0.56 -> 0.52x) but not the
        cells meeting both of its checks (4 of 12, against 6), so the default stays 30 deg/s.
    min_height_m, max_height_m : float
        Heights a mover may fly at [m].
    library : bool
        Include the trajectory units of the plan library.
    library_loops : tuple of int
        Headings per drone ``n`` of the paper's units offered.
    orbit_distances_m : tuple of float
        Distances from the anchor of further orbits, besides the current distance [m] (a close
        orbit at a high elevation gives both nodes a ring in a few seconds).
    anchor_turns : bool
        Also offer every manoeuvre with a hovering (not fixed) anchor turning a full circle in
        place meanwhile (:attr:`ManoeuvreUnit.anchor_turn_deg`).
    arcs : bool
        Also offer arcs (:attr:`ManoeuvreUnit.kind` ``"arc"``): the mover over the anchor's
        zenith (or under its nadir, where the heights allow) to the mirrored elevation, at the
        current distance and at ``orbit_distances_m``, turning a full circle meanwhile or not.
        Off by default: flown in the simulator (``benchmarks/manoeuvres.py --arcs``) they were
        chosen but did not pay for their time (paper seed 0, time to 2 dB over the
        reference's, suggested/optimized: 0.71/0.68x at 30 deg/s against 0.72/0.74x without
        them; 0.63/0.62x at 45 deg/s against 0.57/0.61x).
    sweeps : bool
        Also offer loop sweeps (:mod:`rplearn.plan.sweeps`): the paper unit's ``n`` vertical
        circles with one drone's headings stepping, or both drones', where each library unit is
        (with ``ManoeuvreOptions.rate="information"``, benchmarks/manoeuvres.py: 7 of 12 cells
        against 6, both off).
    revisits : int
        Also offer manoeuvres that see their directions this many times over, each pass after
        the last (a yaw turn of ``revisits * 360`` deg, an orbit of ``revisits`` laps, the
        turning anchor as many circles): an error that drifts over seconds (a heading
        estimate's) is then averaged over passes seconds apart; 1: none.
    min_separation_m : float
        Closest any two nodes may come during a manoeuvre [m]: a candidate passing nearer is
        not offered (two drones a metre or two apart risk a collision, and a position error of
        a fraction of a metre then turns the link direction by many degrees, so such samples
        teach the wrong directions); nodes already nearer may stay as near; 0: no limit.
    """

    elevations_deg: tuple[float, ...] = (-75.0, -60.0, -45.0, -30.0, -15.0, 0.0, 15.0, 30.0, 45.0, 60.0, 75.0)
    fixed_nodes: tuple[str, ...] = ()
    speed_m_s: float = 1.5
    accel_m_s2: float = 1.0
    yaw_rate_deg_s: float = 30.0
    min_height_m: float = 3.0
    max_height_m: float = 120.0
    library: bool = True
    library_loops: tuple[int, ...] = (1, 2, 5)
    orbit_distances_m: tuple[float, ...] = (6.0,)
    min_separation_m: float = 5.0
    anchor_turns: bool = True
    arcs: bool = False
    sweeps: bool = True
    revisits: int = 2

    def __post_init__(self) -> None:
        if int(self.revisits) != self.revisits or self.revisits < 1:
            raise InputError(f"revisits: expected a whole number of passes, at least 1, got {self.revisits!r}", param="revisits")
        if not (np.isfinite(self.min_separation_m) and self.min_separation_m >= 0):
            raise InputError(f"min_separation_m: expected a non-negative distance [m], got {self.min_separation_m!r}",
                             param="min_separation_m")
        for name in ("speed_m_s", "accel_m_s2", "yaw_rate_deg_s"):
            v = float(getattr(self, name))
            if not (np.isfinite(v) and v > 0):
                raise InputError(f"{name}: expected a positive finite number, got {v!r}", param=name)
        if not self.min_height_m < self.max_height_m:
            raise InputError(f"min_height_m: expected below max_height_m, got {self.min_height_m!r}", param="min_height_m")
        object.__setattr__(self, "fixed_nodes", tuple(str(n) for n in self.fixed_nodes))


@check_types
@dataclass(frozen=True)
class Candidate:
    """A manoeuvre from the current poses: the unit to fly and the time to reach its start.

    Attributes
    ----------
    name : str
    unit : ManoeuvreUnit, TrajectoryUnit or GroundPassUnit
    lead_s : float
        Time to reach the unit's start from the current poses (no data counted) [s].
    ends : dict of str to ((float, float, float), float)
        Each moved node's position [m] and heading [deg] after it.
    """

    name: str
    unit: Any
    lead_s: float
    ends: dict[str, tuple[tuple[float, float, float], float]]

    @property
    def duration_s(self) -> float:
        """Flight time: the lead and the unit [s]."""
        return float(self.lead_s + self.unit.duration_s)


def closest_approach_m(unit: Any, state: Mapping[str, tuple[FloatArray, float]]) -> float:
    """Closest distance between any two nodes while ``unit`` is flown (nodes not in it hold still) [m]."""
    ref = unit.sample(4.0)
    pos = {str(n): ref.position_enu_m[:, j, :] for j, n in enumerate(unit.nodes)}
    for n, (p, _) in state.items():
        pos.setdefault(n, np.broadcast_to(np.asarray(p, np.float64), (ref.t_s.size, 3)))
    names = sorted(pos)
    closest = np.inf
    for i, a in enumerate(names):
        for b in names[i + 1:]:
            closest = min(closest, float(np.min(np.linalg.norm(pos[a] - pos[b], axis=1))))
    return closest


def lead_time_s(moves: list[float], opts: CandidateOptions) -> float:
    return max((_trapezoid(d, opts.speed_m_s, opts.accel_m_s2)[0] for d in moves), default=0.0)


def _library(poses: Mapping[str, tuple[FloatArray, float]], a: str, b: str, opts: CandidateOptions) -> list[Candidate]:
    """The plan library's units placed where the pair is (paper units, ground passes)."""
    pa, pb = np.asarray(poses[a][0], float), np.asarray(poses[b][0], float)
    out: list[Candidate] = []
    fixed_a, fixed_b = a in opts.fixed_nodes, b in opts.fixed_nodes
    if not fixed_a and not fixed_b:
        d = float(np.linalg.norm(pb - pa))
        h = 0.5 * float(pa[2] + pb[2])
        if h > d / 2.0 + opts.min_height_m and d > 1.0:
            centre = 0.5 * (pa + pb)
        else:
            h = d / 2.0 + opts.min_height_m + 1.0
            centre = np.array([0.5 * (pa[0] + pb[0]), 0.5 * (pa[1] + pb[1]), h])
        az = float(np.degrees(np.arctan2(pb[1] - pa[1], pb[0] - pa[0]))) if np.hypot(*(pb - pa)[:2]) > 0.1 else 0.0
        for n in opts.library_loops:
            for psi in (0.0, 24.0, 48.0):
                unit = TrajectoryUnit(nodes=(a, b), psi0_deg=psi, distance_m=max(d, 2.0), height_m=h, n_loops=int(n),
                                      speed_m_s=opts.speed_m_s, accel_m_s2=opts.accel_m_s2, yaw_rate_deg_s=opts.yaw_rate_deg_s,
                                      center_enu_m=(float(centre[0]), float(centre[1])), line_azimuth_deg=az,
                                      label=f"unit_{a}{b}_n{n}_psi{psi:g}")
                for name, u in [(f"paper unit n={n} psi0={psi:g} ({a},{b})", unit), *(loop_sweeps(unit) if opts.sweeps else [])]:
                    ref = u.evaluate(np.array([0.0, u.duration_s]))
                    lead = lead_time_s([float(np.linalg.norm(ref.position_enu_m[0, j] - p)) for j, p in enumerate((pa, pb))], opts)
                    ends = {node: (tuple(float(v) for v in ref.position_enu_m[1, j]), float(np.degrees(ref.yaw_rad[1, j])))
                            for j, node in enumerate((a, b))}
                    out.append(Candidate(name, u, lead, ends))  # type: ignore[arg-type]
    elif fixed_a != fixed_b:
        station, drone = (a, b) if fixed_a else (b, a)
        ps, pd_ = np.asarray(poses[station][0], float), np.asarray(poses[drone][0], float)
        dist = float(np.hypot(*(pd_ - ps)[:2]))
        if dist < 5.0:
            return out
        facing = float(poses[station][1])  # the passes are flown in front of the station, which never turns
        for dh in (0.0, -10.0, 10.0):
            h = float(pd_[2]) + dh
            if not opts.min_height_m <= h <= opts.max_height_m:
                continue
            passes = GroundPassUnit(nodes=(station, drone), distance_m=dist, height_m=h, station_height_m=max(float(ps[2]), 0.1),
                                  speed_m_s=opts.speed_m_s, n_passes=2, station_yaw_deg=facing, label=f"passes_{drone}_{h:.0f}m")
            ref = passes.evaluate(np.array([0.0, passes.duration_s]))
            lead = lead_time_s([float(np.linalg.norm(ref.position_enu_m[0, 1] - pd_))], opts)
            ends = {drone: (tuple(float(v) for v in ref.position_enu_m[1, 1]), float(np.degrees(ref.yaw_rad[1, 1])))}
            out.append(Candidate(f"ground passes at {h:.0f} m ({drone} about {station})", passes, lead, ends))  # type: ignore[arg-type]
    return out


def _arcs(base: dict[str, Any], mover: str, anchor: str, current_deg: float,
          opts: CandidateOptions) -> list[tuple[str, ManoeuvreUnit, int]]:
    """Arcs of ``mover`` about ``anchor`` from its current elevation ``current_deg`` to the
    mirrored one, over the zenith and under the nadir, at the current and the orbit distances,
    without and with a full turn; only those whose heights stay within the options' limits."""
    out: list[tuple[str, ManoeuvreUnit, int]] = []
    for dist in (None, *opts.orbit_distances_m):
        for sweep, way in ((180.0 - 2.0 * current_deg, "over"), (-180.0 - 2.0 * current_deg, "under")):
            for turn in (0.0, 360.0):
                unit = ManoeuvreUnit(kind="arc", sweep_deg=sweep, distance_m=dist, turn_deg=turn, **base)
                ref = unit.evaluate(np.linspace(0.0, unit.duration_s, 61))
                z = ref.position_enu_m[:, 1, 2]
                if not (opts.min_height_m <= float(np.min(z)) and float(np.max(z)) <= opts.max_height_m):
                    continue
                at = "" if dist is None else f" at {dist:g} m"
                out.append((f"arc of {mover} {way} {anchor}{at}{', turning' if turn else ''}", unit, 1))
    return out


@check_types
def candidate_manoeuvres(poses: Mapping[str, tuple[tuple[float, float, float], float]],
                         options: CandidateOptions | None = None) -> list[Candidate]:
    """Every manoeuvre the vehicles can fly from their current poses (module docstring).

    Parameters
    ----------
    poses : mapping of node to ((x, y, z), yaw_deg)
        Each node's current position (ENU [m]) and heading [deg].
    options : CandidateOptions, optional
    """
    opts = options or CandidateOptions()
    if len(poses) < 2:
        raise InputError(f"poses: expected at least two nodes, got {len(poses)}", param="poses")
    state = {str(n): (np.asarray(p, np.float64), float(y)) for n, (p, y) in poses.items()}
    kw: dict[str, Any] = dict(speed_m_s=opts.speed_m_s, accel_m_s2=opts.accel_m_s2, yaw_rate_deg_s=opts.yaw_rate_deg_s)
    out: list[Candidate] = []
    names = sorted(state)
    for mover in names:
        if mover in opts.fixed_nodes:
            continue
        pm, ym = state[mover]
        for anchor in names:
            if anchor == mover:
                continue
            pa, ya = state[anchor]
            base = dict(nodes=(anchor, mover), anchor_enu_m=tuple(pa), start_enu_m=tuple(pm), anchor_yaw_deg=ya,
                        start_yaw_deg=ym, **kw)
            units: list[tuple[str, ManoeuvreUnit, int]] = []
            again = int(opts.revisits)
            if anchor == names[0] or mover == names[0]:  # a turn in place does not depend on the anchor: list it once
                units.append((f"yaw turn of {mover}", ManoeuvreUnit(kind="yaw", label=f"yaw_{mover}", **base), 1))
                if again > 1:
                    units.append((f"yaw turn of {mover} by {360 * again} deg",
                                  ManoeuvreUnit(kind="yaw", turn_deg=360.0 * again, label=f"yaw_{mover}_x{again}", **base), again))
            d = pm - pa
            horiz = float(np.hypot(d[0], d[1]))
            if horiz >= 1.0:
                current = float(np.degrees(np.arctan2(d[2], horiz)))
                for el in sorted(set(opts.elevations_deg) | {round(current, 1)}):
                    for kind in ("climb", "climb_turn", "spiral", "orbit"):
                        if kind != "orbit" and abs(el - current) < 1.0:
                            continue
                        for dist in (None, *opts.orbit_distances_m) if kind == "orbit" else (None,):
                            unit = ManoeuvreUnit(kind=kind, elevation_deg=float(el), distance_m=dist, **base)
                            z = unit._target_position()[2]
                            if not opts.min_height_m <= z <= opts.max_height_m or (
                                    kind != "orbit" and abs(z - pm[2]) < MIN_CLIMB_M):
                                continue
                            up = "climb" if z > pm[2] else "descent"
                            what = {"climb": up, "climb_turn": f"{up} then turn", "spiral": f"{up} turning", "orbit": "orbit"}[kind]
                            at = "" if dist is None else f" at {dist:g} m"
                            units.append((f"{what} of {mover} to el {el:+.0f} deg from {anchor}{at}", unit, 1))
                            if kind == "orbit" and again > 1:
                                units.append((f"{what} of {mover} to el {el:+.0f} deg from {anchor}{at}, {again} laps",
                                              replace(unit, laps=again, label=""), again))
                if opts.arcs:
                    units.extend(_arcs(base, mover, anchor, current, opts))
            for name, unit, times in units:
                out.append(Candidate(name, unit, 0.0, {mover: unit.end_pose()}))
                if anchor not in opts.fixed_nodes and opts.anchor_turns:  # the hovering peer turns meanwhile
                    both = replace(unit, anchor_turn_deg=360.0 * times, label="")
                    out.append(Candidate(f"{name}, {anchor} turning", both, 0.0,
                                         {mover: both.end_pose(), anchor: (tuple(pa), both.anchor_end_yaw_deg())}))
    if opts.library:
        for i, a in enumerate(names):
            for b in names[i + 1:]:
                out.extend(_library(state, a, b, opts))
    if opts.min_separation_m > 0:  # nodes already nearer may stay as near, never come nearer
        now = min(float(np.linalg.norm(state[a][0] - state[b][0])) for i, a in enumerate(names) for b in names[i + 1:])
        floor = min(opts.min_separation_m, now - 1e-6)
        out = [c for c in out if closest_approach_m(c.unit, state) >= floor]
    return out


@check_types
def with_start(candidate: Candidate, label: str) -> Candidate:
    """The candidate with its unit relabelled (labels must be unique in a campaign)."""
    return replace(candidate, unit=replace(candidate.unit, label=label))


__all__ = ["MANOEUVRE_KINDS", "MIN_CLIMB_M", "Candidate", "CandidateOptions", "ManoeuvreUnit", "candidate_manoeuvres", "with_start"]
