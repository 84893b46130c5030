"""Commands on flight logs: ``inspect`` (what is in them) and ``sync`` (a matched dataset)."""

from __future__ import annotations

import typer

from rplearn.cli._app import app, fail, flag_values, geodetic_flag, link, note, numbers, pairs, reader_options, say, user_errors, with_flag

# The reader options inspect and sync declare alike (typer copies a declaration for each command).
_NODE = typer.Option(None, "--node", help="FILE=NODE for ULogs and one-node tables.")
_RECEIVER = typer.Option(None, "--receiver", help="FILE=NODE: capturing node of a pcap.")
_ADDRESS = typer.Option(None, "--address", help="MAC=NODE: transmitter addresses of pcaps.")
_RSSI_TOPIC = typer.Option(None, "--rssi-topic", help="TOPIC=TX:RX: RSSI topic of ROS bags, packets from TX received by RX.")
_RSSI_FIELD = typer.Option(None, "--rssi-field", help="Field of the RSSI [dBm] in --rssi-topic messages, dots for nested fields (default "
                                                      "rssi).")
_MSG_DEFINITION = typer.Option(None, "--msg-definition", help="TYPE=FILE.msg: custom message type a bag does not describe (e.g. "
                                                              "pkg/msg/LinkQuality=LinkQuality.msg).")
_REQUIRE_VALID = typer.Option(False, "--require-valid/--accept-invalid", help="Drop ULog positions the autopilot flags invalid (xy_valid or z_valid = "
                                                                              "0), or keep them (default).")
_STATION_GEODETIC = typer.Option(None, "--station", help="LAT,LON,ALT: ground station position of MAVLink logs (.tlog, DataFlash) and of ULogs "
                                                         "read with --ulog-radio [deg, deg, m AMSL] (default: the log's home position, else the "
                                                         "vehicle's first fix).")
_STATION = typer.Option(None, "--station-node", help="Node id of the ground station of MAVLink logs and of ULogs read with --ulog-radio "
                                                     "(default gcs).")
_STATION_HEADING = typer.Option(None, "--station-heading", help="Compass heading of the ground station's antenna (its body x axis) in MAVLink "
                                                                "logs and ULogs read with --ulog-radio [deg clockwise from north] (default 90, "
                                                                "east).")
_ULOG_RADIO = typer.Option(False, "--ulog-radio", help="Read the telemetry radio of PX4 ULogs (radio_status: a SiK radio's RSSI both ways) as the "
                                                       "links between the vehicle and the ground station (needs --tx-power and --frequency; "
                                                       "default: poses only).")


@app.command()
@user_errors
def inspect(
    logs: list[str] = typer.Argument(..., help="Log files: CSV/Parquet, ROS 1/2 bags, PX4 ULog, pcap, MAVLink .tlog and ArduPilot DataFlash .bin."),
    node: list[str] | None = _NODE,
    receiver: list[str] | None = _RECEIVER,
    address: list[str] | None = _ADDRESS,
    pose_topic: list[str] | None = typer.Option(None, "--pose-topic", help="TOPIC=NODE for ROS bags."),
    rssi_topic: list[str] | None = _RSSI_TOPIC,
    rssi_field: str | None = _RSSI_FIELD,
    msg_definition: list[str] | None = _MSG_DEFINITION,
    require_valid: bool = _REQUIRE_VALID,
    station_geodetic: str | None = _STATION_GEODETIC,
    station: str | None = _STATION,
    station_heading: float | None = _STATION_HEADING,
    ulog_radio: bool = _ULOG_RADIO,
    frequency_hz: float | None = typer.Option(None, "--frequency", help="Carrier frequency for logs without it [Hz]: the distance a calibration flight needs "
                                                                        "is 10 wavelengths (433 MHz assumed without it)."),
    markdown: bool = typer.Option(False, "--markdown", help="Print Markdown instead of text."),
    as_json: bool = typer.Option(False, "--json", help="Print strict JSON instead of text (times from the log start)."),
) -> None:
    """Summarise logs: nodes, time spans (seconds from the log start), report rates, RSSI range, gaps,
    what the readers excluded, whether the log holds a calibration flight, and anything suspicious.

    Example: rplearn inspect flight/pose_log.parquet flight/signal_log.parquet
    """
    from rplearn.io.inspect import inspect_logs

    with flag_values():
        options = reader_options(node, receiver, address, pose_topic, rssi_topic, rssi_field, msg_definition,
                                 require_valid=require_valid, station_geodetic=geodetic_flag(station_geodetic, "--station"),
                                 station=station, station_heading_deg=station_heading, frequency_hz=frequency_hz,
                                 ulog_radio=ulog_radio)
    if markdown and as_json:
        fail("--markdown and --json: choose one")
    report = inspect_logs(logs, options)
    if as_json:
        from rplearn.io.inspect_json import inspect_to_json

        say(inspect_to_json(report))
        unreadable = [f for f in report.files if f.get("error") is not None]
        if unreadable:
            fail(unreadable_line(unreadable, len(report.files), "(see the JSON)"))
        return
    text = report.to_markdown() if markdown else report.to_text()
    # the report names reader options as the library knows them; here they are flags
    say("\n".join(with_flag(line, None, inspect) for line in text.splitlines()))
    unreadable = [f for f in report.files if f.get("error") is not None]
    if unreadable:
        fail(unreadable_line(unreadable, len(report.files), "(see above)"))


