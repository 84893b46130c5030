"""Checks of a pose table's values before it becomes a canonical pose log
(:func:`rplearn.io.tables.canonical_pose`): numbers, coordinates within any place, and a track
without jumps no plausible speed explains (in-range sentinels, positions logged before the fix)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from rplearn.core.plausible import PLAUSIBLE
from rplearn.errors import InputError, LogFormatError
from rplearn.io.mavlink_phases import MAX_HORIZONTAL_SPEED_M_S, MAX_VERTICAL_SPEED_M_S, invalid_fixes, unexplained_steps

#: A node's top speed, horizontal and vertical, is this many times the 75th percentile of its
#: speeds between consecutive rows while it moves (above :data:`MOVING_SPEED_M_S`), at least the
#: plausible maxima of a multicopter (a fixed wing at 70 m/s is not cut at 40 m/s; time on the
#: ground does not lower it) and at most :data:`TOP_SPEED_CAP_M_S` (frequent sentinels, whose
#: steps are thousands of m/s, cannot raise it past them).
TOP_SPEED_FACTOR = 3.0
#: Fewest moving steps between a node's rows from which its own speeds are read.
MIN_SPEED_STEPS = 8
#: Speed [m/s] above which a step between two rows is a moving one (:data:`TOP_SPEED_FACTOR`).
MOVING_SPEED_M_S = 1.0
#: Largest top speed [m/s] a node's own speeds give, across and up/down: a fast fixed wing's.
TOP_SPEED_CAP_M_S = (150.0, 50.0)


def _float_column(df: pd.DataFrame, name: str) -> np.ndarray:
    return pd.to_numeric(df[name], errors="coerce").to_numpy(np.float64, na_value=np.nan)


#: The plausible range (:data:`~rplearn.core.plausible.PLAUSIBLE`) of each position column: a value beyond it is
#: no place (a sentinel such as 1e308 or the largest float32, or a corrupt value), ``implausible_pose``.
POSITION_RANGES: dict[str, str] = {"x": "coordinate_m", "y": "coordinate_m", "z": "coordinate_m",
                                   "lat": "latitude_deg", "lon": "longitude_deg", "alt": "altitude_m"}


def _beyond(column: str) -> str:
    """How a refusal says a value of a position column no place has."""
    q = PLAUSIBLE[POSITION_RANGES[column]]
    if q.name == "coordinate_m":
        return " or coordinates beyond 1e8 m"
    return f" or values outside {q.low:g} to {q.high:g} {q.unit} (no place: a sentinel, or not in {q.unit}?)"


def finite_values(
    df: pd.DataFrame, numeric: tuple[str, ...], nan_policy: str, source: str
) -> tuple[pd.DataFrame, dict[str, np.ndarray], dict[str, int]]:
    """The numeric columns as float arrays, rows with a NaN, a non-number or a position no place
    has (:data:`POSITION_RANGES`: an ENU coordinate beyond 1e8 m, a latitude, longitude or
    altitude outside its plausible range; a sentinel or a corrupt value) dropped or refused.

    Returns ``(table, values, dropped)``: the table and arrays without the bad rows and their
    counts, ``nan_pose`` (NaN, infinite or no number) and ``implausible_pose`` (a finite
    position no place has); both 0 unless ``nan_policy="drop"``. With ``"error"`` the first bad
    row is refused in one line naming ``source``, its column and its row.
    """
    values = {c: _float_column(df, c) for c in numeric}
    nan = np.zeros(len(df), bool)
    far = np.zeros(len(df), bool)
    first_bad: tuple[int, str] | None = None
    column_bad: dict[str, int] = {}
    for c in numeric:
        b_nan = ~np.isfinite(values[c])
        b_far = np.zeros(len(df), bool)
        if c in POSITION_RANGES:  # a position beyond any place: a sentinel or corrupt value
            q = PLAUSIBLE[POSITION_RANGES[c]]
            b_far = ((values[c] < q.low) | (values[c] > q.high)) & ~b_nan
        b = b_nan | b_far
        if b.any():
            r = int(np.flatnonzero(b)[0])
            column_bad[c] = int(b.sum())
            if first_bad is None or r < first_bad[0]:
                first_bad = (r, c)
        nan |= b_nan
        far |= b_far
    if first_bad is None:
        return df, values, {"nan_pose": 0, "implausible_pose": 0}
    bad = nan | far
    if nan_policy == "error":
        r, c = first_bad
        raise InputError(
            f"{source}: field {c} has {column_bad[c]} row(s) with NaN, infinite or non-numeric values"
            f"{_beyond(c) if c in POSITION_RANGES else ''} (first at row {df.index[r]}); expected numbers, or drop "
            "those rows (nan_policy='drop')",
            param="nan_policy",
        )
    counts = {"nan_pose": int(nan.sum()), "implausible_pose": int((far & ~nan).sum())}
    return df.loc[~bad], {c: v[~bad] for c, v in values.items()}, counts


def top_speeds(t: np.ndarray, xyz: np.ndarray, codes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per row, its node's top horizontal and vertical speed [m/s] (:data:`TOP_SPEED_FACTOR`);
    rows sorted by node, then time."""
    same = codes[1:] == codes[:-1]
    dt = np.diff(t)
    ok = same & (dt > 0)
    dh = np.hypot(*np.diff(xyz[:, :2], axis=0).T)
    dv = np.abs(np.diff(xyz[:, 2]))
    out = []
    for delta, floor, cap in ((dh, MAX_HORIZONTAL_SPEED_M_S, TOP_SPEED_CAP_M_S[0]),
                              (dv, MAX_VERTICAL_SPEED_M_S, TOP_SPEED_CAP_M_S[1])):
        top = np.full(len(t), floor)
        for code in np.unique(codes):
            steps = ok & (codes[1:] == code)
            speed = delta[steps] / dt[steps]
            moving = speed[speed > MOVING_SPEED_M_S]
            if len(moving) >= MIN_SPEED_STEPS:
                top[codes == code] = min(cap, max(floor, TOP_SPEED_FACTOR * float(np.quantile(moving, 0.75))))
        out.append(top)
    return out[0], out[1]


