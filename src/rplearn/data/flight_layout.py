"""What a matched dataset says about how its flight was flown: which nodes held still and how
often each link direction reported.

A model file keeps both (``training.fixed_nodes``, ``training.packet_rate_hz``) so that the next
flight's plan (``rplearn trajectory --optimize --from-model``) is made for the same layout (a
ground station and a drone, or two drones) and the same radio, not for the planner's defaults.

A dataset in memory is read by :func:`fixed_nodes` and :func:`packet_rate_hz`. A dataset read a
chunk at a time (a streamed fit, the parts of a dataset on Dask, the batches of a live session)
is summed up in a :class:`LayoutSketch`, bounded whatever the flight's length, whose parts merge
in the rows' order and which gives both by the same rules (:func:`still_nodes`, :func:`recorded_rate_hz`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd

#: A node holds still when nearly all its learning rows (:data:`STILL_SHARE`) put it within
#: :data:`STILL_RADIUS_M` of its median position and :data:`STILL_ANGLE_DEG` of its mean attitude:
#: a ground station logged with its own GPS and attitude estimate wanders by a metre or two and
#: by degrees (the simulator's station by 1 m and 19 deg of heading), a station ``sync`` holds at
#: one pose not at all, while a drone of a calibration flight moves tens of metres and turns
#: through every heading. A GPS glitch in a few rows does not make a station move.
STILL_RADIUS_M = 5.0
STILL_ANGLE_DEG = 30.0
STILL_SHARE = 0.99
#: Rows read at most to tell who held still (every k-th row, evenly over the flight: the share
#: above holds in such a sample as in the whole, at a bounded cost on a dataset of millions);
#: also the rows a :class:`LayoutSketch` keeps at most.
LAYOUT_ROWS = 100_000
#: Packet rates a fit records [Hz]: outside them two readings a nanosecond apart, or one in hours,
#: say nothing of the radio (none recorded).
RECORDED_RATE_HZ = (1e-3, 1e5)
#: Distinct intervals between readings a :class:`LayoutSketch` keeps per link direction; beyond
#: them the intervals are counted in bins of their logarithm, :data:`FINEST_BIN` wide at first,
#: twice as wide each time more bins than this are filled (a median off by half a bin: 0.01 %
#: at the finest, 0.1 % for intervals spread over 1 ms to 1 s, 0.8 % over 1 ns to a day).
INTERVAL_VALUES = 4096
#: The finest bin of the intervals' natural logarithm (a relative 0.024 %).
FINEST_BIN = 2.0 ** -12

_POSE = ("x", "y", "z", "qw", "qx", "qy", "qz")
_POSE_COLUMNS = tuple(f"{end}_{c}" for end in ("tx", "rx") for c in _POSE)


def fixed_nodes(rows: pd.DataFrame) -> tuple[str, ...] | None:
    """The nodes that hold still over a matched dataset (module constants), as transmitter and
    as receiver alike, sorted (None: the rows carry no poses of both ends).

    Parameters
    ----------
    rows : DataFrame
        Matched samples with ``tx``, ``rx`` and both ends' poses (``tx_x`` ... ``rx_qz``).
    """
    if len(rows) == 0 or any(c not in rows.columns for c in _POSE_COLUMNS):
        return None
    rows = rows.iloc[::-(-len(rows) // LAYOUT_ROWS)]
    poses = np.concatenate([rows[[f"{end}_{c}" for c in _POSE]].to_numpy("float64") for end in ("tx", "rx")])
    codes, names = pd.factorize(pd.concat([rows["tx"], rows["rx"]], ignore_index=True).astype(str))
    return still_nodes(codes, [str(n) for n in names], poses)


def still_nodes(codes: np.ndarray, names: list[str], poses: np.ndarray) -> tuple[str, ...]:
    """The nodes whose poses hold still (module constants), sorted: ``poses[i]`` (``x, y, z, qw,
    qx, qy, qz``) is one of node ``names[codes[i]]``'s poses."""
    return tuple(sorted(str(name) for k, name in enumerate(names) if holds_still(poses[codes == k])))


