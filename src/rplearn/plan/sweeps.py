"""Loop sweeps: the paper unit's vertical circles with one drone's (or both drones') headings stepping.

The paper's unit (:class:`~rplearn.plan.trajectory.TrajectoryUnit`) flies ``2 n`` vertical
circles: in the first ``n`` the first drone steps through ``n`` headings while the second holds
its own, in the second ``n`` the other way round. Every circle sweeps the elevation of each
drone seen from the other through -90..90 deg, so each loop crosses both nodes' pole caps (the
peer straight above and below), at one heading per loop. A :class:`LoopSweepUnit` is one such
half, or both drones stepping at once, for ``n`` loops: it teaches the node that turns, or both,
as many headings as the paper unit in half its time, and is offered among the manoeuvre
candidates (:attr:`~rplearn.plan.manoeuvres.CandidateOptions.sweeps`) where the spread left sits
in the pole caps of one node.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rplearn._argtypes import check_types
from rplearn.errors import InputError
from rplearn.plan.trajectory import FloatArray, TrajectoryUnit

#: Which drone steps its heading from loop to loop.
TURNING = ("first", "second", "both")


@check_types
@dataclass(frozen=True)
class LoopSweepUnit(TrajectoryUnit):
    """``n`` vertical circles of the paper's unit with the ``turning`` drone(s) stepping by ``360/n`` deg.

    Attributes
    ----------
    turning : str
        ``"first"`` or ``"second"`` (that drone steps through ``psi0 + i 360/n``, the other
        holds ``psi0``) or ``"both"`` (the first steps by ``360/n``, the second by twice that, so
        that their relative heading changes from loop to loop too, which a lockstep would not:
        then each node's direction would fix the other's, and the loop could not tell the two
        patterns apart; an odd ``n`` of at least 3, where both visit all ``n`` headings).
    (the rest as :class:`~rplearn.plan.trajectory.TrajectoryUnit`; the unit flies ``n`` loops)
    """

    turning: str = "second"

    def __post_init__(self) -> None:
        if self.turning not in TURNING:
            raise InputError(f"turning: expected one of {', '.join(TURNING)}, got {self.turning!r}", param="turning")
        if self.turning == "both" and (int(self.n_loops) % 2 == 0 or self.n_loops < 3):
            raise InputError(f"n_loops: both drones turning needs an odd number of loops, at least 3, got {self.n_loops!r}",
                             param="n_loops")
        super().__post_init__()

    def heading_schedule_deg(self) -> FloatArray:
        """Headings relative to the line of both drones during each of the ``n`` loops [deg], shape (n, 2)."""
        steps = self.heading_step_deg * np.arange(int(self.n_loops))
        held = np.zeros_like(steps)
        first = steps if self.turning in ("first", "both") else held
        second = {"first": held, "second": steps, "both": np.mod(2.0 * steps, 360.0)}[self.turning]
        return self.psi0_deg + np.stack([first, second], axis=1)

    @property
    def path_length_m(self) -> float:
        """Path length flown by each drone [m] (``n`` circumferences ``pi d``)."""
        return float(self.n_loops * np.pi * self.distance_m)


def loop_sweeps(unit: TrajectoryUnit) -> list[tuple[str, LoopSweepUnit]]:
    """The loop sweeps flown where ``unit`` is (its circle, heading and loops): one loop with no
    turn when ``n = 1``, else the first and the second drone turning, and both for an odd ``n``;
    each with a name."""
    kw = dict(nodes=unit.nodes, psi0_deg=unit.psi0_deg, distance_m=unit.distance_m, height_m=unit.height_m,
              n_loops=unit.n_loops, speed_m_s=unit.speed_m_s, accel_m_s2=unit.accel_m_s2, yaw_rate_deg_s=unit.yaw_rate_deg_s,
              center_enu_m=unit.center_enu_m, line_azimuth_deg=unit.line_azimuth_deg)
    a, b = unit.nodes
    ways = ("second",) if unit.n_loops == 1 else TURNING if unit.n_loops % 2 else TURNING[:2]
    out = []
    for way in ways:
        who = {"first": a, "second": b, "both": f"{a} and {b}"}[way]
        what = "one loop" if unit.n_loops == 1 else f"{unit.n_loops} loops, {who} turning"
        out.append((f"loop sweep {what} psi0={unit.psi0_deg:g} ({a},{b})",
                    LoopSweepUnit(turning=way, label=f"{unit.label}_sweep_{way}", **kw)))  # type: ignore[arg-type]
    return out


__all__ = ["TURNING", "LoopSweepUnit", "loop_sweeps"]
