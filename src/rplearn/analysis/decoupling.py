"""Decoupling certificate: how well a flight determines each node's *own* pattern.

A link's samples measure joint gains ``G_a(d_a) + G_b(d_b)``; the joint prediction can be good
while the split between the two patterns is loose (a bump added to one antenna and taken from
the other where the pairs of directions flown meet). This module reads the model's posterior
covariance of the pattern coefficients ``Sigma`` (gauge-constrained: the free constant of a
bipartite link graph has no variance) in two ways:

- **per-node spread**: the posterior standard deviation of each node's gain, RMS over the
  node's *covered* directions (points of the model's coverage grid within
  :data:`rplearn.core.coverage.COVERED_WITHIN_DEG` of a learning direction) and over the sphere;
  for a node whose constant the gauge fixes, the mean over those directions is removed first
  (the constant is a convention, as in :func:`rplearn.analysis.pattern_error.pattern_errors_db`),
  so the covered spread is the posterior's prediction of that node's pattern error;
- **unsplit components**: with ``M`` the per-node error metric (mean square of each node's
  error over its covered directions, averaged over the nodes) and ``G`` the joint one (mean
  square of the joint error over the learning samples' pairs of directions), the generalised
  eigenproblem ``(L^T M L) u = tau (L^T G L) u`` (``Sigma = L L^T``) splits the posterior into
  components whose expected per-node and joint mean squares add up to the totals
  (``E[delta^T M delta] = sum_i tau_i s_i``, ``E[delta^T G delta] = sum_i s_i``). A component
  with ``tau`` >= 1 / :data:`UNSPLIT_JOINT_FRACTION` changes the patterns much more than the
  joint gains the flight measured: the flight cannot split it between the nodes. The
  certificate lists them, with the per-node dB they carry and where on each node they lie.

Everything is a function of the model (its covariance and coverage grid) and the learning
samples' pairs of directions (or their Gram matrix); nothing is refitted.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from rplearn._argtypes import check_types
from rplearn.analysis.pattern_error import gauged_nodes
from rplearn.core.bases import fibonacci_grid_nodes
from rplearn.core.coverage import COVERED_WITHIN_DEG
from rplearn.core.lsq.normal_equations import NormalEquations
from rplearn.core.threads import blas_threads
from rplearn.data.tables import LinkSamples
from rplearn.errors import InputError
from rplearn.models.fit import LearningGram
from rplearn.models.own_posterior import OwnPosterior
from rplearn.models.patterns import PatternSet

#: A component is *unsplit* when the joint mean square it causes on the learning pairs is below
#: this fraction of the per-node mean square it causes over the covered directions (a component
#: confined to one of two nodes gives 2; one the flight cannot see at all, 0).
UNSPLIT_JOINT_FRACTION = 0.1
#: Unsplit components carrying less than this per-node RMS [dB] are counted but not listed.
MIN_LISTED_DB = 0.05
#: Components listed in the summary at most.
MAX_LISTED = 3
#: Points of the Fibonacci grid over which the sphere average is taken.
SPHERE_POINTS = 2048
#: Points of the Fibonacci grid on which the own-pattern std is stored (about 4.5 deg apart).
OWN_MAP_POINTS = 2048
#: Pattern columns above which the components are not computed (an eigenproblem of that size).
MAX_COMPONENT_COLUMNS = 1500


@dataclass(frozen=True)
class NodeSpread:
    """Posterior spread of one node's own pattern [dB].

    Attributes
    ----------
    covered_std_db : float
        RMS over the covered directions of the posterior std of the node's gain (its mean there
        removed for a gauged node): the predicted pattern error where the flight looked.
    sphere_std_db : float
        The same over the whole sphere.
    covered_fraction : float
        Fraction of the sphere within :data:`COVERED_WITHIN_DEG` of a learning direction.
    """

    covered_std_db: float
    sphere_std_db: float
    covered_fraction: float

    def to_dict(self) -> dict[str, float]:
        return {"covered_std_db": self.covered_std_db, "sphere_std_db": self.sphere_std_db,
                "covered_fraction": self.covered_fraction}


@dataclass(frozen=True)
class SplitComponent:
    """One posterior component the flight cannot split between nodes.

    Attributes
    ----------
    per_node_db : float
        Its expected RMS per node over the covered directions [dB].
    joint_db : float
        Its expected RMS in the joint gain over the learning pairs of directions [dB].
    peaks : dict of node to (az_deg, el_deg, sign, share)
        Per node: the body-frame direction where the component is largest, its sign there
        (+1/-1), and the node's share of the component's per-node mean square.
    """

    per_node_db: float
    joint_db: float
    peaks: dict[str, tuple[float, float, int, float]]

    def text(self) -> str:
        parts = [f"{n} {share:.0%} of it, peak {'+' if s > 0 else '-'} at az {az:.0f} el {el:.0f} deg"
                 for n, (az, el, s, share) in self.peaks.items() if share >= 0.05]
        return f"{self.per_node_db:.2f} dB per node, {self.joint_db:.2f} dB in the joint gain: " + "; ".join(parts)

    def to_dict(self) -> dict[str, Any]:
        return {"per_node_db": self.per_node_db, "joint_db": self.joint_db,
                "peaks": {n: list(v) for n, v in self.peaks.items()}}


@check_types
@dataclass(frozen=True)
class DecouplingCertificate:
    """What a flight identifies of each node's own pattern (see the module docstring).

    Attributes
    ----------
    nodes : dict of node to NodeSpread
    components : tuple of SplitComponent
        The unsplit components carrying at least :data:`MIN_LISTED_DB`, largest first (empty
        when not computed, see ``notes``).
    n_unsplit : int
        Unsplit components carrying at least :data:`MIN_LISTED_DB` (listed or not).
    unsplit_db : float
        Per-node RMS [dB] carried by all unsplit components together (NaN when not computed).
    covered_db : float
        Per-node RMS [dB] of the whole posterior over the covered directions (the nodes' mean square).
    notes : list of str
    own_std_db : dict of node to ndarray
        With an own-pattern posterior: the posterior std of each node's gain [dB] at the
        :data:`OWN_MAP_POINTS` points of a Fibonacci grid, which ``plot --spread`` draws.
    """

    nodes: dict[str, NodeSpread]
    components: tuple[SplitComponent, ...] = ()
    n_unsplit: int = 0
    unsplit_db: float = float("nan")
    covered_db: float = float("nan")
    notes: list[str] = field(default_factory=list)
    own_std_db: dict[str, np.ndarray] = field(default_factory=dict)

    def summary(self) -> str:
        """A few lines: each node's spread, then the unsplit components."""
        lines = ["own-pattern spread (1 sigma, mean removed where the gauge fixes it): " + ", ".join(
            f"{n} {s.covered_std_db:.2f} dB where the flight looked ({s.covered_fraction:.0%} of the sphere), "
            f"{s.sphere_std_db:.2f} dB over the sphere" for n, s in self.nodes.items())]
        if np.isfinite(self.unsplit_db):
            share = (self.unsplit_db / self.covered_db) ** 2 if self.covered_db > 0 else 0.0
            if self.n_unsplit:
                lines.append(f"not split between nodes by this flight: {self.n_unsplit} component(s), "
                             f"{self.unsplit_db:.2f} dB per node ({share:.0%} of the own-pattern variance where it looked)")
                lines += [f"  {k + 1}. {c.text()}" for k, c in enumerate(self.components)]
            else:
                lines.append("not split between nodes by this flight: no component above "
                             f"{MIN_LISTED_DB:.2f} dB (every pattern change it allows shows in the joint gain)")
        lines += self.notes
        return "\n".join(lines)

    def to_dict(self) -> dict[str, Any]:
        return {"nodes": {n: s.to_dict() for n, s in self.nodes.items()},
                "components": [c.to_dict() for c in self.components], "n_unsplit": self.n_unsplit,
                "unsplit_db": self.unsplit_db, "covered_db": self.covered_db,
                "unsplit_joint_fraction": UNSPLIT_JOINT_FRACTION, "covered_within_deg": COVERED_WITHIN_DEG,
                "notes": list(self.notes),
                **({"own_std_db": {n: np.round(v, 3).tolist() for n, v in self.own_std_db.items()}} if self.own_std_db else {})}


def covered_directions(model: PatternSet, within_deg: float = COVERED_WITHIN_DEG) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Per node, the points of the model's coverage grid within ``within_deg`` of a learning direction [rad].

    Raises
    ------
    InputError
        When the model stores no coverage grid for a node.
    """
    grids = model.training.coverage_deg or {}
    out = {}
    for node in model.nodes:
        if node not in grids:
            raise InputError(f"model: no coverage grid for node {node} (training.coverage_deg); refit it", param="model")
        grid = np.asarray(grids[node], np.float64)
        az, el = fibonacci_grid_nodes(grid.size)
        keep = grid <= within_deg
        out[node] = (az[keep], el[keep])
    return out


def _metric(design: np.ndarray, demean: bool) -> np.ndarray:
    """``X^T X / n`` of a node's design over a set of directions (mean removed: the error of the node's shape)."""
    if design.shape[0] == 0:
        return np.zeros((design.shape[1], design.shape[1]))
    if demean:
        design = design - design.mean(axis=0)
    return design.T @ design / design.shape[0]


def _node_spreads(model: PatternSet, covered: Mapping[str, tuple[np.ndarray, np.ndarray]],
                  cov: np.ndarray, own: OwnPosterior | None = None) -> tuple[dict[str, NodeSpread], list[np.ndarray]]:
    """Per node: the covered spread (from ``own`` when given, at its basis), the sphere spread
    (from the model's covariance ``cov``: the predictive spread ``fit`` uses, capped where the
    flight never looked), and the covered metric at the basis of the covered spread."""
    p = model.basis.n_coef
    basis, q, own_cov = (model.basis, p, cov) if own is None else (own.basis, own.basis.n_coef, own.covariance)
    gauged = gauged_nodes(model)
    saz, sel = fibonacci_grid_nodes(SPHERE_POINTS)
    sphere = model.basis.design(saz, sel)
    grid_sizes = {n: len((model.training.coverage_deg or {})[n]) for n in model.nodes}
    sphere_metrics = {demean: _metric(sphere, demean) for demean in {node in gauged for node in model.nodes}}
    spreads, metrics = {}, []
    for k, node in enumerate(model.nodes):
        block = cov[k * p:(k + 1) * p, k * p:(k + 1) * p]
        az, el = covered[node]
        m = _metric(basis.design(az, el), node in gauged)
        metrics.append(m)
        covered_var = float(np.sum(m * own_cov[k * q:(k + 1) * q, k * q:(k + 1) * q]))
        if own is not None:
            offset = _offset_from_mean(model, own, k)
            covered_var += float(offset @ m @ offset)
        sphere_var = float(np.sum(sphere_metrics[node in gauged] * block))
        spreads[node] = NodeSpread(float(np.sqrt(max(covered_var, 0.0))), float(np.sqrt(max(sphere_var, 0.0))),
                                   float(az.size / grid_sizes[node]))
    return spreads, metrics


def _offset_from_mean(model: PatternSet, own: OwnPosterior, k: int) -> np.ndarray:
    """Node ``k``'s posterior mean at ``own.basis`` less the model's coefficients there (zero
    without a mean). SH coefficients nest (degree ``l`` in columns ``l**2 .. (l+1)**2 - 1``), so the
    model's lower order fills the first columns."""
    q = own.basis.n_coef
    if own.mean is None:
        return np.zeros(q)
    chosen = np.zeros(q)
    p = min(model.basis.n_coef, q)
    chosen[:p] = model.coef[k, :p]
    return np.asarray(own.mean[k], np.float64) - chosen


