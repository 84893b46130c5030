"""Commands that use learned patterns to plan: ``links`` (a swarm's link budget over time),
``headings`` (yaws that keep a hovering swarm connected) and ``orient`` (one link)."""

from __future__ import annotations

from typing import Any

import typer

from rplearn.cli._app import app, flag_values, floats, note, numbers, pairs, reader_options, say, split_list, user_errors, xyz

# Options two or three of these commands declare alike (typer copies a declaration for each command).
_FREQUENCY = typer.Option(None, "--frequency", help="Carrier frequency [Hz] (default: the one the model was learned at).")
_RANK_SENSITIVITY = typer.Option(None, "--sensitivity", metavar="DBM|RADIO",
                                help="Rank by availability, P(RSSI >= this), not gain: dBm or a radio (sik, esp32-11b, wifi-6mbps, ...).")
_MIN_AVAILABILITY = typer.Option(None, "--min-availability", metavar="P",
                                help="With --sensitivity: the strongest heading(s) at least this available.")


@app.command()
@user_errors(flags={"plot_path": "--plot"})
def links(
    model_path: str = typer.Argument(..., metavar="MODEL.json"),
    poses: list[str] = typer.Argument(..., metavar="POSE_LOG...", help="Pose log(s) of the drones: a plan or a flight (CSV/Parquet, bag, ULog)."),
    output: str = typer.Option(..., "-o", "--out", help="Predicted links, one row per time and ordered pair (.csv or .parquet)."),
    tx_power_dbm: float = typer.Option(..., "--tx-power", help="Transmit power of every drone [dBm]."),
    frequency_hz: float | None = _FREQUENCY,
    pattern: list[str] | None = typer.Option(None, "--as", help="DRONE=NODE: the drone carries the antenna learned as NODE (repeat)."),
    step_s: float = typer.Option(1.0, "--step", help="Spacing of the prediction times over the span all logs cover [s]."),
    at: list[str] | None = typer.Option(None, "--at", help="Predict at these times instead [s] (repeat or comma-separate)."),
    min_rssi_dbm: float = typer.Option(-85.0, "--min-rssi", help="RSSI a link needs in each direction to be up [dBm]."),
    max_gap_s: float = typer.Option(2.0, "--max-gap", help="A drone is absent inside pose-log gaps longer than this [s]."),
    connectivity_out: str | None = typer.Option(None, "--connectivity", help="Also write the per-time connectivity table here (.csv or .parquet)."),
    plot_out: str | None = typer.Option(None, "--plot", help="Also plot RSSI, threshold and bottleneck over time here (.png)."),
    node: list[str] | None = typer.Option(None, "--node", help="FILE=NODE for ULogs and one-node tables."),
    pose_topic: list[str] | None = typer.Option(None, "--pose-topic", help="TOPIC=NODE: pose topics of ROS bags."),
    nan_policy: str = typer.Option("error", "--nan-policy", help="Pose rows with NaN or non-numeric values: error (default) or drop (counted)."),
    allow_unsorted: bool = typer.Option(False, "--allow-unsorted", help="Accept pose tables whose times go backwards within a node, "
                                        "and signal tables within a link (the rows are sorted)."),
    sensitivity: str | None = typer.Option(None, "--sensitivity", metavar="DBM|RADIO",
                                     help="Also each link's availability, P(RSSI >= this), and P(swarm connected) per time: dBm or a radio (sik, ...)."),
    draws: int = typer.Option(1000, "--draws", min=1, help="Monte Carlo draws of the patterns, the flight level and the fading (with --sensitivity)."),
    path_pair: list[str] | None = typer.Option(None, "--pair", help="A-B: also P(a path between drones A and B, over any relays) (repeat)."),
) -> None:
    """Predict every link of a swarm over time and whether it stays connected.

    For each time and ordered pair of drones: distance, predicted joint gain and RSSI with
    its spread, and whether the link is up. Per time: the pairs up both ways, the number of
    connected groups, and the bottleneck RSSI (the swarm is connected for any threshold
    below it). Drones that were not in the calibration flight use the pattern of the
    antenna they carry (--as).

    Example: rplearn links sh10.json plan_poses.csv --tx-power 20 --as C=A --as D=B --plot links.png -o links.csv
    """
    from rplearn.analysis.swarm import SwarmOptions
    from rplearn.workflows.logs import swarm_links

    with flag_values():
        readers = reader_options(node, pose_topic=pose_topic, nan_policy=nan_policy, allow_unsorted=allow_unsorted)
        times = floats(at, "--at", "times in seconds")
        options = SwarmOptions(frequency_hz, pairs(pattern, "--as"), min_rssi_dbm, step_s, times, max_gap_s)
    if sensitivity is not None:
        _links_availability(model_path, poses, tx_power_dbm, (output, connectivity_out, plot_out), options, readers,
                            (sensitivity, draws, path_pair or []))
        return
    if path_pair:
        raise typer.BadParameter("--pair needs --sensitivity", param_hint="--pair")
    outcome = swarm_links(model_path, poses, output, tx_power_dbm, options, readers, connectivity_out, plot_out)
    for line in outcome.notes:
        say(line)
    if outcome.mismatch is not None:
        note(outcome.mismatch.describe("--frequency", model_path), "warning")
    say(outcome.prediction.summary())
    say(f"wrote {len(outcome.prediction.links):,} predicted links to {output}")


