"""MSI Planet antenna files (``.msi``, also ``.pln``): the reader and the writer.

An ASCII file: header lines ``KEY value`` (``NAME`` first; ``FREQUENCY`` in MHz; ``GAIN`` in
dBd unless followed by ``dBi``), then ``HORIZONTAL 360`` and 360 lines ``angle loss`` for
angles 0..359 deg, then ``VERTICAL 360`` likewise. A loss is the attenuation [dB] relative to
``GAIN``, written as a positive number without sign. Sources: the Radio Mobile definition page
of the format (radiomobile.pe1mew.nl, "The program: Definitions: MSI": 360 points per cut,
"zero degrees represents North for the Horizontal pattern and ... the horizon for the Vertical
pattern", gain in dBd unless marked dBi, losses relative to the maximum without minus sign);
the CPAN reader RF::Antenna::Planet::MSI::Format (FREQUENCY may carry ``MHz``/``GHz``, GAIN
``dBd``/``dBi``, some vendors omit the NAME token); and the MSI reader of crc-covlib
(ic-crc/crc-covlib, ``crc_covlib/helper/antennas.py``), which documents the vertical cut as
0 = horizon of the front lobe, 90 = nadir, 180 = horizon of the back lobe, 270 = zenith.

Angle conventions of the files this module writes (and assumes when it reads)
-----------------------------------------------------------------------------
The antenna is the node's body frame FLU (x forward, y left, z up); "boresight" is forward.

- Horizontal cut (the body's x-y plane, ``el = 0``): MSI angle ``h`` [deg] is 0 at forward
  and increases *clockwise seen from above* (towards the right, like a compass bearing from
  north), so our azimuth (counter-clockwise, +90 = left) is ``az = -h`` wrapped to
  (-180, 180]: ``h = 90`` is right (``az = -90``), ``h = 270`` is left (``az = +90``).
- Vertical cut (the body's x-z plane, through forward and up): MSI angle ``v`` [deg] is 0 at
  the forward horizon and increases *downwards*: ``v = 90`` nadir (``el = -90``), ``v = 180``
  the backward horizon (``az = 180, el = 0``), ``v = 270`` zenith (``el = +90``). So the
  direction is ``x = cos v, z = -sin v``; for ``v`` in [0, 90] ``el = -v``, for ``v`` in
  [270, 360) ``el = 360 - v``.
- ``GAIN`` is written in dBi: the largest gain of the node over the sphere (1 deg grid) and
  both cuts; every loss is ``GAIN - G(direction)`` >= 0. For a two-node fit only the shape is
  identified (paper Sec. V-A), so the absolute GAIN is then the gauge's choice (noted in
  ``COMMENT``).
"""

from __future__ import annotations

import math
import os
import re
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from rplearn._argtypes import check_types
from rplearn._atomic import atomic_open
from rplearn._version import __version__
from rplearn.core.geometry import wrap_angle_rad
from rplearn.core.plausible import check_frequency_hz, check_plausible, check_same_band
from rplearn.errors import InputError
from rplearn.io.export import PatternLike, check_pattern_like, grid_angles_deg, node_file_names, select_nodes

FloatArray = NDArray[np.float64]

MSI_N_ANGLES = 360
DBD_TO_DBI = 2.15
_LOSS_DECIMALS = 2
_KNOWN_KEYS = frozenset(
    [
        "NAME",
        "MAKE",
        "FREQUENCY",
        "H_WIDTH",
        "V_WIDTH",
        "FRONT_TO_BACK",
        "GAIN",
        "TILT",
        "POLARIZATION",
        "COMMENT",
        "HORIZONTAL",
        "VERTICAL",
    ]
)


@check_types
@dataclass
class MsiPattern:
    """Horizontal and vertical cuts of one antenna, as in an MSI Planet file.

    Attributes
    ----------
    name : str
    frequency_mhz : float
        NaN when the file gives none.
    gain_dbi : float
        Reference (peak) gain [dBi] (a file's dBd value is converted with +2.15 dB).
    horizontal_loss_db, vertical_loss_db : ndarray, shape (360,)
        Attenuation relative to ``gain_dbi`` [dB] (positive) at MSI angles 0..359 deg; see the
        module docstring for the angle conventions.
    header : dict of str -> str
        Every header line as written (keys upper case), e.g. ``{"GAIN": "5.00 dBi"}``.
    """

    name: str
    frequency_mhz: float
    gain_dbi: float
    horizontal_loss_db: FloatArray
    vertical_loss_db: FloatArray
    header: dict[str, str] = field(default_factory=dict)


