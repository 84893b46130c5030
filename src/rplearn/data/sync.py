"""Pose-signal matching: the poses of both ends of every signal sample (paper Sec. V-B4).

For every signal sample, the positions of its transmitter and receiver are interpolated
linearly and their attitudes by spherical linear interpolation (slerp) at the sample's time,
after optional clock offsets. A sample is dropped, and counted by reason, when:

``late``
    only in live matching (:class:`rplearn.data.live_sync.LiveMatcher`): it arrived after
    the hashes of rows of its time were forgotten, more than
    :data:`~rplearn.data.live_sync.DUPLICATE_MEMORY_S` late (a copy of a row, which ``sync``
    of the whole log drops as ``duplicate``, or a row held up that long);
``duplicate``
    it repeats an earlier row exactly, in every column (a logger or a merge writing the same
    packet twice); the first copy is kept. :func:`rplearn.data.streaming.synchronise_stream`
    finds them across chunks too;
``invalid_value``
    its time, tx power or frequency is missing, NaN or not a number, or its tx or rx id is
    empty. A frequency or power outside the plausible bands
    (:data:`~rplearn.data.tables.FREQUENCY_BAND_HZ`, :data:`~rplearn.data.tables.TX_POWER_BAND_DBM`)
    is no drop but an :class:`~rplearn.errors.InputError` naming the row: a unit mistake
    (MHz for Hz) that would otherwise drop every sample;
``outside_window``
    its time lies outside ``[from_s, to_s]``: seconds from the log start (the origin ``inspect``
    prints, :func:`~rplearn.data.phases.log_start_s`) or log times (``window_clock="log"``);
``nan_rssi``
    its RSSI is missing: an empty cell, NaN or infinite;
``unparsable_rssi``
    its RSSI is text that is no number (``"n/a"``, ``"-70dBm"``, ``"-7O"``), in a CSV/Parquet
    file (:func:`rplearn.io.tables.canonical_signal` keeps such a cell's text) or a signal
    table given to :func:`synchronise`;
``sentinel_rssi``
    its RSSI is one of the sentinel values radios report for "no measurement"
    (default ``0, -127, -128, 127``);
``implausible_rssi``
    its RSSI lies outside the range any radio reports, :data:`PLAUSIBLE_RSSI_DBM`
    (a corrupt field or a unit mistake, e.g. mW or a percentage), or above the transmit
    power (no packet arrives stronger than it was sent);
``tx_equals_rx``
    its transmitter is its receiver;
``other_link``
    it belongs to another direction than the one chosen with ``SyncOptions(link=(tx, rx))``;
``duplicate_reading``
    it repeats the reading of the row before it on its link, every column but the time equal,
    within ``repeat_fraction`` of the link's report period (:mod:`rplearn.data.readings`: a
    DataFlash ``RAD`` written twice; never two packets of a radio reporting at a steady rate);
``unknown_node``
    one of its ends has no pose log. By default this is a counted drop (a capture often
    hears nodes that are not part of the experiment); ``SyncOptions(on_unknown_node="error")``
    raises :class:`~rplearn.errors.InputError` instead;
``out_of_span``
    its time lies before the first or after the last pose of one end;
``pose_gap``
    its time lies inside a gap of one end's pose log longer than ``max_gap_s``;
``near_field``
    its ends are no farther apart than the far-field limit, two wavelengths (paper Sec. III),
    where the link budget of eq. 1 does not hold and which :func:`rplearn.core.link.check_far_field`
    refuses: a drone on the ground beside its station, before take-off;
``disarmed``, ``on_ground``
    only with ``airborne=True``: an end is a vehicle that is disarmed (``armed`` pose column) or
    not more than ``airborne_margin_m`` above its take-off altitude (:mod:`rplearn.data.phases`).
    Off by default: CSV/Parquet logs are usually calibration flights already, and a pattern may
    be learned on the ground on purpose; the summary counts the samples taken on the ground.

When a quarter or more of the samples reaching the pose-gap test fall in pose gaps, the summary
(or the error) names the ``max_gap_s`` the pose rate needs (:func:`~rplearn.data.phases.max_gap_advice`).

Outage events (signal rows with ``outage`` True: a lost link, no RSSI) are matched apart and
kept with ``outage`` True (:mod:`rplearn.data.outages`); ``SyncSummary.outages`` counts them.

A node whose pose log has a single row is static (a ground station, a parked drone): its pose
holds at every time and it never causes ``out_of_span`` or ``pose_gap``; one logged with identical rows
holds still over its log's span. Both are fixed nodes, named by ``SyncSummary.fixed_nodes`` and a note.

Time convention: the output column ``t`` is the signal time on the common clock,
``t_signal + signal_clock_offset_s``; a pose log's times are shifted by
``clock_offsets_s[node]`` before interpolation. An offset is what must be *added* to a log's
time to put it on the common clock. All options are fields of :class:`SyncOptions`.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd

from rplearn._argtypes import check_types, is_finite_real
from rplearn.core.link import FAR_FIELD_WAVELENGTHS, SPEED_OF_LIGHT_M_S
from rplearn.core.plausible import FREQUENCY_BAND_HZ, check_frequency_hz
from rplearn.data.outages import match_outages, outage_text, split_outages, with_outages
from rplearn.data.phases import AIRBORNE_MARGIN_M, WINDOW_CLOCKS, FlightPhases, flight_phases, max_gap_advice, phase_notes, window_mask
from rplearn.data.poses import STATUS_OUT_OF_SPAN, STATUS_POSE_GAP, PoseTrack, tracks_of_pose_log
from rplearn.data.readings import REPEAT_FRACTION, duplicate_rows, repeated_reading_mask
from rplearn.data.sync_match import block_row, factorize_ends, float_block, interpolate_end, matched_frame, node_codes
from rplearn.data.sync_notes import fixed_nodes, fixed_note, implausible_note
from rplearn.data.tables import QUATERNION_NORM_TOLERANCE, SENTINEL_RSSI_DBM, SIGNAL_COLUMNS, check_tx_power_dbm, check_unit_labels, empty_ids, normalise_times
from rplearn.errors import BadValueError, InputError

#: RSSI values radios and drivers report when there is no measurement [dBm].
DEFAULT_SENTINEL_RSSI_DBM: tuple[float, ...] = SENTINEL_RSSI_DBM
#: RSSI values outside this range are no received power any radio reports [dBm]: above
#: +30 dBm a receiver front end would be destroyed, below -150 dBm lies under any noise floor.
PLAUSIBLE_RSSI_DBM: tuple[float, float] = (-150.0, 30.0)
#: Scales of the received power a sync accepts (``SyncOptions.rssi_scale``).
RSSI_SCALES: tuple[str, ...] = ("dbm", "relative")
#: Drop reasons, in the order they are tested.
DROP_REASONS: tuple[str, ...] = (
    "late", "duplicate", "invalid_value", "outside_window", "nan_rssi", "unparsable_rssi", "sentinel_rssi",
    "implausible_rssi", "tx_equals_rx",
    "other_link", "duplicate_reading", "unknown_node", "out_of_span", "pose_gap", "near_field", "disarmed", "on_ground",
)


@check_types
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
    ground_kept : int
        Matched samples with an end on the ground or disarmed, kept (``airborne=False``).
    notes : list of str
        What was done (window, airborne filter), advice (``max_gap_s``).
    outages : dict of str to int
        Outage events (:mod:`rplearn.data.outages`): ``in``, ``kept`` and dropped per reason.
    fixed_nodes : list of str
        Nodes taken as holding still (:mod:`rplearn.data.sync_notes`): a pose log of one row, or of identical rows.
    """

    n_in: int = 0
    n_out: int = 0
    dropped: dict[str, int] = field(default_factory=lambda: {r: 0 for r in DROP_REASONS})
    unknown_nodes: list[str] = field(default_factory=list)
    non_unit_quaternions: int = 0
    ground_kept: int = 0
    notes: list[str] = field(default_factory=list)
    outages: dict[str, int] = field(default_factory=dict)
    fixed_nodes: list[str] = field(default_factory=list)

    @property
    def n_dropped(self) -> int:
        return int(sum(self.dropped.values()))

    def merge(self, other: SyncSummary) -> SyncSummary:
        """Add another summary's counts into this one (for chunked matching); returns self."""
        self.n_in += other.n_in
        self.n_out += other.n_out
        for k, v in other.dropped.items():
            self.dropped[k] = self.dropped.get(k, 0) + int(v)
        self.unknown_nodes = sorted(set(self.unknown_nodes) | set(other.unknown_nodes))
        self.non_unit_quaternions += other.non_unit_quaternions
        self.ground_kept += other.ground_kept
        self.notes += [n for n in other.notes if n not in self.notes]
        self.outages = {k: self.outages.get(k, 0) + other.outages.get(k, 0) for k in {**self.outages, **other.outages}}
        self.fixed_nodes = sorted(set(self.fixed_nodes) | set(other.fixed_nodes))
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
        lines += [f"  {n}" for n in [*self.notes, outage_text(self.outages)] if n]
        if self.ground_kept:
            lines.append(f"  {self.ground_kept} matched sample(s) were taken with an end on the ground or disarmed "
                         "(kept; airborne=True drops them)")
        return "\n".join(lines)