def track_pieces(t: np.ndarray, xyz: np.ndarray, h: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """One node's pieces of track (rows in time order; ``h``, ``v``: its top speeds, :func:`top_speeds`): the
    rows between two steps those speeds do not explain, as the first row and the end (exclusive) of each."""
    cut, _, _ = unexplained_steps(t[:-1], xyz[:-1], h[:-1], v[:-1], t[1:], xyz[1:], h[1:], v[1:])
    starts = np.concatenate([[0], np.flatnonzero(cut) + 1])
    return starts, np.concatenate([starts[1:], [len(t)]])


def _around_largest_piece(t: np.ndarray, xyz: np.ndarray, codes: np.ndarray) -> tuple[np.ndarray, dict[int, str]]:
    """:func:`~rplearn.io.mavlink_phases.invalid_fixes` of rows sorted by node and time, at each
    node's own top speeds, anchored on its largest piece of track (the rows between two steps no
    speed explains): forward over the rows up to its end (fixes logged before the position was
    valid), backward over the rows from its start (a sentinel at the end, zeros at shutdown).
    Returns the invalid rows and the steps (row -> what the step was)."""
    h, v = top_speeds(t, xyz, codes)
    invalid = np.zeros(len(t), bool)
    steps: dict[int, str] = {}
    for code in np.unique(codes):
        idx = np.flatnonzero(codes == code)
        if len(idx) < 2:
            continue
        starts, ends = track_pieces(t[idx], xyz[idx], h[idx], v[idx])
        k = int(np.argmax(ends - starts))
        for rows, times in ((idx[:ends[k]], t[idx[:ends[k]]]), (idx[starts[k]:][::-1], -t[idx[starts[k]:][::-1]])):
            bad, found = invalid_fixes(times, xyz[rows], h[rows], v[rows], np.zeros(len(rows), int), np.ones(len(rows), bool))
            invalid[rows] |= bad
            steps.update({int(rows[i]): text for i, text in found.items()})
    label = "the node's top speed ({:.0f} m/s across, {:.0f} m/s up/down)"
    return invalid, {i: text.replace("the logged speed", label.format(h[i], v[i])) for i, text in steps.items()}


def position_jumps(
    t: np.ndarray, xyz: np.ndarray, nodes: np.ndarray, rows: np.ndarray, nan_policy: str, source: str,
) -> tuple[np.ndarray, list[str]]:
    """Rows on the wrong side of a position step no plausible speed explains, refused or dropped.

    The rule of the MAVLink readers (:func:`rplearn.io.mavlink_phases.invalid_fixes`), at each
    node's own top speed (:func:`top_speeds`: a table carries no velocity): per node, in time
    order, a step larger than ``(speed + slack) * dt + margin`` cuts the track into pieces; the
    largest piece anchors the valid track (:func:`_around_largest_piece`), another piece is
    valid when the step to the valid fixes beside it is explained. A sentinel inside the plausible range (``z = -1000``, ``x = y = z = 0``
    before the fix or at shutdown) is such a piece. ``rows`` are the file rows of the
    positions, for messages.

    Returns ``(keep, notes)``: a mask of the rows to keep and one note per dropped piece.

    Raises
    ------
    InputError
        With ``nan_policy="error"``, naming the first row on the wrong side and the step; with
        ``"drop"`` too when a node's wrong side holds half its rows or more (which side is wrong
        is then no longer clear: no data is dropped on a guess).
    """
    if len(t) < 2:
        return np.ones(len(t), bool), []
    codes = pd.factorize(pd.Series(nodes, dtype=object))[0]  # a node id of any type (a hostile one)
    order = np.lexsort((t, codes))
    invalid_sorted, steps = _around_largest_piece(t[order], xyz[order], codes[order])
    if not invalid_sorted.any():
        return np.ones(len(t), bool), []
    invalid = np.zeros(len(t), bool)
    invalid[order] = invalid_sorted
    notes = []
    for at_sorted, step in sorted(steps.items()):
        node, code = nodes[order[at_sorted]], codes[order[at_sorted]]
        piece = invalid & (codes == code)
        n_node, n_bad = int((codes == code).sum()), int(piece.sum())
        first = int(np.flatnonzero(piece)[np.argmin(rows[piece])])
        where = (f"{source}: fields x, y, z of node {node} jump: {step} at row {int(rows[order[at_sorted]])} "
                 f"(t = {float(t[order[at_sorted]]):.3f} s); {n_bad} of its {n_node} row(s) lie on the wrong side "
                 f"of a jump, first at row {int(rows[first])} (a sentinel, or a position logged before the fix "
                 "was valid)")
        if nan_policy == "error":
            raise InputError(f"{where}; expected a continuous track, or drop those rows (nan_policy='drop')",
                             param="nan_policy")
        if 2 * n_bad >= n_node:
            raise InputError(f"{where}; which side is valid is unclear with so many rows on the wrong side: "
                             "expected a continuous track, cut the log to the flight", param="nan_policy")
        notes.append(f"{where}: dropped")
    return ~invalid, notes


def same_rows(table: pd.DataFrame) -> np.ndarray:
    """Mask of the rows of ``table`` repeating an earlier row of it in every column (by pandas'
    hashing of each column's values; by their text only when a cell cannot be hashed: the text
    of every cell of a 210,000-row pose table took 4 s, the values 0.3 s)."""
    try:
        return table.duplicated(keep="first").to_numpy(bool)
    except TypeError:  # unhashable cells: compare their text
        return table.astype(str).duplicated(keep="first").to_numpy(bool)


def repeated_poses(
    df: pd.DataFrame, t: np.ndarray, nodes: np.ndarray, rows: np.ndarray, nan_policy: str, source: str,
) -> tuple[np.ndarray, dict[str, int], list[str]]:
    """Rows sharing their node and time with an earlier row: copies dropped, conflicts refused
    or dropped.

    ``df`` holds the pose columns alone (node, time, position, attitude: a column beside them, a
    satellite count or a sequence number, says nothing of the pose). A row identical in every
    one to an earlier row of the same node and time is a copy (a logger writing a block twice,
    as the live source finds across its polls): dropped and counted as ``duplicate_pose`` under any
    ``nan_policy``. Rows of one node and time that differ in a value are a conflict (two poses
    of one instant: which one is true is unknown): refused naming the rows and the first
    differing field, or with ``nan_policy="drop"`` all rows of that node and time dropped and
    counted as ``conflicting_pose``. ``rows`` are the file rows of ``df``'s rows, for messages.

    Returns ``(keep, dropped, notes)``.

    Raises
    ------
    InputError
        On a conflict with ``nan_policy="error"``.
    """
    keep = np.ones(len(t), bool)
    dropped = {"duplicate_pose": 0, "conflicting_pose": 0}
    key = pd.DataFrame({"node": pd.Series(nodes, dtype=object), "t": t})
    shared = key.duplicated(keep=False).to_numpy(bool)
    if not shared.any():
        return keep, dropped, []
    group = key.groupby(["node", "t"], dropna=False, sort=False).ngroup().to_numpy()  # a missing id is one node
    cand = np.flatnonzero(shared)
    copies = cand[same_rows(df.iloc[cand].set_axis(range(cand.size)))]
    keep[copies] = False
    notes = []
    if copies.size:
        dropped["duplicate_pose"] = int(copies.size)
        first = int(copies[np.argmin(rows[copies])])
        original = int(rows[np.flatnonzero(group == group[first])[0]])
        notes.append(f"{source}: {copies.size:,} pose row(s) repeat an earlier row of their node and time in every "
                     f"value, first at row {int(rows[first])} (a copy of row {original}: a block written twice): "
                     "dropped as copies (duplicate_pose)")
    left = cand[keep[cand]]
    conflict_in = pd.Series(group[left]).duplicated(keep=False).to_numpy(bool)
    if not conflict_in.any():
        return keep, dropped, notes
    conflict = left[conflict_in]
    a = int(conflict[np.argmin(rows[conflict])])
    same = conflict[group[conflict] == group[a]]
    b = int(same[same != a][0])
    fields = [str(c) for c in df.columns
              if not (str(df[c].iloc[a]) == str(df[c].iloc[b]))]
    where = (f"{source}: field {fields[0] if fields else 't'}: {conflict.size:,} pose row(s) share a node and time with "
             f"a row of other values, first node {nodes[a]} at t = {float(t[a])!r} (rows {int(rows[a])} and "
             f"{int(rows[b])} differ in {', '.join(fields) or 'their values'}): two poses of one instant")
    if nan_policy == "error":
        raise InputError(f"{where}; expected one pose per node and time, or drop those rows (nan_policy='drop')",
                         param="nan_policy")
    keep[conflict] = False
    dropped["conflicting_pose"] = int(conflict.size)
    notes.append(f"{where}: all rows of those times dropped (conflicting_pose)")
    return keep, dropped, notes


@dataclass
class TrackEnds:
    """What the rows of a pose table read in parts (a file still being written, polled by
    ``rplearn live``) carry from part to part, per node: the last row kept (its time [s] and
    ENU position [m]), the node's top speeds [m/s] (across, up/down) and the rows kept and
    dropped as on the wrong side of a jump so far."""

    last: dict[str, tuple[float, np.ndarray]] = field(default_factory=dict)
    speeds: dict[str, tuple[float, float]] = field(default_factory=dict)
    kept: dict[str, int] = field(default_factory=dict)
    dropped: dict[str, int] = field(default_factory=dict)
    #: Per node, the values of its last :data:`REMEMBERED_ROWS` rows kept, by time: a row of
    #: a later part repeating one of them is a copy (a block written twice).
    recent: dict[str, dict[float, tuple[float, ...]]] = field(default_factory=dict)
    #: Rows of the table read so far (the file row of the next part's first row): advanced by every
    #: part handed to :func:`~rplearn.io.tables.canonical_pose`, refused or not, as the file offset is.
    rows_read: int = 0
    #: The file rows of the next part's rows, when they are not the rows after :attr:`rows_read` (a reader
    #: holding some rows back hands them out later: :class:`rplearn.io.live_sources.CsvTail`); used once.
    file_rows: np.ndarray | None = None

    def part_rows(self, n: int) -> np.ndarray:
        """The file rows of a part of ``n`` rows (:attr:`file_rows`, else those after :attr:`rows_read`);
        :attr:`rows_read` advanced."""
        given, self.file_rows = self.file_rows, None
        rows = np.asarray(given, np.int64) if given is not None and len(given) == n else self.rows_read + np.arange(n)
        self.rows_read = max(self.rows_read, int(rows.max()) + 1) if n else self.rows_read
        return rows

    def remember(self, nodes: np.ndarray, values: dict[str, np.ndarray]) -> None:
        """Keep the values of the rows kept (of one part, in file order)."""
        columns = list(values)
        for i, node in enumerate(nodes):
            seen = self.recent.setdefault(str(node), {})
            seen[float(values["t"][i])] = tuple(float(values[c][i]) for c in columns)
            if len(seen) > REMEMBERED_ROWS:
                del seen[next(iter(seen))]


#: Rows per node whose values a pose table read in parts remembers (:class:`TrackEnds`).
REMEMBERED_ROWS = 4096


def earlier_rows(
    ends: TrackEnds, values: dict[str, np.ndarray], nodes: np.ndarray, rows: np.ndarray, nan_policy: str, source: str,
) -> tuple[np.ndarray, dict[str, int], list[str]]:
    """Rows of a part of a pose table (a file still being written) at or before their node's
    last row kept from the parts before: a row repeating a remembered row in every value is a
    copy (dropped, ``duplicate_pose``); another at a remembered time is a conflict (refused, or
    with ``nan_policy="drop"`` dropped as ``conflicting_pose``: the earlier row was handed out);
    any other is a step back in time, refused (:class:`LogFormatError`).

    Returns ``(keep, dropped, notes)``.
    """
    keep = np.ones(len(rows), bool)
    dropped = {"duplicate_pose": 0, "conflicting_pose": 0}
    notes: list[str] = []
    columns = list(values)
    t = values["t"]
    last_t = np.array([ends.last[str(n)][0] if str(n) in ends.last else -np.inf for n in nodes], np.float64)
    for i in np.flatnonzero(t <= last_t):  # the rows a part repeats or puts back in time (most: none)
        node = str(nodes[i])
        seen = ends.recent.get(node, {}).get(float(t[i]))
        here = tuple(float(values[c][i]) for c in columns)
        keep[i] = False
        if seen == here:
            dropped["duplicate_pose"] += 1
            continue
        if seen is None:
            raise LogFormatError(
                f"{source}: field t goes backwards at row {int(rows[i])} (node {node}: {ends.last[node][0]!r} -> "
                f"{float(t[i])!r}, before the rows read earlier); expected increasing times", param="allow_unsorted")
        field_name = next(c for c, a, b in zip(columns, seen, here, strict=True) if a != b)
        where = (f"{source}: field {field_name}: row {int(rows[i])} gives node {node} at t = {float(t[i])!r} other "
                 "values than a row read earlier: two poses of one instant")
        if nan_policy == "error":
            raise InputError(f"{where}; expected one pose per node and time, or drop such rows (nan_policy='drop')",
                             param="nan_policy")
        dropped["conflicting_pose"] += 1
        notes.append(f"{where}: dropped (conflicting_pose)")
    if dropped["duplicate_pose"]:
        notes.insert(0, f"{source}: {dropped['duplicate_pose']:,} pose row(s) repeat a row read earlier in every value "
                        "(a block written twice): dropped as copies (duplicate_pose)")
    return keep, dropped, notes


def steps_from_last(
    ends: TrackEnds, t: np.ndarray, xyz: np.ndarray, nodes: np.ndarray, rows: np.ndarray, nan_policy: str,
    source: str,
) -> tuple[np.ndarray, list[str]]:
    """The new rows of a pose table read in parts checked against each node's last row kept
    from the parts before (``ends``, updated here), so that every row is checked against its
    predecessor however the parts cut the track (a part of one row included).

    The rows (sorted by node, then time) are already checked among themselves
    (:func:`position_jumps`). Per node, the first rows that the step from the last row kept
    does not explain, at the node's top speed (:func:`top_speeds`, the highest seen so far),
    are on the wrong side of a jump: refused with ``nan_policy="error"``, else dropped (a
    sentinel between parts), and refused too when the dropped rows reach half the node's rows
    (which side is valid is then unclear). ``rows`` are the file rows, for messages.

    Returns ``(keep, notes)``.
    """
    keep = np.ones(len(t), bool)
    notes: list[str] = []
    codes, names = pd.factorize(pd.Series(nodes, dtype=object))
    h_now, v_now = top_speeds(t, xyz, codes) if len(t) else (np.zeros(0), np.zeros(0))
    for k, name in enumerate(names):
        node = str(name)
        idx = np.flatnonzero(codes == k)
        idx = idx[np.argsort(t[idx], kind="stable")]
        h, v = ends.speeds.get(node, (MAX_HORIZONTAL_SPEED_M_S, MAX_VERTICAL_SPEED_M_S))
        h, v = max(h, float(h_now[idx[0]])), max(v, float(v_now[idx[0]]))
        ends.speeds[node] = (h, v)
        if node in ends.last:
            t0, x0 = ends.last[node]
            n = idx.size
            bad, dh, dv = unexplained_steps(np.full(n, t0), np.broadcast_to(x0, (n, 3)), np.full(n, h), np.full(n, v),
                                            t[idx], xyz[idx], np.full(n, h), np.full(n, v))
            wrong = int(np.argmin(bad)) if not bad.all() else n  # the rows before the first the step explains
            if wrong:
                i = idx[0]
                where = (f"{source}: fields x, y, z of node {node} jump: a step of {float(dv[0]):.1f} m up/down and "
                         f"{float(dh[0]):.1f} m across in {float(t[i] - t0):.2f} s from its last row read before "
                         f"(t = {t0:.3f} s) that the node's top speed ({h:.0f} m/s across, {v:.0f} m/s up/down) does "
                         f"not explain, at row {int(rows[i])} (t = {float(t[i]):.3f} s); {wrong} row(s) lie on the "
                         "wrong side of it (a sentinel, or a position logged before the fix was valid)")
                if nan_policy == "error":
                    raise InputError(f"{where}; expected a continuous track, or drop those rows (nan_policy='drop')",
                                     param="nan_policy")
                dropped = ends.dropped.get(node, 0) + wrong
                if 2 * dropped >= dropped + ends.kept.get(node, 0) + n - wrong:
                    raise InputError(f"{where}; which side is valid is unclear with so many rows on the wrong side: "
                                     "expected a continuous track, cut the log to the flight", param="nan_policy")
                ends.dropped[node] = dropped
                keep[idx[:wrong]] = False
                notes.append(f"{where}: dropped")
        kept = idx[keep[idx]]
        if kept.size:
            ends.last[node] = (float(t[kept[-1]]), xyz[kept[-1]].copy())
            ends.kept[node] = ends.kept.get(node, 0) + int(kept.size)
    return keep, notes


__all__ = ["MIN_SPEED_STEPS", "MOVING_SPEED_M_S", "TOP_SPEED_CAP_M_S", "TOP_SPEED_FACTOR", "TrackEnds", "earlier_rows",
           "finite_values", "position_jumps", "repeated_poses", "same_rows", "steps_from_last", "top_speeds"]
