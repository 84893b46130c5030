"""Flight simulator: calibration flights with known ground-truth patterns (paper Secs. IV-V).

Drones track the references of a :class:`~rplearn.plan.trajectory.Campaign` with a tracking error,
tilting into their acceleration and into the wind (the paper's day had about 10 m/s); their
autopilots log pose estimates (RTK-GNSS-level position noise, a few degrees of yaw noise, about
100 Hz); their radios exchange packets (about 80 per second per direction, with jitter, loss and
short dropouts) whose received power follows paper eq. 1 from the *true* poses and patterns,
plus log-normal fading, a per-direction electronics offset (non-reciprocity, Sec. V-B3),
integer-dBm RSSI, a sensitivity floor (no packet below it) and a saturation plateau.

Every effect is sized by a field of a config dataclass and switched off by setting it to zero
(or ``None`` / ``False``). The outputs are the raw pose and signal logs in the canonical
schemas of :mod:`rplearn.data.tables`, so that they go through the same synchronisation as real
logs, plus the ground truth (:class:`~rplearn.sim.antennas.GroundTruth`) and, for scoring, the
matched dataset built from the true poses at every packet time (``matched_truth``).

Noise level (what "the RMSE of the true patterns equals the noise level" means): the residual
``rssi - (P_tx + G_tx + G_rx + offset - FSPL)`` evaluated with the true poses and patterns is
the fading plus the rounding to integer dBm (plus clipping at the plateau, rare by design).
Its nominal standard deviation is :attr:`SimulationResult.noise_std_db`
``= sqrt(fading_std_db^2 + 1/12)`` (uniform rounding error of variance 1/12 dB^2).
"""

from __future__ import annotations

import logging
import os
import time
from dataclasses import dataclass, field, replace

import numpy as np
import pandas as pd
from numpy.typing import NDArray

from rplearn._argtypes import check_types
from rplearn.core.environment import log_distance_column, two_ray_excess_db
from rplearn.core.geometry import (
    attitude_from_thrust,
    direction_in_body,
    distance_m,
    link_directions,
    quat_wxyz_from_euler,
    quat_wxyz_from_yaw,
    quat_wxyz_multiply,
)
from rplearn.core.link import free_space_path_loss_db
from rplearn.data.tables import MATCHED_COLUMNS, POSE_COLUMNS, SIGNAL_COLUMNS
from rplearn.errors import InputError
from rplearn.io.files import write_table
from rplearn.plan.campaign import write_references
from rplearn.plan.trajectory import G_M_S2, TrajectoryUnit
from rplearn.sim.antennas import GroundTruth, load_ground_truth
from rplearn.sim.config import EstimatorConfig, FlightConfig, RadioConfig, SimulationConfig
from rplearn.sim.noise import ou_process
from rplearn.sim.presets import make_preset

FloatArray = NDArray[np.float64]
logger = logging.getLogger(__name__)

__all__ = [
    "EstimatorConfig",
    "FlightConfig",
    "RadioConfig",
    "SimulationConfig",
    "SimulationResult",
    "load_ground_truth",
    "simulate",
]


