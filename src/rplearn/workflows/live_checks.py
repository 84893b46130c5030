"""The checks of a live session (``rplearn live``, :mod:`rplearn.workflows.live`): its options and
outputs before any work, the fixed nodes it was told of that no row names, and why a session
that ended without a model has none.
"""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from typing import Any

from rplearn._argtypes import check_types
from rplearn.errors import BadValueError, InputError
from rplearn.io.files import check_output_kind
from rplearn.io.partitions import file_identity
from rplearn.io.resolve import check_outputs, distinct_inputs

#: What ``until_spread_db`` is read over (:attr:`rplearn.workflows.live.LiveOptions.spread_over`).
SPREAD_OVER = ("sphere", "covered")


@check_types
def is_csv_source(source: str) -> bool:
    """Whether ``source`` names a pose and a signal CSV (``POSE.csv,SIGNAL.csv``), not a MAVLink connection."""
    return "," in source and all(p.lower().endswith(".csv") for p in source.split(","))


def source_pose_metadata(source: str, station: str) -> dict[str, Any]:
    """What :func:`rplearn.workflows.logs.fixed_node_advice` reads of a live source's pose logs, as
    :func:`rplearn.io.read_logs` says it of the same files: a pose table (the CSV source's first file), or a MAVLink
    stream holding the ground station ``station``."""
    if is_csv_source(source):
        return {"files": [{"source": source.split(",")[0], "format": "csv", "kind": "pose"}]}
    return {"files": [{"source": source, "format": "tlog", "kind": "pose+signal", "station": station}]}


def check_live_options(options: Any) -> None:
    """Refuse :class:`rplearn.workflows.live.LiveOptions` whose values contradict (one line naming the field)."""
    o = options
    if not (math.isfinite(o.ranking_every_s) and o.ranking_every_s >= 0):
        raise InputError(f"ranking_every_s: expected a non-negative number of seconds, got {o.ranking_every_s}",
                         param="ranking_every_s")
    for name in ("refit_s", "idle_s", "duration_s", "until_spread_db"):
        v = getattr(o, name)
        if v is not None and not (math.isfinite(v) and v > 0):
            raise InputError(f"{name}: expected a positive number of {'dB' if 'db' in name else 'seconds'}, got {v}",
                             param=name)
    if o.spread_over not in SPREAD_OVER:
        raise BadValueError(f"spread_over: expected {' or '.join(SPREAD_OVER)}, got {o.spread_over!r}", param="spread_over")
    if o.spread_over == "covered" and o.until_spread_db is not None and o.until_coverage_pct is None:
        raise InputError("a spread target over the covered directions needs a coverage target too: that spread is small "
                         "from the first seconds, while they are a few percent of the sphere (or read it over the "
                         "sphere: spread_over='sphere')", param="until_coverage_pct")
    if o.until_coverage_pct is not None and not 0 < o.until_coverage_pct <= 100:
        raise InputError(f"until_coverage_pct: expected a percentage in (0, 100], got {o.until_coverage_pct}",
                         param="until_coverage_pct")
    for name in ("nodes", "fixed_nodes"):
        ids = getattr(o, name) or ()
        if name == "nodes" and o.nodes is not None and not ids:
            raise InputError("nodes: no node id given (None: the nodes of the first matched samples)", param=name)
        blank = [n for n in ids if not n.strip()]
        twice = sorted({n for n in ids if ids.count(n) > 1})
        if blank or twice:
            raise InputError(f"{name}: " + (f"an empty node id in {list(ids)}" if blank else f"{', '.join(twice)} is named "
                             "twice") + "; name each node once", param=name)
    missing = [n for n in o.fixed_nodes if o.nodes is not None and n not in o.nodes]
    if missing:
        raise InputError(f"fixed_nodes: {', '.join(missing)} is not among nodes ({', '.join(o.nodes)}), those "
                         "learned: a node held still must be learned too", param="fixed_nodes", related=("nodes",))


