"""Predictions for a dataset of poses: joint gain, received power and how wrong they may be.

:func:`predict_dataset` adds to every row of a matched dataset (``rssi_dbm`` optional, so that
links never flown can be predicted) the predicted joint gain ``G_tx + G_rx`` [dB] and received
power (paper eq. 1) [dBm], and for pattern models two spreads: the standard error of the gain
for a new flight (the learned coefficients' and the flight's own level's, when the model
estimated the flights' spread), and the spread of one new packet's RSSI, which adds the
noise about the flight's level (or the training residual: fading, noise and misfit). :func:`frequency_mismatch` says when rows are at
a carrier other than the one the model learned at.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd
from numpy.typing import ArrayLike

from rplearn._argtypes import check_types
from rplearn.core.link import received_power_dbm
from rplearn.core.plausible import describe_band, frequency_bands, same_band
from rplearn.core.threads import blas_threads, prediction_flops
from rplearn.data.tables import link_samples
from rplearn.errors import InputError
from rplearn.models.base import Model

#: Relative difference of carrier frequencies above which a warning is given.
FREQUENCY_TOLERANCE = 0.05

#: Columns :func:`predict_dataset` adds (the two spreads only for models with a covariance,
#: the coverage only for models that stored it).
PREDICTION_COLUMNS: tuple[str, ...] = (
    "gain_pred_db", "rssi_pred_dbm", "gain_pred_std_db", "rssi_pred_std_db", "tx_coverage_deg", "rx_coverage_deg",
)
#: A direction further than this from every learning direction of its node is uncovered [deg].
UNCOVERED_DEG = 10.0


@check_types
@dataclass(frozen=True)
class FrequencyMismatch:
    """Rows at a carrier other than the model's.

    Attributes
    ----------
    n_rows : int
        Rows more than :data:`FREQUENCY_TOLERANCE` away from the model's frequency.
    median_hz : float
        Median frequency of those rows [Hz].
    learned_hz : float
        The frequency the model learned at [Hz].
    """

    n_rows: int
    median_hz: float
    learned_hz: float

    def describe(self, where: str, model_name: str) -> str:
        return (
            f"{where}: {self.n_rows:,} row(s) at {self.median_hz / 1e9:.3f} GHz, but {model_name} learned at "
            f"{self.learned_hz / 1e9:.3f} GHz; antenna patterns change with frequency"
        )


@check_types
def check_model_band(model: Model, frequency_hz: ArrayLike | Mapping[float, int], where: str, model_name: str | None = None) -> None:
    """Refuse rows whose carriers are of another band than the one ``model`` learned at.

    Each band of the rows (:func:`~rplearn.core.plausible.frequency_bands`: the rows' carriers,
    or carrier -> row count) is compared with the model's carrier; a model that does not state
    its carrier is not checked.
    """
    if model.frequency_hz is None:
        return
    learned = float(model.frequency_hz)
    for lo, hi, n in frequency_bands(frequency_hz if isinstance(frequency_hz, Mapping) else np.asarray(frequency_hz, np.float64)):
        far = lo if abs(lo - learned) > abs(hi - learned) else hi
        if not same_band(far, learned):
            raise InputError(f"{where}: {n:,} row(s) at {describe_band(lo, hi)}, but {model_name or f'the {model.label} model'} "
                             f"learned at {describe_band(learned, learned)}; antenna patterns change with frequency "
                             "(evaluate a model of this band, or the rows of its band)")


@check_types
def check_model_nodes(model: Model, nodes: Sequence[str], where: str, model_name: str | None = None) -> None:
    """Refuse rows naming a node the pattern model has no pattern of (``nodes``: the rows' node
    ids), naming ``where`` (the dataset) and the model; a model without per-node patterns (a
    baseline) is not checked."""
    known = getattr(model, "nodes", None)
    if known is None:
        return
    unknown = sorted({str(n) for n in nodes} - {str(n) for n in known})
    if unknown:
        raise InputError(f"{where}: node(s) {', '.join(unknown)} in columns tx/rx, but {model_name or f'the {model.label} model'} "
                         f"has patterns of {', '.join(map(str, known))} only")


@check_types
def frequency_mismatch(model: Model, frequency_hz: ArrayLike) -> FrequencyMismatch | None:
    """Rows whose carrier differs from the model's by more than 5 % (None: all agree, or the
    model does not state its frequency)."""
    learned = model.frequency_hz
    f = np.asarray(frequency_hz, np.float64).ravel()
    if learned is None or f.size == 0:
        return None
    off = np.abs(f / float(learned) - 1.0) > FREQUENCY_TOLERANCE
    if not np.any(off):
        return None
    return FrequencyMismatch(int(off.sum()), float(np.median(f[off])), float(learned))


@check_types
@dataclass
class DatasetPrediction:
    """A dataset with predictions added, and how well they match any measured RSSI.

    Attributes
    ----------
    table : DataFrame
        The input rows with :data:`PREDICTION_COLUMNS` added.
    n_measured : int
        Rows with a measured RSSI.
    rmse_db : float
        RMSE of the predicted joint gain against the measured one on those rows [dB]
        (NaN without any).
    mismatch : FrequencyMismatch or None
        Rows at another carrier than the model's.
    n_uncovered : int
        Rows where an end looks more than :data:`UNCOVERED_DEG` from every direction its node
        was learned from (0 when the model stores no coverage).
    notes : tuple of str
        What the predictions assume: the link directions the model never learned and the
        electronics offset taken for them (:func:`unlearned_directions`).
    """

    table: pd.DataFrame
    n_measured: int
    rmse_db: float
    mismatch: FrequencyMismatch | None
    n_uncovered: int = 0
    notes: tuple[str, ...] = ()

    def summary(self, output: str) -> str:
        line = f"wrote {len(self.table):,} predictions to {output}"
        if self.n_measured:
            line += f" (RMSE against the {self.n_measured:,} measured RSSI values: {self.rmse_db:.2f} dB)"
        return line

    @property
    def warnings(self) -> list[str]:
        """What a user should act on: predictions where the flight never looked."""
        if not self.n_uncovered:
            return []
        share = self.n_uncovered / max(len(self.table), 1)
        return [f"{self.n_uncovered:,} of {len(self.table):,} predictions ({share:.0%}) look at directions more than "
                f"{UNCOVERED_DEG:g} deg from any direction their antenna was learned from (columns tx_coverage_deg, "
                "rx_coverage_deg): there the pattern is an extrapolation (or the prior's); trust their spread, "
                "not their value, or fly those directions"]


@check_types
def predict_dataset(model: Model, dataset: pd.DataFrame, source: str = "dataset") -> DatasetPrediction:
    """Predict the joint gain, received power and their spreads for every row (paper eq. 1).

    Parameters
    ----------
    model : Model
        Any learned model.
    dataset : DataFrame
        Matched dataset (docs/conventions.md); ``rssi_dbm`` may be absent or NaN.
    source : str
        File name for messages.
    """
    samples = link_samples(dataset, source, require_rssi=False)
    check_model_nodes(model, samples.nodes, source)
    if samples.frequency_hz is not None:
        check_model_band(model, samples.frequency_hz, source)
    basis = getattr(model, "basis", None)
    flops = prediction_flops(len(samples), basis.n_coef if basis is not None else 1,
                             getattr(model, "covariance", None) is not None)
    with blas_threads(flops):  # the thread policy (rplearn.core.threads): size and free cores
        return _predict_dataset(model, dataset, samples)


def _predict_dataset(model: Model, dataset: pd.DataFrame, samples: Any) -> DatasetPrediction:
    """:func:`predict_dataset` of the dataset's checked samples."""
    gain = model.predict_gain(samples)
    table = dataset.drop(columns=[c for c in PREDICTION_COLUMNS if c in dataset.columns])  # no stale predictions
    table["gain_pred_db"] = gain
    table["rssi_pred_dbm"] = received_power_dbm(
        table["tx_power_dbm"].to_numpy(np.float64), gain, samples.distance_m, table["frequency_hz"].to_numpy(np.float64)
    )
    std = model.predict_gain_std(samples)
    residual_db = 0.0
    if std is not None:
        # one packet's noise about its flight's level (an automatic fit over flights), else the
        # training residual; unknown (None) in a hand-made file: the spread is then NaN
        training = model.training
        rmse = training.noise_std_db if training.noise_std_db is not None else training.rmse_db
        residual_db = float(rmse) if rmse is not None else float("nan")
        table["gain_pred_std_db"] = std
        table["rssi_pred_std_db"] = np.sqrt(std**2 + residual_db**2)
    n_uncovered = _add_coverage(model, samples, table)
    predicted = np.isfinite(gain)
    measured = np.isfinite(samples.joint_gain_db) & predicted
    rmse = float(np.sqrt(np.mean((gain[measured] - samples.joint_gain_db[measured]) ** 2))) if measured.any() else float("nan")
    mismatch = frequency_mismatch(model, table["frequency_hz"].to_numpy(np.float64))
    notes = unlearned_directions(model, samples)
    if "rssi_pred_std_db" in table.columns and not np.isfinite(residual_db):
        notes.append("rssi_pred_std_db is NaN in every row: the model file states no training residual "
                     "(training.rmse_db or noise_std_db), so one packet's spread is unknown; gain_pred_std_db holds")
    if not predicted.all():
        notes.append(f"{int((~predicted).sum()):,} of {len(gain):,} rows have no prediction (NaN): an antenna at or "
                     "below the two-ray ground level of the model; they are left out of the RMSE")
    return DatasetPrediction(table, int(measured.sum()), rmse, mismatch, n_uncovered, tuple(notes))