def msi_horizontal_directions_rad(angle_deg: ArrayLike) -> tuple[FloatArray, FloatArray]:
    """Body-frame (az, el) [rad] of MSI horizontal angles [deg] (clockwise from forward)."""
    az = wrap_angle_rad(-np.radians(np.asarray(angle_deg, np.float64)))
    return az, np.zeros_like(az)


def msi_vertical_directions_rad(angle_deg: ArrayLike) -> tuple[FloatArray, FloatArray]:
    """Body-frame (az, el) [rad] of MSI vertical angles [deg] (0 forward horizon, 90 nadir)."""
    v = np.radians(np.asarray(angle_deg, np.float64))
    x, z = np.cos(v), -np.sin(v)
    x = np.where(np.abs(x) < 1e-12, 0.0, x)
    az = np.where(x < 0, np.pi, 0.0)
    el = np.arctan2(z, np.abs(x))
    return az, el


# -- the file: read and write ------------------------------------------------------------
_NUMBER = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?"


def _parse_frequency_mhz(text: str, where: str) -> float:
    m = re.fullmatch(rf"\s*({_NUMBER})\s*(hz|khz|mhz|ghz)?\s*", text, re.IGNORECASE)
    if not m:
        raise InputError(f"{where}: FREQUENCY: expected a number [MHz], got {text!r}")
    scale = {None: 1.0, "hz": 1e-6, "khz": 1e-3, "mhz": 1.0, "ghz": 1e3}[
        m.group(2).lower() if m.group(2) else None
    ]
    value = float(m.group(1)) * scale
    check_frequency_hz(value, where, None, unit="MHz", field="FREQUENCY")
    return value


def _parse_gain_dbi(text: str, where: str) -> float:
    m = re.fullmatch(rf"\s*({_NUMBER})\s*(dbi|dbd)?\s*", text, re.IGNORECASE)
    if not m:
        raise InputError(f"{where}: GAIN: expected a number with optional dBi/dBd, got {text!r}")
    value = float(m.group(1))
    value = value if (m.group(2) or "").lower() == "dbi" else value + DBD_TO_DBI
    check_plausible("gain_dbi", value, where, field="GAIN")
    return value


@check_types
def read_msi(path: str | os.PathLike[str]) -> MsiPattern:
    """Read an MSI Planet antenna file (see the module docstring for the format).

    Header keys are case-insensitive; a first line without a known key is taken as the name
    (some vendors omit the ``NAME`` token). Lines end in CR LF or LF.
    Both cuts must hold 360 lines ``angle loss`` with angles 0..359 in order and losses >= 0
    (rounding to -0.005 tolerated). A GAIN without unit is dBd (converted to dBi).

    Raises
    ------
    InputError
        One line naming the file and line number, for any malformed content.
    """
    path = os.fspath(path)
    try:
        with open(path, encoding="latin-1") as f:
            raw = f.read().splitlines()
    except OSError as exc:
        raise InputError(f"{path}: cannot read MSI file ({exc.strerror})") from None
    header: dict[str, str] = {}
    header_line: dict[str, int] = {}
    cuts: dict[str, FloatArray] = {}
    i = 0
    while i < len(raw):
        line = raw[i].strip()
        where = f"{path}:{i + 1}"
        i += 1
        if not line:
            continue
        parts = line.split(None, 1)
        key, value = parts[0], (parts[1].strip() if len(parts) > 1 else "")
        key_u = key.upper()
        if key_u in ("HORIZONTAL", "VERTICAL"):
            if key_u in cuts:
                raise InputError(f"{where}: second {key_u} section")
            try:
                n = int(value.split()[0])
            except (ValueError, IndexError):
                raise InputError(f"{where}: expected '{key_u} 360', got {line!r}") from None
            if n != MSI_N_ANGLES:
                raise InputError(f"{where}: expected {MSI_N_ANGLES} points in {key_u}, got {n}")
            cut = np.empty(n)
            for k in range(n):
                if i >= len(raw):
                    raise InputError(f"{path}:{i}: {key_u} ends after {k} of {n} points")
                row, where_row = raw[i].split(), f"{path}:{i + 1}"
                i += 1
                try:
                    if len(row) != 2:
                        raise ValueError
                    angle, loss = float(row[0]), float(row[1])
                except ValueError:
                    raise InputError(
                        f"{where_row}: expected '<angle> <loss>' in {key_u}, got {raw[i - 1].strip()!r}"
                    ) from None
                if not abs(angle - k) <= 1e-6:
                    raise InputError(f"{where_row}: expected angle {k} in {key_u}, got {row[0]}")
                if not math.isfinite(loss) or loss < -0.005:
                    raise InputError(
                        f"{where_row}: loss must be a finite attenuation >= 0 dB, got {row[1]}"
                    )
                cut[k] = max(loss, 0.0)
            cuts[key_u] = cut
            continue
        if re.fullmatch(_NUMBER, key):
            raise InputError(
                f"{where}: unexpected data line {line!r} outside a HORIZONTAL/VERTICAL section of {MSI_N_ANGLES} points"
            )
        if not header and key_u not in _KNOWN_KEYS:
            header["NAME"] = line  # some vendors omit the NAME token on the first line
            header_line["NAME"] = i
            continue
        if key_u in header:
            raise InputError(f"{where}: repeated header key {key_u}")
        header[key_u] = value
        header_line[key_u] = i
    for needed in ("HORIZONTAL", "VERTICAL"):
        if needed not in cuts:
            raise InputError(f"{path}:{len(raw)}: no {needed} section")
    if "GAIN" not in header:
        raise InputError(f"{path}:1: no GAIN line")
    gain = _parse_gain_dbi(header["GAIN"], f"{path}:{header_line['GAIN']}")
    freq = (
        _parse_frequency_mhz(header["FREQUENCY"], f"{path}:{header_line['FREQUENCY']}")
        if "FREQUENCY" in header
        else float("nan")
    )
    return MsiPattern(
        header.get("NAME", ""), freq, gain, cuts["HORIZONTAL"], cuts["VERTICAL"], header
    )


