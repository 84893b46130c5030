"""scikit-learn estimators: the joint pattern model and the paper's baselines (Sec. V-C1).

All three share one input convention, so that ``GridSearchCV`` and ``cross_val_score`` can
tune and compare them:

``X`` has 4 columns ``az_tx, el_tx, az_rx, el_rx`` [rad] (paper eq. 3) for a single link
direction between two nodes, or 6 columns with the transmitter's and receiver's node numbers
appended (integers ``0 .. n_nodes-1``) for any number of nodes; ``y`` is the observed joint
gain [dB] (paper eq. 5).

The estimators are thin wrappers: the maths is that of the model classes, on the same code
path.

- :class:`PatternRegressor` learns one pattern per node (SH, BG or P basis) and decouples
  the joint gain (paper Sec. IV-B, V-A): :func:`rplearn.models.fit.solve_patterns`, the
  solver behind :func:`~rplearn.models.fit.fit_patterns`; it predicts with
  :meth:`rplearn.models.patterns.PatternSet.predict_gain`.
- :class:`MeanRegressor` (the paper's M) predicts the training mean: the one-link case of
  :class:`~rplearn.models.baselines.MeanModel` (:func:`~rplearn.models.baselines.mean_joint_gain_db`).
- :class:`JointKNNRegressor` (the paper's NN-k, ``k = 400``) averages the ``k`` nearest
  training samples in the 4-D joint-angle space; it cannot decouple the patterns. It is the
  one-link case of :class:`~rplearn.models.baselines.KNNModel`
  (:func:`~rplearn.models.baselines.knn_regressor`), and like it refuses a ``k`` larger than
  the number of training samples.
"""

from __future__ import annotations

from typing import Any, Self

import numpy as np
from sklearn.base import BaseEstimator, RegressorMixin
from sklearn.utils.validation import check_is_fitted, validate_data

from rplearn.core.gauge import Gauge
from rplearn.core.geometry import Directions
from rplearn.core.lsq.solver import DEFAULT_RIDGE
from rplearn.data.tables import LinkSamples
from rplearn.errors import InputError
from rplearn.models.baselines import knn_regressor, mean_joint_gain_db
from rplearn.models.fit import solve_patterns
from rplearn.models.options import FitOptions
from rplearn.models.spec import ModelSpec

ANGLE_COLUMNS = ("az_tx", "el_tx", "az_rx", "el_rx")
_BASIS_KINDS = {"sh": "sh", "bg": "bg", "poly": "poly", "p": "poly"}


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


def samples_from_features(X: np.ndarray, y: np.ndarray | None, nodes: tuple[str, ...]) -> LinkSamples:
    """The :class:`~rplearn.data.tables.LinkSamples` of a feature matrix (see module docstring).

    Parameters
    ----------
    X : ndarray, shape (n, 4) or (n, 6)
    y : ndarray or None
        Joint gain [dB]; None (NaN) to predict.
    nodes : tuple of str
        Node names; node number ``i`` is ``nodes[i]``.
    """
    d, tx, rx = split_features(X)
    n = X.shape[0]
    gain = np.full(n, np.nan) if y is None else np.asarray(y, np.float64)
    return LinkSamples(d, tx, rx, nodes, gain, np.full(n, np.nan))


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
    link_offsets : bool
        Learn one electronics offset per link seen in both directions (non-reciprocal radios);
        False (the default here) takes the radios as reciprocal, as the paper's model does.

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
        link_offsets: bool = False,
    ) -> None:
        self.basis = basis
        self.order = order
        self.ridge = ridge
        self.sigma_rad2 = sigma_rad2
        self.grid = grid
        self.gauge = gauge
        self.n_nodes = n_nodes
        self.link_offsets = link_offsets

    def _spec(self) -> ModelSpec:
        """The :class:`ModelSpec` of the hyper-parameters (the model classes' spec)."""
        kind = _BASIS_KINDS.get(str(self.basis).lower())
        if kind is None:
            raise InputError(f"basis: expected one of sh, bg or poly, got {self.basis!r}", param="basis")
        return ModelSpec(kind, self.order, self.ridge, self.sigma_rad2, self.grid)

    def fit(self, X: Any, y: Any) -> Self:  # array-likes, checked by validate_data
        X, y = validate_data(self, X, y, y_numeric=True, dtype=np.float64)
        _, tx, rx = split_features(X)
        n_nodes = self.n_nodes if self.n_nodes is not None else int(max(tx.max(), rx.max())) + 1
        names = tuple(str(i) for i in range(max(n_nodes, 2)))
        options = FitOptions(gauge=Gauge.of(self.gauge), link_offsets=bool(self.link_offsets))
        self.patterns_, self.report_ = solve_patterns(samples_from_features(X, y, names), self._spec(), options)
        self.coef_ = self.patterns_.coef
        return self

    def predict(self, X: Any) -> np.ndarray:  # an array-like, checked by validate_data
        check_is_fitted(self, "coef_")
        X = validate_data(self, X, reset=False, dtype=np.float64)
        _, tx, rx = split_features(X)
        if np.any(tx >= self.coef_.shape[0]) or np.any(rx >= self.coef_.shape[0]):
            raise InputError(f"node number beyond the {self.coef_.shape[0]} nodes the model was fitted on")
        return self.patterns_.predict_gain(samples_from_features(X, None, self.patterns_.nodes))

    @property
    def n_params_(self) -> int:
        """Coefficients of all antennas (the paper's |phi| column), and any link offsets."""
        check_is_fitted(self, "coef_")
        return int(self.patterns_.n_params)


class MeanRegressor(RegressorMixin, BaseEstimator):
    """The paper's M baseline: the mean of the training joint gain, whatever the directions.

    The one-link case of :class:`~rplearn.models.baselines.MeanModel`, which keeps one mean
    per directed link: this estimator treats every sample as one link (node-number columns,
    if present, are ignored, as are the angles), which with one link is the paper's global M.
    Any number of feature columns is accepted.
    """

    def fit(self, X: Any, y: Any) -> Self:  # array-likes, checked by validate_data
        X, y = validate_data(self, X, y, y_numeric=True, dtype=np.float64)
        self.mean_ = mean_joint_gain_db(y)
        return self

    def predict(self, X: Any) -> np.ndarray:  # an array-like, checked by validate_data
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
    columns, if present, are ignored: the model learns the joint pattern of one link, the
    one-link case of :class:`~rplearn.models.baselines.KNNModel`.

    Raises
    ------
    IdentifiabilityError
        From :meth:`fit`, naming ``n_neighbors``, when it exceeds the number of training samples.
    """

    def __init__(self, n_neighbors: int = 400) -> None:
        self.n_neighbors = n_neighbors

    def fit(self, X: Any, y: Any) -> Self:  # array-likes, checked by validate_data
        X, y = validate_data(self, X, y, y_numeric=True, dtype=np.float64)
        split_features(X)  # same fixed layout as PatternRegressor
        self.knn_ = knn_regressor(X[:, :4], y, self.n_neighbors)
        self.n_train_ = X.shape[0]
        return self

    def predict(self, X: Any) -> np.ndarray:  # an array-like, checked by validate_data
        check_is_fitted(self, "knn_")
        X = validate_data(self, X, reset=False, dtype=np.float64)
        split_features(X)
        return self.knn_.predict(X[:, :4])

    @property
    def n_params_(self) -> int:
        """All training samples serve as parameters (the paper's Table I counts them)."""
        return int(self.n_train_)
