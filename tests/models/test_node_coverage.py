"""The nodes' coverage grids as jobs (rplearn.models.node_coverage): the same grids, bit for bit,
however the work is cut and wherever it runs, and riding along with a fit's statistics."""

from __future__ import annotations

import numpy as np
import pytest

import rplearn.models.node_coverage as node_coverage
from rplearn.core.coverage import coverage_grid
from rplearn.core.geometry import Directions
from rplearn.data.tables import LinkSamples
from rplearn.models.node_coverage import CoverageWork, node_coverage_grids


def _samples(n: int, seed: int, nodes: tuple[str, ...] = ("A", "B", "C"), one_link: bool = False) -> LinkSamples:
    rng = np.random.default_rng(seed)
    k = len(nodes)
    tx = np.zeros(n, np.intp) if one_link else rng.integers(0, k, n)
    rx = (tx + (1 if one_link else rng.integers(1, k, n))) % k
    az = rng.normal(0.0, 0.7, (2, n))
    el = rng.uniform(-0.6, 0.3, (2, n))
    y = rng.normal(0.0, 3.0, n)
    return LinkSamples(Directions(az[0], el[0], az[1], el[1]), tx, rx, nodes, y, np.full(n, 30.0))


def _alone(parts: list[LinkSamples], k: int, previous=None) -> list[float]:
    """Node ``k``'s grid from all its directions at once (``coverage_grid``, as before the jobs)."""
    az = np.concatenate([np.r_[p.directions.az_tx[p.tx_index == k], p.directions.az_rx[p.rx_index == k]] for p in parts])
    el = np.concatenate([np.r_[p.directions.el_tx[p.tx_index == k], p.directions.el_rx[p.rx_index == k]] for p in parts])
    return np.round(coverage_grid(az, el, previous), 1).tolist()


