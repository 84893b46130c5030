"""``fit --order auto``: a regularised pattern whose order and smoothing the data choose.

The statistics of every learning unit are accumulated once, at the largest candidate order;
:func:`rplearn.core.lsq.selection.select_order_and_smoothing` chooses order and smoothing by grouped
cross-validation over the units (GCV with one unit); the model is then solved from the sum of
the same statistics (a sub-block for a smaller SH order), so no sample is read twice.
"""

from __future__ import annotations

import functools
import time
from collections import Counter
from collections.abc import Callable, Mapping, Sequence
from contextlib import ExitStack
from typing import Any

import numpy as np
import scipy.linalg  # noqa: F401  (order selection solves through scipy: loaded before any BLAS limit, rplearn.core.threads)

from rplearn.core.geometry import Directions
from rplearn.core.lsq.block_sums import time_block_labels
from rplearn.core.lsq.link_statistics import reserve_block_buffer
from rplearn.core.lsq.normal_equations import NormalEquations
from rplearn.core.lsq.runtime import DEFAULT_RUNTIME
from rplearn.core.lsq.selection import (
    DEFAULT_PENALTY_POWER,
    SearchPrior,
    Selection,
    at_smoothing_cap,
    nested_columns,
    penalty_scale,
    penalty_vector,
    select_beside,
    select_order_and_smoothing,
    sub_statistics,
)
from rplearn.core.lsq.solver import penalised_inverse, solve
from rplearn.core.plausible import check_same_band
from rplearn.core.threads import blas_threads_for, one_blas_thread
from rplearn.core.threads import warm_up as warm_up_blas
from rplearn.data.tables import LinkSamples
from rplearn.errors import InputError
from rplearn.models.auto_prior import deviation_problem, held_out_errors, keeps_prior, kept_prior_coef, kept_prior_target, kept_within_noise
from rplearn.models.auto_spread import (
    drift_std_db,
    held_out_misfit_var,
    misfit_covariance,
    planning_basis,
    prior_misfit_var,
    prior_std_db,
    unseen_spread_cap_db,
    within_unit_noise_var,
)
from rplearn.models.fit import FittedModel, LearningGram
from rplearn.models.load import load_priors
from rplearn.models.node_coverage import CoverageWork
from rplearn.models.options import FitOptions
from rplearn.models.own_posterior import OwnPrior, continued_jobs, continued_parts, continued_points, own_pattern_posterior, solved_parts, tied_own_posterior
from rplearn.models.patterns import PatternSet
from rplearn.models.spec import ModelSpec, check_model_size, default_ridge
from rplearn.models.streamed import frequency_counts, weighted_median
from rplearn.models.terms import regression_inputs, shared_fields, statistics_counts
from rplearn.models.training import TrainingSummary

#: Largest SH order ``--order auto`` considers (the cost of the selection is that of one fit
#: at this order: its statistics are accumulated once). A cost cap: on the paper's data the
#: cross-validated error still falls, by about 0.01 dB, from SH-15 to SH-16, while the
#: selection's time grows by a third (2.5x against 3.4x one SH-10 fit; benchmarks/auto_fit.py).
MAX_AUTO_ORDER = 15
#: An order is a candidate only with at least this many learning samples per coefficient.
SAMPLES_PER_COEF = 10
#: Penalty exponent with a prior: plain ridge on the deviation from the prior, so that where the
#: flight did not look the pattern is the prior's (a smoothness penalty would extend the
#: deviations fitted on the covered band over the whole sphere, all the more where it is narrow;
#: measured on the ``ground`` preset: 4.25-4.60 dB test RMSE with 0 against 4.38-4.88 dB with 2).
PRIOR_PENALTY_POWER = 0.0
#: Orders of BG and P when chosen automatically (their smoothing is chosen; the order is the default).
_FIXED_AUTO_ORDER = {"bg": 7, "poly": 12}


