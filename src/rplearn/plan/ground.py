"""A drone flying passes in front of a static ground station: the narrow view of real campaigns.

Unlike the paper's calibration unit (two drones sweeping every heading, :class:`TrajectoryUnit`),
a ground pass sees little of either antenna: the station sees the drone within a small azimuth
sector at one elevation (set by the altitude), and the drone sees the station in a band of
headings around its nose, below the horizon. This is how most real link measurements are
flown (a ground antenna, one drone at a few altitudes), and what a pattern learner must survive
without extrapolating wildly.

The unit has the interface the simulator and the reference writer use: ``nodes``, ``label``,
``role``, ``duration_s`` and :meth:`GroundPassUnit.sample` returning a
:class:`~rplearn.plan.trajectory.UnitReference` (the station is node 0 and stands still).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rplearn._argtypes import check_types
from rplearn.errors import InputError
from rplearn.plan.trajectory import UnitReference, check_unit_fields


@check_types
@dataclass(frozen=True)
class GroundPassUnit:
    """A drone flying back and forth along an arc in front of a static ground station.

    Attributes
    ----------
    nodes : (str, str)
        The ground station (static, node 0) and the drone.
    distance_m : float
        Horizontal distance from the station to the drone's arc [m].
    height_m : float
        Drone altitude [m].
    station_height_m : float
        Height of the station's antenna [m].
    arc_deg : float
        Width of the arc, centred on the station's forward direction [deg].
    heading_band_deg : float
        The drone's yaw swings within this band around facing the station [deg].
    speed_m_s : float
        Speed along the arc at its middle [m/s].
    n_passes : int
        Passes along the arc (there and back is two).
    station_yaw_deg : float
        Heading of the station (ENU, ccw from east) [deg]; the arc is centred on it.
    label, role : str
    """

    nodes: tuple[str, str] = ("G", "D")
    distance_m: float = 40.0
    height_m: float = 20.0
    station_height_m: float = 1.5
    arc_deg: float = 30.0
    heading_band_deg: float = 40.0
    speed_m_s: float = 2.0
    n_passes: int = 6
    station_yaw_deg: float = 0.0
    label: str = ""
    role: str = "learning"

    def __post_init__(self) -> None:
        check_unit_fields(self, ("distance_m", "height_m", "station_height_m", "arc_deg", "speed_m_s"))
        if not (0.0 <= self.heading_band_deg <= 360.0):
            raise InputError(f"heading_band_deg: expected 0..360, got {self.heading_band_deg!r}", param="heading_band_deg")
        if int(self.n_passes) != self.n_passes or self.n_passes < 1:
            raise InputError(f"n_passes: expected a positive integer, got {self.n_passes!r}", param="n_passes")
        if self.role not in ("learning", "testing"):
            raise InputError(f"role: expected 'learning' or 'testing', got {self.role!r}", param="role")

    @property
    def pass_s(self) -> float:
        """Duration of one pass along the arc [s] (a cosine profile: speed_m_s at the middle)."""
        half_width_m = np.radians(self.arc_deg) / 2.0 * self.distance_m
        return float(np.pi * half_width_m / self.speed_m_s)

    @property
    def duration_s(self) -> float:
        return float(self.n_passes * self.pass_s)

    def sample(self, rate_hz: float, t_offset_s: float = 0.0) -> UnitReference:
        """References of the station (node 0) and the drone at ``rate_hz`` [Hz]."""
        t = np.arange(0.0, self.duration_s, 1.0 / rate_hz)
        return self.evaluate(t, t_offset_s)

    def evaluate(self, t_rel_s: np.ndarray, t_offset_s: float = 0.0) -> UnitReference:
        """References at unit times ``t_rel_s`` [s]."""
        t = np.asarray(t_rel_s, np.float64)
        n = t.size
        yaw0 = np.radians(self.station_yaw_deg)
        half = np.radians(self.arc_deg) / 2.0
        w = np.pi / self.pass_s  # one pass = half a period of the arc angle
        phase = -half * np.cos(w * t)  # from one end of the arc to the other and back
        dphase = half * w * np.sin(w * t)
        ddphase = half * w * w * np.cos(w * t)
        ang = yaw0 + phase
        d = self.distance_m
        pos = np.zeros((n, 2, 3))
        vel = np.zeros((n, 2, 3))
        acc = np.zeros((n, 2, 3))
        pos[:, 0, 2] = self.station_height_m
        pos[:, 1] = np.column_stack([d * np.cos(ang), d * np.sin(ang), np.full(n, self.height_m)])
        vel[:, 1] = np.column_stack([-d * np.sin(ang) * dphase, d * np.cos(ang) * dphase, np.zeros(n)])
        acc[:, 1] = np.column_stack([
            -d * (np.cos(ang) * dphase**2 + np.sin(ang) * ddphase),
            d * (-np.sin(ang) * dphase**2 + np.cos(ang) * ddphase),
            np.zeros(n),
        ])
        # the drone faces the station, its yaw swinging over the band at an unrelated rate
        swing = np.radians(self.heading_band_deg) / 2.0 * np.sin(w * t * 0.37 + 0.5)
        facing = np.arctan2(-pos[:, 1, 1], -pos[:, 1, 0])
        yaw = np.column_stack([np.full(n, yaw0), np.angle(np.exp(1j * (facing + swing)))])
        return UnitReference(self, t + t_offset_s, pos, vel, acc, yaw, np.zeros(n, np.int_))


__all__ = ["GroundPassUnit"]