@check_types
def unlearned_directions(model: Model, samples: Any) -> list[str]:
    """Notes on the predicted link directions ``TX->RX`` a pattern model never learned from:
    they are predicted with an electronics offset of 0 dB, the mean level of the links it
    learned (a direction learned alone carries its own level in the patterns). Empty for
    models that do not list their learned directions (baselines, older files)."""
    from rplearn.models.terms import learned_directions

    learned = learned_directions(model.training)
    if learned is None:
        return []
    names = [str(n) for n in samples.nodes]
    code = np.asarray(samples.tx_index, np.int64) * len(names) + np.asarray(samples.rx_index)
    asked = [(names[c // len(names)], names[c % len(names)]) for c in np.unique(code)]
    missing = [f"{a}->{b}" for a, b in asked if (a, b) not in learned]
    if not missing:
        return []
    known = ", ".join(f"{a}->{b}" for a, b in sorted(learned)) or "no direction"
    return [f"link direction(s) {', '.join(missing)} were never learned: predicted with an electronics offset of 0 dB "
            f"(the model learned {known}); radios that are not reciprocal may differ by a few dB"]


def end_coverage_deg(model: Model, samples: Any) -> tuple[np.ndarray, np.ndarray] | None:
    """Coverage [deg] of each sample's tx and rx end (see :meth:`PatternSet.coverage_deg`), or
    None when the model stores no coverage."""
    coverage = getattr(model, "coverage_deg", None)
    if coverage is None or not model.training.coverage_deg:
        return None
    d = samples.directions
    cols = []
    for idx, az, el in ((samples.tx_index, d.az_tx, d.el_tx), (samples.rx_index, d.az_rx, d.el_rx)):
        col = np.full(len(samples), np.nan)
        for k, node in enumerate(samples.nodes):
            sel = np.asarray(idx) == k
            if sel.any():
                got = coverage(node, np.asarray(az)[sel], np.asarray(el)[sel])
                if got is not None:
                    col[sel] = got
        cols.append(col)
    return cols[0], cols[1]


def uncovered_rows(model: Model, samples: Any, within_deg: float = UNCOVERED_DEG) -> int | None:
    """Samples with an end more than ``within_deg`` from every learning direction of its node
    (None when the model stores no coverage)."""
    ends = end_coverage_deg(model, samples)
    if ends is None:
        return None
    return int(np.sum(np.fmax(ends[0], ends[1]) > within_deg))


def _add_coverage(model: Model, samples: Any, table: pd.DataFrame) -> int:
    """Add ``tx_coverage_deg``, ``rx_coverage_deg`` when the model stores coverage; return the
    rows with an end beyond :data:`UNCOVERED_DEG`."""
    ends = end_coverage_deg(model, samples)
    if ends is None:
        return 0
    out = {"tx": ends[0], "rx": ends[1]}
    table["tx_coverage_deg"], table["rx_coverage_deg"] = ends
    worst = np.fmax(out["tx"], out["rx"])
    return int(np.sum(worst > UNCOVERED_DEG))


@check_types
def distinct_labels(labels: Sequence[str], names: Sequence[str]) -> list[str]:
    """Labels made distinct by adding the name (e.g. file name) where two share a label."""
    counts = pd.Series(list(labels)).value_counts()
    return [f"{label} ({name})" if counts[label] > 1 else label for label, name in zip(labels, names)]
