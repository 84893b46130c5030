"""Learned radiation patterns of a group of nodes: evaluate, predict, save and load.

A :class:`PatternSet` holds one pattern per node in a common basis. It evaluates
``G_n(az, el)`` [dBi] at any body-frame directions, predicts the joint gain of any link and the
received power for any pair of poses (paper eq. 1), and round-trips through the JSON model file
of docs/conventions.md (versioned schema, SHA-256 checksum of the payload; no pickle).
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from rplearn._argtypes import check_types
from rplearn._version import __version__
from rplearn.core.bases import Basis, basis_from_dict
from rplearn.core.basis_base import chunk_directions
from rplearn.core.environment import PathLoss
from rplearn.core.geometry import Directions, distance_m, link_directions
from rplearn.core.link import received_power_dbm
from rplearn.core.plausible import check_covariance
from rplearn.core.threads import blas_threads, prediction_flops
from rplearn.errors import InputError, ModelFileError
from rplearn.io.modelfile import jsonable as _jsonable
from rplearn.io.modelfile import read_model_file, read_sidecar, write_model_with_sidecar
from rplearn.models.base import frequency_from_training
from rplearn.models.terms import split_offset_name
from rplearn.models.training import TrainingSummary, training_and_provenance

FloatArray = NDArray[np.float64]

if TYPE_CHECKING:
    from rplearn.data.tables import LinkSamples


#: A covariance of more values than this is saved in the model file's binary sidecar, not as
#: JSON text (the paper's two drones at SH-10, 242 columns, are 58,564 values: inline).
INLINE_COVARIANCE_VALUES = 250_000

#: The largest magnitude [dB] of a coefficient a model file may hold (patterns and shared
#: terms): plausible gains span -100..60 dBi (:data:`rplearn.core.plausible.PLAUSIBLE`), a
#: relative RSSI scale adds a level of a few hundred dB at most, and squares of values near
#: 1e154 overflow: a file beyond it was edited or written wrong, and is refused on reading.
COEFFICIENT_LIMIT_DB = 1e6


@check_types
@dataclass
class PatternSet:
    """One radiation pattern per node, each ``G_n = basis(az, el) . coef[n]`` [dBi].

    Attributes
    ----------
    basis : Basis
    nodes : tuple of str
    coef : ndarray, shape (n_nodes, n_coef)
    covariance : ndarray or None
        Covariance of all coefficients (``n_nodes * n_coef`` square), for standard errors.
    gauge : list of dict
        How unidentifiable constants were fixed (see :mod:`rplearn.core.lsq.solver`).
    training : TrainingSummary
        Training summary (samples, RMSE, rank, condition number, ridge, ...); a mapping of
        its entries (a model file's ``training``) is read by :meth:`TrainingSummary.from_dict`.
    provenance : dict
        Library version, command and parameters that made the model.
    path_loss : PathLoss
        The environment term the patterns were learned with (free space by default).
    shared_names : tuple of str
        Coefficients learned with the patterns besides them: ``"exponent"`` (the log-distance
        exponent less 2) and ``"offset:A->B"`` (half the electronics difference of a link
        logged both ways: ``A->B`` gets ``+value``, ``B->A`` ``-value``).
    shared_coef : ndarray
        Their values; the covariance, when given, covers the patterns and then these.
    """

    basis: Basis
    nodes: tuple[str, ...]
    coef: FloatArray
    covariance: FloatArray | None = None
    gauge: list[dict[str, Any]] = field(default_factory=list)
    training: TrainingSummary = field(default_factory=TrainingSummary)
    provenance: dict[str, Any] = field(default_factory=dict)
    path_loss: PathLoss = field(default_factory=PathLoss)
    shared_names: tuple[str, ...] = ()
    shared_coef: FloatArray = field(default_factory=lambda: np.zeros(0))

    def __post_init__(self) -> None:
        self.training = TrainingSummary.from_dict(self.training)
        self.nodes = tuple(str(n) for n in self.nodes)
        self.coef = np.asarray(self.coef, np.float64)
        if self.coef.shape != (len(self.nodes), self.basis.n_coef):
            raise InputError(
                f"coef has shape {self.coef.shape}, expected ({len(self.nodes)}, {self.basis.n_coef})"
            )
        self.shared_names = tuple(str(n) for n in self.shared_names)
        self.shared_coef = np.asarray(self.shared_coef, np.float64).ravel()
        if self.shared_coef.size != len(self.shared_names) or not np.all(np.isfinite(self.shared_coef)):
            raise InputError(f"shared_coef: expected {len(self.shared_names)} finite values for "
                             f"{', '.join(self.shared_names) or 'no shared columns'}", param="shared_coef")
        links: set[frozenset[str]] = set()
        self._offset_ends: dict[int, tuple[str, str]] = {}
        if len(set(self.shared_names)) != len(self.shared_names):
            raise InputError("shared_names: a shared column is named twice", param="shared_names")
        for j, name in enumerate(self.shared_names):
            if name == "exponent":
                continue
            a, b = split_offset_name(name, self.nodes)
            if a == b or frozenset((a, b)) in links:
                raise InputError(f"shared column {name!r}: a link's offset is one column, between two nodes "
                                 "(a -> b is +value, b -> a is -value)", param="shared_names")
            links.add(frozenset((a, b)))
            self._offset_ends[j] = (a, b)
        if ("exponent" in self.shared_names) != self.path_loss.learns_exponent:
            raise InputError(f"path loss {self.path_loss.kind}: an 'exponent' coefficient is expected exactly with "
                             "the log-distance term", param="shared_names")

    @property
    def n_pattern_columns(self) -> int:
        """Coefficients of the patterns (the covariance's shared columns follow them)."""
        return len(self.nodes) * self.basis.n_coef

    def shared_std(self) -> FloatArray:
        """Standard errors of :attr:`shared_coef` (NaN without a covariance)."""
        m = len(self.shared_names)
        if self.covariance is None or self.covariance.shape[0] != self.n_pattern_columns + m:
            return np.full(m, np.nan)
        d = np.diag(self.covariance)[self.n_pattern_columns:]
        return np.sqrt(np.maximum(d, 0.0))

    @property
    def path_loss_exponent(self) -> tuple[float, float] | None:
        """``(exponent, standard error)`` of a log-distance model; None for another term."""
        if "exponent" not in self.shared_names:
            return None
        j = self.shared_names.index("exponent")
        return 2.0 + float(self.shared_coef[j]), float(self.shared_std()[j])

    def link_offsets_db(self) -> dict[tuple[str, str], tuple[float, float]]:
        """Electronics offset of every learned direction ``(tx, rx)``: ``(offset [dB], standard error)``.

        Gauge: the two directions of a link sum to zero (their common part is in the patterns'
        joint level); a direction not listed is predicted with offset 0.
        """
        out = {}
        se = self.shared_std()
        for j, (a, b) in self._offset_ends.items():
            out[(a, b)] = (float(self.shared_coef[j]), float(se[j]))
            out[(b, a)] = (-float(self.shared_coef[j]), float(se[j]))
        return out

    def shared_regressors(self, samples: LinkSamples) -> FloatArray:
        """Values of the shared columns for every sample, shape ``(len(shared_names), n)``."""
        from rplearn.core.environment import log_distance_column

        n = len(samples)
        out = np.zeros((len(self.shared_names), n))
        if not self.shared_names:
            return out
        names = np.asarray(samples.nodes, dtype=object)
        tx = names[samples.tx_index] if n else np.zeros(0, object)
        rx = names[samples.rx_index] if n else np.zeros(0, object)
        for j, name in enumerate(self.shared_names):
            if name == "exponent":
                d = np.asarray(samples.distance_m, np.float64)
                positive = d > 0
                out[j] = np.nan  # no distance, no prediction
                out[j, positive] = log_distance_column(d[positive])
            else:
                a, b = self._offset_ends[j]
                out[j] = (tx == a) & (rx == b)
                out[j] -= (tx == b) & (rx == a)
        return out

    def environment_db(self, samples: LinkSamples) -> FloatArray:
        """What the environment term and the link offsets add to the patterns' joint gain [dB]
        for every sample (zero for a free-space model without offsets)."""
        out = np.zeros(len(samples))
        known = self.path_loss.known_db(samples.distance_m, samples.tx_z_m, samples.rx_z_m, samples.frequency_hz,
                                        strict=False) if self.path_loss.kind == "two-ray" else None
        if known is not None:
            out += known
        if self.shared_names:
            out += self.shared_coef @ self.shared_regressors(samples)
        return out

    # -- evaluation ----------------------------------------------------------------------
    def node_index(self, node: str) -> int:
        """Index of a node id; raises :class:`InputError` naming the known nodes."""
        try:
            return self.nodes.index(str(node))
        except ValueError:
            raise InputError(f"unknown node {str(node)!r}; the model knows {', '.join(self.nodes)}") from None

    def end_indices(self, samples: LinkSamples) -> tuple[NDArray[np.intp], NDArray[np.intp]]:
        """Each sample's transmitter and receiver as indices into :attr:`nodes` (a node the
        model does not know is refused, as by :meth:`node_index`)."""
        idx = np.array([self.node_index(n) for n in samples.nodes], dtype=np.intp)
        return idx[samples.tx_index], idx[samples.rx_index]

    def evaluate(self, node: str, az_rad: ArrayLike, el_rad: ArrayLike) -> FloatArray:
        """Gain of ``node`` toward body-frame directions [dBi]."""
        az = np.asarray(az_rad, np.float64)
        el = np.asarray(el_rad, np.float64)
        k = self.node_index(node)
        outside = ~(np.abs(el) <= np.pi / 2 + 1e-9)
        if np.any(outside):
            raise InputError(
                f"el_rad: elevation {float(el[outside].flat[0]):g} is outside [-pi/2, pi/2] rad (degrees by mistake?)",
                param="el_rad",
            )
        shape = np.broadcast(az, el).shape
        az, el = np.broadcast_arrays(az, el)
        with blas_threads(prediction_flops(az.size, self.basis.n_coef) / 2):  # one end (rplearn.core.threads)
            return self.basis.evaluate(self.coef[k], az, el).reshape(shape)

    def standard_error(self, node: str, az_rad: ArrayLike, el_rad: ArrayLike) -> FloatArray:
        """Standard error of :meth:`evaluate` from the fit's coefficient covariance [dB].

        Within the gauge: for a two-node fit the shared constant is fixed, not estimated.
        """
        if self.covariance is None:
            raise InputError("this model carries no covariance")
        k = self.node_index(node)
        p = self.basis.n_coef
        cov = self.covariance[k * p : (k + 1) * p, k * p : (k + 1) * p]
        with blas_threads(prediction_flops(np.size(az_rad), p, spreads=True) / 2):  # one end (rplearn.core.threads)
            return np.sqrt(np.maximum(self.basis.quadratic_form(cov, az_rad, el_rad), 0.0))

    def coverage_deg(self, node: str, az_rad: ArrayLike, el_rad: ArrayLike) -> FloatArray | None:
        """Angle [deg] from each direction to the nearest direction ``node`` was learned from
        (from the coverage grid stored at fitting, ``training.coverage_deg``; an upper bound
        within about 1 degree); None for a model without one (older files, references)."""
        grids = self.training.coverage_deg or {}
        if str(node) not in grids:
            return None
        from rplearn.core.coverage import coverage_at

        return coverage_at(grids[str(node)], az_rad, el_rad)

    @property
    def new_flight_level_std_db(self) -> float:
        """Spread [dB] of a new flight's own level about the level the model learned (the
        between-flight spread of an automatic fit over several flights, plus the uncertainty of
        the learned flights' mean level; 0 for a model that did not estimate it)."""
        value = self.training.new_flight_level_std_db
        return float(value) if isinstance(value, (int, float)) and np.isfinite(value) else 0.0

    def predict_gain_std(self, samples: LinkSamples, new_flight: bool = True) -> FloatArray | None:
        """Standard error of :meth:`predict_gain` for a new flight [dB]: from the coefficient
        covariance and, with ``new_flight``, the spread of a new flight's level
        (:attr:`new_flight_level_std_db`).

        The joint gain ``G_tx + G_rx`` does not depend on the constant a two-node fit cannot
        identify, so this error is meaningful for every fit. It does not cover the measurement
        noise of a new packet (add ``training["noise_std_db"]``, or the training residual, for
        that; :func:`rplearn.models.predict.predict_dataset` does).

        Returns
        -------
        ndarray or None
            One standard error per sample [dB]; None when the model carries no covariance.
        """
        if self.covariance is None:
            return None
        with blas_threads(prediction_flops(len(samples), self.basis.n_coef, spreads=True)):  # rplearn.core.threads
            return self._gain_std(samples, new_flight)

    def _gain_std(self, samples: LinkSamples, new_flight: bool) -> FloatArray:
        """:meth:`predict_gain_std` of a model with a covariance."""
        assert self.covariance is not None
        level_var = self.new_flight_level_std_db ** 2 if new_flight else 0.0
        p = self.basis.n_coef
        m = len(self.shared_names)
        if m and self.covariance.shape[0] != self.n_pattern_columns + m:
            m = 0  # an older covariance of the patterns alone
        shared = self.shared_regressors(samples)[:m] if m else np.zeros((0, len(samples)))
        shared_idx = self.n_pattern_columns + np.arange(m)
        tx, rx = self.end_indices(samples)
        d = samples.directions
        az_tx, el_tx, az_rx, el_rx = (np.asarray(a, np.float64) for a in d)
        var = np.empty(len(samples))
        code = tx.astype(np.int64) * len(self.nodes) + rx
        rows = np.arange(p) if self.basis.row_order is None else np.asarray(self.basis.row_order)
        step = chunk_directions(8 * p)  # a step's features of both ends and their product: a few MB (issue 30)
        for c in np.unique(code):
            t, r = divmod(int(c), len(self.nodes))
            sel = np.flatnonzero(code == c)
            # joint covariance of the two ends' coefficients, in the basis's fastest row order
            both = np.concatenate([t * p + rows, r * p + rows, shared_idx])
            joint = self.covariance[np.ix_(both, both)]
            feats = np.empty((2 * p + m, min(step, sel.size)))
            for s0 in range(0, sel.size, step):
                part = sel[s0 : s0 + step]
                f = feats[:, : part.size]
                self.basis.design_rows_into(az_tx[part], el_tx[part], f[:p])
                self.basis.design_rows_into(az_rx[part], el_rx[part], f[p : 2 * p])
                f[2 * p :] = shared[:, part]
                var[part] = np.einsum("in,in->n", joint @ f, f)  # f^T C f of every sample
        return np.sqrt(np.maximum(var, 0.0) + level_var)

    def predict_joint_gain_db(
        self,
        tx_node: str | Sequence[str],
        rx_node: str | Sequence[str],
        az_tx: ArrayLike,
        el_tx: ArrayLike,
        az_rx: ArrayLike,
        el_rx: ArrayLike,
    ) -> FloatArray:
        """Joint gain ``G_tx(az_tx, el_tx) + G_rx(az_rx, el_rx)`` [dB] (paper eq. 1)."""
        az_tx = np.atleast_1d(np.asarray(az_tx, np.float64))
        n = az_tx.size
        if isinstance(tx_node, str) and isinstance(rx_node, str):
            return self.evaluate(tx_node, az_tx, el_tx) + self.evaluate(rx_node, az_rx, el_rx)
        tx_idx, rx_idx = (np.full(n, self.node_index(v)) if isinstance(v, str) else np.array(
            [self.node_index(u) for u in np.broadcast_to(np.asarray(v, dtype=object), (n,))]) for v in (tx_node, rx_node))
        angles = [np.asarray(a, np.float64).ravel() for a in (az_tx, el_tx, az_rx, el_rx)]
        for name, a in zip(("az_tx", "el_tx", "az_rx", "el_rx"), angles):
            if a.size not in (1, n):
                raise InputError(f"{name} has {a.size} values, az_tx has {n}")
        az_tx, el_tx, az_rx, el_rx = (np.broadcast_to(a, (n,)) for a in angles)
        return self._sum_node_gains(tx_idx, az_tx, el_tx) + self._sum_node_gains(rx_idx, az_rx, el_rx)

    def predict_for_poses(
        self,
        tx_node: str,
        rx_node: str,
        tx_position_xyz: ArrayLike,
        tx_quat_wxyz: ArrayLike,
        rx_position_xyz: ArrayLike,
        rx_quat_wxyz: ArrayLike,
        tx_power_dbm: ArrayLike | None = None,
        frequency_hz: ArrayLike | None = None,
    ) -> dict[str, FloatArray]:
        """Joint gain [dB] and, given power and frequency, received power [dBm] for poses.

        Positions ENU [m], attitudes FLU -> ENU quaternions ``(qw, qx, qy, qz)``.
        """
        d = link_directions(tx_position_xyz, tx_quat_wxyz, rx_position_xyz, rx_quat_wxyz)
        gain = self.predict_joint_gain_db(tx_node, rx_node, *d)
        out = {"gain_db": gain}
        dist = distance_m(tx_position_xyz, rx_position_xyz)
        if self.path_loss.kind != "free" or self.shared_names:
            out["environment_db"] = self.link_environment_db(tx_node, rx_node, tx_position_xyz, rx_position_xyz,
                                                             frequency_hz)
            gain = gain + out["environment_db"]
            out["gain_db"] = gain
        if tx_power_dbm is not None and frequency_hz is not None:
            out["rssi_dbm"] = received_power_dbm(tx_power_dbm, gain, dist, frequency_hz)
        return out

    def _link_samples_between(
        self, tx_node: str, rx_node: str, tx_position_xyz: ArrayLike, rx_position_xyz: ArrayLike,
        frequency_hz: ArrayLike | None = None,
    ) -> LinkSamples:
        """Samples of the link ``tx_node -> rx_node`` between positions (ENU [m]), with no
        attitude: what the environment term and the offsets need (distance, heights, nodes)."""
        from rplearn.data.tables import LinkSamples

        tx_xyz = np.atleast_2d(np.asarray(tx_position_xyz, np.float64))
        rx_xyz = np.atleast_2d(np.asarray(rx_position_xyz, np.float64))
        tx_xyz, rx_xyz = np.broadcast_arrays(tx_xyz, rx_xyz)
        n = tx_xyz.shape[0]
        nodes = (str(tx_node), str(rx_node))
        for node in nodes:
            self.node_index(node)
        freq = None if frequency_hz is None else np.broadcast_to(np.asarray(frequency_hz, np.float64), (n,))
        zero = np.zeros(n)
        return LinkSamples(Directions(zero, zero, zero, zero), np.zeros(n, np.intp), np.ones(n, np.intp), nodes,
                           np.full(n, np.nan), distance_m(tx_xyz, rx_xyz), freq, tx_z_m=tx_xyz[:, 2], rx_z_m=rx_xyz[:, 2])

    def link_environment_db(
        self,
        tx_node: str,
        rx_node: str,
        tx_position_xyz: ArrayLike,
        rx_position_xyz: ArrayLike,
        frequency_hz: ArrayLike | None = None,
    ) -> FloatArray:
        """What the environment term and the link's offset add to the joint gain [dB] between
        positions (ENU [m]); it depends on no attitude. Zero for a free-space model without
        offsets; NaN where a two-ray antenna is at or below the ground."""
        if self.path_loss.kind == "two-ray" and frequency_hz is None:
            frequency_hz = self.frequency_hz
        samples = self._link_samples_between(tx_node, rx_node, tx_position_xyz, rx_position_xyz, frequency_hz)
        return self.environment_db(samples)

    def link_environment_std_db(
        self, tx_node: str, rx_node: str, tx_position_xyz: ArrayLike, rx_position_xyz: ArrayLike
    ) -> FloatArray:
        """Standard error [dB] of :meth:`link_environment_db` from the learned exponent and offsets
        (0 when nothing is learned beside the patterns, or without a covariance)."""
        samples = self._link_samples_between(tx_node, rx_node, tx_position_xyz, rx_position_xyz)
        m, pc = len(self.shared_names), self.n_pattern_columns
        if not m or self.covariance is None or self.covariance.shape[0] != pc + m:
            return np.zeros(len(samples))
        s = self.shared_regressors(samples)
        var = np.einsum("in,ij,jn->n", s, self.covariance[pc:, pc:], s)
        return np.sqrt(np.maximum(var, 0.0))

    # -- files ---------------------------------------------------------------------------
    def to_dict(self, inline_covariance: bool = True) -> dict[str, Any]:
        """JSON-ready payload of the model file (without the checksum envelope); the covariance
        left out unless ``inline_covariance`` (:meth:`save` puts a large one in a sidecar)."""
        payload: dict[str, Any] = {
            "basis": self.basis.to_dict(),
            "label": self.basis.label,
            "nodes": list(self.nodes),
            "coefficients": {n: self.coef[i].tolist() for i, n in enumerate(self.nodes)},
            "gauge": self.gauge,
            "training": _jsonable(self.training.to_dict()),
            "provenance": {"rplearn_version": __version__, **_jsonable(self.provenance)},
        }
        if self.covariance is not None and inline_covariance:
            payload["covariance"] = self.covariance.tolist()
        if self.path_loss.kind != "free":
            payload["path_loss"] = self.path_loss.to_dict()
        if self.shared_names:
            payload["shared"] = {n: float(v) for n, v in zip(self.shared_names, self.shared_coef)}
        return payload

    def save(self, path: str | os.PathLike[str]) -> None:
        """Write the JSON model file (schema ``rplearn.model`` v1, SHA-256 checksummed); a
        covariance of more than :data:`INLINE_COVARIANCE_VALUES` values (a swarm's) goes into a
        binary sidecar beside it (``model.json.<sha>.npz``, checksummed in the model file: see
        :func:`rplearn.io.modelfile.write_model_with_sidecar`). As JSON text the covariance of
        30 drones at SH-10 was 239 MiB, 20 s to write and 7.6 s to read."""
        inline = self.covariance is None or self.covariance.size <= INLINE_COVARIANCE_VALUES
        write_model_with_sidecar(path, "patterns", self.to_dict(inline_covariance=inline),
                                 None if inline or self.covariance is None else {"covariance": self.covariance})

    @classmethod
    def from_dict(cls, payload: Mapping[str, Any], source: str = "model") -> PatternSet:
        """Rebuild from :meth:`to_dict` output, checking every field."""
        try:
            basis = basis_from_dict(payload["basis"])
            nodes = [str(n) for n in payload["nodes"]]
            coefs = payload["coefficients"]
            if set(coefs) != set(nodes):
                raise ModelFileError(f"{source}: coefficients name nodes {sorted(coefs)}, expected {nodes}")
            rows = [np.asarray(coefs[n], dtype=np.float64) for n in nodes]
            for n, row in zip(nodes, rows):
                if row.shape != (basis.n_coef,):
                    raise ModelFileError(
                        f"{source}: coefficients must be {len(nodes)} finite vectors of {basis.n_coef} values "
                        f"(node {n} has shape {row.shape})"
                    )
            coef = np.array(rows)
            cov = payload.get("covariance")
            cov_arr = None if cov is None else np.asarray(cov, dtype=np.float64)
            if "sidecar" in payload:  # a large covariance, written beside the model file (save)
                arrays = read_sidecar(source, payload["sidecar"])
                if "covariance" not in arrays or cov is not None:
                    raise ModelFileError(f"{source}: the sidecar must hold the covariance, and the model file must not")
                cov_arr = np.asarray(arrays["covariance"], dtype=np.float64)
            path_loss = PathLoss.from_dict(payload.get("path_loss"))
            shared = payload.get("shared") or {}
            if not isinstance(shared, Mapping):
                raise ModelFileError(f"{source}: 'shared' must map names to numbers")
            shared_names = tuple(str(k) for k in shared)
            shared_coef = np.array([float(v) for v in shared.values()], dtype=np.float64)
            training, provenance = training_and_provenance(payload, source)
            gauge = payload.get("gauge", [])
            if not isinstance(gauge, list):
                raise ModelFileError(f"{source}: field 'gauge' must be a list, got {type(gauge).__name__}")
        except ModelFileError as exc:  # named after the file once (the basis's own check does not know it)
            raise exc if str(exc).startswith(f"{source}:") else ModelFileError(f"{source}: {exc}") from None
        except (KeyError, TypeError, ValueError, InputError) as exc:
            raise ModelFileError(f"{source}: malformed model ({type(exc).__name__}: {exc})") from None
        if coef.shape != (len(nodes), basis.n_coef) or not np.all(np.isfinite(coef)):
            raise ModelFileError(
                f"{source}: coefficients must be {len(nodes)} finite vectors of {basis.n_coef} values"
            )
        if np.max(np.abs(coef), initial=0.0) > COEFFICIENT_LIMIT_DB or not np.all(np.abs(shared_coef) <= COEFFICIENT_LIMIT_DB):
            raise ModelFileError(f"{source}: a coefficient of magnitude {max(np.max(np.abs(coef)), *np.abs(shared_coef)):.3g} dB: "
                                 f"no gain or level in dB comes near {COEFFICIENT_LIMIT_DB:g} (its predictions would overflow)")
        p = len(nodes) * basis.n_coef + len(shared_names)
        if cov_arr is not None and cov_arr.shape != (p, p):
            raise ModelFileError(f"{source}: covariance must be {p} x {p}")
        if cov_arr is not None:
            try:
                check_covariance(cov_arr, source)
            except InputError as exc:
                raise ModelFileError(str(exc)) from None
        try:
            return cls(
                basis=basis,
                nodes=tuple(nodes),
                coef=coef,
                covariance=cov_arr,
                gauge=list(gauge),
                training=training,
                provenance=provenance,
                path_loss=path_loss,
                shared_names=shared_names,
                shared_coef=shared_coef,
            )
        except InputError as exc:
            raise ModelFileError(f"{source}: {exc}") from None

    @classmethod
    def load(cls, path: str | os.PathLike[str]) -> PatternSet:
        """Read a JSON model file; refuse a missing, malformed, truncated or tampered one.

        Raises
        ------
        ModelFileError
            One line naming the file and what is wrong.
        """
        model_type, payload = read_model_file(path)
        if model_type != "patterns":
            raise ModelFileError(f"{os.fspath(path)}: holds a {model_type} baseline, not radiation patterns")
        return cls.from_dict(payload, source=os.fspath(path))

    # -- the Model protocol (rplearn.models.base) -------------------------------------------
    @property
    def kind(self) -> str:
        """``"patterns"``: one pattern per node (see :class:`rplearn.models.base.Model`)."""
        return "patterns"

    @property
    def label(self) -> str:
        """The paper's label of the basis, e.g. ``SH-10``."""
        return self.basis.label

    @property
    def n_params(self) -> int:
        """Coefficients of all antennas (the paper's |phi| column), plus any learned beside them
        (the path-loss exponent, link offsets)."""
        return int(self.coef.size) + len(self.shared_names)

    @property
    def frequency_hz(self) -> float | None:
        """Carrier frequency the patterns were learned at [Hz] (training summary; None: unknown)."""
        return frequency_from_training(self.training)

    def predict_gain(self, samples: LinkSamples) -> FloatArray:
        """Joint gain [dB] predicted for every sample of a :class:`~rplearn.data.tables.LinkSamples`."""
        tx, rx = self.end_indices(samples)
        d = samples.directions
        with blas_threads(prediction_flops(len(samples), self.basis.n_coef)):  # rplearn.core.threads
            gain = self._sum_node_gains(tx, d.az_tx, d.el_tx) + self._sum_node_gains(rx, d.az_rx, d.el_rx)
        if self.path_loss.kind != "free" or self.shared_names:
            gain = gain + self.environment_db(samples)
        return gain

    def _sum_node_gains(self, node_idx: np.ndarray, az_rad: FloatArray, el_rad: FloatArray) -> FloatArray:
        """Gain of node ``node_idx[i]`` toward direction ``i`` [dBi], one chunked pass per node."""
        out = np.zeros(node_idx.size)
        for k in np.unique(node_idx):
            sel = np.flatnonzero(node_idx == k)
            out[sel] = self.basis.evaluate(self.coef[k], np.asarray(az_rad)[sel], np.asarray(el_rad)[sel])
        return out
