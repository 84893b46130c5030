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


def mount_rotation(az_rad: np.ndarray, el_rad: np.ndarray, mount_rpy_deg: Sequence[float]) -> tuple[np.ndarray, np.ndarray]:
    """Antenna-frame directions [rad] expressed in the body frame through the mount rotation."""
    rpy = np.asarray(mount_rpy_deg, np.float64).ravel()
    if rpy.size != 3 or not np.all(np.isfinite(rpy)):
        raise InputError(f"mount: expected roll, pitch, yaw in degrees, got {list(mount_rpy_deg)!r}", param="mount")
    q = quat_wxyz_from_euler_enu_flu_deg(rpy[0], rpy[1], rpy[2])
    ce = np.cos(el_rad)
    v = np.stack([ce * np.cos(az_rad), ce * np.sin(az_rad), np.sin(el_rad)], axis=-1)
    b = rotate_body_to_world(np.broadcast_to(q, v.shape[:-1] + (4,)), v)
    return np.arctan2(b[..., 1], b[..., 0]), np.arcsin(np.clip(b[..., 2], -1.0, 1.0))


def _angle(df: pd.DataFrame, name: str, source: str) -> np.ndarray:
    if f"{name}_deg" in df.columns:
        return np.radians(_numbers(df, f"{name}_deg", source))
    return _numbers(df, f"{name}_rad", source)


def _numbers(df: pd.DataFrame, column: str, source: str) -> np.ndarray:
    v = pd.to_numeric(df[column], errors="coerce").to_numpy(np.float64)
    bad = ~np.isfinite(v)
    if np.any(bad):
        row = int(np.flatnonzero(bad)[0])
        raise InputError(f"{source}: column {column} holds a missing or non-numeric value at row {row}")
    return v


def _read_csv(path: str, node: str | None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(az, el) in the file's frame and gain of a CSV pattern; ``el`` from theta when antenna-framed."""
    try:
        df = pd.read_csv(path, skipinitialspace=True)
    except Exception as exc:
        raise InputError(f"{path}: cannot read the pattern ({type(exc).__name__}: {str(exc).splitlines()[0] if str(exc) else ''})") from None
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
    if {"az_deg", "el_deg"} <= set(df.columns):
        az, el = np.radians(_numbers(df, "az_deg", path)), np.radians(_numbers(df, "el_deg", path))
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
    return az, el, gain


def _read_msi(path: str) -> tuple[np.ndarray, np.ndarray, np.ndarray, float | None]:
    msi = read_msi(path)
    angles = np.arange(360.0)
    az_h, el_h = msi_horizontal_directions_rad(angles)
    az_v, el_v = msi_vertical_directions_rad(angles)
    az = np.concatenate([az_h, az_v])
    el = np.concatenate([el_h, el_v])
    gain = msi.gain_dbi - np.concatenate([msi.horizontal_loss_db, msi.vertical_loss_db])
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
        az, el, gain = _read_csv(source, node)
    elif source.lower().endswith(_MSI_EXTENSIONS):
        az, el, gain, frequency = _read_msi(source)
    else:
        raise InputError(f"{source}: unknown pattern format; name it .csv (az/el or phi/theta) or .msi (MSI Planet)")
    az, el = mount_rotation(az, el, mount_rpy_deg)
    return ReferenceSamples(az, el, gain, source, frequency)


__all__ = ["ReferenceSamples", "mount_rotation", "read_reference_pattern"]
