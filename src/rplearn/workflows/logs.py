"""Pipelines on flight logs: synchronise them into a matched dataset, and predict a swarm's
links or best headings from the drones' poses (``rplearn sync``, ``links``, ``headings``).

Output paths are checked before any work; what the readers dropped or assumed comes back as
notes for the user.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, cast

import pandas as pd
from numpy.typing import ArrayLike

from rplearn._argtypes import check_types
from rplearn.analysis.heading_options import SwarmHeadingOptions
from rplearn.analysis.headings import SwarmHeadings, best_swarm_headings
from rplearn.analysis.swarm import SwarmOptions, SwarmPrediction, predict_swarm
from rplearn.data.streaming import conform_chunk, synchronise_stream
from rplearn.data.sync import SyncOptions, SyncSummary, synchronise
from rplearn.data.tables import MATCHED_COLUMNS, SIGNAL_COLUMNS
from rplearn.errors import InputError, LogFormatError
from rplearn.io import ReaderOptions, read_logs
from rplearn.io._csv_headers import REPEATED_HEADER, REPEATED_HEADER_AT, HeaderScan, csv_source, repeated_header_text, scan_csv_headers
from rplearn.io.files import check_output_kind, check_output_path, check_table_path, write_json, write_table, write_table_chunks
from rplearn.io.inspect import file_damage
from rplearn.io.resolve import check_outputs, distinct_inputs
from rplearn.models.load import load_model
from rplearn.models.patterns import PatternSet
from rplearn.models.predict import FrequencyMismatch, frequency_mismatch


@check_types
def reader_notes(metadata: Mapping[str, Any]) -> list[str]:
    """What the log readers dropped or assumed, file by file (from :func:`read_logs` metadata)."""
    notes = []
    for f in metadata.get("files", []):
        source = f.get("source", "log")
        rows = "frame(s)" if f.get("kind") == "signal" else "pose row(s)"  # a capture's drops are frames
        notes += [f"{source}: dropped " + (repeated_header_text(n, f.get(REPEATED_HEADER_AT, ())) if why == REPEATED_HEADER
                                           else f"{n:,} {rows} ({why})") for why, n in (f.get("dropped") or {}).items() if n]
        if f.get("level_assumed"):
            notes.append(f"{source}: yaw only, so level flight (roll = pitch = 0) is assumed")
        notes += file_damage(source, f)
        notes += list(f.get("notes") or [])
    return notes


#: Formats of pose tables (:func:`rplearn.io.tables.table_format`): a node's poses as the user wrote them.
_TABLE_FORMATS = ("csv", "parquet")


def _station_advice(node: str, sources: list[str], reasons: list[str], reader: ReaderOptions) -> str:
    """What the ground station ``node`` of MAVLink/DataFlash/ULog logs ``sources`` is: where it was placed (the
    position given in ``reader``, else the logs' own ``reasons``, quoted) and what to give if it stood elsewhere or
    faced another way (only what ``reader`` does not give already)."""
    logs = " and ".join(sources)
    if reader.station_geodetic is not None:
        lat, lon, alt = reader.station_geodetic
        where = f"one pose row at the position given for it ({lat:.6f}, {lon:.6f}, {alt:.1f} m) in {logs}"
    elif reasons:
        where = "one pose row where the log placed it: " + "; ".join(
            f'"{reason}" ({source})' for source, reason in zip(sources, reasons))
    else:
        where = f"one pose row where {logs} {'places' if len(sources) == 1 else 'place'} it (at the log's home, " \
                "else the vehicle's first fix)"
    text = f"{node} is the ground station, {where}: held fixed, as a station standing through the flight is; " \
           "the log holds no motion of it"
    advice = [] if reader.station_geodetic is not None else ["ReaderOptions.station_geodetic places it if it stood "
                                                              "elsewhere"]
    if reader.station_heading_deg is None:
        advice.append("ReaderOptions.station_heading_deg says where its antenna faced")
    else:
        text += f", its antenna facing heading {reader.station_heading_deg:g} deg as given"
    return text + (f". {', '.join(advice)}" if advice else "")


@check_types
def fixed_node_advice(
    fixed_nodes: Sequence[str], metadata: Mapping[str, Any], reader: ReaderOptions | None = None,
) -> list[str]:
    """What each node a sync took as fixed (``SyncSummary.fixed_nodes``) is, by where its poses came from
    (:func:`read_logs` metadata), and what to do if it moved.

    The ground station a MAVLink or DataFlash log, or a ULog read with its radio, places is one pose row: fixed as a
    station is, the log holds no motion of it, nothing wrong with it. Where it stands is quoted from the log's reader
    (its ``station_note``: the vehicle's home, or its first fix), or is the position given (``reader``'s
    ``station_geodetic``); the options that place and turn it are named only when ``reader`` does not give them
    already. A node of a pose table (CSV/Parquet) logged with one row or identical rows may be a station or a parked
    drone; if it moved, its motion is missing from the table: log its poses. A vehicle of another log (a ULog, a
    bag, a MAVLink log's vehicle) gave no motion: it stood still throughout.

    Parameters
    ----------
    fixed_nodes : sequence of str
        The nodes the sync took as fixed.
    metadata : mapping
        The pose logs' :func:`read_logs` metadata.
    reader : ReaderOptions, optional
        The options the logs were read with (default: :class:`ReaderOptions` ``()``).
    """
    reader = reader or ReaderOptions()
    files = list(metadata.get("files", []))
    stations: dict[str, list[str]] = {}
    reasons: dict[str, list[str]] = {}
    vehicles: dict[str, list[str]] = {}
    for f in files:
        if f.get("station") is not None:
            stations.setdefault(str(f["station"]), []).append(str(f.get("source")))
            if f.get("station_note"):
                reasons.setdefault(str(f["station"]), []).append(str(f["station_note"]))
        for key in ("vehicle", "node"):
            if f.get(key) is not None:
                vehicles.setdefault(str(f[key]), []).append(str(f.get("source")))
    tables = [str(f.get("source")) for f in files if f.get("format") in _TABLE_FORMATS and "pose" in str(f.get("kind"))]
    advice = []
    for node in fixed_nodes:
        if node in stations:
            said = reasons.get(node, [])
            advice.append(_station_advice(node, stations[node], said if len(said) == len(stations[node]) else [], reader))
        elif node in vehicles:
            where = vehicles[node]
            advice.append(f"{node}: {' and '.join(where)} {'gives' if len(where) == 1 else 'give'} it no motion: it "
                          "stood still throughout the log")
        elif tables:
            advice.append(f"{node}: its pose table ({', '.join(tables)}) gives it one pose, or only identical ones: "
                          f"right for a station or a parked drone; if {node} moved, its motion was not logged: log "
                          "its poses")
    return advice


@check_types
@dataclass
class SyncOutcome:
    """A matched dataset written from logs: its counts, where it went, what the readers said.

    Attributes
    ----------
    counts : SyncSummary
        Samples in, matched, and dropped by reason.
    output : str
        The matched dataset written.
    notes : list of str
        What the log readers dropped or assumed.
    streamed : bool
        True when the signal logs were read in chunks (CSV/Parquet signal tables).
    clock : ClockOffsetEstimate or None
        The estimated clock offset of a node (``estimate_offset``), applied or not.
    """

    counts: SyncSummary
    output: str
    notes: list[str] = field(default_factory=list)
    streamed: bool = False
    clock: Any = None

    def summary(self) -> str:
        kept = self.counts.outages.get("kept", 0)
        text = (f"{self.counts.to_text()}\nwrote {self.counts.n_out:,} matched samples"
                + (f" and {kept:,} outage events" if kept else "") + f" to {self.output}")
        if self.clock is not None:
            text = self.clock.summary() + "\n" + text
        return text


#: Rows of a signal table read at a time when a sync streams it.
SYNC_CHUNK_ROWS = 200_000


def _streamable(signal_paths: Sequence[str], reader_options: ReaderOptions) -> bool:
    """True when every signal path is a CSV/Parquet signal table (read in chunks)."""
    from rplearn.io import detect_format
    from rplearn.io.tables import table_kind

    return all(detect_format(p) == "table" and table_kind(p, reader_options.columns) == "signal"
               for p in signal_paths)


def _extra_columns(signal_paths: Sequence[str], options: ReaderOptions) -> tuple[dict[str, str], dict[str, HeaderScan]]:
    """Extra (non-canonical) columns of all signal tables, in order of first appearance, each
    ``"number"`` when every value in every file is a number, else ``"text"`` (a pass over
    those columns only); and the header scans made for that pass (:func:`scan_csv_headers`, by
    path: the CSV files with extra columns), so that reading the rows scans no file again."""
    from rplearn.io.tables import table_columns

    kinds: dict[str, str] = {}
    scans: dict[str, HeaderScan] = {}
    for path in signal_paths:
        columns = table_columns(path, options.columns)
        names = [c for c in columns if c not in SIGNAL_COLUMNS]
        for c in names:
            kinds.setdefault(c, "number")
        for c, numeric in _numeric_columns(path, names, columns, scans).items():
            if not numeric:
                kinds[c] = "text"
    return kinds, scans


def _numeric_columns(path: str, names: list[str], columns: list[str], scans: dict[str, HeaderScan]) -> dict[str, bool]:
    """Whether each of these columns of one table holds numbers only (missing cells allowed);
    ``columns`` are the table's column names after renaming, in file order. A CSV file's header
    scan is kept in ``scans`` under its path."""
    from rplearn.io.tables import table_read_message

    if not names:
        return {}
    if str(path).lower().endswith((".parquet", ".pq")):
        import pyarrow as pa
        import pyarrow.parquet as pq

        schema = pq.ParquetFile(path).schema_arrow
        renamed = dict(zip(columns, schema.names))
        return {c: pa.types.is_integer(schema.field(renamed[c]).type) or pa.types.is_floating(schema.field(renamed[c]).type)
                for c in names}
    renamed = dict(zip(columns, pd.read_csv(path, nrows=0, skipinitialspace=True).columns))
    numeric = {c: True for c in names}
    scans[str(path)] = scan = scan_csv_headers(path, str(path))
    try:
        with csv_source(path, scan) as handle:  # without the header lines repeated mid-file
            for chunk in pd.read_csv(handle, usecols=[renamed[c] for c in names], dtype=str, chunksize=SYNC_CHUNK_ROWS,
                                     skipinitialspace=True):
                for c in names:
                    col = chunk[renamed[c]]
                    numeric[c] = numeric[c] and bool(pd.to_numeric(col, errors="coerce").notna().sum() == col.notna().sum())
    except Exception as exc:  # a malformed line (a quote left open): said as reading the rows says it
        raise LogFormatError(table_read_message(str(path), path, exc, scan)) from None
    return numeric


def _signal_chunks(signal_paths: Sequence[str], options: ReaderOptions, files: list[dict[str, Any]]) -> Iterator[pd.DataFrame]:
    """Every signal table's rows, chunk by chunk, file after file, all with the same columns; what each file's
    reading dropped is added to ``files`` (as :func:`read_logs` metadata says it)."""
    from rplearn.io.tables import iter_signal_table

    extras, scans = _extra_columns(signal_paths, options)  # the files scanned for header lines once, there
    ptx = options.tx_power_dbm if not isinstance(options.tx_power_dbm, Mapping) else None
    for path in signal_paths:
        first_row = 0
        for chunk in iter_signal_table(
            path, SYNC_CHUNK_ROWS, columns=options.columns, tx_power_dbm=ptx,
            frequency_hz=options.frequency_hz, rx=(options.receivers or {}).get(path),
            allow_unsorted=options.allow_unsorted, header_scan=scans.get(str(path)),
        ):
            if first_row == 0:
                files.append({"source": str(path), "kind": "signal", REPEATED_HEADER_AT: list(chunk.attrs.get(REPEATED_HEADER_AT, ())),
                              "dropped": {REPEATED_HEADER: int(chunk.attrs.get(REPEATED_HEADER, 0))}})
            out = conform_chunk(chunk, extras)
            out.attrs.update(source=str(path), first_row=first_row)  # messages name the file and its row
            first_row += len(chunk)
            yield out


def _both_notes(pose_meta: Mapping[str, Any], signal_meta: Mapping[str, Any]) -> list[str]:
    """What the readers of the pose and of the signal logs said, each line once (a log given as
    both, a ``.tlog``, is read once: its notes are said once)."""
    return list(dict.fromkeys(reader_notes(pose_meta) + reader_notes(signal_meta)))


def _signal_log(signal_paths: Sequence[str], pose_paths: Sequence[str], read_with_poses: pd.DataFrame | None,
                pose_meta: dict[str, Any], reader_options: ReaderOptions) -> tuple[pd.DataFrame | None, dict[str, Any]]:
    """The signal log of ``signal_paths`` (None if they hold none) and what its reading said
    (:func:`read_logs`'s metadata): ``read_with_poses`` and ``pose_meta``, what the reading of
    the poses gave, when both name the same files in the same order (a ``.tlog`` or a bag
    given as both, the usual case, is then parsed once, not twice), else read now with the
    same options."""
    if [str(p) for p in signal_paths] == [str(p) for p in pose_paths]:
        return read_with_poses, pose_meta
    logs, meta = read_logs(signal_paths, reader_options)
    return logs.signal, meta


@check_types
def sync_logs(
    pose_paths: Sequence[str],
    signal_paths: Sequence[str],
    output: str,
    reader_options: ReaderOptions | None = None,
    sync_options: SyncOptions | None = None,
    estimate_offset: str | None = None,
    offset_window_s: float = 1.0,
    apply_offset: bool = False,
) -> SyncOutcome:
    """Read pose and signal logs of any format, match every packet with the poses of both
    ends (paper Sec. V-B4) and write the matched dataset.

    CSV and Parquet signal tables are streamed (:data:`SYNC_CHUNK_ROWS` rows at a time), so a
    signal log of any length fits in memory; their samples are written in file order (sorted
    by time within a sorted file). Other formats are read whole and sorted by time.

    With ``estimate_offset`` (a node id), the clock offset of that node's poses is first
    estimated over ``+-offset_window_s`` (:func:`rplearn.analysis.clock.estimate_clock_offset`;
    the signal logs are then read whole once) and reported in the outcome; it is added to the
    node's offset only with ``apply_offset``.
    """
    distinct_inputs(pose_paths, param="pose_paths")
    distinct_inputs(signal_paths, param="signal_paths")
    check_output_path(output, [*pose_paths, *signal_paths])
    check_table_path(output)
    reader_options = reader_options or ReaderOptions()
    sync_options = sync_options or SyncOptions()
    pose_logs, pose_meta = read_logs(pose_paths, reader_options)
    if pose_logs.pose is None:
        from rplearn.io.sniff import swapped_logs_hint

        raise InputError(f"{', '.join(pose_paths)}: no pose log found{swapped_logs_hint(pose_paths, signal_paths)}",
                         param="pose_paths")
    poses = pose_logs.pose
    clock = None
    if apply_offset and estimate_offset is None:
        raise InputError("apply-offset: nothing to apply; give --estimate-offset NODE", param="estimate_offset")
    if estimate_offset is not None:
        from rplearn.analysis.clock import estimate_clock_offset

        whole, _ = _signal_log(signal_paths, pose_paths, pose_logs.signal, pose_meta, reader_options)
        if whole is None:
            raise InputError(f"{', '.join(signal_paths)}: no signal log found", param="signal_paths")
        clock = estimate_clock_offset(pose_logs.pose, whole, estimate_offset, offset_window_s, sync_options)
        if apply_offset and clock.at_edge:
            raise InputError(f"apply-offset: the minimum for {clock.node} is at the edge of the +-{offset_window_s:g} s "
                             "window; widen --offset-window before applying it", param="offset_window")
        if apply_offset:
            offsets = {**dict(sync_options.clock_offsets_s or {}), clock.node: clock.offset_s}
            sync_options = dataclasses.replace(sync_options, clock_offsets_s=offsets)
    source = ", ".join(signal_paths)
    if _streamable(signal_paths, reader_options):
        summary = SyncSummary()
        read: list[dict[str, Any]] = []

        def frames() -> Iterator[pd.DataFrame]:
            for res in synchronise_stream(poses, _signal_chunks(signal_paths, reader_options, read),
                                          sync_options, source=source):
                summary.merge(res.summary)
                yield res.dataset

        write_table_chunks(frames(), output, MATCHED_COLUMNS)
        summary.notes += fixed_node_advice(summary.fixed_nodes, pose_meta, reader_options)
        return SyncOutcome(summary, output, _both_notes(pose_meta, {"files": read}), streamed=True, clock=clock)
    signal, signal_meta = _signal_log(signal_paths, pose_paths, pose_logs.signal, pose_meta, reader_options)
    if signal is None:
        raise InputError(f"{', '.join(signal_paths)}: no signal log found", param="signal_paths")
    result = synchronise(pose_logs.pose, signal, sync_options, source=source)
    result.summary.notes += fixed_node_advice(result.summary.fixed_nodes, pose_meta, reader_options)
    write_table(result.dataset, output)
    return SyncOutcome(result.summary, output, _both_notes(pose_meta, signal_meta), clock=clock)


@check_types
@dataclass
class LinksOutcome:
    """A swarm's predicted links, and what the user should know about the inputs."""

    prediction: SwarmPrediction
    notes: list[str] = field(default_factory=list)
    mismatch: FrequencyMismatch | None = None


@check_types
def swarm_links(
    model_path: str,
    pose_paths: Sequence[str],
    output: str,
    tx_power_dbm: float,
    options: SwarmOptions | None = None,
    reader_options: ReaderOptions | None = None,
    connectivity_out: str | None = None,
    plot_path: str | None = None,
) -> LinksOutcome:
    """Predict every link of a swarm over time from its pose logs and write the tables.

    ``options`` (carrier, ``pattern_of``, threshold, times, longest pose gap) go to
    :func:`rplearn.analysis.swarm.predict_swarm`; ``reader_options`` to
    :func:`rplearn.io.read_logs`.
    """
    options = SwarmOptions() if options is None else options
    frequency_hz = options.frequency_hz
    distinct_inputs(pose_paths, param="pose_paths")
    check_outputs({"output": output, "connectivity_out": connectivity_out, "plot_path": plot_path},
                  [model_path, *pose_paths])
    for path in (output, connectivity_out):
        if path:
            check_table_path(path)
    if plot_path is not None:
        check_output_kind(plot_path, "png", "plot_path")
    model = load_model(model_path)
    logs, meta = read_logs(pose_paths, reader_options)
    if logs.pose is None:
        raise InputError(f"{', '.join(pose_paths)}: no pose log found", param="pose_paths")
    mismatch = frequency_mismatch(model, [frequency_hz]) if frequency_hz is not None else None
    prediction = predict_swarm(cast(PatternSet, model), logs.pose,  # predict_swarm refuses a baseline
                               tx_power_dbm, options, source=", ".join(pose_paths))
    write_table(prediction.links, output)
    if connectivity_out:
        write_table(prediction.connectivity, connectivity_out)
    if plot_path:
        from rplearn.viz.charts import plot_swarm

        plot_swarm(prediction, plot_path)
    return LinksOutcome(prediction, reader_notes(meta), mismatch)


@check_types
def swarm_headings(
    model_path: str,
    positions: Mapping[str, ArrayLike],
    tx_power_dbm: float,
    output: str | None = None,
    options: SwarmHeadingOptions | None = None,
) -> SwarmHeadings:
    """Yaws of a hovering swarm that maximise its bottleneck RSSI; optionally written as
    JSON (``.json``) or a table (``drone, start_yaw_deg, yaw_deg``).

    ``options`` go to :func:`rplearn.analysis.headings.best_swarm_headings`.
    """
    if output:
        check_output_path(output, [model_path])
        if not output.lower().endswith(".json"):
            check_table_path(output)
    result = best_swarm_headings(cast(PatternSet, load_model(model_path)), positions,  # refuses a baseline
                                 tx_power_dbm, options)
    if output:
        if output.lower().endswith(".json"):
            write_json(output, result.to_dict())
        else:
            write_table(result.to_frame(), output)
    return result