@check_types
@dataclass
class SimulationResult:
    """Logs, truth and files of one simulated campaign.

    Attributes
    ----------
    config : SimulationConfig
    seed : int
    pose_log : DataFrame
        Canonical pose log (estimates) ``t, node, x, y, z, qw, qx, qy, qz``.
    signal_log : DataFrame
        Canonical signal log ``t, tx, rx, rssi_dbm, tx_power_dbm, frequency_hz, unit``.
    ground_truth : GroundTruth
    matched_truth : DataFrame
        Every signal-log row with the *true* poses of both ends at the packet time
        (:data:`rplearn.data.tables.MATCHED_COLUMNS` plus ``unit``).
    noise_std_db : float
        Nominal std of the residual noise in dB: ``sqrt(fading^2 + 1/12 if quantized)``.
    realised_noise_std_db : float
        Std of ``rssi - clean power`` over the delivered packets [dB].
    unit_levels_db : dict of str -> float
        The level offset drawn for every unit (flight) and added to all its packets [dB]
        (:attr:`RadioConfig.unit_level_std_db`; zeros when it is 0). Also in the ground truth's
        metadata.
    paths : dict of str -> str
        Files written (``pose_log``, ``signal_log``, ``ground_truth``, ``matched_truth``,
        ``references`` directory); empty without ``out_dir``.
    elapsed_s : float
        Wall time of the simulation (files excluded) [s].
    """

    config: SimulationConfig
    seed: int
    pose_log: pd.DataFrame
    signal_log: pd.DataFrame
    ground_truth: GroundTruth
    matched_truth: pd.DataFrame
    noise_std_db: float
    realised_noise_std_db: float
    paths: dict[str, str] = field(default_factory=dict)
    elapsed_s: float = 0.0
    unit_levels_db: dict[str, float] = field(default_factory=dict)

    def units(self, role: str) -> list[str]:
        """Labels of the units with the given role (``"learning"``/``"testing"``)."""
        return [u.label for u in self.config.campaign.units if u.role == role]

    def matched(self, role: str | None = None, tx: str | None = None, rx: str | None = None) -> pd.DataFrame:
        """Rows of :attr:`matched_truth` of a role and direction."""
        df = self.matched_truth
        mask = np.ones(len(df), bool)
        if role is not None:
            mask &= df["unit"].isin(self.units(role)).to_numpy()
        if tx is not None:
            mask &= (df["tx"] == tx).to_numpy()
        if rx is not None:
            mask &= (df["rx"] == rx).to_numpy()
        return df.loc[mask].reset_index(drop=True)


# ---------------------------------------------------------------------------------------------
# Random processes


def _rotation_z_quat(angle_rad: FloatArray) -> FloatArray:
    return quat_wxyz_from_yaw(angle_rad)


# ---------------------------------------------------------------------------------------------
# Truth of one unit


@dataclass
class _UnitTruth:
    unit: TrajectoryUnit
    t_s: FloatArray  # (n,)
    position_enu_m: FloatArray  # (n, 2, 3)
    quat_wxyz: FloatArray  # (n, 2, 4)

    def interpolate(self, t_s: FloatArray, which: int) -> tuple[FloatArray, FloatArray]:
        """True position and attitude of drone ``which`` at times ``t_s`` (linear / nlerp)."""
        return self._at(*self._weights(t_s), which)

    def _weights(self, t_s: FloatArray) -> tuple[NDArray[np.intp], FloatArray]:
        """Each time's truth interval and its fraction through it, shape (n, 1)."""
        t = np.clip(t_s, self.t_s[0], self.t_s[-1])
        i = np.clip(np.searchsorted(self.t_s, t, side="right") - 1, 0, self.t_s.size - 2)
        w = ((t - self.t_s[i]) / (self.t_s[i + 1] - self.t_s[i]))[:, None]
        return i, w

    def _at(self, i: NDArray[np.intp], w: FloatArray, which: int | None = None) -> tuple[FloatArray, FloatArray]:
        """Position and attitude of drone ``which`` at the fractions ``w`` of intervals ``i``;
        of both drones, shapes (n, 2, 3) and (n, 2, 4), when ``which`` is None (the same
        operations on each element, gathered once)."""
        p = self.position_enu_m if which is None else self.position_enu_m[:, which, :]
        q = self.quat_wxyz if which is None else self.quat_wxyz[:, which, :]
        if which is None:
            w = w[:, :, None]
        j, rest = i + 1, 1.0 - w
        pos = p[i] * rest + p[j] * w
        q0, q1 = q[i], q[j]
        sign = np.where(np.sum(q0 * q1, axis=-1, keepdims=True) < 0, -1.0, 1.0)
        qi = q0 * rest + sign * q1 * w
        qi /= np.linalg.norm(qi, axis=-1, keepdims=True)
        return pos, qi