def own_std_maps(model: PatternSet, own: OwnPosterior) -> dict[str, np.ndarray]:
    """Root expected square error [dB] of each node's reported gain under ``own`` (its posterior
    variance plus the square of the reported gain's difference from the posterior mean) at the
    :data:`OWN_MAP_POINTS` points of a Fibonacci grid
    (:func:`rplearn.core.bases.fibonacci_grid_nodes`, in its order)."""
    q = own.basis.n_coef
    az, el = fibonacci_grid_nodes(OWN_MAP_POINTS)
    design = None if own.mean is None else own.basis.design(az, el)
    out = {}
    for k, node in enumerate(model.nodes):
        block = own.covariance[k * q:(k + 1) * q, k * q:(k + 1) * q]
        var = own.basis.quadratic_form(block, az, el)
        if design is not None:
            var = var + (design @ _offset_from_mean(model, own, k)) ** 2
        out[node] = np.sqrt(np.maximum(var, 0.0))
    return out


def _joint_metric(model: PatternSet, samples: LinkSamples | Sequence[LinkSamples] | None, gram: np.ndarray | None,
                  n_samples: int | None, basis: Any = None) -> np.ndarray:
    """Mean ``x x^T`` of the joint design rows of the learning samples (pattern columns, at
    ``basis``: the model's by default; ``gram`` must be at that basis)."""
    basis = model.basis if basis is None else basis
    pat = basis.n_coef * len(model.nodes)
    if gram is not None:
        g = np.asarray(gram, np.float64)[:pat, :pat]
        return g / float(n_samples or 1)
    normal = NormalEquations(basis, len(model.nodes))
    for part in [samples] if isinstance(samples, LinkSamples) else list(samples or []):
        if tuple(part.nodes) != tuple(model.nodes):
            raise InputError(f"samples: nodes {', '.join(part.nodes)} are not the model's ({', '.join(model.nodes)})",
                             param="samples")
        normal.add(part.directions, part.tx_index, part.rx_index)
    return normal.gram[:pat, :pat] / max(normal.n_samples, 1)