def holds_still(poses: np.ndarray) -> bool:
    """Whether the rows ``x, y, z, qw, qx, qy, qz`` of one node stay near one pose (module
    constants): the rule :func:`fixed_nodes` reads a flight by, and ``simulate --plan`` a plan's
    references (:func:`rplearn.plan.campaign.still_nodes`)."""
    if not poses.size or not np.all(np.isfinite(poses)):
        return False
    position, q = poses[:, :3], poses[:, 3:]
    norm = np.linalg.norm(q, axis=1)
    if np.any(norm <= 0.0):
        return False
    q = q / norm[:, None]
    # the mean attitude: the principal axis of sum q q^T (a quaternion and its negative alike)
    mean = np.linalg.eigh(q.T @ q)[1][:, -1]
    angle_deg = np.degrees(2.0 * np.arccos(np.clip(np.abs(q @ mean), 0.0, 1.0)))
    distance_m = np.linalg.norm(position - np.median(position, axis=0), axis=1)
    return bool(np.quantile(distance_m, STILL_SHARE) <= STILL_RADIUS_M
                and np.quantile(angle_deg, STILL_SHARE) <= STILL_ANGLE_DEG)


def packet_rate_hz(rows: pd.DataFrame) -> float | None:
    """The rate at which a link direction reported [Hz]: the median over the directions of
    each direction's median rate between consecutive readings (gaps between flights, outages
    and dropped rows do not lower it); None without two readings of one direction at distinct times.

    Parameters
    ----------
    rows : DataFrame
        Matched samples with ``t`` [s], ``tx`` and ``rx``.
    """
    if len(rows) < 2 or any(c not in rows.columns for c in ("t", "tx", "rx")):
        return None
    medians = []
    for _, group in rows.groupby([rows["tx"].astype(str), rows["rx"].astype(str)], sort=True):
        t = np.unique(group["t"].to_numpy("float64"))
        step = np.diff(t[np.isfinite(t)])
        if step.size:
            medians.append(float(np.median(step)))
    return recorded_rate_hz(medians)


def recorded_rate_hz(median_intervals_s: list[float]) -> float | None:
    """The packet rate a fit records [Hz] from each link direction's median interval between
    readings [s]: the median of their rates, None without any or outside :data:`RECORDED_RATE_HZ`."""
    if not median_intervals_s:
        return None
    rate = float(np.median([1.0 / m for m in median_intervals_s]))
    return rate if RECORDED_RATE_HZ[0] <= rate <= RECORDED_RATE_HZ[1] else None


