"""Plan check before flying: coverage and identifiability of a campaign (paper Secs. IV-A, V-A).

For a campaign and a pattern model, :func:`check_plan` predicts the directions every drone
will see (from the references, with nominal attitudes: level, or tilted into the reference
acceleration and an expected wind), and reports

- per node, the azimuth-elevation coverage of its body sphere (a 2-D histogram and the
  area-weighted fraction of cells sampled);
- the rank, null-space dimension and condition number of the learning problem (the design
  matrix of paper Sec. V-A, via :func:`rplearn.core.lsq.solver.identifiability`), and the null-space
  dimension expected from the link graph (one per connected part without an odd cycle: with
  two drones, the constant that moves between the patterns);
- whether the plan decouples the patterns (null space no larger than expected) and whether it
  identifies absolute gains (no null space at all).

No signal is needed; the check is as good as the drones' tracking of the references.

Note on attitudes: drones that stayed exactly level would see each other at opposite
elevations at every instant, which leaves every elevation-only component free to move between
the two patterns (SH-10 on the paper campaign: rank 182 of 200). The tilt a multirotor needs
to fly the circle, and more so the tilt into the wind, removes this degeneracy (rank 199 of
200, the one constant); :func:`check_plan` therefore models the tilt by default.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from rplearn._argtypes import check_types
from rplearn.core.bases import Basis, make_basis
from rplearn.core.geometry import Directions, link_directions, quat_wxyz_from_yaw
from rplearn.errors import InputError
from rplearn.plan.campaign import Campaign, link_graph_identifies_gains
from rplearn.plan.trajectory import PlanLimits, UnitSummary

FloatArray = NDArray[np.float64]

__all__ = ["CoverageMap", "NominalAttitude", "PlanCheck", "check_plan", "plan_directions"]


@check_types
@dataclass(frozen=True)
class CoverageMap:
    """Samples of one node's body sphere on an azimuth-elevation grid.

    Attributes
    ----------
    node : str
    az_edges_deg : ndarray, shape (n_az + 1,)
        Azimuth bin edges, -180..180 [deg].
    el_edges_deg : ndarray, shape (n_el + 1,)
        Elevation bin edges, -90..90 [deg].
    counts : ndarray of int, shape (n_el, n_az)
        Samples per cell.
    covered_fraction : float
        Fraction of the sphere's area (cells weighted by solid angle) with at least one sample.
    """

    node: str
    az_edges_deg: FloatArray
    el_edges_deg: FloatArray
    counts: NDArray[np.int_]
    covered_fraction: float


@check_types
@dataclass(frozen=True)
class PlanCheck:
    """What a campaign will let a model learn.

    Attributes
    ----------
    basis_label : str
        The model (e.g. ``SH-10``).
    nodes : tuple of str
    n_samples : int
        Predicted samples (one direction per unit, at ``packet_rate_hz``).
    n_columns, rank, null_dim : int
        Columns of the design matrix, its rank, and ``n_columns - rank``.
    expected_null_dim : int
        Null-space dimension the link graph forces (bipartite connected parts).
    condition_number : float
        Largest / smallest non-zero singular value of the design matrix.
    decoupled : bool
        ``null_dim <= expected_null_dim``: the plan separates the patterns up to the
        unavoidable constants.
    absolute_gains : bool
        The link graph has an odd cycle in every connected part and ``null_dim == 0``.
    coverage : dict of str -> CoverageMap
    units : list of UnitSummary
    """

    basis_label: str
    nodes: tuple[str, ...]
    n_samples: int
    n_columns: int
    rank: int
    null_dim: int
    expected_null_dim: int
    condition_number: float
    decoupled: bool
    absolute_gains: bool
    coverage: dict[str, CoverageMap]
    units: list[UnitSummary]

    def summary(self) -> str:
        """A few human-readable lines."""
        lines = [
            f"model {self.basis_label}: {self.n_samples} samples, {self.n_columns} columns, rank {self.rank} "
            f"(null space {self.null_dim}, expected {self.expected_null_dim}), condition number "
            f"{self.condition_number:.4g}",
            "patterns decoupled" + (" with absolute gains" if self.absolute_gains else " up to the constant(s) the link graph leaves free")
            if self.decoupled
            else "patterns NOT decoupled: add headings/units or lower the model order",
        ]
        for node, cov in self.coverage.items():
            lines.append(f"node {node}: {100 * cov.covered_fraction:.1f}% of the sphere sampled")
        for u in self.units:
            lines.append(
                f"unit {u.label}: {u.duration_s:.0f} s, {u.path_length_m:.0f} m, max speed "
                f"{u.max_speed_m_s:.2f} m/s, max acceleration {u.max_accel_m_s2:.2f} m/s^2"
            )
        return "\n".join(lines)


@check_types
@dataclass(frozen=True)
class NominalAttitude:
    """How a plan check tilts the drones along their reference trajectories.

    Attributes
    ----------
    wind_speed_m_s : float
        Steady wind [m/s] (>= 0).
    wind_toward_deg : float
        Direction the wind blows toward [deg, ENU azimuth from east].
    drag_per_m : float
        Quadratic drag coefficient [1/m] (>= 0).
    tilt_into_motion : bool
        Tilt into the thrust the motion and wind need (default), or fly level.
    """

    wind_speed_m_s: float = 0.0
    wind_toward_deg: float = 90.0
    drag_per_m: float = 0.021
    tilt_into_motion: bool = True

    def __post_init__(self) -> None:
        if not (np.isfinite(self.wind_speed_m_s) and self.wind_speed_m_s >= 0):
            raise InputError(f"wind_speed_m_s: expected a speed >= 0 m/s, got {self.wind_speed_m_s!r}",
                             param="wind_speed_m_s")
        if not np.isfinite(self.wind_toward_deg):
            raise InputError(f"wind_toward_deg: expected a finite angle, got {self.wind_toward_deg!r}",
                             param="wind_toward_deg")
        if not (np.isfinite(self.drag_per_m) and self.drag_per_m >= 0):
            raise InputError(f"drag_per_m: expected a number >= 0, got {self.drag_per_m!r}", param="drag_per_m")


@check_types
def plan_directions(
    campaign: Campaign, packet_rate_hz: float = 80.0, attitude: NominalAttitude | None = None,
) -> tuple[Directions, NDArray[np.intp], NDArray[np.intp], tuple[str, ...]]:
    """Directions the drones will see, one sample per packet of the first -> second direction.

    With ``attitude.tilt_into_motion`` (default) attitudes follow the thrust a multirotor needs for the
    reference acceleration and the given wind (as in :mod:`rplearn.sim.flight`, without noise);
    otherwise they are level with the reference heading. Level attitudes are a degenerate
    idealisation: then ``el_second = -el_first`` at every sample, and any function of
    elevation alone can move from one pattern to the other (``h(el)`` on one, ``-h(-el)`` on
    the other), so zonal components are not identifiable; the tilt breaks this.

    Returns
    -------
    directions, tx_index, rx_index, nodes
        As :class:`rplearn.data.tables.LinkSamples` has them; ``nodes`` sorted.
    """
    if not (packet_rate_hz > 0):
        raise InputError(f"packet_rate_hz: expected > 0 Hz, got {packet_rate_hz!r}")
    attitude = attitude or NominalAttitude()
    nodes = campaign.nodes
    lookup = {n: i for i, n in enumerate(nodes)}
    parts: list[Directions] = []
    tx_idx: list[NDArray[np.intp]] = []
    rx_idx: list[NDArray[np.intp]] = []
    for unit in campaign.units:
        ref = unit.sample(packet_rate_hz)
        quats = []
        for j in range(2):
            if attitude.tilt_into_motion:
                from rplearn.core.geometry import attitude_from_thrust
                from rplearn.plan.trajectory import G_M_S2

                w = np.radians(attitude.wind_toward_deg)
                wind = attitude.wind_speed_m_s * np.array([np.cos(w), np.sin(w), 0.0])
                v_air = wind[None, :] - ref.velocity_enu_m_s[:, j, :]
                a_drag = attitude.drag_per_m * np.linalg.norm(v_air, axis=1, keepdims=True) * v_air
                thrust = ref.accel_enu_m_s2[:, j, :] - a_drag + np.array([0.0, 0.0, G_M_S2])
                quats.append(attitude_from_thrust(thrust, ref.yaw_rad[:, j]))
            else:
                quats.append(quat_wxyz_from_yaw(ref.yaw_rad[:, j]))
        parts.append(
            link_directions(ref.position_enu_m[:, 0, :], quats[0], ref.position_enu_m[:, 1, :], quats[1])
        )
        n = ref.t_s.size
        tx_idx.append(np.full(n, lookup[unit.nodes[0]], np.intp))
        rx_idx.append(np.full(n, lookup[unit.nodes[1]], np.intp))
    dirs = Directions(*(np.concatenate([getattr(p, f) for p in parts]) for f in Directions._fields))
    return dirs, np.concatenate(tx_idx), np.concatenate(rx_idx), nodes


@check_types
def coverage_map(node: str, az_rad: FloatArray, el_rad: FloatArray, bin_deg: float = 10.0) -> CoverageMap:
    """Azimuth-elevation histogram of one node's samples and the area fraction covered."""
    if not (0 < bin_deg <= 90):
        raise InputError(f"bin_deg: expected 0 < bin <= 90 deg, got {bin_deg!r}")
    az_edges = np.linspace(-180.0, 180.0, int(round(360.0 / bin_deg)) + 1)
    el_edges = np.linspace(-90.0, 90.0, int(round(180.0 / bin_deg)) + 1)
    counts, _, _ = np.histogram2d(np.degrees(el_rad), np.degrees(az_rad), bins=[el_edges, az_edges])
    area = np.diff(np.sin(np.radians(el_edges)))[:, None] * np.ones(az_edges.size - 1)[None, :]
    covered = float(np.sum(area * (counts > 0)) / np.sum(area))
    return CoverageMap(node, az_edges, el_edges, counts.astype(np.int_), covered)


