"""Learning patterns from a matched dataset too big for memory, chunk by chunk.

The joint least-squares problem needs only its sufficient statistics (``X^T X``, ``X^T y``,
``y^T y`` and the sample count per link, :class:`~rplearn.core.normal_equations.NormalEquations`),
so a dataset can be read a chunk at a time: each chunk is checked, turned into link samples,
accumulated and dropped. The solve, the training RMSE (from the statistics) and the model are
the same as :func:`rplearn.models.fit.solve_patterns` gives on the whole dataset, to rounding.

Only pattern models (SH, BG, P) stream; the baselines need every sample (the mean model could,
k-NN stores them).
"""

from __future__ import annotations

import time
from collections import Counter
from dataclasses import dataclass
from typing import Any, Iterable, Mapping, Sequence

import numpy as np
import pandas as pd

from rplearn.core.environment import PathLoss
from rplearn.core.normal_equations import NormalEquations
from rplearn.models.terms import regression_inputs, shared_fields, statistics_counts
from rplearn.core.selection import penalty_scale, penalty_vector
from rplearn.core.solver import FitReport, solve
from rplearn.data.tables import LinkSamples, link_samples, node_ids
from rplearn.errors import InputError
from rplearn.models.fit import node_coverage_grids
from rplearn.models.patterns import PatternSet
from rplearn.models.spec import ModelSpec


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
    """Median of values given with their counts (the carrier frequencies of a dataset) [Hz]."""
    if not counts:
        return None
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
    """Rows per distinct ``(unit, tx, rx)`` of a dataset read in chunks of those columns only.

    A small table (one row per unit and link direction, column ``n`` the rows) from which
    units, nodes and the model size are checked before the data are read in full.
    """
    parts = []
    for chunk in chunks:
        cols = {c: node_ids(chunk[c]) for c in ("tx", "rx") if c in chunk.columns}
        if "unit" in chunk.columns:
            cols["unit"] = chunk["unit"].astype(str).to_numpy(dtype=object)
        frame = pd.DataFrame(cols)
        parts.append(frame.groupby(list(frame.columns), sort=False, dropna=False).size().rename("n").reset_index())
    if not parts:
        return pd.DataFrame(columns=["tx", "rx", "n"])
    every = pd.concat(parts, ignore_index=True)
    keys = [c for c in every.columns if c != "n"]
    return every.groupby(keys, sort=True, dropna=False)["n"].sum().reset_index()


def _accumulate(
    chunks: Iterable[pd.DataFrame], spec: ModelSpec, nodes: Sequence[str], units: Sequence[str] | None,
    source: str, by_unit: bool, block_rows: int | None = None, path_loss: PathLoss | None = None,
) -> tuple[dict[str, NormalEquations], float | None, int, float, dict[str, list[float]]]:
    """Statistics of the learning rows of every chunk: one accumulator per unit (``by_unit``)
    or one for all; the median frequency, the non-unit quaternions, the time spent [s] and the
    nodes' coverage grids (:func:`rplearn.models.fit.node_coverage_grids`)."""
    if not spec.decouples:
        raise InputError(f"{spec.label}: only pattern models (sh, bg, poly) learn from a stream", param="spec")
    basis = spec.basis()
    path_loss = path_loss or PathLoss()
    stats: dict[str, NormalEquations] = {}
    wanted = None if not units else {str(u) for u in units}
    freq: Counter[float] = Counter()
    non_unit, learn_s, first_row, learn_row, last_t = 0, 0.0, 0, 0, -np.inf
    grids: dict[str, list[float]] | None = None
    for chunk in chunks:
        where = f"{source} (rows {first_row:,} to {first_row + len(chunk) - 1:,})"
        first_row += len(chunk)
        if wanted is not None:
            chunk = chunk[chunk["unit"].astype(str).isin(wanted).to_numpy()]
        if chunk.empty:
            continue
        if block_rows:  # one unit: contiguous stretches of its rows, which must be in time order
            t = chunk["t"].to_numpy(np.float64)
            if t.size and (np.any(np.diff(t) < 0) or t[0] < last_t):
                raise InputError(f"{where}: field t goes backwards; cutting a single flight into time blocks "
                                 "for cross-validation needs rows sorted by time (sort the file, or label units)")
            last_t = float(t[-1]) if t.size else last_t
            block = (learn_row + np.arange(len(chunk))) // block_rows + 1
            labels = np.char.add("block ", block.astype(str))
        elif by_unit and "unit" in chunk.columns:
            labels = chunk["unit"].astype(str).to_numpy()
        else:
            labels = np.full(len(chunk), "all")
        learn_row += len(chunk)
        for label in np.unique(labels):
            part = chunk[labels == label] if by_unit else chunk
            samples = link_samples(part, where, nodes=nodes)
            t0 = time.perf_counter()
            y, env = regression_inputs(samples, path_loss)
            acc = stats.setdefault(str(label), NormalEquations(basis, len(nodes), environment=env is not None))
            acc.add(samples.directions, samples.tx_index, samples.rx_index, y, env)
            learn_s += time.perf_counter() - t0
            non_unit += samples.non_unit_quaternions
            grids = node_coverage_grids(samples, grids)
            frequency_counts(samples, freq)
            if not by_unit:
                break
    if not stats or sum(a.n_samples for a in stats.values()) == 0:
        raise InputError(f"{source}: no samples selected", param="units")
    return stats, weighted_median(freq), non_unit, learn_s, grids or {}