def _simulate_unit_truth(
    unit: TrajectoryUnit, t0_s: float, flight: FlightConfig, rng: np.random.Generator
) -> _UnitTruth:
    ref = unit.sample(flight.truth_rate_hz, t_offset_s=t0_s)
    n = ref.t_s.size
    dt = 1.0 / flight.truth_rate_hz
    pos = ref.position_enu_m.copy()
    quats = np.empty((n, 2, 4))
    wind_dir = np.radians(flight.wind_toward_deg)
    steady = flight.wind_speed_m_s * np.array([np.cos(wind_dir), np.sin(wind_dir), 0.0])
    gust = ou_process(rng, n, dt, flight.gust_std_m_s, flight.gust_tau_s, dims=2)
    wind = steady[None, :] + np.column_stack([gust, np.zeros(n)])
    for j in range(2):
        err = ou_process(rng, n, dt, flight.tracking_std_m, flight.tracking_tau_s, dims=3)
        pos[:, j, :] += err
        yaw = ref.yaw_rad[:, j] + np.radians(
            ou_process(rng, n, dt, flight.yaw_tracking_std_deg, flight.yaw_tracking_tau_s)[:, 0]
        )
        if flight.tilt_into_motion:
            v_air = wind - ref.velocity_enu_m_s[:, j, :]
            a_drag = flight.drag_per_m * np.linalg.norm(v_air, axis=1, keepdims=True) * v_air
            thrust = ref.accel_enu_m_s2[:, j, :] - a_drag + np.array([0.0, 0.0, G_M_S2])
        else:
            thrust = np.tile([0.0, 0.0, 1.0], (n, 1))
        q = attitude_from_thrust(thrust, yaw)
        if flight.tilt_jitter_deg > 0:
            jit = np.radians(ou_process(rng, n, dt, flight.tilt_jitter_deg, flight.tilt_jitter_tau_s, dims=2))
            q_j = quat_wxyz_from_euler(jit[:, 0], jit[:, 1], np.zeros(n))
            q = quat_wxyz_multiply(q, q_j)
        quats[:, j, :] = q
    return _UnitTruth(unit, ref.t_s, pos, quats)


def _pose_estimates(
    truth: _UnitTruth, which: int, est: EstimatorConfig, rng: np.random.Generator
) -> pd.DataFrame:
    t0, t1 = truth.t_s[0], truth.t_s[-1]
    dt = 1.0 / est.pose_rate_hz
    t = np.arange(t0, t1, dt)
    if est.pose_time_jitter_s > 0:
        t = t + rng.normal(0.0, est.pose_time_jitter_s, t.size)
        t = np.unique(np.clip(t, t0, t1))
    n = t.size
    pos, q = truth.interpolate(t, which)
    pos = pos + np.column_stack(
        [
            ou_process(rng, n, dt, est.horizontal_noise_std_m, est.position_noise_tau_s, dims=2),
            ou_process(rng, n, dt, est.vertical_noise_std_m, est.position_noise_tau_s, dims=1),
        ]
    )
    if est.yaw_noise_std_deg > 0:
        dyaw = np.radians(ou_process(rng, n, dt, est.yaw_noise_std_deg, est.yaw_noise_tau_s)[:, 0])
        q = quat_wxyz_multiply(_rotation_z_quat(dyaw), q)
    if est.tilt_noise_std_deg > 0:
        tilt = np.radians(rng.normal(0.0, est.tilt_noise_std_deg, (n, 2)))
        q = quat_wxyz_multiply(q, quat_wxyz_from_euler(tilt[:, 0], tilt[:, 1], np.zeros(n)))
    q = np.where(q[:, :1] < 0, -q, q)
    return pd.DataFrame(
        {
            "t": t,
            "node": truth.unit.nodes[which],
            "x": pos[:, 0],
            "y": pos[:, 1],
            "z": pos[:, 2],
            "qw": q[:, 0],
            "qx": q[:, 1],
            "qy": q[:, 2],
            "qz": q[:, 3],
        }
    )


def _packet_times(t0: float, t1: float, radio: RadioConfig, rng: np.random.Generator) -> FloatArray:
    interval = 1.0 / radio.packet_rate_hz
    n = int(np.floor((t1 - t0) / interval))
    gaps = np.full(n, interval)
    if radio.packet_jitter > 0:
        gaps = np.maximum(gaps * (1.0 + radio.packet_jitter * rng.standard_normal(n)), 0.05 * interval)
    t = t0 + rng.uniform(0.0, interval) + np.cumsum(gaps) - gaps[0]
    return t[t <= t1]


