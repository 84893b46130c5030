"""Baselines of paper Sec. V-C1, on link samples: the mean (M) and k nearest neighbours (NN-k).

Neither decouples the joint gain into per-node patterns. Both are kept per directed link
``tx -> rx`` (with a single link, as in the paper, this is the paper's global model): the
joint gain of one link says nothing about another.

- :class:`MeanModel`: the mean training joint gain.
- :class:`KNNModel`: the average joint gain of the ``k`` (default 400) nearest training samples
  in the 4-D joint-angle space ``(az_tx, el_tx, az_rx, el_rx)`` [rad], Euclidean distance,
  uniform weights (paper: k = 400 was best; larger k tends to the mean).

The maths of one link, :func:`mean_joint_gain_db` and :func:`knn_regressor`, is shared with the
scikit-learn estimators of :mod:`rplearn.models.estimators`, which see one link at a time.
Both classes implement the :class:`rplearn.models.base.Model` protocol.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike

from rplearn._argtypes import check_types
from rplearn.data.tables import LinkSamples
from rplearn.errors import IdentifiabilityError, InputError, ModelFileError
from rplearn.io.modelfile import read_sidecar, write_model_with_sidecar
from rplearn.models.base import frequency_from_training, learned_frequency_hz
from rplearn.models.training import TrainingSummary, training_and_provenance

if TYPE_CHECKING:
    from sklearn.neighbors import KNeighborsRegressor

Link = tuple[str, str]


def _links(samples: LinkSamples) -> dict[Link, np.ndarray]:
    """Sample indices of every directed link ``(tx, rx)`` of the samples."""
    code = samples.tx_index.astype(np.int64) * len(samples.nodes) + samples.rx_index
    out = {}
    for c in np.unique(code):
        t, r = divmod(int(c), len(samples.nodes))
        out[(samples.nodes[t], samples.nodes[r])] = np.flatnonzero(code == c)
    return out


def _angles(samples: LinkSamples, idx: np.ndarray | slice = slice(None)) -> np.ndarray:
    """Joint angles ``(az_tx, el_tx, az_rx, el_rx)`` of the chosen samples [rad], one row each."""
    d = samples.directions
    return np.column_stack([d.az_tx[idx], d.el_tx[idx], d.az_rx[idx], d.el_rx[idx]])


def _missing_link(key: Link, known: Iterable[Link]) -> InputError:
    names = ", ".join(f"{a}->{b}" for a, b in known)
    return InputError(f"link {key[0]}->{key[1]} was not in the training data (the model knows {names})")


def _nodes_of_links(links: Iterable[Link]) -> tuple[str, ...]:
    """Node ids of directed links, in order of first appearance."""
    return tuple(dict.fromkeys(n for key in links for n in key))


def _baseline_training(samples: LinkSamples) -> TrainingSummary:
    """Training summary of a baseline: sample count and, when known, the carrier [Hz]."""
    return TrainingSummary(n_samples=len(samples), frequency_hz=learned_frequency_hz(samples))


# -- the maths of one link, shared with the scikit-learn estimators -------------------------
def mean_joint_gain_db(gain_db: ArrayLike) -> float:
    """The paper's M for one link: the mean training joint gain [dB].

    Raises
    ------
    IdentifiabilityError
        Without any sample.
    """
    g = np.asarray(gain_db, np.float64)
    if g.size == 0:
        raise IdentifiabilityError("the mean baseline needs at least one sample")
    return float(np.mean(g))


def check_n_neighbors(n_neighbors: Any, n_samples: int | None = None, what: str = "the training data") -> int:
    """``n_neighbors`` as an int: positive, and at most ``n_samples`` when that is given.

    Raises
    ------
    InputError
        (``param="n_neighbors"``) unless a positive integer.
    IdentifiabilityError
        (``param="n_neighbors"``) when ``what`` has fewer than ``n_neighbors`` samples.
    """
    try:
        k = int(n_neighbors)
    except (TypeError, ValueError):
        k = 0
    if k < 1 or k != n_neighbors:
        raise InputError(f"n_neighbors must be a positive integer, got {n_neighbors!r}", param="n_neighbors")
    if n_samples is not None and n_samples < k:
        raise IdentifiabilityError(
            f"{what} has {n_samples} samples, fewer than n_neighbors = {k} neighbours", param="n_neighbors"
        )
    return k


def knn_regressor(
    angles_rad: np.ndarray, gain_db: np.ndarray, n_neighbors: int, what: str = "the training data"
) -> KNeighborsRegressor:
    """The paper's NN-k for one link: a fitted k-d-tree ``KNeighborsRegressor``.

    Parameters
    ----------
    angles_rad : ndarray, shape (n, 4)
        Joint angles ``(az_tx, el_tx, az_rx, el_rx)`` [rad].
    gain_db : ndarray, shape (n,)
        Joint gain [dB].
    n_neighbors : int
        k; refused (see :func:`check_n_neighbors`) when larger than ``n``.
    what : str
        What the samples are, for the message.
    """
    from sklearn.neighbors import KNeighborsRegressor  # imported on use: slow to import

    k = check_n_neighbors(n_neighbors, len(gain_db), what)
    return KNeighborsRegressor(n_neighbors=k, algorithm="kd_tree").fit(angles_rad, gain_db)


# -- the models -----------------------------------------------------------------------------
class _PerLinkBaseline:
    """What both baselines share: they know the directed links they learned, and the carrier
    their training samples were at."""

    training: TrainingSummary

    def _known_links(self) -> Mapping[tuple[str, str], Any]:
        raise NotImplementedError

    @property
    def nodes(self) -> tuple[str, ...]:
        """Node ids of the links the model knows."""
        return _nodes_of_links(self._known_links())

    @property
    def frequency_hz(self) -> float | None:
        """Carrier frequency of the training samples [Hz] (None: unknown)."""
        return frequency_from_training(self.training)

    def _per_link(self, samples: LinkSamples, value: Callable[[Link, np.ndarray], Any]) -> np.ndarray:
        """``value(link, indices)`` for the samples of each directed link [dB]; a link the model
        does not know is refused, naming the ones it knows."""
        known = self._known_links()
        out = np.empty(len(samples))
        for key, idx in _links(samples).items():
            if key not in known:
                raise _missing_link(key, known)
            out[idx] = value(key, idx)
        return out

    def predict_gain_std(self, samples: LinkSamples) -> None:
        """None: the baseline has no coefficient covariance."""
        return None


@check_types
@dataclass
class MeanModel(_PerLinkBaseline):
    """The paper's M: mean training joint gain per directed link [dB]."""

    means_db: dict[Link, float]
    training: TrainingSummary = field(default_factory=TrainingSummary)
    provenance: dict[str, Any] = field(default_factory=dict)
    kind: str = "mean"
    label: str = "M"

    def __post_init__(self) -> None:
        self.training = TrainingSummary.from_dict(self.training)

    @classmethod
    def fit(cls, samples: LinkSamples) -> MeanModel:
        if len(samples) == 0:
            raise IdentifiabilityError("the mean baseline needs at least one sample")
        means = {k: mean_joint_gain_db(samples.joint_gain_db[i]) for k, i in _links(samples).items()}
        return cls(means, training=_baseline_training(samples))

    def _known_links(self) -> Mapping[tuple[str, str], Any]:
        return self.means_db

    @property
    def n_params(self) -> int:
        """One mean per directed link."""
        return len(self.means_db)

    def predict_gain(self, samples: LinkSamples) -> np.ndarray:
        """The training mean of each sample's link [dB]."""
        return self._per_link(samples, lambda key, idx: self.means_db[key])

    def to_dict(self) -> dict[str, Any]:
        return {
            "label": self.label,
            "links": [{"tx": t, "rx": r, "mean_db": v} for (t, r), v in self.means_db.items()],
            "training": self.training.to_dict(),
            "provenance": self.provenance,
        }

    def save(self, path: str | os.PathLike[str]) -> None:
        write_model_with_sidecar(path, "mean", self.to_dict(), None)  # (removes an earlier save's sidecar)

    @classmethod
    def from_dict(cls, payload: Mapping[str, Any], source: str = "model") -> MeanModel:
        try:
            means = {(str(e["tx"]), str(e["rx"])): float(e["mean_db"]) for e in payload["links"]}
        except (KeyError, TypeError, ValueError) as exc:
            raise ModelFileError(f"{source}: malformed mean model ({type(exc).__name__}: {exc})") from None
        if not means or not all(np.isfinite(list(means.values()))):
            raise ModelFileError(f"{source}: mean model needs finite means for at least one link")
        return cls(means, *training_and_provenance(payload, source))


