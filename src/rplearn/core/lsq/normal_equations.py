"""Sufficient statistics of the joint least-squares problem, accumulated in chunks (paper Sec. V-A).

Each signal sample ``i`` names its transmitter ``t_i`` and receiver ``r_i`` and observes the joint
gain ``y_i = G_t(az_tx_i, el_tx_i) + G_r(az_rx_i, el_rx_i) + noise`` (paper eq. 5). With every
pattern a linear combination of the same basis, ``G_n = f(az, el) . p_n``, the row of sample
``i`` in the design matrix holds ``f(az_tx, el_tx)`` in the block of node ``t_i``,
``f(az_rx, el_rx)`` in the block of ``r_i`` and zeros elsewhere (the paper's Sec. V-A matrix).

The design matrix is never formed: :class:`NormalEquations` accumulates ``X^T X``, ``X^T y``,
``y^T y`` and ``n`` chunk by chunk, one link direction at a time (:func:`link_statistics`),
through a block buffer reused by later fits in the same thread (:mod:`rplearn.core.lsq.runtime`),
so memory does not grow with the number of samples. :mod:`rplearn.core.lsq.solver` solves the result.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from rplearn._argtypes import check_types
from rplearn.core.bases import Basis
from rplearn.core.geometry import Directions
from rplearn.core.lsq.link_statistics import block_rows, block_samples, block_starts, link_statistics, max_links_per_block, segmented_link_statistics
from rplearn.core.lsq.runtime import DEFAULT_RUNTIME
from rplearn.core.threads import blas_threads_for
from rplearn.errors import InputError

FloatArray = NDArray[np.float64]

#: The path-loss exponent is refused as not identifiable when the part of its log-distance
#: column ``10 log10 d`` that the other columns (the patterns) cannot explain has a standard
#: deviation below this [dB]: the distance then varies by less than about +-12% independently
#: of the directions (a flight at constant distance, or at constant altitude over a static
#: station), one unit of exponent moves the gain less than a pattern's misfit does, and the
#: patterns could take any exponent.
EXPONENT_MIN_SPREAD_DB = 0.5

#: Entries of a directed link's sums (:attr:`NormalEquations.directed`) after its two feature
#: blocks: sum of y, sample count, sum of the environment column.
_SUM_Y, _COUNT, _SUM_E = 0, 1, 2


@check_types
@dataclass
class NormalEquations:
    """Sufficient statistics of the joint least-squares problem, accumulated chunk by chunk.

    Parameters
    ----------
    basis : Basis
        The basis shared by all nodes.
    n_nodes : int
        Number of nodes (patterns) in the problem.
    environment : bool
        Also accumulate one shared per-sample regressor (the log-distance column of
        :mod:`rplearn.core.environment`), given to every :meth:`add`.
    block_coefs : int, optional
        Keep only each node's first ``block_coefs`` coefficients in the sums per time block
        (:attr:`block_directed`: a smaller spherical-harmonic order's, whose coefficients lead;
        what the drifting error is read at), so that they take less memory; default all.

    Besides ``X^T X`` and ``X^T y`` of the pattern columns, every directed link keeps the sums
    of its features, observations and environment values (:attr:`directed`), from which
    :meth:`with_shared` appends shared columns (the environment column and one electronics
    offset per link logged both ways) without re-reading samples.
    """

    basis: Basis
    n_nodes: int
    environment: bool = False
    block_coefs: int | None = None
    gram: FloatArray = field(init=False)
    rhs: FloatArray = field(init=False)
    yty: float = field(init=False, default=0.0)
    n_samples: int = field(init=False, default=0)
    link_counts: dict[tuple[int, int], int] = field(init=False, default_factory=dict)
    #: per directed link (tx, rx): [sum f_tx (p), sum f_rx (p), sum y, count, sum e], natural order
    directed: dict[tuple[int, int], FloatArray] = field(init=False, default_factory=dict)
    #: environment column: X^T e of the pattern columns, e^T e, e^T y
    env_cross: FloatArray = field(init=False)
    env_sq: float = field(init=False, default=0.0)
    env_y: float = field(init=False, default=0.0)
    #: shared columns appended after the pattern columns (set by :meth:`with_shared`):
    #: ``("exponent",)`` or ``("offset", a, b)`` (+1 on a -> b samples, -1 on b -> a)
    shared: tuple[tuple[Any, ...], ...] = field(init=False, default=())
    #: sums per time block of these samples (:class:`~rplearn.core.lsq.block_sums.BlockSums`), set
    #: by code that keeps them (a live session's total); None: not kept. Not merged or copied.
    blocks: Any = field(init=False, default=None, repr=False, compare=False)
    #: per time block (the labels given to :meth:`add` as ``time_block``), each directed link's
    #: sums as :attr:`directed` holds them over all samples: read off the rows the statistics
    #: compute anyway (no sample re-read), merged by :meth:`merge`, not carried by
    #: :meth:`with_shared`; empty when no labels were given
    block_directed: dict[int, dict[tuple[int, int], FloatArray]] = field(init=False, default_factory=dict, repr=False,
                                                                         compare=False)

    def __post_init__(self) -> None:
        if self.n_nodes < 2:
            raise InputError(f"a link problem needs at least 2 nodes, got {self.n_nodes}")
        self.gram = np.zeros((self.n_columns, self.n_columns))
        self.rhs = np.zeros(self.n_columns)
        self.env_cross = np.zeros(self.n_pattern_columns)
        # link_statistics orders rows [tx features, y, 1, e, rx features], features in the
        # basis's row order; this index puts them back as [tx, rx, y, 1, e] in natural order.
        p = self.basis.n_coef
        rows = self.basis.row_order
        natural = np.arange(p) if rows is None else np.argsort(rows)
        m = self._n_extra
        self._natural = np.concatenate([natural, natural + p + 1 + m, np.arange(p, p + 1 + m)])
        if self.block_coefs is not None and not 1 <= int(self.block_coefs) <= p:
            raise InputError(f"block_coefs: expected 1..{p}, got {self.block_coefs!r}", param="block_coefs")

    @property
    def n_block_coefs(self) -> int:
        """Coefficients per node kept in the sums per time block (:attr:`block_directed`)."""
        return self.basis.n_coef if self.block_coefs is None else int(self.block_coefs)

    @property
    def _n_extra(self) -> int:
        return 2 if self.environment else 1

    @property
    def n_pattern_columns(self) -> int:
        """Columns of the patterns (``n_nodes * n_coef``); shared columns follow them."""
        return self.basis.n_coef * self.n_nodes

    @property
    def n_columns(self) -> int:
        return self.n_pattern_columns + len(self.shared)

    def add(
        self,
        directions: Directions,
        tx_index: ArrayLike,
        rx_index: ArrayLike,
        joint_gain_db: ArrayLike | None = None,
        environment: ArrayLike | None = None,
        time_block: ArrayLike | None = None,
    ) -> NormalEquations:
        """Accumulate a chunk of samples.

        Parameters
        ----------
        directions : Directions
            ``az_tx, el_tx, az_rx, el_rx`` of every sample [rad].
        tx_index, rx_index : array_like of int
            Node index of the transmitter and receiver of every sample.
        joint_gain_db : array_like, optional
            Observed joint gain [dB] (paper eq. 5); omitted for an identifiability check only.
        environment : array_like, optional
            The shared environment regressor of every sample; required exactly when the
            statistics were made with ``environment=True``.
        time_block : array_like of int, optional
            The block of time of every sample (e.g. ``floor(t / 5 s)``): each block's sums per
            directed link are kept too (:attr:`block_directed`).
        """
        if self.shared:
            raise InputError("these statistics have shared columns appended (with_shared); add samples before that")
        az_tx, el_tx, az_rx, el_rx = (np.ascontiguousarray(a, np.float64).ravel() for a in directions)
        tx = np.asarray(tx_index).ravel()
        rx = np.asarray(rx_index).ravel()
        n = az_tx.size
        y = np.zeros(n) if joint_gain_db is None else np.ascontiguousarray(joint_gain_db, np.float64).ravel()
        if (environment is None) == self.environment:
            raise InputError("environment: give the environment column exactly when the statistics accumulate one",
                             param="environment")
        e = np.zeros(n) if environment is None else np.ascontiguousarray(environment, np.float64).ravel()
        blocks = None if time_block is None else np.asarray(time_block).ravel()
        if blocks is not None and not np.issubdtype(blocks.dtype, np.integer):
            raise InputError(f"time_block: expected an integer block per sample, got {blocks.dtype}", param="time_block")
        for name, arr in (("el_tx", el_tx), ("az_rx", az_rx), ("el_rx", el_rx), ("tx_index", tx), ("rx_index", rx),
                          ("joint_gain_db", y), ("environment", e), ("time_block", e if blocks is None else blocks)):
            if arr.size != n:
                raise InputError(f"{name} has {arr.size} values, az_tx has {n}")
        for name, arr in (("az_tx", az_tx), ("el_tx", el_tx), ("az_rx", az_rx), ("el_rx", el_rx), ("joint_gain_db", y),
                          ("environment", e)):
            if not np.all(np.isfinite(arr)):
                raise InputError(f"{name}: {int(np.sum(~np.isfinite(arr)))} NaN or infinite value(s)")
        if n == 0:
            return self
        if np.any(tx < 0) or np.any(rx < 0) or np.any(tx >= self.n_nodes) or np.any(rx >= self.n_nodes):
            raise InputError(f"node index out of range 0..{self.n_nodes - 1}")
        if np.any(tx == rx):
            raise InputError("a sample has the same node as transmitter and receiver")
        with blas_threads_for(n, 2 * self.basis.n_coef):  # the thread policy (rplearn.core.threads)
            self._add_checked(n, tx, rx, (az_tx, el_tx, az_rx, el_rx, y, e), blocks)
        return self

    def _add_checked(self, n: int, tx: NDArray[Any], rx: NDArray[Any], arrays: tuple[FloatArray, ...],
                     blocks: NDArray[Any] | None = None) -> None:
        """:meth:`add` of ``n`` checked samples: ``arrays`` are ``az_tx, el_tx, az_rx, el_rx, y, e``;
        ``blocks`` each sample's time block, or None."""
        az_tx, el_tx, az_rx, el_rx, y, e = arrays
        self._own_gram()
        pair_code = tx.astype(np.int64) * self.n_nodes + rx
        if pair_code.min() == pair_code.max():  # one link direction: no grouping needed
            groups = [(int(pair_code[0]), slice(0, n))]
        else:  # sorted once by link, each link a contiguous slice (no mask per link)
            # codes below 2^16 (up to 256 nodes) sort as uint16: numpy's stable sort is then a
            # radix sort (4 ms for 500,000 samples against 30 ms as int64)
            keys = pair_code.astype(np.uint16) if self.n_nodes**2 <= 2**16 else pair_code
            order = np.argsort(keys, kind="stable")
            sorted_code = pair_code[order]
            az_tx, el_tx, az_rx, el_rx, y, e = (a[order] for a in (az_tx, el_tx, az_rx, el_rx, y, e))
            blocks = None if blocks is None else blocks[order]
            starts = np.flatnonzero(np.r_[True, sorted_code[1:] != sorted_code[:-1]])
            ends = np.r_[starts[1:], n]
            groups = [(int(sorted_code[a]), slice(int(a), int(b))) for a, b in zip(starts, ends)]
        # runs of samples of one link and one time block (each link's samples in their order)
        runs = None
        if blocks is not None:
            cut = np.zeros(n, bool)
            cut[[sel.start for _, sel in groups]] = True
            cut[1:] |= blocks[1:] != blocks[:-1]
            runs = np.flatnonzero(cut)
        if len(groups) > 1 and self.basis.moment_shape is not None and self.basis.stacked_samples:
            # many links: features of many links per pass, each node's diagonal block from its
            # summed moments once per call, not once per link end
            codes = np.array([c for c, _ in groups], np.int64)
            starts = np.array([sel.start for _, sel in groups], np.intp)
            self._add_links(codes, np.r_[starts, n], (az_tx, el_tx, az_rx, el_rx, y, e),
                            None if runs is None or blocks is None else (runs, blocks[runs]))
        else:
            for code, sel in groups:
                t, r = divmod(code, self.n_nodes)
                link_runs = None
                if runs is not None and blocks is not None:
                    mine = runs[(runs >= sel.start) & (runs < sel.stop)]
                    link_runs = (mine - sel.start, blocks[mine])
                self._add_pair(t, r, (az_tx[sel], el_tx[sel], az_rx[sel], el_rx[sel], y[sel], e[sel]), link_runs)
        self.n_samples += n

    def _add_run_sums(self, t: int, r: int, labels: NDArray[Any], sums: FloatArray) -> None:
        """Add runs' row sums (rows ``[f_tx, y, 1, e, f_rx]`` in the block's row order) of link
        ``t -> r`` to :attr:`block_directed` under the runs' time blocks ``labels``."""
        m = self._n_extra
        p, q = self.basis.n_coef, self.n_block_coefs
        # [f_tx, f_rx, y, 1, (e)] in natural order, each node's first q coefficients only
        natural = sums[:, self._natural if q == p else self._natural[np.r_[0:q, p:p + q, 2 * p:2 * p + 1 + m]]]
        for label, row in zip(labels.tolist(), natural):
            per_link = self.block_directed.setdefault(int(label), {})
            prev = per_link.get((t, r))
            vec = np.zeros(2 * q + 3) if prev is None else prev
            vec[: 2 * q + 1 + m] += row
            per_link[(t, r)] = vec

    def _add_links(
        self, codes: NDArray[np.int64], bounds: NDArray[np.intp], arrays: tuple[FloatArray, ...],
        runs: tuple[NDArray[np.intp], NDArray[Any]] | None = None,
    ) -> None:
        """Add samples sorted by link (link ``codes[j]`` = ``tx * n_nodes + rx`` holds samples
        ``bounds[j]:bounds[j + 1]``; ``arrays``: ``az_tx, el_tx, az_rx, el_rx, y, e``) in blocks
        of samples (:func:`segmented_link_statistics`); the diagonal blocks from the nodes'
        summed moments, the cross blocks into the upper block triangle, then mirrored. ``runs``:
        the starts of the runs of one link and time block, and their blocks' labels."""
        az_tx, el_tx, az_rx, el_rx, y, e = arrays
        p = self.basis.n_coef
        n = az_tx.size
        m = self._n_extra
        per_block = block_samples(block_rows(self.basis, m))
        shape = self.basis.moment_shape
        assert shape is not None  # only bases with Gram moments come here
        node_moments = np.zeros((self.n_nodes, *shape))
        touched: set[tuple[int, int]] = set()
        nodes = np.arange(self.n_nodes)[:, None]

        starts = block_starts(bounds, per_block, max_links_per_block(self.basis, m))
        stops = dict(zip(starts, [*starts[1:], n]))

        def statistics(s: int) -> tuple[FloatArray, tuple[FloatArray, FloatArray], int, int, NDArray[np.int64], Any]:
            stop = stops[s]
            first = int(np.searchsorted(bounds, s, side="right")) - 1
            last = int(np.searchsorted(bounds, stop, side="left"))
            local = np.clip(bounds[first : last + 1], s, stop) - s
            tx = codes[first:last] // self.n_nodes
            tx_runs = np.r_[0, np.flatnonzero(tx[1:] != tx[:-1]) + 1, tx.size]  # links sorted by tx: its runs
            extra = np.ones((1, stop - s)) if not self.environment else np.stack([np.ones(stop - s), e[s:stop]])
            part = slice(s, stop)
            mine = None
            if runs is not None:  # this block's runs of one link and time block, from its first sample
                a, b = int(np.searchsorted(runs[0], s, side="right")) - 1, int(np.searchsorted(runs[0], stop, side="left"))
                at = np.maximum(runs[0][a:b], s)
                mine = (at, runs[1][a:b], np.zeros((b - a, 2 * p + 1 + m)))
            products, moments = segmented_link_statistics(
                self.basis, Directions(az_tx[part], el_tx[part], az_rx[part], el_rx[part]), y[part], extra, local,
                self._natural[:p], local[tx_runs], None if mine is None else (mine[0] - s, mine[2]))
            return products, moments, first, last, tx[tx_runs[:-1]], mine

        for products, moments, first, last, run_tx, mine in DEFAULT_RUNTIME.in_order(statistics, starts):
            tx, rx = np.divmod(codes[first:last], self.n_nodes)
            flat = node_moments.reshape(self.n_nodes, -1)
            flat += (run_tx[None, :] == nodes).astype(np.float64) @ moments[0].reshape(run_tx.size, -1)
            flat += (rx[None, :] == nodes).astype(np.float64) @ moments[1].reshape(rx.size, -1)
            self._add_products(tx, rx, products)
            touched.update(zip(np.minimum(tx, rx).tolist(), np.maximum(tx, rx).tolist()))
            if mine is not None:
                link = np.searchsorted(bounds, mine[0], side="right") - 1  # each run's link
                for j in range(link.size):
                    t, r = divmod(int(codes[link[j]]), self.n_nodes)
                    self._add_run_sums(t, r, mine[1][j:j + 1], mine[2][j:j + 1])
        nat = self._natural[:p]
        for k in np.flatnonzero(np.any(node_moments != 0, axis=(1, 2))):
            self.gram[k * p : (k + 1) * p, k * p : (k + 1) * p] += self.basis.gram_from_moments(node_moments[k])[
                np.ix_(nat, nat)]
        for a, b in touched:  # the cross blocks went into the upper block triangle: mirror them
            self.gram[b * p : (b + 1) * p, a * p : (a + 1) * p] = self.gram[a * p : (a + 1) * p, b * p : (b + 1) * p].T

    def _add_products(self, tx: NDArray[np.int64], rx: NDArray[np.int64], products: FloatArray) -> None:
        """Add the per-link products of :func:`segmented_link_statistics` (rows ``[f_tx, y, 1,
        e]``, columns ``[y, 1, e, f_rx]``, features in natural order): cross blocks into
        the upper block triangle of the Gram, then ``X^T y``, ``y^T y``, the environment
        column's products and each directed link's sums (:attr:`directed`)."""
        p = self.basis.n_coef
        gap = 1 + self._n_extra
        y_row, one_row, env_row = p, p + 1, p + 2
        cross = products[:, :p, gap:]  # F_tx^T F_rx, into the upper block triangle (loop below)
        # per node: sums over its links as a product with the links' node indicator
        nodes = np.arange(self.n_nodes)
        at_tx = (tx[None, :] == nodes[:, None]).astype(np.float64)  # (nodes, links)
        at_rx = (rx[None, :] == nodes[:, None]).astype(np.float64)
        tx_cols = products[:, :p, :gap]  # rows f_tx times columns y, 1, e
        rx_rows = products[:, p:, gap:]  # rows y, 1, e times columns f_rx
        self.rhs[: self.n_pattern_columns] += (at_tx @ tx_cols[:, :, 0] + at_rx @ rx_rows[:, 0, :]).ravel()
        self.yty += float(products[:, y_row, 0].sum())
        sums = np.zeros((tx.size, 2 * p + 3))
        sums[:, :p] = tx_cols[:, :, 1]
        sums[:, p : 2 * p] = rx_rows[:, 1, :]
        sums[:, 2 * p + _SUM_Y] = products[:, y_row, 1]
        sums[:, 2 * p + _COUNT] = products[:, one_row, 1]
        if self.environment:
            sums[:, 2 * p + _SUM_E] = products[:, one_row, 2]
            self.env_cross += (at_tx @ tx_cols[:, :, 2] + at_rx @ rx_rows[:, 2, :]).ravel()
            self.env_y += float(products[:, y_row, 2].sum())
            self.env_sq += float(products[:, env_row, 2].sum())
        gram = self.gram  # (no shared columns while adding)
        for j, (t, r) in enumerate(zip(tx.tolist(), rx.tolist())):
            # a slice add per link: 16 us against 22 us for fancy-indexed adds of all links at once
            if t < r:
                gram[t * p : (t + 1) * p, r * p : (r + 1) * p] += cross[j]
            else:
                gram[r * p : (r + 1) * p, t * p : (t + 1) * p] += cross[j].T
            key = (min(t, r), max(t, r))
            self.link_counts[key] = self.link_counts.get(key, 0) + int(round(sums[j, 2 * p + _COUNT]))
            prev = self.directed.get((t, r))
            self.directed[(t, r)] = sums[j] if prev is None else prev + sums[j]

    def _add_pair(
        self, t: int, r: int, arrays: tuple[FloatArray, ...], runs: tuple[NDArray[np.intp], NDArray[Any]] | None = None,
    ) -> None:
        """Add the samples of link ``t -> r`` (``arrays``: ``az_tx, el_tx, az_rx, el_rx, y, e``);
        ``runs``: the starts of its runs of one time block and their labels."""
        az_tx, el_tx, az_rx, el_rx, y, e = arrays
        p = self.basis.n_coef
        bt = slice(t * p, (t + 1) * p)
        br = slice(r * p, (r + 1) * p)
        n = az_tx.size
        key = (min(t, r), max(t, r))
        self.link_counts[key] = self.link_counts.get(key, 0) + n
        # Both nodes' blocks of X^T X, X^T y and y^T y, and the sums of the directed link, from
        # one pass over the samples.
        extra = np.ones((1, n)) if not self.environment else np.stack([np.ones(n), e])
        run_sums = None if runs is None else (runs[0], np.zeros((runs[0].size, 2 * p + 1 + self._n_extra)))
        block = link_statistics(self.basis, az_tx, el_tx, az_rx, el_rx, y, extra, run_sums)
        if runs is not None and run_sums is not None:
            self._add_run_sums(t, r, runs[1], run_sums[1])
        block = block[np.ix_(self._natural, self._natural)]
        self.gram[bt, bt] += block[:p, :p]
        self.gram[br, br] += block[p : 2 * p, p : 2 * p]
        self.gram[bt, br] += block[:p, p : 2 * p]
        self.gram[br, bt] += block[p : 2 * p, :p]
        self.rhs[bt] += block[:p, 2 * p]
        self.rhs[br] += block[p : 2 * p, 2 * p]
        self.yty += float(block[2 * p, 2 * p])
        one = 2 * p + 1
        sums = np.zeros(2 * p + 3)
        sums[: 2 * p] = block[: 2 * p, one]
        sums[2 * p + _SUM_Y] = block[2 * p, one]
        sums[2 * p + _COUNT] = block[one, one]
        if self.environment:
            env = one + 1
            sums[2 * p + _SUM_E] = block[one, env]
            self.env_cross[bt] += block[:p, env]
            self.env_cross[br] += block[p : 2 * p, env]
            self.env_y += float(block[2 * p, env])
            self.env_sq += float(block[env, env])
        prev = self.directed.get((t, r))
        self.directed[(t, r)] = sums if prev is None else prev + sums

    def _own_gram(self) -> None:
        """Copy the Gram before changing it when it is read-only: a large solve keeps it (its
        solves and lazy covariance read it, :mod:`rplearn.core.lsq.refined`) and marks it so."""
        if not self.gram.flags.writeable:
            self.gram = self.gram.copy()

    def merge(self, other: NormalEquations) -> NormalEquations:
        """Add another accumulator's statistics (same basis, node count and columns) into this one."""
        if other.basis != self.basis or other.n_nodes != self.n_nodes or other.environment != self.environment:
            raise InputError("cannot merge normal equations of different bases, node counts or environment columns")
        if self.shared or other.shared:
            raise InputError("merge statistics before appending shared columns (with_shared)")
        self._own_gram()
        self.gram += other.gram
        self.rhs += other.rhs
        self.yty += other.yty
        self.n_samples += other.n_samples
        for k, v in other.link_counts.items():
            self.link_counts[k] = self.link_counts.get(k, 0) + v
        for k, sums in other.directed.items():
            self.directed[k] = sums.copy() if k not in self.directed else self.directed[k] + sums
        if other.block_directed and self.n_block_coefs != other.n_block_coefs:
            if self.block_directed:
                raise InputError("cannot merge sums per time block of different coefficient counts (block_coefs)")
            self.block_coefs = other.block_coefs  # none kept yet: these take the other's
        for label, links in other.block_directed.items():
            mine = self.block_directed.setdefault(label, {})
            for k, sums in links.items():
                mine[k] = sums.copy() if k not in mine else mine[k] + sums
        self.env_cross += other.env_cross
        self.env_sq += other.env_sq
        self.env_y += other.env_y
        return self

    def two_way_links(self) -> list[tuple[int, int]]:
        """Links ``(a, b)``, ``a < b``, with samples in both directions (those that can carry an
        electronics offset), sorted."""
        return sorted((a, b) for (a, b) in self.directed if a < b and (b, a) in self.directed)

    @property
    def environment_sum(self) -> float:
        """Sum of the environment column over all samples."""
        return float(sum(v[2 * self.basis.n_coef + _SUM_E] for v in self.directed.values()))

    def column_sums(self) -> tuple[FloatArray, float]:
        """``X^T 1`` (the sum of every column over the samples, shared columns included) and
        ``1^T y``, from each directed link's sums (no sample re-read): the mean residual of a fit
        ``c`` over these samples is ``(1^T y - c . X^T 1) / n``."""
        p = self.basis.n_coef
        out = np.zeros(self.n_columns)
        sum_y = 0.0
        for (t, r), v in self.directed.items():
            out[t * p:(t + 1) * p] += v[:p]
            out[r * p:(r + 1) * p] += v[p:2 * p]
            sum_y += float(v[2 * p + _SUM_Y])
        for j, shared in enumerate(self.shared):
            if shared[0] == "exponent":
                out[self.n_pattern_columns + j] = self.environment_sum
            else:
                a, b = shared[1], shared[2]
                out[self.n_pattern_columns + j] = sum(float(self.directed[k][2 * p + _COUNT]) * sign
                                                      for k, sign in (((a, b), 1.0), ((b, a), -1.0)) if k in self.directed)
        return out, sum_y

    def with_shared(self, offset_links: list[tuple[int, int]] | None = None) -> NormalEquations:
        """These statistics with shared columns appended after the pattern columns.

        The environment column (``("exponent",)``) when accumulated, then one column per link
        of ``offset_links`` (``("offset", a, b)``: +1 on the samples ``a -> b``, -1 on
        ``b -> a``), whose coefficient is half the difference between the two directions'
        electronics (the gauge that makes a link's two offsets sum to zero; their common part
        is the patterns' joint level). Links without samples here give zero columns (a unit
        of a fleet that did not fly them). Returns a new object; this one is unchanged.
        """
        links = list(offset_links or [])
        for a, b in links:
            if not (0 <= a < b < self.n_nodes):
                raise InputError(f"offset link ({a}, {b}): expected node indices a < b below {self.n_nodes}")
        shared: list[tuple[Any, ...]] = ([("exponent",)] if self.environment else []) + [("offset", a, b) for a, b in links]
        out = NormalEquations(self.basis, self.n_nodes, self.environment)
        out.yty, out.n_samples = self.yty, self.n_samples
        out.link_counts = dict(self.link_counts)
        out.directed = {k: v.copy() for k, v in self.directed.items()}
        out.env_cross, out.env_sq, out.env_y = self.env_cross.copy(), self.env_sq, self.env_y
        out.shared = tuple(shared)
        pc, p = self.n_pattern_columns, self.basis.n_coef
        size = pc + len(shared)
        gram = np.zeros((size, size))
        rhs = np.zeros(size)
        gram[:pc, :pc] = self.gram
        rhs[:pc] = self.rhs
        col = pc
        if self.environment:
            gram[:pc, col] = self.env_cross
            gram[col, col] = self.env_sq
            rhs[col] = self.env_y
            col += 1
        zero = np.zeros(2 * p + 3)
        for a, b in links:
            fwd, back = self.directed.get((a, b), zero), self.directed.get((b, a), zero)
            ba, bb = slice(a * p, (a + 1) * p), slice(b * p, (b + 1) * p)
            gram[ba, col] = fwd[:p] - back[p : 2 * p]  # a is tx on a -> b, rx on b -> a
            gram[bb, col] = fwd[p : 2 * p] - back[:p]
            gram[col, col] = fwd[2 * p + _COUNT] + back[2 * p + _COUNT]
            rhs[col] = fwd[2 * p + _SUM_Y] - back[2 * p + _SUM_Y]
            if self.environment:
                gram[pc, col] = fwd[2 * p + _SUM_E] - back[2 * p + _SUM_E]
            col += 1
        out.gram = np.triu(gram) + np.triu(gram, 1).T
        out.rhs = rhs
        return out