def auto_orders(kind: str, n_samples: int, n_nodes: int, order: int | None = None) -> list[int]:
    """Candidate orders: SH 2 .. the largest with :data:`SAMPLES_PER_COEF` samples per
    coefficient (at most :data:`MAX_AUTO_ORDER`); BG and P only ``order`` (default 7, 12)."""
    if kind != "sh":
        return [int(order or _FIXED_AUTO_ORDER[kind])]
    top = 1
    while top < MAX_AUTO_ORDER and n_nodes * (top + 1) ** 2 * SAMPLES_PER_COEF <= n_samples:
        top += 1
    if top < 2:
        raise InputError(
            f"{n_samples:,} samples are too few to choose an SH order for {n_nodes} antennas "
            f"(SH-2 needs {n_nodes * 4 * SAMPLES_PER_COEF:,}); give --order", param="order")
    return list(range(2, top + 1))


def prior_coefficients(prior: Mapping[str, Any], nodes: Sequence[str], basis: Any) -> np.ndarray:
    """Coefficients of the prior patterns in ``basis``, one block per node (zeros for a node
    without a prior): a spherical-harmonic prior is truncated or zero-padded (the harmonics are
    orthonormal, so truncation is the least-squares projection), any other is projected by
    least squares on a Fibonacci grid of 4 points per coefficient.

    Parameters
    ----------
    prior : mapping of node to pattern-like
        A model (e.g. a reference model from :mod:`rplearn.models.reference`) for each node with
        a prior; its pattern of that node is used, or its only pattern.
    """
    from rplearn.core.bases import fibonacci_grid_nodes

    p = basis.n_coef
    target = np.zeros(len(nodes) * p)
    for node, model in prior.items():
        if str(node) not in nodes:
            raise InputError(f"prior: node {node} is not in the learning data (nodes {', '.join(nodes)})", param="prior")
        names = [str(n) for n in getattr(model, "nodes", ())]
        source = str(node) if str(node) in names else (names[0] if len(names) == 1 else None)
        if source is not None and source != str(node) and source in nodes:
            raise InputError(f"prior: the prior model for {node} holds only node {source}, another node of the learning "
                             f"data; give {source}'s prior to {source} (--prior {source}=...) or a model of {node}", param="prior")
        if source is None:
            raise InputError(f"prior: the prior model for {node} holds {', '.join(names)}, not {node}", param="prior")
        k = list(nodes).index(str(node))
        mbasis = getattr(model, "basis", None)
        if basis.kind == "sh" and getattr(mbasis, "kind", None) == "sh":
            c = np.asarray(model.coef, np.float64)[names.index(source)]
            m = min(c.size, p)
            target[k * p:k * p + m] = c[:m]
        else:
            az, el = fibonacci_grid_nodes(4 * p)
            g = np.asarray(model.evaluate(source, az, el), np.float64)
            target[k * p:(k + 1) * p] = np.linalg.lstsq(basis.design(az, el), g, rcond=None)[0]
    return target



