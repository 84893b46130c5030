"""Joint least-squares identification of one radiation pattern per node (paper Sec. IV-B, V-A).

Each signal sample ``i`` names its transmitter ``t_i`` and receiver ``r_i`` and observes the joint
gain ``y_i = G_t(az_tx_i, el_tx_i) + G_r(az_rx_i, el_rx_i) + noise`` (paper eq. 5). With every
pattern a linear combination of the same basis, ``G_n = f(az, el) . p_n``, the row of sample
``i`` in the design matrix holds ``f(az_tx, el_tx)`` in the block of node ``t_i``,
``f(az_rx, el_rx)`` in the block of ``r_i`` and zeros elsewhere (the paper's Sec. V-A matrix).
Shared columns may follow the patterns' (:meth:`NormalEquations.with_shared`): the
log-distance column of the environment term, whose coefficient is the path-loss exponent less
2, and one electronics offset per link logged both ways (half the difference of its two
directions; the common part is the joint level of the patterns). Their coefficients are
unpenalised; an environment column the directions explain (a flight at constant distance, or
at constant altitude over a static station) is refused as not identifiable.

The solver never forms the design matrix: it accumulates the sufficient statistics
``X^T X``, ``X^T y``, ``y^T y`` and ``n`` chunk by chunk
(:class:`~rplearn.core.lsq.normal_equations.NormalEquations`), so memory does not grow with the
number of samples, then solves the ridge-regularised normal equations (:func:`solve`).

Identifiability (paper Sec. V-A, docs/conventions.md). A constant can move between the two ends of a
link: ``G_t + c`` and ``G_r - c`` predict the same. In a connected group of nodes whose link
graph is bipartite (two nodes, or an even cycle) this leaves exactly one free constant,
``+c`` on one side of the bipartition and ``-c`` on the other; a link graph with an odd cycle
(a triangle) fixes it. The solver does not leave this to the ridge: for every bipartite
component it adds one explicit linear constraint (the *gauge*), by default "both sides have the
same mean gain over the sphere" (``gauge="equal-mean"``), or "node N has mean gain V dBi over
the sphere" (``gauge={"node": N, "mean_gain_dbi": V}``) when one antenna's level is known. The
fit report names the gauge of every component.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from rplearn._argtypes import check_types
from rplearn.core.bases import Basis
from rplearn.core.gauge import EQUAL_MEAN, Gauge
from rplearn.core.geometry import Directions
from rplearn.core.lsq.closing import Regularisation, close_solution
from rplearn.core.lsq.level import shrink_target
from rplearn.core.lsq.normal_equations import EXPONENT_MIN_SPREAD_DB, NormalEquations, independent_spread_db
from rplearn.core.lsq.solution import FitReport, GaugeNote, JointSolution
from rplearn.core.lsq.solver_large import solve_large, unit_shared_scaling
from rplearn.core.lsq.spectrum import null_directions, spectrum_estimate, spectrum_report
from rplearn.errors import IdentifiabilityError, InputError

FloatArray = NDArray[np.float64]

#: Default ridge weight lambda added to the diagonal of X^T X (absolute, like the paper's
#: kappa = 50 and scikit-learn's ``alpha``). Identifiability is handled by the gauge, so the
#: ridge only guards against directions the flight did not cover: against the diagonal of
#: X^T X of a well-covered flight (about n / (4 pi) = 4,500 for SH and 56,000 samples) it
#: changes no prediction measurably (paper replica: SH-10 test RMSE 4.481 dB with 1e-6 or 1),
#: while on a single short unit it keeps SH-10 from extrapolating to 1,323 dB RMSE (7.8 dB).
DEFAULT_RIDGE = 1.0
#: Where the level a prior's pattern is shrunk toward comes from: ``"data"`` (the prior gives
#: only its shape; :mod:`rplearn.core.lsq.level`) or ``"prior"`` (its absolute dBi, for calibrated
#: power and a trusted reference).
PRIOR_LEVELS: tuple[str, ...] = ("data", "prior")


# -------------------------------------------------------------------------------------------
# Link graph


@check_types
def link_components(n_nodes: int, links: Iterable[tuple[int, int]]) -> list[tuple[list[int], list[int] | None]]:
    """Connected components of the link graph and, for bipartite ones, their two sides.

    Returns
    -------
    list of (nodes, side_b)
        ``side_b`` is the list of nodes on the second side of the bipartition, or ``None``
        when the component has an odd cycle (absolute gains identifiable).
    """
    adj: dict[int, set[int]] = {i: set() for i in range(n_nodes)}
    for a, b in links:
        adj[a].add(b)
        adj[b].add(a)
    color = [-1] * n_nodes
    out = []
    for start in range(n_nodes):
        if color[start] != -1:
            continue
        color[start] = 0
        comp = [start]
        bipartite = True
        queue = deque([start])
        while queue:
            u = queue.popleft()
            for v in adj[u]:
                if color[v] == -1:
                    color[v] = 1 - color[u]
                    comp.append(v)
                    queue.append(v)
                elif color[v] == color[u]:
                    bipartite = False
        comp.sort()
        out.append((comp, [v for v in comp if color[v] == 1] if bipartite else None))
    return out


# -------------------------------------------------------------------------------------------
# Reports and solutions


#: Above this many columns the solver estimates the spectrum (:func:`spectrum_estimate`)
#: instead of a full eigendecomposition, and factorises the regularised system by Cholesky
#: (:mod:`rplearn.core.lsq.solver_large`) instead of inverting the KKT matrix: swarms of tens of nodes.
#: At and below it every result is as before.
LARGE_COLUMNS = 1500


def _gauge_constraints(
    basis: Basis,
    n_nodes: int,
    node_names: Sequence[str],
    components: list[tuple[list[int], list[int] | None]],
    gauge: Gauge,
) -> tuple[FloatArray, FloatArray, list[GaugeNote]]:
    p = basis.n_coef
    mean = basis.sphere_mean
    rows, values, notes = [], [], []
    fixed_node = None
    fixed_value = 0.0
    if gauge.node is not None:
        if gauge.node not in node_names:
            raise InputError(f"gauge: unknown node {gauge.node!r}; nodes are {', '.join(node_names)}", param="gauge_node")
        fixed_node = list(node_names).index(gauge.node)
        fixed_value = float(gauge.mean_gain_dbi or 0.0)
    if fixed_node is not None:
        for comp, side_b in components:
            if fixed_node in comp and side_b is None:
                raise InputError(
                    f"gauge: node {node_names[fixed_node]} is in a group whose links form an odd cycle, so its "
                    "absolute gain is already identified; fit without a gauge node"
                )
    for comp, side_b in components:
        if side_b is None or len(comp) < 2:
            continue
        side_a = [v for v in comp if v not in side_b]
        names = tuple(node_names[v] for v in comp)
        sa = tuple(node_names[v] for v in side_a)
        sb = tuple(node_names[v] for v in side_b)
        row = np.zeros(n_nodes * p)
        if fixed_node is not None and fixed_node in comp:
            row[fixed_node * p : (fixed_node + 1) * p] = mean
            rows.append(row)
            values.append(fixed_value)
            text = (
                f"links among {', '.join(names)} form no odd cycle, so one constant is unidentifiable "
                f"(+c on {', '.join(sa)}, -c on {', '.join(sb)}); fixed by setting the sphere-mean gain "
                f"of {node_names[fixed_node]} to {fixed_value:g} dBi"
            )
            notes.append(GaugeNote(names, sa, sb, f"fixed-mean:{node_names[fixed_node]}={fixed_value:g}", text))
        else:
            for v in side_a:
                row[v * p : (v + 1) * p] += mean / len(side_a)
            for v in side_b:
                row[v * p : (v + 1) * p] -= mean / len(side_b)
            rows.append(row)
            values.append(0.0)
            text = (
                f"links among {', '.join(names)} form no odd cycle, so one constant is unidentifiable "
                f"(+c on {', '.join(sa)}, -c on {', '.join(sb)}); fixed by giving both sides the same "
                "mean gain over the sphere (only pattern shapes and the joint level are identified)"
            )
            notes.append(GaugeNote(names, sa, sb, "equal-mean", text))
    if rows:
        return np.array(rows), np.array(values), notes
    return np.zeros((0, n_nodes * p)), np.zeros(0), notes


@check_types
def solve(
    normal: NormalEquations,
    node_names: Sequence[str] | None = None,
    ridge: float = DEFAULT_RIDGE,
    gauge: Gauge | str | Mapping[str, Any] = EQUAL_MEAN,
    min_samples_per_coef: float = 1.0,
    penalty: FloatArray | None = None,
    penalty_target: FloatArray | None = None,
    prior_level: str = "data",
) -> JointSolution:
    """Solve accumulated normal equations with a ridge and explicit gauge constraints.

    Minimises ``||X p - y||^2 + sum_j (ridge + penalty_j) (p_j - t_j)^2`` (the ridge on the
    pattern columns only) subject to one gauge constraint per bipartite component of the link
    graph (see module docstring), through the KKT system
    ``[[X^T X + ridge I + diag(penalty), C^T], [C, 0]] [p; mu] = [X^T y + (ridge + penalty) t; d]``.
    ``penalty`` (one non-negative weight per column, absolute units of ``X^T X``) is the
    smoothness penalty of :mod:`rplearn.core.lsq.selection`. The target ``t``
    (:func:`rplearn.core.lsq.level.shrink_target`) is never a fixed level: its shape is that of
    ``penalty_target`` (one value per pattern column: a prior pattern's coefficients, whose
    per-node sphere mean is dropped) or zero, and its constant per node is the data's (the
    least-squares constants under the same gauge), so that adding a constant to every ``y``
    moves every prediction by that constant and changes nothing else. A known absolute level
    is given by the gauge (``{"node": N, "mean_gain_dbi": V}``), or, with calibrated power and a
    trusted reference, by ``prior_level="prior"``: the target is then ``penalty_target`` itself,
    its absolute level included (shifting the data then moves the fit toward or away from it).

    Raises
    ------
    IdentifiabilityError
        Fewer samples than columns (times ``min_samples_per_coef``), a node without samples,
        or a singular system (coverage too poor for the basis; raise the ridge).
    """
    n_nodes = normal.n_nodes
    names = list(node_names) if node_names is not None else [str(i) for i in range(n_nodes)]
    if len(names) != n_nodes:
        raise InputError(f"{len(names)} node names for {n_nodes} nodes")
    if not (np.isfinite(ridge) and ridge >= 0):
        raise InputError(f"ridge must be a non-negative number, got {ridge!r}")
    pcols = normal.n_columns
    pat = normal.n_pattern_columns
    if normal.n_samples < min_samples_per_coef * pcols:
        raise IdentifiabilityError(
            f"{normal.n_samples} samples cannot identify {pcols} coefficients "
            f"({n_nodes} nodes x {normal.basis.label}); fly longer or choose a smaller model"
        )
    seen: set[int] = set()
    for a, b in normal.link_counts:
        seen.update((a, b))
    missing = [names[i] for i in range(n_nodes) if i not in seen]
    if missing:
        raise IdentifiabilityError(f"node(s) {', '.join(missing)} appear in no sample; their patterns cannot be learned")
    components = link_components(n_nodes, normal.link_counts.keys())
    _check_exponent(normal)
    cmat, cval, notes = _gauge_constraints(normal.basis, n_nodes, names, components, Gauge.of(gauge))
    cmat = np.pad(cmat, ((0, 0), (0, pcols - pat)))
    large = pcols > LARGE_COLUMNS
    k = cmat.shape[0]
    if penalty is not None:
        penalty = _pad_shared(np.asarray(penalty, np.float64), pat, pcols)
        if penalty.shape != (pcols,) or not np.all(np.isfinite(penalty)) or np.any(penalty < 0):
            raise InputError(f"penalty: expected {pcols} non-negative finite weights, got shape {penalty.shape}")
    rhs = np.concatenate([normal.rhs, cval])
    prior = None
    if penalty_target is not None:
        prior = _pad_shared(np.asarray(penalty_target, np.float64), pat, pcols)
        if prior.shape != (pcols,) or not np.all(np.isfinite(prior)):
            raise InputError(f"penalty_target: expected {pcols} finite values, got shape {prior.shape}")
    if prior_level not in PRIOR_LEVELS:
        raise InputError(f"prior level: expected {' or '.join(PRIOR_LEVELS)}, got {prior_level!r}", param="prior_level")
    shrunk = ridge > 0 or (penalty is not None and bool(np.any(penalty > 0)))
    if shrunk and prior is not None and prior_level == "prior":
        weights = np.zeros(pcols)
        weights[:pat] = ridge
        rhs[:pcols] += (weights + (0.0 if penalty is None else penalty)) * prior
    elif shrunk:  # toward the data's level and the prior's shape, never toward a fixed level
        weights = np.zeros(pcols)
        weights[:pat] = ridge
        if penalty is not None:
            weights += penalty
        target = shrink_target(normal.gram, normal.rhs, normal.basis, n_nodes, None if prior is None else prior[:pat],
                               (cmat, cval), components)
        rhs[:pcols] += weights * target
    if large:
        solution = solve_large(normal, n_nodes, components, (cmat, cval), rhs[:pcols], penalty,
                               Regularisation(float(ridge), penalty is not None, shrunk), notes)
        if solution is not None:
            return solution
        sv, rank, cond = spectrum_estimate(_unit_shared_columns(normal), null_directions(normal.basis, n_nodes, components, pcols))
    else:
        sv, rank, cond = spectrum_report(_unit_shared_columns(normal))
    kkt = np.zeros((pcols + k, pcols + k))
    kkt[:pcols, :pcols] = normal.gram
    kkt[np.arange(pat), np.arange(pat)] += ridge  # the shared columns are not shrunk
    if penalty is not None:
        kkt[np.arange(pcols), np.arange(pcols)] += penalty
    kkt[:pcols, pcols:] = cmat.T
    kkt[pcols:, :pcols] = cmat
    # the KKT inverse (every system of up to LARGE_COLUMNS columns)
    # Scale rows/columns for a better-conditioned factorisation.
    scale = 1.0 / np.sqrt(np.maximum(np.abs(np.diag(kkt))[:pcols], 1e-300))
    full_scale = np.concatenate([scale, np.ones(k)])
    kkt_s = kkt * full_scale[:, None] * full_scale[None, :]
    # numpy's LAPACK (not scipy's): a second OpenBLAS thread pool would wait for numpy's
    # spinning threads after the big rank-k update and make this small inverse 40x slower.
    try:
        kinv_s = np.linalg.inv(kkt_s)
    except np.linalg.LinAlgError:
        kinv_s = np.full((pcols + k, pcols + k), np.nan)
    finite = bool(np.all(np.isfinite(kinv_s)))
    from rplearn.core.lsq.solver_cholesky import MAX_KKT_CONDITION  # (ctypes: loaded where used)

    cond_1 = float(np.abs(kkt_s).sum(axis=0).max() * np.abs(kinv_s).sum(axis=0).max()) if finite else np.inf
    if not finite or cond_1 > MAX_KKT_CONDITION:
        raise IdentifiabilityError(
            f"the samples do not identify {normal.basis.label} for {n_nodes} nodes: design rank {rank} of "
            f"{pcols} columns, {pcols - rank} free direction(s) but only {k} gauge constant(s); "
            "add samples over the uncovered directions, choose a smaller model, or raise the ridge"
        )
    kinv = kinv_s * full_scale[:, None] * full_scale[None, :]
    coef = (kinv @ rhs)[:pcols]
    return close_solution(normal, coef, (sv, rank, cond), notes, k,
                          Regularisation(float(ridge), penalty is not None, shrunk),
                          KktInverse(kinv[:pcols, :pcols], normal.gram))


class KktInverse:
    """The dense path's :class:`~rplearn.core.lsq.closing.SolvedSystem`: the top-left block
    ``M`` of the inverse KKT matrix (the covariance of the constrained estimate, sandwiched with
    ``X^T X`` when a ridge alone regularises), its covariance formed at once."""

    lazy: ClassVar[bool] = False

    def __init__(self, inverse: FloatArray, gram: FloatArray) -> None:
        self.inverse, self.gram = inverse, gram

    def fitted_square(self, gram: FloatArray, coef: FloatArray) -> float:
        return float(coef @ gram @ coef)  # numpy's BLAS: a fixed-order fit imports no scipy

    def inverse_diagonal(self, index: NDArray[np.intp]) -> FloatArray:
        return np.diag(self.inverse)[index]

    def covariance(self, variance: float, sandwich: bool) -> FloatArray:
        a = self.inverse
        cov = variance * (a @ self.gram @ a.T) if sandwich else variance * a
        return 0.5 * (cov + cov.T)


def penalised_inverse(
    normal: NormalEquations,
    node_names: Sequence[str],
    ridge: float,
    gauge: Gauge | str | Mapping[str, Any],
    penalty: FloatArray,
) -> FloatArray | None:
    """The top-left block ``M`` of the inverse KKT matrix :func:`solve` forms with this ridge,
    penalty and gauge, through one Cholesky factor.

    Its covariance is ``s^2 M`` (``s^2`` the residual variance: a posterior's, the penalty
    read as a prior). No coefficients, spectrum or report of a solve
    (:func:`rplearn.core.lsq.solver_cholesky.constrained_inverse`): for the automatic fit's
    posteriors at other smoothings, which read nothing else.

    Parameters
    ----------
    normal : NormalEquations
        The statistics (with their shared columns, if any).
    node_names : sequence of str
        One name per node, in the statistics' order (for the gauge).
    ridge : float
        Added to the diagonal of the pattern columns (not the shared ones).
    gauge : Gauge, str or mapping
        As :func:`solve`'s.
    penalty : 1-D float64 array
        Non-negative finite weight of every column (or of every pattern column: the shared
        ones then get none), absolute units of ``X^T X``.

    Returns
    -------
    (n_columns, n_columns) float64 array or None
        ``M``. None when the regularised matrix is not positive definite or the KKT matrix is
        conditioned worse than :func:`solve` accepts
        (:data:`~rplearn.core.lsq.solver_cholesky.MAX_KKT_CONDITION`): :func:`solve` then
        gives its own answer or tells why there is none.

    Raises
    ------
    InputError
        When ``penalty`` has not one non-negative finite weight per column.
    """
    from rplearn.core.lsq.solver_cholesky import constrained_inverse

    pcols, pat = normal.n_columns, normal.n_pattern_columns
    weights = _pad_shared(np.asarray(penalty, np.float64), pat, pcols)
    if weights.shape != (pcols,) or not np.all(np.isfinite(weights)) or np.any(weights < 0):
        raise InputError(f"penalty: expected {pcols} non-negative finite weights, got shape {weights.shape}")
    names = list(node_names)
    components = link_components(normal.n_nodes, normal.link_counts.keys())
    cmat = _gauge_constraints(normal.basis, normal.n_nodes, names, components, Gauge.of(gauge))[0]
    cmat = np.pad(cmat, ((0, 0), (0, pcols - pat)))
    a = np.array(normal.gram, np.float64)
    a[np.arange(pat), np.arange(pat)] += float(ridge)
    a[np.arange(pcols), np.arange(pcols)] += weights
    return constrained_inverse(a, cmat)


def _unit_shared_columns(normal: NormalEquations) -> FloatArray:
    """See :func:`rplearn.core.lsq.solver_large.unit_shared_scaling`."""
    return unit_shared_scaling(normal)[0]


def _pad_shared(values: FloatArray, pat: int, pcols: int) -> FloatArray:
    """Per-column weights given for the pattern columns only, padded with zeros for shared ones."""
    if values.ndim == 1 and values.size == pat and pcols > pat:
        return np.concatenate([values, np.zeros(pcols - pat)])
    return values


def _check_exponent(normal: NormalEquations) -> None:
    """Refuse a path-loss exponent the other columns could take (see :data:`EXPONENT_MIN_SPREAD_DB`)."""
    pat = normal.n_pattern_columns
    n = max(normal.n_samples, 1)
    for j, col in enumerate(normal.shared):
        if col[0] != "exponent":
            continue
        independent_db = independent_spread_db(normal, pat + j)
        if independent_db >= EXPONENT_MIN_SPREAD_DB:
            continue
        mean = normal.environment_sum / n
        std = float(np.sqrt(max(normal.gram[pat + j, pat + j] / n - mean**2, 0.0)))
        lo, hi = 10 ** ((-mean - 2 * std) / 10), 10 ** ((-mean + 2 * std) / 10)
        raise IdentifiabilityError(
            f"the path-loss exponent is not identifiable: the distance spans only about {lo:.3g}-{hi:.3g} m "
            f"(mean +- 2 std), and the part of 10 log10 d the directions do not explain varies by "
            f"{independent_db:.2f} dB (std; at least {EXPONENT_MIN_SPREAD_DB:g} dB is needed), so the patterns could "
            "take any exponent; fit in free space (or with the two-ray term), or fly the same directions at "
            "several distances",
            param="path_loss",
        )


@check_types
@dataclass(frozen=True, eq=False)
class JointFitOptions:
    """How :func:`fit_joint` learns the patterns (everything but the samples and the basis).

    Attributes
    ----------
    ridge : float
        Ridge weight added to the diagonal of ``X^T X`` (default :data:`DEFAULT_RIDGE`).
    gauge : Gauge
        How the free constant of a two-node (bipartite) problem is fixed (also the legacy
        ``"equal-mean"`` or ``{"node": ID, "mean_gain_dbi": V}``, read by :meth:`Gauge.of`).
    smoothing : float
        Relative weight of the smoothness penalty (:mod:`rplearn.core.lsq.selection`).
    penalty_power : float
        Exponent of the SH roughness weights.
    environment : array_like, optional
        A shared per-sample regressor learned with the patterns, one value per sample (the
        log-distance column of :func:`rplearn.core.environment.log_distance_column`).
    link_offsets : bool
        Learn one electronics offset per link logged in both directions.
    chunk_size : int
        Samples accumulated per step.

    Raises
    ------
    InputError
        On the first invalid option, naming it (``param``).
    """

    ridge: float = DEFAULT_RIDGE
    gauge: Gauge | str | Mapping[str, Any] = field(default_factory=Gauge)
    smoothing: float = 0.0
    penalty_power: float = 2.0
    environment: ArrayLike | None = None
    link_offsets: bool = False
    chunk_size: int = 1_000_000

    def __post_init__(self) -> None:
        object.__setattr__(self, "gauge", Gauge.of(self.gauge))
        for name in ("ridge", "smoothing"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float, np.number)) and np.isfinite(value) and value >= 0):
                raise InputError(f"{name}: expected a non-negative number, got {value!r}", param=name)
        if not (isinstance(self.penalty_power, (int, float, np.number)) and np.isfinite(self.penalty_power)):
            raise InputError(f"penalty_power: expected a finite number, got {self.penalty_power!r}",
                             param="penalty_power")
        if isinstance(self.chunk_size, bool) or not isinstance(self.chunk_size, (int, np.integer)) or self.chunk_size < 1:
            raise InputError(f"chunk_size: expected a positive number of samples, got {self.chunk_size!r}",
                             param="chunk_size")


@check_types
def fit_joint(
    directions: Directions,
    tx_index: ArrayLike,
    rx_index: ArrayLike,
    joint_gain_db: ArrayLike,
    n_nodes: int,
    basis: Basis,
    node_names: Sequence[str] | None = None,
    options: JointFitOptions | None = None,
) -> JointSolution:
    """Fit one pattern per node from link samples (paper Sec. IV-B and V-A).

    Parameters
    ----------
    directions : Directions
        ``az_tx, el_tx, az_rx, el_rx`` [rad] of every sample (paper eq. 3).
    tx_index, rx_index : array_like of int
        Node index of the transmitter and the receiver of every sample.
    joint_gain_db : array_like
        Observed joint gain [dB] (paper eq. 5).
    n_nodes : int
        Number of nodes.
    basis : Basis
        Pattern basis shared by all nodes.
    node_names : sequence of str, optional
        Names used in reports and gauge notes.
    options : JointFitOptions, optional
        Ridge, gauge, smoothing, shared columns (default ``JointFitOptions()``).

    Examples
    --------
    >>> sol = fit_joint(d, tx, rx, y, 2, basis, ["A", "B"], JointFitOptions(ridge=1e-6))  # doctest: +SKIP
    """
    options = JointFitOptions() if options is None else options
    environment, chunk_size = options.environment, options.chunk_size
    normal = NormalEquations(basis, n_nodes, environment=environment is not None)
    env = None if environment is None else np.asarray(environment, np.float64).ravel()
    tx = np.asarray(tx_index)
    rx = np.asarray(rx_index)
    y = np.asarray(joint_gain_db, np.float64)
    n = y.size
    for s in range(0, max(n, 1), chunk_size):
        e = min(n, s + chunk_size)
        normal.add(Directions(*(np.asarray(d)[s:e] for d in directions)), tx[s:e], rx[s:e], y[s:e],
                   None if env is None else env[s:e])
    if env is not None or options.link_offsets:
        normal = normal.with_shared(normal.two_way_links() if options.link_offsets else None)
    penalty = None
    if options.smoothing:
        from rplearn.core.lsq.selection import penalty_scale, penalty_vector

        penalty = penalty_vector(basis, n_nodes, options.smoothing,
                                 penalty_scale(normal.gram, normal.n_pattern_columns), options.penalty_power)
    return solve(normal, node_names, ridge=options.ridge, gauge=options.gauge, penalty=penalty)


@check_types
def identifiability(
    directions: Directions,
    tx_index: ArrayLike,
    rx_index: ArrayLike,
    n_nodes: int,
    basis: Basis,
    node_names: Sequence[str] | None = None,
) -> FitReport:
    """Rank, null-space dimension and condition number a set of directions gives a model.

    Used to check a flight plan before flying (no signal needed).
    """
    normal = NormalEquations(basis, n_nodes)
    normal.add(directions, tx_index, rx_index, None)
    names = list(node_names) if node_names is not None else [str(i) for i in range(n_nodes)]
    components = link_components(n_nodes, normal.link_counts.keys())
    expected = sum(1 for comp, side_b in components if side_b is not None and len(comp) > 1)
    notes = _gauge_constraints(basis, n_nodes, names, components, Gauge())[2]
    sv, rank, cond = spectrum_report(normal.gram)
    return FitReport(
        n_samples=normal.n_samples,
        n_columns=normal.n_columns,
        rank=rank,
        null_dim=normal.n_columns - rank,
        condition_number=cond,
        expected_null_dim=expected,
        gauges=tuple(notes),
        ridge=0.0,
        rmse_db=float("nan"),
        singular_values=sv,
    )