def _dropout_windows(
    radio: RadioConfig, units: tuple[TrajectoryUnit, ...] | list[TrajectoryUnit], starts: FloatArray,
    rng: np.random.Generator,
) -> FloatArray:
    """Short dropouts ``(begin, end)`` [s], shape (n, 2): placed uniformly within the flown time.

    A unit is picked with probability proportional to its duration, then a start within it.
    """
    if not (radio.dropouts > 0 and radio.dropout_duration_s > 0):
        return np.zeros((0, 2))
    flown = np.array([(s, s + u.duration_s) for s, u in zip(starts, units)])
    lengths = flown[:, 1] - flown[:, 0]
    pick = rng.choice(len(lengths), size=radio.dropouts, p=lengths / lengths.sum())
    begin = flown[pick, 0] + rng.uniform(0.0, 1.0, radio.dropouts) * (
        lengths[pick] - radio.dropout_duration_s
    ).clip(min=0.0)
    return np.column_stack([begin, begin + radio.dropout_duration_s])


def unit_levels_db(radio: RadioConfig, units: tuple[TrajectoryUnit, ...] | list[TrajectoryUnit],
                   rng: np.random.Generator) -> dict[str, float]:
    """The level offset of every unit [dB] (all 0 without :attr:`RadioConfig.unit_level_std_db`;
    nothing drawn then): independent normal draws, then, within each role (learning, testing)
    of two or more units, centred and scaled to a root mean square of exactly
    ``unit_level_std_db``. A campaign of a dozen flights draws too few levels for their spread
    to be the nominal one (6 flights drawn at 3 dB RMS spread by 1.2 to 4.8 dB, 95% of the time): the
    flights' order is the seed's, their spread the configuration's, so that a test checks an
    estimate of the spread rather than the luck of a few draws."""
    if not radio.unit_level_std_db > 0:
        return {u.label: 0.0 for u in units}
    draws = rng.normal(0.0, 1.0, len(units))
    roles = np.array([u.role for u in units])
    for role in np.unique(roles):
        sel = roles == role
        if sel.sum() >= 2:
            centred = draws[sel] - draws[sel].mean()
            draws[sel] = centred / max(float(np.sqrt(np.mean(centred**2))), 1e-12)
    return {u.label: float(v) * radio.unit_level_std_db for u, v in zip(units, draws)}


def _arrivals(truth: _UnitTruth, radio: RadioConfig, dropouts: FloatArray, rng: np.random.Generator) -> FloatArray:
    """Times [s] of the packets of one direction that are not lost at random or in a dropout."""
    t = _packet_times(truth.t_s[0], truth.t_s[-1], radio, rng)
    keep = rng.uniform(size=t.size) >= radio.loss_probability
    for b, e in dropouts:
        keep &= ~((t >= b) & (t < e))
    return t[keep]


@dataclass
class _Link:
    """The packets of one direction of one unit: signal-log rows, matched truth, residual noise [dB]."""

    signal: pd.DataFrame
    matched: pd.DataFrame
    noise_db: FloatArray


