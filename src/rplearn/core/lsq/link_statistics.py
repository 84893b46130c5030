"""Products of the feature blocks of links: the work inside :class:`~rplearn.core.lsq.normal_equations.NormalEquations`.

Per link direction, ``Z^T Z`` with ``Z = [f(tx directions), y, extra..., f(rx directions)]``
(:func:`link_statistics`), or for many short links at once (:func:`segmented_link_statistics`),
through a float64 block buffer kept per thread, in blocks of samples that two worker threads
compute ahead: both owned by :data:`~rplearn.core.lsq.runtime.DEFAULT_RUNTIME`.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from rplearn.core.bases import Basis
from rplearn.core.geometry import Directions
from rplearn.core.lsq.runtime import DEFAULT_RUNTIME

FloatArray = NDArray[np.float64]

#: Samples per feature sub-chunk (fits the CPU cache) and per accumulation block.
FEATURE_CHUNK = 4096
BLOCK_SAMPLES = 65536
#: The block buffer holds at most this many values (64 MiB): high orders take fewer samples per
#: block (SH-24, 1,155 rows: about 7,000), so the buffer kept between fits stays bounded
#: (it was 0.6 GB after one SH-24 fit).
BLOCK_MAX_VALUES = 8 * 2**20


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
    DEFAULT_RUNTIME.block_buffer(rows * max(1, min(int(n_samples), block_samples(rows))))


def _fill_features(
    basis: Basis,
    buf: FloatArray,
    directions: Directions,
    moments: Any,
    gap: int = 1,
    segments: tuple[NDArray[np.intp], NDArray[np.intp]] | None = None,
) -> None:
    """Write tx features into rows ``0 .. p-1`` and rx features into rows ``p+gap .. 2p+gap-1`` of ``buf``
    (the features of ``directions.az_tx, el_tx`` and of ``directions.az_rx, el_rx``).

    Rows are in the basis's :attr:`~rplearn.core.bases.Basis.row_order`; rows ``p .. p+gap-1``
    are left for the observations and extra columns. Works in cache-sized chunks; a basis that
    accepts stacked samples computes both ends of a chunk in one pass, through a (p, 2, chunk)
    strided view of the two row groups, and adds to ``moments[0]`` (tx) and ``moments[1]`` (rx)
    when given: per range of samples when ``segments`` (bounds of the tx ranges, of the rx
    ranges) are given, see :meth:`~rplearn.core.sh.SphericalHarmonics.design_rows_into`.
    """
    az_tx, el_tx, az_rx, el_rx = directions
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
            local = None if segments is None else tuple(np.clip(b - s, 0, e - s) for b in segments)
            basis.design_rows_into(az_both[:, s:e], el_both[:, s:e], both, moments, local)
        else:
            basis.design_rows_into(az_tx[s:e], el_tx[s:e], view[:p])
            basis.design_rows_into(az_rx[s:e], el_rx[s:e], view[p + gap : 2 * p + gap])


#: Runs of samples whose rows :func:`link_statistics` and :func:`segmented_link_statistics` also
#: sum (``(starts, sums)``: the first sample of every run, strictly ascending from 0, and a zeroed
#: array of shape ``(runs, rows)`` the sums of each run's rows ``[f_tx, y, extra, f_rx]``, features
#: in the basis's row order, are added to): a time block's sums of its features, observations and
#: count (the runs of samples of one link in one block of time,
#: :class:`~rplearn.core.lsq.block_sums.BlockSums`). With Gram moments (SH) the feature sums come
#: from each run's moments (:meth:`~rplearn.core.sh.SphericalHarmonics.sums_from_moments`), kept
#: per run instead of per range: no pass over the feature rows of their own.
RunSums = tuple[NDArray[np.intp], FloatArray]


def run_sums_in(buf: FloatArray, starts: NDArray[np.intp], start: int, stop: int) -> tuple[int, FloatArray]:
    """The sums of the rows of ``buf`` (the samples ``start:stop`` of a link, one per column)
    over the parts of the runs beginning at ``starts`` (strictly ascending, ``starts[0] == 0``)
    that fall in them: the index of the first run, and the sums, shape ``(runs there, rows)``."""
    first, local = _local_runs(starts, start, stop)
    return first, np.add.reduceat(buf, local, axis=1).T


def _local_runs(starts: NDArray[np.intp], start: int, stop: int) -> tuple[int, NDArray[np.intp]]:
    """The first run of ``starts`` in the samples ``start:stop`` and the starts of the runs' parts
    there, from 0."""
    first = int(np.searchsorted(starts, start, side="right")) - 1
    last = int(np.searchsorted(starts, stop, side="left"))
    return first, (np.maximum(starts[first:last], start) - start).astype(np.intp)


def _moment_run_sums(basis: Basis, buf: FloatArray, moments: tuple[FloatArray, FloatArray], local: NDArray[np.intp],
                     gap: int) -> FloatArray:
    """Each run's sums of the rows ``[f_tx, y, extra, f_rx]`` of ``buf``: the features' from the
    runs' moments (tx, rx), the ``gap`` rows of ``y`` and the extra columns summed directly."""
    p = basis.n_coef
    return np.concatenate([basis.sums_from_moments(moments[0]), np.add.reduceat(buf[p:p + gap], local, axis=1).T,
                           basis.sums_from_moments(moments[1])], axis=1)