@dataclass
class Intervals:
    """The intervals between one link direction's consecutive distinct reading times, counted:
    exact values while there are at most :data:`INTERVAL_VALUES` of them, else bins of their
    logarithm (``width`` > 0: ``values`` are the bins' numbers ``floor(ln(interval) / width)``).

    Attributes
    ----------
    values, counts : ndarray
        Distinct intervals [s] (or bins) and how many times each was seen.
    width : float
        The bins' width in ``ln`` [s] (0: exact values).
    first, last : float
        The earliest and latest reading times [s] summed up (an interval to the next rows' first).
    """

    values: np.ndarray = field(default_factory=lambda: np.zeros(0))
    counts: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    width: float = 0.0
    first: float = np.inf
    last: float = -np.inf

    def binned(self, width: float) -> np.ndarray:
        """``values`` in bins of ``width`` (at least this one's)."""
        if width == self.width:
            return self.values
        if self.width == 0.0:
            return np.floor(np.log(self.values) / width)
        return np.floor(self.values / round(width / self.width))

    def then(self, later: Intervals) -> Intervals:
        """These intervals, then those of later readings (and the one between them); a new value."""
        width = max(self.width, later.width)
        values = np.concatenate([self.binned(width), later.binned(width)])
        counts = np.concatenate([self.counts, later.counts])
        gap = later.first - self.last
        if np.isfinite(gap) and gap > 0.0:
            values = np.append(values, gap if width == 0.0 else np.floor(np.log(gap) / width))
            counts = np.append(counts, 1)
        out = Intervals(values, counts, width, min(self.first, later.first), max(self.last, later.last))
        return out.counted()

    def counted(self) -> Intervals:
        """The same intervals, each value once with its count, in bins wide enough for at most
        :data:`INTERVAL_VALUES` of them."""
        width = self.width
        values, counts = _summed(self.values, self.counts, exact=width == 0.0)
        if width == 0.0 and values.size > INTERVAL_VALUES:
            width = FINEST_BIN
            values, counts = _summed(np.floor(np.log(values) / width), counts, exact=False)
        while values.size > INTERVAL_VALUES:
            width *= 2.0
            values, counts = _summed(np.floor(values / 2.0), counts, exact=False)
        return Intervals(values, counts, width, self.first, self.last)

    def median_s(self) -> float | None:
        """The median interval [s] (the middle two's mean when they split an even count, as
        :func:`numpy.median`; a bin's geometric middle), None without any."""
        if not self.counts.size:
            return None
        order = np.argsort(self.values)
        values = self.values[order] if self.width == 0.0 else np.exp((self.values[order] + 0.5) * self.width)
        cum = np.cumsum(self.counts[order])
        half = cum[-1] / 2.0
        i = int(np.searchsorted(cum, half))
        if cum[i] == half and i + 1 < values.size:
            return float((values[i] + values[i + 1]) / 2.0)
        return float(values[i])


def _summed(values: np.ndarray, counts: np.ndarray, exact: bool) -> tuple[np.ndarray, np.ndarray]:
    """Each distinct value once with its counts summed, sorted; ``exact``: intervals, else bin
    numbers (counted by :func:`numpy.bincount` over their range when it is short)."""
    if not exact and values.size and values.max() - values.min() < 2 ** 22:
        low = values.min()
        total = np.bincount((values - low).astype(np.int64), weights=counts)
        where = np.flatnonzero(total)
        return where + low, total[where].astype(np.int64)
    if np.all(counts == 1):  # a chunk's intervals, each seen once (faster than by the inverse)
        values, summed = np.unique(values, return_counts=True)
        return values, summed.astype(np.int64)
    values, inverse = np.unique(values, return_inverse=True)
    return values, np.bincount(inverse, weights=counts, minlength=values.size).astype(np.int64)


def _row_keys(rows: pd.DataFrame, posed: bool) -> np.ndarray:
    """A 64-bit key of each row from its content (time and both ends' positions): the rows a
    :class:`LayoutSketch` keeps are those of the smallest keys, whatever the chunks or their order."""
    columns = ["t", *(("tx_x", "rx_x") if posed else ())]
    key = np.zeros(len(rows), np.uint64)
    for c in columns:
        if c in rows.columns:
            bits = np.ascontiguousarray(pd.to_numeric(rows[c], errors="coerce").to_numpy(np.float64)).view(np.uint64)
            key = _mix(key ^ bits)
    return key