@pytest.mark.parametrize("job_samples", [7, 1000, 32_768])
def test_the_grids_do_not_depend_on_how_the_work_is_cut(monkeypatch, job_samples):
    monkeypatch.setattr(node_coverage, "COVERAGE_JOB_SAMPLES", job_samples)
    parts = [_samples(3_000, 1), _samples(25, 2), _samples(0, 3)]
    work = CoverageWork(parts)
    assert len(work.jobs) == 3 * sum(max(1, -(-len(p) // job_samples)) for p in parts)
    grids = work.run()
    assert list(grids) == ["A", "B", "C"]
    for k, node in enumerate(grids):
        assert grids[node] == _alone(parts, k)
    # the jobs in another order, the masks put back in the jobs' order: the same grids
    masks = [None] * len(work.jobs)
    for i in reversed(range(len(work.jobs))):
        masks[i] = work.jobs[i]()
    assert work.grids(masks) == grids


def test_earlier_grids_and_a_node_without_directions():
    parts = [_samples(2_000, 4, ("A", "B", "C", "D"))]
    parts[0].tx_index[parts[0].tx_index == 3] = 0  # D never transmits ...
    parts[0].rx_index[parts[0].rx_index == 3] = 1  # ... nor receives (and no sample has tx == rx)
    keep = parts[0].tx_index != parts[0].rx_index
    p = parts[0]
    parts = [LinkSamples(Directions(*(np.asarray(a)[keep] for a in p.directions)), p.tx_index[keep], p.rx_index[keep],
                         p.nodes, p.joint_gain_db[keep], p.distance_m[keep])]
    previous = {"A": np.full(16384, 2.0), "D": np.full(16384, 7.5)}
    grids = node_coverage_grids(parts, previous)
    assert grids["D"] == [7.5] * 16384  # no direction of its own: 180 everywhere, the earlier grid's minimum
    assert grids["A"] == _alone(parts, 0, previous["A"])
    assert grids["B"] == _alone(parts, 1)
    assert node_coverage_grids(_samples(10, 5), None)["A"] == _alone([_samples(10, 5)], 0)


def test_a_fit_gives_the_grids_of_its_samples_with_the_jobs_riding_along(monkeypatch):
    """SH (statistics on the workers, a small solve): the coverage jobs are queued behind the
    statistics' last block; the model's grids are those of its samples computed alone."""
    from rplearn.core.lsq import runtime as runtime_module
    from rplearn.models.fit import fit_model
    from rplearn.models.spec import ModelSpec

    samples = _samples(40_000, 6, ("A", "B"), one_link=True)  # one link of 40,000 samples: two blocks on the workers
    started: list[int] = []
    original = runtime_module.Overlapped.start

    def spy(self, pool):
        started.append(len(self._jobs))
        return original(self, pool)

    monkeypatch.setattr(runtime_module.Overlapped, "start", spy)
    fitted = fit_model(samples, ModelSpec("sh", 4))
    assert started == [len(CoverageWork(samples).jobs)] == [4]
    assert fitted.model.training.coverage_deg == node_coverage_grids(samples)
    started.clear()
    fitted = fit_model(samples, ModelSpec.parse("bg-3"))  # statistics in the caller: the jobs run after
    assert started == []
    assert fitted.model.training.coverage_deg == node_coverage_grids(samples)


def test_an_automatic_fit_accumulates_its_units_on_the_workers_and_stores_their_grids(monkeypatch):
    """``fit_auto``: the units' statistics computed on the workers (a unit each, the first of three
    halved so that both workers stay busy to the end) are the ones computed one after the other
    (the halved unit's up to the rounding of its two halves' sum), and the grids' jobs ride
    behind them."""
    from rplearn.core.lsq import runtime as runtime_module
    from rplearn.core.lsq.normal_equations import NormalEquations
    from rplearn.models.auto import fit_auto
    from rplearn.models.spec import ModelSpec

    # OpenBLAS's sums depend on its thread count, which the policy sets from the free cores:
    # one thread for the fit and for the units computed alone below
    monkeypatch.setenv("RPLEARN_THREADS", "1")
    units = {f"u{i}": _samples(9_000, 10 + i, ("A", "B")) for i in range(3)}
    started: list[int] = []
    original = runtime_module.Overlapped.start

    def spy(self, pool):
        started.append(len(self._jobs))
        return original(self, pool)

    added: list[tuple[NormalEquations, np.ndarray]] = []
    original_add = NormalEquations.add

    def add(self, directions, *args, **kwargs):
        out = original_add(self, directions, *args, **kwargs)
        added.append((out, np.asarray(directions.az_tx)))
        return out

    from rplearn.models import auto as auto_module

    given: dict[str, NormalEquations] = {}
    original_fit = auto_module.fit_from_statistics

    def fit_from_statistics(stats, *args, **kwargs):
        given.update(stats)
        return original_fit(stats, *args, **kwargs)

    monkeypatch.setattr(runtime_module.Overlapped, "start", spy)
    monkeypatch.setattr(NormalEquations, "add", add)
    monkeypatch.setattr(auto_module, "fit_from_statistics", fit_from_statistics)
    fitted, _ = fit_auto(units, ModelSpec("sh", 4))
    assert started == [len(CoverageWork(list(units.values())).jobs)] == [6]
    assert fitted.model.training.coverage_deg == node_coverage_grids(list(units.values()))
    assert sorted(len(az) for _, az in added) == [4_500, 4_500, 9_000, 9_000]  # u0 in halves
    assert list(given) == list(units)
    for name, s in units.items():  # each unit's statistics as computed alone, in this thread
        alone = original_add(NormalEquations(given[name].basis, 2), s.directions, s.tx_index, s.rx_index, s.joint_gain_db)
        if name == "u0":  # the sum of its halves
            np.testing.assert_allclose(given[name].gram, alone.gram, rtol=1e-13, atol=1e-13 * np.abs(alone.gram).max())
            np.testing.assert_allclose(given[name].rhs, alone.rhs, rtol=1e-13, atol=1e-13 * np.abs(alone.rhs).max())
            assert given[name].n_samples == alone.n_samples and given[name].yty == pytest.approx(alone.yty, rel=1e-14)
        else:
            np.testing.assert_array_equal(given[name].gram, alone.gram)
            np.testing.assert_array_equal(given[name].rhs, alone.rhs)
