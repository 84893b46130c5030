"""Sufficient statistics of the joint least-squares problem, accumulated in chunks (paper Sec. V-A).

Each signal sample ``i`` names its transmitter ``t_i`` and receiver ``r_i`` and observes the joint
gain ``y_i = G_t(az_tx_i, el_tx_i) + G_r(az_rx_i, el_rx_i) + noise`` (paper eq. 5). With every
pattern a linear combination of the same basis, ``G_n = f(az, el) . p_n``, the row of sample
``i`` in the design matrix holds ``f(az_tx, el_tx)`` in the block of node ``t_i``,
``f(az_rx, el_rx)`` in the block of ``r_i`` and zeros elsewhere (the paper's Sec. V-A matrix).

The design matrix is never formed: :class:`NormalEquations` accumulates ``X^T X``, ``X^T y``,
``y^T y`` and ``n`` chunk by chunk, one link direction at a time (:func:`link_statistics`),
through a block buffer reused by later fits in the same thread, so memory does not grow with
the number of samples. :mod:`rplearn.core.solver` solves the result.
"""

from __future__ import annotations

import threading
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from rplearn.core.bases import Basis
from rplearn.core.geometry import Directions
from rplearn.errors import InputError

FloatArray = NDArray[np.float64]

#: Samples per feature sub-chunk (fits the CPU cache) and per accumulation block.
FEATURE_CHUNK = 4096
BLOCK_SAMPLES = 65536
#: The block buffer holds at most this many values (64 MiB): high orders take fewer samples per
#: block (SH-24, 1,155 rows: about 7,000), so the buffer kept between fits stays bounded
#: (it was 0.6 GB after one SH-24 fit).
BLOCK_MAX_VALUES = 8 * 2**20


#: The path-loss exponent is refused as not identifiable when the part of its log-distance
#: column ``10 log10 d`` that the other columns (the patterns) cannot explain has a standard
#: deviation below this [dB]: the distance then varies by less than about +-12% independently
#: of the directions (a flight at constant distance, or at constant altitude over a static
#: station), one unit of exponent moves the gain less than a pattern's misfit does, and the
#: patterns could take any exponent.
EXPONENT_MIN_SPREAD_DB = 0.5

_BUFFERS = threading.local()


def _block_buffer(size: int) -> FloatArray:
    """A float64 scratch buffer of at least ``size`` values, reused by later fits in this thread.

    Fresh memory is slow on first touch (one page fault per 4 KiB; measured 20-30 ms for the
    52 MB block of an SH-10 fit on this kind of machine), so the block buffer is kept.
    """
    buf = getattr(_BUFFERS, "block", None)
    if buf is None or buf.size < size:
        _BUFFERS.block = None  # let the old one go first
        buf = np.empty(size)
        buf.fill(0.0)  # pay the page faults now, once, not inside the first rank-k update
        _BUFFERS.block = buf
    return buf[:size]


