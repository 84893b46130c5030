"""Baselines of paper Sec. V-C1, on link samples: the mean (M) and k nearest neighbours (NN-k).

Neither decouples the joint gain into per-node patterns. Both are kept per directed link
``tx -> rx`` (with a single link, as in the paper, this is the paper's global model): the
joint gain of one link says nothing about another.

- :class:`MeanModel`: the mean training joint gain.
- :class:`KNNModel`: the average joint gain of the ``k`` (default 400) nearest training samples
  in the 4-D joint-angle space ``(az_tx, el_tx, az_rx, el_rx)`` [rad], Euclidean distance,
  uniform weights (paper: k = 400 was best; larger k tends to the mean).
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from typing import Any, Mapping

import numpy as np
from rplearn.data.tables import LinkSamples
from rplearn.errors import IdentifiabilityError, InputError, ModelFileError
from rplearn.io.modelfile import write_model_file


def _links(samples: LinkSamples) -> dict[tuple[str, str], np.ndarray]:
    code = samples.tx_index.astype(np.int64) * len(samples.nodes) + samples.rx_index
    out = {}
    for c in np.unique(code):
        t, r = divmod(int(c), len(samples.nodes))
        out[(samples.nodes[t], samples.nodes[r])] = np.flatnonzero(code == c)
    return out


def _angles(samples: LinkSamples, idx: np.ndarray | slice = slice(None)) -> np.ndarray:
    d = samples.directions
    return np.column_stack([d.az_tx[idx], d.el_tx[idx], d.az_rx[idx], d.el_rx[idx]])


def _missing_link(key: tuple[str, str], known) -> InputError:
    names = ", ".join(f"{a}->{b}" for a, b in known)
    return InputError(f"link {key[0]}->{key[1]} was not in the training data (the model knows {names})")


@dataclass
class MeanModel:
    """The paper's M: mean training joint gain per directed link [dB]."""

    means_db: dict[tuple[str, str], float]
    training: dict[str, Any] = field(default_factory=dict)
    provenance: dict[str, Any] = field(default_factory=dict)
    kind: str = "mean"
    label: str = "M"

    @classmethod
    def fit(cls, samples: LinkSamples) -> "MeanModel":
        if len(samples) == 0:
            raise IdentifiabilityError("the mean baseline needs at least one sample")
        means = {k: float(np.mean(samples.joint_gain_db[i])) for k, i in _links(samples).items()}
        return cls(means, training={"n_samples": len(samples)})

    @property
    def n_params(self) -> int:
        return len(self.means_db)

    def predict_samples(self, samples: LinkSamples) -> np.ndarray:
        out = np.empty(len(samples))
        for key, idx in _links(samples).items():
            if key not in self.means_db:
                raise _missing_link(key, self.means_db)
            out[idx] = self.means_db[key]
        return out

    def to_dict(self) -> dict[str, Any]:
        return {
            "label": self.label,
            "links": [{"tx": t, "rx": r, "mean_db": v} for (t, r), v in self.means_db.items()],
            "training": self.training,
            "provenance": self.provenance,
        }

    def save(self, path: str | os.PathLike[str]) -> None:
        write_model_file(path, "mean", self.to_dict())

    @classmethod
    def from_dict(cls, payload: Mapping[str, Any], source: str = "model") -> "MeanModel":
        try:
            means = {(str(e["tx"]), str(e["rx"])): float(e["mean_db"]) for e in payload["links"]}
        except (KeyError, TypeError, ValueError) as exc:
            raise ModelFileError(f"{source}: malformed mean model ({type(exc).__name__}: {exc})") from None
        if not means or not all(np.isfinite(list(means.values()))):
            raise ModelFileError(f"{source}: mean model needs finite means for at least one link")
        return cls(means, dict(payload.get("training", {})), dict(payload.get("provenance", {})))


