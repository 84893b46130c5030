"""Measured or vendor antenna patterns ("reference patterns") as gains at body-frame directions.

Formats (docs/conventions.md, "Reference pattern"), chosen by content:

- CSV with ``az_deg, el_deg, gain_dbi`` (or ``gain_db``): directions already in the drone's
  body frame (FLU; azimuth counter-clockwise from forward, elevation up). rplearn's own grid
  export (``node, az_deg, el_deg, gain_db``) is of this kind; give the node to read when it holds
  several.
- CSV with ``phi_deg`` or ``phi_rad``, ``theta_deg`` or ``theta_rad``, ``gain_dbi``: the
  antenna's own spherical frame, theta measured from the antenna's +z axis, phi from its +x
  axis towards +y (the convention of chamber measurements and of most vendor files).
- MSI Planet (``.msi``, ``.pln``, ``.txt`` with an MSI header), e.g. as written by
  ``rplearn export --format msi``: the horizontal and vertical cuts, gain = reference gain
  minus loss, at the directions of :func:`~rplearn.io.msi.msi_horizontal_directions_rad`
  and :func:`~rplearn.io.msi.msi_vertical_directions_rad`.

A **mounting rotation** ``(roll, pitch, yaw)`` [deg] says how the antenna is mounted on the drone:
the rotation of the antenna frame in the body frame, applied as for an attitude (yaw about z,
then pitch about y, then roll about x; :func:`~rplearn.core.geometry.quat_wxyz_from_euler_enu_flu_deg`).
An antenna hanging upside down is ``(180, 0, 0)``: its +z axis (theta = 0) points down the
body's -z axis. The mount applies to every format (identity by default).
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pandas as pd

from rplearn.core.geometry import quat_wxyz_from_euler_enu_flu_deg, rotate_body_to_world
from rplearn.core.plausible import check_frequency_hz, check_plausible
from rplearn.errors import InputError
from rplearn.io.msi import msi_horizontal_directions_rad, msi_vertical_directions_rad, read_msi

_MSI_EXTENSIONS = (".msi", ".pln", ".ant", ".txt")


@dataclass(frozen=True)
class ReferenceSamples:
    """Gains of one antenna at body-frame directions.

    Attributes
    ----------
    az_rad, el_rad : ndarray
        Body-frame directions [rad] (after the mount).
    gain_dbi : ndarray
        Gain [dBi].
    source : str
    frequency_hz : float or None
        The pattern's frequency when the file states it.
    """

    az_rad: np.ndarray
    el_rad: np.ndarray
    gain_dbi: np.ndarray
    source: str
    frequency_hz: float | None = None

    def __len__(self) -> int:
        return int(self.gain_dbi.size)


#: A reference pattern needs at least this many distinct measured directions.
MIN_REFERENCE_DIRECTIONS = 12
#: One direction measured twice with gains further apart than this is refused [dB].
REPEAT_GAIN_TOLERANCE_DB = 6.0


def mount_rotation(az_rad: np.ndarray, el_rad: np.ndarray, mount_rpy_deg: Sequence[float]) -> tuple[np.ndarray, np.ndarray]:
    """Antenna-frame directions [rad] expressed in the body frame through the mount rotation."""
    rpy = np.asarray(mount_rpy_deg, np.float64).ravel()
    if rpy.size != 3 or not np.all(np.isfinite(rpy)):
        raise InputError(f"mount: expected roll, pitch, yaw in degrees, got {list(mount_rpy_deg)!r}", param="mount")
    check_plausible("mount_deg", rpy, "mount", param="mount", field="angle")
    q = quat_wxyz_from_euler_enu_flu_deg(rpy[0], rpy[1], rpy[2])
    ce = np.cos(el_rad)
    v = np.stack([ce * np.cos(az_rad), ce * np.sin(az_rad), np.sin(el_rad)], axis=-1)
    b = rotate_body_to_world(np.broadcast_to(q, v.shape[:-1] + (4,)), v)
    return np.arctan2(b[..., 1], b[..., 0]), np.arcsin(np.clip(b[..., 2], -1.0, 1.0))


def _angle(df: pd.DataFrame, name: str, source: str) -> np.ndarray:
    if f"{name}_deg" in df.columns and f"{name}_rad" in df.columns:
        raise InputError(f"{source}: both columns {name}_deg and {name}_rad; keep one")
    if f"{name}_deg" in df.columns:
        return np.radians(_degrees(df, f"{name}_deg", source))
    v = _numbers(df, f"{name}_rad", source)
    if v.size and float(np.max(np.abs(v))) > 2 * np.pi + 1e-6:
        raise InputError(f"{source}: column {name}_rad holds {float(np.max(np.abs(v))):g}, beyond 2 pi: degrees? "
                         f"name the column {name}_deg")
    return v


def _degrees(df: pd.DataFrame, column: str, source: str) -> np.ndarray:
    """A ``*_deg`` column, refused when it reads as radians (every value within 2 pi, several distinct)."""
    v = _numbers(df, column, source)
    if np.unique(v).size >= 4 and float(np.max(np.abs(v))) <= 2 * np.pi + 1e-9:
        raise InputError(f"{source}: column {column} spans only {float(v.min()):g} to {float(v.max()):g}: radians? "
                         f"give degrees (or name the column {column[:-4]}_rad where the format allows it)")
    return v


def _check_measured(az: np.ndarray, el: np.ndarray, gain: np.ndarray, path: str, gain_col: str) -> None:
    """Plausible gains, enough distinct directions, no direction measured twice with gains far apart."""
    check_plausible("gain_dbi", gain, path, field=gain_col)
    ce = np.cos(el)
    v = np.round(np.stack([ce * np.cos(az), ce * np.sin(az), np.sin(el)], axis=-1), 6) + 0.0  # -0.0 is 0.0
    keys, first, inverse = np.unique(v, axis=0, return_index=True, return_inverse=True)
    if keys.shape[0] < MIN_REFERENCE_DIRECTIONS:
        raise InputError(f"{path}: {keys.shape[0]} distinct measured direction(s); a pattern needs at least "
                         f"{MIN_REFERENCE_DIRECTIONS} (e.g. a horizontal and a vertical cut)")
    inverse = inverse.ravel()
    lo, hi = np.full(keys.shape[0], np.inf), np.full(keys.shape[0], -np.inf)
    np.minimum.at(lo, inverse, gain)
    np.maximum.at(hi, inverse, gain)
    spread = hi - lo
    if np.any(spread > REPEAT_GAIN_TOLERANCE_DB):
        k = int(np.argmax(spread))
        rows = np.flatnonzero(inverse == k)[:2]
        raise InputError(f"{path}: rows {rows[0]} and {rows[1]} measure one direction with {gain_col} "
                         f"{gain[rows[0]]:g} and {gain[rows[1]]:g} ({spread[k]:.1f} dB apart, more than "
                         f"{REPEAT_GAIN_TOLERANCE_DB:g}): two patterns in one file?")


def _numbers(df: pd.DataFrame, column: str, source: str) -> np.ndarray:
    v = pd.to_numeric(df[column], errors="coerce").to_numpy(np.float64)
    bad = ~np.isfinite(v)
    if np.any(bad):
        row = int(np.flatnonzero(bad)[0])
        raise InputError(f"{source}: column {column} holds a missing or non-numeric value at row {row}")
    return v


def _csv_frequency(df: pd.DataFrame, path: str) -> float | None:
    """The carrier of a CSV pattern with a ``frequency_hz`` column: one, and a radio carrier."""
    if "frequency_hz" not in df.columns:
        return None
    f = _numbers(df, "frequency_hz", path)
    check_frequency_hz(f, path, None)
    if np.unique(f).size > 1:
        raise InputError(f"{path}: column frequency_hz holds {np.unique(f).size} carriers; one pattern is of one frequency")
    return float(f[0]) if f.size else None


def _read_csv(path: str, node: str | None) -> tuple[np.ndarray, np.ndarray, np.ndarray, float | None]:
    """(az, el) in the file's frame, gain and the optional carrier of a CSV pattern; ``el`` from
    theta when antenna-framed."""
    try:
        df = pd.read_csv(path, skipinitialspace=True)
    except Exception as exc:
        raise InputError(f"{path}: cannot read the pattern ({type(exc).__name__}: {str(exc).splitlines()[0] if str(exc) else ''})") from None
    if {"gain_dbi", "gain_db"} <= set(df.columns):
        raise InputError(f"{path}: both columns gain_dbi and gain_db; keep one")
    gain_col = "gain_dbi" if "gain_dbi" in df.columns else "gain_db" if "gain_db" in df.columns else None
    if gain_col is None:
        raise InputError(f"{path}: missing column gain_dbi; expected az_deg, el_deg, gain_dbi or phi_deg, theta_deg, gain_dbi")
    if "node" in df.columns:
        nodes = sorted(df["node"].astype(str).unique())
        if node is None and len(nodes) > 1:
            raise InputError(f"{path}: holds the patterns of {', '.join(nodes)}; say which node to read", param="node")
        chosen = str(node) if node is not None and len(nodes) > 1 else nodes[0]  # one pattern: whatever its name
        if chosen not in nodes:
            raise InputError(f"{path}: no pattern of node {chosen}; it holds {', '.join(nodes)}", param="node")
        df = df[df["node"].astype(str) == chosen]
    body = {"az_deg", "el_deg"} & set(df.columns)
    antenna = {f"{a}_{u}" for a in ("phi", "theta") for u in ("deg", "rad")} & set(df.columns)
    if body and antenna:
        raise InputError(f"{path}: both body-frame ({', '.join(sorted(body))}) and antenna-frame "
                         f"({', '.join(sorted(antenna))}) direction columns; keep one frame")
    if {"az_deg", "el_deg"} <= set(df.columns):
        az, el = np.radians(_degrees(df, "az_deg", path)), np.radians(_degrees(df, "el_deg", path))
        if np.any(np.abs(el) > np.pi / 2 + 1e-9):
            raise InputError(f"{path}: column el_deg outside [-90, 90] degrees")
    elif any(f"phi_{u}" in df.columns for u in ("deg", "rad")) and any(f"theta_{u}" in df.columns for u in ("deg", "rad")):
        phi, theta = _angle(df, "phi", path), _angle(df, "theta", path)
        if np.any(theta < -1e-9) or np.any(theta > np.pi + 1e-9):
            raise InputError(f"{path}: theta outside [0, 180] degrees (measured from the antenna's +z axis)")
        az, el = phi, np.pi / 2 - theta
    else:
        raise InputError(f"{path}: missing direction columns; expected az_deg, el_deg (body frame) or "
                         "phi_deg|phi_rad, theta_deg|theta_rad (antenna frame)")
    gain = _numbers(df, gain_col, path)
    if gain.size == 0:
        raise InputError(f"{path}: no pattern rows")
    _check_measured(az, el, gain, path, gain_col)
    return az, el, gain, _csv_frequency(df, path)


def _read_msi(path: str) -> tuple[np.ndarray, np.ndarray, np.ndarray, float | None]:
    msi = read_msi(path)
    angles = np.arange(360.0)
    az_h, el_h = msi_horizontal_directions_rad(angles)
    az_v, el_v = msi_vertical_directions_rad(angles)
    az = np.concatenate([az_h, az_v])
    el = np.concatenate([el_h, el_v])
    gain = msi.gain_dbi - np.concatenate([msi.horizontal_loss_db, msi.vertical_loss_db])
    check_plausible("gain_dbi", gain, path, field="gain (GAIN less the cut's loss)")
    f = None if not np.isfinite(msi.frequency_mhz) else float(msi.frequency_mhz) * 1e6
    return az, el, gain, f


def read_reference_pattern(
    path: str | os.PathLike[str], mount_rpy_deg: Sequence[float] = (0.0, 0.0, 0.0), node: str | None = None
) -> ReferenceSamples:
    """Read a reference pattern (CSV or MSI Planet) as gains at body-frame directions.

    Parameters
    ----------
    path : path
        The pattern file (see the module docstring for the formats).
    mount_rpy_deg : (roll, pitch, yaw)
        Mounting rotation of the antenna frame in the body frame [deg].
    node : str, optional
        The node to read from a grid export holding several (a file of one node is read
        whatever its node is named).
    """
    source = os.fspath(path)
    if not os.path.isfile(source):
        raise InputError(f"{source}: no such file")
    frequency = None
    if source.lower().endswith(".csv"):
        az, el, gain, frequency = _read_csv(source, node)
    elif source.lower().endswith(_MSI_EXTENSIONS):
        az, el, gain, frequency = _read_msi(source)
    else:
        raise InputError(f"{source}: unknown pattern format; name it .csv (az/el or phi/theta) or .msi (MSI Planet)")
    az, el = mount_rotation(az, el, mount_rpy_deg)
    return ReferenceSamples(az, el, gain, source, frequency)


__all__ = ["MIN_REFERENCE_DIRECTIONS", "REPEAT_GAIN_TOLERANCE_DB", "ReferenceSamples", "mount_rotation", "read_reference_pattern"]