def _fmt_loss(v: float) -> str:
    s = f"{max(v, 0.0):.{_LOSS_DECIMALS}f}"
    return "0.00" if s == "-0.00" else s


@check_types
def write_msi(msi: MsiPattern, path: str | os.PathLike[str]) -> str:
    """Write an :class:`MsiPattern` as an MSI Planet file; return the path.

    ASCII, CR LF line ends (the format comes from Windows tools), losses with 2 decimals.
    """
    for key, cut in (("horizontal", msi.horizontal_loss_db), ("vertical", msi.vertical_loss_db)):
        if np.shape(cut) != (MSI_N_ANGLES,):
            raise InputError(
                f"{key}_loss_db: expected {MSI_N_ANGLES} values, got shape {np.shape(cut)}"
            )
    header = dict(msi.header)
    header["NAME"] = msi.name
    lines = [f"NAME {msi.name}"]
    lines += [f"{k} {v}" for k, v in header.items() if k != "NAME"]
    for title, cut in (("HORIZONTAL", msi.horizontal_loss_db), ("VERTICAL", msi.vertical_loss_db)):
        lines.append(f"{title} {MSI_N_ANGLES}")
        lines += [f"{a} {_fmt_loss(float(v))}" for a, v in enumerate(cut)]
    path = os.fspath(path)
    with atomic_open(path, "w", encoding="ascii", errors="replace", newline="\r\n") as f:
        f.write("\n".join(lines) + "\n")
    return path


# -- a pattern's cuts as MSI files -----------------------------------------------------------
def peak_gain_dbi(pattern_like: Any, node: str, step_deg: float = 1.0) -> float:
    """Largest gain of ``node`` on a regular az-el grid [dBi]."""
    az, el = grid_angles_deg(step_deg)
    el_g, az_g = np.meshgrid(np.radians(el), np.radians(az), indexing="ij")
    return float(np.nanmax(pattern_like.evaluate(node, az_g, el_g)))


