"""Ready-made simulation configurations: ``paper``, ``trio``, ``smoke``, ``ground``, ``pathloss``, ``tworay`` and ``campaign``.

- ``paper``: a replica of the paper's campaign (Sec. V): two X500-class drones, both antennas
  vertical, one carrying a camera and the other a wireless sensor, which shadow differently;
  three learning units (psi0 = 0, 24, 48 deg) and one testing unit (psi0 = 36 deg), about
  56,000 learning and 24,000 testing packets per direction, a 10 m/s wind, 20 dBm at 2.4 GHz,
  about 80 packets/s, integer RSSI, a per-direction electronics offset and one brief dropout.
  Sized so that the mean baseline scores near the paper's 11 dB RMSE and k-NN-400 near 4.8 dB.
- ``trio``: three drones with an ITU-R F.1336-5 omni (rec. 2.2), an ITU sectoral (rec. 3.1.1)
  and a high-gain cosine beam, flying the three links of a triangle (absolute gains identifiable).
- ``smoke``: a seconds-long two-drone case for tests (a few thousand packets).
- ``ground``: one static ground station (ITU sectoral) and one drone (the paper's camera drone)
  flying passes along a 30-degree arc 40 m in front of it, its nose within 20 degrees of the
  station, at 15 and 25 m (learning) and 35 m (testing): both antennas are seen in a few
  percent of the sphere, as in most real link measurements (:mod:`rplearn.plan.ground`).

- ``pathloss``: the paper's drones and radio without its offsets, in a channel whose path loss
  grows with a log-distance exponent of 3 (:data:`PATHLOSS_EXPONENT`), flying the paper's
  vertical circles at three distances (6, 10 and 16 m; testing at 12 m), so that the exponent
  can be told apart from the patterns (each circle sees every direction at its own distance).
- ``tworay``: a station (ITU omni on a 5 m mast) and a drone (ITU omni, X500 frame) low over
  flat ground, the ``ground`` preset's passes at 6 and 10 m altitude, 60 and 100 m away
  (learning), and at 8 m, 80 m away (testing): the direct ray and one ground reflection at a
  grazing angle of a few degrees (relative permittivity 15, vertical polarization), with each
  antenna's true gain along the reflected ray.
- ``campaign``: the ``ground`` station and drone over many short flights whose levels differ
  (:data:`CAMPAIGN_LEVEL_STD_DB` RMS, drawn per flight from the seed: another battery, radio
  temperature, cable, ground), as in a real campaign of a dozen flights: learning flights
  along the ``ground`` arc at three altitudes (:data:`CAMPAIGN_HEIGHTS_M`, each flown by
  several flights), and testing flights at the middle altitude along an arc
  (:data:`CAMPAIGN_TEST_ARC_DEG`) wider than the learned one, so that about half of their
  samples look at the station from azimuths no learning flight came within 10 deg of.
  Small (10 packets/s) so that tests can fit it in seconds.

All presets are deterministic for a given seed of :func:`rplearn.sim.flight.simulate`.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace
from typing import Any

from rplearn._argtypes import check_types
from rplearn.errors import BadValueError
from rplearn.plan.campaign import Campaign, group_campaign
from rplearn.plan.trajectory import TrajectoryUnit
from rplearn.sim.antennas import AirframeLobe, AntennaSpec, Mounting, NodeAntenna, antenna_from_name
from rplearn.sim.config import EstimatorConfig, FlightConfig, RadioConfig, SimulationConfig

__all__ = ["CAMPAIGN_FLIGHTS", "CAMPAIGN_HEIGHTS_M", "CAMPAIGN_LEVEL_STD_DB", "CAMPAIGN_TEST_ARC_DEG", "PATHLOSS_EXPONENT", "PATHLOSS_UNITS",
           "PRESET_NAMES", "fine_structure_lobes", "make_preset", "x500_frame_lobes"]


def x500_frame_lobes(battery_az_deg: float = 180.0, arm_depth_db: float = 3.0) -> tuple[AirframeLobe, ...]:
    """Shadowing of an X500-class quadcopter frame seen from an antenna on top of it.

    Four arms at +-45/+-135 deg slightly below the horizon, the battery under the centre,
    the flight controller and GNSS mast above.
    """
    arms = tuple(
        AirframeLobe(az_deg=a, el_deg=-12.0, width_deg=10.0, depth_db=arm_depth_db, label=f"arm {a:g}")
        for a in (45.0, 135.0, -135.0, -45.0)
    )
    return arms + (
        AirframeLobe(az_deg=battery_az_deg, el_deg=-65.0, width_deg=22.0, depth_db=10.0, label="battery"),
        AirframeLobe(az_deg=0.0, el_deg=80.0, width_deg=18.0, depth_db=4.0, label="GNSS mast"),
    )


def fine_structure_lobes(key: int, count: int = 40, width_deg: float = 6.0, depth_db: float = 4.0) -> tuple[AirframeLobe, ...]:
    """Narrow scattering lobes (screws, cables, propeller guards): detail below a SH-10 scale.

    Positions are uniform on the sphere and signs alternate (dips and bumps); ``key`` fixes
    them, so they are part of a drone's identity, not of a flight's randomness.
    """
    import numpy as np

    rng = np.random.default_rng(key)
    v = rng.standard_normal((count, 3))
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    az = np.degrees(np.arctan2(v[:, 1], v[:, 0]))
    el = np.degrees(np.arcsin(v[:, 2]))
    return tuple(
        AirframeLobe(float(a), float(e), width_deg, depth_db * (1 if i % 2 == 0 else -1), label="scattering")
        for i, (a, e) in enumerate(zip(az, el))
    )


def _paper_nodes() -> dict[str, NodeAntenna]:
    # Archer T2U Plus: a short vertical dipole-like whip; modelled by the ITU-R F.1336-5
    # omni peak side-lobe pattern (rec. 2.1), G0 = 2 dBi (theta3 = 68 deg), k = 0.7.
    whip = AntennaSpec(kind="itu_omni_peak", g0_dbi=2.0, k=0.7)
    camera = (
        AirframeLobe(az_deg=0.0, el_deg=-40.0, width_deg=22.0, depth_db=14.0, label="camera gimbal"),
        AirframeLobe(az_deg=25.0, el_deg=5.0, width_deg=14.0, depth_db=5.0, label="camera cable mast"),
        AirframeLobe(az_deg=-100.0, el_deg=10.0, width_deg=30.0, depth_db=-2.5, label="reflection off payload plate"),
    )
    sensor = (
        AirframeLobe(az_deg=100.0, el_deg=25.0, width_deg=25.0, depth_db=12.0, label="sensor box"),
        AirframeLobe(az_deg=-150.0, el_deg=-20.0, width_deg=18.0, depth_db=6.0, label="sensor antenna"),
        AirframeLobe(az_deg=60.0, el_deg=-5.0, width_deg=35.0, depth_db=-2.0, label="reflection off sensor"),
    )
    return {
        "A": NodeAntenna(whip, Mounting.named("vertical"), x500_frame_lobes(180.0) + camera + fine_structure_lobes(1),
                          "X500, camera payload"),
        "B": NodeAntenna(whip, Mounting.named("vertical"), x500_frame_lobes(0.0) + sensor + fine_structure_lobes(2),
                          "X500, sensor payload"),
    }


def _paper() -> SimulationConfig:
    learning = [
        TrajectoryUnit(nodes=("A", "B"), psi0_deg=p, speed_m_s=1.5, role="learning", label=f"learn_{p:g}")
        for p in (0.0, 24.0, 48.0)
    ]
    # the paper's testing unit gave 24,087 samples against ~18,700 per learning unit: flown slower
    testing = [TrajectoryUnit(nodes=("A", "B"), psi0_deg=36.0, speed_m_s=1.12, role="testing", label="test_36")]
    return SimulationConfig(
        name="paper",
        campaign=Campaign(tuple(learning + testing), gap_s=120.0),
        node_antennas=_paper_nodes(),
        flight=FlightConfig(
            tracking_std_m=0.15,
            tracking_tau_s=2.0,
            yaw_tracking_std_deg=1.5,
            wind_speed_m_s=10.0,
            wind_toward_deg=90.0,
            gust_std_m_s=1.5,
            tilt_jitter_deg=1.0,
        ),
        estimator=EstimatorConfig(
            pose_rate_hz=100.0,
            pose_time_jitter_s=0.0005,
            horizontal_noise_std_m=0.015,
            vertical_noise_std_m=0.025,
            yaw_noise_std_deg=3.0,
            tilt_noise_std_deg=0.3,
        ),
        radio=RadioConfig(
            tx_power_dbm=20.0,
            frequency_hz=2.412e9,
            packet_rate_hz=80.0,
            packet_jitter=0.3,
            loss_probability=0.05,
            fading_std_db=4.2,
            quantize=True,
            sensitivity_dbm=-92.0,
            saturation_dbm=-26.0,
            link_offsets_db=((("A", "B"), 1.0), (("B", "A"), -2.5)),
            dropouts=1,
            dropout_duration_s=1.5,
        ),
    )


def _trio() -> SimulationConfig:
    nodes = {
        "A": NodeAntenna(antenna_from_name("itu_omni"), Mounting.named("vertical"), x500_frame_lobes(180.0), "ITU omni"),
        "B": NodeAntenna(
            antenna_from_name("itu_sectoral"), Mounting.named("vertical"), x500_frame_lobes(0.0), "ITU sectoral, forward"
        ),
        "C": NodeAntenna(
            antenna_from_name("high_gain"), Mounting(pitch_deg=-20.0), x500_frame_lobes(90.0), "high-gain beam, tilted up"
        ),
    }
    campaign = group_campaign(("A", "B", "C"), speed_m_s=2.0)
    paper = _paper()
    return SimulationConfig(
        name="trio",
        campaign=replace(campaign, gap_s=120.0),
        node_antennas=nodes,
        flight=paper.flight,
        estimator=paper.estimator,
        radio=replace(paper.radio, link_offsets_db=(), dropouts=0),
    )


def _smoke() -> SimulationConfig:
    opts: dict[str, Any] = dict(distance_m=6.0, height_m=10.0, n_loops=2, speed_m_s=3.0, accel_m_s2=3.0, yaw_rate_deg_s=90.0)
    units = (
        TrajectoryUnit(nodes=("A", "B"), psi0_deg=0.0, role="learning", label="learn_0", **opts),
        TrajectoryUnit(nodes=("A", "B"), psi0_deg=90.0, role="testing", label="test_90", **opts),
    )
    paper = _paper()
    return SimulationConfig(
        name="smoke",
        campaign=Campaign(units, gap_s=5.0),
        node_antennas=_paper_nodes(),
        flight=replace(paper.flight, truth_rate_hz=100.0),
        estimator=paper.estimator,
        radio=replace(paper.radio, packet_rate_hz=20.0, dropouts=0),
    )


#: Altitudes of the ``ground`` preset's passes [m]: learning at the first two, testing at the third.
GROUND_HEIGHTS_M: tuple[float, float, float] = (15.0, 25.0, 35.0)


def _ground() -> SimulationConfig:
    from rplearn.plan.ground import GroundPassUnit

    learn = [GroundPassUnit(height_m=h, label=f"learn_{h:g}m", role="learning", station_yaw_deg=10.0)
             for h in GROUND_HEIGHTS_M[:2]]
    test = [GroundPassUnit(height_m=GROUND_HEIGHTS_M[2], label=f"test_{GROUND_HEIGHTS_M[2]:g}m", role="testing",
                           station_yaw_deg=10.0)]
    drone = _paper_nodes()["A"]
    nodes = {
        "G": NodeAntenna(antenna_from_name("itu_sectoral"), Mounting.named("vertical"), (), "ground station, ITU sectoral"),
        "D": replace(drone, description="X500, camera payload"),
    }
    paper = _paper()
    return SimulationConfig(
        name="ground",
        campaign=Campaign(tuple(learn + test), gap_s=60.0),  # type: ignore[arg-type]
        node_antennas=nodes,
        flight=replace(paper.flight, wind_speed_m_s=0.0, gust_std_m_s=0.0),
        estimator=paper.estimator,
        radio=replace(paper.radio, link_offsets_db=(), dropouts=0),
    )


#: Log-distance exponent of the ``pathloss`` preset's channel.
PATHLOSS_EXPONENT = 3.0
#: ``pathloss`` preset units: (label, psi0 [deg], circle diameter = distance [m], speed [m/s], role).
PATHLOSS_UNITS: tuple[tuple[str, float, float, float, str], ...] = (
    ("learn_6m", 0.0, 6.0, 0.9, "learning"),
    ("learn_10m", 24.0, 10.0, 1.5, "learning"),
    ("learn_16m", 48.0, 16.0, 2.4, "learning"),
    ("test_12m", 36.0, 12.0, 1.8, "testing"),
)


def _pathloss(exponent: float = PATHLOSS_EXPONENT) -> SimulationConfig:
    units = tuple(TrajectoryUnit(nodes=("A", "B"), psi0_deg=psi, distance_m=d, speed_m_s=v, height_m=20.0, role=role,
                                 label=label) for label, psi, d, v, role in PATHLOSS_UNITS)
    paper = _paper()
    return SimulationConfig(
        name="pathloss",
        campaign=Campaign(units, gap_s=60.0),
        node_antennas=_paper_nodes(),
        flight=paper.flight,
        estimator=paper.estimator,
        radio=replace(paper.radio, link_offsets_db=(), dropouts=0, path_loss_exponent=exponent),
    )


#: ``tworay`` preset: the station's antenna height and the drone's altitudes (learning, learning,
#: testing) [m], and the horizontal distances of its passes [m].
TWORAY_STATION_HEIGHT_M = 5.0
TWORAY_HEIGHTS_M: tuple[float, float, float] = (6.0, 10.0, 8.0)
TWORAY_DISTANCES_M: tuple[float, float, float] = (60.0, 100.0, 80.0)


def _tworay() -> SimulationConfig:
    from rplearn.plan.ground import GroundPassUnit

    roles = ("learning", "learning", "testing")
    units = tuple(GroundPassUnit(height_m=h, distance_m=d, station_height_m=TWORAY_STATION_HEIGHT_M, role=role,
                                 label=f"{'learn' if role == 'learning' else 'test'}_{h:g}m_{d:g}m", station_yaw_deg=10.0)
                  for h, d, role in zip(TWORAY_HEIGHTS_M, TWORAY_DISTANCES_M, roles))
    ground = _ground()
    omni = antenna_from_name("itu_omni")
    nodes = {
        "G": NodeAntenna(omni, Mounting.named("vertical"), (), "station, ITU omni on a 5 m mast"),
        "D": NodeAntenna(omni, Mounting.named("vertical"), x500_frame_lobes(180.0), "X500, ITU omni"),
    }
    return SimulationConfig(
        name="tworay",
        campaign=Campaign(units, gap_s=60.0),  # type: ignore[arg-type]
        node_antennas=nodes,
        flight=ground.flight,
        estimator=ground.estimator,
        radio=replace(ground.radio, two_ray=True, ground_level_m=0.0, ground_permittivity=15.0),
    )


#: ``campaign`` preset: the RMS of the flights' levels [dB], the learning flights' altitudes
#: (cycled), the number of learning and testing flights, and the testing flights' arc [deg].
CAMPAIGN_LEVEL_STD_DB = 3.0
CAMPAIGN_HEIGHTS_M: tuple[float, ...] = (15.0, 20.0, 25.0)
CAMPAIGN_FLIGHTS: tuple[int, int] = (9, 6)
CAMPAIGN_TEST_ARC_DEG = 70.0


def _campaign() -> SimulationConfig:
    from rplearn.plan.ground import GroundPassUnit

    n_learn, n_test = CAMPAIGN_FLIGHTS
    common: dict[str, Any] = dict(station_yaw_deg=10.0, n_passes=4)
    learn = [GroundPassUnit(height_m=CAMPAIGN_HEIGHTS_M[k % len(CAMPAIGN_HEIGHTS_M)], role="learning",
                            label=f"flight_{k + 1:02d}", **common) for k in range(n_learn)]
    middle = CAMPAIGN_HEIGHTS_M[len(CAMPAIGN_HEIGHTS_M) // 2]
    test = [GroundPassUnit(height_m=middle, arc_deg=CAMPAIGN_TEST_ARC_DEG, role="testing",
                           label=f"test_flight_{k + 1:02d}", **common) for k in range(n_test)]
    ground = _ground()
    return SimulationConfig(
        name="campaign",
        campaign=Campaign(tuple(learn + test), gap_s=30.0),  # type: ignore[arg-type]
        node_antennas=ground.node_antennas,
        flight=ground.flight,
        estimator=ground.estimator,
        radio=replace(ground.radio, packet_rate_hz=10.0, unit_level_std_db=CAMPAIGN_LEVEL_STD_DB),
    )


_PRESETS: dict[str, Callable[[], SimulationConfig]] = {"paper": _paper, "trio": _trio, "smoke": _smoke, "ground": _ground,
                                                       "pathloss": _pathloss, "tworay": _tworay, "campaign": _campaign}
#: Names accepted by :func:`make_preset` and :func:`rplearn.sim.flight.simulate`.
PRESET_NAMES: tuple[str, ...] = tuple(_PRESETS)


@check_types
def make_preset(name: str) -> SimulationConfig:
    """The :class:`SimulationConfig` of a named preset (``paper``, ``trio``, ``smoke``)."""
    try:
        return _PRESETS[name]()
    except KeyError:
        raise BadValueError(f"preset: expected one of {', '.join(PRESET_NAMES)}, got {name!r}", param="preset") from None