def unreadable_line(unreadable: list[dict], n_files: int, where: str) -> str:
    """The last line of ``inspect`` when files could not be read: their names (the first three),
    and each one's reason when a single file failed."""
    names = [str(f.get("path") or f.get("file") or "?") for f in unreadable]
    shown = ", ".join(names[:3]) + (f" and {len(names) - 3} more" if len(names) > 3 else "")
    if len(unreadable) == 1:
        reason = str(unreadable[0].get("error") or "").splitlines()[0] if unreadable[0].get("error") else ""
        prefix = f"{names[0]}: "
        reason = reason[len(prefix):] if reason.startswith(prefix) else reason
        return f"{names[0]}: could not be read ({reason})" if reason else f"{names[0]}: could not be read {where}"
    return f"{shown}: {len(unreadable)} of {n_files} file(s) could not be read {where}"


@app.command()
@user_errors
def sync(
    poses: list[str] = typer.Option(..., "--poses", help="Pose log(s): CSV/Parquet, bag, ULog, MAVLink .tlog/.bin. Repeat for several."),
    signals: list[str] = typer.Option(..., "--signals", help="Signal log(s): CSV/Parquet, bag, pcap, MAVLink .tlog/.bin, ULog with --ulog-radio. "
                                                            "Repeat for several."),
    output: str = typer.Option(..., "-o", "--out", help="Matched dataset (.parquet or .csv)."),
    link_text: str | None = typer.Option(None, "--link", help="Keep one direction TX:RX (the paper's choice), or 'all'."),
    max_gap_s: float = typer.Option(0.2, "--max-gap", help="Drop samples inside pose gaps longer than this [s]."),
    offset: list[str] | None = typer.Option(None, "--offset", help="NODE=SECONDS clock offset added to a node's pose times."),
    node: list[str] | None = _NODE,
    receiver: list[str] | None = _RECEIVER,
    address: list[str] | None = _ADDRESS,
    pose_topic: list[str] | None = typer.Option(None, "--pose-topic", help="TOPIC=NODE: pose topics of ROS bags."),
    rssi_topic: list[str] | None = _RSSI_TOPIC,
    rssi_field: str | None = _RSSI_FIELD,
    msg_definition: list[str] | None = _MSG_DEFINITION,
    tx_power_dbm: float | None = typer.Option(None, "--tx-power", help="Transmit power for logs without it [dBm]."),
    frequency_hz: float | None = typer.Option(None, "--frequency", help="Carrier frequency for logs without it [Hz]."),
    nan_policy: str = typer.Option("error", "--nan-policy", help="Pose-table rows with NaN or non-numeric values: error (default) or drop (counted)."),
    allow_unsorted: bool = typer.Option(False, "--allow-unsorted", help="Accept pose tables whose times go backwards within a node, "
                                        "and signal tables within a link (the rows are sorted)."),
    require_valid: bool = _REQUIRE_VALID,
    station_geodetic: str | None = _STATION_GEODETIC,
    station: str | None = _STATION,
    station_heading: float | None = _STATION_HEADING,
    ulog_radio: bool = _ULOG_RADIO,
    on_unknown_node: str = typer.Option("drop", "--on-unknown-node", help="Signals naming a node without a pose log: drop (counted, default) or error."),
    rssi_scale: str = typer.Option("dbm", "--rssi-scale", help="dbm (default: calibrated, dropped outside -150..30 dBm or above the transmit power) or "
                                                               "relative (uncalibrated dB on the radio's own scale: no plausibility window)."),
    estimate_offset: str | None = typer.Option(None, "--estimate-offset", help="NODE: find the clock offset of NODE's poses that best explains the signal (a "
                                                                               "low-order pattern fit's residual over shifts of its pose times) and report it "
                                                                               "with its uncertainty."),
    offset_window: float = typer.Option(1.0, "--offset-window", help="Shifts tried by --estimate-offset, +- this [s]."),
    apply_offset: bool = typer.Option(False, "--apply-offset", help="Add the offset --estimate-offset found to NODE's pose times in the matched dataset "
                                                                    "(default: report only)."),
    from_s: float | None = typer.Option(None, "--from", help="Keep samples from this time on [s]: seconds from the log start (the origin inspect prints), or a "
                                                             "log time with --log-time."),
    to_s: float | None = typer.Option(None, "--to", help="Keep samples up to this time [s]: seconds from the log start, or a log time with --log-time."),
    log_time: bool = typer.Option(False, "--log-time", help="Read --from/--to as times on the logs' own clock instead of seconds from the log start."),
    airborne: bool = typer.Option(False, "--airborne/--all-phases", help="Keep only samples while every vehicle is armed (where the log says) and more than "
                                                                         "--airborne-margin above its take-off altitude; default: all phases (CSV/Parquet logs "
                                                                         "are usually calibration flights already), the summary counts samples taken on the "
                                                                         "ground."),
    airborne_margin_m: float = typer.Option(2.0, "--airborne-margin", help="Height above the take-off altitude from which a vehicle is airborne [m]."),
    repeat_fraction: float = typer.Option(0.1, "--repeat-fraction", help="Rows of one link with equal values closer than this fraction of its report period "
                                                                         "are one reading logged twice, merged (0 keeps every row)."),
) -> None:
    """Match every signal sample with the interpolated poses of both ends (paper Sec. V-B4).

    Example: rplearn sync --poses flight/pose_log.parquet --signals flight/signal_log.parquet --link A:B -o data.parquet
    """
    from rplearn.data.sync import SyncOptions
    from rplearn.workflows.logs import sync_logs

    with flag_values():
        readers = reader_options(
            node, receiver, address, pose_topic, rssi_topic, rssi_field, msg_definition, tx_power_dbm=tx_power_dbm,
            frequency_hz=frequency_hz, nan_policy=nan_policy, allow_unsorted=allow_unsorted, require_valid=require_valid,
            station_geodetic=geodetic_flag(station_geodetic, "--station"), station=station,
            station_heading_deg=station_heading, ulog_radio=ulog_radio)
        offsets = numbers(pairs(offset, "--offset"), "--offset", "NODE=SECONDS")
        options = SyncOptions(link=link(link_text), max_gap_s=max_gap_s, clock_offsets_s=offsets or None,
                              on_unknown_node=on_unknown_node, rssi_scale=rssi_scale, from_s=from_s, to_s=to_s,
                              window_clock="log" if log_time else "start", airborne=airborne,
                              airborne_margin_m=airborne_margin_m, repeat_fraction=repeat_fraction)
    outcome = sync_logs(poses, signals, output, readers, options, estimate_offset=estimate_offset,
                        offset_window_s=offset_window, apply_offset=apply_offset)
    if outcome.clock is not None:
        c = outcome.clock
        say(c.curve_text())
        if not apply_offset:
            note(f"the offset was not applied; rerun with --apply-offset (or --offset {c.node}={c.offset_s:.3f}) to use it")
    for line in outcome.notes:  # part of the data's accounting: on standard output, options named by their flags
        say(with_flag(line, None, sync) if "Options." in line else line)
    say("\n".join(with_flag(line, None, sync) for line in outcome.summary().splitlines()))
