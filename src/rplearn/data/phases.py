"""Flight phases: the log's start, a time window, when vehicles are airborne, the ``max_gap_s``
a pose rate needs, and whether a log holds a calibration flight at all.

**Log start.** Times given "from the log start" (``SyncOptions(window_clock="start")``, what
``rplearn inspect`` prints) count from the first pose of a moving node on the common clock
(after clock offsets), or the first pose of any node when none moves.

**Airborne.** A vehicle is airborne while it is armed (where its pose log has an ``armed``
column, as MAVLink readers give it; a node without one is taken as armed) and higher than its
**take-off altitude** by more than ``margin_m`` (default :data:`AIRBORNE_MARGIN_M`). The take-off
altitude of a node is its lowest altitude while it **holds still**: over :data:`SETTLE_S`
seconds, its one-second mean positions stay within :data:`STILL_VERTICAL_M` vertically and
:data:`STILL_HORIZONTAL_M` horizontally (a drone on the ground before take-off or after landing;
GNSS noise is averaged out, a single low outlier does not count), provided the node spends less
than :data:`BELOW_GROUND_SHARE` of its poses more than the margin below it (else that still
stretch was a hover, not the ground). A node that never holds still on the ground (a simulated
or cut calibration flight, which starts and ends in the air, pausing at most a few seconds) is
airborne throughout. The margin, 2 m,
is above the altitude noise of a barometer or GNSS (0.5-1 m) and the height of a drone's legs,
and below any calibration flight. A **vehicle** is a node that is ever armed or ever airborne;
the others (a ground station, a node that never leaves the ground) do not restrict samples. A
log where no node is a vehicle holds no flight: every sample is on the ground.

**No calibration flight.** :func:`calibration_problems` says when a log cannot teach a pattern:
no node ever airborne, or two linked nodes never farther apart than
:func:`calibration_distance_m`: the larger of :data:`CALIBRATION_WAVELENGTHS` wavelengths (well
into the far field, where eq. 1 holds) and :data:`CALIBRATION_MIN_DISTANCE_M` (below it, the
1-2 m error of a consumer GNSS position turns the directions between the nodes by more than
10-20 deg).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from itertools import combinations

import numpy as np
import pandas as pd

from rplearn._argtypes import check_types
from rplearn.core.link import SPEED_OF_LIGHT_M_S
from rplearn.data.poses import PoseTrack
from rplearn.errors import InputError

#: A vehicle higher than its take-off altitude by more than this is airborne [m].
AIRBORNE_MARGIN_M: float = 2.0
#: A node holds still when its 1 s mean positions stay within these over this long [s] ...
SETTLE_S: int = 10
#: ... vertically [m] ...
STILL_VERTICAL_M: float = 0.5
#: ... and horizontally [m].
STILL_HORIZONTAL_M: float = 1.0
#: A still stretch with more than this share of the node's poses well below it is a hover.
BELOW_GROUND_SHARE: float = 0.01
#: The ``max_gap_s`` advised for a slow pose log, in units of its median pose interval.
MAX_GAP_FACTOR: float = 1.5
#: A calibration flight takes two linked nodes farther apart than this many wavelengths ...
CALIBRATION_WAVELENGTHS: float = 10.0
#: ... and farther than this [m].
CALIBRATION_MIN_DISTANCE_M: float = 5.0
#: Frequency assumed when a log does not say it: the lowest band drone radios use (433 MHz), so
#: the longest wavelength and the most demanding distance [Hz].
UNKNOWN_FREQUENCY_HZ: float = 433e6
#: How ``SyncOptions.from_s``/``to_s`` are read: seconds from the log start, or log time.
WINDOW_CLOCKS: tuple[str, ...] = ("start", "log")


def log_start_s(tracks: Mapping[str, PoseTrack]) -> float:
    """The log start [s, common clock]: the first pose of a moving node (of any node if none moves)."""
    moving = [float(tr.t_s[0]) for tr in tracks.values() if not tr.static]
    every = [float(tr.t_s[0]) for tr in tracks.values()]
    return min(moving) if moving else (min(every) if every else 0.0)


def window_mask(t_s: np.ndarray, from_s: float | None, to_s: float | None, origin_s: float) -> np.ndarray:
    """True for times inside ``[origin_s + from_s, origin_s + to_s]`` (an open end when None) [s]."""
    t = np.asarray(t_s, np.float64)
    keep = np.ones(t.shape, bool)
    with np.errstate(invalid="ignore"):
        if from_s is not None:
            keep &= t >= origin_s + float(from_s)
        if to_s is not None:
            keep &= t <= origin_s + float(to_s)
    return keep


def takeoff_altitude_m(t_s: np.ndarray, position_xyz: np.ndarray) -> float:
    """Lowest altitude while the node holds still [m] (module docstring); NaN when it never does.

    Parameters
    ----------
    t_s : ndarray (n,)
        Pose times [s].
    position_xyz : ndarray (n, 3)
        ENU positions [m].
    """
    t = np.asarray(t_s, np.float64)
    xyz = np.asarray(position_xyz, np.float64)
    if not (np.isfinite(np.sum(t)) and np.isfinite(np.sum(xyz))):  # a finite sum: every value finite
        ok = np.isfinite(t) & np.isfinite(xyz).all(axis=1)
        t, xyz = t[ok], xyz[ok]
    if t.size == 0:
        return float("nan")
    # the seconds holding a pose only: a log's span (a corrupt or sentinel time, a clock that
    # jumps years) never sizes an array
    seconds, second = np.unique(np.floor(t - t[0]), return_inverse=True)
    if seconds.size < SETTLE_S:
        return float("nan")
    count = np.bincount(second)
    mean = np.column_stack([np.bincount(second, xyz[:, j]) / count for j in range(3)])
    windows = np.lib.stride_tricks.sliding_window_view(mean, SETTLE_S, axis=0)  # (bins, 3, SETTLE_S)
    spread = windows.max(axis=2) - windows.min(axis=2)
    still = (np.hypot(spread[:, 0], spread[:, 1]) <= STILL_HORIZONTAL_M) & (spread[:, 2] <= STILL_VERTICAL_M)
    still &= seconds[SETTLE_S - 1:] - seconds[:seconds.size - SETTLE_S + 1] == SETTLE_S - 1  # every second has a pose
    if not still.any():
        return float("nan")
    ground = float(np.median(windows[still, 2, :], axis=1).min())
    return ground if np.mean(xyz[:, 2] < ground - AIRBORNE_MARGIN_M) <= BELOW_GROUND_SHARE else float("nan")


def armed_log(pose_log: pd.DataFrame, clock_offsets_s: Mapping[str, float] | None = None,
              source: str = "pose log") -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Per node, sorted times [s, common clock] and armed flags of the rows of the optional
    ``armed`` column that say it (missing values left out); empty without the column."""
    if "armed" not in pose_log.columns:
        return {}
    try:
        flags = pose_log["armed"].astype("boolean")
    except (TypeError, ValueError) as exc:
        raise InputError(f"{source}: field armed: expected true/false values ({exc})") from None
    known = ~flags.isna().to_numpy()
    t = pd.to_numeric(pose_log["t"], errors="coerce").to_numpy(np.float64)
    node = pose_log["node"].astype(str).to_numpy(dtype=object)
    offsets = dict(clock_offsets_s or {})
    out: dict[str, tuple[np.ndarray, np.ndarray]] = {}
    values = flags.to_numpy(dtype=bool, na_value=False)
    for n in pd.unique(node[known]):
        sel = known & (node == n) & np.isfinite(t)
        order = np.argsort(t[sel], kind="stable")
        out[str(n)] = (t[sel][order] + float(offsets.get(str(n), 0.0)), values[sel][order])
    return out


