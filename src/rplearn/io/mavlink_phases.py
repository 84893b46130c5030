"""Flight phases and record hygiene of ArduPilot logs, for :mod:`rplearn.io.mavlink`.

Position fixes before a valid position solution
    An autopilot reports positions before its estimator has an origin (ArduPilot's EKF
    reports ``GLOBAL_POSITION_INT.alt`` near 0 m until the origin is set, which can put a
    vehicle ~90 m below its station) and again after every reboot. A fix is invalid when the
    log says so (GPS fix below 3-D: ``GPS_RAW_INT.fix_type`` / DataFlash ``GPS.Status`` < 3)
    or when it lies on the wrong side of a *position step the logged speed does not explain*:
    a jump between consecutive fixes larger than ``(speed + STEP_SPEED_SLACK_M_S) * dt +
    STEP_MARGIN_M``, horizontally and vertically apart, with the speed the larger logged one of
    the two fixes (``GLOBAL_POSITION_INT`` vx, vy, vz), else a plausible maximum
    (:data:`MAX_HORIZONTAL_SPEED_M_S`, :data:`MAX_VERTICAL_SPEED_M_S`). Such steps cut a
    boot's fixes into pieces. Which side is invalid: an estimator's position, once valid,
    stays valid until the next reboot, so the boot's *last* piece is valid, and an earlier
    piece is valid only when it joins the valid fixes after it with a displacement the speed
    explains (a glitch that returns is one invalid piece; the stretch from the boot's start to
    the step where the origin was set is another). Nothing is tuned to the 0.8 m of the real
    case: any fixed, stale or jumping value far enough from the truth gives such a step.
    ``HOME_POSITION`` / ``GPS_GLOBAL_ORIGIN`` (DataFlash ``ORGN``) times are named in the
    evidence of a period but do not by themselves invalidate fixes (an excerpt of a log, or a
    ground station that joins mid-flight, sees its first origin message late).

Reboots
    The boot clock (``time_boot_ms``, ``TimeUS``) stepping back by more than
    :data:`REBOOT_STEP_S` is a reboot; from the vehicle's last message before it until its
    first valid fix after it is excluded (``after_reboot``).

Excluded periods
    Each is a dict ``reason`` (``before_valid_position``: from the log start; ``after_reboot``;
    ``invalid_position``: a piece inside a boot), ``from_t``, ``to_t`` (log time [s], the
    clock of the pose and signal ``t``), ``pose_rows``, ``signal_rows`` and ``detail`` (one
    line of the evidence). Rows strictly inside ``(from_t, to_t)`` are dropped (a period from
    the log start includes it).

One row per radio reading
    A reading reported twice (DataFlash writes each ``RAD`` twice, 2-6 ms apart; a ground
    station's tlog may carry it as both ``RADIO`` and ``RADIO_STATUS``) is one reading: a
    report identical in every field to the previous one and less than a quarter of the
    report period after it is a copy, when such copies are systematic (far more frequent
    than two distinct consecutive readings are equal by chance; a fast radio's chance
    coincidences stay rows). The report period is the median spacing of consecutive
    *distinct* readings.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

#: A boot clock stepping back by more than this is a reboot [s].
REBOOT_STEP_S = 1.0
#: Plausible top speeds of a small drone, used when a log carries no velocity [m/s].
MAX_HORIZONTAL_SPEED_M_S = 40.0
MAX_VERTICAL_SPEED_M_S = 20.0
#: Speed change allowed between two fixes beyond the larger logged speed [m/s].
STEP_SPEED_SLACK_M_S = 5.0
#: Position noise a step must exceed to count (GPS altitude jumps of a few metres) [m].
STEP_MARGIN_M = 5.0
#: A copy of a reading follows it within this fraction of the report period.
DUPLICATE_FRACTION_OF_PERIOD = 0.25

REASONS = ("before_valid_position", "after_reboot", "invalid_position")


def boot_ids(t_boot_s: np.ndarray) -> np.ndarray:
    """Boot number of each message in file order: +1 where the boot clock steps back."""
    t = np.asarray(t_boot_s, np.float64)
    return np.concatenate([[0], np.cumsum(np.diff(t) < -REBOOT_STEP_S)]).astype(np.int64) if len(t) else np.zeros(0, np.int64)


def logged_speeds(speed: np.ndarray, fallback: float) -> np.ndarray:
    """The speeds [m/s] a log reports with its fixes, as magnitudes; ``fallback`` where one is not a number."""
    s = np.abs(np.asarray(speed, np.float64))
    return np.where(np.isfinite(s), s, fallback)


def step_allowed(dt: np.ndarray, speed_a: np.ndarray, speed_b: np.ndarray) -> np.ndarray:
    """Largest displacement [m] two fixes ``dt`` [s] apart may show, given their speeds [m/s]."""
    return (np.maximum(speed_a, speed_b) + STEP_SPEED_SLACK_M_S) * np.abs(dt) + STEP_MARGIN_M


def unexplained_steps(ta: np.ndarray, xa: np.ndarray, ha: np.ndarray, va: np.ndarray, tb: np.ndarray, xb: np.ndarray,
                 hb: np.ndarray, vb: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Whether going from fixes a to fixes b is a step the speeds do not explain, with the
    horizontal and vertical displacements [m]."""
    dt = tb - ta
    dh = np.hypot(xb[..., 0] - xa[..., 0], xb[..., 1] - xa[..., 1])
    dv = np.abs(xb[..., 2] - xa[..., 2])
    bad = (dh > step_allowed(dt, ha, hb)) | (dv > step_allowed(dt, va, vb))
    return bad, dh, dv