def _environment_db(
    truth_model: GroundTruth, link: tuple[str, str], tx_pose: tuple[FloatArray, FloatArray],
    rx_pose: tuple[FloatArray, FloatArray], direct_gain_db: FloatArray, dist: FloatArray, radio: RadioConfig,
) -> FloatArray:
    """What the channel adds to free space [dB]: a log-distance exponent and a ground ray, on
    the link ``(tx, rx)`` whose ends have the poses ``(positions, quaternions)``.

    The reflected ray leaves the transmitter toward the receiver's image below the ground and
    arrives from the transmitter's image, so each antenna's true gain along it differs from
    the direct ray's: the simulator uses those gains (a two-ray fit cannot know them).
    """
    (tx, rx), (tx_pos, tx_q), (rx_pos, rx_q) = link, tx_pose, rx_pose
    out = (radio.path_loss_exponent - 2.0) * log_distance_column(dist)
    if radio.two_ray:
        g = radio.ground_level_m
        tx_img, rx_img = tx_pos.copy(), rx_pos.copy()
        tx_img[:, 2] = 2.0 * g - tx_pos[:, 2]
        rx_img[:, 2] = 2.0 * g - rx_pos[:, 2]
        az_t, el_t = direction_in_body(tx_pos, tx_q, rx_img)
        az_r, el_r = direction_in_body(rx_pos, rx_q, tx_img)
        reflected = truth_model.predict_joint_gain_db(tx, rx, az_t, el_t, az_r, el_r)
        ratio = 10.0 ** ((reflected - direct_gain_db) / 20.0)
        out = out + two_ray_excess_db(dist, tx_pos[:, 2] - g, rx_pos[:, 2] - g, radio.frequency_hz,
                                      radio.ground_permittivity, radio.polarization, gain_ratio=ratio)
    return out


def _link_packets(
    truth: _UnitTruth, j_tx: int, truth_model: GroundTruth, radio: RadioConfig, offsets: dict[str, float],
    dropouts: FloatArray, rng: np.random.Generator, level_db: float = 0.0,
) -> _Link:
    """Packets of drone ``j_tx`` to the other drone of a unit, received as paper eq. 1 says.

    Clean power from the true poses and patterns (plus the unit's level ``level_db``), plus
    fading, a sensitivity floor (lost below it), integer-dBm rounding and a saturation plateau.
    """
    j_rx = 1 - j_tx
    tx, rx = truth.unit.nodes[j_tx], truth.unit.nodes[j_rx]
    t = _arrivals(truth, radio, dropouts, rng)
    pos, q = truth._at(*truth._weights(t))  # both ends at the same times, interpolated at once
    tx_pos, tx_q = np.ascontiguousarray(pos[:, j_tx]), np.ascontiguousarray(q[:, j_tx])
    rx_pos, rx_q = np.ascontiguousarray(pos[:, j_rx]), np.ascontiguousarray(q[:, j_rx])
    dirs = link_directions(tx_pos, tx_q, rx_pos, rx_q)
    dist = distance_m(tx_pos, rx_pos)
    gain = truth_model.predict_joint_gain_db(tx, rx, *dirs)
    clean = (
        radio.tx_power_dbm
        + gain
        + offsets.get(f"{tx}->{rx}", 0.0)
        + level_db
        - free_space_path_loss_db(dist, radio.frequency_hz)
        + _environment_db(truth_model, (tx, rx), (tx_pos, tx_q), (rx_pos, rx_q), gain, dist, radio)
    )
    power = clean + radio.fading_std_db * rng.standard_normal(t.size)
    delivered = np.ones(t.size, bool)
    if radio.sensitivity_dbm is not None:
        delivered &= power >= radio.sensitivity_dbm
    rssi = np.round(power) if radio.quantize else power
    if radio.saturation_dbm is not None:
        rssi = np.minimum(rssi, radio.saturation_dbm)
    t, rssi, clean = t[delivered], rssi[delivered], clean[delivered]
    sig = pd.DataFrame(
        {
            "t": t,
            "tx": tx,
            "rx": rx,
            "rssi_dbm": rssi,
            "tx_power_dbm": float(radio.tx_power_dbm),
            "frequency_hz": float(radio.frequency_hz),
            "unit": truth.unit.label,
        }
    )
    ends = (("tx", tx_pos[delivered], tx_q[delivered]), ("rx", rx_pos[delivered], rx_q[delivered]))
    return _Link(sig, _with_true_poses(sig, ends), rssi - clean)