def _peaks(model: PatternSet, covered: Mapping[str, tuple[np.ndarray, np.ndarray]], vecs: np.ndarray,
           metrics: Sequence[np.ndarray], basis: Any = None) -> list[dict[str, tuple[float, float, int, float]]]:
    """Per column of ``vecs`` (components, pattern columns at ``basis``): each node's share of its
    per-node mean square and the covered direction where it is largest. Each node's design over
    its covered directions is evaluated once for every component (16,384 grid points at SH-15
    cost about 0.1 s each)."""
    basis = model.basis if basis is None else basis
    p = basis.n_coef
    gauged = gauged_nodes(model)
    energy = [[float(vec[k * p:(k + 1) * p] @ metrics[k] @ vec[k * p:(k + 1) * p]) for k in range(len(model.nodes))]
              for vec in vecs.T]
    out: list[dict[str, tuple[float, float, int, float]]] = [{} for _ in range(vecs.shape[1])]
    for k, node in enumerate(model.nodes):
        az, el = covered[node]
        if az.size == 0 or not out:
            continue
        values = basis.design(az, el) @ vecs[k * p:(k + 1) * p]
        if node in gauged:
            values = values - values.mean(axis=0)
        for j, column in enumerate(values.T):
            i = int(np.argmax(np.abs(column)))
            out[j][node] = (float(np.degrees(az[i])), float(np.degrees(el[i])), int(np.sign(column[i]) or 1),
                            energy[j][k] / (sum(energy[j]) or 1.0))
    return out


