"""Time order of the rows of canonical tables: a pose table's times within each node, a signal
table's within each link (a logger that rebooted restarts its clock), across the chunks of one
file (:class:`LinkTimes`). Split from :mod:`rplearn.io.tables`."""

from __future__ import annotations

import numpy as np
import pandas as pd

from rplearn.errors import LogFormatError


def check_time_order(t: np.ndarray, nodes: np.ndarray, source: str, rows: np.ndarray | None = None) -> None:
    """Raise :class:`LogFormatError` at the first row whose time [s] goes back within its node; ``rows``: the file
    rows of ``t``'s rows (some dropped before), for the message (by default their positions)."""
    order_ok = np.ones(len(t), bool)
    same_node = nodes[1:] == nodes[:-1]
    order_ok[1:] = ~(same_node & (t[1:] < t[:-1]))
    if not order_ok.all():
        r = int(np.flatnonzero(~order_ok)[0])
        raise LogFormatError(
            f"{source}: field t goes backwards at row {r if rows is None else int(rows[r])} (node {nodes[r]}: "
            f"{float(t[r - 1])!r} -> "
            f"{float(t[r])!r}); expected increasing times, or sort them on reading "
            "(allow_unsorted=True)",
            param="allow_unsorted",
        )


class LinkTimes:
    """What :func:`check_link_time_order` carries from chunk to chunk of one file: each link's
    last time and the hashes of the rows seen (8 bytes a row, each chunk's sorted once), so that
    a row repeating an earlier one is known for a copy wherever it stands."""

    def __init__(self) -> None:
        self.last_t: dict[tuple[str, str], float] = {}
        self.seen: list[np.ndarray] = []

    def seen_before(self, hashes: np.ndarray) -> np.ndarray:
        """Which of ``hashes`` an earlier chunk held."""
        out = np.zeros(hashes.size, bool)
        for block in self.seen:
            at = np.clip(np.searchsorted(block, hashes), 0, block.size - 1)
            out |= block[at] == hashes
        return out


def _steps_back(t: np.ndarray, codes: np.ndarray, n_links: int, last: np.ndarray) -> np.ndarray:
    """Rows whose time is below the previous kept time of their link (``last``: each link's time
    before the first row), among the rows with a finite time and a link code >= 0."""
    back = np.zeros(t.size, bool)
    for k in range(n_links):
        rows = np.flatnonzero(codes == k)
        if rows.size:
            before = np.concatenate([[last[k]], t[rows[:-1]]])
            back[rows] = t[rows] < before
    return back


def check_link_time_order(signal: pd.DataFrame, source: str, first_row: int = 0, state: LinkTimes | None = None) -> None:
    """Raise :class:`LogFormatError` at the first row of a canonical signal table whose time [s]
    goes back within its link (``tx -> rx``), in file order: a logger that rebooted restarts its
    clock, and its later rows, sorted by time, would be matched with poses of another moment. A
    row equal in every column to an earlier one (a doubled record, a block or a whole log written
    twice) is not a step back: ``sync`` drops and counts it as a duplicate. Rows are compared
    with earlier chunks only where a step back is seen (a sorted log costs one hash a row).

    Parameters
    ----------
    signal : DataFrame
        Canonical signal rows (:func:`canonical_signal`) in file order; rows without a finite
        time are skipped (``sync`` drops and counts them).
    source : str
        The file, for the message.
    first_row : int
        The file row of ``signal``'s first row (a chunk of a file read in chunks).
    state : LinkTimes, optional
        Carried from chunk to chunk of one file (updated here).
    """
    from rplearn.data.streaming import row_hashes

    state = LinkTimes() if state is None else state
    t = signal["t"].to_numpy(np.float64)
    hashes = row_hashes(signal)
    codes, links = pd.factorize(signal["tx"].astype(str) + "\x00" + signal["rx"].astype(str))
    keys = [(tx, rx) for tx, _, rx in (str(link).partition("\x00") for link in links)]
    last = np.array([state.last_t.get(key, -np.inf) for key in keys])
    kept = np.isfinite(t) & ~pd.Series(hashes).duplicated().to_numpy()
    codes = np.where(kept, codes, -1)
    back = _steps_back(t, codes, len(keys), last)
    if back.any():  # copies of an earlier chunk's rows are no step back either
        copies = np.flatnonzero(kept)[state.seen_before(hashes[kept])]
        if copies.size:
            codes[copies] = -1
            back = _steps_back(t, codes, len(keys), last)
    if back.any():
        r = int(np.flatnonzero(back)[0])
        k = int(codes[r])
        earlier = np.flatnonzero(codes[:r] == k)
        previous = float(t[earlier[-1]]) if earlier.size else float(last[k])
        raise LogFormatError(
            f"{source}: field t goes backwards at row {first_row + r} (link {keys[k][0]} -> {keys[k][1]}: "
            f"{previous!r} -> {float(t[r])!r}; a logger that rebooted restarts its clock); expected increasing times "
            "within each link: give each boot's rows as a file of its own on one clock, or sort them on reading "
            "(allow_unsorted=True)",
            param="allow_unsorted",
        )
    state.seen.append(np.sort(hashes))
    for k, key in enumerate(keys):
        rows = np.flatnonzero(codes == k)
        if rows.size:
            state.last_t[key] = float(t[rows[-1]])


__all__ = ["LinkTimes", "check_link_time_order", "check_time_order"]
