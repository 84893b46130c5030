"""Geodetic coordinates (WGS-84) to local frames, for log readers; pymap3d is imported only
when these are called."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from rplearn._argtypes import check_types
from rplearn.core.geometry import ned_to_enu
from rplearn.core.plausible import PLAUSIBLE, check_plausible

FloatArray = NDArray[np.float64]


@check_types
def geodetic_to_enu(
    lat_deg: ArrayLike,
    lon_deg: ArrayLike,
    alt_m: ArrayLike,
    origin_geodetic: tuple[float, float, float],
    where: str = "geodetic position",
) -> FloatArray:
    """Geodetic positions (WGS-84 latitude, longitude [deg], ellipsoidal or AMSL altitude [m],
    the same datum as the origin) -> local ENU positions (..., 3) [m] around ``origin_geodetic``
    = (lat0 [deg], lon0 [deg], alt0 [m]).

    The positions and the origin are checked against the plausibility table
    (:data:`rplearn.core.plausible.PLAUSIBLE`: latitude, longitude, altitude); ``where`` starts
    the message. (Logs of several places may share one origin: distances from it are the
    readers' to check, e.g. a vehicle's from its station.)
    """
    import pymap3d

    lat, lon, alt = (np.asarray(v, np.float64) for v in (lat_deg, lon_deg, alt_m))
    for quantity, field, values in (("latitude_deg", "latitude", lat), ("longitude_deg", "longitude", lon),
                                    ("altitude_m", "altitude", alt)):
        # a missing value (NaN) is the reader's to count; a wrong one is refused here
        check_plausible(quantity, np.where(np.isnan(values), PLAUSIBLE[quantity].low, values), where,
                        field=f"{field} [{PLAUSIBLE[quantity].unit}]")
    lat0, lon0, alt0 = (float(v) for v in origin_geodetic)
    for quantity, field, value in (("latitude_deg", "latitude", lat0), ("longitude_deg", "longitude", lon0),
                                   ("altitude_m", "altitude", alt0)):
        check_plausible(quantity, value, where, field=f"origin {field} [{PLAUSIBLE[quantity].unit}]")
    e, n, u = pymap3d.geodetic2enu(lat, lon, alt, lat0, lon0, alt0)
    enu = np.stack([np.asarray(e, np.float64), np.asarray(n, np.float64), np.asarray(u, np.float64)], axis=-1)
    return enu


def local_ned_to_geodetic(
    position_xyz_ned: ArrayLike, anchor_geodetic: tuple[float, float, float]
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Local NED positions (..., 3) [m] of a frame anchored at ``anchor_geodetic`` -> (lat [deg],
    lon [deg], alt [m]). PX4's ``vehicle_local_position`` is such a frame."""
    import pymap3d

    v = np.asarray(position_xyz_ned, np.float64)
    lat0, lon0, alt0 = (float(a) for a in anchor_geodetic)
    lat, lon, alt = pymap3d.ned2geodetic(v[..., 0], v[..., 1], v[..., 2], lat0, lon0, alt0)
    return np.asarray(lat, np.float64), np.asarray(lon, np.float64), np.asarray(alt, np.float64)


def local_ned_to_enu(
    position_xyz_ned: ArrayLike,
    anchor_geodetic: tuple[float, float, float],
    origin_geodetic: tuple[float, float, float] | None = None,
) -> FloatArray:
    """Local NED positions anchored at ``anchor_geodetic`` -> ENU [m] around ``origin_geodetic``.

    Without an origin (or with the anchor as origin) this is :func:`ned_to_enu`; otherwise the
    positions go through geodetic coordinates, which puts several vehicles in one frame.
    """
    if origin_geodetic is None or tuple(map(float, origin_geodetic)) == tuple(map(float, anchor_geodetic)):
        return ned_to_enu(position_xyz_ned)
    lat, lon, alt = local_ned_to_geodetic(position_xyz_ned, anchor_geodetic)
    return geodetic_to_enu(lat, lon, alt, origin_geodetic)
