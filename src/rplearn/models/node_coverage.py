"""The coverage grid each pattern model stores, per node: the work split into jobs (issue 30).

A node's grid (:func:`rplearn.core.coverage.coverage_grid`) is the angle from each point of a
Fibonacci grid to the nearest grid point whose cell holds one of the node's learning
directions. Finding those cells (one nearest-point query per direction) is most of the work
and splits exactly by samples: the occupied cells of all the directions are the union of those
of any partition of them. So the work is cut into jobs of at most :data:`COVERAGE_JOB_SAMPLES`
samples per node, which the statistics' workers can run in any order while a fit's last block
or its solve leaves one of them idle (:func:`rplearn.models.fit.fit_model`); the grids are then
finished per node (the distances to the occupied cells, an earlier grid, the rounding of the
model file). The grids are the same, bit for bit, however the jobs are cut and wherever they
run.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from functools import partial
from typing import Any

import numpy as np

from rplearn.data.tables import LinkSamples

#: Directions (all nodes together) from which the nodes' coverage grids are computed on the
#: statistics' worker threads (pykdtree and numpy release the interpreter lock).
PARALLEL_COVERAGE_DIRECTIONS = 20_000
#: Samples of one sample set per job of :class:`CoverageWork` (the paper's 56,005: two jobs per
#: node, four in all, which two workers share evenly with a fit's three blocks of statistics).
COVERAGE_JOB_SAMPLES = 32_768


def _occupied(part: LinkSamples, k: int, lo: int, hi: int) -> np.ndarray:
    """The grid points occupied by node ``k``'s directions in samples ``lo:hi`` of ``part``
    (its transmitter and its receiver ends)."""
    from rplearn.core.coverage import occupied_grid_points

    d = part.directions
    rows = slice(lo, hi)
    t = np.asarray(part.tx_index)[rows] == k
    r = np.asarray(part.rx_index)[rows] == k
    az = np.concatenate([np.asarray(d.az_tx)[rows][t], np.asarray(d.az_rx)[rows][r]])
    el = np.concatenate([np.asarray(d.el_tx)[rows][t], np.asarray(d.el_rx)[rows][r]])
    return occupied_grid_points(az, el)


class CoverageWork:
    """The nodes' coverage grids of one or several sample sets (the units of one fit, same
    nodes), as jobs (:attr:`jobs`: callables without arguments giving occupied-cell masks, in
    any order, on any thread) and a finishing step (:meth:`grids`).

    Parameters
    ----------
    samples : LinkSamples or sequence of LinkSamples
        The learning samples (several sets are pooled).
    previous : mapping, optional
        Earlier grids per node (chunked data), combined by the minimum.
    """

    def __init__(self, samples: LinkSamples | Sequence[LinkSamples], previous: Mapping[str, Any] | None = None) -> None:
        parts = [samples] if isinstance(samples, LinkSamples) else list(samples)
        self.nodes: tuple[str, ...] = tuple(parts[0].nodes)
        self.previous = previous
        self.n_directions = 2 * sum(len(part) for part in parts)
        self.node_of_job: list[int] = []
        self.jobs: list[Callable[[], np.ndarray]] = []
        for part in parts:
            n = len(part)
            for lo in range(0, max(n, 1), COVERAGE_JOB_SAMPLES):
                for k in range(len(self.nodes)):
                    self.node_of_job.append(k)
                    self.jobs.append(partial(_occupied, part, k, lo, min(n, lo + COVERAGE_JOB_SAMPLES)))

    @property
    def parallel(self) -> bool:
        """Whether the work is worth the two worker threads (several nodes, many directions)."""
        return len(self.nodes) > 1 and self.n_directions >= PARALLEL_COVERAGE_DIRECTIONS

    def grids(self, masks: Sequence[np.ndarray]) -> dict[str, list[float]]:
        """Per node, its grid rounded to 0.1 degree, from the jobs' masks (in the jobs' order)."""
        from rplearn.core.coverage import COVERAGE_GRID_POINTS

        occupied = [np.zeros(COVERAGE_GRID_POINTS, bool) for _ in self.nodes]
        for k, mask in zip(self.node_of_job, masks):
            occupied[k] |= mask
        finish = [partial(self._finish, k, occupied[k]) for k in range(len(self.nodes))]
        return dict(zip(self.nodes, self._call(finish)))

    def _call(self, jobs: Sequence[Callable[[], Any]]) -> list[Any]:
        """The jobs' results in order: on the workers when :attr:`parallel`, else here."""
        if self.parallel:
            from rplearn.core.lsq.runtime import DEFAULT_RUNTIME

            return list(DEFAULT_RUNTIME.in_order(lambda job: job(), jobs))
        return [job() for job in jobs]

    def _finish(self, k: int, occupied: np.ndarray) -> list[float]:
        return _rounded_grid(occupied, None if self.previous is None else self.previous.get(self.nodes[k]))

    def run(self) -> dict[str, list[float]]:
        """The grids, the jobs run here (on the workers when :attr:`parallel`)."""
        return self.grids(self._call(self.jobs))


def node_coverage_grids(
    samples: LinkSamples | Sequence[LinkSamples], previous: Mapping[str, Any] | None = None
) -> dict[str, list[float]]:
    """Per node, the coverage grid of its learning directions (:func:`rplearn.core.coverage.coverage_grid`),
    rounded to 0.1 degree for the model file; several sample sets (the units of one fit, same
    nodes) are pooled, and ``previous`` grids are combined (chunked data). With many directions
    the work is done on the two worker threads of
    :data:`~rplearn.core.lsq.runtime.DEFAULT_RUNTIME` (each grid is the same as alone)."""
    return CoverageWork(samples, previous).run()


def _rounded_grid(occupied: np.ndarray, previous: Any = None) -> list[float]:
    """A node's grid from its occupied mask (and its ``previous`` grid), rounded to 0.1 degree for the model file."""
    from rplearn.core.coverage import grid_distance_deg

    return np.round(grid_distance_deg(occupied, previous), 1).tolist()


def occupied_masks(samples: LinkSamples) -> list[np.ndarray]:
    """Per node (in ``samples.nodes``' order), the mask of the grid points its learning directions
    occupy (:func:`rplearn.core.coverage.occupied_grid_points`): the union of a session's masks
    gives, with :func:`grids_of_occupied`, the grids :func:`node_coverage_grids` combines batch by
    batch, bit for bit (a grid point's nearest occupied point in a union is the nearest of the
    parts', and rounding commutes with the minimum)."""
    return [_occupied(samples, k, 0, len(samples)) for k in range(len(samples.nodes))]


def grids_of_occupied(nodes: Sequence[str], occupied: Sequence[np.ndarray]) -> dict[str, list[float]]:
    """Per node, its grid rounded to 0.1 degree from its occupied mask (:func:`occupied_masks`)."""
    return {str(node): _rounded_grid(mask) for node, mask in zip(nodes, occupied)}


__all__ = ["COVERAGE_JOB_SAMPLES", "PARALLEL_COVERAGE_DIRECTIONS", "CoverageWork", "grids_of_occupied", "node_coverage_grids",
           "occupied_masks"]