@check_types
@dataclass
class SyncResult:
    """Matched dataset (columns :data:`~rplearn.data.tables.MATCHED_COLUMNS` first, then any
    extra signal columns) and the :class:`SyncSummary` of the matching."""

    dataset: pd.DataFrame
    summary: SyncSummary


def _check(ok: bool, name: str, expected: str, value: Any, error: type[InputError] = InputError) -> None:
    """Raise :class:`InputError` (or ``error``) naming option ``name`` (``param=name``) unless ``ok``."""
    if not ok:
        raise error(f"{name}: expected {expected}, got {value!r}", param=name)


def _seconds_by_node(value: Any, name: str) -> dict[str, float]:
    """A mapping of node id to a finite number of seconds, checked."""
    ok = isinstance(value, Mapping) and all(is_finite_real(v) for v in value.values())
    _check(ok, name, "a mapping of node id to a finite number of seconds", value)
    return {str(k): float(v) for k, v in value.items()}


def _checked_link(link: Any) -> tuple[str, str] | None:
    """The direction ``(tx, rx)`` as two different node ids, or None."""
    if link is None:
        return None
    try:
        pair = tuple(str(n) for n in link)
    except TypeError:
        pair = ()
    _check(len(pair) == 2 and pair[0] != pair[1], "link", "(tx, rx), two different node ids", link)
    return pair[0], pair[1]


