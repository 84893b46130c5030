"""The ground station of a MAVLink log (``.tlog`` or DataFlash), for :mod:`rplearn.io.mavlink`: where it stood
(given, the vehicle's home, else its first valid fix) and the GPS accuracy the log reports for the fix that placed
it (``station_accuracy_m``: :func:`rplearn.io.damage.one_station` takes two flights' stations within that noise for
one station, as a ULog's, :mod:`rplearn.io.ulog_radio`).

The accuracy is read where the log gives it in metres: a ``.tlog``'s ``GPS_RAW_INT`` ``h_acc``/``v_acc`` [mm]
(MAVLink 2 extension fields), a DataFlash log's ``GPA`` ``HAcc``/``VAcc`` [m]. ``GPS_RAW_INT`` ``eph``/``epv`` and
DataFlash ``HDop``/``VDop`` are dilutions of precision (unitless): no accuracy, so a log reporting only those (the
project's real MAVLink 1 ``.tlog`` fixtures: ``eph`` 158-331, ``epv`` unknown) reports none, and two of its
flights' stations must agree to :data:`~rplearn.data.poses.SAME_POSITION_M`.
"""

from __future__ import annotations

import numpy as np

from rplearn.io._mavlink_records import Raw


def accuracy_at(accuracy: np.ndarray, t: float | None) -> tuple[float, float] | None:
    """The GPS accuracy (horizontal, vertical standard deviations [m]) of the latest of ``accuracy``'s rows (``t``,
    horizontal, vertical) reporting both at or before ``t`` [s], else of the first; None when none does."""
    if t is None or not len(accuracy):
        return None
    ok = accuracy[np.all(np.isfinite(accuracy), axis=1) & np.all(accuracy[:, 1:] > 0, axis=1)]
    if not len(ok):
        return None
    ok = ok[np.argsort(ok[:, 0], kind="stable")]
    i = max(int(np.searchsorted(ok[:, 0], t, side="right")) - 1, 0)
    return float(ok[i, 1]), float(ok[i, 2])


def station_fix(raw: Raw, station_geodetic: tuple[float, float, float] | None, first_fix: np.ndarray
                ) -> tuple[tuple[float, float, float], str, tuple[float, float] | None]:
    """Geodetic position of the ground station (lat, lon [deg], alt [m]), where it came from, and the GPS accuracy
    the log reports for the fix that placed it (None: given, or none reported). ``first_fix``: the vehicle's first
    valid position row (time [s], lat, lon, alt, ...)."""
    if station_geodetic is not None:
        return station_geodetic, "station position given (ReaderOptions.station_geodetic)", None
    home = "HOME_POSITION" if raw.fmt == "tlog" else "ORGN type 1 (home)"
    if raw.home is not None:
        return raw.home, f"station placed at the vehicle's home from {home}", accuracy_at(raw.accuracy, raw.home_t)
    lat, lon, alt = (float(v) for v in first_fix[1:4])
    return ((lat, lon, alt), f"station placed at the vehicle's first position fix (no {home} in the log)",
            accuracy_at(raw.accuracy, float(first_fix[0])))


__all__ = ["accuracy_at", "station_fix"]