def invalid_fixes(t: np.ndarray, xyz: np.ndarray, speed_h: np.ndarray, speed_v: np.ndarray,
                  boot: np.ndarray, fix_ok: np.ndarray, joined: np.ndarray | None = None) -> tuple[np.ndarray, dict[int, str]]:
    """Which fixes (sorted by ``t`` within each boot) are not a valid position (module docstring).

    Parameters
    ----------
    t : ndarray
        Fix times [s]; ``xyz`` (n, 3) their ENU positions [m].
    speed_h, speed_v : ndarray
        Logged horizontal and vertical speeds [m/s] (NaN: not logged).
    boot : ndarray
        Boot number of each fix.
    fix_ok : ndarray of bool
        False where the log says the GPS fix is below 3-D.
    joined : ndarray of bool, optional
        True where a fix is known to join the fix before it (the two ends of a piece whose
        fixes between were read earlier: :mod:`rplearn.io.tlog_window`); no step is looked for there.

    Returns
    -------
    invalid : ndarray of bool
    steps : dict
        Index of the last invalid fix before a step -> one line describing the step.
    """
    t, xyz = np.asarray(t, np.float64), np.asarray(xyz, np.float64)
    h = logged_speeds(speed_h, MAX_HORIZONTAL_SPEED_M_S)
    v = logged_speeds(speed_v, MAX_VERTICAL_SPEED_M_S)
    logged = np.isfinite(np.asarray(speed_v, np.float64))
    invalid = ~np.asarray(fix_ok, bool)
    steps: dict[int, str] = {}
    for b in np.unique(boot):
        idx = np.flatnonzero((boot == b) & ~invalid)
        if len(idx) < 2:
            continue
        a, c = idx[:-1], idx[1:]
        bad, _, _ = unexplained_steps(t[a], xyz[a], h[a], v[a], t[c], xyz[c], h[c], v[c])
        if joined is not None:
            bad &= ~np.asarray(joined, bool)[c]
        cuts = np.flatnonzero(bad) + 1
        starts, ends = np.concatenate([[0], cuts]), np.concatenate([cuts, [len(idx)]])
        chain = idx[starts[-1]]  # first fix of the valid fixes after the piece
        for lo, hi in zip(starts[-2::-1], ends[-2::-1]):
            members = idx[lo:hi]
            last = members[-1]
            jump, dh, dv = unexplained_steps(t[last], xyz[last], h[last], v[last], t[chain], xyz[chain], h[chain], v[chain])
            if jump:
                invalid[members] = True
                speed = "logged" if logged[last] and logged[chain] else "plausible maximum"
                steps[int(last)] = (f"a step of {float(dv):.1f} m up/down and {float(dh):.1f} m across in "
                                    f"{float(t[chain] - t[last]):.2f} s that the {speed} speed does not explain")
            else:
                chain = members[0]
    return invalid, steps