def unsplit_components(model: PatternSet, covered: Mapping[str, tuple[np.ndarray, np.ndarray]], metrics: Sequence[np.ndarray],
                       joint: np.ndarray, own: OwnPosterior | None = None) -> tuple[list[SplitComponent], int, float, float]:
    """The posterior's components and their per-node and joint mean squares (module docstring):
    the unsplit ones listed (largest first), their count, their per-node RMS and the total's.
    The posterior is ``own`` when given (at its basis), else the model's covariance."""
    basis = model.basis if own is None else own.basis
    pat = basis.n_coef * len(model.nodes)
    cov = np.asarray(model.covariance if own is None else own.covariance, np.float64)[:pat, :pat]
    values, vectors = np.linalg.eigh(0.5 * (cov + cov.T))
    keep = values > 1e-12 * max(float(values.max()), 1e-300)
    root = vectors[:, keep] * np.sqrt(values[keep])  # Sigma = L L^T
    n_nodes = len(model.nodes)
    p = basis.n_coef
    per_node = np.zeros((pat, pat))
    for k in range(n_nodes):
        per_node[k * p:(k + 1) * p, k * p:(k + 1) * p] = metrics[k] / n_nodes
    a = root.T @ per_node @ root
    b = root.T @ joint @ root
    a, b = 0.5 * (a + a.T), 0.5 * (b + b.T)
    b_reg = b + np.eye(b.shape[0]) * (1e-9 * max(float(np.trace(b)) / b.shape[0], 1e-300))
    # the generalised problem through b_reg's Cholesky factor (numpy only: a fixed-order fit imports no scipy)
    chol = np.linalg.cholesky(b_reg)
    half = np.linalg.solve(chol, a)
    whitened = np.linalg.solve(chol, half.T)  # chol^-1 a chol^-T
    tau, w = np.linalg.eigh(0.5 * (whitened + whitened.T))
    u = np.linalg.solve(chol.T, w)  # u^T b_reg u = I, u^T a u = diag(tau)
    s = np.sum((b_reg @ u) ** 2, axis=0)  # E[a_i^2] with z = u a: ((u^T u)^-1)_ii = |b_reg u_i|^2
    node_ms = tau * s
    joint_ms = np.einsum("ij,ij->j", u, b @ u) * s
    total_ms = float(np.trace(a))
    unsplit = (joint_ms < UNSPLIT_JOINT_FRACTION * node_ms) & (node_ms > 0)
    order = np.argsort(-np.where(unsplit, node_ms, -1.0))
    listed = [i for i in order if unsplit[i] and node_ms[i] >= MIN_LISTED_DB**2]
    shown = listed[:MAX_LISTED]
    peaks = _peaks(model, covered, root @ u[:, shown], metrics, basis)
    comps = [SplitComponent(float(np.sqrt(node_ms[i])), float(np.sqrt(max(joint_ms[i], 0.0))), peak)
             for i, peak in zip(shown, peaks, strict=True)]
    return comps, len(listed), float(np.sqrt(max(float(np.sum(node_ms[unsplit])), 0.0))), float(np.sqrt(max(total_ms, 0.0)))


