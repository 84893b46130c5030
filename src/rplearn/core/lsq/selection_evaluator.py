"""The validation errors behind :mod:`rplearn.core.lsq.selection`: grouped cross-validation (or
GCV) of one order and smoothing from the per-unit statistics at the largest order.

:class:`FoldEvaluator` keeps every point it has computed (the validation curve), the Cholesky
factors of a batch of points solved at once, for the variance inflations of the chosen and tied
points (:meth:`FoldEvaluator.spread`), and the blocks of the orders the search visits for
generalised cross-validation (within :data:`_CACHE_BYTES`). With held-out units the folds are
solved in the lead layout of :mod:`rplearn.core.lsq.selection_lead`: the points of one smoothing
from one factorisation per fold, whatever their orders. The search itself is in
:mod:`rplearn.core.lsq.selection`.
"""


import functools
from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np

from rplearn.core.basis_base import Basis
from rplearn.core.lsq.level import shrink_target
from rplearn.core.lsq.normal_equations import EXPONENT_MIN_SPREAD_DB, NormalEquations, schur_spread_db
from rplearn.core.lsq.penalty import nested_columns, penalty_scale, with_shared_columns
from rplearn.core.lsq.runtime import DEFAULT_RUNTIME
from rplearn.core.lsq.selection_folds import fold_spread_terms, lead_size, on_one_blas_thread, sub_block, unit_folds
from rplearn.core.lsq.selection_lead import LeadFolds
from rplearn.core.lsq.selection_result import CurvePoint
from rplearn.core.lsq.solver_cholesky import factor_solve, spd_factor
from rplearn.errors import InputError

#: Smoothing values tried, relative to ``mean(diag(X^T X))`` (0: the plain fit with its ridge).
#: When the best is the largest, larger values are tried (by decades, up to
#: :data:`MAX_SMOOTHING`): with a prior, a flight that saw little may be best left at the prior.
SMOOTHING_GRID: tuple[float, ...] = (0.0, *np.logspace(-8.0, 1.0, 19).tolist())
MAX_SMOOTHING = 1e6
#: Weight of the (unpenalised) constant in the cross-validation solves, relative to the
#: roughness of degree 1: keeps them positive definite; moves only the free gauge constant.
_CONSTANT_FLOOR = 1e-6
#: Orders whose fold blocks are kept at least (the coordinate descent moves between neighbours).
_CACHED_ORDERS = 3
#: Bytes of fold blocks past which only :data:`_CACHED_ORDERS` orders are kept (the paper's
#: two nodes up to SH-15: 47 MB for every order; the search comes back to most of them).
_CACHE_BYTES = 96 * 2**20
#: Bytes of Cholesky factors a batch of points solved at once keeps for :meth:`FoldEvaluator.spread`
#: (a swarm's factors are large: past this only the solutions are kept, and the best point's
#: inflation solves again).
_PENDING_FACTOR_BYTES = 128 * 2**20
#: Stands for a factor not kept.
_DROPPED = np.empty((0, 0))
#: Bytes of the folds' Cholesky factors kept for the best points validated so far (the chosen
#: and tied points are among the best: their inflations then factorise nothing again). The
#: paper's SH-15 folds: 6 MB a point; the 4-6 best points are tied in the ``paper`` and
#: ``pathloss`` records, and the factors would be recomputed to the same bits without it.
_KEPT_FACTOR_BYTES = 64 * 2**20


def _cache_bytes(cache: Mapping[int, Any]) -> int:
    """Bytes held by the cached fold blocks of :class:`FoldEvaluator` (views of the folds' own
    matrices, the largest order's, counted too: a bound, not a census)."""
    return sum(sum(a.nbytes for a in block) for _, blocks, _, _ in cache.values() for block in blocks)



