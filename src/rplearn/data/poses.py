"""Pose logs as per-node tracks that can be interpolated at any time (paper Sec. V-B4).

A :class:`PoseTrack` holds one node's pose log as arrays on the common clock; positions are
interpolated linearly and attitudes by spherical linear interpolation (slerp). A node whose
pose log has a single row is static: its pose holds at every time. A node logged with only
identical rows (a ground station logged at 1 Hz, or at the start and the end of a flight) holds
still over its log's span, however long the gaps between its rows. A node whose log holds
still at one pose and later at another, with no pose logged in between, is a station moved
between flights: refused, naming both positions (sync each flight with its own pose log).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd

from rplearn._argtypes import check_types
from rplearn.core.geometry import slerp_wxyz
from rplearn.data.tables import checked_pose_arrays, validate_pose_log
from rplearn.errors import InputError

#: Status of an interpolated pose: known, outside the log's span, inside a gap of the log.
STATUS_OK, STATUS_OUT_OF_SPAN, STATUS_POSE_GAP = 0, 1, 2
#: Two logged poses are the same pose within these: position [m] and quaternion components
#: (sign-insensitive), enough for the rounding of a CSV writer, far below any real motion.
SAME_POSITION_M = 1e-3
SAME_QUATERNION = 1e-6


@check_types
@dataclass(frozen=True)
class PoseTrack:
    """One node's pose log as arrays: times [s] (common clock), ENU positions [m], quaternions.

    Attributes
    ----------
    node : str
        Node id.
    t_s : ndarray (n,)
        Strictly increasing times on the common clock [s].
    position_xyz : ndarray (n, 3)
        ENU positions [m].
    quat_wxyz : ndarray (n, 4)
        Unit quaternions (w, x, y, z), body FLU -> world ENU.
    still : bool
        True for a log of identical poses: no gap between its rows is a pose gap.
    """

    node: str
    t_s: np.ndarray
    position_xyz: np.ndarray
    quat_wxyz: np.ndarray
    still: bool = False

    @property
    def static(self) -> bool:
        """True for a one-row log (a ground station, a parked drone)."""
        return self.t_s.shape[0] == 1

    def interpolate(self, t_s: np.ndarray, max_gap_s: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Pose at times ``t_s`` [s]: positions linearly, attitudes by slerp.

        Parameters
        ----------
        t_s : ndarray (n,)
            Times on the common clock [s].
        max_gap_s : float
            Longest step between two logged poses interpolated across [s].

        Returns
        -------
        position_xyz : ndarray (n, 3)
            ENU positions [m].
        quat_wxyz : ndarray (n, 4)
            Quaternions (w, x, y, z).
        status : ndarray (n,) of int8
            :data:`STATUS_OK` = interpolated, :data:`STATUS_OUT_OF_SPAN` = outside the log's
            span, :data:`STATUS_POSE_GAP` = inside a gap longer than ``max_gap_s``. Poses of
            rows with a non-zero status are meaningless.
        """
        n = t_s.shape[0]
        if self.static:
            q = self.quat_wxyz[0]
            q = -q if q[0] < 0 else q
            return (
                np.broadcast_to(self.position_xyz[0], (n, 3)).copy(),
                np.broadcast_to(q, (n, 4)).copy(),
                np.zeros(n, np.int8),
            )
        i, frac, status = self.brackets(t_s, max_gap_s)
        i1 = i + 1
        p0 = self.position_xyz[i]
        pos = self.position_xyz[i1] - p0
        pos *= frac[:, None]
        pos += p0
        quat = slerp_wxyz(self.quat_wxyz[i], self.quat_wxyz[i1], frac)
        return pos, quat, status

    def brackets(self, t_s: np.ndarray, max_gap_s: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The logged poses around times ``t_s`` [s] of a track of two rows or more.

        Returns
        -------
        index : ndarray (n,) of int
            Row ``i`` of the pose before each time (the pose after is row ``i + 1``).
        fraction : ndarray (n,)
            Where each time lies between the two, in [0, 1].
        status : ndarray (n,) of int8
            As in :meth:`interpolate`.
        """
        tk = self.t_s
        i = np.searchsorted(tk, t_s, side="right")
        i -= 1
        np.clip(i, 0, tk.shape[0] - 2, out=i)
        t0 = tk[i]
        t1 = tk[i + 1]
        status = np.zeros(t_s.shape[0], np.int8)
        on_sample = (t_s == t0) | (t_s == t1)  # a logged pose is known even at a gap's edge
        t1 -= t0  # the step dt between the two poses
        if not self.still:
            status[(t1 > max_gap_s) & ~on_sample] = STATUS_POSE_GAP
        status[(t_s < tk[0]) | (t_s > tk[-1]) | ~np.isfinite(t_s)] = STATUS_OUT_OF_SPAN
        frac = t_s - t0
        frac /= t1
        np.clip(frac, 0.0, 1.0, out=frac)
        return i, frac, status


class TrackSet(dict[str, PoseTrack]):
    """Pose tracks by node id (a ``dict``) whose arrays are views of one store: the times,
    positions and quaternions of every node back to back, node after node (issue 30: many
    nodes' poses are then interpolated in one pass, without a copy per node or per call).

    Attributes
    ----------
    t_s : ndarray (n,)
        Times of all tracks [s, common clock].
    position_xyz : ndarray (n, 3)
        ENU positions [m].
    quat_wxyz : ndarray (n, 4)
        Quaternions (w, x, y, z).
    first_row : dict of str to int
        Row of each node's first pose in the store.
    """

    __slots__ = ("first_row", "position_xyz", "quat_wxyz", "t_s")
    t_s: np.ndarray
    position_xyz: np.ndarray
    quat_wxyz: np.ndarray
    first_row: dict[str, int]

    @classmethod
    def of_rows(
        cls,
        names: Sequence[str],
        rows: Sequence[np.ndarray],
        still: Sequence[bool],
        columns: tuple[np.ndarray, np.ndarray, np.ndarray],
        offsets_s: Sequence[float] | None,
    ) -> TrackSet:
        """Tracks of nodes ``names``, each of rows ``rows[k]`` of ``columns`` = (times [s],
        positions (n, 3) [m], quaternions (n, 4)), its times plus ``offsets_s[k]`` [s] (none added
        when None)."""
        t, pos, quat = columns
        sizes = np.array([r.size for r in rows], np.intp)
        first = np.r_[0, np.cumsum(sizes)].astype(np.intp)
        every: Any = slice(None)  # every row in order (the usual case): no gather
        if int(first[-1]) != t.shape[0] or any(r.size and (r[0] != a or r[-1] != a + r.size - 1)
                                               for r, a in zip(rows, first[:-1])):
            every = np.concatenate(rows) if rows else np.zeros(0, np.intp)
        out = cls()
        if offsets_s is None:
            out.t_s = t[every]
        elif len(set(offsets_s)) == 1:  # one offset (most often none, 0.0): the same sums, no array of them
            out.t_s = t[every] + float(offsets_s[0])
        else:
            out.t_s = t[every] + np.repeat(np.asarray(offsets_s, np.float64), sizes)
        out.position_xyz = np.ascontiguousarray(pos[every])
        out.quat_wxyz = np.ascontiguousarray(quat[every])
        out.first_row = {}
        for k, node in enumerate(names):
            a, b = int(first[k]), int(first[k + 1])
            out.first_row[node] = a
            out[node] = PoseTrack(node, out.t_s[a:b], out.position_xyz[a:b], out.quat_wxyz[a:b], bool(still[k]))
        return out

    @classmethod
    def of(cls, tracks: Mapping[str, PoseTrack]) -> TrackSet:
        """``tracks`` itself when it is a :class:`TrackSet`, else one with the same tracks (copied)."""
        if isinstance(tracks, TrackSet):
            return tracks
        items = list(tracks.items())
        columns = tuple(np.concatenate([getattr(tr, f) for _, tr in items]) if items else np.zeros((0, w))
                        for f, w in (("t_s", 0), ("position_xyz", 3), ("quat_wxyz", 4)))
        columns = (columns[0].reshape(-1), columns[1].reshape(-1, 3), columns[2].reshape(-1, 4))
        sizes = np.cumsum([0] + [tr.t_s.shape[0] for _, tr in items])
        rows = [np.arange(sizes[k], sizes[k + 1]) for k in range(len(items))]
        out = cls.of_rows([n for n, _ in items], rows, [tr.still for _, tr in items], columns, None)
        for node, tr in items:  # the given objects themselves
            out[node] = tr
        return out


@check_types
def pose_tracks(
    pose_log: pd.DataFrame,
    clock_offsets_s: Mapping[str, float] | None = None,
    source: str = "pose log",
) -> dict[str, PoseTrack]:
    """Split a canonical pose log into one :class:`PoseTrack` per node.

    Rows with NaN or infinite values are rejected by :func:`~rplearn.data.tables.validate_pose_log`
    (use the readers' ``nan_policy="drop"`` to drop and count them on reading).

    Parameters
    ----------
    pose_log : DataFrame
        Canonical pose log ``t, node, x, y, z, qw, qx, qy, qz``.
    clock_offsets_s : mapping of node id to float, optional
        Offset added to each node's times to put them on the common clock [s].
    source : str
        Name of the pose log in messages.
    """
    return tracks_of_checked_log(validate_pose_log(pose_log, source), clock_offsets_s, source)


def tracks_of_checked_log(
    df: pd.DataFrame, clock_offsets_s: Mapping[str, float] | None, source: str, max_gap_s: float | None = None,
) -> TrackSet:
    """:func:`pose_tracks` of a pose log already checked (and sorted) by :func:`validate_pose_log`.

    Parameters
    ----------
    max_gap_s : float, optional
        The matching's longest interpolated gap [s]: a node whose poses change only across
        longer gaps, holding still in between, is a station moved between flights (refused).

    Raises
    ------
    InputError
        When ``clock_offsets_s`` names a node without a pose log (``param="clock_offsets_s"``),
        or for a station moved between flights.
    """
    codes, uniques = pd.factorize(df["node"].array)  # equal ids, equal codes (no text object per row)
    t = df["t"].to_numpy(np.float64)
    pos = df[["x", "y", "z"]].to_numpy(np.float64)
    quat = df[["qw", "qx", "qy", "qz"]].to_numpy(np.float64)
    return _tracks_of_arrays(codes, [str(u) for u in uniques], (t, pos, quat), clock_offsets_s, (source, max_gap_s))


def tracks_of_pose_log(
    pose_log: pd.DataFrame, clock_offsets_s: Mapping[str, float] | None, source: str, max_gap_s: float | None = None,
) -> tuple[TrackSet, int]:
    """``tracks_of_checked_log(validate_pose_log(pose_log))`` and the
    :func:`~rplearn.data.tables.non_unit_quaternion_rows` of the checked log, from the checked
    arrays (:func:`~rplearn.data.tables.checked_pose_arrays`), without the checked log as a
    DataFrame: the same tracks and count, the same errors.
    """
    c = checked_pose_arrays(pose_log, source)
    tracks = _tracks_of_arrays(c.codes, [str(n) for n in c.names], (c.t, c.position_xyz, c.quat_wxyz),
                               clock_offsets_s, (source, max_gap_s))
    return tracks, c.non_unit + c.still_off


def _tracks_of_arrays(
    codes: np.ndarray,
    names: Sequence[str],
    columns: tuple[np.ndarray, np.ndarray, np.ndarray],
    clock_offsets_s: Mapping[str, float] | None,
    where: tuple[str, float | None],
) -> TrackSet:
    """The tracks of a checked pose log's arrays, sorted by (node, t): node codes into ``names``,
    (times [s], positions (n, 3) [m], quaternions (n, 4)); ``where``: (source, max_gap_s)."""
    source, max_gap_s = where
    offsets = dict(clock_offsets_s or {})
    t, pos, quat = columns
    # sorted by (node, t): nodes are contiguous runs
    starts = np.flatnonzero(np.r_[True, codes[1:] != codes[:-1]]) if codes.size else np.zeros(0, np.intp)
    ends = np.r_[starts[1:], codes.size]
    run_names = [names[codes[s]] for s in starts]
    rows: list[np.ndarray] = []
    still: list[bool] = []
    for node, s, e in zip(run_names, starts, ends):
        changes = _pose_changes(pos[s:e], quat[s:e])
        still.append(bool(e - s > 1 and not changes.any()))
        if changes.any() and max_gap_s is not None:
            _refuse_moved_station(node, t[s:e], pos[s:e], changes, float(max_gap_s), source)
        rows.append(np.array([s, e - 1]) if still[-1] else np.arange(s, e))  # identical rows: the pose holds
    tracks = TrackSet.of_rows(run_names, rows, still, (t, pos, quat), [float(offsets.get(n, 0.0)) for n in run_names])
    unknown = sorted(set(offsets) - set(tracks))
    if unknown:
        raise InputError(
            f"{source}: clock offsets (clock_offsets_s) name node(s) "
            f"{', '.join(unknown)} without a pose log; known: {', '.join(sorted(tracks))}",
            param="clock_offsets_s",
        )
    return tracks


def _pose_changes(position_xyz: np.ndarray, quat_wxyz: np.ndarray) -> np.ndarray:
    """For each row after the first: whether its pose differs from the row before (one
    component at a time: no reduction along rows of three or four)."""
    changed = np.abs(np.diff(position_xyz[:, 0])) > SAME_POSITION_M
    for j in (1, 2):
        changed |= np.abs(np.diff(position_xyz[:, j])) > SAME_POSITION_M
    rows = np.flatnonzero(~changed)  # the attitude matters only where the position held
    q0, q1 = quat_wxyz[rows], quat_wxyz[rows + 1]
    minus = np.abs(q1[:, 0] - q0[:, 0])
    plus = np.abs(q1[:, 0] + q0[:, 0])
    for j in (1, 2, 3):  # the largest component of q1 - q0 and of q1 + q0 (sign-insensitive)
        np.maximum(minus, np.abs(q1[:, j] - q0[:, j]), out=minus)
        np.maximum(plus, np.abs(q1[:, j] + q0[:, j]), out=plus)
    changed[rows] = np.minimum(minus, plus) > SAME_QUATERNION
    return changed


def _refuse_moved_station(
    node: str, t_s: np.ndarray, position_xyz: np.ndarray, changes: np.ndarray, max_gap_s: float, source: str
) -> None:
    """Refuse a log made only of still stretches (each pose logged twice or more) that changes
    only across gaps longer than ``max_gap_s`` (its samples in between
    would be lost as pose gaps, or, if the gap were bridged, placed on a line the station
    never travelled)."""
    gaps = np.diff(t_s) > max_gap_s
    if np.any(changes & ~gaps):
        return  # the node moves while logged (a change across no gap): a track
    starts = np.r_[0, np.flatnonzero(changes) + 1]
    lengths = np.diff(np.r_[starts, t_s.size])
    if not np.all(gaps[changes]) or np.any(lengths < 2):
        return  # the node moves while logged, or logs some pose once only: a track
    first = int(np.flatnonzero(changes)[0])
    a, b = position_xyz[first], position_xyz[first + 1]
    how = "" if np.any(np.abs(a - b) > SAME_POSITION_M) else " (turned: the same position, another attitude)"
    raise InputError(
        f"{source}: node {node} holds still at ({a[0]:.2f}, {a[1]:.2f}, {a[2]:.2f}) m until t={t_s[first]:.3f} s "
        f"and at ({b[0]:.2f}, {b[1]:.2f}, {b[2]:.2f}) m from t={t_s[first + 1]:.3f} s{how}, with no pose in between: "
        "a station moved between flights? Synchronise each flight with its own pose log"
    )


@check_types
def interpolate_nodes(
    tracks: Mapping[str, PoseTrack], node_ids: Sequence[str], node_code: np.ndarray, t_s: np.ndarray,
    max_gap_s: float, rows: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Poses of many nodes, row ``i`` being node ``node_ids[node_code[i]]`` at time ``t_s[i]`` [s].

    Only the rows where ``rows`` is True are interpolated (their nodes must have a track);
    the others get NaN poses and status :data:`STATUS_OK`.

    Returns
    -------
    position_xyz : ndarray (n, 3)
        ENU positions [m].
    quat_wxyz : ndarray (n, 4)
        Quaternions (w, x, y, z).
    status : ndarray (n,) of int8
        As in :meth:`PoseTrack.interpolate`.
    """
    n = len(t_s)
    pos = np.full((n, 3), np.nan)
    quat = np.full((n, 4), np.nan)
    status = np.zeros(n, np.int8)
    for code, node in enumerate(node_ids):
        sel = np.flatnonzero((node_code == code) & rows)
        if sel.size:
            pos[sel], quat[sel], status[sel] = tracks[node].interpolate(t_s[sel], max_gap_s)
    return pos, quat, status


__all__ = [
    "STATUS_OK",
    "STATUS_OUT_OF_SPAN",
    "STATUS_POSE_GAP",
    "PoseTrack",
    "interpolate_nodes",
    "TrackSet",
    "pose_tracks",
    "tracks_of_checked_log",
    "tracks_of_pose_log",
]
