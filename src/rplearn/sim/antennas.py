"""Reference antennas and airframe effects: the ground truth of simulated flights.

A simulated node is a drone-with-antenna (paper Sec. II-B): an antenna model evaluated in its
own frame, mounted on the body at some orientation, plus smooth airframe effects (shadowing
lobes and nulls of frame, battery and payload) that make two drones of the same model differ.

Antenna models (gains in dBi, angles in degrees inside the formulas, radians in the API):
ITU-R F.1336-5 omnidirectional (recommends 2.1, 2.2) and sectoral (recommends 3.1.1, 3.1.2),
half-wave dipole, isotropic, and a cosine-power beam; the formulas are in
:mod:`rplearn.sim.gain_formulas`.

Frames: an antenna frame has its symmetry axis (omni, dipole) along +z and its boresight
(sectoral, cosine beam) along +x. A :class:`Mounting` rotates the antenna frame into the body
frame (FLU); "vertical" is the identity, "horizontal" lays the axis along the body x axis.

The ground truth of a flight, :class:`GroundTruth`, is the set of nodes with their antenna,
mounting and airframe effects; it round-trips through JSON (:func:`load_ground_truth`) and
offers the interface of a learned ``PatternSet``: ``nodes``, ``evaluate(node, az, el)`` and
``predict_joint_gain_db(...)`` (paper eq. 5 without noise).
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from rplearn._argtypes import check_types
from rplearn._atomic import atomic_open, dump_json
from rplearn.core.geometry import azimuth_elevation, great_circle_angle, quat_wxyz_from_euler, quat_wxyz_to_matrix, unit_vector
from rplearn.errors import InputError, ModelFileError
from rplearn.sim.gain_formulas import (
    SECTORAL_IMPROVED,
    cosine_beam_dbi,
    half_wave_dipole_dbi,
    itu_f1336_omni_average_dbi,
    itu_f1336_omni_peak_dbi,
    itu_f1336_sectoral_average_dbi,
    itu_f1336_sectoral_peak_dbi,
)

FloatArray = NDArray[np.float64]

GROUND_TRUTH_SCHEMA = "rplearn.ground_truth"
GROUND_TRUTH_VERSION = 1


def _check_finite(name: str, value: float) -> float:
    """``value`` as a float; :class:`InputError` naming ``name`` when it is NaN or infinite."""
    v = float(value)
    if not np.isfinite(v):
        raise InputError(f"{name}: expected a finite number, got {value!r}")
    return v


# ---------------------------------------------------------------------------------------------
# Antenna specifications (serialisable)


@check_types
@dataclass(frozen=True)
class AntennaSpec:
    """One antenna model with its parameters; ``gain_dbi`` works in the antenna frame.

    Attributes
    ----------
    kind : str
        ``"itu_omni_peak"`` (F.1336-5 rec. 2.1), ``"itu_omni_average"`` (rec. 2.2),
        ``"itu_sectoral_peak"`` (rec. 3.1.1), ``"itu_sectoral_average"`` (rec. 3.1.2), ``"dipole"``, ``"isotropic"``, ``"cosine_beam"``.
    g0_dbi : float
        Maximum gain [dBi] (ignored by ``dipole``).
    k : float
        Omni side-lobe parameter (0.7 typical, 0 improved).
    phi3_deg, theta3_deg : float or None
        Sectoral 3 dB beamwidths [deg]; ``theta3_deg`` None uses rec. 3.1's relation.
    k_p, k_a, k_h, k_v : float
        Sectoral parameters of rec. 3.1.1 / 3.1.2 (defaults: typical side-lobe performance).
    hpbw_deg, floor_db : float
        Cosine beam half-power beamwidth [deg] and depth of its floor below G0 [dB].
    """

    kind: str
    g0_dbi: float = 0.0
    k: float = 0.7
    phi3_deg: float = 65.0
    theta3_deg: float | None = None
    k_p: float = 0.7
    k_a: float = 0.7
    k_h: float = 0.8
    k_v: float = 0.7
    hpbw_deg: float = 40.0
    floor_db: float = 25.0

    KINDS = (
        "itu_omni_peak",
        "itu_omni_average",
        "itu_sectoral_peak",
        "itu_sectoral_average",
        "dipole",
        "isotropic",
        "cosine_beam",
    )

    def __post_init__(self) -> None:
        if self.kind not in self.KINDS:
            raise InputError(f"antenna kind: expected one of {', '.join(self.KINDS)}, got {self.kind!r}")
        _check_finite("antenna g0_dbi", self.g0_dbi)
        if self.kind.startswith("itu_omni") and not (0.0 <= self.k <= 1.0):
            raise InputError(f"antenna k: expected 0 <= k <= 1, got {self.k}")
        if self.kind.startswith("itu_sectoral") and not (0.0 < self.phi3_deg <= 120.0):
            raise InputError(f"antenna phi3_deg: expected 0 < phi3 <= 120 deg, got {self.phi3_deg}")
        if self.kind == "cosine_beam" and not (0.0 < self.hpbw_deg < 180.0):
            raise InputError(f"antenna hpbw_deg: expected 0 < hpbw < 180 deg, got {self.hpbw_deg}")

    def gain_dbi(self, az_rad: ArrayLike, el_rad: ArrayLike) -> FloatArray:
        """Gain [dBi] towards directions given in the antenna frame (az, el) [rad]."""
        az_deg = np.degrees(np.asarray(az_rad, np.float64))
        el_deg = np.degrees(np.asarray(el_rad, np.float64))
        if self.kind == "itu_omni_peak":
            return itu_f1336_omni_peak_dbi(el_deg, self.g0_dbi, self.k) + 0.0 * az_deg
        if self.kind == "itu_omni_average":
            return itu_f1336_omni_average_dbi(el_deg, self.g0_dbi, self.k) + 0.0 * az_deg
        if self.kind == "itu_sectoral_peak":
            return itu_f1336_sectoral_peak_dbi(
                az_deg, el_deg, self.g0_dbi, self.phi3_deg, self.theta3_deg, self.k_p, self.k_h, self.k_v
            )
        if self.kind == "itu_sectoral_average":
            return itu_f1336_sectoral_average_dbi(
                az_deg, el_deg, self.g0_dbi, self.phi3_deg, self.theta3_deg, self.k_a, self.k_h, self.k_v
            )
        if self.kind == "dipole":
            return half_wave_dipole_dbi(el_deg) + 0.0 * az_deg
        if self.kind == "isotropic":
            return np.full(np.broadcast(az_deg, el_deg).shape, float(self.g0_dbi))
        off_axis = np.degrees(great_circle_angle(np.radians(az_deg), np.radians(el_deg), 0.0, 0.0))
        return cosine_beam_dbi(off_axis, self.g0_dbi, self.hpbw_deg, self.floor_db)


#: Named mountings, (roll, pitch, yaw) of the antenna frame in the body frame [deg].
MOUNTINGS: dict[str, tuple[float, float, float]] = {
    "vertical": (0.0, 0.0, 0.0),
    "horizontal": (0.0, 90.0, 0.0),  # antenna axis along body x (forward)
    "horizontal_lateral": (90.0, 0.0, 0.0),  # antenna axis along body y (left)
    "tilted": (0.0, 45.0, 0.0),
}


@check_types
@dataclass(frozen=True)
class Mounting:
    """Orientation of the antenna frame in the body frame (FLU), aerospace Euler angles [deg].

    ``R_body_from_antenna = Rz(yaw) Ry(pitch) Rx(roll)``. For omni antennas and dipoles the
    antenna axis is the antenna frame's z axis; for beams the boresight is its x axis.
    """

    roll_deg: float = 0.0
    pitch_deg: float = 0.0
    yaw_deg: float = 0.0

    @classmethod
    def named(cls, name: str) -> Mounting:
        """A named mounting: ``vertical``, ``horizontal``, ``horizontal_lateral``, ``tilted``."""
        if name not in MOUNTINGS:
            raise InputError(f"mounting: expected one of {', '.join(MOUNTINGS)}, got {name!r}")
        return cls(*MOUNTINGS[name])

    def matrix_body_from_antenna(self) -> FloatArray:
        """Rotation matrix taking antenna-frame vectors into the body frame."""
        q = quat_wxyz_from_euler(
            np.radians(self.roll_deg), np.radians(self.pitch_deg), np.radians(self.yaw_deg)
        )
        return quat_wxyz_to_matrix(q)

    def body_to_antenna(self, az_rad: ArrayLike, el_rad: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """Body-frame directions (az, el) [rad] expressed in the antenna frame [rad]."""
        v_body = unit_vector(az_rad, el_rad)
        v_ant = v_body @ self.matrix_body_from_antenna()  # R^T v for row vectors
        return azimuth_elevation(v_ant)


@check_types
@dataclass(frozen=True)
class AirframeLobe:
    """A smooth airframe effect: a Gaussian bump in direction on the body sphere [dB].

    ``delta(az, el) = -depth_db * exp(-gamma^2 / (2 width^2))`` with ``gamma`` the great-circle
    angle to the lobe centre. Positive ``depth_db`` is a shadow/null (frame arm, battery,
    payload); negative a reflection-induced gain.

    Attributes
    ----------
    az_deg, el_deg : float
        Centre of the lobe in the body frame [deg].
    width_deg : float
        Angular standard deviation [deg].
    depth_db : float
        Attenuation at the centre [dB].
    label : str
        What casts it (``"battery"``, ``"camera"``...), for humans.
    """

    az_deg: float
    el_deg: float
    width_deg: float
    depth_db: float
    label: str = ""

    def __post_init__(self) -> None:
        if not (self.width_deg > 0.0):
            raise InputError(f"airframe lobe width_deg: expected > 0 deg, got {self.width_deg}")
        if not (-90.0 <= self.el_deg <= 90.0):
            raise InputError(f"airframe lobe el_deg: expected -90..90 deg, got {self.el_deg}")

    def delta_db(self, az_rad: ArrayLike, el_rad: ArrayLike) -> FloatArray:
        """Gain change [dB] at body-frame directions [rad]."""
        gamma = great_circle_angle(az_rad, el_rad, np.radians(self.az_deg), np.radians(self.el_deg))
        w = np.radians(self.width_deg)
        return -self.depth_db * np.exp(-0.5 * (gamma / w) ** 2)


#: Samples per block of :func:`_with_lobes_db` (its five work arrays stay in the cache).
_LOBE_BLOCK = 4096


def _with_lobes_db(lobes: tuple[AirframeLobe, ...], az_rad: FloatArray, el_rad: FloatArray,
                   gain_db: FloatArray) -> FloatArray:
    """``gain_db`` plus every lobe's :meth:`AirframeLobe.delta_db` at the body-frame
    directions (1-D, one shape) [dB], added lobe by lobe in order as that method and
    :func:`~rplearn.core.geometry.great_circle_angle` compute them, bit for bit: the same
    operations in the same order, ``cos(el)`` computed once for all lobes, in blocks of
    samples written into reused arrays instead of new ones per operation.
    """
    centres = []
    for lobe in lobes:
        az2 = np.asarray(np.radians(lobe.az_deg), np.float64)
        el2 = np.asarray(np.radians(lobe.el_deg), np.float64)
        centres.append((az2, el2, np.cos(el2), np.radians(lobe.width_deg), -lobe.depth_db))
    out = np.empty(gain_db.shape)
    n = az_rad.size
    t1, t2, t3, cos_el = (np.empty(min(n, _LOBE_BLOCK)) for _ in range(4))
    for a in range(0, n, _LOBE_BLOCK):
        b = min(a + _LOBE_BLOCK, n)
        az1, el1, g = az_rad[a:b], el_rad[a:b], out[a:b]
        u, v, x, ce = t1[: b - a], t2[: b - a], t3[: b - a], cos_el[: b - a]
        np.cos(el1, out=ce)
        np.copyto(g, gain_db[a:b])
        for az2, el2, cos_el2, width, scale in centres:
            # s = sin((el2 - el1) / 2)^2 + cos(el1) cos(el2) sin((az2 - az1) / 2)^2
            np.subtract(el2, el1, out=u)
            np.divide(u, 2.0, out=u)
            np.sin(u, out=u)
            np.square(u, out=u)
            np.multiply(ce, cos_el2, out=v)
            np.subtract(az2, az1, out=x)
            np.divide(x, 2.0, out=x)
            np.sin(x, out=x)
            np.square(x, out=x)
            np.multiply(v, x, out=v)
            np.add(u, v, out=u)
            # gamma = 2 arcsin(sqrt(clip(s, 0, 1))); delta = -depth exp(-0.5 (gamma / w)^2)
            np.clip(u, 0.0, 1.0, out=u)
            np.sqrt(u, out=u)
            np.arcsin(u, out=u)
            np.multiply(2.0, u, out=u)
            np.divide(u, width, out=u)
            np.square(u, out=u)
            np.multiply(-0.5, u, out=u)
            np.exp(u, out=u)
            np.multiply(scale, u, out=u)
            np.add(g, u, out=g)
    return out


@check_types
@dataclass(frozen=True)
class NodeAntenna:
    """A drone-with-antenna: antenna model, its mounting on the body, and airframe effects."""

    antenna: AntennaSpec
    mounting: Mounting = field(default_factory=Mounting)
    lobes: tuple[AirframeLobe, ...] = ()
    description: str = ""

    def gain_dbi(self, az_rad: ArrayLike, el_rad: ArrayLike) -> FloatArray:
        """Gain of the whole node [dBi] towards body-frame directions (FLU az, el) [rad]."""
        az_b = np.asarray(az_rad, np.float64)
        el_b = np.asarray(el_rad, np.float64)
        az_a, el_a = self.mounting.body_to_antenna(az_b, el_b)
        g = self.antenna.gain_dbi(az_a, el_a)
        if self.lobes and az_b.ndim == 1 and az_b.shape == el_b.shape == np.shape(g):
            return _with_lobes_db(self.lobes, az_b, el_b, np.asarray(g, np.float64))
        for lobe in self.lobes:
            g = g + lobe.delta_db(az_b, el_b)
        return g

    def to_dict(self) -> dict[str, Any]:
        return {
            "antenna": asdict(self.antenna),
            "mounting": asdict(self.mounting),
            "lobes": [asdict(lobe) for lobe in self.lobes],
            "description": self.description,
        }

    @classmethod
    def from_dict(cls, spec: Mapping[str, Any]) -> NodeAntenna:
        return cls(
            antenna=AntennaSpec(**spec["antenna"]),
            mounting=Mounting(**spec.get("mounting", {})),
            lobes=tuple(AirframeLobe(**lobe) for lobe in spec.get("lobes", [])),
            description=str(spec.get("description", "")),
        )


def _link_key(tx: str, rx: str) -> str:
    return f"{tx}->{rx}"


@check_types
@dataclass(frozen=True)
class GroundTruth:
    """The true patterns of every node of a simulated flight, plus the radio's per-link offsets.

    Offers the interface of a learned ``PatternSet`` (``nodes``, ``evaluate``,
    ``predict_joint_gain_db``) so that a learned model can be scored against the truth.

    Attributes
    ----------
    node_antennas : dict of str -> NodeAntenna
        Per node: antenna, mounting, airframe lobes.
    link_offsets_db : dict of str -> float
        Electronics offset of each direction ``"A->B"`` [dB] (non-reciprocity, paper Sec.
        V-B3). It is part of the radio, not of the patterns: :meth:`predict_joint_gain_db`
        adds it only when asked.
    frequency_hz : float
        Carrier frequency [Hz].
    metadata : dict
        Free-form notes (preset name, seed).
    """

    node_antennas: dict[str, NodeAntenna]
    link_offsets_db: dict[str, float] = field(default_factory=dict)
    frequency_hz: float = 2.412e9
    metadata: dict[str, Any] = field(default_factory=dict)

    @property
    def nodes(self) -> tuple[str, ...]:
        """Node ids, sorted."""
        return tuple(sorted(self.node_antennas))

    def _node(self, node: str) -> NodeAntenna:
        try:
            return self.node_antennas[str(node)]
        except KeyError:
            raise InputError(
                f"node: unknown id {node!r}; the ground truth knows {', '.join(self.nodes)}"
            ) from None

    def evaluate(self, node: str, az_rad: ArrayLike, el_rad: ArrayLike) -> FloatArray:
        """True gain [dBi] of ``node`` towards body-frame directions (az, el) [rad]."""
        return self._node(node).gain_dbi(az_rad, el_rad)

    def link_offset_db(self, tx_node: str, rx_node: str) -> float:
        """Electronics offset of the direction tx -> rx [dB] (0 when not set)."""
        return float(self.link_offsets_db.get(_link_key(tx_node, rx_node), 0.0))

    def predict_joint_gain_db(
        self,
        tx_node: str,
        rx_node: str,
        az_tx: ArrayLike,
        el_tx: ArrayLike,
        az_rx: ArrayLike,
        el_rx: ArrayLike,
        include_link_offset: bool = False,
    ) -> FloatArray:
        """True joint gain ``G_tx(az_tx, el_tx) + G_rx(az_rx, el_rx)`` [dB] (paper eq. 5).

        With ``include_link_offset`` the direction's electronics offset is added, which is
        what the observed joint gain of eq. 5 contains on average.
        """
        g = self.evaluate(tx_node, az_tx, el_tx) + self.evaluate(rx_node, az_rx, el_rx)
        if include_link_offset:
            g = g + self.link_offset_db(tx_node, rx_node)
        return g

    def to_dict(self) -> dict[str, Any]:
        from rplearn._version import __version__

        return {
            "schema": GROUND_TRUTH_SCHEMA,
            "version": GROUND_TRUTH_VERSION,
            "rplearn_version": __version__,
            "frequency_hz": float(self.frequency_hz),
            "nodes": {n: self.node_antennas[n].to_dict() for n in self.nodes},
            "link_offsets_db": {k: float(v) for k, v in sorted(self.link_offsets_db.items())},
            "metadata": dict(self.metadata),
        }

    @classmethod
    def from_dict(cls, spec: Mapping[str, Any], source: str = "ground truth") -> GroundTruth:
        if not isinstance(spec, Mapping) or spec.get("schema") != GROUND_TRUTH_SCHEMA:
            raise ModelFileError(f"{source}: field schema: expected {GROUND_TRUTH_SCHEMA!r}")
        if spec.get("version") != GROUND_TRUTH_VERSION:
            raise ModelFileError(
                f"{source}: field version: expected {GROUND_TRUTH_VERSION}, got {spec.get('version')!r}"
            )
        try:
            nodes = {str(n): NodeAntenna.from_dict(s) for n, s in spec["nodes"].items()}
            return cls(
                node_antennas=nodes,
                link_offsets_db={str(k): float(v) for k, v in spec.get("link_offsets_db", {}).items()},
                frequency_hz=float(spec["frequency_hz"]),
                metadata=dict(spec.get("metadata", {})),
            )
        except (KeyError, TypeError, ValueError, AttributeError) as exc:
            raise ModelFileError(f"{source}: malformed ground truth ({type(exc).__name__}: {exc})") from None

    def save(self, path: str) -> str:
        """Write the ground truth as JSON; returns the path."""
        with atomic_open(path, "w", encoding="utf-8") as fh:
            dump_json(self.to_dict(), fh, indent=2, sort_keys=False)
            fh.write("\n")
        return str(path)


@check_types
def load_ground_truth(path: str) -> GroundTruth:
    """Read a ground-truth JSON file written by :meth:`GroundTruth.save`.

    Raises
    ------
    ModelFileError
        When the file is missing, not JSON, or not a ground truth of a known version.
    """
    try:
        with open(path, encoding="utf-8") as fh:
            spec = json.load(fh)
    except FileNotFoundError:
        raise ModelFileError(f"{path}: no such file") from None
    except (OSError, json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise ModelFileError(f"{path}: not a JSON ground truth ({type(exc).__name__}: {exc})") from None
    return GroundTruth.from_dict(spec, source=str(path))


@check_types
def antenna_from_name(name: str, **overrides: Any) -> AntennaSpec:
    """Ready-made antennas by name, with keyword overrides.

    ``itu_omni`` (F.1336-5 rec. 2.2, G0 = 2 dBi, k = 0.7), ``itu_omni_improved`` (k = 0),
    ``itu_omni_peak`` (rec. 2.1), ``itu_sectoral`` (rec. 3.1.1, G0 = 15 dBi, phi3 = 65 deg, typical
    side-lobes), ``itu_sectoral_improved`` (3.1.1.2), ``itu_sectoral_average`` (3.1.2),
    ``dipole``, ``isotropic``, ``high_gain`` (cosine beam, 12 dBi, 40 deg).
    """
    table: dict[str, dict[str, Any]] = {
        "itu_omni": {"kind": "itu_omni_average", "g0_dbi": 2.0, "k": 0.7},
        "itu_omni_improved": {"kind": "itu_omni_average", "g0_dbi": 2.0, "k": 0.0},
        "itu_omni_peak": {"kind": "itu_omni_peak", "g0_dbi": 2.0, "k": 0.7},
        "itu_sectoral": {"kind": "itu_sectoral_peak", "g0_dbi": 15.0, "phi3_deg": 65.0},
        "itu_sectoral_improved": {"kind": "itu_sectoral_peak", "g0_dbi": 15.0, "phi3_deg": 65.0, **SECTORAL_IMPROVED},
        "itu_sectoral_average": {"kind": "itu_sectoral_average", "g0_dbi": 15.0, "phi3_deg": 65.0},
        "dipole": {"kind": "dipole"},
        "isotropic": {"kind": "isotropic", "g0_dbi": 0.0},
        "high_gain": {"kind": "cosine_beam", "g0_dbi": 12.0, "hpbw_deg": 40.0, "floor_db": 25.0},
    }
    if name not in table:
        raise InputError(f"antenna name: expected one of {', '.join(table)}, got {name!r}")
    return AntennaSpec(**{**table[name], **overrides})
