"""The environment term of a link: what the path does beyond free space (``fit --path-loss``).

The paper assumes free space (eq. 1): the observed joint gain ``y = P_rx - P_tx + FSPL(d)``
(eq. 5) is then ``G_tx + G_rx``. Real links near the ground are not free space, and at a fixed
altitude distance and elevation move together, so a loss that grows faster than ``20 log10 d``
would be learned as a pattern that falls with elevation. Two terms, both in dB added to the
joint gain:

- **log-distance** (:data:`PATH_LOSS_KINDS` ``"log-distance"``): ``PL(d) = FSPL(d0) + 10 n
  log10(d / d0)`` with ``d0`` = :data:`REFERENCE_DISTANCE_M` (1 m). Relative to free space
  this adds ``(n - 2) * (-10 log10(d / d0))`` to the joint gain: one shared column
  (:func:`log_distance_column`) whose coefficient is ``n - 2``, learned with the patterns.
- **two-ray** (``"two-ray"``): the direct ray plus one ray reflected off flat ground at a stated
  level (:func:`two_ray_excess_db`): ``20 log10 |1 + Gamma (d / d_r) exp(-j k (d_r - d))|``,
  with the Fresnel reflection coefficient ``Gamma`` of the grazing angle for a stated relative
  permittivity (default :data:`DEFAULT_RELATIVE_PERMITTIVITY`, average ground) and polarization
  (default vertical, as of the upright whips of most drones). Known from the geometry: nothing
  is learned, it is subtracted before the fit and added to every prediction. The antennas'
  gains toward the ground image are taken equal to those along the direct ray (the patterns are
  what is being learned), which is what a two-ray model assumes.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from rplearn._argtypes import check_types
from rplearn.core.link import wavelength_m
from rplearn.core.plausible import check_plausible
from rplearn.errors import BadValueError, InputError

FloatArray = NDArray[np.float64]

#: Environment terms ``fit --path-loss`` accepts.
PATH_LOSS_KINDS: tuple[str, ...] = ("free", "log-distance", "two-ray")
#: Reference distance ``d0`` of the log-distance model [m]: free space up to it.
REFERENCE_DISTANCE_M = 1.0
#: Relative permittivity of the ground by default: ITU-R P.527 "medium dry ground" (15); wet
#: ground is about 30, very dry ground 3-7, sea water 70.
DEFAULT_RELATIVE_PERMITTIVITY = 15.0
#: Polarizations of the two-ray reflection coefficient.
POLARIZATIONS: tuple[str, ...] = ("vertical", "horizontal")
#: The two-ray term is floored here [dB]: the exact null of two equal rays is -infinity, which
#: no receiver reports and a position error of a centimetre moves.
TWO_RAY_FLOOR_DB = -40.0


@check_types
def log_distance_column(distance_m: ArrayLike) -> FloatArray:
    """The log-distance regressor ``-10 log10(d / d0)`` [dB per unit of exponent]: the joint
    gain changes by ``(n - 2)`` times it when the path-loss exponent is ``n`` instead of 2."""
    d = np.asarray(distance_m, np.float64)
    if np.any(~(d > 0)):
        raise InputError("distance_m: expected positive distances for the log-distance term", param="distance_m")
    return -10.0 * np.log10(d / REFERENCE_DISTANCE_M)


@check_types
def reflection_coefficient(sin_grazing: ArrayLike, relative_permittivity: float, polarization: str = "vertical") -> NDArray[np.complex128]:
    """Fresnel reflection coefficient of flat ground at a grazing angle (``sin psi``)."""
    s = np.asarray(sin_grazing, np.float64)
    eps = complex(relative_permittivity)
    root = np.sqrt(eps - (1.0 - s**2))
    if polarization == "vertical":
        return (eps * s - root) / (eps * s + root)
    if polarization == "horizontal":
        return (s - root) / (s + root)
    raise BadValueError(f"polarization: expected {' or '.join(POLARIZATIONS)}, got {polarization!r}", param="polarization")


@check_types
def two_ray_excess_db(
    distance_m: ArrayLike,
    tx_height_m: ArrayLike,
    rx_height_m: ArrayLike,
    frequency_hz: ArrayLike,
    relative_permittivity: float = DEFAULT_RELATIVE_PERMITTIVITY,
    polarization: str = "vertical",
    gain_ratio: ArrayLike = 1.0,
) -> FloatArray:
    """Gain of the two-ray ground-reflection channel over free space [dB].

    Parameters
    ----------
    distance_m : array_like
        Length of the direct ray [m].
    tx_height_m, rx_height_m : array_like
        Heights of the two antennas above the ground plane [m] (positive).
    frequency_hz : array_like
        Carrier frequency [Hz].
    relative_permittivity : float
        Of the ground (real part; at least 1).
    polarization : {"vertical", "horizontal"}
    gain_ratio : array_like
        Amplitude of the antennas' gains along the reflected ray relative to the direct ray
        (1: equal, what a fit assumes; the simulator passes the true one).

    Returns
    -------
    ndarray
        ``20 log10 |1 + Gamma (d / d_r) exp(-j 2 pi (d_r - d) / lambda)|``, floored at
        :data:`TWO_RAY_FLOOR_DB`.
    """
    d = np.asarray(distance_m, np.float64)
    ht = np.asarray(tx_height_m, np.float64)
    hr = np.asarray(rx_height_m, np.float64)
    if not (np.isfinite(relative_permittivity) and relative_permittivity >= 1.0):
        raise InputError(f"relative permittivity: expected a number >= 1, got {relative_permittivity!r}",
                         param="relative_permittivity")
    for name, h in (("tx height above the ground", ht), ("rx height above the ground", hr)):
        if np.any(~(h > 0)):
            bad = np.asarray(h)[~(np.asarray(h) > 0)].ravel()
            raise InputError(f"two-ray: {name} must be positive; {bad.size} sample(s) at or below the ground level "
                             f"(lowest {float(np.nanmin(bad)) if np.any(np.isfinite(bad)) else float('nan'):.2f} m "
                             "above it): state the ground level below every antenna", param="ground_level_m")
    rho2 = np.maximum(d**2 - (ht - hr) ** 2, 0.0)  # squared horizontal distance
    d_r = np.sqrt(rho2 + (ht + hr) ** 2)
    gamma = reflection_coefficient((ht + hr) / d_r, relative_permittivity, polarization)
    phase = 2.0 * np.pi * (d_r - d) / wavelength_m(frequency_hz)
    field = 1.0 + gamma * np.asarray(gain_ratio, np.float64) * (d / d_r) * np.exp(-1j * phase)
    return np.maximum(20.0 * np.log10(np.maximum(np.abs(field), 1e-300)), TWO_RAY_FLOOR_DB)


@check_types
@dataclass(frozen=True)
class PathLoss:
    """Which environment term a fit uses, and its stated parameters.

    Attributes
    ----------
    kind : {"free", "log-distance", "two-ray"}
    ground_level_m : float
        ENU height of the ground plane [m] (two-ray).
    relative_permittivity : float
        Of the ground (two-ray).
    polarization : {"vertical", "horizontal"}
        Of the two-ray reflection coefficient.
    """

    kind: str = "free"
    ground_level_m: float = 0.0
    relative_permittivity: float = DEFAULT_RELATIVE_PERMITTIVITY
    polarization: str = "vertical"

    def __post_init__(self) -> None:
        if self.kind not in PATH_LOSS_KINDS:
            raise BadValueError(f"path loss: expected {', '.join(PATH_LOSS_KINDS)}, got {self.kind!r}", param="path_loss")
        if not np.isfinite(self.ground_level_m):
            raise InputError(f"ground level: expected a finite height in metres, got {self.ground_level_m!r}",
                             param="ground_level_m")
        check_plausible("position_m", self.ground_level_m, "ground_level_m", param="ground_level_m")
        if not (np.isfinite(self.relative_permittivity) and self.relative_permittivity >= 1.0):
            raise InputError(f"relative permittivity: expected a number >= 1, got {self.relative_permittivity!r}",
                             param="relative_permittivity")
        if self.polarization not in POLARIZATIONS:
            raise BadValueError(f"polarization: expected {' or '.join(POLARIZATIONS)}, got {self.polarization!r}",
                             param="polarization")

    @property
    def learns_exponent(self) -> bool:
        """Whether the term adds a shared column (the log-distance exponent)."""
        return self.kind == "log-distance"

    def known_db(
        self, distance_m: ArrayLike, tx_z_m: ArrayLike | None, rx_z_m: ArrayLike | None, frequency_hz: ArrayLike | None,
        strict: bool = True,
    ) -> FloatArray | None:
        """The part of the term that is known from the geometry [dB] (two-ray), or None.

        ``strict`` (learning): an antenna at or below the ground level is an error; otherwise
        (predicting) its samples get NaN.
        """
        if self.kind != "two-ray":
            return None
        if tx_z_m is None or rx_z_m is None:
            raise InputError("two-ray: the samples carry no antenna heights (tx_z, rx_z)", param="path_loss")
        if frequency_hz is None:
            raise InputError("two-ray: the samples carry no carrier frequency (frequency_hz)", param="path_loss")
        ht = np.asarray(tx_z_m, np.float64) - self.ground_level_m
        hr = np.asarray(rx_z_m, np.float64) - self.ground_level_m
        if strict:
            return two_ray_excess_db(distance_m, ht, hr, frequency_hz, self.relative_permittivity, self.polarization)
        above = (ht > 0) & (hr > 0)
        out = np.full(np.broadcast(ht, hr).shape, np.nan)
        if np.any(above):
            d, f = np.broadcast_arrays(np.asarray(distance_m, np.float64), np.asarray(frequency_hz, np.float64), ht)[:2]
            out[above] = two_ray_excess_db(d[above], ht[above], hr[above], f[above], self.relative_permittivity,
                                           self.polarization)
        return out

    def check_heights(self, z_m: ArrayLike, where: str, field: str = "z") -> None:
        """Refuse antennas at or below the two-ray ground (or more than 50 km above it): a
        prediction there would be NaN. Nothing to check for the other kinds."""
        if self.kind != "two-ray":
            return
        h = np.asarray(z_m, np.float64) - self.ground_level_m
        check_plausible("height_above_ground_m", h, where, field=f"{field} above the two-ray ground at {self.ground_level_m:g} m")

    def describe(self) -> str:
        """One line for summaries."""
        if self.kind == "free":
            return "free space (eq. 1)"
        if self.kind == "log-distance":
            return f"log-distance (exponent learned, d0 = {REFERENCE_DISTANCE_M:g} m)"
        return (f"two-ray ground reflection (ground at {self.ground_level_m:g} m, relative permittivity "
                f"{self.relative_permittivity:g}, {self.polarization} polarization)")

    def to_dict(self) -> dict[str, Any]:
        out: dict[str, Any] = {"kind": self.kind}
        if self.kind == "two-ray":
            out.update(ground_level_m=self.ground_level_m, relative_permittivity=self.relative_permittivity,
                       polarization=self.polarization)
        if self.kind == "log-distance":
            out["reference_distance_m"] = REFERENCE_DISTANCE_M
        return out

    @classmethod
    def from_dict(cls, payload: Mapping[str, Any] | None) -> PathLoss:
        """Rebuild from :meth:`to_dict` (None or an empty mapping: free space)."""
        if payload is None or (isinstance(payload, Mapping) and not payload):
            return cls()
        if not isinstance(payload, Mapping):
            raise InputError(f"path loss: expected a mapping with 'kind', got {type(payload).__name__}", param="path_loss")
        try:
            return cls(
                kind=str(payload.get("kind", "free")),
                ground_level_m=float(payload.get("ground_level_m", 0.0)),
                relative_permittivity=float(payload.get("relative_permittivity", DEFAULT_RELATIVE_PERMITTIVITY)),
                polarization=str(payload.get("polarization", "vertical")),
            )
        except (TypeError, ValueError) as exc:
            raise InputError(f"path loss: malformed ({exc})", param="path_loss") from None


__all__ = [
    "DEFAULT_RELATIVE_PERMITTIVITY",
    "PATH_LOSS_KINDS",
    "POLARIZATIONS",
    "REFERENCE_DISTANCE_M",
    "TWO_RAY_FLOOR_DB",
    "PathLoss",
    "log_distance_column",
    "reflection_coefficient",
    "two_ray_excess_db",
]
