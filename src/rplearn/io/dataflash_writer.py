"""Canonical pose and signal logs -> a binary ArduPilot DataFlash log (``.bin``).

The DataFlash counterpart of :func:`rplearn.io.tlog.write_tlog`, for tests of the reader
(:func:`rplearn.io.mavlink.read_mavlink`) on simulated flights with the defects of real
autopilot logs. pymavlink reads DataFlash logs (``DFReader``) but has no writer; the format
is small: records ``A3 95 <type> <payload>``, each type declared first by an ``FMT`` record
(type 128, 89 bytes: ``B type, B length, 4s name, 16s format, 64s columns``), little-endian.

What is written, with ``TimeUS`` [us] on the autopilot's boot clock (zero
:data:`~rplearn.io.tlog.BOOT_LEAD_S` before the first row):

- ``ATT`` (Roll, Pitch, Yaw [deg], NED/FRD) and ``POS`` (Lat, Lng [deg], Alt [m AMSL]) per
  vehicle pose row;
- ``ORGN`` type 0 (EKF origin) and type 1 (home, the station's position) when the position
  becomes valid, and ``ARM`` (ArmState 1) then; ``ARM`` 0 at the start when it is not valid yet;
- ``GPA`` (HAcc, VAcc [m]) per vehicle pose row with ``TlogDefects.fix_accuracy_m``;
- ``RAD`` per signal row, as the air radio reports it (``RSSI`` = the vehicle receiving,
  ``RemRSSI`` = the station receiving, the other 255), written twice (as ArduPilot does)
  with ``TlogDefects.radio_twice``, ``copy_delay_s`` apart.

:class:`~rplearn.io.tlog.TlogDefects` sets the defects (``invalid_until_s``,
``invalid_alt_m``, ``radio_twice``, ``copy_delay_s``); a reboot inside one DataFlash file is
not written (``reboot_at_s`` is refused: ArduPilot starts a new file at boot).
"""

from __future__ import annotations

import os
import struct
from typing import Any

import numpy as np

from rplearn._argtypes import check_types
from rplearn._atomic import atomic_open
from rplearn.core.geometry import enu_to_ned
from rplearn.errors import InputError
from rplearn.io._common import Logs
from rplearn.io.geodetic import local_ned_to_geodetic
from rplearn.io.tlog import BOOT_LEAD_S, TlogDefects, checked_logs, dbm_to_sik_rssi, station_pose, vehicle_fields

_HEAD = b"\xa3\x95"
#: name -> (type, struct format, DataFlash format, columns)
_FORMATS: dict[str, tuple[int, str, str, str]] = {
    "FMT": (128, "BB4s16s64s", "BBnNZ", "Type,Length,Name,Format,Columns"),
    "ATT": (129, "Qfff", "Qfff", "TimeUS,Roll,Pitch,Yaw"),
    "POS": (130, "Qiif", "QLLf", "TimeUS,Lat,Lng,Alt"),
    "RAD": (131, "QBBBBBHH", "QBBBBBHH", "TimeUS,RSSI,RemRSSI,TxBuf,Noise,RemNoise,RxErrors,Fixed"),
    "ORGN": (132, "QBiif", "QBLLf", "TimeUS,Type,Lat,Lng,Alt"),
    "ARM": (133, "QB", "QB", "TimeUS,ArmState"),
    "GPA": (134, "QHH", "QCC", "TimeUS,HAcc,VAcc"),  # C: uint16 x 0.01 [m]
}


def _record(name: str, *values: Any) -> bytes:
    kind, fmt, _, _ = _FORMATS[name]
    return _HEAD + bytes([kind]) + struct.pack("<" + fmt, *values)


def _fmt_records() -> list[bytes]:
    out = []
    for name, (kind, fmt, df_fmt, cols) in _FORMATS.items():
        length = 3 + struct.calcsize("<" + fmt)
        out.append(_record("FMT", kind, length, name.encode(), df_fmt.encode(), cols.encode()))
    return out