class FoldEvaluator:
    """Validation RMSE of (order, smoothing) from the statistics at the largest order."""

    def __init__(self, units: Mapping[str, NormalEquations], make_basis: Callable[[int], Basis],
                 ridge: float, power: float, target: np.ndarray | None = None, prior_level: str = "data") -> None:
        first = next(iter(units.values()))
        self.big, self.n_nodes = first.basis, first.n_nodes
        self.first = first
        self.n_shared = len(first.shared)
        if any(u.shared != first.shared for u in units.values()):
            raise InputError("the units' statistics have different shared columns; append them with one link list",
                             param="units")
        # each order's basis built once (the search asks for it at every point; a basis is immutable)
        self.make_basis = functools.lru_cache(maxsize=None)(make_basis)
        self.ridge, self.power = float(ridge), float(power)
        self.folds, self.gram, self.rhs, self.yty, self.n = unit_folds(units)
        self.sums = [u.column_sums() for u in units.values()]
        if target is not None:
            target = np.asarray(target, np.float64)[:first.n_pattern_columns]  # the prior's: shared columns are not pulled
        self.target = target
        self.prior_level = prior_level
        self.cv = len(units) >= 2
        self.pins: list[tuple[np.ndarray, np.ndarray] | None] = [None] * len(self.folds)
        if self.n_shared and self.cv:
            self.pins = self._fold_pins(units)
        self.seen: dict[tuple[int, float], float] = {}
        self.fold_sse: dict[tuple[int, float], np.ndarray] = {}  # per held-out unit, for ties.within_noise()
        self.excess_db2: dict[tuple[int, float], float] = {}  # per held-out sample, see spread()
        self._spreads: dict[tuple[int, float], tuple[float, float]] = {}  # spread() of each point asked
        self.curve: list[CurvePoint] = []
        self._cache: dict[int, Any] = {}
        self._cache_nbytes: dict[int, int] = {}  # _cache_bytes of each cached order
        # the folds' solutions and factors of the best points so far (within _KEPT_FACTOR_BYTES)
        self._solved: dict[tuple[int, float], list[tuple[np.ndarray, np.ndarray | None]]] = {}
        self._solved_nbytes: dict[tuple[int, float], int] = {}
        self._pending: dict[tuple[int, float], list[tuple[np.ndarray, np.ndarray | None, float]]] = {}  # prefetch()
        self._source: dict[tuple[int, float], list[int]] = {}  # per point and fold: the order its factor was read from
        self._lead: LeadFolds | None = None
        self._top_targets: list[np.ndarray] | None = None

    def _fold_pins(self, units: Mapping[str, NormalEquations]) -> list[tuple[np.ndarray, np.ndarray] | None]:
        """Per fold, the shared columns its learning units cannot identify, pinned to a
        preliminary estimate from all units: a link's offset when a direction of it flew only
        in the held-out unit, the exponent when the other units leave too little spread of
        distance (:data:`EXPONENT_MIN_SPREAD_DB`). Left free, the ridge alone would split
        them from the joint level and the held-out unit would see a made-up error; the final
        fit, which sees every unit, identifies them."""
        p = self.big.n_coef
        pat = self.first.n_pattern_columns
        names = list(units)
        free = []
        for held, fold in zip(names, self.folds):
            mask = np.ones(self.n_shared, bool)
            learn = [units[u] for u in names if u != held]
            n_learn = sum(u.n_samples for u in learn)
            for j, col in enumerate(self.first.shared):
                if col[0] == "offset":
                    a, b = col[1], col[2]
                    count = [sum(float(u.directed[k][2 * p + 1]) for u in learn if k in u.directed) for k in ((a, b), (b, a))]
                    mask[j] = min(count) > 0
                else:
                    mask[j] = schur_spread_db(fold.gram, pat + j, n_learn) >= EXPONENT_MIN_SPREAD_DB
            free.append(mask)
        if all(m.all() for m in free):
            return [None] * len(self.folds)
        w = self._weights(self.big)
        smoothing = float(SMOOTHING_GRID[len(SMOOTHING_GRID) // 2])
        target = self._target(self.gram, self.rhs, self.big, self.target)
        unit = smoothing * penalty_scale(self.gram, self.gram.shape[0] - self.n_shared)
        c, _ = self._solve(self.gram, self._pulled(self.gram, self.rhs, w, unit, target), w, unit)
        values = c[pat:]
        pins: list[tuple[np.ndarray, np.ndarray] | None] = []
        for mask, fold in zip(free, self.folds):
            if mask.all():
                pins.append(None)
                continue
            weight = 1e6 * (np.diag(fold.gram)[pat:] + float(np.mean(np.diag(fold.gram)[:pat])))
            pins.append((np.where(mask, 0.0, weight), values.copy()))
        return pins

    def _target(self, gram: np.ndarray, rhs: np.ndarray, basis: Basis, prior: np.ndarray | None) -> np.ndarray:
        """What one fit shrinks toward: the prior's shape and the data's level, or (``prior_level``
        ``"prior"``) the prior itself."""
        if prior is not None and self.prior_level == "prior":
            return np.concatenate([prior, np.zeros(self.n_shared)])
        return shrink_target(gram, rhs, basis, self.n_nodes, prior)

    def _weights(self, basis: Basis) -> np.ndarray:
        w = basis.roughness(self.power)
        floor = _CONSTANT_FLOOR * (float(np.min(w[w > 0])) if np.any(w > 0) else 1.0)
        return np.concatenate([np.tile(np.maximum(w, floor), self.n_nodes), np.zeros(self.n_shared)])

    def _blocks(self, order: int) -> tuple[np.ndarray, list[tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]],
                                           list[np.ndarray], list[float]]:
        """Roughness weights and, per fold, the learning and held-out blocks of one order, the
        target its fit shrinks toward (the prior's shape and the learning units' own level,
        :func:`~rplearn.core.lsq.level.shrink_target`) and the penalty's unit (cached,
        :meth:`_ensure_blocks`)."""
        self._ensure_blocks([int(order)])
        return self._cache[int(order)]

    def _fold_block(self, order: int, fold: int) -> tuple[tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray],
                                                         np.ndarray, float]:
        """One fold's blocks of one order (:meth:`_blocks`), its target and its penalty's unit
        (independent of the other folds and orders: any thread)."""
        basis = self.make_basis(order)
        pattern_idx = nested_columns(self.big, basis, self.n_nodes)
        idx = with_shared_columns(pattern_idx, self.first)
        if self.cv:
            f = self.folds[fold]
            sub = (sub_block(f.gram, idx), f.rhs[idx], sub_block(f.held_gram, idx), f.held_rhs[idx])
        else:
            sub = (sub_block(self.gram, idx), self.rhs[idx], np.empty(0), np.empty(0))
        prior = None if self.target is None else self.target[pattern_idx]
        g, r = sub[0], sub[1]
        return sub, self._target(g, r, basis, prior), penalty_scale(g, g.shape[0] - self.n_shared)

    def _order_bytes(self, order: int) -> int:
        """Bytes of one order's fold blocks (:meth:`_blocks`): two square matrices per fold."""
        cols = len(nested_columns(self.big, self.make_basis(order), self.n_nodes)) + self.n_shared
        return 2 * (len(self.folds) if self.cv else 1) * cols * cols * 8

    def _ensure_blocks(self, orders: Sequence[int]) -> None:
        """Compute the blocks of the ``orders`` not cached, every (order, fold) on the statistics'
        workers at once, and keep every order's while they hold at most :data:`_CACHE_BYTES`
        (at least the :data:`_CACHED_ORDERS` last asked: bounded memory for a swarm's large
        blocks). Copies of the same numbers: which are kept changes no result."""
        wanted = list(dict.fromkeys(int(o) for o in orders))
        missing = [o for o in wanted if o not in self._cache]
        if missing:
            n_folds = len(self.folds) if self.cv else 1
            jobs = [functools.partial(self._fold_block, o, k) for o in missing for k in range(n_folds)]
            built = list(DEFAULT_RUNTIME.in_order(on_one_blas_thread, jobs, ahead=len(jobs)))
            for i, o in enumerate(missing):
                parts = built[i * n_folds:(i + 1) * n_folds]
                self._cache[o] = (self._weights(self.make_basis(o)), [b for b, _, _ in parts], [t for _, t, _ in parts],
                                  [s for _, _, s in parts])
                self._cache_nbytes[o] = _cache_bytes({o: self._cache[o]})  # counted once, not at every call
        for o in wanted:  # the orders asked last are the newest
            self._cache[o] = self._cache.pop(o)
        while (len(self._cache) > max(_CACHED_ORDERS, len(wanted))
               and sum(self._cache_nbytes[o] for o in self._cache) > _CACHE_BYTES):
            del self._cache_nbytes[next(iter(self._cache))]
            self._cache.pop(next(iter(self._cache)))

    def lead(self) -> LeadFolds:
        """The folds in the lead layout (:mod:`rplearn.core.lsq.selection_lead`), made once."""
        if self._lead is None:
            scales = [penalty_scale(f.gram, f.gram.shape[0] - self.n_shared) for f in self.folds]
            self._lead = LeadFolds(self.folds, self.gram, self.sums, self.pins, (self.big.n_coef, self.n_nodes, self.n_shared),
                                   (self.ridge, self._weights(self.big), scales),
                                   (lambda o: self.make_basis(o).n_coef, self._lead_targets))
        return self._lead

    def _lead_targets(self, order: int) -> list[np.ndarray]:
        """Per fold, the target of an order's fit in the lead layout: without a prior, the largest
        order's leading part (the constants' levels read off the constant and shared columns
        alone: the same at every order); with one, each order's own, reordered."""
        lead = self.lead()
        m = lead_size(self.make_basis(order).n_coef, self.n_nodes, self.n_shared)
        if self.target is None:
            if self._top_targets is None:
                self._top_targets = [self._target(f.gram, f.rhs, self.big, None)[lead.perm] for f in self.folds]
            return [t[:m] for t in self._top_targets]
        idx = with_shared_columns(nested_columns(self.big, self.make_basis(order), self.n_nodes), self.first)
        jobs = [functools.partial(self._fold_block, int(order), k) for k in range(len(self.folds))]
        out = []
        for _, t, _ in DEFAULT_RUNTIME.in_order(on_one_blas_thread, jobs):  # read once: the blocks are not kept
            full = np.zeros(self.gram.shape[0])
            full[idx] = t
            out.append(full[lead.perm][:m])
        return out

    def prefetch(self, points: Sequence[tuple[int, float]]) -> None:
        """Solve every fold of the points not validated yet, on the statistics' workers at once
        (:meth:`~rplearn.core.lsq.runtime.StatisticsRuntime.in_order`: one core each, or here when
        the workers are busy); :meth:`rmse` then records them, in the order it is asked. Nothing
        depends on which thread solved what. The points of one smoothing are solved from one
        factorisation per fold, at the largest of their orders or one kept from earlier
        (:mod:`rplearn.core.lsq.selection_lead`). Their factors are kept (for :meth:`spread` of
        the best point) up to :data:`_PENDING_FACTOR_BYTES` a batch; past it only the solutions."""
        if not self.cv:
            return
        keys = list(dict.fromkeys((int(o), float(s)) for o, s in points if (int(o), float(s)) not in self.seen))
        keys = [k for k in keys if k not in self._pending]
        if not keys:
            return
        lead = self.lead()
        groups: dict[float, list[int]] = {}
        for o, s in keys:
            lead.order(o)  # made here, read by the jobs
            groups.setdefault(s, []).append(o)
        folds = len(self.folds)
        plan: list[tuple[float, list[int], int, bool]] = []
        jobs: list[Callable[[], Any]] = []
        for s, orders in groups.items():
            kept = lead.factors.get(s)
            reuse = kept is not None and kept[0] >= max(orders)
            source = kept[0] if kept is not None and reuse else max(orders)
            plan.append((s, orders, source, reuse))
            jobs += [functools.partial(lead.group, k, s, orders, source, kept[1][k] if kept is not None and reuse else None)
                     for k in range(folds)]
        results = list(DEFAULT_RUNTIME.in_order(on_one_blas_thread, jobs, ahead=len(jobs)))
        held = 0
        for i, (s, orders, source, reuse) in enumerate(plan):
            per_fold = results[i * folds:(i + 1) * folds]
            if not reuse:
                lead.keep(s, source, [upper for upper, _ in per_fold])
            for j, o in enumerate(orders):
                entries: list[tuple[np.ndarray, Any, float]] = []
                for _, points_of_fold in per_fold:
                    c, upper, sse, _ = points_of_fold[j]
                    held += 0 if upper is None else upper.size * 8
                    entries.append((c, upper if upper is None or held <= _PENDING_FACTOR_BYTES else _DROPPED, sse))
                self._pending[(o, s)] = entries
                self._source[(o, s)] = [points_of_fold[j][3] for _, points_of_fold in per_fold]

    def rmse(self, order: int, smoothing: float) -> float:
        key = (int(order), float(smoothing))
        if key in self.seen:
            return self.seen[key]
        if self.cv:
            self.prefetch([key])
            results = self._pending.pop(key)
            per_fold = [sse for _, _, sse in results]
            solved = [(c, upper) for c, upper, _ in results]
            self.fold_sse[key] = np.asarray(per_fold)
            value = float(np.sqrt(sum(per_fold) / self.n))
            if not any(u is _DROPPED for _, u in solved):
                self._keep_solved(key, value, solved)
        else:
            w, blocks, targets, scales = self._blocks(int(order))
            g, r, _, _ = blocks[0]
            weight = smoothing * scales[0]
            value = self._gcv(g, self._pulled(g, r, w, weight, targets[0]), w, weight, r)
        self.seen[key] = value
        self.curve.append(CurvePoint(int(order), float(smoothing), value))
        return value

    def _keep_solved(self, key: tuple[int, float], value: float,
                     solved: list[tuple[np.ndarray, np.ndarray | None]]) -> None:
        """Keep the folds' solutions and factors of ``key`` (validated at ``value``) while it
        is among the best points whose factors fit in :data:`_KEPT_FACTOR_BYTES` (the best
        always: its inflation is always asked), for :meth:`spread`. Which are kept changes no
        figure: a point not kept is solved again, to the same bits."""
        self._solved[key] = solved
        self._solved_nbytes[key] = sum(0 if u is None else u.nbytes for _, u in solved)
        held = 0
        for k in sorted(self._solved, key=lambda k: (self.seen.get(k, value), k)):
            if held and held + self._solved_nbytes[k] > _KEPT_FACTOR_BYTES:
                del self._solved[k], self._solved_nbytes[k]
            else:
                held += self._solved_nbytes[k]

    def inflation(self, order: int, smoothing: float) -> float:
        """:func:`variance_inflation` of one (order, smoothing) (1 without held-out units)."""
        return self.spread(order, smoothing)[0]

    def spread(self, order: int, smoothing: float) -> tuple[float, float]:
        """The within-unit variance inflation and the between-unit level variance [dB^2] of
        one (order, smoothing) (1 and 0 without held-out units); see :func:`variance_inflation`."""
        if not self.cv:
            return 1.0, 0.0
        self.prefetch_spreads([(order, smoothing)])
        return self._spreads[(int(order), float(smoothing))]

    def prefetch_spreads(self, points: Sequence[tuple[int, float]],
                         extra: Sequence[Callable[[], Any]] = ()) -> list[Any]:
        """:meth:`spread` of every point not computed yet, the folds of all of them on the
        statistics' workers at once (:mod:`rplearn.core.lsq.selection_folds`), with the
        ``extra`` jobs (queued first: the caller's work that needs only the choice, e.g. its
        final solve); their results, in order."""
        keys = [k for k in dict.fromkeys((int(o), float(s)) for o, s in points) if k not in self._spreads] if self.cv else []
        jobs = list(extra) + [job for key in keys for job in self._spread_jobs(*key)]
        if not jobs:
            return []
        results = list(DEFAULT_RUNTIME.in_order(on_one_blas_thread, jobs, ahead=len(jobs)))
        folds = len(self.folds)
        spreads = results[len(extra):]
        for i, key in enumerate(keys):
            self._spreads[key] = self._combine_spread(key, spreads[i * folds:(i + 1) * folds])
        return results[:len(extra)]

    def _spread_jobs(self, order: int, smoothing: float) -> list[Callable[[], Any]]:
        """Per fold, the work of :func:`~rplearn.core.lsq.selection_folds.fold_spread_terms` (None
        when its system is not positive definite), solving again, from the factor of the order the
        point was read from (the same bits), unless the point's factors were kept (:meth:`_keep_solved`)."""
        lead = self.lead()
        key = (int(order), float(smoothing))
        sums = lead.column_sums(int(order))
        counts = np.array([f.held_n for f in self.folds], np.float64)
        solved = self._solved.get(key)
        sources = self._source.get(key, [int(order)] * len(self.folds))
        jobs: list[Callable[[], Any]] = []
        for k in range(len(self.folds)):
            def job(k: int = k, known: Any = None if solved is None else solved[k]) -> Any:
                c, upper = known if known is not None else lead.resolve(k, key[0], key[1], sources[k])
                return None if upper is None else fold_spread_terms(c, upper, lead.fold(k, key[0]), k, sums, counts,
                                                                    (self.n, self.yty))
            jobs.append(job)
        return jobs

    def _combine_spread(self, key: tuple[int, float], terms: list[Any]) -> tuple[float, float]:
        """The inflation and level variance of one point from its folds' terms, summed in fold order."""
        if any(t is None for t in terms):
            return 1.0, 0.0
        counts = np.array([f.held_n for f in self.folds], np.float64)
        excess = predicted = 0.0
        for fold_excess, fold_predicted, _ in terms:
            excess += fold_excess
            predicted += fold_predicted
        means = [m for _, _, m in terms]  # per held-out unit: its squared mean residual, that of noise and fit, the level's weight
        kappa = float(max(1.0, excess / predicted)) if predicted > 0 and np.isfinite(excess) else 1.0
        self.excess_db2[key] = float(excess / counts.sum()) if np.isfinite(excess) else 0.0
        square, expected, weight = (np.array(v) for v in zip(*means))
        level_var = float(np.sum(square - kappa * expected) / np.sum(weight))
        return kappa, max(level_var, 0.0) if np.isfinite(level_var) else 0.0

    def _pulled(self, gram: np.ndarray, rhs: np.ndarray, w: np.ndarray, weight: float, target: np.ndarray,
                pin: tuple[np.ndarray, np.ndarray] | None = None) -> np.ndarray:
        """``X^T y`` plus the pull ``(ridge + P) target`` of the ridge and the penalty toward the
        target (the prior's shape and the data's level, never a fixed level) and the pull of
        pinned shared columns toward their values. ``weight``: the smoothing times the
        penalty's unit (:func:`penalty_scale` of ``gram``)."""
        out = rhs.copy()
        k = gram.shape[0] - self.n_shared
        out[:k] += (self.ridge + weight * w[:k]) * target[:k]
        if pin is not None:
            out[gram.shape[0] - self.n_shared:] += pin[0] * pin[1]
        return out

    def _system(self, gram: np.ndarray, w: np.ndarray, weight: float,
                pin: tuple[np.ndarray, np.ndarray] | None = None) -> np.ndarray:
        """The penalised normal matrix: the ridge on the pattern columns (shared columns are not
        shrunk), the smoothness penalty (``weight``: the smoothing times the penalty's unit),
        and the weight of pinned shared columns."""
        a = gram.copy()
        k = gram.shape[0] - self.n_shared
        diagonal = a.reshape(-1)[:: a.shape[0] + 1]  # a view of the diagonal
        diagonal[:k] += self.ridge
        diagonal += weight * w
        if pin is not None:
            diagonal[k:] += pin[0]
        return a

    def _solve(self, gram: np.ndarray, rhs: np.ndarray, w: np.ndarray, weight: float,
               pin: tuple[np.ndarray, np.ndarray] | None = None) -> tuple[np.ndarray, np.ndarray | None]:
        """The penalised solution and the upper Cholesky factor of its system (None when the
        system is not positive definite: least squares then)."""
        upper = spd_factor(self._system(gram, w, weight, pin), overwrite=True)
        if upper is not None:
            return factor_solve(upper, rhs), upper
        import scipy.linalg

        return scipy.linalg.lstsq(self._system(gram, w, weight, pin), rhs)[0], None

    def _gcv(self, g: np.ndarray, pulled: np.ndarray, w: np.ndarray, weight: float, r: np.ndarray) -> float:
        a = self._system(g, w, weight)
        try:
            import scipy.linalg

            factor = scipy.linalg.cho_factor(a, overwrite_a=True, check_finite=False)
            c = scipy.linalg.cho_solve(factor, pulled)
            trace = float(np.trace(scipy.linalg.cho_solve(factor, g)))  # tr(H) = tr((G + P)^-1 G)
        except np.linalg.LinAlgError:
            return float("inf")
        sse = max(self.yty - 2.0 * c @ r + c @ g @ c, 0.0)
        dof = self.n - trace
        return float(np.sqrt(self.n * sse) / dof) if dof > 0 else float("inf")