@check_types
@dataclass(frozen=True)
class SyncOptions:
    """How :func:`synchronise` matches signal samples with poses.

    Parameters
    ----------
    link : (str, str), optional
        Keep only the direction ``tx -> rx`` (the paper uses one direction because links are
        not reciprocal); ``None`` keeps all directions.
    max_gap_s : float
        Longest gap between two poses of a node across which a pose is interpolated [s].
    clock_offsets_s : mapping of node id to float, optional
        Offset added to each node's pose times to put them on the common clock [s].
    signal_clock_offset_s : float or mapping of receiver id to float
        Offset added to signal times [s] (one for the log, or one per receiver: a receiver no signal row names is
        refused, :func:`check_receiver_offsets`).
    sentinel_rssi_dbm : sequence of float
        RSSI values meaning "no measurement" [dBm], dropped as ``sentinel_rssi`` (a NaN or
        infinite RSSI is dropped as ``nan_rssi``, text that is no number as ``unparsable_rssi``).
    on_unknown_node : {"drop", "error"}
        What to do with signals naming a node without a pose log.
    min_samples : int
        :func:`synchronise` raises :class:`InputError` when fewer samples are matched
        (0 disables; not used when streaming).
    rssi_scale : {"dbm", "relative"}
        ``"dbm"``: received power in dBm, dropped as ``implausible_rssi`` outside
        :data:`PLAUSIBLE_RSSI_DBM` or above the transmit power. ``"relative"``: uncalibrated
        power in dB on the radio's own scale (no plausibility window; the unknown offset goes
        into the patterns' shared constant); the matched dataset carries a column
        ``rssi_scale`` = ``relative`` so that later checks know.
    from_s, to_s : float, optional
        Keep only samples from / up to this time [s]: seconds from the log start
        (``window_clock="start"``, default) or log times (``window_clock="log"``).
    airborne : bool
        Keep only samples while every vehicle at either end is armed and more than
        ``airborne_margin_m`` above its take-off altitude (``disarmed``, ``on_ground`` drops).
        Default False (see the module docstring).
    airborne_margin_m : float
        Height above the take-off altitude from which a vehicle is airborne [m].
    repeat_fraction : float
        Rows of one link with equal values closer than this fraction of the link's report
        period are one reading (``duplicate_reading``); 0 keeps every row.

    Raises
    ------
    InputError
        On a value out of its domain; ``param`` names the field at fault.
    """

    link: tuple[str, str] | None = None
    max_gap_s: float = 0.2
    clock_offsets_s: Mapping[str, float] | None = None
    signal_clock_offset_s: float | Mapping[str, float] = 0.0
    sentinel_rssi_dbm: Sequence[float] = DEFAULT_SENTINEL_RSSI_DBM
    on_unknown_node: str = "drop"
    min_samples: int = 1
    rssi_scale: str = "dbm"
    from_s: float | None = None
    to_s: float | None = None
    window_clock: str = "start"
    airborne: bool = False
    airborne_margin_m: float = AIRBORNE_MARGIN_M
    repeat_fraction: float = REPEAT_FRACTION

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        set_(self, "link", _checked_link(self.link))
        _check(is_finite_real(self.max_gap_s) and self.max_gap_s > 0, "max_gap_s", "a positive number of seconds",
               self.max_gap_s)
        if self.clock_offsets_s is not None:
            set_(self, "clock_offsets_s", _seconds_by_node(self.clock_offsets_s, "clock_offsets_s"))
        if isinstance(self.signal_clock_offset_s, Mapping):
            set_(self, "signal_clock_offset_s", _seconds_by_node(self.signal_clock_offset_s, "signal_clock_offset_s"))
        _check(isinstance(self.signal_clock_offset_s, Mapping) or is_finite_real(self.signal_clock_offset_s),
               "signal_clock_offset_s", "a finite number of seconds, or one per receiver id", self.signal_clock_offset_s)
        try:
            sentinel: tuple[float, ...] | None = tuple(float(v) for v in self.sentinel_rssi_dbm)
        except (TypeError, ValueError):
            sentinel = None
        _check(sentinel is not None, "sentinel_rssi_dbm", "a sequence of numbers [dBm]", self.sentinel_rssi_dbm)
        set_(self, "sentinel_rssi_dbm", sentinel)
        _check(self.on_unknown_node in ("drop", "error"), "on_unknown_node", "'drop' or 'error'", self.on_unknown_node,
               BadValueError)
        _check(self.rssi_scale in RSSI_SCALES, "rssi_scale", "'dbm' or 'relative'", self.rssi_scale, BadValueError)
        _check(isinstance(self.min_samples, (int, np.integer)) and not isinstance(self.min_samples, bool)
               and self.min_samples >= 0, "min_samples", "a non-negative integer", self.min_samples)
        for name, value in (("from_s", self.from_s), ("to_s", self.to_s)):
            _check(value is None or is_finite_real(value), name, "a finite number of seconds, or None", value)
        _check(self.from_s is None or self.to_s is None or self.from_s < self.to_s, "to_s",
               f"a time after from_s={self.from_s!r}", self.to_s)
        _check(self.window_clock in WINDOW_CLOCKS, "window_clock", "'start' or 'log'", self.window_clock)
        _check(isinstance(self.airborne, (bool, np.bool_)), "airborne", "True or False", self.airborne)
        _check(is_finite_real(self.airborne_margin_m) and self.airborne_margin_m >= 0, "airborne_margin_m",
               "a non-negative number of metres", self.airborne_margin_m)
        _check(is_finite_real(self.repeat_fraction) and 0 <= self.repeat_fraction <= 0.5, "repeat_fraction",
               "a number from 0 to 0.5", self.repeat_fraction)