def _mix(x: np.ndarray) -> np.ndarray:
    """splitmix64's finaliser: every bit of ``x`` spread over every bit of the result."""
    x = (x ^ (x >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
    x = (x ^ (x >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
    return x ^ (x >> np.uint64(31))


@dataclass
class LayoutSketch:
    """A bounded summary of matched rows read a chunk at a time, from which the layout of their
    flight is read as a dataset in memory gives it (:func:`fixed_nodes`, :func:`packet_rate_hz`).

    Who held still is read from a sample of the rows: those whose 64-bit content key
    (:func:`_row_keys`) is below ``2**(64 - level)``, ``level`` the smallest that keeps at most
    :data:`LAYOUT_ROWS` of them. The sample is the same whatever the chunks, parts and their order
    (the whole set of rows when there are at most :data:`LAYOUT_ROWS`), and about an even half to
    all of the limit otherwise. The packet rate is read from each link direction's
    :class:`Intervals` between consecutive distinct reading times, within each chunk and from the
    rows before a chunk to its first (lost where a chunk's first reading is not later than the last
    one before it: rows out of time order).

    Memory does not grow with the flight: at most :data:`LAYOUT_ROWS` rows of 136 bytes (the key,
    both ends' node codes and 14 pose numbers: 13.6 MB) and, per link direction, at most
    :data:`INTERVAL_VALUES` intervals of 16 bytes (64 kB).

    Attributes
    ----------
    rows : int
        Rows summed up.
    posed : bool
        Whether every chunk carried both ends' poses.
    level : int
    names : list of str
        The node ids the codes name.
    keys, codes, poses : ndarray
        The sampled rows' keys, ``(tx, rx)`` codes and poses (``tx_x`` ... ``rx_qz``).
    links : dict of (str, str) to Intervals
    relative : bool
        Whether any row is of relative received power (``rssi_scale`` = ``relative``, from
        ``sync --rssi-scale relative``): a fit of them records ``training.rssi_scale`` as a fit in
        memory does, so that nothing downstream prints their levels as dBm.
    """

    rows: int = 0
    posed: bool = True
    level: int = 0
    names: list[str] = field(default_factory=list)
    keys: np.ndarray = field(default_factory=lambda: np.zeros(0, np.uint64))
    codes: np.ndarray = field(default_factory=lambda: np.zeros((0, 2), np.int64))
    poses: np.ndarray = field(default_factory=lambda: np.zeros((0, 2 * len(_POSE))))
    links: dict[tuple[str, str], Intervals] = field(default_factory=dict)
    relative: bool = False

    @classmethod
    def of_rows(cls, rows: pd.DataFrame) -> LayoutSketch:
        """The summary of one chunk of matched rows (``t``, ``tx``, ``rx``, both ends' poses)."""
        out = cls(rows=len(rows), posed=all(c in rows.columns for c in _POSE_COLUMNS), relative=is_relative_rssi(rows))
        if not len(rows) or "tx" not in rows.columns or "rx" not in rows.columns:
            return out
        tx, tx_names = pd.factorize(rows["tx"], use_na_sentinel=False)
        rx, rx_names = pd.factorize(rows["rx"], use_na_sentinel=False)
        out.names = sorted({str(n) for n in tx_names} | {str(n) for n in rx_names})
        place = {n: k for k, n in enumerate(out.names)}
        tx = np.array([place[str(n)] for n in tx_names], np.int64)[tx]
        rx = np.array([place[str(n)] for n in rx_names], np.int64)[rx]
        if out.posed:
            keys = _row_keys(rows, True)
            level = _level(keys, 0)
            keep = np.flatnonzero(_below(keys, level))
            out.level, out.keys, out.codes = level, keys[keep], np.column_stack([tx[keep], rx[keep]])
            out.poses = np.column_stack([rows[c].to_numpy(np.float64, copy=False)[keep] for c in _POSE_COLUMNS])
        if "t" in rows.columns:
            out.links = _chunk_intervals(pd.to_numeric(rows["t"], errors="coerce").to_numpy(np.float64), tx, rx, out.names)
        return out

    def merge(self, later: LayoutSketch) -> LayoutSketch:
        """Add the summary of rows that follow these (in place; returns self)."""
        names = sorted(set(self.names) | set(later.names))
        place = {n: k for k, n in enumerate(names)}
        mine = np.array([place[n] for n in self.names], np.int64)
        theirs = np.array([place[n] for n in later.names], np.int64)
        level = _level(np.concatenate([self.keys, later.keys]), max(self.level, later.level))
        a, b = _below(self.keys, level), _below(later.keys, level)
        self.keys = np.concatenate([self.keys[a], later.keys[b]])
        self.codes = np.concatenate([mine[self.codes[a]], theirs[later.codes[b]]]).reshape(-1, 2)
        self.poses = np.concatenate([self.poses[a], later.poses[b]])
        self.names, self.level = names, level
        self.posed = self.posed and later.posed
        self.relative = self.relative or later.relative
        self.rows += later.rows
        for link, ints in later.links.items():
            self.links[link] = self.links[link].then(ints) if link in self.links else ints
        return self

    def fixed_nodes(self) -> tuple[str, ...] | None:
        """:func:`fixed_nodes` of the rows summed up (of the sample, by the same rule)."""
        if not self.rows or not self.posed:
            return None
        n = len(_POSE)
        poses = np.concatenate([self.poses[:, :n], self.poses[:, n:]])
        return still_nodes(np.concatenate([self.codes[:, 0], self.codes[:, 1]]), self.names, poses)

    def packet_rate_hz(self) -> float | None:
        """:func:`packet_rate_hz` of the rows summed up (each direction's median interval from its
        :class:`Intervals`)."""
        medians = [m for m in (self.links[k].median_s() for k in sorted(self.links)) if m is not None]
        return recorded_rate_hz(medians)

    def recorded(self) -> dict[str, Any]:
        """The training-summary entries a fit of these rows writes: ``fixed_nodes``, ``packet_rate_hz``
        and, of relative received power, ``rssi_scale`` (``relative``)."""
        out: dict[str, Any] = {"fixed_nodes": self.fixed_nodes(), "packet_rate_hz": self.packet_rate_hz()}
        if self.relative:
            out["rssi_scale"] = "relative"
        return out


def is_relative_rssi(rows: pd.DataFrame) -> bool:
    """Whether any of the matched rows is of relative received power (``rssi_scale`` column
    ``relative``, any case): the rule every fit records ``training.rssi_scale`` by."""
    return "rssi_scale" in rows.columns and bool((rows["rssi_scale"].astype(str).str.lower() == "relative").any())


def _below(keys: np.ndarray, level: int) -> np.ndarray:
    """Whether each key is kept at ``level`` (below ``2**(64 - level)``)."""
    return keys < np.uint64(2 ** (64 - level)) if 0 < level < 64 else np.full(keys.size, level == 0)


def _level(keys: np.ndarray, level: int) -> int:
    """The smallest level from ``level`` on that keeps at most :data:`LAYOUT_ROWS` of ``keys``."""
    kept = keys[_below(keys, level)]
    while kept.size > LAYOUT_ROWS and level < 64:
        level += 1
        kept = kept[_below(kept, level)]
    return level


def _chunk_intervals(t: np.ndarray, tx: np.ndarray, rx: np.ndarray, names: list[str]) -> dict[tuple[str, str], Intervals]:
    """Each link direction's intervals between consecutive distinct finite times of one chunk
    (a pass over the chunk per direction: a matched dataset's few directions, its rows in time order)."""
    ok = np.isfinite(t)
    t, link = t[ok], (tx * len(names) + rx)[ok]
    out = {}
    for code in np.flatnonzero(np.bincount(link)) if t.size else ():
        mine = t[link == code]
        if not np.all(mine[1:] >= mine[:-1]):
            mine = np.sort(mine)
        mine = mine[np.r_[True, mine[1:] != mine[:-1]]]
        step = np.diff(mine)
        ints = Intervals(step, np.ones(step.size, np.int64), 0.0, float(mine[0]), float(mine[-1]))
        out[(names[code // len(names)], names[code % len(names)])] = ints.counted()
    return out


__all__ = ["FINEST_BIN", "INTERVAL_VALUES", "LAYOUT_ROWS", "RECORDED_RATE_HZ", "STILL_ANGLE_DEG", "STILL_RADIUS_M",
           "STILL_SHARE", "Intervals", "LayoutSketch", "fixed_nodes", "holds_still", "is_relative_rssi", "packet_rate_hz", "recorded_rate_hz", "still_nodes"]
