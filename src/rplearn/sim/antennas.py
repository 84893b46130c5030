"""Reference antennas and airframe effects: the ground truth of simulated flights.

A simulated node is a drone-with-antenna (paper Sec. II-B): an antenna model evaluated in its
own frame, mounted on the body at some orientation, plus smooth airframe effects (shadowing
lobes and nulls of frame, battery and payload) that make two drones of the same model differ.

Antenna models (gains in dBi, angles in degrees inside the formulas, radians in the API):

- ITU-R F.1336-5 omnidirectional, recommends 2.1 (peak side-lobe) and 2.2 (average
  side-lobe), with k = 0.7 (recommends 2.3, typical) or k = 0 (recommends 2.4, improved);
- ITU-R F.1336-5 sectoral, recommends 3.1.1 (peak side-lobe) and 3.1.2 (average side-lobe),
  400 MHz - 6 GHz, with ``k_p``/``k_a``, ``k_h``, ``k_v`` and the beamwidth relation
  ``theta3 = 31000 * 10^(-0.1 G0) / phi3``; no tilt (recommends 3.4/3.5 are not implemented);
- half-wave dipole (textbook, Balanis eq. 4-84), isotropic, and a circularly symmetric
  cosine-power beam (a generic high-gain antenna, not an ITU model).

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
from dataclasses import asdict, dataclass, field
from typing import Any, Mapping

import numpy as np
from numpy.typing import ArrayLike, NDArray

from rplearn.errors import InputError, ModelFileError
from rplearn.core.geometry import (
    azimuth_elevation,
    great_circle_angle,
    quat_wxyz_from_euler,
    quat_wxyz_to_matrix,
    unit_vector,
)

FloatArray = NDArray[np.float64]

GROUND_TRUTH_SCHEMA = "rplearn.ground_truth"
GROUND_TRUTH_VERSION = 1

#: Floor of linear gains before taking logarithms (avoids -inf at exact nulls) [dBi].
GAIN_FLOOR_DBI = -60.0


def _deg(a: ArrayLike) -> FloatArray:
    return np.asarray(a, dtype=np.float64)


def _check_finite(name: str, value: float) -> float:
    v = float(value)
    if not np.isfinite(v):
        raise InputError(f"{name}: expected a finite number, got {value!r}")
    return v


# ---------------------------------------------------------------------------------------------
# ITU-R F.1336-5 omnidirectional antennas (recommends 2)


def itu_f1336_omni_theta3_deg(g0_dbi: float) -> float:
    """3 dB beamwidth in the elevation plane of an omni antenna, ITU-R F.1336-5 eq. (1b) [deg].

    ``theta3 = 107.6 * 10^(-0.1 G0)``.
    """
    return 107.6 * 10.0 ** (-0.1 * float(g0_dbi))


def itu_f1336_omni_peak_dbi(el_deg: ArrayLike, g0_dbi: float, k: float = 0.7) -> FloatArray:
    """Omnidirectional peak side-lobe pattern, ITU-R F.1336-5 recommends 2.1 [dBi].

    ::

        G = G0 - 12 (theta/theta3)^2                      0 <= |theta| < theta4
        G = G0 - 12 + 10 log10(k + 1)                theta4 <= |theta| < theta3
        G = G0 - 12 + 10 log10((|theta|/theta3)^-1.5 + k)  theta3 <= |theta| <= 90

    with ``theta3`` of eq. (1b) and ``theta4 = theta3 sqrt(1 - log10(k + 1) / 1.2)`` (eq. 1c).

    Parameters
    ----------
    el_deg : array_like
        Elevation above the plane perpendicular to the antenna axis [deg], in [-90, 90].
    g0_dbi : float
        Maximum gain in the horizontal plane [dBi].
    k : float
        Side-lobe parameter: 0.7 typical (recommends 2.3), 0 improved (recommends 2.4).
    """
    theta = np.abs(_deg(el_deg))
    theta3 = itu_f1336_omni_theta3_deg(g0_dbi)
    theta4 = theta3 * np.sqrt(1.0 - np.log10(k + 1.0) / 1.2)
    ratio = np.maximum(theta, 1e-12) / theta3
    main = g0_dbi - 12.0 * ratio**2
    shoulder = g0_dbi - 12.0 + 10.0 * np.log10(k + 1.0)
    side = g0_dbi - 12.0 + 10.0 * np.log10(ratio**-1.5 + k)
    return np.where(theta < theta4, main, np.where(theta < theta3, shoulder, side))


def itu_f1336_omni_average_dbi(el_deg: ArrayLike, g0_dbi: float, k: float = 0.7) -> FloatArray:
    """Omnidirectional average side-lobe pattern, ITU-R F.1336-5 recommends 2.2 [dBi].

    ::

        G = G0 - 12 (theta/theta3)^2                      0 <= |theta| < theta3
        G = G0 - 15 + 10 log10(k + 1)                theta3 <= |theta| < theta5
        G = G0 - 15 + 10 log10((|theta|/theta3)^-1.5 + k)  theta5 <= |theta| <= 90

    with ``theta5 = theta3 sqrt(1.25 - log10(k + 1) / 1.2)`` (eq. 1d). Parameters as in
    :func:`itu_f1336_omni_peak_dbi`.
    """
    theta = np.abs(_deg(el_deg))
    theta3 = itu_f1336_omni_theta3_deg(g0_dbi)
    theta5 = theta3 * np.sqrt(1.25 - np.log10(k + 1.0) / 1.2)
    ratio = np.maximum(theta, 1e-12) / theta3
    main = g0_dbi - 12.0 * ratio**2
    shoulder = g0_dbi - 15.0 + 10.0 * np.log10(k + 1.0)
    side = g0_dbi - 15.0 + 10.0 * np.log10(ratio**-1.5 + k)
    return np.where(theta < theta3, main, np.where(theta < theta5, shoulder, side))


# ---------------------------------------------------------------------------------------------
# ITU-R F.1336-5 sectoral antennas (recommends 3.1)


def itu_f1336_sectoral_theta3_deg(g0_dbi: float, phi3_deg: float) -> float:
    """Elevation 3 dB beamwidth of a sectoral antenna, ITU-R F.1336-5 recommends 3.1 [deg].

    ``theta3 = 31000 * 10^(-0.1 G0) / phi3`` (valid for ``phi3 <= 120 deg``).
    """
    return 31000.0 * 10.0 ** (-0.1 * float(g0_dbi)) / float(phi3_deg)


def _sectoral_g180_db(k: float, theta3_deg: float, average: bool) -> float:
    """Relative minimum gain ``G180`` [dB].

    Peak (rec. 3.1.1): ``-12 + 10 log10(1 + 8 k_p) - 15 log10(180/theta3)``;
    average (rec. 3.1.2): ``-15 + 10 log10(1 + 8 k_a) - 15 log10(180/theta3)``.
    """
    base = -15.0 if average else -12.0
    return base + 10.0 * np.log10(1.0 + 8.0 * k) - 15.0 * np.log10(180.0 / theta3_deg)


def _sectoral_g_hr_db(x_h: FloatArray, k_h: float, g180_db: float) -> FloatArray:
    """Relative horizontal pattern ``G_hr(x_h)`` of recommends 3.1.1 and 3.1.2 [dB]."""
    lambda_kh = 3.0 * (1.0 - 0.5 ** (-k_h))
    inner = -12.0 * x_h**2
    outer = -12.0 * np.maximum(x_h, 1e-12) ** (2.0 - k_h) - lambda_kh
    return np.maximum(np.where(x_h <= 0.5, inner, outer), g180_db)


def _sectoral_g_vr_db(
    x_v: FloatArray, k_v: float, k: float, theta3_deg: float, g180_db: float, average: bool
) -> FloatArray:
    """Relative vertical pattern ``G_vr(x_v)`` of recommends 3.1.1 (peak) / 3.1.2 (average) [dB]."""
    c = 10.0 * np.log10((180.0 / theta3_deg) ** 1.5 * (4.0**-1.5 + k_v) / (1.0 + 8.0 * k)) / np.log10(
        22.5 / theta3_deg
    )
    lambda_kv = 12.0 - c * np.log10(4.0) - 10.0 * np.log10(4.0**-1.5 + k_v)
    if average:
        x_k, shoulder, drop = np.sqrt(1.33 - 0.33 * k_v), -15.0, 3.0
    else:
        x_k, shoulder, drop = np.sqrt(1.0 - 0.36 * k_v), -12.0, 0.0
    xs = np.maximum(x_v, 1e-12)
    g = np.where(
        x_v < x_k,
        -12.0 * x_v**2,
        np.where(
            x_v < 4.0,
            shoulder + 10.0 * np.log10(xs**-1.5 + k_v),
            -lambda_kv - drop - c * np.log10(xs),
        ),
    )
    return np.where(x_v >= 90.0 / theta3_deg, g180_db, g)


def _sectoral_dbi(
    az_deg: ArrayLike,
    el_deg: ArrayLike,
    g0_dbi: float,
    phi3_deg: float,
    theta3_deg: float | None,
    k: float,
    k_h: float,
    k_v: float,
    average: bool,
) -> FloatArray:
    if theta3_deg is None:
        theta3_deg = itu_f1336_sectoral_theta3_deg(g0_dbi, phi3_deg)
    az = np.abs(_deg(az_deg))
    el = np.abs(_deg(el_deg))
    g180 = _sectoral_g180_db(k, theta3_deg, average)
    x_h = az / phi3_deg
    x_v = el / theta3_deg
    g_hr = _sectoral_g_hr_db(x_h, k_h, g180)
    g_hr_0 = _sectoral_g_hr_db(np.zeros(1), k_h, g180)[0]
    g_hr_180 = _sectoral_g_hr_db(np.array([180.0 / phi3_deg]), k_h, g180)[0]
    r = (g_hr - g_hr_180) / (g_hr_0 - g_hr_180)
    return g0_dbi + g_hr + r * _sectoral_g_vr_db(x_v, k_v, k, theta3_deg, g180, average)


#: Sectoral side-lobe parameters (k_h, k_v) for typical (rec. 3.1.1.1) and improved (3.1.1.2)
#: side-lobe performance; k_p = k_a = 0.7.
SECTORAL_TYPICAL = {"k_h": 0.8, "k_v": 0.7}
SECTORAL_IMPROVED = {"k_h": 0.7, "k_v": 0.3}


def itu_f1336_sectoral_peak_dbi(
    az_deg: ArrayLike,
    el_deg: ArrayLike,
    g0_dbi: float,
    phi3_deg: float,
    theta3_deg: float | None = None,
    k_p: float = 0.7,
    k_h: float = 0.8,
    k_v: float = 0.7,
) -> FloatArray:
    """Sectoral peak side-lobe pattern, ITU-R F.1336-5 recommends 3.1.1 [dBi].

    ``G(phi, theta) = G0 + G_hr(x_h) + R G_vr(x_v)`` with ``x_h = |phi|/phi3``,
    ``x_v = |theta|/theta3`` and::

        G_hr = -12 x_h^2                      x_h <= 0.5
        G_hr = -12 x_h^(2 - k_h) - lambda_kh  x_h > 0.5,   G_hr >= G180
        lambda_kh = 3 (1 - 0.5^-k_h)
        G180 = -12 + 10 log10(1 + 8 k_p) - 15 log10(180 / theta3)
        G_vr = -12 x_v^2                           x_v < x_k = sqrt(1 - 0.36 k_v)
        G_vr = -12 + 10 log10(x_v^-1.5 + k_v)      x_k <= x_v < 4
        G_vr = -lambda_kv - C log10(x_v)           4 <= x_v < 90/theta3
        G_vr = G180                                x_v = 90/theta3
        lambda_kv = 12 - C log10(4) - 10 log10(4^-1.5 + k_v)
        C = 10 log10((180/theta3)^1.5 (4^-1.5 + k_v) / (1 + 8 k_p)) / log10(22.5/theta3)
        R = (G_hr(x_h) - G_hr(180/phi3)) / (G_hr(0) - G_hr(180/phi3))

    ``C`` and ``lambda_kv`` make ``G_vr`` continuous at ``x_v = 4`` and equal to ``G180`` at
    90 deg. Typical side-lobe performance (rec. 3.1.1.1): ``k_p = 0.7, k_h = 0.8, k_v = 0.7``
    (the defaults); improved (rec. 3.1.1.2): ``k_h = 0.7, k_v = 0.3``. No tilt.

    Parameters
    ----------
    az_deg, el_deg : array_like
        Azimuth from boresight in [-180, 180] and elevation in [-90, 90] [deg].
    g0_dbi : float
        Boresight gain [dBi].
    phi3_deg : float
        Azimuth 3 dB beamwidth [deg].
    theta3_deg : float, optional
        Elevation 3 dB beamwidth [deg]; by default :func:`itu_f1336_sectoral_theta3_deg`.
    """
    return _sectoral_dbi(az_deg, el_deg, g0_dbi, phi3_deg, theta3_deg, k_p, k_h, k_v, average=False)


def itu_f1336_sectoral_average_dbi(
    az_deg: ArrayLike,
    el_deg: ArrayLike,
    g0_dbi: float,
    phi3_deg: float,
    theta3_deg: float | None = None,
    k_a: float = 0.7,
    k_h: float = 0.8,
    k_v: float = 0.7,
) -> FloatArray:
    """Sectoral average side-lobe pattern, ITU-R F.1336-5 recommends 3.1.2 [dBi].

    As :func:`itu_f1336_sectoral_peak_dbi` with ``k_a`` for ``k_p`` and::

        G180 = -15 + 10 log10(1 + 8 k_a) - 15 log10(180 / theta3)
        G_vr = -12 x_v^2                           x_v < x_k = sqrt(1.33 - 0.33 k_v)
        G_vr = -15 + 10 log10(x_v^-1.5 + k_v)      x_k <= x_v < 4
        G_vr = -lambda_kv - 3 - C log10(x_v)       4 <= x_v < 90/theta3
        G_vr = G180                                x_v = 90/theta3
        C = 10 log10((180/theta3)^1.5 (4^-1.5 + k_v) / (1 + 8 k_a)) / log10(22.5/theta3)
    """
    return _sectoral_dbi(az_deg, el_deg, g0_dbi, phi3_deg, theta3_deg, k_a, k_h, k_v, average=True)


# ---------------------------------------------------------------------------------------------
# Other antennas


def half_wave_dipole_dbi(el_deg: ArrayLike) -> FloatArray:
    """Half-wave dipole, ``D = 1.641 [cos(pi/2 cos t) / sin t]^2`` with ``t`` from the axis [dBi].

    ``el_deg`` is the elevation above the plane perpendicular to the dipole [deg]
    (``t = 90 - el``); the peak is 2.15 dBi at ``el = 0``; nulls along the axis are floored at
    :data:`GAIN_FLOOR_DBI`.
    """
    t = np.radians(90.0 - _deg(el_deg))
    s = np.sin(t)
    with np.errstate(divide="ignore", invalid="ignore"):
        f = np.where(np.abs(s) > 1e-9, np.cos(0.5 * np.pi * np.cos(t)) / np.where(s == 0, 1.0, s), 0.0)
    lin = 1.641 * f**2
    return 10.0 * np.log10(np.maximum(lin, 10.0 ** (GAIN_FLOOR_DBI / 10.0)))


def cosine_beam_dbi(off_axis_deg: ArrayLike, g0_dbi: float, hpbw_deg: float, floor_db: float) -> FloatArray:
    """Circularly symmetric cosine-power beam, ``G0 + 10 log10(cos^q t)``, floored [dBi].

    ``q`` is chosen so that the gain is 3 dB down at ``t = hpbw/2``; beyond the main lobe the
    gain never falls below ``G0 - floor_db``. A generic directional (high-gain) antenna, not an
    ITU reference pattern.
    """
    t = np.radians(np.abs(_deg(off_axis_deg)))
    q = np.log(0.5) / np.log(np.cos(np.radians(hpbw_deg) / 2.0))
    c = np.clip(np.cos(t), 1e-12, 1.0)
    return np.maximum(g0_dbi + 10.0 * q * np.log10(c), g0_dbi - floor_db)


# ---------------------------------------------------------------------------------------------
# Antenna specifications (serialisable)


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
        az_deg = np.degrees(_deg(az_rad))
        el_deg = np.degrees(_deg(el_rad))
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
    def named(cls, name: str) -> "Mounting":
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
    def from_dict(cls, spec: Mapping[str, Any]) -> "NodeAntenna":
        return cls(
            antenna=AntennaSpec(**spec["antenna"]),
            mounting=Mounting(**spec.get("mounting", {})),
            lobes=tuple(AirframeLobe(**lobe) for lobe in spec.get("lobes", [])),
            description=str(spec.get("description", "")),
        )


def _link_key(tx: str, rx: str) -> str:
    return f"{tx}->{rx}"


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
    def from_dict(cls, spec: Mapping[str, Any], source: str = "ground truth") -> "GroundTruth":
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
        with open(path, "w", encoding="utf-8") as fh:
            json.dump(self.to_dict(), fh, indent=2, sort_keys=False)
            fh.write("\n")
        return str(path)


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


