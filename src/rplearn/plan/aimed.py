"""Manoeuvres aimed at given body-frame directions of the nodes (where a posterior is widest).

The fixed candidates of :func:`rplearn.plan.manoeuvres.candidate_manoeuvres` sweep whole rings at
elevations of a fixed grid. :func:`aimed_manoeuvres` instead builds, for each node and each
*aim* (a direction in that node's body frame, az/el [rad], e.g. where its pattern's posterior
variance is largest now), the manoeuvres that make the node look along it:

- the node is the **mover**: its peer (the anchor) appears at body elevation ``el`` when the
  mover is at elevation ``-el`` seen from the anchor, and at body azimuth ``az`` when its
  heading is the bearing to the anchor minus ``az``: a climb (or descent) there, then a turn
  that passes that heading and goes :data:`AIM_SECTOR_DEG` / 2 beyond it (or the turn alone
  when the elevation is already the one wanted; not both at once: a spiral passes the heading
  before the elevation), and an orbit at that elevation;
- the node is the **anchor**, hovering: the mover climbs to elevation ``el`` seen from it while
  the anchor turns past the heading that puts the mover at body azimuth ``az`` (a full circle
  more if it would pass it before the climb ends; or the anchor turns alone when the elevation
  is already the one wanted), and an orbit of the mover at that elevation;
- the node is the **anchor**, a static station (``CandidateOptions.fixed_nodes``): the mover
  goes to where the station sees it along the aim (same distance; the way there is the
  candidate's lead time) and turns a full circle there, or orbits the station at the aim's
  elevation.

Every candidate keeps the options' height limits and minimum separation (the way to a station's
aim included). ENU [m], yaw ccw from east; a level node's body azimuth of a peer is the world
bearing to it minus the heading. Off by default (``ManoeuvreOptions.aimed``): flown in the
simulator they met the acceptance checks in fewer cells than the fixed candidates alone
(``benchmarks/manoeuvres.py --aimed 3``: 2 of 12 against 7).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import replace
from typing import Any

import numpy as np

from rplearn._argtypes import check_types
from rplearn.errors import InputError
from rplearn.plan.manoeuvres import Candidate, CandidateOptions, ManoeuvreUnit, closest_approach_m, lead_time_s

#: The turn past an aimed heading: it goes this far beyond it [deg] (half before, when the
#: turn starts that far away), so the aim is seen over a sector, not at one instant.
AIM_SECTOR_DEG = 120.0
#: Largest elevation magnitude an aimed climb or orbit goes to [deg] (a pole of the body frame
#: needs the peer straight above or below; :class:`ManoeuvreUnit` accepts at most 89).
MAX_AIM_EL_DEG = 85.0


def _wrap_deg(angle: float) -> float:
    return float((angle + 180.0) % 360.0 - 180.0)


def _turn_through(yaw_now_deg: float, yaw_aim_deg: float, sector_deg: float) -> float:
    """A signed turn from ``yaw_now_deg`` that passes ``yaw_aim_deg`` and goes ``sector/2`` beyond it [deg]."""
    d = _wrap_deg(yaw_aim_deg - yaw_now_deg)
    return d + (0.5 * sector_deg if d >= 0 else -0.5 * sector_deg)


def _after_climb(unit: ManoeuvreUnit, yaw_aim_deg: float) -> float:
    """The anchor's turn of ``unit`` (a climb while the anchor turns), a full circle longer if it
    passes ``yaw_aim_deg`` only before the mover has reached its elevation [deg]."""
    climb_s = unit._segment_duration(unit._segments[0]) if unit._segments else 0.0
    t = np.linspace(climb_s, unit.duration_s, 64)
    yaw = np.degrees(unit.evaluate(t).yaw_rad[:, 0])
    off = np.abs((yaw - yaw_aim_deg + 180.0) % 360.0 - 180.0)
    turn = float(unit.anchor_turn_deg)
    return turn if float(np.min(off)) <= 0.25 * AIM_SECTOR_DEG else turn + float(np.sign(turn) or 1.0) * 360.0


def _bearing_deg(frm: np.ndarray, to: np.ndarray) -> float:
    return float(np.degrees(np.arctan2(to[1] - frm[1], to[0] - frm[0])))


def _segment_clear_m(p0: np.ndarray, p1: np.ndarray, point: np.ndarray) -> float:
    """Closest distance of ``point`` to the segment ``p0 -> p1`` [m]."""
    d = p1 - p0
    s = 0.0 if float(d @ d) == 0 else float(np.clip((point - p0) @ d / float(d @ d), 0.0, 1.0))
    return float(np.linalg.norm(p0 + s * d - point))


def _pair(state: Mapping[str, tuple[np.ndarray, float]], mover: str, anchor: str, aims: Mapping[str, Sequence[Any]],
          opts: CandidateOptions, rings: bool) -> list[Candidate]:
    pm, ym = state[mover]
    pa, ya = state[anchor]
    d = pm - pa
    horiz = float(np.hypot(d[0], d[1]))
    if horiz < 1.0:
        return []
    current = float(np.degrees(np.arctan2(d[2], horiz)))
    base: dict[str, Any] = dict(nodes=(anchor, mover), anchor_enu_m=tuple(float(v) for v in pa), start_enu_m=tuple(float(v) for v in pm),
                anchor_yaw_deg=ya, start_yaw_deg=ym, speed_m_s=opts.speed_m_s, accel_m_s2=opts.accel_m_s2,
                yaw_rate_deg_s=opts.yaw_rate_deg_s)
    units: list[tuple[str, ManoeuvreUnit, float]] = []  # (name, unit, lead time [s])
    fixed_anchor = anchor in opts.fixed_nodes

    def climbs(el: float, what: str, **kw: Any) -> None:
        """Climb-like units to elevation ``el`` from the anchor (nothing if the heights forbid it)."""
        for kind in kw.pop("kinds"):
            unit = ManoeuvreUnit(kind=kind, elevation_deg=el, **base, **kw)
            z = float(unit._target_position()[2])
            if not opts.min_height_m <= z <= opts.max_height_m:
                continue
            units.append((f"{kind.replace('_', ' ')} of {mover} to el {el:+.0f} deg from {anchor}, {what}", unit, 0.0))

    for k, (az, el) in enumerate(aims.get(mover, ())):  # the mover looks along its aim
        want = float(np.clip(-np.degrees(el), -MAX_AIM_EL_DEG, MAX_AIM_EL_DEG))
        turn = 360.0 if rings else _turn_through(ym, _bearing_deg(pm, pa) - float(np.degrees(az)), AIM_SECTOR_DEG)
        what = f"aimed at {mover}'s direction {k + 1}"
        if abs(want - current) >= 1.0:
            climbs(want, what, kinds=("climb_turn",), turn_deg=turn)
        else:
            units.append((f"yaw turn of {mover} by {turn:+.0f} deg, {what}", ManoeuvreUnit(kind="yaw", turn_deg=turn, **base), 0.0))
        climbs(want, what, kinds=("orbit",))
    for k, (az, el) in enumerate(aims.get(anchor, ())):  # the anchor sees the mover along its aim
        want = float(np.clip(np.degrees(el), -MAX_AIM_EL_DEG, MAX_AIM_EL_DEG))
        what = f"aimed at {anchor}'s direction {k + 1}"
        if not fixed_anchor and not rings:
            turn = _turn_through(ya, _bearing_deg(pa, pm) - float(np.degrees(az)), AIM_SECTOR_DEG)
            if abs(want - current) >= 1.0:
                turn = _after_climb(ManoeuvreUnit(kind="climb", elevation_deg=want, anchor_turn_deg=turn, **base),
                                    _bearing_deg(pa, pm) - float(np.degrees(az)))
                climbs(want, f"{anchor} turning by {turn:+.0f} deg, {what}", kinds=("climb",), anchor_turn_deg=turn)
            else:
                units.append((f"{anchor} turning by {turn:+.0f} deg, {mover} holding, {what}",
                              ManoeuvreUnit(kind="yaw", turn_deg=0.0, anchor_turn_deg=turn, **base), 0.0))
        climbs(want, what, kinds=("orbit",))
        if not fixed_anchor or rings:
            continue
        bearing = np.radians(ya + float(np.degrees(az)))
        dist = float(np.linalg.norm(d))
        e = np.radians(want)
        goal = pa + dist * np.array([np.cos(e) * np.cos(bearing), np.cos(e) * np.sin(bearing), np.sin(e)])
        if not opts.min_height_m <= float(goal[2]) <= opts.max_height_m or np.hypot(*(goal - pa)[:2]) < 1.0:
            continue
        if opts.min_separation_m > 0 and _segment_clear_m(pm, goal, pa) < min(opts.min_separation_m, dist - 1e-6):
            continue  # the way there passes too near the station
        unit = ManoeuvreUnit(kind="yaw", **{**base, "start_enu_m": tuple(float(v) for v in goal)})
        units.append((f"{mover} to where {anchor} sees it along the aim, turning, {what}", unit,
                      lead_time_s([float(np.linalg.norm(goal - pm))], opts)))
    out: list[Candidate] = []
    for name, unit, lead in units:
        ends = {mover: unit.end_pose()}
        if unit.anchor_turn_deg:
            ends[anchor] = ((float(pa[0]), float(pa[1]), float(pa[2])), unit.anchor_end_yaw_deg())
        out.append(Candidate(name, replace(unit, label=f"aim{len(out)}_{unit.label}"), float(lead), ends))
    return out


@check_types
def aimed_manoeuvres(poses: Mapping[str, tuple[tuple[float, float, float], float]], aims: Mapping[str, Sequence[Any]],
                     options: CandidateOptions | None = None, rings: bool = False) -> list[Candidate]:
    """Manoeuvres that make each node look along its aims (module docstring).

    Parameters
    ----------
    poses : mapping of node to ((x, y, z), yaw_deg)
        Each node's current position (ENU [m]) and heading [deg].
    aims : mapping of node to sequence of (az, el)
        Per node, body-frame directions to look along [rad] (nodes without aims: none).
    options : CandidateOptions, optional
        Speeds, heights, fixed nodes and the minimum separation, as for the fixed candidates.
    rings : bool
        Aim the elevation only: every turn a full circle (a hovering anchor's too, in place, with
        the climb) and no move to a station's aim (its orbit only), instead of the sector turns.
    """
    opts = options or CandidateOptions()
    if len(poses) < 2:
        raise InputError(f"poses: expected at least two nodes, got {len(poses)}", param="poses")
    unknown = sorted(str(n) for n in aims if str(n) not in {str(p) for p in poses})
    if unknown:
        raise InputError(f"aims: node(s) {', '.join(unknown)} have no pose", param="aims")
    state = {str(n): (np.asarray(p, np.float64), float(y)) for n, (p, y) in poses.items()}
    names = sorted(state)
    out: list[Candidate] = []
    for mover in names:
        if mover in opts.fixed_nodes:
            continue
        for anchor in names:
            if anchor != mover:
                out.extend(_pair(state, mover, anchor, {str(n): list(v) for n, v in aims.items()}, opts, rings))
    if opts.min_separation_m > 0:
        now = min(float(np.linalg.norm(state[a][0] - state[b][0])) for i, a in enumerate(names) for b in names[i + 1:])
        floor = min(opts.min_separation_m, now - 1e-6)
        out = [c for c in out if closest_approach_m(c.unit, state) >= floor]
    return out


__all__ = ["AIM_SECTOR_DEG", "MAX_AIM_EL_DEG", "aimed_manoeuvres"]
