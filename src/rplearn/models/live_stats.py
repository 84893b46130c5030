"""Sufficient statistics of a flight that is still going on, and the refits from them.

``rplearn live`` learns from every matched sample (the prequential error is its test score:
each batch is predicted before it is learned from). Its fit at any moment is the offline fit
of the samples so far with every stretch of time learned from: ``rplearn fit DATA --units
'flight[1/5],flight[2/5],flight[3/5],flight[4/5],test[5/5]'`` (the same stretches,
:class:`rplearn.data.units.Stretches`, as folds of ``--order auto``), or ``--order N``.

The statistics are kept per *segment*, a run of consecutive batches
(:class:`~rplearn.core.lsq.normal_equations.NormalEquations` at the largest candidate order),
at most ``max_segments`` of them: when there are more, the two neighbours with the fewest
samples are added into one, so memory does not grow with the flight's length. A fixed order
needs only their sum.

The folds of ``--order auto`` are stretches of equal sample counts of the *whole* flight, whose
cuts move as samples arrive: no bounded set of statistics gives them exactly for every
length (the first stretch of a flight of ``n`` samples is its first ``n/5``, for any ``n``).
So a refit during the flight gives each segment whole to the stretch of its middle sample,
and the last refit (``final=True``) is exact: it takes the cuts from the times of every
batch (their ``t`` column, read back from the spool) and re-reads the samples of the few
segments a cut falls inside, from the batches spooled to disk as they arrived; every other
segment's statistics are used as they are.

Each batch's per-link sums also go into :class:`~rplearn.core.lsq.block_sums.BlockSums` (time
blocks of ``DEFAULT_BLOCK_S``; memory flat), which :meth:`LiveStatistics.total` hands on as the
statistics' ``blocks``: the next-best manoeuvre ranking reads from them an error that drifts over
seconds (a heading estimate's). A batch spanning several blocks (a whole log matched at the end)
is split into them.

An automatic choice also keeps the sums per time block its drifting error is stated from
(``training.drift_std_db``, as ``fit --order auto`` states it, for the next flight's plan:
:class:`~rplearn.models.live_drift.DriftBlocks`, memory bounded, at SH-10): a refit during the
flight reads every block whole; the last, exact refit counts a block that a stretch's cut falls
in as the offline fit does, one block per stretch (its rows re-read from the spool).

Every batch's matched rows also go into a :class:`~rplearn.data.flight_layout.LayoutSketch`
(bounded: a sample of at most ``LAYOUT_ROWS`` rows' poses, a few thousand intervals per link
direction), from which every refit records the nodes that held still and the radio's packet rate
(``training.fixed_nodes``, ``training.packet_rate_hz``) as ``fit`` records them of the same rows.
"""

from __future__ import annotations

import os
import time
from collections import Counter
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd

from rplearn._argtypes import check_types
from rplearn._atomic import atomic_path
from rplearn.core.lsq.block_sums import MIN_BLOCKS, BlockSums, time_block_labels
from rplearn.core.lsq.normal_equations import NormalEquations
from rplearn.core.lsq.penalty import sub_statistics
from rplearn.core.lsq.selection import at_smoothing_cap
from rplearn.core.threads import blas_threads_for
from rplearn.data.flight_layout import LayoutSketch
from rplearn.data.tables import OUTAGE_COLUMN, LinkSamples, link_samples
from rplearn.data.units import TIME_UNITS, Stretches, stretch_labels
from rplearn.errors import InputError
from rplearn.models.auto import MAX_AUTO_ORDER, auto_orders, fit_from_statistics
from rplearn.models.auto_spread import block_drift_std_db, planning_basis
from rplearn.models.fit import FittedModel
from rplearn.models.live_drift import DriftBlocks, LinkSums, block_link_sums
from rplearn.models.node_coverage import grids_of_occupied, occupied_masks
from rplearn.models.options import FitOptions
from rplearn.models.patterns import PatternSet
from rplearn.models.spec import ModelSpec, default_ridge
from rplearn.models.streamed import Accumulated, fit_patterns_accumulated, frequency_counts, weighted_median
from rplearn.models.terms import regression_inputs

#: Segments of statistics kept at most (each one ``X^T X`` at the accumulation order).
MAX_SEGMENTS = 16


