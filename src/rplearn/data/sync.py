"""Pose-signal matching: the poses of both ends of every signal sample (paper Sec. V-B4).

For every signal sample, the positions of its transmitter and receiver are interpolated
linearly and their attitudes by spherical linear interpolation (slerp) at the sample's time,
after optional clock offsets. A sample is dropped, and counted by reason, when:

``duplicate``
    it repeats an earlier row exactly, in every column (a logger or a merge writing the same
    packet twice); the first copy is kept. :func:`synchronise_stream` finds duplicates
    within a chunk only;
``invalid_value``
    its time, tx power or frequency is missing, NaN or not a number;
``sentinel_rssi``
    its RSSI is NaN, infinite or one of the sentinel values radios report for "no
    measurement" (default ``0, -127, -128, 127``);
``implausible_rssi``
    its RSSI lies outside the range any radio reports, :data:`PLAUSIBLE_RSSI_DBM`
    (a corrupt field or a unit mistake, e.g. mW or a percentage);
``tx_equals_rx``
    its transmitter is its receiver;
``other_link``
    it belongs to another direction than the one chosen with ``link=(tx, rx)``;
``unknown_node``
    one of its ends has no pose log. By default this is a counted drop (a capture often
    hears nodes that are not part of the experiment); ``on_unknown_node="error"``
    (``rplearn sync --on-unknown-node error``) raises :class:`~rplearn.errors.InputError` instead;
``out_of_span``
    its time lies before the first or after the last pose of one end;
``pose_gap``
    its time lies inside a gap of one end's pose log longer than ``max_gap_s``.

A node whose pose log has a single row is static (a ground station, a parked drone): its pose
holds at every time and it never causes ``out_of_span`` or ``pose_gap``.

Time convention: the output column ``t`` is the signal time on the common clock,
``t_signal + signal_clock_offset_s``; a pose log's times are shifted by
``clock_offsets_s[node]`` before interpolation. An offset is what must be *added* to a log's
time to put it on the common clock.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field
from typing import Iterable, Iterator, Mapping, Sequence

import numpy as np
import pandas as pd

from rplearn.data.tables import (
    MATCHED_COLUMNS,
    QUATERNION_NORM_TOLERANCE,
    SENTINEL_RSSI_DBM,
    SIGNAL_COLUMNS,
    non_unit_quaternion_rows,
    normalise_times,
    validate_pose_log,
)
from rplearn.errors import InputError
from rplearn.core.geometry import slerp_wxyz

logger = logging.getLogger(__name__)

#: RSSI values radios and drivers report when there is no measurement [dBm].
DEFAULT_SENTINEL_RSSI_DBM: tuple[float, ...] = SENTINEL_RSSI_DBM
#: RSSI values outside this range are no received power any radio reports [dBm]: above
#: +30 dBm a receiver front end would be destroyed, below -150 dBm lies under any noise floor.
PLAUSIBLE_RSSI_DBM: tuple[float, float] = (-150.0, 30.0)
#: Drop reasons, in the order they are tested.
DROP_REASONS: tuple[str, ...] = (
    "duplicate",
    "invalid_value",
    "sentinel_rssi",
    "implausible_rssi",
    "tx_equals_rx",
    "other_link",
    "unknown_node",
    "out_of_span",
    "pose_gap",
)

_OK, _OUT_OF_SPAN, _POSE_GAP = 0, 1, 2


@dataclass
class SyncSummary:
    """How many signal samples came in, went out, and why each dropped one was dropped.

    Attributes
    ----------
    n_in : int
        Signal samples read.
    n_out : int
        Samples in the matched dataset.
    dropped : dict of str to int
        Dropped samples per reason (see :data:`DROP_REASONS`); every reason is present.
    unknown_nodes : list of str
        Node ids named by signals but without a pose log.
    non_unit_quaternions : int
        Pose rows whose quaternion norm was off 1 by more than
        :data:`~rplearn.data.tables.QUATERNION_NORM_TOLERANCE` (normalised, not dropped).
    """

    n_in: int = 0
    n_out: int = 0
    dropped: dict[str, int] = field(default_factory=lambda: {r: 0 for r in DROP_REASONS})
    unknown_nodes: list[str] = field(default_factory=list)
    non_unit_quaternions: int = 0

    @property
    def n_dropped(self) -> int:
        return int(sum(self.dropped.values()))

    def merge(self, other: "SyncSummary") -> "SyncSummary":
        """Add another summary's counts into this one (for chunked matching); returns self."""
        self.n_in += other.n_in
        self.n_out += other.n_out
        for k, v in other.dropped.items():
            self.dropped[k] = self.dropped.get(k, 0) + int(v)
        self.unknown_nodes = sorted(set(self.unknown_nodes) | set(other.unknown_nodes))
        self.non_unit_quaternions += other.non_unit_quaternions
        return self

    def to_text(self) -> str:
        lines = [f"signal samples in: {self.n_in}, matched: {self.n_out}, dropped: {self.n_dropped}"]
        for reason in DROP_REASONS:
            if self.dropped.get(reason, 0):
                lines.append(f"  dropped ({reason}): {self.dropped[reason]}")
        if self.unknown_nodes:
            lines.append(f"  nodes without a pose log: {', '.join(self.unknown_nodes)}")
        if self.non_unit_quaternions:
            lines.append(
                f"  pose rows with a non-unit quaternion (|norm - 1| > {QUATERNION_NORM_TOLERANCE:g}, "
                f"normalised): {self.non_unit_quaternions}"
            )
        return "\n".join(lines)