@check_types
def independent_spread_db(normal: NormalEquations, column: int) -> float:
    """Standard deviation [dB] of the part of a column that every other column (the patterns at
    this order, the other shared columns) cannot explain, from the statistics: ``sqrt(S / n)``
    with ``S`` the Schur complement of the column in ``X^T X`` (a tiny jitter keeps the gauge's
    null directions invertible; they are orthogonal to any column)."""
    return schur_spread_db(normal.gram, int(column), normal.n_samples)


def schur_spread_db(gram: FloatArray, column: int, n_samples: int) -> float:
    """:func:`independent_spread_db` of one column of a Gram matrix of ``n_samples`` samples."""
    i = int(column)
    others = np.delete(np.arange(gram.shape[0]), i)
    g = gram[np.ix_(others, others)]
    c = gram[others, i]
    jitter = 1e-9 * max(float(np.mean(np.diag(g))), 1e-300) if others.size else 0.0
    try:
        lower = np.linalg.cholesky(g + jitter * np.eye(others.size))
        from scipy.linalg import blas  # here, not at import: scipy.linalg costs 0.35 s to import

        z = blas.dtrsv(lower, c, lower=1)  # level 2, as in rplearn.core.lsq.selection
        schur = float(gram[i, i] - z @ z)
    except np.linalg.LinAlgError:
        schur = float(gram[i, i] - c @ np.linalg.lstsq(g, c, rcond=None)[0])
    return float(np.sqrt(max(schur, 0.0) / max(int(n_samples), 1)))