@check_types
def decoupling_certificate(
    model: PatternSet,
    samples: LinkSamples | Sequence[LinkSamples] | None = None,
    gram: np.ndarray | None = None,
    n_samples: int | None = None,
    within_deg: float = COVERED_WITHIN_DEG,
    posterior: OwnPosterior | None = None,
) -> DecouplingCertificate:
    """Per-node spread of a pattern model's own patterns and the components its flight cannot split.

    Parameters
    ----------
    model : PatternSet
        A fitted pattern model with a covariance and a coverage grid (every ``fit`` stores both).
    samples : LinkSamples or sequence of LinkSamples, optional
        The learning samples (their pairs of directions make the joint metric), e.g. one per unit.
    gram, n_samples : ndarray and int, optional
        Instead of ``samples``: the learning design's ``X^T X`` at the model's basis (pattern
        columns first) and its number of samples.
    within_deg : float
        Radius of a covered direction [deg].
    posterior : OwnPosterior, optional
        The own-pattern posterior of an automatic fit (``FittedModel.own_posterior``: the
        cross-validated prior continued to the largest candidate order,
        :mod:`rplearn.models.own_posterior`), read for the covered spreads and the unsplit
        components; by default the model's covariance (the chosen order's, capped where the
        flight never looked: its covered spreads are then lower bounds). ``gram``, if given,
        must be at the posterior's basis.

    Returns
    -------
    DecouplingCertificate
        For a fixed-order fit (no ``training["selection"]``: its covariance is the ridge
        estimate's sandwich, not a posterior), without samples or gram, or above :data:`MAX_COMPONENT_COLUMNS` pattern columns, the
        per-node spreads only (a note says why).

    Raises
    ------
    InputError
        When the model carries no covariance or no coverage grid.
    """
    if model.covariance is None:
        raise InputError("model: it carries no covariance; the per-node spread needs one", param="model")
    own = posterior if model.training.selection is not None else None
    with blas_threads(_certificate_flops(model, own)):
        return _certificate(model, samples, gram, n_samples, within_deg, own)