@check_types
def msi_pattern(
    pattern_like: Any,
    node: str,
    frequency_hz: float,
    name: str | None = None,
    comment: str | None = None,
) -> MsiPattern:
    """Horizontal and vertical cuts of one node in MSI Planet terms (see module docstring).

    Parameters
    ----------
    pattern_like : pattern-like
    node : str
    frequency_hz : float
        Carrier frequency [Hz] (written in MHz).
    name : str, optional
        Antenna name (default ``rplearn_<node>``).
    comment : str, optional
        Free text appended to the ``COMMENT`` line.
    """
    check_pattern_like(pattern_like)
    node = select_nodes(pattern_like, [node])[0]
    check_frequency_hz(frequency_hz, "frequency_hz")
    angles = np.arange(MSI_N_ANGLES, dtype=np.float64)
    g_h = np.asarray(
        pattern_like.evaluate(node, *msi_horizontal_directions_rad(angles)), np.float64
    ).ravel()
    g_v = np.asarray(
        pattern_like.evaluate(node, *msi_vertical_directions_rad(angles)), np.float64
    ).ravel()
    if not (np.isfinite(g_h).all() and np.isfinite(g_v).all()):
        raise InputError(f"node {node}: the pattern is not finite on the MSI cuts")
    gain = max(peak_gain_dbi(pattern_like, node), float(g_h.max()), float(g_v.max()))
    name = name or f"rplearn_{node}"
    if any(c in name for c in "\r\n"):
        raise InputError("name: must be one line")
    notes = [
        f"rplearn {__version__}; node {node}; body frame FLU",
        "H-cut 0 deg = forward, clockwise seen from above (90 = right)",
        "V-cut 0 deg = forward horizon, 90 = nadir, 180 = back horizon, 270 = zenith",
    ]
    if getattr(pattern_like, "gauge", None):
        notes.append("two-node fit: absolute gain not identified, shape only (paper Sec. V-A)")
    if comment:
        notes.append(" ".join(str(comment).split()))
    freq_mhz = float(frequency_hz) / 1e6
    header = {
        "NAME": name,
        "MAKE": "rplearn",
        "FREQUENCY": f"{freq_mhz:.6f}".rstrip("0").rstrip("."),
        "GAIN": f"{gain:.2f} dBi",
        "COMMENT": "; ".join(notes),
    }
    return MsiPattern(
        name, freq_mhz, round(gain, 2), round(gain, 2) - g_h, round(gain, 2) - g_v, header
    )


@check_types
def export_msi(
    pattern_like: Any,
    node: str,
    path: str | os.PathLike[str],
    frequency_hz: float | None = None,
    name: str | None = None,
    comment: str | None = None,
) -> MsiPattern:
    """Write the horizontal and vertical cuts of one node as an MSI Planet file.

    Parameters
    ----------
    pattern_like : pattern-like
    node : str
    path : path
        File to write (``.msi`` by convention).
    frequency_hz : float, optional
        Carrier [Hz]; default the pattern's ``frequency_hz`` (a ``GroundTruth``'s carrier, the
        carrier a learned model was learned at); an error if none is known.
    name, comment : str, optional

    Returns
    -------
    MsiPattern
        What was written (before rounding of the losses to 0.01 dB).
    """
    if frequency_hz is None:
        frequency_hz = _frequency_of(pattern_like)
    msi = msi_pattern(pattern_like, node, frequency_hz, name, comment)
    write_msi(msi, path)
    return msi


@check_types
def export_msi_files(
    pattern_like: Any, out_dir: str | os.PathLike[str], frequency_hz: float | None = None
) -> list[str]:
    """One MSI Planet file per node, ``<out_dir>/<node>.msi`` (``rplearn export --format msi``).

    Parameters
    ----------
    pattern_like : pattern-like
        A learned model or a ground truth.
    out_dir : path
        Directory (created if needed).
    frequency_hz : float, optional
        Carrier written into the files [Hz]; default the pattern's own.

    Returns
    -------
    list of str
        The paths written, in node order.
    """
    check_pattern_like(pattern_like)
    if frequency_hz is None:
        frequency_hz = _frequency_of(pattern_like)
    else:
        check_frequency_hz(frequency_hz, "frequency_hz")
        learned = getattr(pattern_like, "frequency_hz", None)
        check_same_band(float(frequency_hz), None if learned is None else float(learned), "frequency_hz",
                        f"the {getattr(pattern_like, 'label', 'pattern')} model")
    check_frequency_hz(frequency_hz, "frequency_hz")
    os.makedirs(out_dir, exist_ok=True)
    label = getattr(pattern_like, "label", "pattern")
    paths = []
    for node, name in node_file_names(select_nodes(pattern_like, None)).items():
        path = os.path.join(os.fspath(out_dir), f"{name}.msi")
        export_msi(
            pattern_like,
            node,
            path,
            frequency_hz=float(frequency_hz),
            name=f"rplearn {label} node {node}",
        )
        paths.append(path)
    return paths


def _frequency_of(pattern_like: PatternLike) -> float:
    """The pattern's optional ``frequency_hz`` [Hz] (see the module docstring)."""
    f = getattr(pattern_like, "frequency_hz", None)
    if f is None:
        raise InputError(
            "the pattern does not state its frequency; give it (frequency_hz)", param="frequency_hz"
        )
    return float(f)
