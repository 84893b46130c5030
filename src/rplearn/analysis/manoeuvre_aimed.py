"""Where each node's pattern posterior is widest now: the aims of :mod:`rplearn.plan.aimed`.

The spread the ranking reads (:mod:`rplearn.analysis.manoeuvres`) is the RMS over a node's target
directions of its gain's posterior std, the node's mean over them removed. Its pointwise part,
``var_i = x_i^T Sigma_kk x_i + |x_i^T D_k|^2`` (``x_i`` the mean-removed design at target direction
``i``, ``Sigma`` the white covariance and ``D`` the drifting/misfit factor of
:class:`~rplearn.analysis.manoeuvre_posterior.ManoeuvrePosterior`), says where the variance left
sits; :func:`widest_directions` picks, per node, the ``n`` target directions of largest variance
at least :data:`AIM_SEPARATION_DEG` apart, for which :func:`rplearn.plan.aimed.aimed_manoeuvres`
builds manoeuvres that look along them.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from rplearn.analysis.manoeuvre_posterior import ManoeuvrePosterior
from rplearn.core.bases import fibonacci_grid_nodes
from rplearn.core.basis_base import Basis
from rplearn.core.geometry import unit_vector
from rplearn.errors import InputError

#: Smallest angle between two aims of a node [deg] (the next widest direction is otherwise a
#: neighbour of the first, the same manoeuvre).
AIM_SEPARATION_DEG = 30.0


def target_directions(nodes: Sequence[str], target_points: int, target_el_deg: tuple[float, float],
                      targets: Mapping[str, tuple[Any, Any]] | None) -> list[tuple[np.ndarray, np.ndarray]]:
    """Per node, its target directions (az, el) [rad]: ``targets[node]`` if given, else the points
    of a ``target_points`` Fibonacci grid within the elevation band ``target_el_deg`` [deg]."""
    az_all, el_all = fibonacci_grid_nodes(int(target_points))
    lo, hi = np.radians(target_el_deg[0]), np.radians(target_el_deg[1])
    band = (el_all >= lo - 1e-12) & (el_all <= hi + 1e-12)
    out = []
    for node in nodes:
        if targets is not None and node in targets:
            az, el = (np.asarray(v, np.float64).ravel() for v in targets[node])
        else:
            az, el = az_all[band], el_all[band]
        if az.size == 0:
            raise InputError(f"targets: no target direction for node {node}", param="targets")
        out.append((az, el))
    return out


def pointwise_variances(post: ManoeuvrePosterior, basis: Basis,
                        directions: Sequence[tuple[np.ndarray, np.ndarray]]) -> list[np.ndarray]:
    """Per node, the posterior variance of its mean-removed gain at each of its target directions [dB^2]."""
    p = basis.n_coef
    out = []
    for k, (az, el) in enumerate(directions):
        x = basis.design(az, el)
        x = x - x.mean(axis=0)
        blk = slice(k * p, (k + 1) * p)
        var = np.einsum("ij,ij->i", x @ post.cov[blk, blk], x)
        if post.drift.shape[1]:
            var = var + np.sum((x @ post.drift[blk]) ** 2, axis=1)
        out.append(np.maximum(var, 0.0))
    return out


def widest_directions(post: ManoeuvrePosterior, basis: Basis, nodes: Sequence[str],
                      directions: Sequence[tuple[np.ndarray, np.ndarray]], n: int) -> dict[str, list[tuple[float, float]]]:
    """Per node, up to ``n`` target directions (az, el) [rad] of largest posterior variance, widest
    first, each at least :data:`AIM_SEPARATION_DEG` from those before it."""
    out: dict[str, list[tuple[float, float]]] = {}
    cos_min = float(np.cos(np.radians(AIM_SEPARATION_DEG)))
    for node, (az, el), var in zip(nodes, directions, pointwise_variances(post, basis, directions)):
        u = unit_vector(az, el)
        picked: list[int] = []
        for i in np.argsort(-var, kind="stable"):
            if len(picked) >= n:
                break
            if all(float(u[i] @ u[j]) < cos_min for j in picked):
                picked.append(int(i))
        out[str(node)] = [(float(az[i]), float(el[i])) for i in picked]
    return out


__all__ = ["AIM_SEPARATION_DEG", "pointwise_variances", "target_directions", "widest_directions"]