# ---------------------------------------------------------------------------------------------
# Matching


def _numeric(df: pd.DataFrame, column: str) -> np.ndarray:
    col = df[column]
    if pd.api.types.is_datetime64_any_dtype(col):  # datetimes: float seconds since the epoch
        return normalise_times(pd.DataFrame({"t": col}))["t"].to_numpy(np.float64)
    if pd.api.types.is_numeric_dtype(col) and not pd.api.types.is_bool_dtype(col):
        return col.to_numpy(np.float64, na_value=np.nan)
    return pd.to_numeric(col, errors="coerce").to_numpy(np.float64, na_value=np.nan)


def _unparsable(df: pd.DataFrame, column: str, parsed: np.ndarray) -> np.ndarray:
    """Rows whose cell of ``column`` holds text that is no number (``parsed`` NaN, the cell not empty)."""
    col = df[column]
    if pd.api.types.is_numeric_dtype(col) or pd.api.types.is_datetime64_any_dtype(col):
        return np.zeros(len(df), bool)
    candidates = np.flatnonzero(np.isnan(parsed))
    out = np.zeros(len(df), bool)
    if candidates.size:
        cells = col.iloc[candidates]
        words = cells.astype(str).str.strip().str.lower()
        text = cells.notna().to_numpy() & ~words.isin(("", "nan", "+nan", "-nan")).to_numpy()
        out[candidates[text]] = True
    return out


