"""Geodetic coordinates (WGS-84) to local frames, for log readers; pymap3d is imported only
when these are called."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from rplearn._argtypes import check_types
from rplearn.core.geometry import ned_to_enu

FloatArray = NDArray[np.float64]


@check_types
def geodetic_to_enu(
    lat_deg: ArrayLike,
    lon_deg: ArrayLike,
    alt_m: ArrayLike,
    origin_geodetic: tuple[float, float, float],
) -> FloatArray:
    """Geodetic positions (WGS-84 latitude, longitude [deg], ellipsoidal or AMSL altitude [m],
    the same datum as the origin) -> local ENU positions (..., 3) [m] around ``origin_geodetic``
    = (lat0 [deg], lon0 [deg], alt0 [m])."""
    import pymap3d

    lat0, lon0, alt0 = (float(v) for v in origin_geodetic)
    e, n, u = pymap3d.geodetic2enu(
        np.asarray(lat_deg, np.float64), np.asarray(lon_deg, np.float64),
        np.asarray(alt_m, np.float64), lat0, lon0, alt0,
    )
    return np.stack([np.asarray(e, np.float64), np.asarray(n, np.float64), np.asarray(u, np.float64)], axis=-1)


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