def block_samples(rows: int) -> int:
    """Samples per accumulation block of ``rows`` rows (:data:`BLOCK_SAMPLES`, fewer for big bases)."""
    return int(max(256, min(BLOCK_SAMPLES, BLOCK_MAX_VALUES // max(int(rows), 1))))


def block_rows(basis: Basis, n_extra: int = 2) -> int:
    """Rows of the accumulation block of :func:`link_statistics` for this basis (with the
    ``n_extra`` rows :class:`NormalEquations` adds: a constant and the environment column)."""
    return 2 * basis.n_coef + 1 + n_extra


def reserve_block_buffer(basis: Basis, n_samples: int) -> None:
    """Allocate (and touch) this thread's block buffer for a fit of ``n_samples`` samples.

    Called before a timed fit so that its learning time does not include the one-off page
    faults of the buffer (measured 0.2 s for the first SH-10 fit of the paper's 56k samples).
    """
    rows = block_rows(basis)
    _block_buffer(rows * max(1, min(int(n_samples), block_samples(rows))))


def _fill_features(
    basis: Basis,
    buf: FloatArray,
    az_tx: FloatArray,
    el_tx: FloatArray,
    az_rx: FloatArray,
    el_rx: FloatArray,
    moments: FloatArray | None,
    gap: int = 1,
) -> None:
    """Write tx features into rows ``0 .. p-1`` and rx features into rows ``p+gap .. 2p+gap-1`` of ``buf``.

    Rows are in the basis's :attr:`~rplearn.core.bases.Basis.row_order`; rows ``p .. p+gap-1``
    are left for the observations and extra columns. Works in cache-sized chunks; a basis that
    accepts stacked samples computes both ends of a chunk in one pass, through a (p, 2, chunk)
    strided view of the two row groups, and adds to ``moments[0]`` (tx) and ``moments[1]`` (rx)
    when given.
    """
    p = basis.n_coef
    n = az_tx.size
    if basis.stacked_samples:
        az_both = np.stack([az_tx, az_rx])
        el_both = np.stack([el_tx, el_rx])
    for s in range(0, n, FEATURE_CHUNK):
        e = min(n, s + FEATURE_CHUNK)
        view = buf[:, s:e]
        if basis.stacked_samples:
            both = np.lib.stride_tricks.as_strided(
                view, shape=(p, 2, e - s), strides=(view.strides[0], (p + gap) * view.strides[0], view.strides[1])
            )
            basis.design_rows_into(az_both[:, s:e], el_both[:, s:e], both, moments)
        else:
            basis.design_rows_into(az_tx[s:e], el_tx[s:e], view[:p])
            basis.design_rows_into(az_rx[s:e], el_rx[s:e], view[p + gap : 2 * p + gap])


def link_statistics(
    basis: Basis,
    az_tx: FloatArray,
    el_tx: FloatArray,
    az_rx: FloatArray,
    el_rx: FloatArray,
    y: FloatArray,
    extra: FloatArray | None = None,
    moments_out: FloatArray | None = None,
) -> FloatArray:
    """``Z^T Z`` with ``Z = [f(tx directions), y, extra..., f(rx directions)]`` over samples of one link.

    A ``(2p + 1 + m, 2p + 1 + m)`` matrix (``m`` rows of ``extra``, shape ``(m, n)``: shared
    regressors such as a constant or the log-distance column), features in the basis's row
    order: the tx and rx blocks of ``X^T X``, ``X^T y``, ``y^T y`` and the extra columns'
    products. Per block of :func:`block_samples` samples, written into this thread's reused
    buffer, either one symmetric rank-k update of all rows, or, for a basis with Gram moments
    (SH), only the product ``[f_tx; y; extra] [y; extra; f_rx]^T`` (about half the work): the
    two diagonal feature blocks then come from the moments. With ``moments_out`` (shape
    ``(2, *basis.moment_shape)``) the moments of the tx and rx ends are added there instead
    and the two diagonal blocks are left zero: a caller with many links turns each node's
    summed moments into its block once (:meth:`NormalEquations.add`).
    """
    az_tx, el_tx, az_rx, el_rx, y = (np.ascontiguousarray(a, np.float64).ravel() for a in (az_tx, el_tx, az_rx, el_rx, y))
    p = basis.n_coef
    n = az_tx.size
    extra = np.zeros((0, n)) if extra is None else np.asarray(extra, np.float64).reshape(-1, n)
    m = extra.shape[0]
    gap = 1 + m  # rows between the tx and rx feature groups: y and the extra rows
    k = 2 * p + gap
    use_moments = basis.moment_shape is not None and basis.stacked_samples
    if use_moments:
        moments = np.zeros((2, *basis.moment_shape)) if moments_out is None else moments_out
    else:
        moments = None
    total = np.zeros((k, k))
    per_block = block_samples(k)
    block = _block_buffer(k * max(1, min(n, per_block)))  # grows to the largest block seen, within the cap
    for start in range(0, n, per_block):
        stop = min(n, start + per_block)
        buf = block[: k * (stop - start)].reshape(k, stop - start)
        part = slice(start, stop)
        _fill_features(basis, buf, az_tx[part], el_tx[part], az_rx[part], el_rx[part], moments, gap)
        buf[p] = y[part]
        if m:
            buf[p + 1 : p + gap] = extra[:, part]
        if moments is None:
            total += buf @ buf.T
        else:
            total[: p + gap, p:] += buf[: p + gap] @ buf[p:].T
    if moments is not None:
        total[p:, : p + gap] = total[: p + gap, p:].T
        if moments_out is None:
            total[:p, :p] = basis.gram_from_moments(moments[0])
            total[p + gap :, p + gap :] = basis.gram_from_moments(moments[1])
    return total


#: Entries of a directed link's sums (:attr:`NormalEquations.directed`) after its two feature
#: blocks: sum of y, sample count, sum of the environment column.
_SUM_Y, _COUNT, _SUM_E = 0, 1, 2


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

    Besides ``X^T X`` and ``X^T y`` of the pattern columns, every directed link keeps the sums
    of its features, observations and environment values (:attr:`directed`), from which
    :meth:`with_shared` appends shared columns (the environment column and one electronics
    offset per link logged both ways) without re-reading samples.
    """

    basis: Basis
    n_nodes: int
    environment: bool = False
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
        for name, arr in (("el_tx", el_tx), ("az_rx", az_rx), ("el_rx", el_rx), ("tx_index", tx), ("rx_index", rx),
                          ("joint_gain_db", y), ("environment", e)):
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
        pair_code = tx.astype(np.int64) * self.n_nodes + rx
        if pair_code.min() == pair_code.max():  # one link direction: no grouping needed
            groups = [(int(pair_code[0]), slice(None))]
        else:  # sorted once by link, each link a contiguous slice (no mask per link)
            order = np.argsort(pair_code, kind="stable")
            sorted_code = pair_code[order]
            az_tx, el_tx, az_rx, el_rx, y, e = (a[order] for a in (az_tx, el_tx, az_rx, el_rx, y, e))
            starts = np.flatnonzero(np.r_[True, sorted_code[1:] != sorted_code[:-1]])
            ends = np.r_[starts[1:], n]
            groups = [(int(sorted_code[a]), slice(int(a), int(b))) for a, b in zip(starts, ends)]
        moment_shape = self.basis.moment_shape if self.basis.stacked_samples else None
        # with Gram moments, each node's diagonal block comes from its summed moments, once per
        # node and chunk, not once per link end
        node_moments: dict[int, FloatArray] | None = {} if moment_shape is not None and len(groups) > 1 else None
        for code, sel in groups:
            t, r = divmod(code, self.n_nodes)
            self._add_pair(t, r, az_tx[sel], el_tx[sel], az_rx[sel], el_rx[sel], y[sel], e[sel], node_moments)
        if node_moments:
            p = self.basis.n_coef
            nat = self._natural[:p]
            for k, m in sorted(node_moments.items()):
                self.gram[k * p : (k + 1) * p, k * p : (k + 1) * p] += self.basis.gram_from_moments(m)[np.ix_(nat, nat)]
            # the links' cross blocks went into the upper block triangle: mirror them
            for a, b in {(min(c // self.n_nodes, c % self.n_nodes), max(c // self.n_nodes, c % self.n_nodes))
                         for c, _ in groups}:
                self.gram[b * p : (b + 1) * p, a * p : (a + 1) * p] = self.gram[a * p : (a + 1) * p, b * p : (b + 1) * p].T
        self.n_samples += n
        return self

    def _add_pair(
        self, t: int, r: int, az_tx: FloatArray, el_tx: FloatArray, az_rx: FloatArray, el_rx: FloatArray, y: FloatArray,
        e: FloatArray, node_moments: dict[int, FloatArray] | None = None,
    ) -> None:
        p = self.basis.n_coef
        bt = slice(t * p, (t + 1) * p)
        br = slice(r * p, (r + 1) * p)
        n = az_tx.size
        key = (min(t, r), max(t, r))
        self.link_counts[key] = self.link_counts.get(key, 0) + n
        # Both nodes' blocks of X^T X, X^T y and y^T y, and the sums of the directed link, from
        # one pass over the samples.
        extra = np.ones((1, n)) if not self.environment else np.stack([np.ones(n), e])
        moments = None
        if node_moments is not None:
            moments = np.zeros((2, *self.basis.moment_shape))
        block = link_statistics(self.basis, az_tx, el_tx, az_rx, el_rx, y, extra, moments)
        if moments is not None:
            for node, m in ((t, moments[0]), (r, moments[1])):
                if node in node_moments:
                    node_moments[node] += m
                else:
                    node_moments[node] = m
            self._add_link_block(t, r, block)
            return
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

    def _add_link_block(self, t: int, r: int, block: FloatArray) -> None:
        """:meth:`_add_pair`'s bookkeeping for a block from the moments path of
        :func:`link_statistics` (rows ``[f_tx, y, extra, f_rx]`` in the basis's row order, the
        diagonal feature blocks left zero): only the parts that are needed are put back into
        natural order, and the cross block goes into the upper block triangle of the Gram
        (:meth:`add` mirrors it)."""
        p = self.basis.n_coef
        m = self._n_extra
        nat = self._natural[:p]
        rx0 = p + 1 + m  # first rx feature row
        cross = block[:p, rx0:][np.ix_(nat, nat)]  # F_tx^T F_rx
        if t < r:
            self.gram[t * p : (t + 1) * p, r * p : (r + 1) * p] += cross
        else:
            self.gram[r * p : (r + 1) * p, t * p : (t + 1) * p] += cross.T
        y_row, one = p, p + 1
        self.rhs[t * p : (t + 1) * p] += block[:p, y_row][nat]
        self.rhs[r * p : (r + 1) * p] += block[y_row, rx0:][nat]
        self.yty += float(block[y_row, y_row])
        sums = np.zeros(2 * p + 3)
        sums[:p] = block[:p, one][nat]
        sums[p : 2 * p] = block[one, rx0:][nat]
        sums[2 * p + _SUM_Y] = block[y_row, one]
        sums[2 * p + _COUNT] = block[one, one]
        if self.environment:
            env = one + 1
            sums[2 * p + _SUM_E] = block[one, env]
            self.env_cross[t * p : (t + 1) * p] += block[:p, env][nat]
            self.env_cross[r * p : (r + 1) * p] += block[env, rx0:][nat]
            self.env_y += float(block[y_row, env])
            self.env_sq += float(block[env, env])
        prev = self.directed.get((t, r))
        self.directed[(t, r)] = sums if prev is None else prev + sums

    def merge(self, other: NormalEquations) -> NormalEquations:
        """Add another accumulator's statistics (same basis, node count and columns) into this one."""
        if other.basis != self.basis or other.n_nodes != self.n_nodes or other.environment != self.environment:
            raise InputError("cannot merge normal equations of different bases, node counts or environment columns")
        if self.shared or other.shared:
            raise InputError("merge statistics before appending shared columns (with_shared)")
        self.gram += other.gram
        self.rhs += other.rhs
        self.yty += other.yty
        self.n_samples += other.n_samples
        for k, v in other.link_counts.items():
            self.link_counts[k] = self.link_counts.get(k, 0) + v
        for k, v in other.directed.items():
            self.directed[k] = v.copy() if k not in self.directed else self.directed[k] + v
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

        z = blas.dtrsv(lower, c, lower=1)  # level 2, as in rplearn.core.selection
        schur = float(gram[i, i] - z @ z)
    except np.linalg.LinAlgError:
        schur = float(gram[i, i] - c @ np.linalg.lstsq(g, c, rcond=None)[0])
    return float(np.sqrt(max(schur, 0.0) / max(int(n_samples), 1)))
