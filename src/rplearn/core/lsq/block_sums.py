"""Per-time-block sums of the statistics: an error that drifts over seconds, in the posterior.

The white-noise posterior of a fit says each sample's error is independent. An error that
drifts (a heading estimate wandering by a few degrees over seconds, a slow level drift, a
multipath lobe) is shared by the samples of a few seconds: a flight that sees a direction once
learns its gain plus that stretch's error, and repeating the direction at once teaches nothing
new, while seeing it again later averages the error out. The model here: the error of sample
``i`` of link ``{a, b}`` in time block ``b(i)`` (blocks of :attr:`BlockSums.block_s` seconds)
is ``w_i + c_{link, b(i)}``, white ``w`` of variance ``sigma^2`` plus an offset shared by the
link's samples in the block, of variance ``s_c^2``. The penalised least-squares estimate
``beta = A^-1 X^T y`` (``A = X^T X + P``, the fit's ridge and smoothness penalty in the units of
``X^T X``) then has the covariance

    ``sigma^2 A^-1 + s_c^2 A^-1 C A^-1``,   ``C = sum_b v_b v_b^T``,  ``v_b = X_b^T 1``

(the first term is the white-noise posterior, its prior included; the second the drifting part:
``v_b`` is the sum of the features of the block's samples). Nothing in the fit changes.

:class:`BlockSums` keeps, with memory that does not grow with the flight's length, ``C``,
``C_n = sum_b n_b v_b v_b^T``, ``sum_b s_b v_b``, ``sum_b s_b^2``, ``sum_b n_b^2`` (``s_b =
1^T y_b``, ``n_b`` the block's samples), from the cumulative statistics' per-link sums
(:attr:`NormalEquations.directed`) at block boundaries: nothing is re-read. It also keeps which
time blocks each link's samples fell in, up to :data:`MIN_BLOCKS` of them a link (a small
count per link and block, :attr:`BlockSums.link_labels`): a drift is read only from a link
seen in :data:`MIN_BLOCKS` distinct blocks (:attr:`BlockSums.link_blocks`), however many links
or pieces share them.
:func:`correlated_ratio` estimates ``kappa = s_c^2 / sigma^2`` from them by moments: the
residual sum of squares and the sum of the blocks' squared residual sums of a penalised fit,
against their expectations under the model (each a linear function of ``sigma^2`` and
``s_c^2`` through traces of ``A^-1 X^T X``, ``A^-1 C`` and ``A^-1 C_n``; the fit's absorption of
the errors included), solved for the two.
"""

from __future__ import annotations

import copy
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from rplearn._argtypes import check_types
from rplearn.core.lsq.normal_equations import NormalEquations
from rplearn.core.lsq.products import spd_inverse
from rplearn.errors import InputError

FloatArray = NDArray[np.float64]

#: Default length of a time block [s]: about the correlation time of a drone's heading error.
DEFAULT_BLOCK_S = 5.0
#: Fewest distinct time blocks one link's samples must fall in for :func:`correlated_ratio` to
#: estimate anything (else 0; :attr:`BlockSums.link_blocks`), and for a model file's drift
#: (:func:`rplearn.models.auto_spread.drift_std_db`, :func:`link_block_count`).
MIN_BLOCKS = 4


def time_block_labels(t_s: Any) -> NDArray[np.int64]:
    """Each sample's :data:`DEFAULT_BLOCK_S` time block, ``floor(t / DEFAULT_BLOCK_S)``: the labels the
    statistics' sums per block are kept and merged under (:meth:`NormalEquations.add`'s ``time_block``),
    the same in memory and streamed chunk by chunk."""
    return np.floor(np.asarray(t_s, np.float64) / DEFAULT_BLOCK_S).astype(np.int64)