def _certificate_flops(model: PatternSet, own: OwnPosterior | None) -> float:
    """Floating-point work of a certificate: each node's design and metric over its coverage grid,
    the sphere's, and the dense factorisations of the pattern columns (two symmetric eigenproblems,
    a Cholesky factor, triangular solves and products, about 30 ``n**3``)."""
    q = (model.basis if own is None else own.basis).n_coef
    columns = q * len(model.nodes)
    grid_points = sum(len(g) for g in (model.training.coverage_deg or {}).values())
    dense = 30.0 * float(columns) ** 3 if model.training.selection is not None and columns <= MAX_COMPONENT_COLUMNS else 0.0
    return float(grid_points) * q**2 + float(SPHERE_POINTS) * model.basis.n_coef**2 + dense


def _certificate(model: PatternSet, samples: LinkSamples | Sequence[LinkSamples] | None, gram: np.ndarray | None,
                 n_samples: int | None, within_deg: float, own: OwnPosterior | None) -> DecouplingCertificate:
    """:func:`decoupling_certificate` of a model with a covariance (``own``: the posterior, for an
    automatic fit only), on the BLAS threads its work is given (:mod:`rplearn.core.threads`: one on
    a busy 2-core machine, where OpenBLAS's second thread made an SH-15 certificate 10 times slower)."""
    covered = covered_directions(model, within_deg)
    cov = np.asarray(model.covariance, np.float64)
    spreads, metrics = _node_spreads(model, covered, cov, own)
    maps = {} if own is None else own_std_maps(model, own)
    covered_db = float(np.sqrt(np.mean([s.covered_std_db**2 for s in spreads.values()])))
    notes = [own.note] if own is not None and own.note else []
    if model.training.selection is None:  # a fixed order: the ridge's estimate, no posterior
        return DecouplingCertificate(spreads, covered_db=covered_db, notes=[
            "(a fixed-order fit's covariance leaves out what its ridge decides where the flight cannot split the "
            "patterns, so these spreads are lower bounds and the unsplit components are not computed; "
            "--order auto gives the posterior's)"])
    if samples is None and gram is None:
        return DecouplingCertificate(spreads, covered_db=covered_db, own_std_db=maps, notes=notes + [
            "(the components not split between nodes are not computed: the pairs of learning directions were not kept)"])
    columns = (model.basis if own is None else own.basis).n_coef * len(model.nodes)
    if columns > MAX_COMPONENT_COLUMNS:
        return DecouplingCertificate(spreads, covered_db=covered_db, own_std_db=maps, notes=notes + [
            f"(components not computed: {columns} pattern columns, above {MAX_COMPONENT_COLUMNS})"])
    joint = _joint_metric(model, samples, gram, n_samples, None if own is None else own.basis)
    comps, n_unsplit, unsplit_db, total_db = unsplit_components(model, covered, metrics, joint, own)
    return DecouplingCertificate(spreads, tuple(comps), n_unsplit, unsplit_db, total_db, notes, maps)


@check_types
def certify(model: Any, samples: LinkSamples | Sequence[LinkSamples] | None = None,
            posterior: OwnPosterior | None = None, learning_gram: LearningGram | None = None) -> DecouplingCertificate | None:
    """:func:`decoupling_certificate` of a fitted model, stored in ``model.training.decoupling``
    (with its :meth:`~DecouplingCertificate.summary` text, which ``fit`` prints); None, and
    nothing stored, for a model without patterns, covariance or coverage grid (a baseline).
    ``learning_gram`` (an automatic fit's :attr:`~rplearn.models.fit.FittedModel.learning_gram`):
    the joint metric is read off it, not off ``samples`` (which are then not needed)."""
    if not isinstance(model, PatternSet) or model.covariance is None or not model.training.coverage_deg:
        return None
    if learning_gram is not None:
        own = posterior if model.training.selection is not None else None
        gram = learning_gram.at(model.basis if own is None else own.basis)
        cert = decoupling_certificate(model, gram=gram, n_samples=learning_gram.n_samples, posterior=posterior)
    else:
        cert = decoupling_certificate(model, samples, posterior=posterior)
    model.training = model.training.replace(decoupling={**cert.to_dict(), "summary": cert.summary()})
    return cert


__all__ = ["MAX_COMPONENT_COLUMNS", "OWN_MAP_POINTS", "certify", "own_std_maps", "MIN_LISTED_DB", "UNSPLIT_JOINT_FRACTION",
           "DecouplingCertificate", "NodeSpread", "SplitComponent", "covered_directions", "decoupling_certificate", "unsplit_components"]
