"""Link budget: wavelength, free-space path loss, observed joint gain (paper eqs. 1 and 5).

Eq. 1 (Friis in dB): ``P_rx = P_tx + G_tx + G_rx + 20 log10(lambda / (4 pi d))``.
Eq. 5: the observed joint gain of a packet ``G_joint = P_rx - P_tx - 20 log10(lambda / (4 pi d))``.
The paper assumes the far field, ``d > 2 lambda`` (Sec. III); closer samples are refused.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from rplearn._argtypes import check_types
from rplearn.errors import FarFieldError, InputError

#: Speed of light in vacuum [m/s].
SPEED_OF_LIGHT_M_S = 299_792_458.0
#: The paper's far-field limit, as a multiple of the wavelength (Sec. III: d > 2 lambda).
FAR_FIELD_WAVELENGTHS = 2.0


@check_types
def wavelength_m(frequency_hz: ArrayLike) -> NDArray[np.float64]:
    """Wavelength [m] of a carrier frequency [Hz]."""
    f = np.asarray(frequency_hz, np.float64)
    if np.any(~np.isfinite(f)) or np.any(f <= 0):
        raise InputError("frequency_hz: expected positive finite frequencies in Hz")
    return SPEED_OF_LIGHT_M_S / f


@check_types
def far_field_limit_m(frequency_hz: ArrayLike) -> NDArray[np.float64]:
    """The far-field limit ``2 lambda`` [m] of a carrier frequency [Hz] (paper Sec. III): no
    received power is predicted, and no sample learned, at or below this distance."""
    return FAR_FIELD_WAVELENGTHS * wavelength_m(frequency_hz)


@check_types
def check_far_field(distance_m: ArrayLike, frequency_hz: ArrayLike, what: str = "samples") -> None:
    """Refuse distances not beyond the far-field limit ``d > 2 lambda`` (paper Sec. III).

    Raises
    ------
    FarFieldError
        Naming how many samples are too close and the closest distance.
    """
    d = np.asarray(distance_m, np.float64)
    limit = far_field_limit_m(frequency_hz)
    bad = ~(d > limit)
    if np.any(bad):
        n_bad = int(np.sum(bad))
        closest = float(np.nanmin(d)) if np.any(np.isfinite(d)) else float("nan")
        raise FarFieldError(
            f"{what}: {n_bad} of {d.size} sample(s) are not in the far field "
            f"(distance must exceed 2 wavelengths = {float(np.max(limit)):.3f} m; closest {closest:.3f} m)"
        )


@check_types
def free_space_path_loss_db(distance_m: ArrayLike, frequency_hz: ArrayLike) -> NDArray[np.float64]:
    """Free-space path loss ``20 log10(4 pi d / lambda)`` [dB] (positive; eq. 1 adds its negative)."""
    d = np.asarray(distance_m, np.float64)
    check_far_field(d, frequency_hz)
    return 20.0 * np.log10(4.0 * np.pi * d / wavelength_m(frequency_hz))


@check_types
def observed_joint_gain_db(
    rssi_dbm: ArrayLike, tx_power_dbm: ArrayLike, distance_m: ArrayLike, frequency_hz: ArrayLike
) -> NDArray[np.float64]:
    """Observed joint gain ``G_tx + G_rx`` of received packets (paper eq. 5) [dB].

    Parameters
    ----------
    rssi_dbm : array_like
        Received power [dBm].
    tx_power_dbm : array_like
        Transmitted power [dBm].
    distance_m : array_like
        Distance between the two antennas [m]; must exceed 2 wavelengths.
    frequency_hz : array_like
        Carrier frequency [Hz].
    """
    return (
        np.asarray(rssi_dbm, np.float64)
        - np.asarray(tx_power_dbm, np.float64)
        + free_space_path_loss_db(distance_m, frequency_hz)
    )


@check_types
def received_power_dbm(
    tx_power_dbm: ArrayLike, joint_gain_db: ArrayLike, distance_m: ArrayLike, frequency_hz: ArrayLike
) -> NDArray[np.float64]:
    """Received power by Friis (paper eq. 1) [dBm]."""
    return (
        np.asarray(tx_power_dbm, np.float64)
        + np.asarray(joint_gain_db, np.float64)
        - free_space_path_loss_db(distance_m, frequency_hz)
    )