def link_statistics(
    basis: Basis,
    az_tx: FloatArray,
    el_tx: FloatArray,
    az_rx: FloatArray,
    el_rx: FloatArray,
    y: FloatArray,
    extra: FloatArray | None = None,
    runs: RunSums | None = None,
) -> FloatArray:
    """``Z^T Z`` with ``Z = [f(tx directions), y, extra..., f(rx directions)]`` over samples of one link.

    A ``(2p + 1 + m, 2p + 1 + m)`` matrix (``m`` rows of ``extra``, shape ``(m, n)``: shared
    regressors such as a constant or the log-distance column), features in the basis's row
    order: the tx and rx blocks of ``X^T X``, ``X^T y``, ``y^T y`` and the extra columns'
    products. Per block of :func:`block_samples` samples, written into this thread's reused
    buffer, either one symmetric rank-k update of all rows, or, for a basis with Gram moments
    (SH), only the product ``[f_tx; y; extra] [y; extra; f_rx]^T`` (about half the work): the
    two diagonal feature blocks then come from the moments. (Many links at once:
    :func:`segmented_link_statistics`.) ``runs`` (:data:`RunSums`): also each run's sums of the
    rows ``[f_tx, y, extra, f_rx]``, from the same block buffer.
    """
    az_tx, el_tx, az_rx, el_rx, y = (np.ascontiguousarray(a, np.float64).ravel() for a in (az_tx, el_tx, az_rx, el_rx, y))
    p = basis.n_coef
    n = az_tx.size
    extra = np.zeros((0, n)) if extra is None else np.asarray(extra, np.float64).reshape(-1, n)
    m = extra.shape[0]
    gap = 1 + m  # rows between the tx and rx feature groups: y and the extra rows
    k = 2 * p + gap
    use_moments = basis.moment_shape is not None and basis.stacked_samples
    total = np.zeros((k, k))
    if not use_moments:  # one symmetric product per block, in this thread
        per_block = block_samples(k)
        block = DEFAULT_RUNTIME.block_buffer(k * max(1, min(n, per_block)))  # grows to the largest block seen, within the cap
        for start in range(0, n, per_block):
            stop = min(n, start + per_block)
            buf = block[: k * (stop - start)].reshape(k, stop - start)
            part = slice(start, stop)
            _fill_features(basis, buf, Directions(az_tx[part], el_tx[part], az_rx[part], el_rx[part]), None, gap)
            buf[p] = y[part]
            if m:
                buf[p + 1 : p + gap] = extra[:, part]
            total += buf @ buf.T
            if runs is not None:
                first, sums = run_sums_in(buf, runs[0], start, stop)
                runs[1][first:first + sums.shape[0]] += sums
        return total
    shape = basis.moment_shape
    assert shape is not None
    moments = np.zeros((2, *shape))
    per_block = pipelined_block_samples(k, n)

    def statistics(start: int) -> tuple[FloatArray, FloatArray, tuple[int, FloatArray] | None]:
        """The cross product, the moments and the runs' sums of the block of samples from
        ``start`` (in any thread: its own block buffer and feature scratch)."""
        stop = min(n, start + per_block)
        block = DEFAULT_RUNTIME.block_buffer(k * per_block)
        buf = block[: k * (stop - start)].reshape(k, stop - start)
        part = slice(start, stop)
        directions = Directions(az_tx[part], el_tx[part], az_rx[part], el_rx[part])
        if runs is None:
            own = np.zeros((2, *shape))
            _fill_features(basis, buf, directions, own, gap)
        else:  # the moments per run (their sums the run's feature sums), then summed
            first, local = _local_runs(runs[0], start, stop)
            bounds = np.r_[local, stop - start].astype(np.intp)
            per_run = (np.zeros((local.size, *shape)), np.zeros((local.size, *shape)))
            _fill_features(basis, buf, directions, per_run, gap, (bounds, bounds))
            own = np.stack([per_run[0].sum(axis=0), per_run[1].sum(axis=0)])
        buf[p] = y[part]
        if m:
            buf[p + 1 : p + gap] = extra[:, part]
        sums = None if runs is None else (first, _moment_run_sums(basis, buf, per_run, local, gap))
        return buf[: p + gap] @ buf[p:].T, own, sums

    # blocks computed ahead by the runtime's workers (features and product of a block on one
    # core each), added here in order: the sums do not depend on which thread made a block
    for product, own, part_sums in DEFAULT_RUNTIME.in_order(statistics, range(0, n, per_block)):
        total[: p + gap, p:] += product
        moments += own
        if runs is not None and part_sums is not None:  # a run split between blocks: both parts added here
            first, sums = part_sums
            runs[1][first:first + sums.shape[0]] += sums
    total[p:, : p + gap] = total[: p + gap, p:].T
    total[:p, :p] = basis.gram_from_moments(moments[0])
    total[p + gap :, p + gap :] = basis.gram_from_moments(moments[1])
    return total