@check_types
@dataclass
class BlockSums:
    """Sums over time blocks of each link's samples (module docstring).

    Parameters
    ----------
    n_nodes, n_coef : int
        Nodes and basis coefficients per node of the statistics followed.
    block_s : float
        Length of a time block [s] (about the correlation time of the drifting error).

    Feed it the cumulative statistics after every batch (:meth:`follow`) or each batch's own
    statistics (:meth:`add_batch`) with a time of the batch (its samples' last, or middle, time):
    block ``k`` holds the batches whose time is in ``[k, k + 1) * block_s``, and closes when a
    batch of another block comes. :meth:`closed` is a copy with the open block closed (what the
    posterior reads).

    :attr:`n_blocks` counts the vectors summed (one per closed block and link, and per piece
    of a block summed in pieces); :attr:`link_labels` the vectors per link (both directions one)
    and block label, for at most :data:`MIN_BLOCKS` labels a link, whose most distinct labels of
    any one link, :attr:`link_blocks`, is what a drift needs.
    """

    n_nodes: int
    n_coef: int
    block_s: float = DEFAULT_BLOCK_S
    cross: FloatArray = field(init=False)
    cross_n: FloatArray = field(init=False)
    sum_yv: FloatArray = field(init=False)
    sum_yy: float = field(init=False, default=0.0)
    sum_n: float = field(init=False, default=0.0)
    sum_nn: float = field(init=False, default=0.0)
    n_blocks: int = field(init=False, default=0)
    link_labels: dict[tuple[int, int], dict[int, int]] = field(init=False, default_factory=dict, repr=False)
    _open: dict[tuple[int, int], FloatArray] = field(init=False, default_factory=dict, repr=False)
    _open_index: int | None = field(init=False, default=None, repr=False)
    _seen: dict[tuple[int, int], FloatArray] = field(init=False, default_factory=dict, repr=False)

    def __post_init__(self) -> None:
        if int(self.n_nodes) < 2 or int(self.n_coef) < 1:
            raise InputError(f"block sums: expected 2+ nodes and 1+ coefficients, got {self.n_nodes!r}, {self.n_coef!r}")
        if not (np.isfinite(self.block_s) and self.block_s > 0):
            raise InputError(f"block_s: expected a positive block length [s], got {self.block_s!r}", param="block_s")
        size = int(self.n_nodes) * int(self.n_coef)
        self.cross = np.zeros((size, size))
        self.cross_n = np.zeros((size, size))
        self.sum_yv = np.zeros(size)

    def _check(self, normal: NormalEquations) -> None:
        if normal.n_nodes != self.n_nodes or normal.basis.n_coef != self.n_coef:
            raise InputError(f"statistics of {normal.n_nodes} nodes x {normal.basis.n_coef} coefficients for block sums of "
                             f"{self.n_nodes} x {self.n_coef}", param="normal")

    def follow(self, normal: NormalEquations, t_s: float) -> BlockSums:
        """Take the samples added to the cumulative ``normal`` since the last call, the last of
        them at ``t_s`` [s]."""
        self._check(normal)
        fresh = {}
        for key, sums in normal.directed.items():
            prev = self._seen.get(key)
            fresh[key] = sums if prev is None else sums - prev
            self._seen[key] = sums.copy()
        self._take(fresh, float(t_s))
        return self

    def add_batch(self, batch: NormalEquations, t_s: float) -> BlockSums:
        """Take one batch's own statistics, its last sample at ``t_s`` [s]."""
        self._check(batch)
        self._take(batch.directed, float(t_s))
        return self

    def _take(self, directed: dict[tuple[int, int], FloatArray], t_s: float) -> None:
        if not np.isfinite(t_s):
            raise InputError(f"t_s: expected a finite time [s], got {t_s!r}", param="t_s")
        index = int(np.floor(t_s / self.block_s))
        if self._open_index is None or index > self._open_index:
            if self._open_index is not None:
                self._close()
            self._open_index = index
        # a batch that arrives late (its time in a block already closed) joins the open block:
        # a block is never closed twice, so C does not hang on how rows were batched
        for key, sums in directed.items():
            pair = (min(key), max(key))
            vec = self._vector(key, sums)
            prev = self._open.get(pair)
            self._open[pair] = vec if prev is None else prev + vec

    def _vector(self, key: tuple[int, int], sums: FloatArray) -> FloatArray:
        """A directed link's sums as ``[X^T 1 over all pattern columns, 1^T y, n]``."""
        p, (t, r) = self.n_coef, key
        out = np.zeros(self.n_nodes * p + 2)
        out[t * p:(t + 1) * p] += sums[:p]
        out[r * p:(r + 1) * p] += sums[p:2 * p]
        out[-2] = sums[2 * p]  # sum y
        out[-1] = sums[2 * p + 1]  # count
        return out

    @property
    def link_blocks(self) -> int:
        """The most distinct time blocks any one link's closed samples fall in (a block summed in
        several vectors, e.g. the stretches a flight is cut into, once), counted up to
        :data:`MIN_BLOCKS` (all a drift needs: the count does not grow with the flight); 0
        before any."""
        return max((len(labels) for labels in self.link_labels.values()), default=0)

    def _count(self, pair: tuple[int, int], label: int, sign: int) -> None:
        """Count a vector of ``label`` in or (``sign=-1``) out for the link ``pair``: a link keeps
        the counts of its first :data:`MIN_BLOCKS` distinct labels, and later labels only when
        one of those was taken out (a block counted as parts instead is taken out, then in again)."""
        labels = self.link_labels.setdefault(pair, {})
        if label in labels:
            labels[label] += sign
            if labels[label] <= 0:
                del labels[label]
        elif sign > 0 and len(labels) < MIN_BLOCKS:
            labels[label] = sign

    def _close(self) -> None:
        for pair, vec in self._open.items():
            n = float(vec[-1])
            if n <= 0:
                continue
            self._count(pair, int(self._open_index if self._open_index is not None else 0), 1)
            v, s = vec[:-2], float(vec[-2])
            outer = np.outer(v, v)
            self.cross += outer
            self.cross_n += n * outer
            self.sum_yv += s * v
            self.sum_yy += s * s
            self.sum_n += n
            self.sum_nn += n * n
            self.n_blocks += 1
        self._open = {}
        self._open_index = None

    def add_vectors(self, v: Any, sign: float = 1.0, *, links: Any, labels: Any) -> BlockSums:
        """Fold closed blocks in: ``v`` one row per block and link, ``[features summed over all
        pattern columns, sum y, count]``, ``links`` each row's link (two node indices, either
        order) and ``labels`` its block's label (for :attr:`link_blocks`); ``sign=-1`` takes
        blocks counted before out again (a block to be counted as parts instead). Rows of no
        samples are left out."""
        if sign not in (1.0, -1.0):
            raise InputError(f"sign: expected 1 or -1, got {sign!r}", param="sign")
        v = np.asarray(v, np.float64)
        ends = np.asarray(links, np.int64).reshape(-1, 2)
        at = np.asarray(labels, np.int64).ravel()
        if ends.shape[0] != v.shape[0] or at.size != v.shape[0]:
            raise InputError(f"add_vectors: {v.shape[0]} rows, {ends.shape[0]} links and {at.size} labels", param="links")
        keep = v[:, -1] > 0
        v, ends, at = v[keep], ends[keep], at[keep]
        for (a, b), label in zip(ends.tolist(), at.tolist()):
            self._count((min(a, b), max(a, b)), label, int(sign))
        features, s, n = v[:, :-2], v[:, -2], v[:, -1]
        self.cross += sign * (features.T @ features)
        self.cross_n += sign * ((features * n[:, None]).T @ features)
        self.sum_yv += sign * (s @ features)
        self.sum_yy += sign * float(s @ s)
        self.sum_n += sign * float(n.sum())
        self.sum_nn += sign * float(n @ n)
        self.n_blocks += int(sign) * int(n.size)
        return self

    def closed(self) -> BlockSums:
        """A copy with the open block closed (the sums of every sample so far)."""
        out = copy.deepcopy(self)
        out._close()
        return out