def _signal_times(
    signal: pd.DataFrame, uniques: np.ndarray, rx_code: np.ndarray, offset_s: float | Mapping[str, float],
) -> np.ndarray:
    """Signal times [s] on the common clock: plus one offset, or one per receiver (``uniques[rx_code]``)."""
    t = _numeric(signal, "t")
    if isinstance(offset_s, Mapping):
        return t + np.array([float(offset_s.get(r, 0.0)) for r in uniques], np.float64)[rx_code]
    return t + float(offset_s)


def check_receiver_offsets(offset_s: float | Mapping[str, float], receivers: Iterable[str], source: str) -> None:
    """Refuse signal clock offsets per receiver (``SyncOptions.signal_clock_offset_s``) that name a node no signal
    row names as its receiver (``receivers``: those the rows name): its offset would be ignored."""
    named = {str(r) for r in receivers}
    if isinstance(offset_s, Mapping) and (unknown := sorted(set(map(str, offset_s)) - named)):
        raise InputError(f"{source}: signal clock offsets (signal_clock_offset_s) name receiver(s) {', '.join(unknown)} that "
                         f"no signal row names as rx; receivers: {', '.join(sorted(named)) or 'none'}", param="signal_clock_offset_s")


def _unknown_nodes(
    tx_code: np.ndarray, rx_code: np.ndarray, uniques: np.ndarray, tracks: Mapping[str, PoseTrack], keep: np.ndarray,
    on_unknown_node: str, source: str, first_row: int = 0,
) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """Which node codes (into ``uniques``) have a pose log, rows naming a node without one.

    Returns ``(known, unknown_mask, names)`` with the unknown node ids named by the kept
    rows; raises with ``on_unknown_node="error"``.
    """
    known = np.array([u in tracks for u in uniques], bool)
    unknown_mask = ~known[tx_code] | ~known[rx_code]
    names: list[str] = []
    if np.any(unknown_mask & keep):
        named = np.unique(np.concatenate([tx_code[unknown_mask & keep], rx_code[unknown_mask & keep]]))
        names = sorted(str(uniques[c]) for c in named if not known[c])
        if on_unknown_node == "error":
            row = int(np.flatnonzero(unknown_mask & keep)[0]) + first_row
            raise InputError(
                f"{source}: field tx/rx: unknown node id(s) {', '.join(names)} at row {row} "
                f"(first); pose logs exist for {', '.join(sorted(tracks))} (to drop and count "
                "such samples: on_unknown_node='drop')",
                param="on_unknown_node",
            )
    return known, unknown_mask, names


