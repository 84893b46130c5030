"""Antenna gain formulas: ITU-R F.1336-5 reference patterns, half-wave dipole, cosine beam.

Closed-form gains [dBi] of the antenna models :class:`rplearn.sim.antennas.AntennaSpec` offers,
as functions of angles in degrees measured in the antenna's own frame:

- ITU-R F.1336-5 omnidirectional, recommends 2.1 (peak side-lobe) and 2.2 (average
  side-lobe), with k = 0.7 (recommends 2.3, typical) or k = 0 (recommends 2.4, improved);
- ITU-R F.1336-5 sectoral, recommends 3.1.1 (peak side-lobe) and 3.1.2 (average side-lobe),
  400 MHz - 6 GHz, with ``k_p``/``k_a``, ``k_h``, ``k_v`` and the beamwidth relation
  ``theta3 = 31000 * 10^(-0.1 G0) / phi3``; no tilt (recommends 3.4/3.5 are not implemented);
- half-wave dipole (textbook, Balanis eq. 4-84) and a circularly symmetric cosine-power beam
  (a generic high-gain antenna, not an ITU model).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from rplearn._argtypes import check_types

FloatArray = NDArray[np.float64]

#: Floor of linear gains before taking logarithms (avoids -inf at exact nulls) [dBi].
GAIN_FLOOR_DBI = -60.0


def _deg(a: ArrayLike) -> FloatArray:
    """Angles [deg] as a float64 array."""
    return np.asarray(a, dtype=np.float64)


# ---------------------------------------------------------------------------------------------
# ITU-R F.1336-5 omnidirectional antennas (recommends 2)


def itu_f1336_omni_theta3_deg(g0_dbi: float) -> float:
    """3 dB beamwidth in the elevation plane of an omni antenna, ITU-R F.1336-5 eq. (1b) [deg].

    ``theta3 = 107.6 * 10^(-0.1 G0)``.
    """
    return 107.6 * 10.0 ** (-0.1 * float(g0_dbi))


@check_types
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


@check_types
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


@dataclass(frozen=True)
class _SideLobes:
    """Side-lobe parameters of a sectoral pattern: ``k`` (``k_p`` peak, ``k_a`` average), ``k_h``,
    ``k_v``, and whether the formula is the average one."""

    k: float
    k_h: float
    k_v: float
    average: bool


def _sectoral_dbi(
    az_deg: ArrayLike, el_deg: ArrayLike, g0_dbi: float, phi3_deg: float, theta3_deg: float | None, lobes: _SideLobes,
) -> FloatArray:
    k, k_h, k_v, average = lobes.k, lobes.k_h, lobes.k_v, lobes.average
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


@check_types
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
        Azimuth from boresight (-180..180) and elevation (-90..90) [deg].
    g0_dbi : float
        Boresight gain [dBi].
    phi3_deg : float
        Azimuth 3 dB beamwidth [deg].
    theta3_deg : float, optional
        Elevation 3 dB beamwidth [deg]; by default :func:`itu_f1336_sectoral_theta3_deg`.
    """
    return _sectoral_dbi(az_deg, el_deg, g0_dbi, phi3_deg, theta3_deg, _SideLobes(k_p, k_h, k_v, average=False))


@check_types
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
    return _sectoral_dbi(az_deg, el_deg, g0_dbi, phi3_deg, theta3_deg, _SideLobes(k_a, k_h, k_v, average=True))


# ---------------------------------------------------------------------------------------------
# Other antennas


@check_types
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


@check_types
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
