"""``rplearn live``: learn while the drones fly, with a live view in the terminal; ``rplearn
replay``: send a ``.tlog`` over UDP at a multiple of its pace (to try ``live`` on the ground)."""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import typer

from rplearn.cli._app import app, flag_values, geodetic_flag, reader_options, say, split_list, user_errors, with_flag
from rplearn.errors import BadValueError, InputError, RplearnError

#: What the reader's messages suggest that ``live`` has no flag for, and what to do from its command line instead.
_LIBRARY_ONLY = (
    (", or sort them on reading (allow_unsorted=True)",
     "; live reads the rows in the order they are appended: sync the finished file with --allow-unsorted"),
    ("(ReaderOptions.nodes={path: node}, or node= for one table)", "(live has no flag for it: write a node column)"),
    ("; or rx=, tx_power_dbm=, frequency_hz=)", ")"),
)


#: What live's notes (``sync``'s words on the fixed nodes) name that only ``sync`` has a flag for.
_SYNC_ONLY = (("ReaderOptions.station_heading_deg says where its antenna faced",
               "sync --station-heading (live has no flag for it) says where its antenna faced"),)


def _node_ids(values: list[str] | None, flag: str) -> list[str] | None:
    """The node ids of a repeatable, comma-separable flag (None when not given); given with none
    (``--nodes ,``) is refused, naming the flag, not read as not given."""
    ids = split_list(values)
    if values and ids is None:
        raise BadValueError(f"{flag}: no node id in {' '.join(repr(v) for v in values)}; name the nodes, e.g. {flag} D,G")
    return ids


def _summary_in_live_terms(text: str) -> str:
    """The session's summary with the library options its notes name as live's flags (``--station``), or, for one live
    has no flag for, as ``sync``'s."""
    for old, new in _SYNC_ONLY:
        text = text.replace(old, new)
    return "\n".join(with_flag(line, None, live) if "Options." in line else line for line in text.splitlines())


def _in_live_terms(exc: RplearnError) -> RplearnError:
    """The error with the library options live has no flag for replaced by what its command line can do."""
    text = str(exc)
    for old, new in _LIBRARY_ONLY:
        text = text.replace(old, new)
    if text == str(exc):
        return exc
    return type(exc)(text, param=None if exc.param in ("allow_unsorted", "nodes") else exc.param, related=exc.related)


def _view(status: Any) -> Any:
    """The live view of a :class:`rplearn.workflows.live.LiveStatus` (rich renderables)."""
    from rich.console import Group
    from rich.table import Table

    from rplearn.workflows.live_status import page_rows, ranking_text

    rows, node_rows = page_rows(status)
    numbers = Table(show_header=False, box=None, pad_edge=False)
    numbers.add_column(style="bold")
    numbers.add_column()
    for label, value in rows:
        numbers.add_row(label, value)
    nodes = Table(title="nodes")
    head, *body = node_rows
    for h in head:
        nodes.add_column(h)
    for r in body:
        nodes.add_row(*r)
    moves = Table(title="next-best manoeuvres", caption=ranking_text(status) or None)
    for h in ("manoeuvre", "duration", "spread after"):
        moves.add_column(h)
    for name, duration_s, spread_db in status.manoeuvres[:3]:
        moves.add_row(name, f"{duration_s:.0f} s", f"{spread_db:.2f} dB")
    if not status.manoeuvres:
        moves.add_row("-", "-", "-")
    return Group(numbers, nodes, moves)


@app.command()
@user_errors(flags={"ranking_every_s": "--advice-s", "receivers": "--receiver NODE", "fixed_nodes": "--fixed NODE", "html": "--html PATH",
                    "record": "--record PATH", "from_model": "--from-model", "nodes": "--nodes"})