@check_types
def check_plan(
    campaign: Campaign,
    basis: Basis | tuple[str, int] = ("sh", 10),
    role: str | None = "learning",
    packet_rate_hz: float = 80.0,
    limits: PlanLimits | None = None,
    coverage_bin_deg: float = 10.0,
    attitude: NominalAttitude | None = None,
) -> PlanCheck:
    """Coverage, rank and condition number a campaign will give a model, before flying.

    Parameters
    ----------
    campaign : Campaign
    basis : Basis or (kind, order)
        The model, or arguments of :func:`rplearn.core.bases.make_basis` (default SH-10).
    role : str or None
        Use only the units of this role (default the learning units); None uses all.
    packet_rate_hz : float
        Expected packets per second in one direction [Hz].
    limits : PlanLimits, optional
        Refuse (``PlanError``) units that exceed them.
    coverage_bin_deg : float
        Cell size of the coverage maps [deg].
    attitude : NominalAttitude, optional
        Nominal attitude model (wind, drag, tilt), see :func:`plan_directions`.
    """
    from rplearn.core.lsq.solver import identifiability

    sub = campaign.with_role(role) if role is not None else campaign
    units = sub.summarize(limits)
    if not isinstance(basis, Basis):
        kind, order = basis
        basis = make_basis(kind, int(order))
    dirs, tx_idx, rx_idx, nodes = plan_directions(sub, packet_rate_hz, attitude)
    report = identifiability(dirs, tx_idx, rx_idx, len(nodes), basis, node_names=nodes)
    coverage: dict[str, CoverageMap] = {}
    for i, node in enumerate(nodes):
        az = np.concatenate([dirs.az_tx[tx_idx == i], dirs.az_rx[rx_idx == i]])
        el = np.concatenate([dirs.el_tx[tx_idx == i], dirs.el_rx[rx_idx == i]])
        coverage[node] = coverage_map(node, az, el, coverage_bin_deg)
    graph_ok = link_graph_identifies_gains(sub.links())
    return PlanCheck(
        basis_label=_label(basis),
        nodes=nodes,
        n_samples=int(report.n_samples),
        n_columns=int(report.n_columns),
        rank=int(report.rank),
        null_dim=int(report.null_dim),
        expected_null_dim=int(report.expected_null_dim),
        condition_number=float(report.condition_number),
        decoupled=bool(report.null_dim <= report.expected_null_dim),
        absolute_gains=bool(graph_ok and report.null_dim == 0),
        coverage=coverage,
        units=units,
    )


def _label(basis: Basis) -> str:
    try:
        return str(basis.label)
    except Exception:  # pragma: no cover - a basis without a label
        return type(basis).__name__
