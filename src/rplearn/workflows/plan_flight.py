"""A written plan flown in the simulator under its own node names (``rplearn simulate --plan``).

``rplearn trajectory --optimize --from-model`` plans under the earlier flight's names (a real
SiK log's station ``gcs`` and drone ``sys1``), which no preset has. The plan's nodes are flown
as the preset's by role: a node the plan's references hold still (within 5 m and 30 deg, the
rule a fit records a flight's station by, :func:`rplearn.plan.campaign.still_nodes`) as the
preset's station (``ground``'s ``G``), a moving node as its drone; two drones as a two-drone
preset's, in sorted order; or as ``node_map`` says (``--node-map gcs=G,sys1=D``). The preset's
per-node configuration is renamed to the plan's names (:func:`rplearn.sim.config.renamed_nodes`),
so that the logs, references and ground truth name ``gcs`` and ``sys1``, and a fit of them is a
model of the user's nodes. A plan whose layout the preset cannot fly (a station and a drone on
two drones, or the other way round) is refused, naming the presets that fly it.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

from rplearn._argtypes import check_types
from rplearn.errors import InputError
from rplearn.plan.campaign import still_nodes
from rplearn.plan.references import read_plan


@check_types
@dataclass(frozen=True)
class PlanFlight:
    """A preset's simulation flying a written plan.

    Attributes
    ----------
    config : SimulationConfig
        The preset's antennas, vehicles and radio flying the plan, under the plan's node names.
    names : dict of str to str
        Each preset node flown as which plan node (empty: the plan's nodes are the preset's).
    text : str
        The mapping in one line (empty without one).
    """

    config: Any
    names: dict[str, str]
    text: str = ""


def _layout(nodes: tuple[str, ...], still: tuple[str, ...]) -> str:
    """Who flies: ``a station G and a drone D``, ``two drones A, B``."""
    moving = [n for n in nodes if n not in still]
    if len(still) == 1 and moving:
        return f"a station {still[0]} and {'a drone' if len(moving) == 1 else 'drones'} {', '.join(moving)}"
    if not still:
        return f"{len(nodes) if len(nodes) != 2 else 'two'} drones {', '.join(nodes)}"
    return f"stations {', '.join(still)}" + (f" and drones {', '.join(moving)}" if moving else "")


def _fitting_presets(stations: int) -> list[str]:
    """The presets whose own campaign holds ``stations`` nodes still, beside moving ones."""
    from rplearn.sim.presets import PRESET_NAMES, make_preset

    fits = []
    for name in PRESET_NAMES:
        campaign = make_preset(name).campaign
        if len(still_nodes(campaign)) == stations and len(campaign.nodes) > stations:
            fits.append(name)
    return fits


def _by_role(preset: str, plan_dir: str, plan: tuple[tuple[str, ...], tuple[str, ...]],
             ours: tuple[tuple[str, ...], tuple[str, ...]]) -> dict[str, str]:
    """Each preset node flown as which plan node, by role (module docstring), or a one-line refusal."""
    (nodes, still), (preset_nodes, preset_still) = plan, ours
    if len(nodes) == 2 and len(still) == 1 and len(preset_still) == 1 and len(preset_nodes) >= 2:
        mover = next(n for n in preset_nodes if n not in preset_still)
        return {preset_still[0]: still[0], mover: next(n for n in nodes if n != still[0])}
    if len(nodes) == 2 and not still and not preset_still and len(preset_nodes) >= 2:
        return dict(zip(preset_nodes[:2], nodes))
    fits = _fitting_presets(len(still)) if len(nodes) == 2 and len(still) <= 1 else []
    fly = (f"fly it with --preset {fits[0]}" + (f" (or {', '.join(fits[1:])})" if fits[1:] else "") if fits
           else "no preset flies it")
    raise InputError(f"{plan_dir}: the plan flies {_layout(nodes, still)}; preset {preset} flies "
                     f"{_layout(preset_nodes, preset_still)}: {fly}, or map its nodes with --node-map PLAN=PRESET,...",
                     param="preset")


def _stated(plan_dir: str, preset: str, nodes: tuple[str, ...], preset_nodes: tuple[str, ...],
            node_map: dict[str, str]) -> dict[str, str]:
    """Each preset node flown as which plan node, as ``node_map`` (plan node -> preset node) says,
    or a one-line refusal naming what does not fit."""
    given = ", ".join(f"{a}={b}" for a, b in node_map.items())
    unknown = sorted(set(node_map) - set(nodes))
    if unknown:
        raise InputError(f"node_map: {given}: {', '.join(unknown)} is no node of the plan in {plan_dir} "
                         f"({', '.join(nodes)})", param="node_map")
    missing = sorted(set(nodes) - set(node_map))
    if missing:
        raise InputError(f"node_map: {given}: the plan's {', '.join(missing)} is not mapped (the plan in {plan_dir} flies "
                         f"{', '.join(nodes)})", param="node_map")
    foreign = sorted(set(node_map.values()) - set(preset_nodes))
    if foreign:
        raise InputError(f"node_map: {given}: {', '.join(foreign)} is no node of preset {preset} "
                         f"({', '.join(preset_nodes)})", param="node_map")
    if len(set(node_map.values())) != len(node_map):
        raise InputError(f"node_map: {given}: two plan nodes mapped to one preset node (expected one to one)",
                         param="node_map")
    return {b: a for a, b in node_map.items()}


@check_types
def plan_flight(preset: str, plan_dir: str, node_map: dict[str, str] | None = None) -> PlanFlight:
    """A simulator preset flying a folder of reference files instead of its own campaign
    (``rplearn simulate --plan``): its antennas, vehicles and radio, under the plan's node names
    (module docstring); the plan's units (:func:`rplearn.plan.references.read_plan`). Its
    electronics offsets and dropouts, drawn for its own campaign, are kept.

    Parameters
    ----------
    preset : str
        A preset of :func:`rplearn.sim.presets.make_preset`.
    plan_dir : str
        The folder of reference files ``<unit>_<node>.csv``.
    node_map : dict of str to str, optional
        Each plan node flown as which preset node; without it, a plan whose nodes are all the
        preset's keeps them, any other is mapped by role.

    Raises
    ------
    InputError
        One line: the plan is not a folder of reference files (``param="plan"``); its layout is
        not the preset's (naming both and the presets that fly it, ``param="preset"``);
        ``node_map`` names a node neither has, leaves a plan node out, or is not one to one
        (``param="node_map"``).
    """
    from rplearn.sim.config import renamed_nodes
    from rplearn.sim.presets import make_preset

    config = make_preset(preset)
    campaign = read_plan(plan_dir)
    nodes, preset_nodes = campaign.nodes, tuple(sorted(config.node_antennas))
    if node_map is None and set(nodes) <= set(preset_nodes):
        return PlanFlight(replace(config, campaign=campaign), {})
    preset_still = still_nodes(config.campaign)
    if node_map is not None:
        names = _stated(plan_dir, preset, nodes, preset_nodes, node_map)
    else:
        names = _by_role(preset, plan_dir, (nodes, still_nodes(campaign)), (tuple(config.campaign.nodes), preset_still))
    inverse = {plan: ours for ours, plan in names.items()}
    roles = ", ".join(inverse[n] + (" (station)" if inverse[n] in preset_still else "") for n in nodes)
    how = " (--node-map)" if node_map is not None else ""
    text = f"flying plan nodes {', '.join(nodes)} as the {preset} preset's {roles}{how}"
    return PlanFlight(renamed_nodes(config, names, campaign), names, text)


@check_types
def plan_config(preset: str, plan_dir: str) -> Any:
    """The :class:`~rplearn.sim.config.SimulationConfig` of :func:`plan_flight` (its nodes mapped
    by role)."""
    return plan_flight(preset, plan_dir).config


__all__ = ["PlanFlight", "plan_config", "plan_flight"]