@dataclass(frozen=True)
class Fixes:
    """The vehicle's position fixes, sorted by time: their times [s], which are invalid
    (:func:`invalid_fixes`), their boot (:func:`boot_ids`), which have a 3-D GPS fix, and the
    steps found (fix index -> what the step was)."""

    t: np.ndarray
    invalid: np.ndarray
    boot: np.ndarray
    fix_ok: np.ndarray
    steps: dict[int, str]


@dataclass(frozen=True)
class LogClock:
    """What a log says about time: its first and last message [s], the time of each boot's last
    vehicle message (``boot_last_t[b]``), and the times of the origin messages (named
    ``origin_name`` in the evidence)."""

    log_start: float
    log_end: float
    boot_last_t: np.ndarray
    origin_t: np.ndarray
    origin_name: str


def excluded_periods(fixes: Fixes, clock: LogClock) -> list[dict[str, Any]]:
    """The periods to exclude (module docstring), rows not yet counted.

    Each period carries ``lo`` and ``hi``, the open bounds rows are dropped inside.
    """
    t, invalid, boot = fixes.t, fixes.invalid, fixes.boot
    boot_last_t, log_start, log_end = clock.boot_last_t, clock.log_start, clock.log_end
    periods: list[dict[str, Any]] = []
    n_boots = int(boot.max()) + 1 if len(boot) else 1
    for b in range(n_boots):
        idx = np.flatnonzero(boot == b)
        if not len(idx):
            continue
        bad = invalid[idx]
        runs = np.flatnonzero(np.diff(np.concatenate([[0], bad.astype(int), [0]])))
        starts, ends = runs[0::2], runs[1::2]
        if b > 0 and (not len(starts) or starts[0] != 0):
            starts, ends = np.concatenate([[0], starts]), np.concatenate([[0], ends])  # a reboot is excluded even with valid fixes
        for s, e in zip(starts, ends):
            first, members = s == 0, idx[s:e]
            after = idx[e] if e < len(idx) else None
            hi = float(t[after]) if after is not None else (log_end if b == n_boots - 1 else float(t[idx[-1]]))
            if first and b == 0:
                reason, lo, shown = "before_valid_position", -np.inf, log_start
            elif first:
                reason, lo = "after_reboot", float(boot_last_t[b - 1])
                shown = lo
            else:
                reason, lo = "invalid_position", float(t[idx[s - 1]])
                shown = lo
            if after is None and b < n_boots - 1:
                hi = float(boot_last_t[b])
                hi = np.nextafter(hi, np.inf)
            periods.append({"reason": reason, "lo": lo, "hi": hi, "from_t": float(shown),
                            "to_t": float(min(hi, log_end)),
                            "detail": _evidence(reason, members, fixes, clock,
                                                boot_last_t[b - 1] if b > 0 else None)})
    return periods


