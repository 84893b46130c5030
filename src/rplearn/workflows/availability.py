"""``rplearn links --sensitivity``: a swarm's links with each one's availability, and the
probability over time that the swarm is connected (:mod:`rplearn.analysis.availability`)."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import cast

import pandas as pd

from rplearn._argtypes import check_types
from rplearn.analysis.availability import AvailabilityOptions, SwarmAvailability, link_availability_column, swarm_availability
from rplearn.analysis.swarm import SwarmOptions, predict_swarm
from rplearn.errors import InputError
from rplearn.io import ReaderOptions, read_logs
from rplearn.io.files import check_output_path, check_table_path, write_table
from rplearn.models.load import load_model
from rplearn.models.patterns import PatternSet
from rplearn.models.predict import frequency_mismatch
from rplearn.workflows.logs import LinksOutcome, reader_notes


@check_types
@dataclass(frozen=True)
class LinkFiles:
    """Where ``rplearn links`` writes: the links table, and optionally the per-time
    connectivity table and the plot."""

    links: str
    connectivity: str | None = None
    plot: str | None = None


@check_types
@dataclass(frozen=True)
class AvailabilityOutcome:
    """The links (with ``availability``), the connectivity (with ``p_connected``, ``p_path_*``)
    and the swarm's Monte Carlo result."""

    links: LinksOutcome
    swarm: SwarmAvailability


@check_types
def swarm_links_availability(
    model_path: str,
    pose_paths: Sequence[str],
    tx_power_dbm: float,
    files: LinkFiles,
    availability: AvailabilityOptions,
    options: SwarmOptions | None = None,
    reader_options: ReaderOptions | None = None,
) -> AvailabilityOutcome:
    """:func:`rplearn.workflows.logs.swarm_links` with availability: every link's
    ``P(RSSI >= sensitivity)`` (column ``availability``) and, per time, the Monte Carlo
    probability that the swarm is connected and that each named pair has a path (columns of the
    connectivity table). The links' ``up`` keeps ``options.min_rssi_dbm``; pass the sensitivity
    there too for one threshold throughout."""
    options = SwarmOptions() if options is None else options
    outputs = [p for p in (files.links, files.connectivity, files.plot) if p]
    for k, path in enumerate(outputs):
        check_output_path(path, [model_path, *pose_paths, *outputs[:k]])
        if path != files.plot:
            check_table_path(path)
    model = cast(PatternSet, load_model(model_path))  # predict_swarm refuses a baseline
    logs, meta = read_logs(pose_paths, reader_options)
    if logs.pose is None:
        raise InputError(f"{', '.join(pose_paths)}: no pose log found", param="pose_paths")
    source = ", ".join(pose_paths)
    mismatch = frequency_mismatch(model, [options.frequency_hz]) if options.frequency_hz is not None else None
    prediction = predict_swarm(model, logs.pose, tx_power_dbm, options, source=source)
    swarm = swarm_availability(model, logs.pose, tx_power_dbm, availability, options, source)
    links = prediction.links.copy()
    links["availability"] = link_availability_column(links, model, availability.sensitivity_dbm)
    extra = swarm.connectivity.drop(columns=["t", "n_missing"])
    connectivity = pd.concat([prediction.connectivity.reset_index(drop=True), extra.reset_index(drop=True)], axis=1)
    prediction = type(prediction)(links, connectivity, prediction.pattern_of, prediction.min_rssi_dbm,
                                  prediction.tx_power_dbm, prediction.frequency_hz, prediction.notes)
    write_table(links, files.links)
    if files.connectivity:
        write_table(connectivity, files.connectivity)
    if files.plot:
        from rplearn.viz.charts import plot_swarm

        plot_swarm(prediction, files.plot)
    return AvailabilityOutcome(LinksOutcome(prediction, reader_notes(meta), mismatch), swarm)


__all__ = ["AvailabilityOutcome", "LinkFiles", "swarm_links_availability"]
