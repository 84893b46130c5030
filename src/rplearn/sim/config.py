"""Configuration of a simulated calibration campaign: flight, pose estimator, radio, antennas.

Every effect is sized by a field and switched off by setting it to zero (or ``None`` /
``False``); :mod:`rplearn.sim.presets` builds the configurations of the paper's campaign.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

from rplearn._argtypes import check_types
from rplearn.errors import InputError
from rplearn.plan.campaign import Campaign
from rplearn.sim.antennas import GroundTruth, NodeAntenna


@check_types
@dataclass(frozen=True)
class FlightConfig:
    """How the drones really fly (truth), around the references.

    Attributes
    ----------
    truth_rate_hz : float
        Rate of the simulated true state; finer times are linearly interpolated [Hz].
    tracking_std_m : float
        Standard deviation of the position tracking error, per axis (Ornstein-Uhlenbeck) [m].
    tracking_tau_s : float
        Correlation time of the tracking error [s].
    yaw_tracking_std_deg : float
        Standard deviation of the heading tracking error [deg].
    yaw_tracking_tau_s : float
        Its correlation time [s].
    wind_speed_m_s : float
        Steady horizontal wind [m/s]; 0 switches wind off.
    wind_toward_deg : float
        Azimuth the wind blows toward, ENU ccw from east [deg].
    gust_std_m_s : float
        Standard deviation of gusts per horizontal axis [m/s].
    gust_tau_s : float
        Correlation time of gusts [s].
    drag_per_m : float
        Quadratic drag coefficient ``c`` of ``a_drag = c |v_air| v_air`` [1/m]; the drone tilts
        so that its thrust cancels drag and gives the reference acceleration. 0.021 tilts an
        X500-class drone by about 12 deg in a 10 m/s wind.
    tilt_jitter_deg : float
        Standard deviation of fast roll/pitch jitter of the controller [deg].
    tilt_jitter_tau_s : float
        Its correlation time [s].
    tilt_into_motion : bool
        Whether the attitude follows the thrust vector (False: always level).
    """

    truth_rate_hz: float = 200.0
    tracking_std_m: float = 0.0
    tracking_tau_s: float = 1.5
    yaw_tracking_std_deg: float = 0.0
    yaw_tracking_tau_s: float = 1.0
    wind_speed_m_s: float = 0.0
    wind_toward_deg: float = 90.0
    gust_std_m_s: float = 0.0
    gust_tau_s: float = 3.0
    drag_per_m: float = 0.021
    tilt_jitter_deg: float = 0.0
    tilt_jitter_tau_s: float = 0.3
    tilt_into_motion: bool = True


@check_types
@dataclass(frozen=True)
class EstimatorConfig:
    """The autopilot's pose estimates written to the pose log.

    Attributes
    ----------
    pose_rate_hz : float
        Pose log rate per drone [Hz].
    pose_time_jitter_s : float
        Standard deviation of the logging time around the nominal grid [s].
    horizontal_noise_std_m, vertical_noise_std_m : float
        Position estimate error (RTK-GNSS level: about 0.01-0.03 m), correlated over
        ``position_noise_tau_s`` [m].
    position_noise_tau_s : float
        Correlation time of the position error [s].
    yaw_noise_std_deg : float
        Heading estimate error (magnetometer: a few degrees), correlated over ``yaw_noise_tau_s``.
    yaw_noise_tau_s : float
        Its correlation time [s].
    tilt_noise_std_deg : float
        White roll/pitch estimate error [deg].
    """

    pose_rate_hz: float = 100.0
    pose_time_jitter_s: float = 0.0
    horizontal_noise_std_m: float = 0.0
    vertical_noise_std_m: float = 0.0
    position_noise_tau_s: float = 1.0
    yaw_noise_std_deg: float = 0.0
    yaw_noise_tau_s: float = 5.0
    tilt_noise_std_deg: float = 0.0


@check_types
@dataclass(frozen=True)
class RadioConfig:
    """The radios: packets, received power (paper eq. 1) and its defects.

    Attributes
    ----------
    tx_power_dbm : float
        Transmitted power [dBm] (the paper: 20 dBm).
    frequency_hz : float
        Carrier frequency [Hz].
    packet_rate_hz : float
        Packets per second per direction [Hz] (the paper: about 80).
    packet_jitter : float
        Standard deviation of the inter-packet time as a fraction of the nominal interval.
    loss_probability : float
        Probability that a packet is lost regardless of its power.
    fading_std_db : float
        Standard deviation of the log-normal fading added to every packet [dB].
    quantize : bool
        Report RSSI as integer dBm.
    sensitivity_dbm : float or None
        Receiver sensitivity: packets received below it are lost [dBm].
    saturation_dbm : float or None
        RSSI plateau: reports never exceed it [dBm].
    link_offsets_db : tuple of ((tx, rx), offset)
        Per-direction electronics offset [dB] (non-reciprocity, Sec. V-B3).
    dropouts : int
        Number of short link dropouts in the whole campaign (both directions silent).
    dropout_duration_s : float
        Duration of each dropout [s].
    path_loss_exponent : float
        Log-distance exponent ``n`` of the path loss, free space up to 1 m (2: free space).
    two_ray : bool
        Add one ray reflected off flat ground at ``ground_level_m`` (relative permittivity
        ``ground_permittivity``, ``polarization``), the antennas' true gains along it included.
    unit_level_std_db : float
        Standard deviation of a level offset [dB] drawn once per trajectory unit (flight) from
        the seed and added to every packet of that unit, both directions: what changes from
        flight to flight in a real campaign (another battery and radio temperature, a cable
        re-plugged, the ground wetter). The learning and the testing units' levels each have
        a root mean square of exactly this value (:func:`rplearn.sim.flight.unit_levels_db`).
        0 switches it off; the levels are in
        :attr:`rplearn.sim.flight.SimulationResult.unit_levels_db`.
    """

    tx_power_dbm: float = 20.0
    frequency_hz: float = 2.412e9
    packet_rate_hz: float = 80.0
    packet_jitter: float = 0.0
    loss_probability: float = 0.0
    fading_std_db: float = 0.0
    quantize: bool = True
    sensitivity_dbm: float | None = None
    saturation_dbm: float | None = None
    link_offsets_db: tuple[tuple[tuple[str, str], float], ...] = ()
    dropouts: int = 0
    dropout_duration_s: float = 2.0
    path_loss_exponent: float = 2.0
    two_ray: bool = False
    ground_level_m: float = 0.0
    ground_permittivity: float = 15.0
    polarization: str = "vertical"
    unit_level_std_db: float = 0.0

    def offsets_dict(self) -> dict[str, float]:
        """Offsets keyed ``"tx->rx"`` [dB]."""
        return {f"{tx}->{rx}": float(v) for (tx, rx), v in self.link_offsets_db}


@check_types
@dataclass(frozen=True)
class SimulationConfig:
    """Everything that defines a simulated campaign.

    Attributes
    ----------
    name : str
        Preset or user label.
    campaign : Campaign
        Trajectory units to fly.
    node_antennas : dict of str -> NodeAntenna
        True pattern of every node (antenna, mounting, airframe lobes).
    flight, estimator, radio : FlightConfig, EstimatorConfig, RadioConfig
        Effects and their sizes.
    reference_rate_hz : float
        Rate of the reference CSV files written with the logs [Hz].
    """

    name: str
    campaign: Campaign
    node_antennas: dict[str, NodeAntenna]
    flight: FlightConfig = field(default_factory=FlightConfig)
    estimator: EstimatorConfig = field(default_factory=EstimatorConfig)
    radio: RadioConfig = field(default_factory=RadioConfig)
    reference_rate_hz: float = 10.0

    def __post_init__(self) -> None:
        missing = sorted(set(self.campaign.nodes) - set(self.node_antennas))
        if missing:
            raise InputError(f"node_antennas: no antenna given for node(s) {', '.join(missing)}")
        if not (self.radio.packet_rate_hz > 0):
            raise InputError(f"radio packet_rate_hz: expected > 0 Hz, got {self.radio.packet_rate_hz}")
        if not (0.0 <= self.radio.loss_probability < 1.0):
            raise InputError(
                f"radio loss_probability: expected 0 <= p < 1, got {self.radio.loss_probability}"
            )
        if self.radio.fading_std_db < 0:
            raise InputError(f"radio fading_std_db: expected >= 0 dB, got {self.radio.fading_std_db}")
        if not (self.radio.unit_level_std_db >= 0):
            raise InputError(f"radio unit_level_std_db: expected >= 0 dB, got {self.radio.unit_level_std_db}")
        if not (1.0 <= self.radio.path_loss_exponent <= 8.0):
            raise InputError(f"radio path_loss_exponent: expected 1..8, got {self.radio.path_loss_exponent}")

    def ground_truth(self, seed: int | None = None) -> GroundTruth:
        """The :class:`GroundTruth` of this configuration."""
        return GroundTruth(
            node_antennas=dict(self.node_antennas),
            link_offsets_db=self.radio.offsets_dict(),
            frequency_hz=self.radio.frequency_hz,
            metadata={"simulation": self.name, "seed": seed},
        )


@check_types
def renamed_nodes(config: SimulationConfig, names: dict[str, str], campaign: Campaign) -> SimulationConfig:
    """``config`` flying ``campaign`` with its nodes renamed: ``names`` maps a node of ``config``
    to its new name (``simulate --plan`` flies a plan's ``gcs``, ``sys1`` as the ``ground``
    preset's ``G``, ``D``). Every per-node field follows: the antennas and the link offsets; the
    nodes ``names`` leaves out are dropped (so that no old name meets a new one).

    Raises
    ------
    InputError
        ``names`` gives two nodes one name, or names a node ``config`` lacks.
    """
    unknown = sorted(set(names) - set(config.node_antennas))
    if unknown or len(set(names.values())) != len(names):
        raise InputError(f"names: expected distinct new names of nodes of {', '.join(sorted(config.node_antennas))}, "
                         f"got {', '.join(f'{a}={b}' for a, b in names.items())}", param="names")
    offsets = tuple(((names[tx], names[rx]), v) for (tx, rx), v in config.radio.link_offsets_db if tx in names and rx in names)
    return replace(config, campaign=campaign, node_antennas={names[n]: a for n, a in config.node_antennas.items() if n in names},
                   radio=replace(config.radio, link_offsets_db=offsets))