@check_types
@dataclass
class Segment:
    """The statistics of a run of consecutive batches and where their samples are spooled.

    The batches are numbered in order; a segment holds ``n_batches`` of them from
    ``first_batch``, spooled (when ``spool_dir`` is set) named by their number, so
    that what a segment keeps does not grow with its batches.
    """

    normal: NormalEquations
    t_min: float
    t_max: float
    first_batch: int = 0
    n_batches: int = 1
    spool_dir: str | None = None

    @property
    def n_samples(self) -> int:
        return int(self.normal.n_samples)

    @property
    def files(self) -> list[str]:
        """The spooled files of its batches, in order (none without a spool)."""
        if self.spool_dir is None:
            return []
        return [_batch_path(self.spool_dir, k) for k in range(self.first_batch, self.first_batch + self.n_batches)]


def _batch_path(spool_dir: str, batch: int) -> str:
    """The spooled file of batch number ``batch``."""
    return os.path.join(spool_dir, f"batch-{batch:07d}.parquet")


@check_types
class LiveStatistics:
    """Statistics of a live session, added batch by batch, and its refits (module docstring).

    Parameters
    ----------
    spec : ModelSpec
        The model: a pattern model (sh, bg, poly) of fixed order, or the kind and ridge of an
        automatic choice (``options.auto``).
    nodes : sequence of str
        Node ids in model order (sorted, as ``fit`` orders them).
    options : FitOptions, optional
        As ``fit``; ``auto=True`` chooses the order and smoothing.
    spool_dir : str, optional
        Folder for the batches' samples, for the exact last refit of an automatic choice
        (none: the last refit cuts the stretches at segment boundaries).
    max_segments : int
    keep_blocks : bool
        Keep the time-block sums (:class:`BlockSums`, two square matrices of the accumulation
        order's columns) for a manoeuvre ranking; False when nothing reads them.
    """

    def __init__(self, spec: ModelSpec, nodes: Sequence[str], options: FitOptions | None = None,
                 spool_dir: str | None = None, max_segments: int = MAX_SEGMENTS, keep_blocks: bool = True) -> None:
        if not spec.decouples:
            raise InputError(f"{spec.label}: live learning is for pattern models (sh, bg, poly)", param="spec")
        self.spec, self.nodes, self.options = spec, tuple(map(str, nodes)), options or FitOptions()
        self.auto = bool(self.options.auto)
        top = (MAX_AUTO_ORDER if spec.kind == "sh" else auto_orders(spec.kind, 0, 1, spec.order)[-1]) if self.auto else spec.order
        self.ridge = default_ridge(spec.kind) if spec.ridge is None else float(spec.ridge)
        self.big = ModelSpec(spec.kind, top, ridge=self.ridge) if self.auto else spec
        self.basis = self.big.basis()
        self.spool_dir = spool_dir if self.auto else None
        self.max_segments = max(int(max_segments), 1) if self.auto else 1
        self.segments: list[Segment] = []
        self.freq: Counter[float] = Counter()
        self._occupied: list[np.ndarray] | None = None  # per node, the coverage grid's cells seen (grids)
        self._grids: dict[str, list[float]] | None = None  # the grids of _occupied, made when read
        self.non_unit = 0
        self.blocks: BlockSums | None = None  # made with the first batch
        self.keep_blocks = bool(keep_blocks)
        #: the automatic choice's drifting error: its time blocks' sums (None for a fixed order)
        self.drift = DriftBlocks(self.basis, len(self.nodes)) if self.auto else None
        self.learn_s = 0.0
        #: the flight's layout (who held still, the packet rate), bounded, recorded by every refit as ``fit`` records it
        self.layout = LayoutSketch()
        self._batches = 0

    @property
    def grids(self) -> dict[str, list[float]] | None:
        """Per node, the coverage grid of every sample so far (as ``fit``'s, rounded to 0.1 degree), None
        before the first: made at a refit from the cells seen, not at every batch."""
        if self._grids is None and self._occupied is not None:
            self._grids = grids_of_occupied(self.nodes, self._occupied)
        return self._grids

    @property
    def n_samples(self) -> int:
        return sum(s.n_samples for s in self.segments)

    def samples(self, matched: pd.DataFrame, source: str = "live") -> LinkSamples:
        """Learning-ready samples of matched rows, in this session's node order."""
        unknown = sorted((set(map(str, matched["tx"])) | set(map(str, matched["rx"]))) - set(self.nodes))
        if unknown:
            raise InputError(f"{source}: node(s) {', '.join(unknown)} appeared after the session fixed its nodes "
                             f"({', '.join(self.nodes)}); name every node at the start", param="nodes")
        return link_samples(matched, source, nodes=self.nodes)

    @staticmethod
    def nodes_of(matched: pd.DataFrame) -> tuple[str, ...]:
        """The nodes matched rows name, sorted (``fit``'s model order)."""
        return tuple(sorted(set(map(str, matched["tx"])) | set(map(str, matched["rx"]))))

    def known_rows(self, matched: pd.DataFrame) -> tuple[pd.DataFrame, list[str]]:
        """The matched rows whose two ends are this session's nodes, and the other nodes the rest name (sorted)."""
        tx, rx = matched["tx"].astype(str), matched["rx"].astype(str)
        known = (tx.isin(self.nodes) & rx.isin(self.nodes)).to_numpy()
        if known.all():
            return matched, []
        return matched[known], sorted((set(tx[~known]) | set(rx[~known])) - set(self.nodes))

    def add(self, matched: pd.DataFrame, samples: LinkSamples) -> None:
        """Learn a batch: its matched rows (spooled) and their samples (:meth:`samples`)."""
        self.layout.merge(LayoutSketch.of_rows(matched))  # outage rows too, as fit reads the layout from every row
        if not len(samples):
            return
        t0 = time.perf_counter()
        y, env = regression_inputs(samples, self.options)
        normal = NormalEquations(self.basis, len(self.nodes), environment=env is not None)
        normal.add(samples.directions, samples.tx_index, samples.rx_index, y, env)
        t_all = pd.to_numeric(matched["t"]).to_numpy(np.float64)
        self._add_blocks(normal, samples, _sample_times(matched, t_all), (y, env))
        if self.drift is not None:
            self.drift.add(_sample_times(matched, t_all), samples.tx_index, samples.rx_index, samples.directions, y)
        seg = Segment(normal, float(t_all.min()), float(t_all.max()), self._batches, 1, self.spool_dir)
        if self.spool_dir is not None:
            with atomic_path(_batch_path(self.spool_dir, self._batches)) as tmp:
                matched.to_parquet(tmp, index=False)
        self._batches += 1
        self.segments.append(seg)
        self._bound()
        masks = occupied_masks(samples)
        self._occupied = masks if self._occupied is None else [a | b for a, b in zip(self._occupied, masks)]
        self._grids = None
        frequency_counts(samples, self.freq)
        self.non_unit += samples.non_unit_quaternions
        self.learn_s += time.perf_counter() - t0

    def _add_blocks(self, normal: NormalEquations, samples: LinkSamples, t: np.ndarray, inputs: tuple[Any, Any]) -> None:
        """The batch into the time blocks (split when it spans several; ``inputs``: its y and environment)."""
        if not self.keep_blocks or not len(t):
            return
        if self.blocks is None:
            self.blocks = BlockSums(len(self.nodes), self.basis.n_coef)
        index = np.floor(t / self.blocks.block_s).astype(np.int64)
        if index.min() == index.max():
            self.blocks.add_batch(normal, float(np.median(t)))
            return
        y, env = inputs
        d = samples.directions
        for k in np.unique(index):
            m = index == k
            part = NormalEquations(self.basis, len(self.nodes), environment=env is not None)
            part.add(type(d)(d.az_tx[m], d.el_tx[m], d.az_rx[m], d.el_rx[m]), samples.tx_index[m], samples.rx_index[m], y[m],
                     None if env is None else env[m])
            self.blocks.add_batch(part, float(np.median(t[m])))

    def _bound(self) -> None:
        while len(self.segments) > self.max_segments:
            n = np.array([s.n_samples for s in self.segments])
            k = int(np.argmin(n[:-1] + n[1:]))
            a, b = self.segments[k], self.segments.pop(k + 1)
            a.normal.merge(b.normal)
            a.t_min, a.t_max = min(a.t_min, b.t_min), max(a.t_max, b.t_max)
            a.n_batches += b.n_batches  # neighbours: b's batches follow a's

    def total(self) -> NormalEquations:
        """The statistics of every sample so far."""
        out = NormalEquations(self.basis, len(self.nodes), environment=self.segments[0].normal.environment)
        for s in self.segments:
            out.merge(s.normal)
        out.blocks = self.blocks  # not copied: whoever reads it closes a copy (BlockSums.closed)
        return out

    def fold_statistics(self, exact: bool) -> dict[str, NormalEquations]:
        """Statistics per stretch of time (the folds of an automatic choice), in time order;
        ``exact``: cut where ``fit`` cuts (re-reading the segments a cut falls inside)."""
        labels = stretch_labels(TIME_UNITS)
        if exact and self.spool_dir is not None:
            return self._exact_folds(labels, self._spooled_stretches())
        n = np.array([s.n_samples for s in self.segments], np.float64)
        middle = np.cumsum(n) - n / 2.0
        which = np.minimum((TIME_UNITS * middle / n.sum()).astype(int), TIME_UNITS - 1)
        folds: dict[str, NormalEquations] = {}
        for seg, j in zip(self.segments, which):
            acc = folds.setdefault(labels[j], NormalEquations(self.basis, len(self.nodes), seg.normal.environment))
            acc.merge(seg.normal)
        return {lab: folds[lab] for lab in labels if lab in folds}

    def _spooled_stretches(self) -> tuple[Stretches, list[tuple[str, np.ndarray]]]:
        """The stretches ``fit`` cuts the spooled rows into, and every spooled file with its rows' times."""
        files = [(f, pd.read_parquet(f, columns=["t"])["t"].to_numpy(np.float64)) for s in self.segments for f in s.files]
        return Stretches.of_times(np.concatenate([t for _, t in files]) if files else np.zeros(0)), files

    def _exact_folds(self, labels: list[str], spooled: tuple[Stretches, list[tuple[str, np.ndarray]]]) -> dict[str, NormalEquations]:
        stretches = spooled[0]
        folds: dict[str, NormalEquations] = {}
        env = self.segments[0].normal.environment
        for seg in self.segments:
            first, last = stretches.index(np.array([seg.t_min, seg.t_max]))
            if first == last:
                folds.setdefault(labels[first], NormalEquations(self.basis, len(self.nodes), env)).merge(seg.normal)
                continue
            for path in seg.files:  # a cut falls inside: its samples, by stretch
                rows = pd.read_parquet(path)
                k = stretches.index(rows["t"].to_numpy(np.float64))
                for j in np.unique(k):
                    s = self.samples(rows[k == j], path)
                    y, e = regression_inputs(s, self.options)
                    folds.setdefault(labels[j], NormalEquations(self.basis, len(self.nodes), env)).add(
                        s.directions, s.tx_index, s.rx_index, y, e)
        return {lab: folds[lab] for lab in labels if lab in folds}

    def refit(self, final: bool = False, provenance: Mapping[str, Any] | None = None) -> FittedModel:
        """The model of every sample so far (module docstring); ``final``: the exact folds.

        Raises
        ------
        InputError
            With too few samples for the model (the automatic choice needs 10 per coefficient of SH-2).
        """
        if not self.segments:
            raise InputError("no samples learned yet", param="samples")
        t0 = time.perf_counter()
        freq = weighted_median(self.freq)
        if not self.auto:
            acc = Accumulated({"all": self.total()}, Counter(self.freq), self.non_unit, 0.0, self.grids, "live", layout=self.layout)
            with blas_threads_for(self.n_samples, self.basis.n_coef * len(self.nodes)):
                fit = fit_patterns_accumulated(acc, self.spec, list(self.nodes), self.options)
            fit.patterns.provenance = {**dict(provenance or {}), "model": self.spec.label}
            return FittedModel(self.spec, fit.patterns, time.perf_counter() - t0)
        orders = auto_orders(self.spec.kind, self.n_samples, len(self.nodes), self.spec.order if self.spec.kind != "sh" else None)
        spooled = self._spooled_stretches() if final and self.spool_dir is not None else None
        folds = self.fold_statistics(False) if spooled is None else self._exact_folds(stretch_labels(TIME_UNITS), spooled)
        top = ModelSpec(self.spec.kind, orders[-1], ridge=self.ridge)
        small = top.basis()
        folds = {k: sub_statistics(v, small) for k, v in folds.items()}
        with blas_threads_for(self.n_samples, small.n_coef * len(self.nodes)):
            fitted, _ = fit_from_statistics(folds, top, orders, list(self.nodes), self.options, freq, provenance)
        model = fitted.model
        assert isinstance(model, PatternSet)  # fit_from_statistics learns patterns
        model.training = model.training.replace(coverage_deg=self.grids, **self.layout.recorded())
        drift = self.drift_std_db(folds, model.training, spooled)
        if drift is not None:
            model.training = model.training.replace(drift_std_db=drift)
        fitted.ltd_s = time.perf_counter() - t0
        return fitted

    def drift_std_db(self, folds: Mapping[str, NormalEquations], training: Any,
                     spooled: tuple[Stretches, list[tuple[str, np.ndarray]]] | None = None) -> float | None:
        """The drifting error ``fit --order auto`` states of these samples
        (:func:`~rplearn.models.auto_spread.block_drift_std_db`), read with a refit's prior and noise
        (its ``training``: ``planning_penalty_weight``, ``penalty_power``, ``noise_std_db`` times the
        square root of ``variance_inflation``) from the session's block sums; ``spooled``: the last
        refit's stretches and spooled files, the blocks their cuts fall in counted per stretch. None
        for a fixed order, a fit with a prior (no planning weight), or fewer than 4 blocks."""
        weight = getattr(training, "planning_penalty_weight", None)
        if self.drift is None or weight is None or training.noise_std_db is None or not folds:
            return None
        # fit --order auto's rules: one link's samples in MIN_BLOCKS distinct blocks, and a
        # smoothing short of the search's largest (there a flat pattern leaves every shape to the
        # block offsets, so no drift can be read)
        if self.drift.link_block_count() < MIN_BLOCKS or at_smoothing_cap(getattr(training, "smoothing", None) or 0.0):
            return None
        plan = planning_basis(next(iter(folds.values())).basis)
        total = NormalEquations(plan, len(self.nodes), next(iter(folds.values())).environment)
        for fold in folds.values():
            total.merge(sub_statistics(fold, plan))
        sums = self.drift.closed()
        if spooled is not None:
            self.drift.split(sums, self._cut_blocks(*spooled))
        noise = float(np.sqrt(float(training.noise_std_db) ** 2 * float(training.variance_inflation or 1.0)))
        return block_drift_std_db(self.drift.at(sums, plan), total, float(weight), self.ridge,
                                  float(training.penalty_power), noise)

    def _cut_blocks(self, stretches: Stretches, files: list[tuple[str, np.ndarray]]) -> dict[int, dict[int, LinkSums]]:
        """The sums of the time blocks the stretches' cuts fall in, per block label, stretch and
        directed link, from their spooled rows (only the files that hold such rows are read)."""
        cut = np.unique(time_block_labels(np.asarray(stretches.starts_s, np.float64)))
        out: dict[int, dict[int, LinkSums]] = {}
        if not cut.size or self.drift is None:
            return out
        for path, t in files:
            if not np.isin(time_block_labels(t), cut).any():
                continue
            rows = pd.read_parquet(path)
            rows = rows[np.isin(time_block_labels(rows["t"].to_numpy(np.float64)), cut)]
            which = stretches.index(rows["t"].to_numpy(np.float64))
            for j in np.unique(which):
                part = rows[which == j]
                s = self.samples(part, path)
                if not len(s):
                    continue
                y, _ = regression_inputs(s, self.options)
                t_s = _sample_times(part, part["t"].to_numpy(np.float64))
                for label, links in block_link_sums(self.drift.basis, time_block_labels(t_s), s.tx_index, s.rx_index,
                                                    s.directions, y).items():
                    kept = out.setdefault(label, {}).setdefault(int(j), {})
                    for link, vec in links.items():
                        kept[link] = vec if link not in kept else kept[link] + vec
        return out


__all__ = ["MAX_SEGMENTS", "LiveStatistics", "Segment"]


def _sample_times(matched: pd.DataFrame, t_s: np.ndarray) -> np.ndarray:
    """The times [s] of the rows :func:`link_samples` keeps (outage rows have no sample)."""
    if OUTAGE_COLUMN in matched.columns:
        return t_s[~matched[OUTAGE_COLUMN].to_numpy(bool)]
    return t_s
