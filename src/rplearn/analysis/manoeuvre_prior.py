"""The smoothness prior's weight that gives a stated pattern spread before any data (for
:attr:`rplearn.analysis.manoeuvres.ManoeuvreOptions.penalty_weight`; re-exported there)."""

from __future__ import annotations

import numpy as np

from rplearn._argtypes import check_types
from rplearn.core.bases import fibonacci_grid_nodes
from rplearn.core.basis_base import Basis
from rplearn.core.lsq.penalty import DEFAULT_PENALTY_POWER
from rplearn.errors import InputError

#: Each node's pattern spread over its sphere [dB] a plan assumes before any data identify the
#: shape (``rplearn trajectory --optimize --prior-std``'s default; ``rplearn live`` ranks under it
#: while its fit is at the search's largest smoothing).
NOMINAL_PRIOR_STD_DB = 6.0


@check_types
def prior_penalty_weight(basis: Basis, prior_std_db: float, noise_std_db: float, ridge: float,
                         power: float = DEFAULT_PENALTY_POWER, shape: str = "smoothness") -> float:
    """The absolute penalty weight whose prior gives each node a spread of ``prior_std_db`` over
    the sphere before any data (the node's mean removed), for :attr:`ManoeuvreOptions.penalty_weight`.

    ``shape="smoothness"`` weighs the coefficients by the basis's roughness (``(l(l+1))^power``
    for SH: the smoothness prior of ``fit --degree auto``); ``"reference"`` by one (a plain ridge
    on the deviation from a reference pattern, as ``fit --prior``). The prior covariance of a
    node's coefficients is ``noise^2 / (ridge + weight * roughness)``; a spread above what the
    ridge alone allows at the basis's order gives 0 (no penalty: the ridge's spread).
    """
    for name, v in (("prior_std_db", prior_std_db), ("noise_std_db", noise_std_db)):
        if not (np.isfinite(v) and v > 0):
            raise InputError(f"{name}: expected a positive spread [dB], got {v!r}", param=name)
    if shape not in ("smoothness", "reference"):
        raise InputError(f"shape: expected 'smoothness' or 'reference', got {shape!r}", param="shape")
    rough = basis.roughness(power) if shape == "smoothness" else np.ones(basis.n_coef)
    az, el = fibonacci_grid_nodes(2048)
    x = basis.design(az, el)
    m = np.einsum("ij,ij->j", x - x.mean(axis=0), x - x.mean(axis=0)) / x.shape[0]

    def spread(weight: float) -> float:
        return float(np.sqrt(noise_std_db**2 * np.sum(m / np.maximum(ridge + weight * rough, 1e-300))))

    lo, hi = 1e-9, 1e12
    if spread(hi) > prior_std_db:
        raise InputError(f"prior_std_db: {prior_std_db:g} dB is below what the ridge alone allows "
                         f"({spread(hi):.3g} dB)", param="prior_std_db")
    if spread(lo) < prior_std_db:
        return 0.0
    for _ in range(200):
        mid = np.sqrt(lo * hi)
        lo, hi = (mid, hi) if spread(mid) > prior_std_db else (lo, mid)
    return float(np.sqrt(lo * hi))


__all__ = ["NOMINAL_PRIOR_STD_DB", "prior_penalty_weight"]
