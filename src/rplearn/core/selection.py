"""Automatic choice of a pattern's order and smoothing from per-unit sufficient statistics.

The learned coefficients are shrunk by a smoothness penalty ``lambda * sum_j w_j c_j^2`` with
``w_j`` the basis's :meth:`~rplearn.core.basis_base.Basis.roughness` (``(l (l+1))^p`` for a
spherical harmonic of degree ``l``, ``p`` = :data:`DEFAULT_PENALTY_POWER`; plain ridge for BG and
P). ``lambda`` is given *relative* to the mean diagonal of the learning data's ``X^T X``, so one
value means the same shrinkage for a short and a long flight: the absolute weight added to
``X^T X`` is ``smoothing * mean(diag(X^T X)) * w_j``.

Order and smoothing are chosen by **grouped cross-validation over flight units**: each unit in
turn is held out, the pattern learned from the others, and its squared error on the held-out
unit computed from that unit's statistics alone (``y^T y - 2 c^T X^T y + c^T X^T X c``); random
samples are never held out, because neighbouring packets of one flight leak into each other.
With a single unit the choice is by **generalised cross-validation** (Golub, Heath and Wahba
1979) on the whole data; ``rplearn fit`` avoids that case by cutting a single flight into
contiguous stretches of time that play the units' part. Either way the validation error is that
of the flown region: a test that looks where no unit looked (another altitude) is an
extrapolation, which the coverage warnings of predict and evaluate flag. Everything comes from the :class:`NormalEquations` accumulated once per
unit at the largest order: for spherical harmonics a lower order's statistics are a sub-block
(degrees nest), so nothing is refitted from raw samples.

The search, a coordinate descent over the validation error (every point is kept as the curve):

1. the smoothing grid :data:`SMOOTHING_GRID` at a middle candidate order (every other value,
   then the neighbours of the best): the relative smoothing means nearly the same at every
   order, and a middle order costs a fraction of the largest;
2. the candidate orders at that smoothing (every other order from the largest down, then the
   neighbours of the best);
3. at the best order, the smoothing walks along the grid while it improves; then step 2 runs
   again at the new smoothing, and step 3 repeats while the order moves;
4. of the points evaluated, those within noise of the best (:func:`_within_noise`: from three
   held-out units, at most :data:`WITHIN_NOISE_SE` standard errors of the paired per-unit
   difference and :data:`WITHIN_NOISE_FRACTION` of the mean square above it), the least
   smoothed (then the largest order) is chosen: the joint gain validates the sum of two
   patterns, not their split, which the penalty decides; more smoothing than the held-out
   units can justify pulls the split toward the prior (on the ``paper`` preset, seed 1: a
   pattern error per node of 1.48 dB at smoothing 3.2e-5 against 1.33 dB at 1e-5, for a
   validation error no unit can tell apart; ``benchmarks/split.py``).

The validation error of an order and smoothing is computed once (a Cholesky solve per held-out
unit) and kept in the curve. The cost is dominated by the few solves at the largest orders:
about 6 of them per held-out unit, against 12-14 for a full grid at the largest order.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Callable, Mapping, Sequence

import numpy as np

from rplearn.core.basis_base import Basis
from rplearn.core.normal_equations import EXPONENT_MIN_SPREAD_DB, NormalEquations, schur_spread_db
from rplearn.errors import IdentifiabilityError, InputError

#: Exponent ``p`` of the SH roughness weights ``(l (l+1))^p``: 2 penalises the squared
#: Laplacian of the pattern (spherical smoothing splines).
DEFAULT_PENALTY_POWER: float = 2.0
#: Smoothing values tried, relative to ``mean(diag(X^T X))`` (0: the plain fit with its ridge).
#: When the best is the largest, larger values are tried (by decades, up to
#: :data:`MAX_SMOOTHING`): with a prior, a flight that saw little may be best left at the prior.
SMOOTHING_GRID: tuple[float, ...] = (0.0, *np.logspace(-8.0, 1.0, 19).tolist())
MAX_SMOOTHING = 1e6
#: Weight of the (unpenalised) constant in the cross-validation solves, relative to the
#: roughness of degree 1: keeps them positive definite; moves only the free gauge constant.
_CONSTANT_FLOOR = 1e-6
#: Points within this many standard errors (of the held-out units' paired difference in squared
#: error) of the best validation error count as equally good: the least smoothed of them is chosen.
WITHIN_NOISE_SE = 2.0
#: ... and by at most this fraction of the best validation mean square (a cap on what a noisy
#: standard error from a few units may excuse: 1% is 0.5% of the RMSE, 0.02 dB at 4.4 dB).
WITHIN_NOISE_FRACTION = 0.01
#: Held-out units needed to estimate that standard error (with fewer the best point is chosen).
MIN_NOISE_UNITS = 3
#: Orders whose fold blocks are kept at once (the coordinate descent moves between neighbours).
_CACHED_ORDERS = 3


@dataclass(frozen=True)
class CurvePoint:
    """Validation error of one (order, smoothing) pair."""

    order: int
    smoothing: float
    rmse_db: float

    def to_dict(self) -> dict[str, Any]:
        return {"order": self.order, "smoothing": self.smoothing, "rmse_db": self.rmse_db}


@dataclass
class Selection:
    """The chosen order and smoothing, and the validation curve behind the choice.

    Attributes
    ----------
    method : str
        ``"grouped-cv"`` (held-out flight units) or ``"gcv"`` (one unit).
    order : int
    smoothing : float
        Relative smoothing (see the module docstring).
    rmse_db : float
        Validation RMSE at the choice [dB] (GCV: its RMSE-equivalent ``sqrt(GCV)``).
    curve : list of CurvePoint
        Every (order, smoothing) evaluated, in the order of the search.
    units : list of str
        The units held out in turn (empty for GCV).
    power : float
        Exponent of the SH roughness weights.
    variance_inflation : float
        Factor (at least 1) by which the held-out units' squared errors exceed what the
        posterior covariance of the folds' fits predicts (see :func:`variance_inflation`); 1
        for GCV.
    """

    method: str
    order: int
    smoothing: float
    rmse_db: float
    curve: list[CurvePoint] = field(default_factory=list)
    units: list[str] = field(default_factory=list)
    power: float = DEFAULT_PENALTY_POWER
    variance_inflation: float = 1.0

    def to_dict(self) -> dict[str, Any]:
        return {"method": self.method, "order": self.order, "smoothing": self.smoothing, "rmse_db": self.rmse_db,
                "power": self.power, "units": list(self.units), "variance_inflation": self.variance_inflation,
                "curve": [p.to_dict() for p in self.curve]}

    def curve_text(self) -> str:
        """The validation curve as a small table (order, smoothing, RMSE), the choice marked."""
        lines = [f"{'order':>5} {'smoothing':>10} {'rmse_db':>8}"]
        for p in sorted(self.curve, key=lambda q: (q.order, q.smoothing)):
            mark = "  <- chosen" if (p.order, p.smoothing) == (self.order, self.smoothing) else ""
            lines.append(f"{p.order:>5} {p.smoothing:>10.1e} {p.rmse_db:>8.3f}{mark}")
        return "\n".join(lines)


def penalty_scale(gram: np.ndarray, n_columns: int | None = None) -> float:
    """``mean(diag(X^T X))`` over the pattern columns (the first ``n_columns``; all by default,
    shared columns such as link offsets excluded when given): the unit of the relative smoothing."""
    d = np.diag(gram)
    if n_columns is not None:
        d = d[:n_columns]
    return float(np.mean(d)) if d.size and np.mean(d) > 0 else 1.0


def penalty_vector(basis: Basis, n_nodes: int, smoothing: float, scale: float, power: float = DEFAULT_PENALTY_POWER) -> np.ndarray:
    """Absolute penalty weight of every column (``n_nodes`` blocks of the basis's roughness)."""
    if not (np.isfinite(smoothing) and smoothing >= 0):
        raise InputError(f"smoothing: expected a non-negative number, got {smoothing!r}", param="smoothing")
    return np.tile(basis.roughness(power), n_nodes) * (float(smoothing) * float(scale))


def nested_columns(big: Basis, small: Basis, n_nodes: int) -> np.ndarray:
    """Columns of ``small``'s joint problem inside ``big``'s (SH orders nest: first ``N^2`` of each block)."""
    if big.kind != small.kind or (big.kind == "sh" and small.n_coef > big.n_coef):
        raise InputError(f"{small.label} is not nested in {big.label}")
    if big.kind != "sh" and small != big:
        raise InputError(f"only spherical harmonics nest; {small.label} is not {big.label}")
    return np.concatenate([k * big.n_coef + np.arange(small.n_coef) for k in range(n_nodes)])


def sub_statistics(normal: NormalEquations, small: Basis) -> NormalEquations:
    """The statistics of a nested smaller basis, taken from ``normal`` (no samples re-read)."""
    if small == normal.basis:
        return normal
    idx = with_shared_columns(nested_columns(normal.basis, small, normal.n_nodes), normal)
    out = NormalEquations(small, normal.n_nodes, normal.environment)
    out.shared = normal.shared
    out.gram = normal.gram[np.ix_(idx, idx)].copy()
    out.rhs = normal.rhs[idx].copy()
    out.yty = normal.yty
    out.n_samples = normal.n_samples
    out.link_counts = dict(normal.link_counts)
    out.env_sq, out.env_y = normal.env_sq, normal.env_y
    p_big, p_small = normal.basis.n_coef, small.n_coef
    out.env_cross = normal.env_cross.reshape(normal.n_nodes, p_big)[:, :p_small].ravel().copy()
    out.directed = {k: np.concatenate([v[:p_small], v[p_big : p_big + p_small], v[2 * p_big :]])
                    for k, v in normal.directed.items()}
    return out


def with_shared_columns(pattern_idx: np.ndarray, normal: NormalEquations) -> np.ndarray:
    """Column indices of a sub-problem: ``pattern_idx`` and then every shared column of ``normal``."""
    return np.concatenate([pattern_idx, normal.n_pattern_columns + np.arange(len(normal.shared))]).astype(np.intp)


@dataclass
class _Fold:
    """Learning statistics (all units but one) and the held-out unit's."""

    gram: np.ndarray
    rhs: np.ndarray
    held_gram: np.ndarray
    held_rhs: np.ndarray
    held_yty: float
    held_n: int


def _folds(units: Mapping[str, NormalEquations]) -> tuple[list[_Fold], np.ndarray, np.ndarray, float, int]:
    gram = sum(u.gram for u in units.values())
    rhs = sum(u.rhs for u in units.values())
    yty = float(sum(u.yty for u in units.values()))
    n = int(sum(u.n_samples for u in units.values()))
    folds = [_Fold(gram - u.gram, rhs - u.rhs, u.gram, u.rhs, u.yty, u.n_samples) for u in units.values()]
    return folds, gram, rhs, yty, n


def _block(matrix: np.ndarray, idx: np.ndarray) -> np.ndarray:
    """``matrix[idx][:, idx]``: the matrix itself (no copy) when ``idx`` is every column in order."""
    if idx.size == matrix.shape[0] and np.array_equal(idx, np.arange(idx.size)):
        return matrix
    return matrix.take(idx, axis=0).take(idx, axis=1)


def _cholesky_solve(a: np.ndarray, rhs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``a^-1 rhs`` for a symmetric positive definite ``a`` and one right-hand side, and the
    upper Cholesky factor ``U`` (``a = U^T U``, Fortran-ordered).

    numpy's Cholesky and two level-2 triangular solves, not scipy's ``cho_factor``: scipy's
    wheels bring a second OpenBLAS whose idle threads spin for a while after each call and
    slow numpy's next factorisation (the final solve) several-fold on a 2-core machine.
    """
    upper = np.linalg.cholesky(a).T  # a = U^T U; the transpose is Fortran-ordered, as BLAS wants it (no copy)
    import scipy.linalg.blas  # here: a fixed-order fit needs no scipy (models.auto loads it before a BLAS limit)

    half = scipy.linalg.blas.dtrsv(upper, rhs, lower=0, trans=1)
    return scipy.linalg.blas.dtrsv(upper, half, lower=0, trans=0), upper


class _Evaluator:
    """Validation RMSE of (order, smoothing) from the statistics at the largest order."""

    def __init__(self, units: Mapping[str, NormalEquations], make_basis: Callable[[int], Basis],
                 ridge: float, power: float, target: np.ndarray | None = None) -> None:
        first = next(iter(units.values()))
        self.big, self.n_nodes = first.basis, first.n_nodes
        self.first = first
        self.n_shared = len(first.shared)
        if any(u.shared != first.shared for u in units.values()):
            raise InputError("the units' statistics have different shared columns; append them with one link list",
                             param="units")
        self.make_basis, self.ridge, self.power = make_basis, float(ridge), float(power)
        self.folds, self.gram, self.rhs, self.yty, self.n = _folds(units)
        if target is not None and target.size == first.n_pattern_columns and self.n_shared:
            target = np.concatenate([target, np.zeros(self.n_shared)])  # shared columns are not pulled
        self.target = target
        self.cv = len(units) >= 2
        self.pins: list[tuple[np.ndarray, np.ndarray] | None] = [None] * len(self.folds)
        if self.n_shared and self.cv:
            self.pins = self._fold_pins(units)
        self.seen: dict[tuple[int, float], float] = {}
        self.fold_sse: dict[tuple[int, float], np.ndarray] = {}  # per held-out unit, for within_noise()
        self.curve: list[CurvePoint] = []
        self._cache: dict[int, Any] = {}
        self._best_solved: tuple[tuple[int, float], list[tuple[np.ndarray, np.ndarray | None]]] | None = None

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
        c, _ = self._solve(self.gram, self._pulled(self.gram, self.rhs, w, smoothing, self.target), w, smoothing)
        values = c[pat:]
        pins: list[tuple[np.ndarray, np.ndarray] | None] = []
        for mask, fold in zip(free, self.folds):
            if mask.all():
                pins.append(None)
                continue
            weight = 1e6 * (np.diag(fold.gram)[pat:] + float(np.mean(np.diag(fold.gram)[:pat])))
            pins.append((np.where(mask, 0.0, weight), values.copy()))
        return pins

    def _weights(self, basis: Basis) -> np.ndarray:
        w = basis.roughness(self.power)
        floor = _CONSTANT_FLOOR * (float(np.min(w[w > 0])) if np.any(w > 0) else 1.0)
        return np.concatenate([np.tile(np.maximum(w, floor), self.n_nodes), np.zeros(self.n_shared)])

    def _blocks(self, order: int) -> tuple[np.ndarray, list[tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]]]:
        """Roughness weights and, per fold, the learning and held-out blocks of one order (cached)."""
        if order not in self._cache:
            basis = self.make_basis(order)
            idx = with_shared_columns(nested_columns(self.big, basis, self.n_nodes), self.first)
            sub = [(_block(f.gram, idx), f.rhs[idx], _block(f.held_gram, idx), f.held_rhs[idx]) for f in self.folds]
            if not self.cv:
                sub = [(_block(self.gram, idx), self.rhs[idx], np.empty(0), np.empty(0))]
            target = None if self.target is None else self.target[idx]
            while len(self._cache) >= _CACHED_ORDERS:  # a few orders at a time: bounded memory
                self._cache.pop(next(iter(self._cache)))
            self._cache[order] = (self._weights(basis), sub, target)
        return self._cache[order]

    def rmse(self, order: int, smoothing: float) -> float:
        key = (int(order), float(smoothing))
        if key in self.seen:
            return self.seen[key]
        w, blocks, target = self._blocks(int(order))
        if self.cv:
            per_fold = []
            solved = []
            for (g, r, held_g, held_r), f, pin in zip(blocks, self.folds, self.pins):
                c, upper = self._solve(g, self._pulled(g, r, w, smoothing, target, pin), w, smoothing, pin)
                solved.append((c, upper))
                per_fold.append(max(f.held_yty - 2.0 * c @ held_r + c @ held_g @ c, 0.0))
            self.fold_sse[key] = np.asarray(per_fold)
            value = float(np.sqrt(sum(per_fold) / self.n))
            if not self.seen or value < min(self.seen.values()):
                self._best_solved = (key, solved)  # the factors of the best point, for inflation()
        else:
            g, r, _, _ = blocks[0]
            value = self._gcv(g, self._pulled(g, r, w, smoothing, target), w, smoothing, r)
        self.seen[key] = value
        self.curve.append(CurvePoint(int(order), float(smoothing), value))
        return value

    def inflation(self, order: int, smoothing: float) -> float:
        """:func:`variance_inflation` of one (order, smoothing) (1 without held-out units)."""
        if not self.cv:
            return 1.0
        w, blocks, target = self._blocks(int(order))
        key = (int(order), float(smoothing))
        solved = self._best_solved[1] if self._best_solved and self._best_solved[0] == key else None
        excess = predicted = 0.0
        for k, ((g, r, held_g, held_r), f, pin) in enumerate(zip(blocks, self.folds, self.pins)):
            c, upper = solved[k] if solved else self._solve(g, self._pulled(g, r, w, smoothing, target, pin), w,
                                                            smoothing, pin)
            if upper is None:
                return 1.0
            # numpy's inverse, not LAPACK's potri from the Cholesky factor through scipy: a third
            # of the work, but scipy's second OpenBLAS pool, woken up, made it slower (see _cholesky_solve)
            inverse = np.linalg.inv(self._system(g, w, smoothing, pin))
            learn_n = self.n - f.held_n
            learn_sse = max((self.yty - f.held_yty) - 2.0 * c @ r + c @ g @ c, 0.0)
            dof = learn_n - float(np.sum(inverse * g))  # less the fit's effective parameters tr(A^-1 G)
            noise_var = learn_sse / max(dof, 1.0)
            held_sse = max(f.held_yty - 2.0 * c @ held_r + c @ held_g @ c, 0.0)
            excess += held_sse - f.held_n * noise_var
            # sum over the held-out samples of x^T (sigma^2 A^-1) x = sigma^2 tr(A^-1 X_u^T X_u)
            predicted += noise_var * float(np.sum(inverse * held_g))  # tr(A^-1 H), both symmetric
        return float(max(1.0, excess / predicted)) if predicted > 0 and np.isfinite(excess) else 1.0

    def _pulled(self, gram: np.ndarray, rhs: np.ndarray, w: np.ndarray, smoothing: float, target: np.ndarray | None,
                pin: tuple[np.ndarray, np.ndarray] | None = None) -> np.ndarray:
        """``X^T y`` plus the prior's pull ``P target`` (shrinking toward the prior, not zero) and
        the pull of pinned shared columns toward their values."""
        if (target is None or smoothing == 0) and pin is None:
            return rhs
        out = rhs.copy()
        if target is not None and smoothing != 0:
            out += smoothing * penalty_scale(gram, gram.shape[0] - self.n_shared) * w * target
        if pin is not None:
            out[gram.shape[0] - self.n_shared:] += pin[0] * pin[1]
        return out

    def _system(self, gram: np.ndarray, w: np.ndarray, smoothing: float,
                pin: tuple[np.ndarray, np.ndarray] | None = None) -> np.ndarray:
        """The penalised normal matrix: the ridge on the pattern columns (shared columns are not
        shrunk), the smoothness penalty, and the weight of pinned shared columns."""
        a = gram.copy()
        k = gram.shape[0] - self.n_shared
        a[np.arange(k), np.arange(k)] += self.ridge
        a[np.diag_indices_from(a)] += smoothing * penalty_scale(gram, k) * w
        if pin is not None:
            a[np.arange(k, gram.shape[0]), np.arange(k, gram.shape[0])] += pin[0]
        return a

    def _solve(self, gram: np.ndarray, rhs: np.ndarray, w: np.ndarray, smoothing: float,
               pin: tuple[np.ndarray, np.ndarray] | None = None) -> tuple[np.ndarray, np.ndarray | None]:
        """The penalised solution and the upper Cholesky factor of its system (None when the
        system is not positive definite: least squares then)."""
        try:
            return _cholesky_solve(self._system(gram, w, smoothing, pin), rhs)
        except np.linalg.LinAlgError:
            import scipy.linalg

            return scipy.linalg.lstsq(self._system(gram, w, smoothing, pin), rhs)[0], None

    def _gcv(self, g: np.ndarray, pulled: np.ndarray, w: np.ndarray, smoothing: float, r: np.ndarray) -> float:
        a = self._system(g, w, smoothing)
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


def _best_smoothing(ev: _Evaluator, order: int, grid: Sequence[float]) -> float:
    """Best smoothing of ``grid`` at one order: every other value, then the neighbours of the best."""
    values = sorted(float(g) for g in grid)
    coarse = values[::2] if values[-1] in values[::2] else [*values[::2], values[-1]]
    best = min(coarse, key=lambda s: ev.rmse(order, s))
    while best == values[-1] and best * 10.0 <= MAX_SMOOTHING:  # the best is at the edge: go on
        values.append(best * 10.0)
        best = min((best, values[-1]), key=lambda s: ev.rmse(order, s))
    i = values.index(best)
    return min(values[max(0, i - 1): i + 2], key=lambda s: ev.rmse(order, s))


def _best_order(ev: _Evaluator, orders: Sequence[int], smoothing: float) -> int:
    """Best order at one smoothing: every other order from the largest down (the curve is flat
    with small wiggles at high orders: no early stop), then the neighbours of the best."""
    best = min(list(orders)[::-1][::2], key=lambda o: ev.rmse(o, smoothing))
    return min([o for o in orders if abs(o - best) <= 1], key=lambda o: ev.rmse(o, smoothing))


def _walk_smoothing(ev: _Evaluator, order: int, start: float, values: list[float]) -> tuple[float, list[float]]:
    """From ``start``, step along the sorted smoothing ``values`` at one order while the
    validation error falls (past the largest, by decades up to :data:`MAX_SMOOTHING`)."""
    values = list(values)
    best = start
    for direction in (1, -1):
        while True:
            i = values.index(best) + direction
            if i == len(values) and values[-1] * 10.0 <= MAX_SMOOTHING:
                values.append(values[-1] * 10.0)
            if not 0 <= i < len(values) or ev.rmse(order, values[i]) >= ev.rmse(order, best):
                break
            best = values[i]
    return best, values


def _within_noise(ev: _Evaluator, best: CurvePoint, point: CurvePoint) -> bool:
    """Whether ``point``'s validation mean square exceeds ``best``'s by at most
    :data:`WITHIN_NOISE_SE` standard errors of their paired difference (the held-out units'
    differences taken as independent draws) and by at most :data:`WITHIN_NOISE_FRACTION` of it.
    Needs :data:`MIN_NOISE_UNITS` held-out units: from two, the standard error is no estimate."""
    if not ev.cv or len(ev.folds) < MIN_NOISE_UNITS:
        return point == best
    b = ev.fold_sse[(best.order, best.smoothing)]
    d = (ev.fold_sse[(point.order, point.smoothing)] - b) / ev.n
    se = float(np.sqrt(d.size * np.var(d, ddof=1)))
    return float(d.sum()) <= min(WITHIN_NOISE_SE * se, WITHIN_NOISE_FRACTION * float(b.sum()) / ev.n)


def _tightest_split(ev: _Evaluator, best: CurvePoint, points: Sequence[CurvePoint]) -> CurvePoint:
    """Among the points within noise of the best validation error, the one that shrinks the
    patterns least (the least smoothing, then the largest order): smoothing chosen for the joint
    prediction alone leaves the split between the nodes' patterns (what the joint gain does not
    see) to the penalty, so a smoothing the held-out units cannot tell from the best is no
    reason to pull the patterns further toward the prior."""
    close = [p for p in points if _within_noise(ev, best, p)]
    return min(close, key=lambda p: (p.smoothing, -p.order)) if close else best


def select_order_and_smoothing(
    units: Mapping[str, NormalEquations],
    make_basis: Callable[[int], Basis],
    orders: Sequence[int],
    ridge: float = 1.0,
    power: float = DEFAULT_PENALTY_POWER,
    grid: Sequence[float] = SMOOTHING_GRID,
    target: np.ndarray | None = None,
) -> Selection:
    """Choose order and smoothing by grouped cross-validation (or GCV for one unit).

    Parameters
    ----------
    units : mapping of unit label to NormalEquations
        Statistics of every learning unit, all accumulated with the basis of ``max(orders)``.
    make_basis : callable
        ``make_basis(order)`` -> the basis of that order (nested in the largest for SH).
    orders : sequence of int
        Candidate orders; for BG and P a single one.
    ridge : float
        The solver's ridge, kept in every solve.
    power : float
        Exponent of the SH roughness weights.
    grid : sequence of float
        Relative smoothing values tried.
    target : ndarray, optional
        Prior coefficients at the largest order (one per column): the penalty shrinks toward
        them instead of toward zero (``fit --prior``).

    Raises
    ------
    IdentifiabilityError
        When no unit holds samples, or every candidate fails.
    """
    units = {str(k): v for k, v in units.items() if v.n_samples > 0}
    if not units:
        raise IdentifiabilityError("no learning samples to choose an order from")
    orders = sorted({int(o) for o in orders})
    if not orders:
        raise InputError("orders: no candidate order", param="orders")
    ev = _Evaluator(units, make_basis, ridge, power, target)
    best_s = _best_smoothing(ev, orders[(len(orders) - 1) // 2], grid)
    best_o = _best_order(ev, orders, best_s)
    values = sorted({float(g) for g in grid} | {best_s})
    for _ in range(len(orders) + len(values)):  # coordinate descent; each pass moves or stops
        best_s, values = _walk_smoothing(ev, best_o, best_s, values)
        moved = _best_order(ev, orders, best_s)
        if moved == best_o:
            break
        best_o = moved
    finite = [p for p in ev.curve if np.isfinite(p.rmse_db)]
    if not finite:
        raise IdentifiabilityError("no candidate order and smoothing could be fitted")
    best = min(finite, key=lambda p: (p.rmse_db, p.order, -p.smoothing))
    choice = _tightest_split(ev, best, finite)
    return Selection("grouped-cv" if ev.cv else "gcv", choice.order, choice.smoothing, choice.rmse_db,
                     ev.curve, sorted(units) if ev.cv else [], float(power), ev.inflation(choice.order, choice.smoothing))


def variance_inflation(
    units: Mapping[str, NormalEquations],
    make_basis: Callable[[int], Basis],
    order: int,
    smoothing: float,
    ridge: float = 1.0,
    power: float = DEFAULT_PENALTY_POWER,
    target: np.ndarray | None = None,
) -> float:
    """How much the posterior covariance understates the error on held-out flight units.

    For each unit ``u`` held out, the fit ``c`` of the others predicts its samples with a
    squared error whose expectation under the Bayesian reading of the penalised solve is
    ``n_u sigma^2 + sigma^2 tr(A^-1 X_u^T X_u)``: new noise plus the posterior variance of the
    fit at the held-out directions (``A`` the penalised normal matrix, ``sigma^2`` the fold's
    learning residual variance, its squared error over the samples less the fit's effective
    number of parameters ``tr(A^-1 X^T X)``, so that a correct model gives 1). The factor returned is the observed excess over the noise
    divided by that predicted variance, summed over the folds, and at least 1. It is above 1
    when neighbouring packets share their errors (fading and shadowing correlated in time:
    fewer independent samples than packets) and when the pattern misfits between units
    (another altitude, another stretch of the sphere); multiplying the posterior covariance
    by it makes the predictive spread of a new flight honest. Everything comes from the
    per-unit statistics; 1 for a single unit.
    """
    units = {str(k): v for k, v in units.items() if v.n_samples > 0}
    if not units:
        raise IdentifiabilityError("no learning samples to validate on")
    return _Evaluator(units, make_basis, ridge, power, target).inflation(int(order), float(smoothing))


def validation_rmse(
    units: Mapping[str, NormalEquations],
    make_basis: Callable[[int], Basis],
    orders: Sequence[int],
    smoothing: float,
    ridge: float = 1.0,
    power: float = DEFAULT_PENALTY_POWER,
) -> list[float]:
    """Validation RMSE [dB] of every order at one smoothing (the curve a sweep plots), by
    grouped cross-validation (GCV with one unit), from statistics at ``max(orders)``."""
    units = {str(k): v for k, v in units.items() if v.n_samples > 0}
    if not units:
        raise IdentifiabilityError("no learning samples to validate on")
    ev = _Evaluator(units, make_basis, ridge, power)
    return [ev.rmse(int(o), float(smoothing)) for o in orders]


__all__ = [
    "validation_rmse",
    "variance_inflation",
    "DEFAULT_PENALTY_POWER",
    "MAX_SMOOTHING",
    "SMOOTHING_GRID",
    "CurvePoint",
    "Selection",
    "nested_columns",
    "penalty_scale",
    "penalty_vector",
    "select_order_and_smoothing",
    "sub_statistics",
]
