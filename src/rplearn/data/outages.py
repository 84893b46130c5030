"""Outage events through pose-signal matching: rows of a signal log that say the link was lost.

A log that marks a lost link (a MAVLink ground station's zero RSSI while the vehicle is
silent, :mod:`rplearn.io.mavlink`) gives signal rows with ``outage`` True and ``rssi_dbm``
NaN: no packet arrived. :func:`rplearn.data.sync.synchronise` matches them apart from the
received packets (which it matches, drops and counts as before, so that a log reads the same
with or without its outages) and keeps them in the matched dataset as outage events, the
poses of both ends interpolated at their times as for any sample, with two differences:

- while the link is lost the vehicle is silent too, so its poses have a gap over the
  outage: an outage event is matched across a pose gap up to :data:`OUTAGE_MAX_GAP_S` (its
  position linear, its attitude slerped across the silence: the heading is uncertain there);
- an outage event after the vehicle's last pose or before its first (a vehicle switched off
  after landing: its radio stops, which the station logs as a lost link) has no pose and is
  dropped as ``out_of_span``, and counted.

The counts per reason (:data:`OUTAGE_REASONS`) go into ``SyncSummary.outages``: ``in``,
``kept`` and every drop.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
import pandas as pd

from rplearn._argtypes import check_types
from rplearn.core.link import FAR_FIELD_WAVELENGTHS, SPEED_OF_LIGHT_M_S
from rplearn.data.poses import STATUS_OUT_OF_SPAN, STATUS_POSE_GAP, PoseTrack, interpolate_nodes
from rplearn.data.readings import duplicate_rows
from rplearn.data.tables import MATCHED_COLUMNS, OUTAGE_COLUMN, node_ids, outage_mask

#: Longest pose gap an outage event is matched across [s] (the vehicle is silent while the link is lost).
OUTAGE_MAX_GAP_S: float = 30.0
#: Why an outage event is not kept, in the order tested.
OUTAGE_REASONS: tuple[str, ...] = ("duplicate", "invalid_value", "outside_window", "tx_equals_rx", "other_link", "unknown_node",
                                   "out_of_span", "pose_gap", "near_field", "disarmed", "on_ground")


@check_types
def split_outages(signal: pd.DataFrame, source: str = "signal log") -> tuple[pd.DataFrame, pd.DataFrame]:
    """The received packets and the outage events of a signal log (``outage`` True), in their order.

    A log without the column gives all its rows and an empty frame.
    """
    down = outage_mask(signal, source)
    if not down.any():
        return signal, signal.iloc[:0]
    return signal[~down], signal[down]


def _times(signal: pd.DataFrame, rx: np.ndarray, offset_s: float | Mapping[str, float]) -> np.ndarray:
    t = pd.to_numeric(signal["t"], errors="coerce").to_numpy(np.float64)
    if isinstance(offset_s, Mapping):
        return t + np.array([float(offset_s.get(r, 0.0)) for r in rx], np.float64)
    return t + float(offset_s)


@check_types
def match_outages(tracks: Mapping[str, PoseTrack], events: pd.DataFrame, options: Any,
                  window: Any = None, phases: Any = None) -> tuple[pd.DataFrame, dict[str, int]]:
    """Match outage events with the poses of both ends (module docstring).

    Parameters
    ----------
    tracks : mapping of node id to PoseTrack
        The pose tracks :func:`~rplearn.data.sync.synchronise` built (clock offsets applied).
    events : DataFrame
        Signal rows with ``outage`` True (:func:`split_outages`).
    options : SyncOptions
        The sync's options: its signal clock offset, link, ``max_gap_s`` (raised to
        :data:`OUTAGE_MAX_GAP_S` here) and window.
    window : callable, optional
        ``window(t)`` -> mask of the times inside the sync's time window (None: no window).
    phases : FlightPhases, optional
        The pose log's flight phases: with ``options.airborne``, events with a vehicle end
        disarmed or on the ground are dropped (``disarmed``, ``on_ground``) as packets are.

    Returns
    -------
    matched : DataFrame
        The kept events in :data:`~rplearn.data.tables.MATCHED_COLUMNS` order (``rssi_dbm``
        NaN), then the other signal columns, ``outage`` True.
    counts : dict of str to int
        ``in``, ``kept`` and the events dropped per reason of :data:`OUTAGE_REASONS`.
    """
    counts = {"in": int(len(events)), "kept": 0, **{r: 0 for r in OUTAGE_REASONS}}
    tx, rx = node_ids(events["tx"]), node_ids(events["rx"])
    t = _times(events, rx, options.signal_clock_offset_s)
    freq = pd.to_numeric(events["frequency_hz"], errors="coerce").to_numpy(np.float64)
    ptx = pd.to_numeric(events["tx_power_dbm"], errors="coerce").to_numpy(np.float64)
    keep = np.ones(len(events), bool)

    def drop(mask: np.ndarray, reason: str) -> None:
        hit = mask & keep
        counts[reason] += int(hit.sum())
        keep[hit] = False

    drop(duplicate_rows(events), "duplicate")  # as sync drops a packet's copies (a log in the file twice)
    drop(~(np.isfinite(t) & np.isfinite(freq) & (freq > 0) & np.isfinite(ptx)) | (tx == "") | (rx == ""),
         "invalid_value")
    if window is not None:
        drop(~window(t), "outside_window")
    drop(tx == rx, "tx_equals_rx")
    if options.link is not None:
        drop(~((tx == options.link[0]) & (rx == options.link[1])), "other_link")
    drop(~(np.isin(tx, list(tracks)) & np.isin(rx, list(tracks))), "unknown_node")
    ids = sorted(tracks)
    gap = max(float(options.max_gap_s), OUTAGE_MAX_GAP_S)
    poses = {end: interpolate_nodes(tracks, ids, np.searchsorted(ids, np.where(keep, ids_, ids[0])), t, gap, keep)
             for end, ids_ in (("tx", tx), ("rx", rx))}
    st = (poses["tx"][2], poses["rx"][2])
    drop((st[0] == STATUS_OUT_OF_SPAN) | (st[1] == STATUS_OUT_OF_SPAN), "out_of_span")
    drop((st[0] == STATUS_POSE_GAP) | (st[1] == STATUS_POSE_GAP), "pose_gap")
    with np.errstate(invalid="ignore"):
        distance = np.linalg.norm(poses["tx"][0] - poses["rx"][0], axis=1)
        drop(~(distance > FAR_FIELD_WAVELENGTHS * SPEED_OF_LIGHT_M_S / np.where(keep, freq, 1.0)), "near_field")
    if options.airborne and phases is not None:
        for end, ids_ in (("tx", tx), ("rx", rx)):
            code = np.searchsorted(ids, np.where(keep, ids_, ids[0]))
            disarmed, ground = phases.masks(ids, code, t, poses[end][0][:, 2], keep)
            drop(disarmed, "disarmed")
            drop(ground, "on_ground")
    idx = np.flatnonzero(keep)
    counts["kept"] = int(idx.size)
    cols: dict[str, Any] = {"t": t[idx], "tx": tx[idx].astype(str), "rx": rx[idx].astype(str),
                            "rssi_dbm": np.full(idx.size, np.nan), "tx_power_dbm": ptx[idx], "frequency_hz": freq[idx]}
    for end in ("tx", "rx"):
        pos, quat, _ = poses[end]
        cols.update({f"{end}_{f}": pos[idx, j] for j, f in enumerate(("x", "y", "z"))})
        cols.update({f"{end}_{f}": quat[idx, j] for j, f in enumerate(("qw", "qx", "qy", "qz"))})
    out = pd.DataFrame(cols, columns=list(MATCHED_COLUMNS))
    for c in [c for c in events.columns if c not in MATCHED_COLUMNS]:
        out[c] = pd.Series(events[c].array[idx], index=out.index)
    out[OUTAGE_COLUMN] = True
    return out, counts


@check_types
def with_outages(dataset: pd.DataFrame, events: pd.DataFrame) -> pd.DataFrame:
    """A matched dataset and its matched outage events in one frame, sorted by time (stable),
    with ``outage`` False on the received packets."""
    if not len(events) and OUTAGE_COLUMN not in dataset.columns:
        out = dataset.copy()
        out[OUTAGE_COLUMN] = np.zeros(len(out), bool)
        return out
    up = dataset.assign(**{OUTAGE_COLUMN: np.zeros(len(dataset), bool)}) if OUTAGE_COLUMN not in dataset else dataset
    both = pd.concat([up, events.reindex(columns=up.columns.union(events.columns, sort=False))], ignore_index=True)
    both[OUTAGE_COLUMN] = both[OUTAGE_COLUMN].astype(bool)
    return both.sort_values("t", kind="stable").reset_index(drop=True)


@check_types
def outage_text(counts: Mapping[str, int]) -> str:
    """One line of a sync summary about the outage events (empty without any)."""
    if not counts or not counts.get("in"):
        return ""
    dropped = ", ".join(f"{r} {counts[r]:,}" for r in OUTAGE_REASONS if counts.get(r))
    return (f"outage events (link lost, no RSSI): {counts['in']:,} in, {counts.get('kept', 0):,} kept in the dataset "
            f"(column {OUTAGE_COLUMN})" + (f", dropped: {dropped}" if dropped else ""))


__all__ = ["OUTAGE_MAX_GAP_S", "OUTAGE_REASONS", "match_outages", "outage_text", "split_outages", "with_outages"]