def _with_true_poses(sig: pd.DataFrame, ends: tuple[tuple[str, FloatArray, FloatArray], ...]) -> pd.DataFrame:
    """Signal rows with the true positions [m] and quaternions of both ends (matched columns)."""
    columns: dict[str, FloatArray] = {}
    for end, p, q in ends:
        columns[f"{end}_x"], columns[f"{end}_y"], columns[f"{end}_z"] = p[:, 0], p[:, 1], p[:, 2]
        for c, name in enumerate(("qw", "qx", "qy", "qz")):
            columns[f"{end}_{name}"] = q[:, c]
    return pd.concat([sig, pd.DataFrame(columns, index=sig.index)], axis=1)  # one block, not 14 inserts


def _simulate_unit(
    unit: TrajectoryUnit, t0_s: float, config: SimulationConfig, truth_model: GroundTruth,
    dropouts: FloatArray, rng: np.random.Generator, level_db: float = 0.0,
) -> tuple[list[pd.DataFrame], list[_Link]]:
    """One unit's flight: the two drones' pose estimates and the packets of both directions.

    Draws from ``rng`` in a fixed order (truth, estimates of drone 0 then 1, link 0 -> 1
    then 1 -> 0) so that a seed gives the same logs.
    """
    truth = _simulate_unit_truth(unit, t0_s, config.flight, rng)
    poses = [_pose_estimates(truth, j, config.estimator, rng) for j in range(2)]
    offsets = config.radio.offsets_dict()
    links = [_link_packets(truth, j_tx, truth_model, config.radio, offsets, dropouts, rng, level_db)
             for j_tx in range(2)]
    return poses, links


def _assemble(
    pose_frames: list[pd.DataFrame], links: list[_Link]
) -> tuple[pd.DataFrame, pd.DataFrame, pd.DataFrame, FloatArray]:
    """Pose log sorted by (node, t), signal log and matched truth sorted by time, residual noise [dB]."""
    pose_log = pd.concat(pose_frames, ignore_index=True).sort_values(["node", "t"], kind="stable")
    pose_log = pose_log.reset_index(drop=True)[list(POSE_COLUMNS)]
    signal_log = pd.concat([lk.signal for lk in links], ignore_index=True)
    order = np.argsort(signal_log["t"].to_numpy(), kind="stable")
    signal_log = signal_log.iloc[order].reset_index(drop=True)[list(SIGNAL_COLUMNS) + ["unit"]]
    matched = pd.concat([lk.matched for lk in links], ignore_index=True).iloc[order].reset_index(drop=True)
    matched = matched[list(MATCHED_COLUMNS) + ["unit"]]
    noise = np.concatenate([lk.noise_db for lk in links]) if links else np.zeros(0)
    return pose_log, signal_log, matched, noise


def _config_of(preset_or_config: str | SimulationConfig, log_format: str) -> SimulationConfig:
    """The configuration of a preset name, or the configuration given; checks ``log_format``."""
    if isinstance(preset_or_config, str):
        config = make_preset(preset_or_config)
    elif isinstance(preset_or_config, SimulationConfig):
        config = preset_or_config
    else:
        raise InputError(
            f"preset_or_config: expected a preset name or a SimulationConfig, got {type(preset_or_config).__name__}",
            param="preset_or_config",
        )
    if log_format not in ("parquet", "csv"):
        raise InputError(f"log_format: expected 'parquet' or 'csv', got {log_format!r}", param="log_format")
    return config


# ---------------------------------------------------------------------------------------------
# Public entry point


