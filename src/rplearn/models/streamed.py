"""Learning patterns from a matched dataset too big for memory, chunk by chunk.

The joint least-squares problem needs only its sufficient statistics (``X^T X``, ``X^T y``,
``y^T y`` and the sample count per link, :class:`~rplearn.core.lsq.normal_equations.NormalEquations`),
so a dataset can be read a chunk at a time: each chunk is checked, turned into link samples,
accumulated and dropped. The solve, the training RMSE (from the statistics) and the model are
the same as :func:`rplearn.models.fit.solve_patterns` gives on the whole dataset, to rounding.

A dataset in many files (:mod:`rplearn.io.partitions`) is accumulated part by part: each
part's statistics (:func:`part_statistics`) add up in the parts' order (:meth:`Accumulated.merge`,
:func:`accumulate_parts`) to what one pass over all of them gives; :mod:`rplearn.workflows.fleet`
runs the same per-part work on a Dask cluster.

Rows that repeat an earlier row in every column are refused as the whole-dataset check refuses
them (:func:`rplearn.data.tables.validate_matched`: the same file, count and first row), wherever
the copies are: in another chunk of a file, or in another part, met when the parts' statistics
are merged (:mod:`rplearn.data.row_copies`: every row's 64-bit hash travels with
:class:`Accumulated`, 8 bytes a row).

The automatic fit's statistics (one per unit, ``by_unit``) keep each sample's 5-s time block
too (:attr:`NormalEquations.block_directed`, :func:`~rplearn.core.lsq.block_sums.time_block_labels` as
:func:`rplearn.models.auto.fit_auto` labels them), from the rows the pass computes anyway: a
block's sums are added up by its label over chunks, parts and Dask tasks, so a block cut by a
chunk or file boundary, or parts read out of order, give the in-memory fit's drifting error
(``training.drift_std_db``). Their memory grows with the flight's duration, not its rows: one
vector of ``2 q + 3`` numbers per unit, block and directed link with samples in it, ``q`` the
coefficients the drift is read at (``NormalEquations.block_coefs``: SH-10's 100 whatever the
largest order, 1.6 kB a vector, against 3.6 kB at SH-15; an hour of one link both ways, 1,440
vectors, 2.3 MB).

The flight's layout (the nodes that held still, the radio's packet rate: ``training.fixed_nodes``,
``training.packet_rate_hz``, which the next flight's plan is made for) is summed up chunk by chunk
too, in a bounded :class:`~rplearn.data.flight_layout.LayoutSketch` (at most
:data:`~rplearn.data.flight_layout.LAYOUT_ROWS` rows of poses and a few thousand intervals per
link direction) that merges in the parts' order, and read by the rules of a fit in memory.

Only pattern models (SH, BG, P) stream; the baselines need every sample (the mean model could,
k-NN stores them).
"""

from __future__ import annotations

import copy
import dataclasses
import time
from collections import Counter
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from rplearn.core.lsq.block_sums import time_block_labels
from rplearn.core.lsq.normal_equations import NormalEquations
from rplearn.core.lsq.selection import penalty_scale, penalty_vector
from rplearn.core.lsq.solver import FitReport, solve
from rplearn.core.plausible import check_one_band
from rplearn.data.flight_layout import LayoutSketch
from rplearn.data.row_copies import RowCopies, SourceHashes
from rplearn.data.tables import LinkSamples, link_samples, node_ids
from rplearn.data.units import Stretches
from rplearn.errors import InputError
from rplearn.io.files import iter_parts
from rplearn.io.partitions import Part
from rplearn.models.auto_spread import planning_basis
from rplearn.models.fit import node_coverage_grids, pattern_set_of_solution
from rplearn.models.options import FitOptions
from rplearn.models.patterns import PatternSet
from rplearn.models.spec import ModelSpec
from rplearn.models.terms import regression_inputs, statistics_counts


@dataclass
class StreamedFit:
    """Patterns learned chunk by chunk, and what the stream held.

    Attributes
    ----------
    patterns : PatternSet
    report : FitReport
    n_samples : int
        Learning samples accumulated.
    non_unit_quaternions : int
        Of those, samples with a tx or rx quaternion not of unit norm (normalised).
    learn_s : float
        Time spent accumulating and solving [s], without reading (the LTD).
    """

    patterns: PatternSet
    report: FitReport
    n_samples: int
    non_unit_quaternions: int
    learn_s: float


def weighted_median(counts: Mapping[float, int]) -> float | None:
    """Median of values given with their counts (the carrier frequencies of a dataset) [Hz]; the
    carriers must be of one band (:func:`~rplearn.core.plausible.check_one_band`)."""
    if not counts:
        return None
    check_one_band(counts, "the dataset")
    values = np.array(sorted(counts), np.float64)
    weights = np.array([counts[v] for v in sorted(counts)], np.float64)
    cum = np.cumsum(weights)
    half = cum[-1] / 2.0
    i = int(np.searchsorted(cum, half))
    if cum[i] == half and i + 1 < values.size:  # an even count split between two values
        return float((values[i] + values[i + 1]) / 2.0)
    return float(values[i])


