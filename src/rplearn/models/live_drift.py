"""The time-block sums of a live session's drifting error, in memory that does not grow with the flight.

An automatic fit states the error drifting over seconds (``training.drift_std_db``,
:func:`rplearn.models.auto_spread.drift_std_db`) from each flight unit's sums per 5-s time block
and link (:func:`rplearn.core.lsq.block_sums.time_block_sums`). The moments estimator
(:func:`rplearn.core.lsq.block_sums.correlated_ratio`) reads those per-block vectors ``v_b``
(the block's features summed, at SH-10: :func:`~rplearn.models.auto_spread.planning_basis`),
``s_b`` (its observations summed) and ``n_b`` (its samples) only through the sums over blocks
``sum v_b v_b^T``, ``sum n_b v_b v_b^T``, ``sum s_b v_b``, ``sum s_b^2``, ``sum n_b`` and ``sum n_b^2``
(:class:`~rplearn.core.lsq.block_sums.BlockSums`): a quadratic form in each block's sums. So a
block whose rows have all come can be folded into those sums and forgotten.

:class:`DriftBlocks` keeps the blocks of the last :data:`MAX_OPEN_BLOCKS` labels open (each
directed link's sums per block, labelled as the offline fit labels them,
:func:`~rplearn.core.lsq.block_sums.time_block_labels`, so a block's rows from several batches
add up to one block, in any order) and folds the oldest beyond that: its memory is bounded,
whatever the flight's length (2 square matrices of the nodes times SH-10's 100 coefficients,
plus at most :data:`MAX_OPEN_BLOCKS` vectors per directed link; 2 nodes: 0.7 MB). A live
matcher drops rows more than :data:`~rplearn.data.live_sync.DUPLICATE_MEMORY_S` (plus the
nodes' poses kept) late, far less than 64 blocks; a row that still comes for a block already
folded starts a block of its own (counted, :attr:`DriftBlocks.late_rows`: the offline fit would
count the two parts as one block).

The offline fit sums each unit's blocks apart: a block across the cut between two stretches of
time (the units of a flight learned whole, :class:`rplearn.data.units.Stretches`) is two blocks.
The cuts move as samples come, so a refit during the flight reads every block whole;
:meth:`DriftBlocks.split` makes the blocks the cuts fall in into the offline fit's parts (the
last, exact refit: their rows re-read from the spool), subtracting the whole block's terms and
adding its parts', so that the last refit's drift is the offline fit's (to rounding).
"""

from __future__ import annotations

import copy
from collections.abc import Mapping
from typing import Any

import numpy as np
from numpy.typing import NDArray

from rplearn._argtypes import check_types
from rplearn.core.lsq.block_sums import BlockSums, time_block_labels
from rplearn.core.lsq.penalty import nested_columns
from rplearn.models.auto_spread import planning_basis

FloatArray = NDArray[np.float64]

#: Time blocks (labels) whose sums are kept open at most; the oldest are folded first. 64
#: blocks of 5 s: 320 s, several times how late a live matcher still matches a row.
MAX_OPEN_BLOCKS = 64
#: Samples whose features are computed at once (a whole log matched at the end: bounded memory).
CHUNK_SAMPLES = 8192

#: Each directed link's sums in one block: ``[sum f_tx (q), sum f_rx (q), sum y, count]``.
LinkSums = dict[tuple[int, int], FloatArray]