@check_types
def time_block_sums(statistics: Sequence[NormalEquations], block_s: float = DEFAULT_BLOCK_S,
                    n_coef: int | None = None) -> BlockSums | None:
    """The block sums of samples whose statistics kept their time blocks
    (:attr:`NormalEquations.block_directed`: samples added with ``time_block``), every block
    closed: each statistics' blocks (a flight unit's) apart from the others'. None when none
    kept any.

    Parameters
    ----------
    statistics : sequence of NormalEquations
        The statistics (of one basis and node count), e.g. one per flight unit.
    block_s : float
        The length of the blocks the labels count [s].
    n_coef : int, optional
        Only the first ``n_coef`` coefficients of every node (a smaller spherical-harmonic
        order, whose coefficients lead the larger one's, as
        :func:`rplearn.core.lsq.penalty.sub_statistics` takes them); default all the statistics
        kept per block (:attr:`NormalEquations.block_coefs`).
    """
    kept = [st for st in statistics if st.block_directed]
    if not kept:
        return None
    big = kept[0].n_block_coefs  # the coefficients each block's sums kept (NormalEquations.block_coefs)
    p = big if n_coef is None else int(n_coef)
    if not 1 <= p <= big:
        raise InputError(f"n_coef: expected 1..{big}, got {n_coef!r}", param="n_coef")
    out = BlockSums(kept[0].n_nodes, p, block_s)
    groups: dict[tuple[int, int, tuple[int, int]], int] = {}  # (statistics, block, link) -> its vector
    where, links, rows = [], [], []
    for i, st in enumerate(kept):
        if st.n_nodes != out.n_nodes or st.basis.n_coef != kept[0].basis.n_coef or st.n_block_coefs != big:
            raise InputError("time_block_sums: statistics of different bases, node counts or block coefficients",
                             param="statistics")
        for label in sorted(st.block_directed):
            for key, sums in st.block_directed[label].items():
                where.append(groups.setdefault((i, label, (min(key), max(key))), len(groups)))
                links.append(key)
                rows.append(sums)
    sums_all, at, code = np.array(rows, np.float64), np.array(where, np.intp), np.array([t * out.n_nodes + r for t, r in links])
    v = np.zeros((len(groups), out.n_nodes * p + 2))
    pairs = np.array([pair for _, _, pair in groups], np.int64).reshape(len(groups), 2)  # each vector's link and block
    labels = np.array([label for _, label, _ in groups], np.int64)
    for c in np.unique(code):  # each directed link's entries at once (a vector holds each at most once)
        t, r = divmod(int(c), out.n_nodes)
        m = code == c
        v[at[m], t * p:(t + 1) * p] += sums_all[m, :p]
        v[at[m], r * p:(r + 1) * p] += sums_all[m, big:big + p]
        v[at[m], -2:] += sums_all[m, 2 * big:2 * big + 2]  # sum y, count
    return out.add_vectors(v, links=pairs, labels=labels)