def frequency_counts(samples: LinkSamples, counts: Counter[float] | None = None) -> Counter[float]:
    """Samples per carrier frequency [Hz], added to ``counts`` (for :func:`weighted_median`)."""
    counts = Counter() if counts is None else counts
    if samples.frequency_hz is not None:
        values, n = np.unique(samples.frequency_hz, return_counts=True)
        counts.update(dict(zip(values.tolist(), n.tolist())))
    return counts


def units_and_nodes(chunks: Iterable[pd.DataFrame]) -> pd.DataFrame:
    """Rows per distinct ``(unit, tx, rx, frequency_hz)`` of a dataset read in chunks of those columns only.

    A small table (one row per unit and link direction, column ``n`` the rows) from which
    units, nodes and the model size are checked before the data are read in full.
    """
    parts = []
    for chunk in chunks:
        cols = {c: node_ids(chunk[c]) for c in ("tx", "rx") if c in chunk.columns}
        if "unit" in chunk.columns:
            cols["unit"] = chunk["unit"].astype(str).to_numpy(dtype=object)
        if "frequency_hz" in chunk.columns:  # the bands, checked before any statistics
            cols["frequency_hz"] = pd.to_numeric(chunk["frequency_hz"], errors="coerce").to_numpy(np.float64)
        frame = pd.DataFrame(cols)
        parts.append(frame.groupby(list(frame.columns), sort=False, dropna=False).size().rename("n").reset_index())
    if not parts:
        return pd.DataFrame(columns=["tx", "rx", "n"])
    every = pd.concat(parts, ignore_index=True)
    keys = [c for c in every.columns if c != "n"]
    return every.groupby(keys, sort=True, dropna=False)["n"].sum().reset_index()


@dataclass
class Accumulated:
    """The statistics of the learning rows of some chunks, and what they held.

    Several accumulations (the parts of a partitioned dataset, computed anywhere) add up with
    :meth:`merge`, in the order of the rows, to what one pass over all of them gives.

    Attributes
    ----------
    stats : dict of str to NormalEquations
        One accumulator per learning unit (or time block), or ``{"all": ...}``.
    freq : Counter
        Samples per carrier frequency [Hz].
    non_unit : int
        Samples with a non-unit quaternion.
    learn_s : float
        Time spent turning samples into statistics [s].
    grids : dict of str to list of float, or None
        Coverage grids by node (None before any sample).
    source : str
        Where the rows came from (in messages).
    copies : RowCopies, optional
        Every row's hash and the rows repeating earlier ones (:mod:`rplearn.data.row_copies`),
        refused by :func:`checked`.
    layout : LayoutSketch
        The learning rows' layout (who held still, the packet rate), bounded
        (:class:`~rplearn.data.flight_layout.LayoutSketch`).
    """

    stats: dict[str, NormalEquations]
    freq: Counter[float]
    non_unit: int = 0
    learn_s: float = 0.0
    grids: dict[str, list[float]] | None = None
    source: str = "dataset"
    copies: RowCopies | None = None
    layout: LayoutSketch = field(default_factory=LayoutSketch)

    @property
    def n_samples(self) -> int:
        return sum(a.n_samples for a in self.stats.values())

    def merge(self, later: Accumulated) -> Accumulated:
        """Add the accumulation of rows that follow these (in place; returns self)."""
        for label, acc in later.stats.items():
            if label in self.stats:
                self.stats[label].merge(acc)
            else:
                self.stats[label] = acc
        self.freq.update(later.freq)
        self.non_unit += later.non_unit
        self.learn_s += later.learn_s
        if later.grids is not None:
            self.grids = later.grids if self.grids is None else {
                k: np.minimum(np.asarray(v), np.asarray(later.grids[k])).tolist() for k, v in self.grids.items()}
        self.source = self.source if self.source == later.source else f"{self.source}, ..."
        if later.copies is not None:
            self.copies = later.copies if self.copies is None else self.copies.then(later.copies)
        self.layout.merge(later.layout)
        return self

    def combined(self, later: Accumulated) -> Accumulated:
        """A new accumulation of these rows then ``later``'s; neither input changes (a task on
        a cluster must not change the stored results of others, which may be reused)."""
        return copy.deepcopy(self).merge(copy.deepcopy(later))


