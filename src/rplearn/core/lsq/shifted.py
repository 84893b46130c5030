"""Statistics of the data less a known fit: ``y - X t`` from those of ``y``, no sample re-read.

An automatic fit with a reference prior (``fit --order auto --prior``) searches the order of the
*deviation* from the prior: with ``t`` the prior's coefficients at the largest candidate order,
the model at a smaller order ``k`` is ``t`` plus a deviation in the degrees up to ``k``
(:mod:`rplearn.models.auto_prior`). Its penalised least squares are those of the residuals
``y - X t`` with a zero target, so the order search runs unchanged on shifted statistics:

- ``X^T (y - X t) = X^T y - X^T X t``,
- ``(y - X t)^T (y - X t) = y^T y - 2 t^T X^T y + t^T X^T X t``,
- each directed link's sum of ``y`` less its feature sums times ``t``, and ``e^T y`` less
  ``e^T X t`` (the environment column), so that :meth:`NormalEquations.column_sums` and
  :meth:`NormalEquations.with_shared` read the shifted data too.

Linear in the statistics, so per-unit shifts add up to the shift of their sum and every fold of
the cross-validation is exact.
"""

from __future__ import annotations

import copy

import numpy as np

from rplearn.core.lsq.normal_equations import NormalEquations


def shifted_statistics(normal: NormalEquations, coef: np.ndarray) -> NormalEquations:
    """The statistics of ``y - X coef`` (see the module docstring).

    Parameters
    ----------
    normal : NormalEquations
        Statistics of ``y`` (shared columns, if any, appended).
    coef : 1-D float64 array
        One value per pattern column of ``normal`` (the shared columns are not shifted: their
        coefficients are taken as zero).

    Returns
    -------
    NormalEquations
        A new object sharing ``normal``'s Gram, marked read-only (a merge into it copies it
        first), every other array its own; ``normal`` is unchanged.
    """
    pat = normal.n_pattern_columns
    t = np.zeros(normal.n_columns)
    t[:pat] = np.asarray(coef, np.float64).ravel()[:pat]
    gt = normal.gram @ t
    out = copy.copy(normal)
    out.gram = normal.gram.view()
    out.gram.flags.writeable = False
    out.rhs = normal.rhs - gt
    out.yty = float(normal.yty - 2.0 * float(normal.rhs @ t) + float(t @ gt))
    p = normal.basis.n_coef
    blocks = t[:pat].reshape(normal.n_nodes, p)
    directed = {}  # their feature sums are in the columns' order (NormalEquations.column_sums)
    for (a, b), v in normal.directed.items():
        w = v.copy()
        w[2 * p] -= float(v[:p] @ blocks[a] + v[p:2 * p] @ blocks[b])
        directed[(a, b)] = w
    out.directed = directed
    out.link_counts = dict(normal.link_counts)
    out.env_cross = normal.env_cross.copy()  # a merge or add into the copy adds into it in place
    out.env_y = float(normal.env_y - normal.env_cross @ t[:pat])
    out.blocks = None
    return out


__all__ = ["shifted_statistics"]