def match_chunk(
    tracks: Mapping[str, PoseTrack], signal: pd.DataFrame, options: SyncOptions, source: str,
    seen_before: np.ndarray | None = None, first_row: int = 0, phases: FlightPhases | None = None,
    carry: dict | None = None,
) -> SyncResult:
    """Match one signal log (or chunk of one) with the pose tracks; drops counted by reason.

    ``seen_before`` marks rows that repeat a row of an earlier chunk (counted as duplicates);
    ``first_row`` is the row number of the chunk's first row in the whole log (for messages);
    ``phases``: the pose log's; ``carry``: see :func:`~rplearn.data.readings.repeated_readings`.
    """
    phases = phases if phases is not None else flight_phases(pd.DataFrame(), tracks)
    missing = [c for c in SIGNAL_COLUMNS if c not in signal.columns]
    if missing:
        raise InputError(
            f"{source}: missing column(s) {', '.join(missing)}; expected {', '.join(SIGNAL_COLUMNS)}"
        )
    check_unit_labels(signal, source, first_row)  # a sample of no unit: refused here, not by fit later
    summary = SyncSummary(n_in=int(len(signal)))
    cells = factorize_ends(signal)  # each end's cells factorised once, for the node and the link codes
    tx_code, rx_code, uniques = node_codes(signal["tx"], signal["rx"], cells)  # one text per node, not per row
    values = {"t": _signal_times(signal, uniques, rx_code, options.signal_clock_offset_s)}
    values.update({c: _numeric(signal, c) for c in ("rssi_dbm", "tx_power_dbm", "frequency_hz")})
    block = float_block(len(signal))  # the matched dataset's float columns, filled in place
    for c in ("t", "rssi_dbm", "tx_power_dbm", "frequency_hz"):
        block[block_row(c)] = values[c]
    t, rssi, ptx, freq = (block[block_row(c)] for c in ("t", "rssi_dbm", "tx_power_dbm", "frequency_hz"))
    keep = np.ones(len(signal), bool)

    def drop(mask: np.ndarray, reason: str) -> None:
        hit = mask & keep
        summary.dropped[reason] += int(np.count_nonzero(hit))
        np.bitwise_xor(keep, hit, out=keep)  # hit is within keep: its rows go

    drop(duplicate_rows(signal) | (False if seen_before is None else seen_before), "duplicate")
    empty = empty_ids(uniques)
    drop(~(np.isfinite(t) & np.isfinite(ptx) & np.isfinite(freq) & (freq > 0)) | empty[tx_code] | empty[rx_code],
         "invalid_value")
    if options.from_s is not None or options.to_s is not None:
        origin = phases.start_s if options.window_clock == "start" else 0.0
        drop(~window_mask(t, options.from_s, options.to_s, origin), "outside_window")
    # a unit mistake or a corrupt field: refused, naming the row (a NaN is a counted drop above)
    check_frequency_hz(np.where(keep, freq, FREQUENCY_BAND_HZ[0]), source, None, first_row)
    check_tx_power_dbm(np.where(keep, ptx, 0.0), source, None, first_row)
    unparsable = _unparsable(signal, "rssi_dbm", rssi)
    drop(~np.isfinite(rssi) & ~unparsable, "nan_rssi")
    drop(unparsable, "unparsable_rssi")
    drop(np.isin(rssi, np.asarray(options.sentinel_rssi_dbm, np.float64)), "sentinel_rssi")
    if options.rssi_scale == "dbm":
        drop((rssi < PLAUSIBLE_RSSI_DBM[0]) | (rssi > PLAUSIBLE_RSSI_DBM[1]) | (rssi > ptx), "implausible_rssi")
    drop(tx_code == rx_code, "tx_equals_rx")
    if options.link is not None:
        drop(~((uniques == options.link[0])[tx_code] & (uniques == options.link[1])[rx_code]), "other_link")
    drop(repeated_reading_mask(signal, options.repeat_fraction, t, carry, cells), "duplicate_reading")
    known, unknown, names = _unknown_nodes(tx_code, rx_code, uniques, tracks, keep, options.on_unknown_node, source,
                                           first_row)
    if names:
        summary.unknown_nodes = names
    drop(unknown, "unknown_node")
    poses = {end: block[block_row(f"{end}_x"):block_row(f"{end}_x") + 7] for end in ("tx", "rx")}
    st_tx, st_rx = (interpolate_end(tracks, list(uniques), code, t, options.max_gap_s, keep & known[code], poses[end])
                    for end, code in (("tx", tx_code), ("rx", rx_code)))
    drop((st_tx == STATUS_OUT_OF_SPAN) | (st_rx == STATUS_OUT_OF_SPAN), "out_of_span")
    drop((st_tx == STATUS_POSE_GAP) | (st_rx == STATUS_POSE_GAP), "pose_gap")
    with np.errstate(invalid="ignore"):
        d = poses["tx"][:3] - poses["rx"][:3]
        distance = np.sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2])
        limit = FAR_FIELD_WAVELENGTHS * SPEED_OF_LIGHT_M_S / np.where(keep, freq, 1.0)
        drop(keep & ~(distance > limit), "near_field")
    off = np.zeros(len(signal), bool)
    for end, code in (("tx", tx_code), ("rx", rx_code)):
        disarmed, ground = phases.masks(list(uniques), code, t, poses[end][2], keep & known[code])
        if options.airborne:
            drop(disarmed, "disarmed")
            drop(ground, "on_ground")
        off |= disarmed | ground
    summary.ground_kept = 0 if options.airborne else int((off & keep).sum())
    idx = np.flatnonzero(keep)
    summary.n_out = int(idx.size)
    matched = matched_frame(signal, idx, block, {"tx": tx_code, "rx": rx_code}, uniques)
    if options.rssi_scale == "relative":
        matched["rssi_scale"] = pd.Series(["relative"] * len(matched), index=matched.index, dtype=object)
    return SyncResult(matched, summary)


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
    name = f"link {link[0]}:{link[1]}"
    absent = [str(n) for n in link if str(n) not in present]
    if absent:
        raise InputError(
            f"{source}: {name}: node {', '.join(absent)} is in no signal log; the signal logs name "
            f"{', '.join(present) or 'no node'}",
            param="link",
        )
    if not ((tx == str(link[0])) & (rx == str(link[1]))).any():
        pairs = sorted(set(zip(tx, rx)))
        raise InputError(
            f"{source}: {name}: no signal from {link[0]} to {link[1]}; directions present: "
            f"{', '.join(f'{a}:{b}' for a, b in pairs)}",
            param="link",
        )