@check_types
def check_live_source(source: str) -> None:
    """Refuse a source that names CSV files but is not two distinct ones, ``POSE.csv,SIGNAL.csv`` (three files, one
    alone, the same file twice: the first read as the second's pose table, or as a MAVLink connection)."""
    parts = source.split(",")
    tables = [p for p in parts if p.lower().endswith((".csv", ".parquet", ".pq"))]
    if tables and (len(parts) != 2 or not is_csv_source(source)):
        parquet = any(not p.lower().endswith(".csv") for p in tables)
        raise InputError(f"{source}: a CSV source is two files, POSE.csv,SIGNAL.csv (canonical pose and signal CSVs being "
                         f"appended to), given {len(parts)}" + ("; Parquet files are not appended to: sync them" if parquet else ""),
                         param="source")
    if tables:
        distinct_inputs(parts, param="source")


@check_types
def check_live_outputs(source: str, output: str, record: str | None, html: str | None, from_model: str | None = None) -> None:
    """Refuse, before any work, an output that is an input (a CSV source's files, a ``.tlog`` read as a connection,
    ``from_model``: an earlier flight's model file, which the session's refits would overwrite) or another output (the
    model, the page, the recording: each its own file), or whose name says another kind."""
    inputs = source.split(",") if is_csv_source(source) else [source] if os.path.exists(source) else []
    earlier = file_identity(from_model) if from_model else None
    for name, path in (("output", output), ("html", html), ("record", record)):
        if path and earlier is not None and file_identity(path) == earlier:
            raise InputError(f"{name}: {path} is also given as from_model, the earlier flight's model the ranking reads: "
                             "the session would overwrite it; write to another file", param=name, related=("from_model",))
    check_outputs({"output": output, "html": html, "record": record}, inputs)
    check_output_kind(output, "model")
    if html is not None:
        check_output_kind(html, "html", "html")
    if record is not None and is_csv_source(source):  # it was ignored: nothing written, nothing said
        raise InputError(f"record: {record}: a CSV source is recorded already (its two files); --record keeps a "
                         "MAVLink stream as a .tlog", param="record")


@check_types
def fixed_nodes_note(fixed_nodes: Sequence[str], nodes: Sequence[str]) -> str | None:
    """The note (after ``--fixed ``) for the nodes named as unable to move that the session does not learn (a typo,
    a station under another id): the manoeuvres are ranked with them absent; None when every one is learned."""
    missing = [n for n in fixed_nodes if n not in nodes]
    if not missing:
        return None
    return (f"{', '.join(missing)}: no matched row names it (the session's nodes: {', '.join(nodes)}); "
            "the manoeuvres are ranked as if no node named there were held still")


@check_types
def no_model_message(source: str, status: Any, messages: int | None, waited_s: float) -> str:
    """Why a session ended without a model, in one line: nothing received (``messages``: MAVLink messages received
    in all, None for a CSV source), no row matched, or too few learned (the last refit's refusal)."""
    s = status
    if messages == 0 and os.path.isfile(source):
        return f"{source}: no MAVLink message in it (a .tlog, as MAVProxy or QGroundControl record it?)"
    if messages == 0:
        return (f"{source}: no MAVLink message received from it in {waited_s:.0f} s: is the vehicle or the forwarder "
                "sending to this address and port, and is the link up?")
    never = [p for p in source.split(",") if is_csv_source(source) and not os.path.exists(p)]
    if never:
        return (f"{', '.join(never)}: no such file: the session waited for it to appear and ended "
                f"({s.stopped or 'stopped'}) with no model")
    if s.received == 0:
        radio = "" if messages is None else (f": {messages} MAVLink messages, none of them a radio report with both ends "
                                             "placed (RADIO_STATUS or RADIO, with the vehicle's position)")
        return f"{source}: the session ended ({s.stopped or 'stopped'}) before any signal row was received{radio}; no model"
    drops = ", ".join(f"{n} {r}" + (f" ({s.dropped_where[r]})" if s.dropped_where.get(r) else "") for r, n in s.dropped.items() if n)
    why = [n[len("waiting: "):] for n in s.notes if n.startswith("waiting: ")] or [n for n in s.notes if "too few" in n]
    return (f"{source}: the session ended ({s.stopped or 'stopped'}) before a model could be learned: {s.received} signal "
            f"rows received, {s.matched} matched, {s.learned} learned" + (f" (dropped: {drops})" if drops else "")
            + (f"; {why[-1]}" if why else ""))


__all__ = ["SPREAD_OVER", "check_live_options", "check_live_outputs", "check_live_source", "fixed_nodes_note", "is_csv_source",
           "no_model_message", "source_pose_metadata"]