@check_types
def simulate(
    preset_or_config: str | SimulationConfig,
    seed: int = 0,
    out_dir: str | None = None,
    log_format: str = "parquet",
) -> SimulationResult:
    """Simulate a calibration campaign and (optionally) write its logs and ground truth.

    Parameters
    ----------
    preset_or_config : str or SimulationConfig
        A preset name (``"paper"``, ``"trio"``, ``"smoke"``; see :mod:`rplearn.sim.presets`) or a
        full configuration.
    seed : int
        Seed of every random effect; the same seed gives the same logs.
    out_dir : str, optional
        Directory to write ``pose_log.<fmt>``, ``signal_log.<fmt>``, ``matched_truth.<fmt>``,
        ``ground_truth.json`` and ``references/<unit>_<node>.csv`` into.
    log_format : str
        ``"parquet"`` or ``"csv"``.

    Returns
    -------
    SimulationResult
    """
    config = _config_of(preset_or_config, log_format)
    started = time.perf_counter()
    truth_model = config.ground_truth(seed)
    radio = config.radio
    units = config.campaign.units
    if int(seed) != seed or seed < 0:
        raise InputError(f"seed: expected a non-negative integer, got {seed!r}", param="seed")
    # one child per unit, one for the dropouts, one for the units' levels (spawned children
    # are keyed by their index: adding the last leaves the others' draws unchanged)
    unit_seeds = np.random.SeedSequence(int(seed)).spawn(len(units) + 2)
    starts = config.campaign.start_times_s()
    dropouts = _dropout_windows(radio, units, starts, np.random.default_rng(unit_seeds[len(units)]))
    levels = unit_levels_db(radio, units, np.random.default_rng(unit_seeds[len(units) + 1]))
    if radio.unit_level_std_db > 0:
        truth_model.metadata["unit_levels_db"] = dict(levels)
    pose_frames: list[pd.DataFrame] = []
    links: list[_Link] = []
    for k, (unit, t0) in enumerate(zip(units, starts)):
        poses, unit_links = _simulate_unit(
            unit, float(t0), config, truth_model, dropouts, np.random.default_rng(unit_seeds[k]), levels[unit.label]
        )
        pose_frames += poses
        links += unit_links
    pose_log, signal_log, matched, noise = _assemble(pose_frames, links)
    nominal = float(np.sqrt(radio.fading_std_db**2 + (1.0 / 12.0 if radio.quantize else 0.0)))
    result = SimulationResult(
        config=config,
        seed=int(seed),
        pose_log=pose_log,
        signal_log=signal_log,
        ground_truth=truth_model,
        matched_truth=matched,
        noise_std_db=nominal,
        realised_noise_std_db=float(np.std(noise)) if noise.size else float("nan"),
        elapsed_s=time.perf_counter() - started,
        unit_levels_db=levels,
    )
    if out_dir is not None:
        result.paths = write_simulation(result, out_dir, log_format)
    logger.info(
        "simulated %s: %d poses, %d packets in %.2f s", config.name, len(pose_log), len(signal_log), result.elapsed_s
    )
    return result


@check_types
def write_simulation(result: SimulationResult, out_dir: str, log_format: str = "parquet") -> dict[str, str]:
    """Write the logs, matched truth, ground truth and references of a simulation.

    Returns
    -------
    dict of str -> str
        Paths by role.
    """
    os.makedirs(out_dir, exist_ok=True)
    paths = {
        "pose_log": os.path.join(out_dir, f"pose_log.{log_format}"),
        "signal_log": os.path.join(out_dir, f"signal_log.{log_format}"),
        "matched_truth": os.path.join(out_dir, f"matched_truth.{log_format}"),
        "ground_truth": os.path.join(out_dir, "ground_truth.json"),
        "references": os.path.join(out_dir, "references"),
    }
    write_table(result.pose_log, paths["pose_log"])
    write_table(result.signal_log, paths["signal_log"])
    write_table(result.matched_truth, paths["matched_truth"])
    result.ground_truth.save(paths["ground_truth"])
    write_references(result.config.campaign, paths["references"], result.config.reference_rate_hz)
    return paths


@check_types
def with_effects_off(config: SimulationConfig) -> SimulationConfig:
    """The same campaign with every random or non-ideal effect switched off.

    Perfect tracking, no wind or gusts (the drones still tilt into the reference
    acceleration), exact pose estimates, no packet jitter, loss, fading, quantisation,
    sensitivity floor, plateau, electronics offsets or dropouts.
    """
    return replace(
        config,
        flight=FlightConfig(truth_rate_hz=config.flight.truth_rate_hz, drag_per_m=0.0),
        estimator=EstimatorConfig(pose_rate_hz=config.estimator.pose_rate_hz),
        radio=RadioConfig(
            tx_power_dbm=config.radio.tx_power_dbm,
            frequency_hz=config.radio.frequency_hz,
            packet_rate_hz=config.radio.packet_rate_hz,
            quantize=False,
        ),
    )