def sync_options_or_default(options: SyncOptions | None) -> SyncOptions:
    if options is None:
        return SyncOptions()
    if not isinstance(options, SyncOptions):
        raise InputError(f"options: expected a SyncOptions, got {type(options).__name__}", param="options")
    return options


@check_types
def synchronise(
    pose_log: pd.DataFrame,
    signal_log: pd.DataFrame,
    options: SyncOptions | None = None,
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
    options : SyncOptions, optional
        Direction, gap threshold [s], clock offsets [s], sentinel RSSI values [dBm],
        unknown-node policy and minimum sample count; ``SyncOptions()`` by default.
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
    options = sync_options_or_default(options)
    tracks, non_unit = tracks_of_pose_log(pose_log, options.clock_offsets_s, "pose log", options.max_gap_s)
    phases = flight_phases(pose_log, tracks, options.clock_offsets_s, options.airborne_margin_m)
    if options.link is not None:
        check_link_nodes(signal_log, options.link, source)
    check_receiver_offsets(options.signal_clock_offset_s, signal_log["rx"].astype(str).unique() if "rx" in signal_log else (), source)
    signal_log, events = split_outages(signal_log, source)
    result = match_chunk(tracks, signal_log, options, source, phases=phases)  # one chunk: nothing to carry
    result.summary.non_unit_quaternions = non_unit
    finish_summary(result.summary, tracks, phases, options, source)
    if len(events):  # outage events (a lost link): matched apart, kept, counted
        origin = phases.start_s if options.window_clock == "start" else 0.0
        inside = None if options.from_s is None and options.to_s is None else (
            lambda t: window_mask(t, options.from_s, options.to_s, origin))
        matched, result.summary.outages = match_outages(tracks, events, options, inside, phases)
        result.dataset = with_outages(result.dataset, matched)
    return result


def finish_summary(summary: SyncSummary, tracks: Mapping[str, PoseTrack], phases: FlightPhases,
                   options: SyncOptions, source: str) -> None:
    """Add the phase notes, the fixed nodes and any ``max_gap_s`` advice to a whole log's summary; raise when
    fewer than ``min_samples`` were matched (naming the ``max_gap_s`` the poses need)."""
    notes = phase_notes(phases, options.from_s, options.to_s, options.window_clock, options.airborne)
    summary.notes += [n for n in notes if n not in summary.notes]
    later = DROP_REASONS[DROP_REASONS.index("pose_gap"):]
    reached = summary.n_out + sum(summary.dropped.get(r, 0) for r in later)
    share = summary.dropped["pose_gap"] / reached if reached else 0.0
    advice = max_gap_advice(tracks, options.max_gap_s) if share >= 0.25 else None
    if advice:  # in the summary (and the error below), not a log warning that would repeat it
        summary.notes.append(f"{100 * share:.0f}% of the samples fall in pose gaps: {advice}")
    summary.fixed_nodes = fixed_nodes(tracks)
    said = [fixed_note(tracks, summary.fixed_nodes),
            implausible_note(summary.n_out, summary.dropped, DROP_REASONS, options.rssi_scale, PLAUSIBLE_RSSI_DBM)]
    summary.notes += [n for n in said if n and n not in summary.notes]
    if summary.n_out < options.min_samples:
        raise InputError(
            f"{source}: only {summary.n_out} signal sample(s) matched, at least "
            f"{options.min_samples} needed ({summary.to_text().replace(chr(10), ';')})"
        )


__all__ = ["DEFAULT_SENTINEL_RSSI_DBM", "DROP_REASONS", "PLAUSIBLE_RSSI_DBM", "SyncOptions", "SyncResult", "SyncSummary",
           "check_link_nodes", "check_receiver_offsets", "duplicate_rows", "finish_summary", "synchronise"]