def _links_availability(
    model_path: str, poses: list[str], tx_power_dbm: float, files: tuple[str, str | None, str | None], options: Any,
    readers: Any, asked: tuple[str, int, list[str]],
) -> None:
    """``links --sensitivity``: the links with their availability and the swarm's Monte Carlo."""
    from rplearn.analysis.availability import AvailabilityOptions
    from rplearn.analysis.radios import sensitivity_dbm
    from rplearn.workflows.availability import LinkFiles, swarm_links_availability

    sensitivity, draws, path_pairs = asked
    named = []
    for text in path_pairs:
        a, sep, b = text.partition("-")
        if not (sep and a and b):
            raise typer.BadParameter(f"expected A-B, got {text!r}", param_hint="--pair")
        named.append((a, b))
    with flag_values():
        availability = AvailabilityOptions(sensitivity_dbm(sensitivity), n_draws=draws, pairs=named)
    outcome = swarm_links_availability(model_path, poses, tx_power_dbm, LinkFiles(*files), availability, options, readers)
    for line in outcome.links.notes:
        say(line)
    if outcome.links.mismatch is not None:
        note(outcome.links.mismatch.describe("--frequency", model_path), "warning")
    say(outcome.links.prediction.summary())
    say(outcome.swarm.summary())
    say(f"wrote {len(outcome.links.prediction.links):,} predicted links (with availability) to {files[0]}")