@dataclass
class SyncResult:
    """Matched dataset (columns :data:`~rplearn.data.tables.MATCHED_COLUMNS` first, then any
    extra signal columns) and the :class:`SyncSummary` of the matching."""

    dataset: pd.DataFrame
    summary: SyncSummary


# ---------------------------------------------------------------------------------------------
# Interpolation primitives


@dataclass(frozen=True)
class PoseTrack:
    """One node's pose log as arrays: times [s] (common clock), ENU positions [m], quaternions."""

    node: str
    t_s: np.ndarray
    position_xyz: np.ndarray
    quat_wxyz: np.ndarray

    @property
    def static(self) -> bool:
        return self.t_s.shape[0] == 1

    def interpolate(self, t_s: np.ndarray, max_gap_s: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Pose at times ``t_s``: positions linearly, attitudes by slerp.

        Returns
        -------
        position_xyz : ndarray (n, 3)
        quat_wxyz : ndarray (n, 4)
        status : ndarray (n,) of int8
            0 = interpolated, 1 = outside the log's span, 2 = inside a gap longer than
            ``max_gap_s``. Poses of rows with a non-zero status are meaningless.
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
        tk = self.t_s
        i = np.searchsorted(tk, t_s, side="right") - 1
        i = np.clip(i, 0, tk.shape[0] - 2)
        t0 = tk[i]
        t1 = tk[i + 1]
        dt = t1 - t0
        status = np.zeros(n, np.int8)
        on_sample = (t_s == t0) | (t_s == t1)  # a logged pose is known even at a gap's edge
        status[(dt > max_gap_s) & ~on_sample] = _POSE_GAP
        status[(t_s < tk[0]) | (t_s > tk[-1]) | ~np.isfinite(t_s)] = _OUT_OF_SPAN
        frac = np.clip((t_s - t0) / dt, 0.0, 1.0)
        p0 = self.position_xyz[i]
        pos = p0 + frac[:, None] * (self.position_xyz[i + 1] - p0)
        quat = slerp_wxyz(self.quat_wxyz[i], self.quat_wxyz[i + 1], frac)
        return pos, quat, status


def pose_tracks(
    pose_log: pd.DataFrame,
    clock_offsets_s: Mapping[str, float] | None = None,
    source: str = "pose log",
) -> dict[str, PoseTrack]:
    """Split a canonical pose log into one :class:`PoseTrack` per node.

    Rows with NaN or infinite values are rejected by :func:`~rplearn.data.tables.validate_pose_log`
    (use the readers' ``nan_policy="drop"`` to drop and count them on reading).
    """
    return _tracks(validate_pose_log(pose_log, source), clock_offsets_s, source)


def _tracks(df: pd.DataFrame, clock_offsets_s: Mapping[str, float] | None, source: str) -> dict[str, PoseTrack]:
    """:func:`pose_tracks` of a pose log already checked by :func:`validate_pose_log`."""
    offsets = dict(clock_offsets_s or {})
    tracks: dict[str, PoseTrack] = {}
    nodes = df["node"].to_numpy()
    t = df["t"].to_numpy(np.float64)
    pos = df[["x", "y", "z"]].to_numpy(np.float64)
    quat = df[["qw", "qx", "qy", "qz"]].to_numpy(np.float64)
    # df is sorted by (node, t): nodes are contiguous runs
    starts = np.flatnonzero(np.r_[True, nodes[1:] != nodes[:-1]])
    ends = np.r_[starts[1:], len(nodes)]
    for s, e in zip(starts, ends):
        node = str(nodes[s])
        tracks[node] = PoseTrack(
            node,
            t[s:e] + float(offsets.get(node, 0.0)),
            np.ascontiguousarray(pos[s:e]),
            np.ascontiguousarray(quat[s:e]),
        )
    unknown = sorted(set(offsets) - set(tracks))
    if unknown:
        raise InputError(
            f"{source}: clock offsets (rplearn sync --offset, or clock_offsets_s=) name node(s) "
            f"{', '.join(unknown)} without a pose log; known: {', '.join(sorted(tracks))}"
        )
    return tracks


# ---------------------------------------------------------------------------------------------
# Matching


def _numeric(df: pd.DataFrame, column: str) -> np.ndarray:
    col = df[column]
    if pd.api.types.is_datetime64_any_dtype(col):  # datetimes: float seconds since the epoch
        return normalise_times(pd.DataFrame({"t": col}))["t"].to_numpy(np.float64)
    if pd.api.types.is_numeric_dtype(col) and not pd.api.types.is_bool_dtype(col):
        return col.to_numpy(np.float64, na_value=np.nan)
    return pd.to_numeric(col, errors="coerce").to_numpy(np.float64, na_value=np.nan)


def _match_chunk(
    tracks: Mapping[str, PoseTrack],
    signal: pd.DataFrame,
    link: tuple[str, str] | None,
    max_gap_s: float,
    signal_clock_offset_s: float | Mapping[str, float],
    sentinel_rssi_dbm: Sequence[float],
    on_unknown_node: str,
    source: str,
) -> SyncResult:
    missing = [c for c in SIGNAL_COLUMNS if c not in signal.columns]
    if missing:
        raise InputError(
            f"{source}: missing column(s) {', '.join(missing)}; expected {', '.join(SIGNAL_COLUMNS)}"
        )
    summary = SyncSummary(n_in=int(len(signal)))
    n = len(signal)
    t = _numeric(signal, "t")
    rssi = _numeric(signal, "rssi_dbm")
    ptx = _numeric(signal, "tx_power_dbm")
    freq = _numeric(signal, "frequency_hz")
    tx = signal["tx"].astype(str).to_numpy(dtype=object)
    rx = signal["rx"].astype(str).to_numpy(dtype=object)

    if isinstance(signal_clock_offset_s, Mapping):
        off = pd.Series(rx).map(lambda r: float(signal_clock_offset_s.get(r, 0.0))).to_numpy(np.float64)
        t = t + off
    else:
        t = t + float(signal_clock_offset_s)

    keep = np.ones(n, bool)

    def drop(mask: np.ndarray, reason: str) -> None:
        hit = mask & keep
        summary.dropped[reason] += int(hit.sum())
        keep[hit] = False

    drop(duplicate_rows(signal), "duplicate")
    drop(~(np.isfinite(t) & np.isfinite(ptx) & np.isfinite(freq) & (freq > 0)), "invalid_value")
    drop(~np.isfinite(rssi) | np.isin(rssi, np.asarray(sentinel_rssi_dbm, np.float64)), "sentinel_rssi")
    drop((rssi < PLAUSIBLE_RSSI_DBM[0]) | (rssi > PLAUSIBLE_RSSI_DBM[1]), "implausible_rssi")
    drop(tx == rx, "tx_equals_rx")
    if link is not None:
        drop(~((tx == str(link[0])) & (rx == str(link[1]))), "other_link")

    # node ids -> pose tracks; factorise once over both ends
    codes, uniques = pd.factorize(np.concatenate([tx, rx]))
    tx_code, rx_code = codes[:n], codes[n:]
    known = np.array([u in tracks for u in uniques], bool)
    unknown_mask = ~known[tx_code] | ~known[rx_code]
    if np.any(unknown_mask & keep):
        names = sorted({str(u) for u, k in zip(uniques, known) if not k} & (
            set(tx[unknown_mask & keep]) | set(rx[unknown_mask & keep])))
        if on_unknown_node == "error":
            row = int(np.flatnonzero(unknown_mask & keep)[0])
            raise InputError(
                f"{source}: field tx/rx: unknown node id(s) {', '.join(names)} at row {row} "
                f"(first); pose logs exist for {', '.join(sorted(tracks))} (to drop and count "
                "such samples: rplearn sync --on-unknown-node drop, or on_unknown_node='drop')"
            )
        summary.unknown_nodes = names
        logger.warning("%s: signals name node(s) without a pose log: %s", source, ", ".join(names))
    drop(unknown_mask, "unknown_node")

    poses = {}
    for end, end_code in (("tx", tx_code), ("rx", rx_code)):
        pos = np.full((n, 3), np.nan)
        quat = np.full((n, 4), np.nan)
        status = np.zeros(n, np.int8)
        for code, node in enumerate(uniques):
            if not known[code]:
                continue
            sel = np.flatnonzero((end_code == code) & keep)
            if sel.size == 0:
                continue
            p, q, s = tracks[node].interpolate(t[sel], max_gap_s)
            pos[sel] = p
            quat[sel] = q
            status[sel] = s
        poses[end] = (pos, quat, status)
    st_tx, st_rx = poses["tx"][2], poses["rx"][2]
    drop((st_tx == _OUT_OF_SPAN) | (st_rx == _OUT_OF_SPAN), "out_of_span")
    drop((st_tx == _POSE_GAP) | (st_rx == _POSE_GAP), "pose_gap")

    idx = np.flatnonzero(keep)
    cols: dict[str, np.ndarray] = {
        "t": t[idx],
        "tx": tx[idx].astype(str),
        "rx": rx[idx].astype(str),
        "rssi_dbm": rssi[idx],
        "tx_power_dbm": ptx[idx],
        "frequency_hz": freq[idx],
    }
    for end in ("tx", "rx"):
        pos, quat, _ = poses[end]
        for j, f in enumerate(("x", "y", "z")):
            cols[f"{end}_{f}"] = pos[idx, j]
        for j, f in enumerate(("qw", "qx", "qy", "qz")):
            cols[f"{end}_{f}"] = quat[idx, j]
    out = pd.DataFrame(cols, columns=list(MATCHED_COLUMNS))
    extra = [c for c in signal.columns if c not in MATCHED_COLUMNS]
    for c in extra:
        out[c] = signal[c].to_numpy()[idx]
    summary.n_out = int(idx.size)
    return SyncResult(out, summary)


def _check_options(max_gap_s: float, on_unknown_node: str, link: tuple[str, str] | None) -> None:
    if not (np.isfinite(max_gap_s) and max_gap_s > 0):
        raise InputError(
            f"max gap (rplearn sync --max-gap, or max_gap_s=): expected a positive number of seconds, "
            f"got {float(max_gap_s)!r}"
        )
    if on_unknown_node not in ("drop", "error"):
        raise InputError(
            "unknown-node policy (rplearn sync --on-unknown-node, or on_unknown_node=): "
            f"expected 'drop' or 'error', got {on_unknown_node!r}"
        )
    if link is not None and (len(link) != 2 or str(link[0]) == str(link[1])):
        raise InputError(
            "link (rplearn sync --link TX:RX, or link=(tx, rx)): expected two different node ids, "
            f"got {':'.join(map(str, link))}"
        )


def duplicate_rows(signal: pd.DataFrame) -> np.ndarray:
    """Mask of rows repeating an earlier row exactly, in every column (the first copy is False)."""
    mask = np.zeros(len(signal), bool)
    if signal.empty:
        return mask
    # Only rows sharing a time can repeat each other: compare whole rows within those (few)
    # rows only, which is 10x faster than hashing every row of a long log.
    t = signal["t"].to_numpy() if "t" in signal.columns else None
    if t is not None:
        try:
            order = np.argsort(t, kind="stable")
            same = np.flatnonzero(t[order][1:] == t[order][:-1])
        except TypeError:  # times of mixed types: compare everything
            candidates = np.arange(len(signal))
        else:
            if same.size == 0:
                return mask
            candidates = np.unique(np.concatenate([order[same], order[same + 1]]))
    else:
        candidates = np.arange(len(signal))
    subset = signal.iloc[candidates]
    try:
        repeated = subset.duplicated(keep="first").to_numpy(bool)
    except TypeError:  # unhashable cells (lists): compare their text
        repeated = subset.astype(str).duplicated(keep="first").to_numpy(bool)
    mask[candidates[repeated]] = True
    return mask


def check_link_nodes(signal: pd.DataFrame, link: tuple[str, str], source: str = "signal log") -> None:
    """Raise :class:`InputError` when a node of ``link`` is in no signal row, or the direction is absent.

    Parameters
    ----------
    signal : DataFrame
        Signal log with ``tx`` and ``rx``.
    link : (str, str)
        The chosen direction ``(tx, rx)``.
    source : str
        Name of the signal log in messages.
    """
    tx = signal["tx"].astype(str)
    rx = signal["rx"].astype(str)
    present = sorted(set(tx) | set(rx))
    flag = f"--link {link[0]}:{link[1]}"
    absent = [str(n) for n in link if str(n) not in present]
    if absent:
        raise InputError(
            f"{source}: {flag}: node {', '.join(absent)} is in no signal log; the signal logs name "
            f"{', '.join(present) or 'no node'}"
        )
    if not ((tx == str(link[0])) & (rx == str(link[1]))).any():
        pairs = sorted(set(zip(tx, rx)))
        raise InputError(
            f"{source}: {flag}: no signal from {link[0]} to {link[1]}; directions present: "
            f"{', '.join(f'{a}:{b}' for a, b in pairs)}"
        )


def synchronise(
    pose_log: pd.DataFrame,
    signal_log: pd.DataFrame,
    link: tuple[str, str] | None = None,
    max_gap_s: float = 0.2,
    clock_offsets_s: Mapping[str, float] | None = None,
    signal_clock_offset_s: float | Mapping[str, float] = 0.0,
    sentinel_rssi_dbm: Sequence[float] = DEFAULT_SENTINEL_RSSI_DBM,
    on_unknown_node: str = "drop",
    min_samples: int = 1,
    source: str = "signal log",
) -> SyncResult:
    """Match every signal sample with the poses of both its ends (paper Sec. V-B4).

    Parameters
    ----------
    pose_log : DataFrame
        Canonical pose log (``t, node, x, y, z, qw, qx, qy, qz``) of all nodes.
    signal_log : DataFrame
        Canonical signal log (``t, tx, rx, rssi_dbm, tx_power_dbm, frequency_hz`` and any
        extra columns, which are kept).
    link : (str, str), optional
        Keep only the direction ``tx -> rx`` (the paper uses one direction because links are
        not reciprocal); ``None`` keeps all directions.
    max_gap_s : float
        Longest gap between two poses of a node across which a pose is interpolated [s].
    clock_offsets_s : mapping of node id to float, optional
        Offset added to each node's pose times to put them on the common clock [s].
    signal_clock_offset_s : float or mapping of receiver id to float
        Offset added to signal times [s] (one for the log, or one per receiver).
    sentinel_rssi_dbm : sequence of float
        RSSI values meaning "no measurement", dropped as ``sentinel_rssi`` along with
        NaN and infinite values.
    on_unknown_node : {"drop", "error"}
        What to do with signals naming a node without a pose log.
    min_samples : int
        Raise :class:`InputError` when fewer samples are matched (0 disables).
    source : str
        Name of the signal log in messages.

    Returns
    -------
    SyncResult
        ``dataset`` in :data:`~rplearn.data.tables.MATCHED_COLUMNS` order plus extra columns,
        in the order of the input rows; ``summary`` with counts per drop reason.

    Raises
    ------
    InputError
        On a missing column, a bad pose log, an unknown node with ``on_unknown_node="error"``,
        or fewer than ``min_samples`` matched samples.
    """
    _check_options(max_gap_s, on_unknown_node, link)
    pose = validate_pose_log(pose_log, "pose log")
    tracks = _tracks(pose, clock_offsets_s, "pose log")
    if link is not None:
        check_link_nodes(signal_log, link, source)
    result = _match_chunk(
        tracks, signal_log, link, max_gap_s, signal_clock_offset_s, sentinel_rssi_dbm,
        on_unknown_node, source,
    )
    result.summary.non_unit_quaternions = non_unit_quaternion_rows(pose)
    if result.summary.n_out < min_samples:
        raise InputError(
            f"{source}: only {result.summary.n_out} signal sample(s) matched, at least "
            f"{min_samples} needed ({result.summary.to_text().replace(chr(10), ';')})"
        )
    return result


def synchronise_stream(
    pose_log: pd.DataFrame,
    signal_chunks: Iterable[pd.DataFrame],
    link: tuple[str, str] | None = None,
    max_gap_s: float = 0.2,
    clock_offsets_s: Mapping[str, float] | None = None,
    signal_clock_offset_s: float | Mapping[str, float] = 0.0,
    sentinel_rssi_dbm: Sequence[float] = DEFAULT_SENTINEL_RSSI_DBM,
    on_unknown_node: str = "drop",
    source: str = "signal log",
) -> Iterator[SyncResult]:
    """Match a signal log chunk by chunk; yields one :class:`SyncResult` per chunk.

    The pose log is held in memory (a 100 Hz log of an hour is 360,000 rows per node); the
    signal log is consumed lazily, so memory stays bounded by the chunk size. Merge the
    per-chunk summaries with :meth:`SyncSummary.merge`. Options as in :func:`synchronise`.
    """
    _check_options(max_gap_s, on_unknown_node, link)
    pose = validate_pose_log(pose_log, "pose log")
    tracks = _tracks(pose, clock_offsets_s, "pose log")
    non_unit = non_unit_quaternion_rows(pose)
    for chunk in signal_chunks:
        result = _match_chunk(
            tracks, chunk, link, max_gap_s, signal_clock_offset_s, sentinel_rssi_dbm,
            on_unknown_node, source,
        )
        result.summary.non_unit_quaternions, non_unit = non_unit, 0  # counted once, in the first chunk
        yield result


def synchronise_to_parquet(
    pose_log: pd.DataFrame,
    signal_chunks: Iterable[pd.DataFrame],
    out_path: str,
    **options,
) -> SyncSummary:
    """Stream a signal log through :func:`synchronise_stream` into one Parquet file.

    Parameters
    ----------
    pose_log : DataFrame
        Canonical pose log.
    signal_chunks : iterable of DataFrame
        Signal-log chunks, e.g. :func:`rplearn.io.tables.iter_signal_table`.
    out_path : str
        Parquet file to write (one row group per non-empty chunk).
    **options
        Passed to :func:`synchronise_stream`.

    Returns
    -------
    SyncSummary
        Counts over the whole log.
    """
    import pyarrow as pa
    import pyarrow.parquet as pq

    total = SyncSummary()
    writer = None
    schema = None
    try:
        for res in synchronise_stream(pose_log, signal_chunks, **options):
            total.merge(res.summary)
            if res.dataset.empty:
                continue
            table = pa.Table.from_pandas(res.dataset, preserve_index=False)
            if writer is None:
                schema = table.schema
                writer = pq.ParquetWriter(out_path, schema)
            else:
                table = table.select(schema.names).cast(schema)
            writer.write_table(table)
        if writer is None:  # nothing matched: write an empty file with the canonical columns
            empty = pd.DataFrame({c: pd.Series(dtype=str if c in ("tx", "rx") else float)
                                  for c in MATCHED_COLUMNS})
            empty.to_parquet(out_path, index=False)
    finally:
        if writer is not None:
            writer.close()
    return total


__all__ = [
    "DEFAULT_SENTINEL_RSSI_DBM",
    "DROP_REASONS",
    "PoseTrack",
    "check_link_nodes",
    "duplicate_rows",
    "SyncResult",
    "SyncSummary",
    "pose_tracks",
    "slerp_wxyz",
    "synchronise",
    "synchronise_stream",
    "synchronise_to_parquet",
]