def block_link_sums(basis: Any, labels: NDArray[np.int64], tx: NDArray[Any], rx: NDArray[Any],
                    directions: Any, y: FloatArray) -> dict[int, LinkSums]:
    """Each time block's and directed link's sums ``[sum f_tx, sum f_rx, sum y, count]`` of the
    features of ``basis`` (natural order), computed :data:`CHUNK_SAMPLES` samples at a time.

    Parameters
    ----------
    basis : Basis
        The basis the sums are kept in (the planning basis).
    labels : ndarray of int
        Each sample's time block (:func:`~rplearn.core.lsq.block_sums.time_block_labels`).
    tx, rx : ndarray of int
        Each sample's transmitter and receiver (node indices).
    directions : Directions
        The samples' directions at both ends [rad].
    y : ndarray
        The samples' observations (the regression's joint gains [dB]).
    """
    out: dict[int, LinkSums] = {}
    n_nodes = int(max(tx.max(initial=0), rx.max(initial=0))) + 1
    for a in range(0, labels.size, CHUNK_SAMPLES):
        sl = slice(a, a + CHUNK_SAMPLES)
        lab, t, r = labels[sl], np.asarray(tx[sl], np.int64), np.asarray(rx[sl], np.int64)
        key = (lab - lab.min()) * (n_nodes * n_nodes) + t * n_nodes + r
        order = np.argsort(key, kind="stable")
        k = key[order]
        starts = np.flatnonzero(np.r_[True, k[1:] != k[:-1]])
        at = np.asarray(a + order, np.intp)
        f_tx = np.add.reduceat(basis.design_t(directions.az_tx[at], directions.el_tx[at]), starts, axis=1)
        f_rx = np.add.reduceat(basis.design_t(directions.az_rx[at], directions.el_rx[at]), starts, axis=1)
        sum_y = np.add.reduceat(np.asarray(y, np.float64)[at], starts)
        count = np.diff(np.r_[starts, order.size]).astype(np.float64)
        for g, first in enumerate(starts):
            i = order[first]
            link = (int(t[i]), int(r[i]))
            vec = np.concatenate([f_tx[:, g], f_rx[:, g], [sum_y[g], count[g]]])
            sums = out.setdefault(int(lab[i]), {})
            sums[link] = vec if link not in sums else sums[link] + vec
    return out


def pair_vectors(links: LinkSums, n_nodes: int, q: int) -> FloatArray:
    """One block's vectors ``[v over every node's q columns, s, n]``, one row per link (both
    directions of a pair in one, as :func:`~rplearn.core.lsq.block_sums.time_block_sums` adds them)."""
    pairs: dict[tuple[int, int], FloatArray] = {}
    for (t, r), sums in links.items():
        vec = pairs.setdefault((min(t, r), max(t, r)), np.zeros(n_nodes * q + 2))
        vec[t * q:(t + 1) * q] += sums[:q]
        vec[r * q:(r + 1) * q] += sums[q:2 * q]
        vec[-2:] += sums[2 * q:]
    return np.array([pairs[k] for k in sorted(pairs)]).reshape(len(pairs), n_nodes * q + 2)


def _pairs(links: LinkSums) -> set[tuple[int, int]]:
    """The links (both directions one) with samples in one block's sums."""
    return {(min(t, r), max(t, r)) for (t, r), sums in links.items() if sums[-1] > 0}


def add_links(into: dict[int, LinkSums], more: Mapping[int, LinkSums]) -> None:
    """Add the block sums ``more`` into ``into`` (by label and directed link)."""
    for label, links in more.items():
        kept = into.setdefault(label, {})
        for link, vec in links.items():
            kept[link] = vec if link not in kept else kept[link] + vec