#: Fewest samples per block when a link's samples are split for the workers: a block's product
#: then keeps a long inner dimension, and a short link (a flight unit of the automatic fit:
#: about 19,000 samples at SH-15, where splitting measured 7% more CPU time) stays one block.
PIPELINE_MIN_BLOCK = 16384


def pipelined_block_samples(rows: int, n_samples: int) -> int:
    """Samples per block of :func:`link_statistics` for a basis with Gram moments: ``n_samples``
    split into two to four equal blocks of at least :data:`PIPELINE_MIN_BLOCK` (computed by the
    two workers of :data:`~rplearn.core.lsq.runtime.DEFAULT_RUNTIME` while earlier ones are
    added), at most :func:`block_samples`; one block when they would be shorter."""
    n = int(n_samples)
    blocks = min(4, n // PIPELINE_MIN_BLOCK)
    if blocks < 2:
        return block_samples(rows)
    return int(min(block_samples(rows), -(-n // blocks)))


def segmented_link_statistics(
    basis: Basis, directions: Directions, y: FloatArray, extra: FloatArray, bounds: NDArray[np.intp],
    natural: NDArray[np.intp] | None = None, tx_bounds: NDArray[np.intp] | None = None, runs: RunSums | None = None,
) -> tuple[FloatArray, tuple[FloatArray, FloatArray]]:
    """:func:`link_statistics` of many links at once, for a basis with Gram moments (SH).

    ``directions`` are those of the samples (``az_tx, el_tx, az_rx, el_rx`` [rad], float64,
    contiguous), ``y`` their observations and ``extra`` the ``m`` shared rows, shape ``(m, n)``.

    The samples (at most :func:`block_samples` of the rows) are sorted by link, link ``j``
    holding samples ``bounds[j]:bounds[j + 1]``. The features of all of them are computed in
    one pass (not one per link: a swarm's links hold a few hundred samples each, too few to
    amortise a pass), then per link the product ``[f_tx; y; extra] [y; extra; f_rx]^T``, and with
    ``runs`` (:data:`RunSums`, runs that do not straddle links) each run's sums of the rows
    ``[f_tx, y, extra, f_rx]`` in the basis's row order.

    Returns
    -------
    products : ndarray, shape (links, p + 1 + m, 1 + m + p)
        Per link, rows ``[f_tx, y, extra]`` times columns ``[y, extra, f_rx]``, features in the
        basis's row order (``m`` rows of ``extra``), or in natural order when ``natural`` (the
        row of each feature) is given.
    moments : tuple of two ndarrays
        Gram moments of the tx directions, shape ``(runs, *basis.moment_shape)``, per range of
        ``tx_bounds`` (by default per link: give the ranges of equal transmitters, fewer and
        longer, when the links are sorted by it), and of each link's rx directions, shape
        ``(links, *basis.moment_shape)``.
    """
    p = basis.n_coef
    n = directions.az_tx.size
    m = extra.shape[0]
    gap = 1 + m
    k = 2 * p + gap
    n_links = bounds.size - 1
    buf = DEFAULT_RUNTIME.block_buffer(k * n)[: k * n].reshape(k, n)
    tx_bounds = bounds if tx_bounds is None else tx_bounds
    shape = basis.moment_shape
    assert shape is not None  # only bases with Gram moments come here
    if runs is None:
        moments = (np.zeros((tx_bounds.size - 1, *shape)), np.zeros((n_links, *shape)))
        _fill_features(basis, buf, directions, moments, gap, (tx_bounds, bounds))
    else:  # the moments per run (their sums the run's feature sums), then summed per range
        cuts = np.r_[runs[0], n].astype(np.intp)
        per_run = (np.zeros((runs[0].size, *shape)), np.zeros((runs[0].size, *shape)))
        _fill_features(basis, buf, directions, per_run, gap, (cuts, cuts))
        moments = (_ranges_of_runs(per_run[0], runs[0], tx_bounds), _ranges_of_runs(per_run[1], runs[0], bounds))
    buf[p] = y
    buf[p + 1 : p + gap] = extra
    if runs is not None:
        runs[1][:] += _moment_run_sums(basis, buf, per_run, runs[0], gap)
    products = np.empty((n_links, p + gap, gap + p))
    for j in range(n_links):
        a, b = bounds[j], bounds[j + 1]
        np.matmul(buf[: p + gap, a:b], buf[p:, a:b].T, out=products[j])
    if natural is not None:
        rows, cols = np.r_[natural, p:p + gap], np.r_[0:gap, gap + natural]
        products = products[:, rows[:, None], cols[None, :]]
    return products, moments


def _ranges_of_runs(per_run: FloatArray, starts: NDArray[np.intp], bounds: NDArray[np.intp]) -> FloatArray:
    """Per-run values summed over the ranges of ``bounds`` (each run inside one range)."""
    which = np.searchsorted(bounds, starts, side="right") - 1  # non-decreasing: the runs in order
    out = np.zeros((bounds.size - 1, *per_run.shape[1:]))
    ranges, first = np.unique(which, return_index=True)
    out[ranges] = np.add.reduceat(per_run, first, axis=0)
    return out


def block_starts(bounds: NDArray[np.intp], per_block: int, max_links: int) -> list[int]:
    """Starts of the blocks of samples sorted by link (link ``j`` holds samples
    ``bounds[j]:bounds[j + 1]``): at most ``per_block`` samples and about ``max_links`` links
    each (the per-link products of a block, ``links x (p + 1 + m)^2`` values, stay bounded
    however short the links are)."""
    n = int(bounds[-1])
    cuts = set(range(0, n, per_block)) | {int(b) for b in bounds[: -1 : max(1, max_links)]}
    return sorted(c for c in cuts if c < n)


def max_links_per_block(basis: Basis, n_extra: int) -> int:
    """Links per block that keep a block's products within a quarter of :data:`BLOCK_MAX_VALUES`."""
    side = basis.n_coef + 1 + n_extra
    return max(1, BLOCK_MAX_VALUES // (4 * side * side))


__all__ = ["BLOCK_MAX_VALUES", "BLOCK_SAMPLES", "FEATURE_CHUNK", "PIPELINE_MIN_BLOCK", "RunSums", "block_rows", "block_samples",
           "block_starts", "link_statistics", "max_links_per_block", "pipelined_block_samples",
           "reserve_block_buffer", "run_sums_in", "segmented_link_statistics"]
