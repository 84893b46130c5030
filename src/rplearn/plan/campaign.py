"""Campaigns of trajectory units, and schedules of pairs for groups of drones (paper Sec. V-C).

Several units (:class:`~rplearn.plan.trajectory.TrajectoryUnit`) with different ``psi0`` make
a *campaign*, flown one after the other (the paper's default: learning units
``psi0 = 0, 24, 48`` deg and a testing unit ``psi0 = 36`` deg, Sec. V-C). For more than two
drones, :func:`pair_schedule` picks pairs whose link graph identifies absolute gains
(docs/conventions.md: every connected part needs an odd cycle), and :func:`group_campaign` flies the
paper's units with each pair. :func:`write_references` writes the per-drone references.
"""

from __future__ import annotations

import os
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import NDArray

from rplearn._argtypes import check_types
from rplearn._atomic import atomic_path
from rplearn.data.flight_layout import holds_still
from rplearn.errors import InputError
from rplearn.plan.trajectory import PlanLimits, TrajectoryUnit, UnitSummary, summarize_unit

FloatArray = NDArray[np.float64]


@check_types
@dataclass(frozen=True)
class Campaign:
    """Trajectory units flown one after the other, with a gap (battery swap) between them.

    Attributes
    ----------
    units : tuple of TrajectoryUnit
    gap_s : float
        Time between the end of one unit and the start of the next [s].
    """

    units: tuple[TrajectoryUnit, ...]
    gap_s: float = 60.0

    def __post_init__(self) -> None:
        if not self.units:
            raise InputError("campaign units: expected at least one trajectory unit", param="units")
        labels = [u.label for u in self.units]
        if len(set(labels)) != len(labels):
            raise InputError(f"campaign units: labels must be unique, got {labels}", param="units")

    @property
    def nodes(self) -> tuple[str, ...]:
        """All node ids flying in the campaign, sorted."""
        return tuple(sorted({n for u in self.units for n in u.nodes}))

    def start_times_s(self) -> FloatArray:
        """Start time of every unit [s]."""
        d = np.array([u.duration_s for u in self.units])
        return np.concatenate([[0.0], np.cumsum(d + self.gap_s)[:-1]])

    @property
    def duration_s(self) -> float:
        """Time from the first unit's start to the last unit's end [s]."""
        return float(self.start_times_s()[-1] + self.units[-1].duration_s)

    def links(self) -> list[tuple[str, str]]:
        """Distinct pairs of nodes that fly a unit together (undirected, sorted)."""
        return sorted({tuple(sorted(u.nodes)) for u in self.units})  # type: ignore[misc]

    def with_role(self, role: str) -> Campaign:
        """The sub-campaign of units with the given role."""
        units = tuple(u for u in self.units if u.role == role)
        if not units:
            raise InputError(f"campaign: no unit has role {role!r}", param="role")
        return replace(self, units=units)

    def summarize(self, limits: PlanLimits | None = None) -> list[UnitSummary]:
        """:func:`summarize_unit` of every unit (raises :class:`~rplearn.errors.PlanError` on a violated limit)."""
        return [summarize_unit(u, limits) for u in self.units]


@check_types
def still_nodes(campaign: Campaign, rate_hz: float = 1.0) -> tuple[str, ...]:
    """The nodes that a campaign's references hold still, sorted: over all the units a node flies,
    its reference positions and headings sampled at ``rate_hz`` [Hz] stay within 5 m and 30 deg
    of one pose, the rule by which a fit records a flight's station
    (:func:`rplearn.data.flight_layout.holds_still`). The ``ground`` preset's station ``G``; a
    written plan's station (``trajectory --optimize --station``, or planned for a flight whose
    station held still); none of two drones."""
    poses: dict[str, list[FloatArray]] = {}
    for unit in campaign.units:
        ref = unit.sample(rate_hz)
        half = 0.5 * ref.yaw_rad
        for j, node in enumerate(unit.nodes):
            level = np.zeros((ref.t_s.size, 4))
            level[:, 0], level[:, 3] = np.cos(half[:, j]), np.sin(half[:, j])  # a heading about the vertical
            poses.setdefault(node, []).append(np.hstack([ref.position_enu_m[:, j, :], level]))
    return tuple(sorted(node for node, rows in poses.items() if holds_still(np.concatenate(rows))))