def _evidence(reason: str, members: np.ndarray, fixes: Fixes, clock: LogClock, reboot_t: float | None) -> str:
    """One line of what the log says about a period (times from the log start [s])."""
    t, steps, fix_ok = fixes.t, fixes.steps, fixes.fix_ok
    origin_t, origin_name, log_start = clock.origin_t, clock.origin_name, clock.log_start
    parts = []
    if reboot_t is not None:
        parts.append(f"the boot clock went back (reboot) after {reboot_t - log_start:.1f} s")
    if len(members):
        no_fix = int((~fix_ok[members]).sum())
        if no_fix:
            parts.append(f"{no_fix} fix(es) with a GPS fix below 3-D")
        step = steps.get(int(members[-1]))
        if step:
            parts.append(step)
        if len(origin_t) and (reboot_t is None or np.any(origin_t > reboot_t)):
            lo = -np.inf if reboot_t is None else reboot_t
            later = origin_t[origin_t > lo]
            first = float(later.min()) if len(later) else None
            if first is not None and first >= float(t[members[0]]):
                parts.append(f"no {origin_name} until {first - log_start:.1f} s")
    elif reason == "after_reboot":
        parts.append("no position fix until the vehicle was heard again")
    return "; ".join(parts) or "no valid position"


def in_periods(t: np.ndarray, periods: list[dict[str, Any]]) -> np.ndarray:
    """Index of the period each time lies in (-1: none)."""
    t = np.asarray(t, np.float64)
    if not periods:
        return np.full(len(t), -1, np.int64)
    lo = np.array([p["lo"] for p in periods], np.float64)
    hi = np.array([p["hi"] for p in periods], np.float64)
    order = np.argsort(lo, kind="stable")
    k = np.searchsorted(lo[order], t, side="left") - 1  # the last period starting before t
    inside = (k >= 0) & (t < hi[order][np.clip(k, 0, None)])
    return np.where(inside, order[np.clip(k, 0, None)], -1).astype(np.int64)


def report_period_s(t: np.ndarray, values: np.ndarray) -> float | None:
    """Report period [s] of a radio (``values`` one row per report, sorted by ``t``): the
    median spacing of consecutive distinct readings when at least a quarter of the reports
    change the reading, else (readings that rarely change) the median of the longer half of
    the spacings; None with fewer than two reports."""
    if len(t) < 2:
        return None
    d = np.diff(t)
    change = np.any(values[1:] != values[:-1], axis=1) & (d > 0)
    if change.sum() >= max(3, 0.25 * len(t)):
        return float(np.median(d[change]))
    d = np.sort(d[d > 0])
    return float(np.median(d[len(d) // 2:])) if len(d) else None


def repeated_readings(t: np.ndarray, values: np.ndarray) -> tuple[np.ndarray, float | None]:
    """Which reports (sorted by ``t``) copy an identical one less than a quarter of the report
    period before them (module docstring), and the report period [s].

    Copies are merged only when systematic: identical reports closer than a quarter period
    must be more than three times as many (plus 3) as identical reports a quarter to half a
    period apart, which a radio without copies gives about as often by chance.
    """
    t, values = np.asarray(t, np.float64), np.asarray(values)
    copy = np.zeros(len(t), bool)
    period = report_period_s(t, values)
    if period is None:
        return copy, period
    q = DUPLICATE_FRACTION_OF_PERIOD * period
    order = np.lexsort((t, *values.T[::-1]))  # identical readings together, by time
    v, ts = values[order], t[order]
    same = np.all(v[1:] == v[:-1], axis=1)
    dd = np.diff(ts)
    close, next_window = same & (dd < q), same & (dd >= q) & (dd < 2 * q)
    if close.sum() > 3 * next_window.sum() + 3:
        copy[order[1:][close]] = True
    return copy, period


__all__ = ["DUPLICATE_FRACTION_OF_PERIOD", "Fixes", "LogClock", "MAX_HORIZONTAL_SPEED_M_S", "MAX_VERTICAL_SPEED_M_S", "REASONS",
           "REBOOT_STEP_S", "STEP_MARGIN_M", "STEP_SPEED_SLACK_M_S", "boot_ids", "excluded_periods",
           "in_periods", "invalid_fixes", "logged_speeds", "repeated_readings", "report_period_s", "step_allowed", "unexplained_steps"]