def accumulate(
    chunks: Iterable[pd.DataFrame], spec: ModelSpec, nodes: Sequence[str], units: Sequence[str] | None,
    source: str, by_unit: bool, stretches: Stretches | None = None, options: FitOptions | None = None,
) -> Accumulated:
    """Statistics of the learning rows of every chunk: one accumulator per unit (``by_unit``)
    or one for all, or per stretch of time of a single flight (``stretches``, the folds of its
    cross-validation; rows in any order), with the environment term of ``options`` (its
    log-distance column accumulated, a two-ray term subtracted). ``by_unit`` (the automatic
    fit's folds) also keeps each sample's time block (module docstring). An empty result is
    allowed (a part without learning rows); see :func:`checked`.

    Every row of the chunks (of any unit) is hashed, and copies of earlier rows recorded in
    :attr:`Accumulated.copies` (refused by :func:`checked` with the whole-dataset message); a
    chunk is no longer learned from once a copy has been seen."""
    if not spec.decouples:
        raise InputError(f"{spec.label}: only pattern models (sh, bg, poly) learn from a stream", param="spec")
    basis = spec.basis()
    block_coefs = planning_basis(basis).n_coef  # the blocks' sums: only what the drift reads
    options = options or FitOptions()
    out = Accumulated({}, Counter(), source=source)
    wanted = None if not units else {str(u) for u in units}
    first_row = 0
    hashes = SourceHashes(source)
    for chunk in chunks:
        where = f"{source} (rows {first_row:,} to {first_row + len(chunk) - 1:,})"
        first_row += len(chunk)
        if hashes.add(chunk):  # a copy: refused by checked with the count over the whole source
            continue
        if wanted is not None:
            chunk = chunk[chunk["unit"].astype(str).isin(wanted).to_numpy()]
        if chunk.empty:
            continue
        out.layout.merge(LayoutSketch.of_rows(chunk))  # the rows a fit in memory reads its layout from
        t = chunk["t"].to_numpy(np.float64) if "t" in chunk.columns else np.zeros(0)  # link_samples names a missing t
        if stretches is not None and t.size:  # one unit: its contiguous stretches of time
            labels = stretches.label(t).astype(str)
        elif by_unit and "unit" in chunk.columns:
            labels = chunk["unit"].astype(str).to_numpy()
        else:
            labels = np.full(len(chunk), "all")
        for label in np.unique(labels):
            part = chunk[labels == label] if by_unit else chunk
            samples = link_samples(part, where, nodes=nodes)
            t0 = time.perf_counter()
            y, env = regression_inputs(samples, options)
            acc = out.stats.setdefault(str(label), NormalEquations(basis, len(nodes), environment=env is not None,
                                                                   block_coefs=block_coefs))
            # the automatic fit's folds: each sample's time block too, as rplearn.models.auto.fit_auto
            # keeps them (the drifting error, training.drift_std_db), merged by label across chunks
            blocks = None if not by_unit or samples.t_s is None else time_block_labels(samples.t_s)
            acc.add(samples.directions, samples.tx_index, samples.rx_index, y, env, time_block=blocks)
            out.learn_s += time.perf_counter() - t0
            out.non_unit += samples.non_unit_quaternions
            out.grids = node_coverage_grids(samples, out.grids)
            frequency_counts(samples, out.freq)
            if not by_unit:
                break
    out.copies = hashes.finish()
    return out


#: Rows read at a time from one part of a dataset.
PART_CHUNK_ROWS = 500_000


def part_statistics(
    part: Part, spec: ModelSpec, nodes: Sequence[str], units: Sequence[str] | None, by_unit: bool,
    stretches: Stretches | None = None, options: FitOptions | None = None,
) -> Accumulated:
    """:func:`accumulate` over one part of a dataset, read :data:`PART_CHUNK_ROWS` rows at a
    time (its rows named by their place in its file); ``options`` as :func:`accumulate`."""
    return accumulate(iter_parts([part], PART_CHUNK_ROWS), spec, nodes, units, part.path, by_unit, stretches,
                      options)