@check_types
def paper_campaign(
    nodes: tuple[str, str] = ("A", "B"),
    learning_psi0_deg: Sequence[float] = (0.0, 24.0, 48.0),
    testing_psi0_deg: Sequence[float] = (36.0,),
    **unit_options: object,
) -> Campaign:
    """The paper's campaign (Sec. V-C): learning units psi0 = 0, 24, 48 deg, testing 36 deg.

    Parameters
    ----------
    nodes : (str, str)
        The two drones.
    learning_psi0_deg, testing_psi0_deg : sequence of float
        Initial headings of the learning and the testing units [deg].
    **unit_options
        Further :class:`~rplearn.plan.trajectory.TrajectoryUnit` fields shared by every unit,
        e.g. ``distance_m`` [m], ``height_m`` [m], ``n_loops``, ``speed_m_s`` [m/s]; an
        :class:`~rplearn.errors.InputError` about one of them carries its name as ``param``.
    """
    units = [
        TrajectoryUnit(nodes=nodes, psi0_deg=float(p), role="learning", label=f"learn_{p:g}", **unit_options)  # type: ignore[arg-type]
        for p in learning_psi0_deg
    ] + [
        TrajectoryUnit(nodes=nodes, psi0_deg=float(p), role="testing", label=f"test_{p:g}", **unit_options)  # type: ignore[arg-type]
        for p in testing_psi0_deg
    ]
    return Campaign(tuple(units))


# ---------------------------------------------------------------------------------------------
# Groups of more than two drones


@check_types
def link_graph_identifies_gains(pairs: Iterable[tuple[str, str]]) -> bool:
    """Whether a link graph identifies absolute gains: every component has an odd cycle.

    A connected component without an odd cycle is bipartite, and an alternating ``+c/-c``
    constant on its two sides leaves every joint gain unchanged (docs/conventions.md).
    """
    adj: dict[str, set[str]] = {}
    for a, b in pairs:
        if a == b:
            raise InputError(f"link graph: a node cannot link to itself ({a})", param="pairs")
        adj.setdefault(a, set()).add(b)
        adj.setdefault(b, set()).add(a)
    if not adj:
        return False
    colour: dict[str, int] = {}
    for start in adj:
        if start in colour:
            continue
        colour[start] = 0
        stack = [start]
        odd = False
        while stack:
            v = stack.pop()
            for w in adj[v]:
                if w not in colour:
                    colour[w] = 1 - colour[v]
                    stack.append(w)
                elif colour[w] == colour[v]:
                    odd = True
        if not odd:
            return False
    return True


@check_types
def pair_schedule(nodes: Sequence[str]) -> list[tuple[str, str]]:
    """Pairs of drones to fly units with, so that the link graph identifies absolute gains.

    Three or more drones: a triangle on the first three, each further drone paired with the
    one before it (connected, one odd cycle, ``n`` pairs). Two drones: the single pair, which
    identifies only the shapes (paper Sec. V-A).
    """
    ids = [str(n) for n in nodes]
    if len(ids) < 2 or len(set(ids)) != len(ids):
        raise InputError(f"nodes: expected at least two distinct node ids, got {ids}", param="nodes")
    if len(ids) == 2:
        return [(ids[0], ids[1])]
    pairs = [(ids[0], ids[1]), (ids[1], ids[2]), (ids[2], ids[0])]
    pairs += [(ids[i - 1], ids[i]) for i in range(3, len(ids))]
    return pairs


@check_types
def group_campaign(
    nodes: Sequence[str],
    learning_psi0_deg: Sequence[float] = (0.0, 24.0, 48.0),
    testing_psi0_deg: Sequence[float] = (36.0,),
    **unit_options: object,
) -> Campaign:
    """A campaign for a group: for each pair of :func:`pair_schedule`, the paper's units."""
    units: list[TrajectoryUnit] = []
    for a, b in pair_schedule(nodes):
        for role, psis in (("learning", learning_psi0_deg), ("testing", testing_psi0_deg)):
            for p in psis:
                units.append(
                    TrajectoryUnit(
                        nodes=(a, b),
                        psi0_deg=float(p),
                        role=role,
                        label=f"{'learn' if role == 'learning' else 'test'}_{a}{b}_{p:g}",
                        **unit_options,  # type: ignore[arg-type]
                    )
                )
    return Campaign(tuple(units))


@check_types
def write_references(
    campaign: Campaign | TrajectoryUnit, out_dir: str, rate_hz: float = 10.0
) -> list[str]:
    """Write per-unit, per-drone references ``t, x, y, z, yaw_deg`` as CSV files.

    Files are named ``<unit label>_<node>.csv``; ``t`` starts at 0 for each unit [s].

    Returns
    -------
    list of str
        The paths written.
    """
    units = (campaign,) if isinstance(campaign, TrajectoryUnit) else campaign.units
    os.makedirs(out_dir, exist_ok=True)
    paths: list[str] = []
    for unit in units:
        ref = unit.sample(rate_hz)
        for j, node in enumerate(unit.nodes):
            path = os.path.join(out_dir, f"{unit.label}_{node}.csv")
            with atomic_path(path) as tmp:
                ref.table(j).to_csv(tmp, index=False, float_format="%.4f")
            paths.append(path)
    return paths


__all__ = [
    "Campaign",
    "group_campaign",
    "link_graph_identifies_gains",
    "pair_schedule",
    "paper_campaign",
    "still_nodes",
    "write_references",
]