def live(
    source: str = typer.Argument(..., help="A MAVLink connection as pymavlink names it (udpin:0.0.0.0:14550, tcp:HOST:PORT, a serial device "
                                           "such as /dev/ttyUSB0: what MAVProxy, QGroundControl and mavlink-router forward), or "
                                           "POSE.csv,SIGNAL.csv: a canonical pose and signal CSV a robot is appending to."),
    output: str = typer.Option(..., "-o", "--out", help="Model file (.json), rewritten atomically at every refit: an interrupted session "
                                                        "leaves the last good model."),
    model: str = typer.Option("sh", "--model", help="sh, bg or poly."),
    degree: str | None = typer.Option(None, "--order", help="Order, or 'auto' (default for sh): order and smoothing chosen by cross-validation "
                                                            "over the flight's 5 stretches of time."),
    refit_s: float = typer.Option(2.0, "--refit-s", help="Seconds between refits."),
    until_spread_db: float | None = typer.Option(None, "--until-spread", help="End when every node's pattern spread is below this [dB]: "
                                                                           "over its sphere (the directions never seen count with "
                                                                           "the fit's spread there), or see --spread-over."),
    spread_over: str = typer.Option("sphere", "--spread-over", help="What --until-spread is read over: sphere (default) or covered "
                                                                   "(only the directions seen; needs --until-coverage)."),
    until_coverage_pct: float | None = typer.Option(None, "--until-coverage", help="End when every node's covered share of the sphere "
                                                                               "reaches this [%] (with --until-spread: both)."),
    duration_s: float | None = typer.Option(None, "--duration", help="End after this many seconds."),
    idle_s: float = typer.Option(10.0, "--idle", help="The stream has ended when nothing arrived for this long [s] after its first (live waits for it)."),
    nodes: list[str] | None = typer.Option(None, "--nodes", help="Node ids (default: those of the first matched samples)."),
    tx_power_dbm: float | None = typer.Option(None, "--tx-power", help="MAVLink, or a signal CSV without tx_power_dbm: the radios' transmit power [dBm]."),
    frequency_hz: float | None = typer.Option(None, "--frequency", help="MAVLink, or a signal CSV without a frequency_hz column: the carrier frequency [Hz]."),
    station_geodetic: str | None = typer.Option(None, "--station", help="MAVLink: LAT,LON,ALT of the ground station [deg, deg, m AMSL]."),
    nan_policy: str = typer.Option("error", "--nan-policy", help="CSV: pose rows with NaN or non-numeric values, coordinates beyond "
                                                              "any place or on the wrong side of a position jump: error "
                                                              "(default) or drop (counted), as sync."),
    receiver: str | None = typer.Option(None, "--receiver", help="CSV: the receiving node of every row of a signal CSV without an rx column."),
    max_gap_s: float = typer.Option(0.2, "--max-gap", help="Drop samples inside pose gaps longer than this [s] (as sync)."),
    html: str | None = typer.Option(None, "--html", help="Also write a self-refreshing page with the numbers and the coverage and "
                                                         "spread maps."),
    record: str | None = typer.Option(None, "--record", help="MAVLink: keep the received stream as a .tlog (for sync and fit after)."),
    quiet: bool = typer.Option(False, "--quiet", help="No live view; print the summary at the end."),
    fixed: list[str] | None = typer.Option(None, "--fixed", help="Nodes that cannot move (a ground station), for the next-best "
                                                                 "manoeuvres; default for MAVLink: the station (gcs)."),
    advice_s: float = typer.Option(15.0, "--advice-s", help="Seconds at least between the starts of two rankings of the next-best "
                                                            "manoeuvres (0: after every refit once the last has finished; a ranking "
                                                            "takes seconds and runs beside the refits)."),
    no_advice: bool = typer.Option(False, "--no-advice", help="Do not rank the next-best manoeuvres."),
    from_model: str | None = typer.Option(None, "--from-model", help="An earlier flight's model file of the same drones (rplearn fit "
                                                                     "--order auto; e.g. before a payload change): the next-best "
                                                                     "manoeuvres are ranked with its noise, smoothing and drift until "
                                                                     "the session has learned as many samples as it did. The "
                                                                     "session's model is learned as without it."),
) -> None:
    """Learn the patterns while the drones fly: match, predict each new batch before learning it
    (the prequential error), refit every --refit-s and show coverage, spread and plausibility.

    Example: rplearn live udpin:0.0.0.0:14550 --tx-power 20 --frequency 433e6 --until-spread 2 -o model.json
    """
    from rplearn.cli.learning import degree_option
    from rplearn.data.sync import SyncOptions
    from rplearn.models.options import FitOptions
    from rplearn.models.spec import ModelSpec
    from rplearn.workflows.live import LiveOptions, run_live
    from rplearn.workflows.live_advice import live_advisor
    from rplearn.workflows.live_checks import check_live_outputs, check_live_source

    with flag_values():  # a flag's value that is none of its words or not of its form: a usage error (exit 2)
        auto, order = degree_option(degree, model)
        spec = ModelSpec.parse(model, order=order)
        csv_source = "," in source and all(p.lower().endswith(".csv") for p in source.split(","))
        if receiver is not None and not csv_source:
            raise InputError(f"--receiver: names the receiver of a signal CSV's rows; {source} is a MAVLink stream, "
                             "whose radio reports name both ends")
        receivers = [f"{source.split(',')[-1]}={receiver}"] if receiver is not None else None
        reader = reader_options(receiver=receivers, tx_power_dbm=tx_power_dbm, frequency_hz=frequency_hz,
                                nan_policy=nan_policy, station_geodetic=geodetic_flag(station_geodetic, "--station"))
        named_fixed = tuple(_node_ids(fixed, "--fixed") or ())  # the user's: a note when no row names one (not the default station)
        listed = _node_ids(nodes, "--nodes") or []
        outside = [n for n in named_fixed if listed and n not in listed]
        if outside:
            raise InputError(f"--fixed: {', '.join(outside)} is not among --nodes ({', '.join(listed)}), the "
                             "nodes learned: a node held still must be learned too")
        still = named_fixed or (() if csv_source else (reader.station,))
        if no_advice and from_model is not None:
            raise InputError("--from-model: gives the ranking of the next-best manoeuvres its noise, smoothing and drift; "
                             "drop --no-advice")
        options = LiveOptions(spec=spec, fit=FitOptions(auto=auto), reader=reader, sync=SyncOptions(max_gap_s=max_gap_s),
                              refit_s=refit_s, duration_s=duration_s, until_spread_db=until_spread_db, spread_over=spread_over,
                              until_coverage_pct=until_coverage_pct, idle_s=idle_s, nodes=tuple(listed) or None,
                              ranking_every_s=advice_s, fixed_nodes=named_fixed)  # its values checked before the advisor's
    check_live_source(source)
    check_live_outputs(source, output, record, html, from_model)  # before --from-model is read and said
    advisor = None if no_advice else live_advisor(still, 0.0, until_spread_db, from_model, spec, listed or None,
                                                  None if csv_source else frequency_hz)  # paced by ranking_every_s
    if advisor is not None and advisor.earlier is not None:
        say(advisor.earlier.text())
    options = replace(options, manoeuvres=advisor)
    try:
        if quiet:
            outcome = run_live(source, output, options, None, record, html)
        else:
            from rich.live import Live

            from rplearn.cli._app import console

            with Live(console=console, refresh_per_second=4, transient=False) as view:
                outcome = run_live(source, output, options, lambda s: view.update(_view(s)), record, html)
    except RplearnError as exc:
        raise _in_live_terms(exc) from None
    say(_summary_in_live_terms(outcome.status.summary()))
    say(f"wrote {output}")


@app.command()
@user_errors
def replay(
    log: str = typer.Argument(..., help="A MAVLink .tlog."),
    address: str = typer.Option("127.0.0.1:14550", "--to", help="HOST:PORT to send the messages to (UDP)."),
    speed: float = typer.Option(1.0, "--speed", help="Times the log's pace (its boot times and speeds scaled alike)."),
) -> None:
    """Send a .tlog's messages over UDP at --speed times their pace, as a vehicle would: to try
    `rplearn live udpin:...` on the ground.

    Example: rplearn replay flight.tlog --to 127.0.0.1:14550 --speed 20
    """
    from rplearn.io.live_sources import replay_tlog, udp_target

    with flag_values():
        udp_target(address)
    say(f"sent {replay_tlog(log, address, speed)} messages to {address}")