def fit_auto(
    unit_samples: Mapping[str, LinkSamples],
    spec: ModelSpec | None = None,
    options: FitOptions | None = None,
    provenance: Mapping[str, Any] | None = None,
    power: float | None = None,
) -> tuple[FittedModel, Selection]:
    """Learn a regularised pattern set with its order and smoothing chosen from the data.

    Parameters
    ----------
    unit_samples : mapping of unit label to LinkSamples
        The learning samples of every flight unit, all with the same node list.
    spec : ModelSpec, optional
        The kind (sh, bg, poly; default sh) and ridge; BG and P: the order (its smoothing is
        chosen); SH: its order is ignored (chosen).
    options : FitOptions, optional
        The gauge, environment term and link offsets (as :func:`rplearn.models.fit.solve_patterns`),
        and the priors: reference patterns whose shape to shrink toward instead of toward zero
        (``fit --prior``; their absolute level is not imposed unless ``prior_level="prior"``:
        it is the data's, or the gauge's): where the flight looked, the data win; where it did
        not, the pattern falls back to the prior. ``prior_std_db`` (how far each prior may be
        from the truth, where known: a vendor's tolerance) sets the predictive spread where
        the flight did not look (see :func:`fit_from_statistics`).
    provenance : mapping, optional
    power : float, optional
        Exponent of the SH roughness weights: :data:`DEFAULT_PENALTY_POWER` without a prior,
        :data:`PRIOR_PENALTY_POWER` (plain ridge toward the prior) with one.

    Returns
    -------
    fitted : FittedModel
        LTD covers the accumulation, the selection and the final solve.
    selection : Selection
        The choice and its validation curve (also in ``model.training["selection"]``).
    """
    spec = spec or ModelSpec.parse("sh")
    kind = spec.kind
    if kind not in ("sh", "bg", "poly"):
        raise InputError(f"automatic selection is for pattern models (sh, bg, poly), not {kind}", param="model")
    options = options or FitOptions(auto=True)
    order = spec.order if kind != "sh" else None
    units = {str(u): s for u, s in unit_samples.items() if len(s)}
    if not units:
        raise InputError("no learning samples", param="units")
    nodes = next(iter(units.values())).nodes
    if any(s.nodes != nodes for s in units.values()):
        raise InputError("the units' samples name different node lists; build them with one nodes=", param="unit_samples")
    n = sum(len(s) for s in units.values())
    ridge = default_ridge(kind) if spec.ridge is None else float(spec.ridge)
    orders = auto_orders(kind, n, len(nodes), order)
    big = ModelSpec(kind, orders[-1], ridge=ridge)
    check_model_size(big, n, len(nodes))
    basis = big.basis()
    reserve_block_buffer(basis, max(len(s) for s in units.values()))
    warm_up_blas()
    # The units' statistics on the runtime's workers (unit_statistics), and the coverage grids'
    # jobs behind them, while this thread selects the order.
    coverage = CoverageWork(list(units.values()))
    with DEFAULT_RUNTIME.overlapping(coverage.jobs if coverage.parallel else []) as riding, \
            blas_threads_for(n, basis.n_coef * len(nodes)):
        t0 = time.perf_counter()
        stats = unit_statistics(units, basis, options)
        accumulated = time.perf_counter()
        freq: Counter[float] = Counter()
        for s in units.values():
            frequency_counts(s, freq)
        fitted, choice = fit_from_statistics(stats, big, orders, nodes, options, weighted_median(freq), provenance,
                                             power)
        fitted.ltd_s = time.perf_counter() - t0
    waited = time.perf_counter()
    model = fitted.model
    assert isinstance(model, PatternSet)  # fit_from_statistics learns patterns
    grids = coverage.grids(riding.results()) if coverage.parallel else coverage.run()
    model.training = model.training.replace(ltd_s=fitted.ltd_s, coverage_deg=grids)
    fitted.phases_s = {"accumulation": accumulated - t0, **(fitted.phases_s or {}),
                       "coverage": time.perf_counter() - waited}
    return fitted, choice


def unit_statistics(units: Mapping[str, LinkSamples], basis: Any, options: FitOptions) -> dict[str, NormalEquations]:
    """Every unit's statistics at ``basis``, as :func:`fit_auto` accumulates them.

    The samples of each unit (or of half of one, :func:`unit_pieces`, so that the pieces keep
    the runtime's workers busy to the end) on the workers, one piece each, the halves added up
    in order, with each sample's time block (the sums per block of the drifting error, at the
    planning order's coefficients, from the same pass).

    Parameters
    ----------
    units : mapping of unit label to LinkSamples
        Every unit's samples (none empty), with one node list.
    basis : Basis
        The largest candidate order's basis.
    options : FitOptions
        The environment term (:func:`rplearn.models.terms.regression_inputs`).

    Returns
    -------
    dict of unit label to NormalEquations
        In ``units``' order.
    """
    nodes = next(iter(units.values())).nodes
    inputs = {u: regression_inputs(s, options) for u, s in units.items()}
    block_coefs = planning_basis(basis).n_coef  # the blocks' sums: only what the drift reads

    def piece_statistics(piece: tuple[str, int, int]) -> NormalEquations:
        u, a, b = piece
        s, (y, env) = units[u], inputs[u]
        # each sample's time block: the sums per block (for the drifting error) from the same pass
        blocks = None if s.t_s is None else time_block_labels(np.asarray(s.t_s)[a:b])
        return NormalEquations(basis, len(nodes), environment=env is not None, block_coefs=block_coefs).add(
            Directions(*(np.asarray(d)[a:b] for d in s.directions)), np.asarray(s.tx_index)[a:b],
            np.asarray(s.rx_index)[a:b], y[a:b], None if env is None else env[a:b], time_block=blocks)

    pieces = unit_pieces({u: len(s) for u, s in units.items()}, DEFAULT_RUNTIME.workers)
    stats: dict[str, NormalEquations] = {}
    for (u, _, _), part in sorted(zip(pieces, list(DEFAULT_RUNTIME.in_order(piece_statistics, pieces)), strict=True),
                                  key=lambda item: (list(units).index(item[0][0]), item[0][1])):
        stats[u] = stats[u].merge(part) if u in stats else part
    return stats