@check_types
def link_block_count(statistics: Sequence[NormalEquations]) -> int:
    """The most distinct time blocks any one link's samples fall in, over ``statistics`` (their
    :attr:`NormalEquations.block_directed` labels; a block whose samples several statistics
    hold, e.g. the stretches a flight is cut into, counted once; both directions of a link as
    one link); 0 when none kept any.

    What a drift needs: its offsets vary over the blocks of each link, so a link seen in fewer
    blocks shows no drift to tell from its pattern and level, however many pieces its samples
    were summed in (:attr:`BlockSums.n_blocks` counts one vector per statistics, block and link:
    a 7-s flight cut into 5 stretches gave 6 from 2 blocks).
    """
    labels: dict[tuple[int, int], set[int]] = {}
    for st in statistics:
        for label, per_link in st.block_directed.items():
            for key, sums in per_link.items():
                if sums[2 * st.n_block_coefs + 1] > 0:  # the link's samples in the block (rows [f_tx, f_rx, y, 1, e])
                    labels.setdefault((min(key), max(key)), set()).add(int(label))
    return max((len(v) for v in labels.values()), default=0)


@check_types
def correlated_ratio(normal: NormalEquations, blocks: BlockSums, prior_diag: Any) -> float:
    """``kappa = s_c^2 / sigma^2``: the drifting error's block-offset variance over the white
    noise's, estimated by moments (module docstring); 0 when no link's samples fall in
    :data:`MIN_BLOCKS` distinct blocks (:attr:`BlockSums.link_blocks`: three links seen in 2
    blocks are 6 vectors but show no drift to tell from the pattern) or when the blocks'
    residuals scatter no more than white noise allows.

    Parameters
    ----------
    normal : NormalEquations
        The statistics of the same samples as ``blocks`` (pattern columns first).
    blocks : BlockSums
        Their block sums, every sample in a closed block (:meth:`BlockSums.closed`).
    prior_diag : array_like
        The fit's prior precision per pattern column in the units of ``X^T X`` (ridge + penalty).

    Notes
    -----
    The moments fit the pattern columns alone (the block sums hold no others): with a
    path-loss or link-offset term its effect stays in the residuals, and a term that drifts
    with distance over time is counted as drifting error (``kappa`` too large, revisits
    favoured more than they should be).
    """
    if blocks.link_blocks < MIN_BLOCKS:
        return 0.0
    pc = normal.n_pattern_columns
    if blocks.cross.shape[0] != pc:
        raise InputError(f"block sums of {blocks.cross.shape[0]} columns for statistics of {pc} pattern columns", param="blocks")
    gram = np.asarray(normal.gram, np.float64)[:pc, :pc]
    a = gram + np.diag(np.asarray(prior_diag, np.float64).ravel())
    a_inv = spd_inverse(a)
    beta = a_inv @ normal.rhs[:pc]
    rss = float(normal.yty - 2.0 * beta @ normal.rhs[:pc] + beta @ gram @ beta)
    block_rss = float(blocks.sum_yy - 2.0 * beta @ blocks.sum_yv + beta @ blocks.cross @ beta)
    k_g, k_c = a_inv @ gram, a_inv @ blocks.cross
    n = float(normal.n_samples)
    t_g, t_c, t_gc = float(np.trace(k_g)), float(np.trace(k_c)), float(np.sum(k_g * k_c.T))
    # E[rss] = sigma^2 tr((I-H)^2) + s_c^2 tr(J (I-H)^2);  E[block rss] = sigma^2 tr(J (I-H)^2) + s_c^2 tr(J (I-H) J (I-H))
    white_rss = n - 2.0 * t_g + float(np.sum(k_g * k_g.T))
    mixed = blocks.sum_n - 2.0 * t_c + t_gc
    block_block = blocks.sum_nn - 2.0 * float(np.sum(a_inv * blocks.cross_n)) + float(np.sum(k_c * k_c.T))
    system = np.array([[white_rss, mixed], [mixed, block_block]])
    try:
        sigma2, sc2 = np.linalg.solve(system, np.array([rss, block_rss]))
    except np.linalg.LinAlgError:
        return 0.0
    if not (np.isfinite(sigma2) and np.isfinite(sc2)) or sigma2 <= 0 or sc2 <= 0:
        return 0.0
    return float(sc2 / sigma2)


__all__ = ["DEFAULT_BLOCK_S", "MIN_BLOCKS", "BlockSums", "correlated_ratio", "link_block_count", "time_block_labels",
           "time_block_sums"]