@app.command()
@user_errors
def headings(
    model_path: str = typer.Argument(..., metavar="MODEL.json"),
    pos: list[str] = typer.Option(..., "--pos", help="DRONE=x,y,z: hover position, ENU [m] (repeat for every drone)."),
    tx_power_dbm: float = typer.Option(..., "--tx-power", help="Transmit power of every drone [dBm]."),
    yaw: list[str] | None = typer.Option(None, "--yaw", help="DRONE=DEG: current yaw, ENU ccw from east [deg] (default 0)."),
    fixed: list[str] | None = typer.Option(None, "--fixed", help="Drones that must keep their yaw (repeat or comma-separate)."),
    pattern: list[str] | None = typer.Option(None, "--as", help="DRONE=NODE: the drone carries the antenna learned as NODE."),
    frequency_hz: float | None = _FREQUENCY,
    step_deg: float = typer.Option(5.0, "--step", help="Yaw grid [deg]."),
    output: str | None = typer.Option(None, "-o", "--out", help="Also write the chosen yaws here (.csv or .json)."),
    sensitivity: str | None = _RANK_SENSITIVITY,
    min_availability: float | None = _MIN_AVAILABILITY,
) -> None:
    """Yaws for a hovering swarm that keep it best connected (maximise the bottleneck RSSI).

    Every drone in turn takes the yaw that maximises the weakest link the swarm needs to stay
    connected, until nothing improves: a local optimum, never worse than the current yaws.

    Example: rplearn headings sh10.json --pos A=0,0,20 --pos B=40,0,20 --pos C=20,30,25 --as C=A --tx-power 20
    """
    from rplearn.analysis.heading_options import SwarmHeadingOptions
    from rplearn.analysis.radios import sensitivity_dbm
    from rplearn.workflows.logs import swarm_headings

    with flag_values():
        positions = {drone: xyz(text, f"--pos {drone}") for drone, text in pairs(pos, "--pos").items()}
        start = numbers(pairs(yaw, "--yaw"), "--yaw", "DRONE=DEG")
        level = None if sensitivity is None else sensitivity_dbm(sensitivity)
        options = SwarmHeadingOptions(frequency_hz, pairs(pattern, "--as"), start, split_list(fixed) or (), step_deg,
                                      sensitivity_dbm=level, min_availability=min_availability)
    result = swarm_headings(model_path, positions, tx_power_dbm, output, options)
    say(result.summary())
    if output:
        say(f"wrote {output}")


@app.command()
@user_errors
def orient(
    model_path: str = typer.Argument(..., metavar="MODEL.json"),
    tx: str = typer.Option(..., "--tx", help="Transmitting node."),
    rx: str = typer.Option(..., "--rx", help="Receiving node."),
    tx_pos: str = typer.Option(..., "--tx-pos", help="x,y,z ENU [m]."),
    rx_pos: str = typer.Option(..., "--rx-pos", help="x,y,z ENU [m]."),
    turn: str = typer.Option("tx", "--turn", help="tx, rx or both."),
    tx_yaw: float = typer.Option(0.0, "--tx-yaw", help="Current yaw of tx, ENU ccw from east [deg]."),
    rx_yaw: float = typer.Option(0.0, "--rx-yaw", help="Current yaw of rx [deg]."),
    tx_power_dbm: float = typer.Option(20.0, "--tx-power", help="[dBm]."),
    frequency_hz: float | None = _FREQUENCY,
    caution: float = typer.Option(1.28, "--caution", min=0.0,  # = analysis.headings.CAUTION_Z (tested)
                                  help="Rank headings by the gain minus this many standard errors (1.28: the 10% lower bound; 0: the prediction alone)."),
    sensitivity: str | None = _RANK_SENSITIVITY,
    min_availability: float | None = _MIN_AVAILABILITY,
) -> None:
    """Heading that maximises a link, and the received power before and after.

    Headings are ranked by a lower bound of the gain, so a heading the calibration flight saw
    beats an extrapolated one predicted alike.

    Example: rplearn orient sh10.json --tx A --rx B --tx-pos 0,0,20 --rx-pos 10,5,25 --turn both
    """
    from rplearn.analysis.heading_options import YawOptions, check_turn
    from rplearn.analysis.radios import sensitivity_dbm
    from rplearn.workflows.planning import orient_link

    with flag_values():
        level = None if sensitivity is None else sensitivity_dbm(sensitivity)
        options = YawOptions(tx_yaw_deg=tx_yaw, rx_yaw_deg=rx_yaw, tx_power_dbm=tx_power_dbm, frequency_hz=frequency_hz,
                             caution_z=caution, sensitivity_dbm=level, min_availability=min_availability)
        ends = xyz(tx_pos, "--tx-pos"), xyz(rx_pos, "--rx-pos")
        check_turn(turn)
    result = orient_link(model_path, tx, rx, *ends, turn, options)
    say(result.summary())