@check_types
def write_dataflash(
    logs: Logs,
    path: str | os.PathLike,
    vehicle: str,
    station: str,
    origin_geodetic: tuple[float, float, float],
    defects: TlogDefects | None = None,
) -> dict[str, Any]:
    """Write a vehicle's poses and its telemetry link to a static station as a DataFlash log
    (module docstring).

    Parameters
    ----------
    logs : Logs
        Pose log (the vehicle's rows and the station's) and signal log (the two directions
        between them only), canonical schemas.
    path : str or PathLike
        Output ``.bin``; written atomically.
    vehicle, station : str
        Node ids of the vehicle and the ground station.
    origin_geodetic : (lat_deg, lon_deg, alt_m)
        Geodetic position of the logs' ENU origin (altitude AMSL).
    defects : TlogDefects, optional
        ``invalid_until_s``, ``invalid_alt_m``, ``radio_twice``, ``copy_delay_s`` and ``fix_accuracy_m``.

    Returns
    -------
    dict
        Records written per type, ``rssi_clipped``, ``station_geodetic``,
        ``station_heading_deg`` and ``clock_offset_s`` (the log's time minus the logs' time [s]).

    Raises
    ------
    InputError
        As :func:`rplearn.io.tlog.write_tlog`; on a reboot in ``defects`` (``param`` "defects").
    """
    defects = defects or TlogDefects()
    if not isinstance(defects, TlogDefects) or defects.reboot_at_s is not None:
        raise InputError("defects: a DataFlash file holds one boot; give a TlogDefects without reboot_at_s",
                         param="defects")
    pose, signal = checked_logs(logs, vehicle, station, origin_geodetic)
    origin = tuple(float(v) for v in origin_geodetic)
    v = vehicle_fields(pose, vehicle, origin)  # type: ignore[arg-type]
    t0 = float(min(v["t"][0], signal["t"].min())) - BOOT_LEAD_S
    us = np.rint((v["t"] - t0) * 1e6).astype(np.int64)
    _, invalid, _ = defects.phases(v["t"] - v["t"][0])
    alt = np.where(invalid, defects.invalid_alt_m, v["alt"])
    sxyz, heading, _ = station_pose(pose, station)
    slat, slon, salt = (float(x) for x in local_ned_to_geodetic(enu_to_ned(sxyz), origin))  # type: ignore[arg-type]
    records: list[tuple[int, int, bytes]] = []
    first_valid = int(np.flatnonzero(~invalid)[0]) if np.any(~invalid) else None
    if invalid[0]:
        records.append((int(us[0]), 0, _record("ARM", int(us[0]), 0)))
    if first_valid is not None:
        at = int(us[first_valid])
        for kind in (0, 1):
            records.append((at, 0, _record("ORGN", at, kind, int(round(slat * 1e7)), int(round(slon * 1e7)), salt)))
        records.append((at, 0, _record("ARM", at, 1)))
    roll, pitch, yaw = (np.degrees(v[k]) for k in ("roll", "pitch", "yaw"))
    for i in range(len(us)):
        records.append((int(us[i]), 1, _record("ATT", int(us[i]), roll[i], pitch[i], yaw[i])))
        records.append((int(us[i]), 2, _record("POS", int(us[i]), int(round(v["lat"][i] * 1e7)),
                                               int(round(v["lon"][i] * 1e7)), float(alt[i]))))
        if defects.fix_accuracy_m is not None:
            records.append((int(us[i]), 2, _record("GPA", int(us[i]), *(int(round(a * 100)) for a in defects.fix_accuracy_m))))
    raw, clipped = dbm_to_sik_rssi(signal["rssi_dbm"].to_numpy(np.float64))
    at_vehicle = (signal["rx"] == vehicle).to_numpy()
    sig_us = np.rint((signal["t"].to_numpy(np.float64) - t0) * 1e6).astype(np.int64)
    copies = 2 if defects.radio_twice else 1
    for i in range(len(signal)):
        rssi, rem = (int(raw[i]), 255) if at_vehicle[i] else (255, int(raw[i]))
        for c in range(copies):
            at = int(sig_us[i] + c * round(defects.copy_delay_s * 1e6))
            records.append((at, 3, _record("RAD", at, rssi, rem, 100, 0, 0, 0, 0)))
    records.sort(key=lambda r: (r[0], r[1]))
    with atomic_open(path, "wb", param="path") as fh:
        fh.write(b"".join(_fmt_records()))
        fh.write(b"".join(r[2] for r in records))
    return {"att": len(us), "pos": len(us), "rad": copies * len(signal), "rssi_clipped": clipped,
            "gpa": len(us) if defects.fix_accuracy_m is not None else 0,
            "invalid_position_rows": int(invalid.sum()), "station_geodetic": (slat, slon, salt),
            "station_heading_deg": heading, "clock_offset_s": -t0}


__all__ = ["write_dataflash"]