def unit_statistics_streamed(
    chunks: Iterable[pd.DataFrame], spec: ModelSpec, nodes: Sequence[str], units: Sequence[str] | None = None,
    source: str = "dataset", block_rows: int | None = None, path_loss: PathLoss | None = None,
) -> tuple[dict[str, NormalEquations], float | None, int, dict[str, list[float]]]:
    """The statistics of every learning unit of a dataset given in chunks (for ``--degree auto``
    on a big file): ``(statistics by unit, median frequency [Hz], non-unit quaternions,
    coverage grids by node)``. A dataset without a ``unit`` column is one unit, ``"all"``; with
    ``block_rows`` the learning rows are cut into contiguous blocks of that many rows instead
    (cross-validation of a single flight). ``path_loss``: the environment term (its
    log-distance column is accumulated; a two-ray term is subtracted)."""
    stats, f, non_unit, _, grids = _accumulate(chunks, spec, nodes, units, source, by_unit=True, block_rows=block_rows,
                                               path_loss=path_loss)
    return stats, f, non_unit, grids


def fit_patterns_streamed(
    chunks: Iterable[pd.DataFrame],
    spec: ModelSpec,
    nodes: Sequence[str],
    units: Sequence[str] | None = None,
    gauge: str | Mapping[str, Any] = "equal-mean",
    source: str = "dataset",
    path_loss: PathLoss | None = None,
    link_offsets: bool = True,
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
    gauge : str or mapping
        As :func:`rplearn.models.fit.solve_patterns`.
    source : str
        Name of the dataset in messages (a chunk's rows are named by their place in the file).
    path_loss : PathLoss, optional
        The environment term (free space by default; :mod:`rplearn.models.terms`).
    link_offsets : bool
        Learn one electronics offset per link logged in both directions.
    """
    path_loss = path_loss or PathLoss()
    stats, f, non_unit, learn_s, grids = _accumulate(chunks, spec, nodes, units, source, by_unit=False,
                                                     path_loss=path_loss)
    normal = next(iter(stats.values()))
    basis = normal.basis
    t0 = time.perf_counter()
    counts = statistics_counts(normal.directed, nodes)
    links = normal.two_way_links() if link_offsets else []
    if normal.environment or links:
        normal = normal.with_shared(links)
    penalty = None
    if spec.smoothing:
        penalty = penalty_vector(basis, len(nodes), spec.smoothing, penalty_scale(normal.gram, normal.n_pattern_columns))
    sol = solve(normal, list(nodes), ridge=spec.ridge, gauge=gauge, penalty=penalty)
    learn_s += time.perf_counter() - t0
    fields, terms = shared_fields(sol, list(nodes), path_loss, counts)
    training = sol.report.to_dict()
    training.update(terms)
    if spec.smoothing:
        training["smoothing"] = spec.smoothing
    training["coverage_deg"] = grids
    if f is not None:
        training["frequency_hz"] = f
    patterns = PatternSet(
        basis=basis, nodes=tuple(nodes), coef=sol.coef, covariance=sol.covariance,
        gauge=[g.to_dict() for g in sol.report.gauges], training=training, **fields,
    )
    return StreamedFit(patterns, sol.report, normal.n_samples, non_unit, learn_s)


__all__ = ["StreamedFit", "frequency_counts", "fit_patterns_streamed", "unit_statistics_streamed", "units_and_nodes", "weighted_median"]