@dataclass
class KNNModel:
    """The paper's NN-k: k nearest neighbours in the 4-D joint-angle space, per directed link."""

    n_neighbors: int
    train_angles_rad: dict[tuple[str, str], np.ndarray]
    train_gain_db: dict[tuple[str, str], np.ndarray]
    training: dict[str, Any] = field(default_factory=dict)
    provenance: dict[str, Any] = field(default_factory=dict)
    kind: str = "knn"

    def __post_init__(self) -> None:
        self._regressors: dict[tuple[str, str], Any] = {}

    @property
    def label(self) -> str:
        return f"NN-{self.n_neighbors}"

    @classmethod
    def fit(cls, samples: LinkSamples, n_neighbors: int = 400) -> "KNNModel":
        if int(n_neighbors) < 1:
            raise InputError(f"n_neighbors must be a positive integer, got {n_neighbors!r}")
        angles, gains = {}, {}
        for key, idx in _links(samples).items():
            if idx.size < n_neighbors:
                raise IdentifiabilityError(
                    f"link {key[0]}->{key[1]} has {idx.size} samples, fewer than k = {n_neighbors} neighbours"
                )
            angles[key] = _angles(samples, idx)
            gains[key] = samples.joint_gain_db[idx].copy()
        model = cls(int(n_neighbors), angles, gains, training={"n_samples": len(samples)})
        for key in angles:
            model._regressor(key)
        return model

    def _regressor(self, key: tuple[str, str]):
        from sklearn.neighbors import KNeighborsRegressor  # imported on use: slow to import

        if key not in self._regressors:
            reg = KNeighborsRegressor(n_neighbors=self.n_neighbors, algorithm="kd_tree")
            self._regressors[key] = reg.fit(self.train_angles_rad[key], self.train_gain_db[key])
        return self._regressors[key]

    @property
    def n_params(self) -> int:
        """Every training sample is a parameter (paper Table I)."""
        return int(sum(v.size for v in self.train_gain_db.values()))

    def predict_samples(self, samples: LinkSamples) -> np.ndarray:
        out = np.empty(len(samples))
        for key, idx in _links(samples).items():
            if key not in self.train_gain_db:
                raise _missing_link(key, self.train_gain_db)
            out[idx] = self._regressor(key).predict(_angles(samples, idx))
        return out

    def to_dict(self) -> dict[str, Any]:
        return {
            "label": self.label,
            "n_neighbors": self.n_neighbors,
            "links": [
                {"tx": t, "rx": r, "angles_rad": self.train_angles_rad[(t, r)].tolist(), "gain_db": self.train_gain_db[(t, r)].tolist()}
                for (t, r) in self.train_gain_db
            ],
            "training": self.training,
            "provenance": self.provenance,
        }

    def save(self, path: str | os.PathLike[str]) -> None:
        write_model_file(path, "knn", self.to_dict())

    @classmethod
    def from_dict(cls, payload: Mapping[str, Any], source: str = "model") -> "KNNModel":
        try:
            k = int(payload["n_neighbors"])
            angles, gains = {}, {}
            for e in payload["links"]:
                key = (str(e["tx"]), str(e["rx"]))
                a = np.asarray(e["angles_rad"], np.float64)
                g = np.asarray(e["gain_db"], np.float64)
                if a.ndim != 2 or a.shape[1] != 4 or a.shape[0] != g.size or g.size < k:
                    raise ModelFileError(f"{source}: link {key[0]}->{key[1]} has inconsistent training arrays")
                angles[key], gains[key] = a, g
        except ModelFileError:
            raise
        except (KeyError, TypeError, ValueError) as exc:
            raise ModelFileError(f"{source}: malformed k-NN model ({type(exc).__name__}: {exc})") from None
        if not angles:
            raise ModelFileError(f"{source}: k-NN model holds no link")
        return cls(k, angles, gains, dict(payload.get("training", {})), dict(payload.get("provenance", {})))