@check_types
class DriftBlocks:
    """A live session's time-block sums of the drifting error (module docstring).

    Parameters
    ----------
    basis : Basis
        The statistics' basis (the accumulation order); the sums are kept at its planning
        basis (:func:`~rplearn.models.auto_spread.planning_basis`: SH-10, or the basis itself).
    n_nodes : int
        The session's nodes.
    max_open : int, optional
        Blocks kept open at most (default :data:`MAX_OPEN_BLOCKS`, read when the session starts).
    """

    def __init__(self, basis: Any, n_nodes: int, max_open: int | None = None) -> None:
        self.basis = planning_basis(basis)
        self.n_nodes = int(n_nodes)
        self.max_open = max(int(MAX_OPEN_BLOCKS if max_open is None else max_open), 1)
        self.folded = BlockSums(self.n_nodes, self.basis.n_coef)
        self.open: dict[int, LinkSums] = {}
        self.folded_through: int | None = None  # the latest label folded
        #: samples that came for a block older than the latest one folded (module docstring)
        self.late_rows = 0
        #: each link's (both directions') folded blocks: with the open ones, the distinct blocks
        #: a drift needs (:func:`~rplearn.core.lsq.block_sums.link_block_count`'s rule)
        self.folded_per_link: dict[tuple[int, int], int] = {}

    def add(self, t_s: FloatArray, tx: NDArray[Any], rx: NDArray[Any], directions: Any, y: FloatArray) -> None:
        """Add samples (their times [s, common clock], ends, directions and observations)."""
        if not np.size(t_s):
            return
        labels = time_block_labels(t_s)
        if self.folded_through is not None:
            self.late_rows += int(np.count_nonzero(labels <= self.folded_through))
        add_links(self.open, block_link_sums(self.basis, labels, np.asarray(tx), np.asarray(rx), directions, y))
        excess = len(self.open) - self.max_open
        if excess > 0:
            oldest = sorted(self.open)[:excess]
            for label in oldest:
                for pair in _pairs(self.open[label]):
                    self.folded_per_link[pair] = self.folded_per_link.get(pair, 0) + 1
            self._fold(self.folded, [(label, self.open.pop(label)) for label in oldest])
            self.folded_through = max(oldest[-1], self.folded_through if self.folded_through is not None else oldest[-1])

    def link_block_count(self) -> int:
        """The most distinct time blocks any one link's samples fall in so far (both directions
        of a link one link; a late row's block, folded again, counted again): a drift needs
        :data:`~rplearn.core.lsq.block_sums.MIN_BLOCKS` (a flight of a few seconds has none)."""
        counts = dict(self.folded_per_link)
        for links in self.open.values():
            for pair in _pairs(links):
                counts[pair] = counts.get(pair, 0) + 1
        return max(counts.values(), default=0)

    def _fold(self, into: BlockSums, blocks: list[tuple[int, LinkSums]], sign: float = 1.0) -> None:
        """Fold each ``(label, its links' sums)`` of ``blocks`` into ``into`` (``sign=-1``: out again)."""
        q = self.basis.n_coef
        rows, pairs, labels = [], [], []
        for label, links in blocks:
            if links:
                rows.append(pair_vectors(links, self.n_nodes, q))
                keys = sorted({(min(t, r), max(t, r)) for t, r in links})  # pair_vectors' rows, in its order
                pairs += keys
                labels += [label] * len(keys)
        if rows:
            into.add_vectors(np.concatenate(rows), sign, links=pairs, labels=labels)

    def closed(self) -> BlockSums:
        """The sums of every block so far, each whole (a copy: the open blocks folded in)."""
        out = copy.deepcopy(self.folded)
        self._fold(out, list(self.open.items()))
        return out

    def split(self, sums: BlockSums, parts: Mapping[int, Mapping[int, LinkSums]]) -> BlockSums:
        """``sums`` with each block of ``parts`` (label -> its rows' sums per stretch of time ->
        per directed link) counted as its stretches' parts, not whole (module docstring): in place."""
        for label in sorted(parts):
            by_stretch = [parts[label][j] for j in sorted(parts[label]) if parts[label][j]]
            if len(by_stretch) < 2:
                continue  # within one stretch: whole, as counted
            whole: dict[int, LinkSums] = {}
            for links in by_stretch:
                add_links(whole, {label: links})
            self._fold(sums, [(label, whole[label])], -1.0)
            self._fold(sums, [(label, links) for links in by_stretch])
        return sums

    def at(self, sums: BlockSums, basis: Any) -> BlockSums:
        """``sums`` at the coefficients of ``basis`` (nested in the kept one: a smaller SH order's)."""
        if basis == self.basis:
            return sums
        idx = nested_columns(self.basis, basis, self.n_nodes)
        out = BlockSums(self.n_nodes, basis.n_coef, sums.block_s)
        out.cross, out.cross_n = sums.cross[np.ix_(idx, idx)], sums.cross_n[np.ix_(idx, idx)]
        out.sum_yv = sums.sum_yv[idx]
        out.sum_yy, out.sum_n, out.sum_nn, out.n_blocks = sums.sum_yy, sums.sum_n, sums.sum_nn, sums.n_blocks
        out.link_labels = copy.deepcopy(sums.link_labels)  # the blocks per link: what the drift's check reads
        return out


__all__ = ["CHUNK_SAMPLES", "MAX_OPEN_BLOCKS", "DriftBlocks", "LinkSums", "add_links", "block_link_sums", "pair_vectors"]