#: Fewest samples in half a unit :func:`unit_pieces` splits (shorter blocks cost more per sample).
MIN_PIECE_SAMPLES = 4096


def unit_pieces(sizes: Mapping[str, int], workers: int) -> list[tuple[str, int, int]]:
    """The ranges of samples ``(unit, start, stop)`` whose statistics :func:`fit_auto` accumulates
    on the ``workers`` threads, largest first: every unit whole, then the largest halved (down to
    :data:`MIN_PIECE_SAMPLES`) until the pieces are a multiple of the workers, so that no worker
    idles while the last unit is summed (three units of a flight on two workers: 1.5 units'
    time, not 2).

    Parameters
    ----------
    sizes : mapping of unit label to int
        Every unit's sample count (units of none are left out).
    workers : int
        The threads that accumulate the statistics.

    Returns
    -------
    list of (str, int, int)
        ``(unit, start, stop)``: the half-open sample range of each piece, the units in their
        order and each unit's pieces in sample order.
    """
    pieces = [(str(u), 0, int(n)) for u, n in sizes.items() if n > 0]
    while workers > 1 and len(pieces) % workers:
        largest = max(range(len(pieces)), key=lambda i: pieces[i][2] - pieces[i][1])
        u, a, b = pieces[largest]
        if b - a < 2 * MIN_PIECE_SAMPLES:
            break
        pieces[largest: largest + 1] = [(u, a, (a + b) // 2), (u, (a + b) // 2, b)]
    return sorted(pieces, key=lambda piece: piece[1] - piece[2])


def _one_thread(fn: Callable[..., Any], *args: Any) -> Any:
    """``fn(*args)`` with one BLAS thread (small products: threads would only wait for each other)."""
    with one_blas_thread():
        return fn(*args)


def _final_setup(total: NormalEquations, big: Any, kind: str, ridge: float, power: float, order: int, smoothing: float,
                 search_target: np.ndarray | None) -> tuple[Any, NormalEquations, float, np.ndarray,
                                                                   np.ndarray | None]:
    """The chosen basis, its statistics (a sub-block of ``total``), the penalty's unit, the
    penalty and the target of the final solve at ``order`` and ``smoothing``."""
    n_nodes = total.n_nodes
    chosen = ModelSpec(kind, order, ridge=ridge).basis()
    normal = sub_statistics(total, chosen)
    scale = penalty_scale(normal.gram, normal.n_pattern_columns)
    penalty = penalty_vector(chosen, n_nodes, smoothing, scale, power)
    sub_target = None if search_target is None else search_target[nested_columns(big, chosen, n_nodes)]
    return chosen, normal, scale, penalty, sub_target


def _early_parts(early: Mapping[str, Any], results: Sequence[Any], total: NormalEquations, names: list[str]) -> list[Any]:
    """The own posteriors' parts of the jobs run beside the selection (``final_jobs`` of
    :func:`fit_from_statistics`): the jobs' results after the final solve's (``results[0]``),
    with the point that is the final solve's own system read off it (:func:`solved_parts`; its
    inverse is computed here should the solve give no covariance)."""
    parts = list(results[1:])
    for i in early["same"]:
        sol = results[0]
        point = early["points"][i]
        known = solved_parts(early["prior"], point, sol.covariance, sol.residual_variance_db2,
                             total.basis.n_coef * len(names))
        parts.insert(i, continued_parts(total, names, point) if known is False else known)
    return parts


def fit_from_statistics(
    stats: Mapping[str, NormalEquations],
    spec: ModelSpec,
    orders: list[int],
    nodes: tuple[str, ...] | list[str],
    options: FitOptions | None = None,
    frequency_hz: float | None = None,
    provenance: Mapping[str, Any] | None = None,
    power: float | None = None,
) -> tuple[FittedModel, Selection]:
    """The selection and the final solve of :func:`fit_auto`, from per-unit statistics
    accumulated at the largest of ``orders`` (in memory, or streamed from a big file), for the
    kind and ridge of ``spec``, learned as ``options`` say (:class:`FitOptions`; prior files are
    loaded here, :func:`rplearn.models.load.load_priors`).

    Statistics accumulated with an environment column (the log-distance term of
    ``path_loss``) get it as a shared column, and with ``link_offsets`` one offset per link
    logged both ways (over all units) is appended, before the selection.

    The model's covariance is the posterior's, read with the noise about each flight's own
    level (``training["noise_std_db"]``, :func:`within_unit_noise_var`), times the selection's
    within-flight variance inflation; the selection's between-flight level spread is stored
    (``flight_level_std_db``) with that of a new flight's level about the learned flights'
    mean (``new_flight_level_std_db``: times ``sqrt(1 + sum of the flights' squared sample
    shares)``), which :meth:`PatternSet.predict_gain_std` adds. Its spread where the data are
    absent is ``training["prior_std_db"]`` per node (and ``training["prior_std_source"]`` says
    where that number comes from): without a prior, :func:`unseen_spread_cap_db` (the
    posterior re-read with a prior of that spread); with a prior for every node,
    ``prior_spread_db`` when given, else how far the flight found the prior off where it
    looked (its RMS misfit, less the noise and the levels, shared by the two ends of a link)
    or the capped implied spread, whichever is larger. The misfit the cross-validation finds
    beyond the posterior (:func:`held_out_misfit_var`) is added to each node's pattern
    covariance (``training["misfit_std_db"]``: per node).
    """
    t0 = time.perf_counter()
    options = options or FitOptions(auto=True)
    orders = sorted({int(o) for o in orders})  # the search and the kept prior read the largest last
    if not orders:
        raise InputError("no candidate orders to choose from", param="orders")
    kind, ridge = spec.kind, float(spec.ridge if spec.ridge is not None else default_ridge(spec.kind))
    gauge, path_loss, link_offsets = options.gauge, options.path_loss, options.link_offsets
    prior, prior_spread_db, prior_level = load_priors(options).priors or None, options.prior_std_db, options.prior_level
    if power is None:
        power = PRIOR_PENALTY_POWER if prior else DEFAULT_PENALTY_POWER
    for node, model in (prior or {}).items():  # a prior of another band is another antenna
        if frequency_hz is not None:
            check_same_band(frequency_hz, getattr(model, "frequency_hz", None), "the learning data",
                            f"the prior of {node}", param="prior")
    if prior_spread_db is not None:
        missing = sorted(set(map(str, nodes)) - set(map(str, prior or {})))
        if missing:
            raise InputError(f"prior_std_db: it states how far the priors may be off, but node(s) {', '.join(missing)} "
                             "have no prior; give a prior for every node", param="prior_std_db")
    first = next(iter(stats.values()))
    if first.environment != path_loss.learns_exponent:
        raise InputError(f"path loss {path_loss.kind}: the statistics were accumulated "
                         f"{'with' if first.environment else 'without'} an environment column", param="path_loss")
    total = NormalEquations(first.basis, first.n_nodes, first.environment)
    for st in stats.values():
        total.merge(st)
    counts = statistics_counts(total.directed, nodes)
    unit_stats = list(stats.values())  # with their time blocks (with_shared does not carry them)
    links = total.two_way_links() if link_offsets else []
    if first.environment or links:
        stats = {u: st.with_shared(links) for u, st in stats.items()}
        total = total.with_shared(links)
    target = prior_coefficients(prior, list(nodes), first.basis) if prior else None
    plain_total, search_target, shape = total, target, None

    def make_basis(k: int) -> Any:
        return ModelSpec(kind, k, ridge=ridge).basis()

    names = list(map(str, nodes))
    early: dict[str, Any] = {}

    def final_jobs(order: int, smoothing: float, keys: list[tuple[int, float]]) -> list[Callable[[], Any]]:
        # the final solve and the own posteriors' inverses need only the choice (the prior is
        # not kept on this path): on the workers with the chosen and tied points' inflations
        setup = _final_setup(total, first.basis, kind, ridge, power, order, smoothing, search_target)
        chosen_, normal_, scale_, penalty_, sub_target_ = setup
        prior_ = OwnPrior(smoothing, scale_, power, ridge, gauge, target, prior_level)
        own_first_, points = continued_points(plain_total, chosen_, len(nodes), prior_,
                                              [(o, s, 0.0) for o, s in keys], make_basis)  # inflations: not used here
        # at the largest basis the chosen point's tie group is the final solve's own system: its
        # posterior is read off that solve (solved_parts), not inverted a second time
        same = [i for i, g in enumerate(points) if not own_first_ and g.smoothing == smoothing and g.scale == scale_]
        early.update(setup=setup, own_first=own_first_, points=points, same=same[:1], prior=prior_)
        return [functools.partial(solve, normal_, list(nodes), ridge=ridge, gauge=gauge, penalty=penalty_,
                                  penalty_target=sub_target_, prior_level=prior_level),
                *(functools.partial(continued_parts, plain_total, names, g) for i, g in enumerate(points)
                  if i not in same[:1])]

    searched_prior = keeps_prior(kind, target, first.basis, len(nodes))
    selecting = time.perf_counter()
    results, choice = select_beside(stats, make_basis, orders, ridge, power, prior=SearchPrior(target, prior_level),
                                    beside=None if searched_prior else final_jobs)
    keep, compared = False, None
    if searched_prior:
        # the search again on the deviation from the prior, its degrees above the chosen order
        # kept; the held-out units choose between the two, the kept prior when they cannot tell
        assert target is not None
        deviation = deviation_problem(stats, total, target, prior_level)
        kept = select_order_and_smoothing(deviation.units, make_basis, orders, ridge, power, target=deviation.target,
                                          prior_level=prior_level)
        kept_sse, cut_sse = (held_out_errors(u, make_basis, c, ridge, t, prior_level)
                             for u, c, t in ((deviation.units, kept, deviation.target), (stats, choice, target)))
        keep = kept_within_noise(kept, choice, kept_sse, cut_sse, total.n_samples)
        compared = {"kept": keep, "kept_order": int(kept.order), "kept_rmse_db": float(kept.rmse_db),
                    "cut_order": int(choice.order), "cut_rmse_db": float(choice.rmse_db), "model_order": int(orders[-1])}
        if keep:
            stats, total, shape, search_target, choice = (deviation.units, deviation.total, deviation.shape,
                                                         deviation.target, kept)
    selected = time.perf_counter()
    final = ModelSpec(kind, orders[-1] if keep else choice.order, ridge=ridge, smoothing=choice.smoothing)
    chosen, normal, scale, penalty, sub_target = early["setup"] if early else _final_setup(
        total, first.basis, kind, ridge, power, choice.order, choice.smoothing, search_target)
    own_prior = OwnPrior(choice.smoothing, scale, power, ridge, gauge, target, prior_level)
    own_first, jobs = (early["own_first"], []) if early else continued_jobs(plain_total, chosen, names, own_prior,
                                                                            choice.ties, make_basis)
    # else the own-pattern posteriors' inverses on the statistics' workers while this thread
    # solves (one BLAS thread each, this thread's too): they do not depend on the final solve
    with DEFAULT_RUNTIME.beside(jobs) as continued, ExitStack() as stack:
        sol = results[0] if early else solve(normal, list(nodes), ridge=ridge, gauge=gauge, penalty=penalty,
                                             penalty_target=sub_target, prior_level=prior_level)
        inflation = float(choice.variance_inflation)
        # the flights' levels: apart from the noise (the residual about each flight's own level)
        # and added to the spread of a new flight's predictions (its level about the common one)
        level_var = float(choice.flight_level_std_db) ** 2
        within_var = sol.residual_variance_db2
        if choice.method == "grouped-cv":
            within_var = within_unit_noise_var(stats, normal, np.concatenate([sol.coef.ravel(), sol.shared_coef]),
                                               sol.report.rank)
        shares = np.array([st.n_samples for st in stats.values()], np.float64) / max(normal.n_samples, 1)
        new_level_var = level_var * (1.0 + float(shares @ shares)) if level_var > 0 else 0.0
        noise_var = within_var * inflation
        # the next flight's plan: the drifting error from the time blocks kept in the same pass
        # (with a prior the penalty pulls toward it, which the moments do not model: none; at the
        # search's largest smoothing the flat pattern leaves every shape to the offsets: none)
        # (on a worker while this thread reads the covariance below: one BLAS thread each)
        drift_jobs = [] if target is not None or at_smoothing_cap(choice.smoothing) else [functools.partial(
            _one_thread, drift_std_db, unit_stats, total, choice.smoothing * scale, ridge, power, float(np.sqrt(noise_var)))]
        drifted = stack.enter_context(DEFAULT_RUNTIME.beside(drift_jobs))
        rescale = within_var / sol.residual_variance_db2 if sol.residual_variance_db2 > 0 else 1.0
        # the covariance's basis: the chosen one, or with the prior kept the largest (auto_prior)
        model_basis, cov_normal, cov_penalty = chosen, normal, penalty
        if keep:
            model_basis, cov_normal = first.basis, plain_total
            cov_penalty = penalty_vector(model_basis, len(nodes), choice.smoothing, scale, power)
        spread = prior_std_db(model_basis, list(nodes), ridge + cov_penalty, noise_var, power)
        spread_source = "implied by the cross-validated smoothing"
        covariance = None if sol.covariance is None else sol.covariance * (rescale * inflation)
        plain = normal if not keep else sub_statistics(plain_total, chosen)
        cap = unseen_spread_cap_db(plain, chosen)
        # without a prior the unseen spread is the measured gains' (not the smoothing's): the
        # cross-validation chooses smoothing for prediction where the data are, which says nothing
        # of the unseen sphere (``campaign``: 0.7 dB implied against 12 dB off where unseen)
        wanted = {str(n): cap for n in nodes}
        if target is not None and covariance is not None and prior is not None and set(map(str, prior)) >= set(map(str, nodes)):
            if prior_spread_db is None:
                # the misfit of the prior the model keeps: to the chosen order, or all of it (auto_prior)
                misfit = (prior_misfit_var(plain_total, kept_prior_target(target, shape, first.basis, len(nodes)), first.basis)
                          if keep and shape is not None else
                          prior_misfit_var(normal, target[nested_columns(first.basis, chosen, len(nodes))], chosen))
                learned = float(np.sqrt(max(misfit - within_var - level_var, 0.0) / 2.0))  # two ends a sample
                spread_source = "learned from the prior's misfit to the flight"
                if any(learned < wanted[str(n)] for n in nodes):
                    spread_source = "implied by the cross-validated smoothing (larger than " + spread_source + ")"
                # never below the smoothing's (capped) spread: a prior that fits where the flight
                # looked is not thereby known to fit everywhere
                wanted = {str(n): max(learned, wanted[str(n)]) for n in nodes}
            else:
                wanted = {str(n): float(prior_spread_db) for n in nodes}  # the user's tolerance, both ways
                spread_source = "stated"
        elif any(wanted[str(n)] < spread[str(n)] for n in nodes):
            spread_source = "the spread of the measured gains (the smoothing implied more)"
        elif any(wanted[str(n)] > spread[str(n)] for n in nodes):
            spread_source = "the spread of the measured gains (the smoothing implied less)"
        uncapped = covariance
        factor = np.array([(spread[str(n)] / max(wanted[str(n)], 1e-9)) ** 2 for n in nodes])
        if covariance is not None and (keep or np.any(np.abs(factor - 1.0) > 1e-9)):
            # the same posterior, read with a prior of the wanted spread: the penalty per node
            # scaled so that its implied prior spread is the wanted one (the mean is the CV's)
            weights = (ridge + cov_penalty) * np.repeat(factor, model_basis.n_coef)
            with one_blas_thread():  # scipy's LAPACK: no pool of its own left spinning beside numpy's
                inverse = penalised_inverse(cov_normal, list(nodes), 0.0, gauge, weights)  # the covariance alone: no solve
            if inverse is not None:
                covariance = inverse * (within_var * inflation)
            else:
                wide = solve(cov_normal, list(nodes), ridge=0.0, gauge=gauge, penalty=weights,
                             penalty_target=None if keep else sub_target, prior_level=prior_level)
                covariance = wide.covariance * (within_var / wide.residual_variance_db2) * inflation
            spread = prior_std_db(model_basis, list(nodes), weights, noise_var, power)
        misfit_var = held_out_misfit_var(choice.held_out_excess_db2, uncapped, normal) if choice.method == "grouped-cv" else 0.0
        if covariance is not None and misfit_var > 0:
            pat = model_basis.n_coef * len(nodes)
            covariance = covariance.copy()
            covariance[:pat, :pat] += misfit_covariance(model_basis, len(nodes), misfit_var / 2.0)  # two ends a sample
        parts = _early_parts(early, results, plain_total, names) if early else continued()
        drift = drifted()[0] if drift_jobs else None
    with one_blas_thread():
        own = own_pattern_posterior(plain_total, chosen, names, own_prior, noise_var, uncapped,
                                    (lambda: parts[0]) if own_first else None)
    own = tied_own_posterior(own, plain_total, names, own_prior, choice.ties, within_var, make_basis,
                             parts[1:] if own_first else parts or None)
    ltd = time.perf_counter() - t0
    fields, terms = shared_fields(sol, list(nodes), options, counts, rescale * inflation)
    training = sol.report.to_dict()
    training.update(terms)
    training.update(smoothing=choice.smoothing, penalty_power=power, selection=choice.to_dict(), ltd_s=ltd,
                    variance_inflation=inflation, prior_std_db=spread, prior_std_source=spread_source,
                    noise_std_db=float(np.sqrt(within_var)), flight_level_std_db=float(np.sqrt(level_var)),
                    new_flight_level_std_db=float(np.sqrt(new_level_var)), misfit_std_db=float(np.sqrt(misfit_var / 2.0)))
    if target is None:  # a smoothness prior: its absolute weight (units of X^T X) at the chosen order
        training["planning_penalty_weight"] = float(choice.smoothing) * float(scale)
    if drift is not None:
        training["drift_std_db"] = drift
    if prior:
        training["prior_level"] = prior_level
        training["prior"] = {str(n): str(getattr(m, "provenance", {}).get("model", getattr(m, "label", "?")))
                             for n, m in prior.items()}
    coef = sol.coef
    if compared is not None:
        training["prior_kept"] = compared
    if keep:
        assert shape is not None
        coef = kept_prior_coef(shape, sol.coef, model_basis, chosen, len(nodes))
    if frequency_hz is not None:
        training["frequency_hz"] = frequency_hz
    model = PatternSet(basis=model_basis, nodes=tuple(nodes), coef=coef, covariance=covariance,
                       gauge=[g.to_dict() for g in sol.report.gauges], training=TrainingSummary.from_dict(training), **fields)
    model.provenance = {**dict(provenance or {}), "model": final.label}
    gram = LearningGram(plain_total.basis, len(nodes), plain_total.gram, int(plain_total.n_samples))
    phases = {"selection": selected - selecting, "closing": time.perf_counter() - selected}
    return FittedModel(final, model, ltd, own_posterior=own, learning_gram=gram, phases_s=phases), choice


__all__ = ["MIN_PIECE_SAMPLES", "unit_statistics", "held_out_misfit_var", "misfit_covariance", "unit_pieces",
           "unseen_spread_cap_db", "within_unit_noise_var", "MAX_AUTO_ORDER", "PRIOR_PENALTY_POWER", "SAMPLES_PER_COEF", "auto_orders", "fit_auto",
           "fit_from_statistics", "prior_coefficients", "prior_misfit_var", "prior_std_db"]
