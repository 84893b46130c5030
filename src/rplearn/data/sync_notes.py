"""What a sync's summary says beside its counts (:mod:`rplearn.data.sync`): the nodes it takes as fixed, and the
question it asks when many samples' received power is out of range.

A node whose pose log has a single row, or only identical rows (:class:`~rplearn.data.poses.PoseTrack`: ``static``,
``still``), is taken to hold still: its one pose at every time (one row) or over its log's span, with no pose gap
between its rows (identical rows). That is right for a ground station, or a drone parked through the log; a node that
moved but was logged so would be learned at a place and an attitude it did not have. The summary names these nodes
(``SyncSummary.fixed_nodes``) and says what was taken; where they came from, and so what advice fits, is known to the
caller that read the logs (:func:`rplearn.workflows.logs.sync_logs`).
"""

from __future__ import annotations

from collections.abc import Mapping

from rplearn._argtypes import check_types
from rplearn.data.poses import PoseTrack

#: Share of the samples reaching the RSSI range test dropped as ``implausible_rssi`` from which
#: the summary asks whether the received power is uncalibrated.
IMPLAUSIBLE_ADVICE_SHARE = 0.25


@check_types
def fixed_nodes(tracks: Mapping[str, PoseTrack]) -> list[str]:
    """The nodes taken as holding still, sorted: a pose log of one row, or of identical rows."""
    return sorted(str(n) for n, tr in tracks.items() if tr.static or tr.still)


#: How the summary's line naming the fixed nodes (:func:`fixed_note`) begins.
FIXED_NOTE_START = "fixed node(s)"


@check_types
def fixed_note(tracks: Mapping[str, PoseTrack], nodes: list[str]) -> str | None:
    """The summary's line naming the fixed ``nodes`` of ``tracks`` and what was taken for each; None without any."""
    if not nodes:
        return None
    said = []
    for node in nodes:
        tr = tracks[node]
        said.append(f"{node} at every time (one pose row)" if tr.static else
                    f"{node} from t = {tr.t_s[0]:.3f} to {tr.t_s[-1]:.3f} s (identical pose rows, no pose gap between "
                    "them)")
    return (f"{FIXED_NOTE_START} (a pose log of one row, or of identical rows, is a node holding still at that pose): "
            f"{'; '.join(said)}")


@check_types
def implausible_note(n_out: int, dropped: Mapping[str, int], drop_reasons: tuple[str, ...], rssi_scale: str,
                     plausible_dbm: tuple[float, float]) -> str | None:
    """The question a summary asks when many samples' RSSI is out of range or above the transmit
    power: a radio's own units or a constant offset (uncalibrated), which ``rssi_scale="relative"`` reads."""
    later = drop_reasons[drop_reasons.index("implausible_rssi"):]
    reached = n_out + sum(dropped.get(r, 0) for r in later)
    share = dropped["implausible_rssi"] / max(reached, 1)
    if rssi_scale != "dbm" or not dropped["implausible_rssi"] or share < IMPLAUSIBLE_ADVICE_SHARE:
        return None
    return (f"{100 * share:.0f}% of the samples have an RSSI outside {plausible_dbm[0]:g} to "
            f"{plausible_dbm[1]:g} dBm or above the transmit power (implausible_rssi): a radio reporting its own "
            "units or with a constant offset (uncalibrated power)? SyncOptions.rssi_scale='relative' learns from it as "
            "relative power")


__all__ = ["FIXED_NOTE_START", "IMPLAUSIBLE_ADVICE_SHARE", "fixed_nodes", "fixed_note", "implausible_note"]