@check_types
@dataclass(frozen=True)
class FlightPhases:
    """When each node flies: its take-off altitude [m], the highest it rose above it [m], its
    armed flags, which nodes are vehicles, and the log start [s]; see the module docstring."""

    start_s: float
    takeoff_m: Mapping[str, float]
    highest_m: Mapping[str, float]
    armed: Mapping[str, tuple[np.ndarray, np.ndarray]]
    vehicles: tuple[str, ...]
    margin_m: float = AIRBORNE_MARGIN_M

    def armed_at(self, node: str, t_s: np.ndarray) -> np.ndarray:
        """Whether ``node`` is armed at times ``t_s``: its last armed flag at or before each
        time (its first before it); True where its log does not say."""
        if node not in self.armed:
            return np.ones(np.shape(t_s), bool)
        tk, flags = self.armed[node]
        i = np.clip(np.searchsorted(tk, t_s, side="right") - 1, 0, tk.size - 1)
        return flags[i]

    def masks(self, node_ids: Sequence[str], code: np.ndarray, t_s: np.ndarray, z_m: np.ndarray,
              rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """For one end of every sample (node ``node_ids[code[i]]`` at ``t_s[i]``, height ``z_m[i]``),
        masks of the rows (among ``rows``) where it is a vehicle that is disarmed, and one that is
        not airborne (every row when the log has no vehicle)."""
        n = len(t_s)
        disarmed = np.zeros(n, bool)
        if not self.vehicles:
            return disarmed, np.asarray(rows, bool).copy()
        names = [str(node) for node in node_ids]
        for c, node in enumerate(names):  # the vehicles whose log says when they were armed
            if node in self.vehicles and node in self.armed:
                sel = np.flatnonzero((code == c) & rows)
                if sel.size:
                    disarmed[sel] = ~self.armed_at(node, t_s[sel])
        # a vehicle that never holds still has no take-off altitude (NaN): airborne throughout
        takeoff = np.array([self.takeoff_m[node] if node in self.vehicles else np.nan for node in names], np.float64)
        if not np.isfinite(takeoff).any():
            return disarmed, np.zeros(n, bool)
        at = takeoff[code]
        with np.errstate(invalid="ignore"):
            ground = ~(z_m - at > self.margin_m)
        ground &= rows
        ground &= np.isfinite(at)
        return disarmed, ground

    def describe(self) -> str:
        """One line: the vehicles, their take-off altitudes and the rule."""
        if not self.vehicles:
            return (f"no node is ever armed or more than {self.margin_m:g} m above its take-off altitude: "
                    "the log holds no flight")
        each = ", ".join(f"{v} (take-off altitude z = {self.takeoff_m[v]:.1f} m, highest {self.highest_m[v]:.1f} m above it)"
                         if np.isfinite(self.takeoff_m[v]) else f"{v} (never holds still: in the air throughout)"
                         for v in self.vehicles)
        return f"armed (where the log says) and more than {self.margin_m:g} m above the take-off altitude; vehicles: {each}"


@check_types
def flight_phases(pose_log: pd.DataFrame, tracks: Mapping[str, PoseTrack],
                  clock_offsets_s: Mapping[str, float] | None = None,
                  margin_m: float = AIRBORNE_MARGIN_M, source: str = "pose log") -> FlightPhases:
    """The :class:`FlightPhases` of a pose log (``tracks`` made from it; ``pose_log`` for its
    optional ``armed`` column)."""
    armed = armed_log(pose_log, clock_offsets_s, source)
    takeoff, highest, vehicles = {}, {}, []
    for node, tr in sorted(tracks.items()):
        z = tr.position_xyz[:, 2]
        fixed = tr.static or tr.still
        takeoff[node] = float(np.median(z)) if fixed else takeoff_altitude_m(tr.t_s, tr.position_xyz)
        highest[node] = float(np.max(z) - takeoff[node])  # NaN: never holds still, airborne throughout
        ever_armed = node in armed and bool(armed[node][1].any())
        if not fixed and (ever_armed or not highest[node] <= margin_m):
            vehicles.append(node)
    return FlightPhases(log_start_s(tracks), takeoff, highest, armed, tuple(vehicles), float(margin_m))


def phase_notes(phases: FlightPhases, from_s: float | None, to_s: float | None, window_clock: str,
                airborne: bool) -> list[str]:
    """What a time window and the airborne filter do on a log (lines for a sync's summary)."""
    notes = []
    if from_s is not None or to_s is not None:
        clock = "log time" if window_clock == "log" else f"seconds from the log start, t = {phases.start_s:.3f} s"
        lo = "the start" if from_s is None else f"{from_s:g} s"
        hi = "the end" if to_s is None else f"{to_s:g} s"
        notes.append(f"window: samples from {lo} to {hi} kept ({clock})")
    if airborne:
        notes.append(f"airborne only: {phases.describe()}")
    return notes


def _nice_ceil(x: float) -> float:
    """``x`` rounded up to two significant digits."""
    if not (x > 0 and math.isfinite(x)):
        return x
    step = 10.0 ** (math.floor(math.log10(x)) - 1)
    return round(math.ceil(x / step - 1e-9) * step, 12)


def advised_max_gap_s(pose_interval_s: float) -> float:
    """The ``max_gap_s`` a pose log with this median interval needs [s]: :data:`MAX_GAP_FACTOR`
    times it, rounded up to two digits."""
    return _nice_ceil(MAX_GAP_FACTOR * float(pose_interval_s))


@check_types
def max_gap_advice(tracks: Mapping[str, PoseTrack], max_gap_s: float) -> str | None:
    """What ``max_gap_s`` the slowest moving node's pose rate needs, or None when it is no slower
    than ``max_gap_s`` allows.

    The advice is :data:`MAX_GAP_FACTOR` times the node's median pose interval (rounded up to
    two digits), with the share of each moving node's log span it leaves bridged (a sample
    falls in a pose gap only when one of its ends' poses are farther apart than ``max_gap_s``).
    """
    moving = {n: tr for n, tr in tracks.items() if not tr.static and not tr.still and tr.t_s.size > 1}
    if not moving:
        return None
    medians = {n: float(np.median(np.diff(tr.t_s))) for n, tr in moving.items()}
    slowest = max(medians, key=lambda n: medians[n])
    value = advised_max_gap_s(medians[slowest])
    if value <= max_gap_s:
        return None
    covered = []
    for n, tr in sorted(moving.items()):
        d = np.diff(tr.t_s)
        covered.append(f"{n} {100.0 * d[d <= value].sum() / d.sum():.0f}%")
    return (f"poses of node {slowest} come every {medians[slowest]:.3g} s ({1.0 / medians[slowest]:.2g} Hz), "
            f"more than max_gap_s={max_gap_s:g} allows: max_gap_s={value:g} ({MAX_GAP_FACTOR:g} x that interval) "
            f"bridges the pose steps over {', '.join(covered)} of the log span")


def calibration_distance_m(frequency_hz: float | None) -> float:
    """Distance two linked nodes must exceed for a calibration flight [m] (module docstring)."""
    f = UNKNOWN_FREQUENCY_HZ if frequency_hz is None or not frequency_hz > 0 else float(frequency_hz)
    return max(CALIBRATION_WAVELENGTHS * SPEED_OF_LIGHT_M_S / f, CALIBRATION_MIN_DISTANCE_M)


def largest_distance_m(a: PoseTrack, b: PoseTrack) -> float:
    """The largest distance between two nodes over their common time span, at the poses of
    either [m] (positions interpolated linearly, a static node's held); NaN without overlap."""
    if a.static or b.static:
        times = (b if a.static else a).t_s
    else:
        lo, hi = max(a.t_s[0], b.t_s[0]), min(a.t_s[-1], b.t_s[-1])
        times = np.union1d(a.t_s, b.t_s)
        times = times[(times >= lo) & (times <= hi)]
    if times.size == 0:
        return float("nan")

    def at(tr: PoseTrack) -> np.ndarray:
        if tr.static:
            return np.broadcast_to(tr.position_xyz[0], (times.size, 3))
        return np.column_stack([np.interp(times, tr.t_s, tr.position_xyz[:, j]) for j in range(3)])

    return float(np.linalg.norm(at(a) - at(b), axis=1).max())


@check_types
def calibration_problems(phases: FlightPhases, tracks: Mapping[str, PoseTrack],
                         pairs: Sequence[tuple[str, str]] | None = None,
                         frequency_hz: float | None = None) -> list[str]:
    """Lines saying why a log holds no calibration flight (empty when it may hold one).

    Parameters
    ----------
    phases : FlightPhases
        Of the pose log.
    tracks : mapping of node id to PoseTrack
        The pose log's tracks.
    pairs : sequence of (str, str), optional
        Linked nodes (directions of the signal log); every pair of nodes by default.
    frequency_hz : float, optional
        Carrier frequency [Hz]; :data:`UNKNOWN_FREQUENCY_HZ` when not known.
    """
    out = []
    if len(tracks) and not phases.vehicles:
        highest = ", ".join(f"{n} {h:.1f} m" for n, h in sorted(phases.highest_m.items()) if not tracks[n].static)
        armed = [n for n in phases.armed if n in tracks and not (tracks[n].static or tracks[n].still)]
        never = f"; never armed: {', '.join(sorted(armed))}" if armed else ""
        out.append(f"no calibration flight: no node ever rises more than {phases.margin_m:g} m above its take-off "
                   f"altitude (highest above it: {highest or 'static nodes only'}){never}")
    links = sorted({tuple(sorted(p)) for p in (pairs or combinations(sorted(tracks), 2))
                    if p[0] in tracks and p[1] in tracks and p[0] != p[1]})
    need = calibration_distance_m(frequency_hz)
    f = frequency_hz if frequency_hz and frequency_hz > 0 else None
    how = (f"{CALIBRATION_WAVELENGTHS:g} wavelengths at {(f or UNKNOWN_FREQUENCY_HZ) / 1e6:g} MHz"
           + ("" if f else " (frequency unknown: the lowest drone band assumed)")
           + f", and at least {CALIBRATION_MIN_DISTANCE_M:g} m")
    close = [(a, b, largest_distance_m(tracks[a], tracks[b])) for a, b in links]
    close = [(a, b, d) for a, b, d in close if np.isfinite(d) and d <= need]
    for a, b, d in close:
        lead = "no calibration flight: " if len(close) == len(links) else ""
        out.append(f"{lead}nodes {a} and {b} never get farther apart than {d:.1f} m (a calibration flight needs "
                   f"more than {need:.1f} m: {how})")
    return out


__all__ = [
    "AIRBORNE_MARGIN_M", "CALIBRATION_MIN_DISTANCE_M", "advised_max_gap_s", "CALIBRATION_WAVELENGTHS", "FlightPhases", "MAX_GAP_FACTOR",
    "BELOW_GROUND_SHARE", "SETTLE_S", "STILL_HORIZONTAL_M", "STILL_VERTICAL_M", "UNKNOWN_FREQUENCY_HZ", "WINDOW_CLOCKS", "armed_log", "calibration_distance_m",
    "calibration_problems", "flight_phases", "largest_distance_m", "log_start_s", "max_gap_advice", "phase_notes",
    "takeoff_altitude_m", "window_mask",
]
