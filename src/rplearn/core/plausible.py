"""Plausible physical quantities: one table, one frequency check, one band per dataset.

Every physical quantity rplearn reads from a user (a flag, a dataset, a log, a model file, a
reference pattern, an MSI file, a prior, a Python call) is checked here, against the range in
:data:`PLAUSIBLE` (docs/conventions.md, "Plausible values"). A value outside it is an
:class:`~rplearn.errors.InputError` whose one line names where it came from (the file, field,
row or parameter), the value, the range, and why the range is what it is.

Carrier frequencies get one check, :func:`check_frequency_hz`, whatever unit the source writes
them in (Hz in datasets, model files and the API; MHz in MSI files), with a hint when the value
reads as another unit (2412 Hz "looks like MHz", an MSI ``FREQUENCY 2.412`` [MHz] "looks like
GHz"). A dataset, a model and a prior hold **one band** (:func:`frequency_bands`: carriers
within :data:`BAND_SPAN` of the band's lowest one, e.g. Wi-Fi channels 1-13 at 2.412-2.472 GHz,
or 5.17-5.83 GHz): a dataset mixing bands is refused with its samples counted per band
(:func:`check_one_band`), and a model or prior used at another band than it learned at is
refused (:func:`check_same_band`).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from rplearn._argtypes import check_types
from rplearn.errors import InputError


@check_types
@dataclass(frozen=True)
class Plausible:
    """The plausible range of one physical quantity.

    Attributes
    ----------
    name : str
        The quantity, with its unit (``"latitude_deg"``).
    low, high : float
        Inclusive bounds.
    unit : str
        Unit of the bounds, as printed.
    why : str
        Why the bounds are what they are (printed with a refusal).
    """

    name: str
    low: float
    high: float
    unit: str
    why: str


#: The plausibility table: every physical quantity read from any source is checked against its
#: row (:func:`check_plausible`). Distances are those of a drone radio link (SiK, Wi-Fi, LoRa
#: telemetry: tens of km at most); heights those of an aircraft, not a satellite.
PLAUSIBLE: Mapping[str, Plausible] = {q.name: q for q in (
    Plausible("frequency_hz", 1e7, 3e11, "Hz", "radio carriers of drone links: 10 MHz to 300 GHz"),
    Plausible("tx_power_dbm", -40.0, 60.0, "dBm", "radio transmit powers: 0.1 uW to 1 kW"),
    Plausible("latitude_deg", -90.0, 90.0, "deg", "a WGS-84 latitude"),
    Plausible("longitude_deg", -180.0, 180.0, "deg", "a WGS-84 longitude"),
    Plausible("altitude_m", -1_000.0, 50_000.0, "m", "a drone's altitude: no place is 1 km below the sea, no drone 50 km above it"),
    Plausible("position_m", -100_000.0, 100_000.0, "m", "an ENU coordinate within 100 km of the origin (the station or home)"),
    Plausible("coordinate_m", -1e8, 1e8, "m", "a coordinate of a place on or near the Earth in any Cartesian frame: local, UTM or ECEF"),
    Plausible("link_distance_m", 0.0, 100_000.0, "m", "a drone radio link, or a home or station, within 100 km of the flight"),
    Plausible("height_above_ground_m", 0.01, 50_000.0, "m", "an antenna above the two-ray ground, and within 50 km of it"),
    Plausible("gain_dbi", -100.0, 60.0, "dBi", "antenna gains: a 60 dBi dish is the largest, -100 dBi a deep null"),
    Plausible("mount_deg", -360.0, 360.0, "deg", "a mounting angle (roll, pitch, yaw)"),
)}

#: Carriers within this fraction above a band's lowest one are of the same band.
BAND_SPAN: float = 0.25
#: Plausible carrier frequencies [Hz] (the row ``frequency_hz`` of :data:`PLAUSIBLE`).
FREQUENCY_BAND_HZ: tuple[float, float] = (PLAUSIBLE["frequency_hz"].low, PLAUSIBLE["frequency_hz"].high)
_UNITS: dict[str, float] = {"Hz": 1.0, "kHz": 1e3, "MHz": 1e6, "GHz": 1e9}


def _at(size: int, row: int, row_offset: int) -> str:
    return f" at row {row + row_offset}" if size > 1 or row_offset else ""


def _prefix(where: str, field: str) -> str:
    return f"{where}: " if where == field else f"{where}: {field} "


@check_types
def check_plausible(
    quantity: str, values: ArrayLike, where: str, param: str | None = None, row_offset: int = 0, field: str | None = None
) -> None:
    """Refuse values of ``quantity`` outside its row of :data:`PLAUSIBLE` (or not finite).

    Parameters
    ----------
    quantity : str
        A key of :data:`PLAUSIBLE`.
    values : array_like
        The values, in the row's unit.
    where : str
        The file, flag or parameter they came from (the message's start).
    param : str, optional
        The parameter at fault (the CLI names its flag).
    row_offset : int
        Number of the first value's row (a chunk of a file).
    field : str, optional
        The column or field named in the message (default ``quantity``).

    Raises
    ------
    InputError
        For the first value outside the range, naming it, its row, the range and why.
    """
    q = PLAUSIBLE[quantity]
    v = np.atleast_1d(np.asarray(values, np.float64)).ravel()
    bad = ~((v >= q.low) & (v <= q.high))
    if not np.any(bad):
        return
    row = int(np.flatnonzero(bad)[0])
    x = float(v[row])
    what = "is not a number" if np.isnan(x) else f"is outside {q.low:g} to {q.high:g} {q.unit}"
    raise InputError(f"{_prefix(where, field or quantity)}{x:g}{_at(v.size, row, row_offset)} {what} ({q.why})", param=param)


@check_types
def check_frequency_hz(
    values: Any, where: str, param: str | None = "frequency_hz", row_offset: int = 0, unit: str = "Hz",
    field: str = "frequency_hz",
) -> None:
    """The one carrier-frequency check: refuse values outside :data:`FREQUENCY_BAND_HZ`.

    Parameters
    ----------
    values : float or array_like
        Carrier frequencies, in ``unit``.
    where : str
        Their source (file, ``file: FREQUENCY``, flag or parameter).
    param : str, optional
        The parameter at fault.
    row_offset : int
        Number of the first value's row.
    unit : {"Hz", "kHz", "MHz", "GHz"}
        The unit the source writes them in (MHz in MSI files).
    field : str
        The column or key named in the message (``FREQUENCY`` in an MSI file); not repeated
        when ``where`` is that name.

    Raises
    ------
    InputError
        Naming the first bad value and its row; a value that would be plausible in another unit
        gets the hint (``2412 looks like MHz (2.412e+09 Hz)``).
    """
    if unit not in _UNITS:
        raise InputError(f"unit: expected one of {', '.join(_UNITS)}, got {unit!r}", param="unit")
    scale = _UNITS[unit]
    f = np.atleast_1d(np.asarray(values, np.float64)).ravel()
    lo, hi = FREQUENCY_BAND_HZ
    bad = ~((f * scale >= lo) & (f * scale <= hi))
    if not np.any(bad):
        return
    row = int(np.flatnonzero(bad)[0])
    v = float(f[row])
    prefix, at = _prefix(where, field), _at(f.size, row, row_offset)
    if not (np.isfinite(v) and v > 0):
        raise InputError(f"{prefix}expected a positive frequency in {unit}, got {v:g}{at}", param=param)
    hints = [f"{u} ({v * s:g} Hz)" for u, s in _UNITS.items() if u != unit and lo <= v * s <= hi]
    hint = f"; {v:g} looks like {' or '.join(hints)}" if hints else ""
    raise InputError(f"{prefix}{v:g}{at} is not a radio carrier in {unit} (expected {lo / scale:g} to {hi / scale:g} {unit}){hint}",
                     param=param)


@check_types
def frequency_bands(frequency_hz: ArrayLike | Mapping[float, int]) -> tuple[tuple[float, float, int], ...]:
    """The bands of a set of carriers: ``(lowest, highest, count)`` each, lowest band first.

    ``frequency_hz`` is an array of carriers (one per sample) or a mapping of carrier to its
    sample count. A band holds the carriers within :data:`BAND_SPAN` of its lowest one.
    """
    if isinstance(frequency_hz, Mapping):
        values = np.array(sorted(frequency_hz), np.float64)
        counts = np.array([frequency_hz[k] for k in sorted(frequency_hz)], np.int64)
    else:
        try:
            carriers = np.asarray(frequency_hz, np.float64).ravel()
        except (TypeError, ValueError):
            raise InputError(f"frequency_hz: expected carrier frequencies in Hz, got {type(frequency_hz).__name__}",
                             param="frequency_hz") from None
        values, counts = np.unique(carriers, return_counts=True)
    keep = np.isfinite(values)
    values, counts = values[keep], counts[keep]
    bands: list[tuple[float, float, int]] = []
    for v, n in zip(values.tolist(), counts.tolist(), strict=True):
        if bands and v <= bands[-1][0] * (1.0 + BAND_SPAN):
            lo, _, m = bands[-1]
            bands[-1] = (lo, v, m + int(n))
        else:
            bands.append((v, v, int(n)))
    return tuple(bands)


@check_types
def describe_band(low_hz: float, high_hz: float) -> str:
    """``2.412 GHz`` or ``2.412-2.462 GHz`` (MHz below 1 GHz)."""
    scale, unit = (1e9, "GHz") if low_hz >= 1e9 else (1e6, "MHz")
    lo, hi = f"{low_hz / scale:.4g}", f"{high_hz / scale:.4g}"
    return f"{lo} {unit}" if lo == hi else f"{lo}-{hi} {unit}"


@check_types
def check_one_band(frequency_hz: ArrayLike | Mapping[float, int], where: str, param: str | None = None) -> None:
    """Refuse carriers of more than one band (:func:`frequency_bands`), counting each band's samples.

    Antenna patterns change with frequency: a model learns one band. ``frequency_hz`` is as for
    :func:`frequency_bands`.
    """
    bands = frequency_bands(frequency_hz)
    if len(bands) > 1:
        listed = ", ".join(f"{describe_band(lo, hi)} ({n:,} samples)" for lo, hi, n in bands)
        raise InputError(f"{where}: carriers of {len(bands)} bands: {listed}; antenna patterns change with frequency, "
                         "so learn one band at a time (the rows or parts of one band)", param=param)


@check_types
def same_band(a_hz: float, b_hz: float) -> bool:
    """Whether two carriers are of one band (the higher within :data:`BAND_SPAN` of the lower)."""
    lo, hi = sorted((float(a_hz), float(b_hz)))
    return hi <= lo * (1.0 + BAND_SPAN)


@check_types
def check_same_band(used_hz: float, learned_hz: float | None, where: str, what: str, param: str | None = "frequency_hz") -> None:
    """Refuse using at ``used_hz`` a pattern ``what`` learned at ``learned_hz`` of another band.

    Nothing is checked when ``learned_hz`` is None (the pattern does not state its carrier).
    """
    if learned_hz is None:
        return
    if not same_band(used_hz, learned_hz):
        raise InputError(f"{where}: {describe_band(used_hz, used_hz)}, but {what} learned at "
                         f"{describe_band(learned_hz, learned_hz)}; antenna patterns change with frequency "
                         "(use a model of this band)", param=param)


@check_types
def check_covariance(covariance: ArrayLike, where: str) -> None:
    """Refuse a covariance matrix that is not square, holds a missing (null, NaN) or infinite
    entry, or has a negative variance on its diagonal (read from a file: checked without a copy
    of the matrix)."""
    c = np.asarray(covariance, np.float64)
    if c.ndim != 2 or c.shape[0] != c.shape[1]:
        raise InputError(f"{where}: covariance: expected a square matrix, got shape {c.shape}")
    if not np.isfinite(np.sum(c)):
        i, j = (int(k) for k in np.argwhere(~np.isfinite(c))[0])
        raise InputError(f"{where}: covariance: entry ({i}, {j}) is {c[i, j]} (missing or not finite)")
    d = np.diag(c)
    if np.any(d < 0):
        i = int(np.flatnonzero(d < 0)[0])
        raise InputError(f"{where}: covariance: the variance on the diagonal at {i} is negative ({d[i]:g})")


__all__ = [
    "BAND_SPAN", "FREQUENCY_BAND_HZ", "PLAUSIBLE", "Plausible", "check_covariance", "check_frequency_hz",
    "check_one_band", "check_plausible", "check_same_band", "describe_band", "frequency_bands", "same_band",
]
