"""A fleet's flights as a partitioned dataset: the ``fleet`` preset.

A fleet operator logs every flight of many drones; the matched samples pile up as partitioned
Parquet, one file per flight. :func:`simulate_fleet` makes such a dataset: ``drones`` drones
(alternately the paper's camera drone and its sensor drone, each its own identity, named
``D01``, ``D02``, ...) fly the paper's campaign (three learning units and one testing unit) in
pairs taken in turn, one flight per seed; each flight's logs are simulated, matched
(:func:`rplearn.data.sync.synchronise`) and written to ``flight=NNNN/part-0.parquet`` with
its units renamed ``<unit>@fNNNN`` (``test...`` units stay test units). About 160,000 samples
a flight.
"""

from __future__ import annotations

import itertools
import os
import time
from collections.abc import Callable
from dataclasses import dataclass, field, replace

from rplearn._atomic import atomic_open, dump_json
from rplearn._budget import Cost, budget, check_work
from rplearn.data.sync import synchronise
from rplearn.errors import InputError
from rplearn.io.files import write_table
from rplearn.plan.campaign import Campaign
from rplearn.sim.config import SimulationConfig
from rplearn.sim.flight import simulate
from rplearn.sim.presets import make_preset

#: Drones of the default fleet.
FLEET_DRONES = 4
#: What one flight of each preset takes (measured: ``simulate --preset fleet --flights 2`` on a
#: loaded 2-core machine, 9.5 to 20 s, 22.5 MB of Parquet and 443 MB peak a paper flight): seconds, bytes written,
#: peak memory (one flight at a time).
FLIGHT_COST: dict[str, tuple[float, float, float]] = {"paper": (12.0, 24e6, 6e8), "smoke": (1.0, 1.5e6, 3e8)}


def fleet_cost(flights: float, preset: str = "paper") -> Cost:
    """What :func:`simulate_fleet` takes for ``flights`` flights of ``preset`` (:data:`FLIGHT_COST`)."""
    seconds, disk, memory = FLIGHT_COST.get(preset, FLIGHT_COST["paper"])
    return Cost(memory_bytes=memory, seconds=seconds * flights, disk_bytes=disk * flights)


@dataclass
class FleetResult:
    """What :func:`simulate_fleet` wrote.

    Attributes
    ----------
    out_dir : str
        The dataset's root folder (give it to ``fit`` and ``evaluate``).
    files : list of str
        One Parquet file per flight.
    samples : int
        Matched samples in all.
    pairs : list of tuple of str
        The pair of drones of each flight.
    elapsed_s : float
    """

    out_dir: str
    files: list[str] = field(default_factory=list)
    samples: int = 0
    pairs: list[tuple[str, str]] = field(default_factory=list)
    elapsed_s: float = 0.0


def drone_ids(drones: int) -> list[str]:
    """``D01``, ``D02``, ... (three digits from 100 drones)."""
    width = max(2, len(str(drones)))
    return [f"D{k + 1:0{width}d}" for k in range(drones)]


def fleet_pairs(drones: int) -> list[tuple[str, str]]:
    """Every pair of the fleet, in an order that links all drones early (a ring first)."""
    ids = drone_ids(drones)
    ring = [(ids[k], ids[(k + 1) % drones]) for k in range(drones)] if drones > 2 else [(ids[0], ids[1])]
    rest = [p for p in itertools.combinations(ids, 2) if p not in ring and p[::-1] not in ring]
    return ring + rest


def flight_config(pair: tuple[str, str], drones: int, preset: str = "paper") -> SimulationConfig:
    """A two-drone preset's campaign (``paper`` or ``smoke``, seconds long, for tests) flown
    by one pair of the fleet (odd drones carry the paper's camera drone's antenna and frame,
    even ones its sensor drone's)."""
    if preset not in ("paper", "smoke"):
        raise InputError(f"preset: a fleet flies the paper or smoke campaign, not {preset!r}", param="preset")
    paper = make_preset(preset)
    kinds = list(paper.node_antennas.values())
    ids = drone_ids(drones)
    antennas = {n: kinds[ids.index(n) % len(kinds)] for n in pair}
    units = tuple(replace(u, nodes=pair) for u in paper.campaign.units)
    offsets = (((pair[0], pair[1]), 1.0), ((pair[1], pair[0]), -2.5))
    return replace(paper, name="fleet", campaign=Campaign(units, gap_s=paper.campaign.gap_s), node_antennas=antennas,
                   radio=replace(paper.radio, link_offsets_db=offsets))


def simulate_fleet(
    out_dir: str, flights: int = 8, drones: int = FLEET_DRONES, seed: int = 0,
    progress: Callable[[int, int], None] | None = None, preset: str = "paper",
) -> FleetResult:
    """Simulate ``flights`` flights of a fleet and write them as a partitioned dataset.

    Parameters
    ----------
    out_dir : str
        Folder to write into (created; must hold no flight files yet).
    flights : int
        Number of flights (one file each).
    drones : int
        Drones in the fleet (at least 2).
    seed : int
        Flight ``k`` is simulated with seed ``seed * 100_003 + k``.
    progress : callable, optional
        Called with ``(flights done, flights)``.
    preset : {"paper", "smoke"}
        The campaign each flight flies (see :func:`flight_config`).
    """
    if int(flights) != flights or flights < 1:
        raise InputError(f"flights: expected a positive integer, got {flights!r}", param="flights")
    if int(drones) != drones or not 2 <= drones <= 999:
        raise InputError(f"drones: expected 2 to 999 drones, got {drones!r}", param="drones")
    if os.path.isdir(out_dir) and any(n.startswith("flight=") for n in os.listdir(out_dir)):
        raise InputError(f"{out_dir}: already holds flight=... folders; write the fleet into an empty folder",
                         param="out_dir")
    check_work("flights", int(flights), lambda n: fleet_cost(n, preset), "flights", limits=budget(out_dir))
    started = time.perf_counter()
    pairs = fleet_pairs(int(drones))
    flight_config(pairs[0], int(drones), preset)  # refuse a bad preset before writing anything
    result = FleetResult(out_dir)
    for k in range(int(flights)):
        pair = pairs[k % len(pairs)]
        sim = simulate(flight_config(pair, int(drones), preset), seed=int(seed) * 100_003 + k)
        matched = synchronise(sim.pose_log, sim.signal_log, source=f"flight {k}").dataset
        matched["unit"] = matched["unit"].astype(str) + f"@f{k:04d}"
        path = os.path.join(out_dir, f"flight={k:04d}", "part-0.parquet")
        os.makedirs(os.path.dirname(path), exist_ok=True)
        write_table(matched, path)
        result.files.append(path)
        result.samples += len(matched)
        result.pairs.append(pair)
        if progress is not None:
            progress(k + 1, int(flights))
    result.elapsed_s = time.perf_counter() - started
    with atomic_open(os.path.join(out_dir, "_fleet.json"), "w", encoding="utf-8") as fh:
        dump_json({"flights": int(flights), "drones": int(drones), "seed": int(seed), "samples": result.samples,
                   "pairs": [list(p) for p in result.pairs]}, fh, indent=1)
    return result


__all__ = ["FLEET_DRONES", "FleetResult", "drone_ids", "fleet_pairs", "flight_config", "simulate_fleet"]
