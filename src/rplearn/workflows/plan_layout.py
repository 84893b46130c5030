"""Who flies the plan of ``trajectory --optimize`` and how often their radio reports: two drones
or a ground station and a drone, their names, and the packet rate.

Without an earlier flight's model these are the flags' (two drones ``A``, ``B``; ``--station``:
station ``G`` and drone ``D``; 80 packets/s). With ``--from-model`` the plan is made for that
flight's own layout where the flags say nothing: its nodes' names, its station when one node
held still in every learning row (``training.fixed_nodes``), and its radio's packet rate
(``training.packet_rate_hz``): a SiK telemetry link's 1 packet/s teaches 80 times less per second
than the default, and a station and a drone fly other manoeuvres than two drones.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Any

#: The packets per second a plan assumes in each link direction without a flag or a model's.
DEFAULT_PACKET_RATE_HZ = 80.0
#: Height of a ground station's antenna in a plan [m].
STATION_HEIGHT_M = 1.5
#: A node name a reference file can carry: ``read_plan`` parses ``<unit>_<node>.csv``, so no ``_``.
_SAFE_NAME = re.compile(r"^[A-Za-z0-9][A-Za-z0-9.-]{0,63}$")


@dataclass(frozen=True)
class PlanLayout:
    """The plan's nodes, where they start, which hold still, and the packet rate.

    Attributes
    ----------
    nodes : (str, str)
        The two nodes, the moving one first when one is a station.
    poses : dict of str to ((float, float, float), float)
        Each node's start position (ENU) [m] and heading [deg].
    fixed : tuple of str
        The station, or nothing.
    packet_rate_hz : float
        Packets per second in each link direction.
    text : str
        What was taken from the earlier flight's model (empty without one, or when the flags
        said everything).
    """

    nodes: tuple[str, str]
    poses: dict[str, tuple[tuple[float, float, float], float]]
    fixed: tuple[str, ...]
    packet_rate_hz: float
    text: str = ""


def plan_layout(station: bool | None, packet_rate_hz: float | None, distance_m: float, height_m: float,
                training: Any = None, model_nodes: tuple[str, ...] = ()) -> PlanLayout:
    """The layout of a plan (module docstring).

    Parameters
    ----------
    station : bool or None
        A ground station and a drone (True), two drones (False), or the earlier flight's layout
        (None; two drones without one).
    packet_rate_hz : float or None
        Stated packets per second, or None: the earlier flight's, else :data:`DEFAULT_PACKET_RATE_HZ`.
    distance_m, height_m : float
        Starting distance between the nodes (horizontal from a station) and drone height [m].
    training : TrainingSummary, optional
        The earlier flight's training summary (``fixed_nodes``, ``packet_rate_hz``).
    model_nodes : tuple of str
        The earlier flight's nodes.
    """
    recorded = getattr(training, "fixed_nodes", None)  # None: not recorded (a file written before fits recorded it)
    still = tuple(str(n) for n in (recorded or ()))
    names = tuple(str(n) for n in model_nodes)
    usable = len(names) == 2 and len(set(names)) == 2 and all(_SAFE_NAME.match(n) for n in names)
    one_still = len(names) == 2 and len(still) == 1 and still[0] in names
    said: list[str] = []
    if station is None and training is not None:
        station = one_still
        if one_still and usable:
            said.append(f"a ground station {still[0]}, held still in the earlier flight, and a drone "
                        f"{next(n for n in names if n != still[0])} (--two-drones plans for two drones)")
        elif one_still:
            said.append(f"a ground station G and a drone D, as the earlier flight's station {still[0]} held still (its "
                        "names cannot name a reference file; --two-drones plans for two drones)")
        elif recorded is None:
            said.append("two drones A, B: the earlier flight's layout is not recorded (a model file written before fits "
                        "recorded it, or of rows without poses; --station plans for a station)")
            usable = False
        elif usable:
            said.append(f"two drones {names[0]}, {names[1]}, as in the earlier flight (--station plans for a station)")
    if station:
        ground, mover = (still[0], next(n for n in names if n != still[0])) if one_still and usable else ("G", "D")
        nodes: tuple[str, str] = (mover, ground)
        poses = {ground: ((0.0, 0.0, STATION_HEIGHT_M), 0.0), mover: ((distance_m, 0.0, height_m), 180.0)}
        fixed: tuple[str, ...] = (ground,)
    else:
        a, b = names if usable and recorded is not None else ("A", "B")
        nodes = (a, b)
        poses = {a: ((-distance_m / 2.0, 0.0, height_m), 0.0), b: ((distance_m / 2.0, 0.0, height_m), 0.0)}
        fixed = ()
    rate = packet_rate_hz
    if rate is None:
        earlier = getattr(training, "packet_rate_hz", None)
        rate = float(earlier) if earlier is not None else DEFAULT_PACKET_RATE_HZ
        if earlier is not None:
            said.append(f"{rate:.3g} packets/s in each link direction, the earlier flight's (--packet-rate states another)")
        elif training is not None:
            said.append(f"{rate:g} packets/s, the default: the earlier flight's rate is not recorded (--packet-rate states it)")
    return PlanLayout(nodes, poses, fixed, float(rate), "; ".join(said))