def accumulate_parts(
    parts: Sequence[Part], spec: ModelSpec, nodes: Sequence[str], units: Sequence[str] | None, by_unit: bool,
    stretches: Stretches | None = None, options: FitOptions | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> Accumulated:
    """The statistics of every part (:func:`part_statistics`), added in the parts' order, in
    this process; ``progress(done, parts)`` after each part. ``stretches`` (of a single flight)
    label each row by its stretch of time wherever it is read. An empty result is allowed
    (see :func:`checked`)."""
    total = Accumulated({}, Counter(), source=parts[0].path if parts else "dataset")
    for k, part in enumerate(parts):
        acc = part_statistics(part, spec, nodes, units, by_unit, stretches, options)
        total = acc if k == 0 else total.merge(acc)
        if progress is not None:
            progress(k + 1, len(parts))
    return total


def checked(acc: Accumulated, source: str) -> Accumulated:
    """``acc`` without its row hashes, or an error when rows repeat earlier rows (the message of
    :func:`~rplearn.data.tables.validate_matched`, naming the file and row) or it holds no sample."""
    refusal = None if acc.copies is None else acc.copies.error()
    if refusal is not None:
        raise refusal
    acc = dataclasses.replace(acc, copies=None)  # 8 bytes a row, not needed by the solve
    if not acc.stats or acc.n_samples == 0:
        raise InputError(f"{source}: no samples selected", param="units")
    check_one_band(acc.freq, source)  # every part of one band
    return acc


def unit_statistics_streamed(
    chunks: Iterable[pd.DataFrame], spec: ModelSpec, nodes: Sequence[str], units: Sequence[str] | None = None,
    source: str = "dataset", stretches: Stretches | None = None, options: FitOptions | None = None,
) -> tuple[dict[str, NormalEquations], float | None, int, dict[str, list[float]]]:
    """The statistics of every learning unit of a dataset given in chunks (for ``--order auto``
    on a big file): ``(statistics by unit, median frequency [Hz], non-unit quaternions,
    coverage grids by node)``. A dataset without a ``unit`` column is one unit, ``"all"``; with
    ``stretches`` the learning rows are cut into those stretches of time instead
    (cross-validation of a single flight, :class:`rplearn.data.units.Stretches`). ``options``: as :func:`accumulate`."""
    acc = checked(accumulate(chunks, spec, nodes, units, source, by_unit=True, stretches=stretches,
                             options=options), source)
    return acc.stats, weighted_median(acc.freq), acc.non_unit, acc.grids or {}


def fit_patterns_streamed(
    chunks: Iterable[pd.DataFrame],
    spec: ModelSpec,
    nodes: Sequence[str],
    units: Sequence[str] | None = None,
    options: FitOptions | None = None,
    source: str = "dataset",
) -> StreamedFit:
    """Learn one pattern per node from a dataset given in chunks (see the module docstring).

    Parameters
    ----------
    chunks : iterable of DataFrame
        The matched dataset, a chunk at a time (e.g. :func:`rplearn.io.files.iter_table`).
    spec : ModelSpec
        A pattern model (SH, BG or P).
    nodes : sequence of str
        Node ids in model order: those of the learning samples (:func:`units_and_nodes`).
        Check the model size first (:func:`~rplearn.models.spec.check_model_size`), with the
        sample count :func:`units_and_nodes` gives.
    units : sequence of str, optional
        Learning units; every row when None.
    options : FitOptions, optional
        Gauge, environment term and link offsets, as :func:`rplearn.models.fit.solve_patterns`.
    source : str
        Name of the dataset in messages (a chunk's rows are named by their place in the file).
    """
    acc = checked(accumulate(chunks, spec, nodes, units, source, by_unit=False, options=options), source)
    return fit_patterns_accumulated(acc, spec, nodes, options)


def fit_patterns_accumulated(
    acc: Accumulated, spec: ModelSpec, nodes: Sequence[str], options: FitOptions | None = None,
) -> StreamedFit:
    """:func:`fit_patterns_streamed` from statistics already accumulated (one label), e.g.
    merged from the parts of a dataset computed on a cluster."""
    options = options or FitOptions()
    stats, f, non_unit, learn_s, grids = acc.stats, weighted_median(acc.freq), acc.non_unit, acc.learn_s, acc.grids or {}
    if len(stats) != 1:
        raise InputError(f"expected the statistics of all learning rows together, got {len(stats)} labels", param="spec")
    normal = next(iter(stats.values()))
    basis = normal.basis
    t0 = time.perf_counter()
    counts = statistics_counts(normal.directed, nodes)
    links = normal.two_way_links() if options.link_offsets else []
    if normal.environment or links:
        normal = normal.with_shared(links)
    penalty = None
    if spec.smoothing:
        penalty = penalty_vector(basis, len(nodes), spec.smoothing, penalty_scale(normal.gram, normal.n_pattern_columns))
    sol = solve(normal, list(nodes), ridge=spec.ridge_weight, gauge=options.gauge, penalty=penalty)
    learn_s += time.perf_counter() - t0
    entries = {"coverage_deg": grids, **({} if f is None else {"frequency_hz": f})}
    patterns = pattern_set_of_solution(sol, spec, basis, list(nodes), options, counts, entries)
    patterns.training = patterns.training.replace(**acc.layout.recorded())  # as a fit in memory records them
    return StreamedFit(patterns, sol.report, normal.n_samples, non_unit, learn_s)


__all__ = ["PART_CHUNK_ROWS", "Accumulated", "StreamedFit", "accumulate", "accumulate_parts", "checked", "fit_patterns_accumulated",
           "frequency_counts", "fit_patterns_streamed", "part_statistics", "unit_statistics_streamed", "units_and_nodes", "weighted_median"]
