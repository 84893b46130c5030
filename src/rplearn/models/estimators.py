"""scikit-learn estimators: the joint pattern model and the paper's baselines (Sec. V-C1).

All three share one input convention, so that ``GridSearchCV`` and ``cross_val_score`` can
tune and compare them:

``X`` has 4 columns ``az_tx, el_tx, az_rx, el_rx`` [rad] (paper eq. 3) for a single link
direction between two nodes, or 6 columns with the transmitter's and receiver's node numbers
appended (integers ``0 .. n_nodes-1``) for any number of nodes; ``y`` is the observed joint
gain [dB] (paper eq. 5).

- :class:`PatternRegressor` learns one pattern per node (SH, BG or P basis) and decouples
  the joint gain (paper Sec. IV-B, V-A).
- :class:`MeanRegressor` (the paper's M) predicts the training mean.
- :class:`JointKNNRegressor` (the paper's NN-k, ``k = 400``) averages the ``k`` nearest
  training samples in the 4-D joint-angle space; it cannot decouple the patterns.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from sklearn.base import BaseEstimator, RegressorMixin
from sklearn.neighbors import KNeighborsRegressor
from sklearn.utils.validation import check_is_fitted, validate_data

from rplearn.core.bases import make_basis
from rplearn.errors import InputError
from rplearn.core.geometry import Directions
from rplearn.models.patterns import PatternSet
from rplearn.core.solver import DEFAULT_RIDGE, fit_joint

ANGLE_COLUMNS = ("az_tx", "el_tx", "az_rx", "el_rx")


def split_features(X: np.ndarray) -> tuple[Directions, np.ndarray, np.ndarray]:
    """Directions and node numbers from a 4- or 6-column feature matrix."""
    if X.ndim != 2 or X.shape[1] not in (4, 6):
        raise InputError(
            f"X must have 4 columns (az_tx, el_tx, az_rx, el_rx) or 6 (plus tx and rx node numbers), got shape {X.shape}"
        )
    d = Directions(X[:, 0], X[:, 1], X[:, 2], X[:, 3])
    if X.shape[1] == 4:
        n = X.shape[0]
        return d, np.zeros(n, np.intp), np.ones(n, np.intp)
    tx, rx = X[:, 4], X[:, 5]
    if np.any(tx != np.round(tx)) or np.any(rx != np.round(rx)) or np.any(tx < 0) or np.any(rx < 0):
        raise InputError("node number columns (5 and 6) must hold non-negative integers")
    return d, tx.astype(np.intp), rx.astype(np.intp)


class PatternRegressor(RegressorMixin, BaseEstimator):
    """Joint radiation-pattern model: one pattern per node, fitted by least squares.

    Parameters
    ----------
    basis : {"sh", "bg", "poly"}
        Basis family (paper Sec. IV-C to IV-E).
    order : int
        SH-L (degrees 0..L-1), BG-k (k x 2k grid) or P-k (total degree <= k).
    ridge : float
        Ridge weight on the diagonal of ``X^T X`` (default 1; the paper used 50).
    sigma_rad2 : float
        BG kernel variance [rad^2] (paper's sigma).
    grid : {"paper", "fibonacci"}
        BG node layout.
    gauge : "equal-mean" or dict
        How the constant a two-node problem cannot identify is fixed.
    n_nodes : int or None
        Number of nodes; by default one more than the largest node number seen (2 for 4 columns).

    Attributes
    ----------
    patterns_ : PatternSet
        Learned patterns (node names are the node numbers as strings).
    report_ : FitReport
        Rank, null-space dimension, condition number, gauge notes.
    coef_ : ndarray (n_nodes, n_coef)
    """

    def __init__(
        self,
        basis: str = "sh",
        order: int = 10,
        ridge: float = DEFAULT_RIDGE,
        sigma_rad2: float = 0.5,
        grid: str = "paper",
        gauge: Any = "equal-mean",
        n_nodes: int | None = None,
    ) -> None:
        self.basis = basis
        self.order = order
        self.ridge = ridge
        self.sigma_rad2 = sigma_rad2
        self.grid = grid
        self.gauge = gauge
        self.n_nodes = n_nodes

    def _make_basis(self):
        if str(self.basis).lower() == "bg":
            return make_basis("bg", self.order, sigma_rad2=self.sigma_rad2, grid=self.grid)
        return make_basis(self.basis, self.order)

    def fit(self, X, y):
        X, y = validate_data(self, X, y, y_numeric=True, dtype=np.float64)
        d, tx, rx = split_features(X)
        n_nodes = self.n_nodes if self.n_nodes is not None else int(max(tx.max(), rx.max())) + 1
        n_nodes = max(n_nodes, 2)
        basis = self._make_basis()
        names = [str(i) for i in range(n_nodes)]
        sol = fit_joint(d, tx, rx, y, n_nodes, basis, node_names=names, ridge=self.ridge, gauge=self.gauge)
        self.report_ = sol.report
        self.coef_ = sol.coef
        self.patterns_ = PatternSet(
            basis=basis,
            nodes=tuple(names),
            coef=sol.coef,
            covariance=sol.covariance,
            gauge=[g.to_dict() for g in sol.report.gauges],
            training=sol.report.to_dict(),
        )
        return self

    def predict(self, X):
        check_is_fitted(self, "coef_")
        X = validate_data(self, X, reset=False, dtype=np.float64)
        d, tx, rx = split_features(X)
        if np.any(tx >= self.coef_.shape[0]) or np.any(rx >= self.coef_.shape[0]):
            raise InputError(f"node number beyond the {self.coef_.shape[0]} nodes the model was fitted on")
        basis = self.patterns_.basis
        ft = basis.design_t(d.az_tx, d.el_tx)
        fr = basis.design_t(d.az_rx, d.el_rx)
        return np.einsum("pn,np->n", ft, self.coef_[tx]) + np.einsum("pn,np->n", fr, self.coef_[rx])

    @property
    def n_params_(self) -> int:
        """Coefficients of all antennas (the paper's |phi| column)."""
        check_is_fitted(self, "coef_")
        return int(self.coef_.size)


class MeanRegressor(RegressorMixin, BaseEstimator):
    """The paper's M baseline: the mean of the training joint gain, whatever the directions."""

    def fit(self, X, y):
        X, y = validate_data(self, X, y, y_numeric=True, dtype=np.float64)
        self.mean_ = float(np.mean(y))
        return self

    def predict(self, X):
        check_is_fitted(self, "mean_")
        X = validate_data(self, X, reset=False, dtype=np.float64)
        return np.full(X.shape[0], self.mean_)

    @property
    def n_params_(self) -> int:
        return 1


class JointKNNRegressor(RegressorMixin, BaseEstimator):
    """The paper's NN-k baseline: k nearest neighbours in the 4-D joint-angle space.

    Uses the Euclidean distance of ``(az_tx, el_tx, az_rx, el_rx)`` [rad], uniform weights,
    as the paper does (its k = 400 was the best; larger k tends to the mean). Node-number
    columns, if present, are ignored: the model learns the joint pattern only.
    """

    def __init__(self, n_neighbors: int = 400) -> None:
        self.n_neighbors = n_neighbors

    def fit(self, X, y):
        X, y = validate_data(self, X, y, y_numeric=True, dtype=np.float64)
        split_features(X)  # same fixed layout as PatternRegressor
        k = min(int(self.n_neighbors), X.shape[0])
        self.knn_ = KNeighborsRegressor(n_neighbors=k, algorithm="kd_tree").fit(X[:, :4], y)
        self.n_train_ = X.shape[0]
        return self

    def predict(self, X):
        check_is_fitted(self, "knn_")
        X = validate_data(self, X, reset=False, dtype=np.float64)
        split_features(X)
        return self.knn_.predict(X[:, :4])

    @property
    def n_params_(self) -> int:
        """All training samples serve as parameters (the paper's Table I counts them)."""
        return int(self.n_train_)
