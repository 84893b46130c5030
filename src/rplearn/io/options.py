"""Options of the log readers (:func:`rplearn.io.read_logs`) as one validated value.

:class:`ReaderOptions` gathers what the readers of every format may need: column renaming of
tables, the common geodetic origin, node ids of files that do not name them, ROS bag topics,
pcap receivers and addresses, constants that some formats do not log, and how strict to be
with NaN, unsorted or flagged pose rows. Every field has a default, so
``ReaderOptions()`` reads self-describing canonical tables.
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from rplearn._argtypes import check_types, is_finite_real
from rplearn.core.plausible import PLAUSIBLE
from rplearn.data.tables import check_frequency_hz, check_tx_power_dbm
from rplearn.errors import BadValueError, InputError

#: Values of :attr:`ReaderOptions.nan_policy`.
NAN_POLICIES: tuple[str, ...] = ("error", "drop")


def _mapping(value: Any, name: str, key_is_path: bool = False) -> dict[Any, Any] | None:
    """A copy of an optional mapping option (keys as ``str`` when they are paths)."""
    if value is None:
        return None
    if not isinstance(value, Mapping):
        raise InputError(f"{name}: expected a mapping, got {type(value).__name__}", param=name)
    if key_is_path:
        return {os.fspath(k) if isinstance(k, os.PathLike) else str(k): v for k, v in value.items()}
    return dict(value)


def check_origin(origin: Any, name: str = "origin_geodetic") -> tuple[float, float, float] | None:
    """A geodetic position as three floats (lat [deg], lon [deg], alt [m]), or None."""
    if origin is None:
        return None
    try:
        values = tuple(origin)
    except TypeError:
        values = ()
    if len(values) != 3 or not all(is_finite_real(v) for v in values):
        raise InputError(
            f"{name}: expected (lat_deg, lon_deg, alt_m), three finite numbers, got {origin!r}",
            param=name,
        )
    lat, lon, alt = (float(v) for v in values)
    if abs(lat) > 90.0 or abs(lon) > 180.0:
        raise InputError(
            f"{name}: latitude must lie in [-90, 90] and longitude in [-180, 180] degrees, "
            f"got ({lat!r}, {lon!r})",
            param=name,
        )
    band = PLAUSIBLE["altitude_m"]
    if not band.low <= alt <= band.high:
        raise InputError(
            f"{name}: altitude {alt:g} m is outside {band.low:g} to {band.high:g} m ({band.why})",
            param=name,
        )
    return lat, lon, alt


def _check_tx_power(value: Any) -> Any:
    """A transmit power [dBm]: None, one finite number, or a mapping of node id to one."""
    if value is None:
        return None
    if isinstance(value, Mapping):
        bad = [str(k) for k, v in value.items() if not is_finite_real(v)]
        if bad:
            raise InputError(
                f"tx_power_dbm: expected finite numbers [dBm], node(s) {', '.join(bad)} have none",
                param="tx_power_dbm",
            )
        return {str(k): float(v) for k, v in value.items()}
    if not is_finite_real(value):
        raise InputError(
            f"tx_power_dbm: expected a finite number [dBm] or a mapping of node id to one, got {value!r}",
            param="tx_power_dbm",
        )
    return value


def _check_rssi_topics(value: Any) -> dict[str, tuple[str, str]] | None:
    """RSSI topics as ``{topic: (tx, rx)}`` with two non-empty node ids each."""
    topics = _mapping(value, "rssi_topics")
    if topics is None:
        return None
    out: dict[str, tuple[str, str]] = {}
    for topic, ends in topics.items():
        pair = tuple(ends) if isinstance(ends, (tuple, list)) else ()
        if len(pair) != 2 or not all(str(e) for e in pair):
            raise InputError(
                f"rssi_topics: topic {topic} must map to (tx, rx), two node ids, got {ends!r}",
                param="rssi_topics",
            )
        out[str(topic)] = (str(pair[0]), str(pair[1]))
    return out


@check_types
@dataclass(frozen=True)
class ReaderOptions:
    """How :func:`rplearn.io.read_logs` reads logs of every format.

    Parameters
    ----------
    columns : mapping of str to str, optional
        Column renaming for CSV/Parquet tables, ``{"their name": "canonical name"}``, applied
        after :data:`rplearn.io.tables.COLUMN_ALIASES`.
    origin_geodetic : (float, float, float), optional
        Common ENU origin (lat [deg], lon [deg], alt [m] above the ellipsoid) for geodetic
        tables and ULogs. By default the first geodetic file's origin (its first fix, or a
        ULog's anchor) is used for all the others.
    nodes : mapping of path to node id, optional
        Node id of a ULog, of the vehicle of a MAVLink log (``.tlog``, DataFlash), or of a
        one-node table without a ``node`` column.
    pose_topics : mapping of topic to node id, optional
        Pose topics of ROS bags (Odometry, PoseStamped or PoseWithCovarianceStamped).
    rssi_topics : mapping of topic to (tx, rx), optional
        RSSI topics of ROS bags: packets from ``tx`` received by ``rx``.
    rssi_field : str
        Field of the RSSI [dBm] in the RSSI topics' messages; dots for nested fields.
    msg_definitions : mapping of type name to .msg path or text, optional
        Custom message types a bag does not describe (``"pkg/msg/Type"``).
    receivers : mapping of path to node id, optional
        Capturing node of every pcap file (and ``rx`` of signal tables without the column).
    address_map : mapping of MAC address to node id, optional
        Transmitter addresses of pcap files; frames from other addresses are dropped.
    tx_power_dbm : float or mapping of node id to float, optional
        Transmit power [dBm] for logs that do not carry it (pcap, bags, tables without the
        column). A mapping (per transmitter) is accepted by pcap and MAVLink files only.
    frequency_hz : float, optional
        Carrier frequency [Hz] for logs that do not carry it.
    nan_policy : {"error", "drop"}
        Pose-table rows with NaN or non-numeric values raise, or are dropped and counted.
    allow_unsorted : bool
        Accept pose tables whose times go backwards within a node, and signal tables whose
        times go backwards within a link (the rows are sorted: rows of a logger that rebooted
        are then matched on its restarted clock).
    require_valid : bool
        Drop ULog local-position rows flagged invalid by the autopilot (``xy_valid`` or
        ``z_valid`` = 0).
    station : str
        Node id of the ground station of MAVLink logs (``.tlog``, DataFlash) and of ULogs read
        with ``ulog_radio``; the vehicle's id comes from ``nodes`` (default ``sys<system id>``).
    station_geodetic : (float, float, float), optional
        Position of that ground station (lat [deg], lon [deg], alt [m] AMSL); by default the
        log's home position, else the vehicle's first fix.
    station_heading_deg : float, optional
        Compass heading of that station's body x axis [deg, clockwise from north]; by default
        90 (east, assumed), which makes its body frame the ENU world frame.
    ulog_radio : bool
        Read the telemetry radio's readings of PX4 ULogs (``radio_status``) as both directions
        of the link between the vehicle and the ground station (``station``, placed as for
        MAVLink logs), with ``tx_power_dbm`` and ``frequency_hz`` (:mod:`rplearn.io.ulog_radio`);
        by default a ULog gives poses only (its readings are counted in a note).

    Raises
    ------
    InputError
        On a value out of its domain; ``param`` names the field at fault.
    """

    columns: Mapping[str, str] | None = None
    origin_geodetic: tuple[float, float, float] | None = None
    nodes: Mapping[str, str] | None = None
    pose_topics: Mapping[str, str] | None = None
    rssi_topics: Mapping[str, tuple[str, str]] | None = None
    rssi_field: str = "rssi"
    msg_definitions: Mapping[str, str] | None = None
    receivers: Mapping[str, str] | None = None
    address_map: Mapping[str, str] | None = None
    tx_power_dbm: float | Mapping[str, float] | None = None
    frequency_hz: float | None = None
    nan_policy: str = "error"
    allow_unsorted: bool = False
    require_valid: bool = False
    station: str = "gcs"
    station_geodetic: tuple[float, float, float] | None = None
    station_heading_deg: float | None = None
    ulog_radio: bool = False

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        for name in ("columns", "pose_topics", "msg_definitions", "address_map"):
            set_(self, name, _mapping(getattr(self, name), name))
        for name in ("nodes", "receivers"):
            set_(self, name, _mapping(getattr(self, name), name, key_is_path=True))
        set_(self, "rssi_topics", _check_rssi_topics(self.rssi_topics))
        set_(self, "origin_geodetic", check_origin(self.origin_geodetic))
        set_(self, "station_geodetic", check_origin(self.station_geodetic, "station_geodetic"))
        if not isinstance(self.station, str) or not self.station.strip():
            raise InputError(f"station: expected a node id, got {self.station!r}", param="station")
        if self.station_heading_deg is not None and not is_finite_real(self.station_heading_deg):
            raise InputError(f"station_heading_deg: expected degrees, got {self.station_heading_deg!r}",
                             param="station_heading_deg")
        set_(self, "tx_power_dbm", _check_tx_power(self.tx_power_dbm))
        if self.frequency_hz is not None and not (is_finite_real(self.frequency_hz) and self.frequency_hz > 0):
            raise InputError(
                f"frequency_hz: expected a positive number of hertz, got {self.frequency_hz!r}",
                param="frequency_hz",
            )
        if self.frequency_hz is not None:
            check_frequency_hz(self.frequency_hz, "frequency_hz")
        if self.tx_power_dbm is not None:
            powers = self.tx_power_dbm.values() if isinstance(self.tx_power_dbm, Mapping) else [self.tx_power_dbm]
            check_tx_power_dbm(list(powers), "tx_power_dbm")
        if not isinstance(self.rssi_field, str) or not self.rssi_field:
            raise InputError(f"rssi_field: expected a field name, got {self.rssi_field!r}", param="rssi_field")
        if self.nan_policy not in NAN_POLICIES:
            raise BadValueError(
                f"nan_policy: expected 'error' or 'drop', got {self.nan_policy!r}", param="nan_policy"
            )
        for name in ("allow_unsorted", "require_valid", "ulog_radio"):
            value = getattr(self, name)
            if not isinstance(value, (bool, int)) or value not in (True, False):
                raise InputError(f"{name}: expected True or False, got {value!r}", param=name)
            set_(self, name, bool(value))


__all__ = ["NAN_POLICIES", "ReaderOptions"]