@check_types
@dataclass
class KNNModel(_PerLinkBaseline):
    """The paper's NN-k: k nearest neighbours in the 4-D joint-angle space, per directed link."""

    n_neighbors: int
    train_angles_rad: dict[Link, np.ndarray]
    train_gain_db: dict[Link, np.ndarray]
    training: TrainingSummary = field(default_factory=TrainingSummary)
    provenance: dict[str, Any] = field(default_factory=dict)
    kind: str = "knn"

    def __post_init__(self) -> None:
        self.training = TrainingSummary.from_dict(self.training)
        self._regressors: dict[Link, Any] = {}

    @property
    def label(self) -> str:
        return f"NN-{self.n_neighbors}"

    @classmethod
    def fit(cls, samples: LinkSamples, n_neighbors: int = 400) -> KNNModel:
        k = check_n_neighbors(n_neighbors)
        angles, gains = {}, {}
        for key, idx in _links(samples).items():
            angles[key] = _angles(samples, idx)
            gains[key] = samples.joint_gain_db[idx].copy()
        model = cls(k, angles, gains, training=_baseline_training(samples))
        for key in angles:
            model._regressor(key)
        return model

    def _regressor(self, key: Link) -> KNeighborsRegressor:
        if key not in self._regressors:
            what = f"link {key[0]}->{key[1]}"
            self._regressors[key] = knn_regressor(self.train_angles_rad[key], self.train_gain_db[key], self.n_neighbors, what)
        return self._regressors[key]

    def _known_links(self) -> Mapping[tuple[str, str], Any]:
        return self.train_gain_db

    @property
    def n_params(self) -> int:
        """Every training sample is a parameter (paper Table I)."""
        return int(sum(v.size for v in self.train_gain_db.values()))

    def predict_gain(self, samples: LinkSamples) -> np.ndarray:
        """Mean joint gain of the k nearest training samples of each sample's link [dB]."""
        return self._per_link(samples, lambda key, idx: self._regressor(key).predict(_angles(samples, idx)))

    def to_dict(self) -> dict[str, Any]:
        return {
            "label": self.label,
            "n_neighbors": self.n_neighbors,
            "links": [
                {"tx": t, "rx": r, "angles_rad": self.train_angles_rad[(t, r)].tolist(), "gain_db": self.train_gain_db[(t, r)].tolist()}
                for (t, r) in self.train_gain_db
            ],
            "training": self.training.to_dict(),
            "provenance": self.provenance,
        }

    def save(self, path: str | os.PathLike[str]) -> None:
        """Write the model file, its training samples in a binary sidecar beside it
        (``model.json.<sha>.npz``, checksummed in the model file; see
        :func:`rplearn.io.modelfile.write_model_with_sidecar`): JSON text of 150k samples was 22 MB and
        took seconds to read."""
        links = list(self.train_gain_db)
        arrays: dict[str, np.ndarray] = {}
        for i, key in enumerate(links):
            arrays[f"angles_{i}"] = np.asarray(self.train_angles_rad[key], np.float64)
            arrays[f"gain_{i}"] = np.asarray(self.train_gain_db[key], np.float64)
        payload = {
            "label": self.label,
            "n_neighbors": self.n_neighbors,
            "links": [{"tx": t, "rx": r, "samples": int(self.train_gain_db[(t, r)].size)} for t, r in links],
            "training": self.training.to_dict(),
            "provenance": self.provenance,
        }
        write_model_with_sidecar(path, "knn", payload, arrays)

    @classmethod
    def from_dict(cls, payload: Mapping[str, Any], source: str = "model") -> KNNModel:
        """Rebuild from a payload: training samples inline (:meth:`to_dict`) or in the model
        file's sidecar (:meth:`save`; ``source`` is then the model file's path)."""
        arrays = read_sidecar(source, payload["sidecar"]) if isinstance(payload, Mapping) and "sidecar" in payload else None
        try:
            k = int(payload["n_neighbors"])
            angles, gains = {}, {}
            for i, e in enumerate(payload["links"]):
                key = (str(e["tx"]), str(e["rx"]))
                if arrays is None:
                    a = np.asarray(e["angles_rad"], np.float64)
                    g = np.asarray(e["gain_db"], np.float64)
                else:
                    if f"angles_{i}" not in arrays or f"gain_{i}" not in arrays:
                        raise ModelFileError(f"{source}: the sidecar holds no samples of link {key[0]}->{key[1]}")
                    a = np.asarray(arrays[f"angles_{i}"], np.float64)
                    g = np.asarray(arrays[f"gain_{i}"], np.float64)
                    if g.size != int(e["samples"]):
                        raise ModelFileError(f"{source}: link {key[0]}->{key[1]} has {g.size} samples in the sidecar, "
                                             f"the model file says {e['samples']}")
                if a.ndim != 2 or a.shape[1] != 4 or a.shape[0] != g.size or g.size < k:
                    raise ModelFileError(f"{source}: link {key[0]}->{key[1]} has inconsistent training arrays")
                if not (np.all(np.isfinite(a)) and np.all(np.isfinite(g))):
                    raise ModelFileError(f"{source}: link {key[0]}->{key[1]} has non-finite training values")
                angles[key], gains[key] = a, g
        except ModelFileError:
            raise
        except (KeyError, TypeError, ValueError) as exc:
            raise ModelFileError(f"{source}: malformed k-NN model ({type(exc).__name__}: {exc})") from None
        if not angles:
            raise ModelFileError(f"{source}: k-NN model holds no link")
        return cls(k, angles, gains, *training_and_provenance(payload, source))
