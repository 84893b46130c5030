"""Plan check: coverage, rank and condition number of a campaign before flying."""

from __future__ import annotations

import numpy as np
import pytest

from rplearn.core.bases import make_basis
from rplearn.errors import PlanError
from rplearn.plan.campaign import group_campaign, paper_campaign
from rplearn.plan.check import NominalAttitude, check_plan, coverage_map, plan_directions
from rplearn.plan.trajectory import PlanLimits
from rplearn.sim.presets import make_preset


@pytest.fixture(scope="module")
def paper_check():
    return check_plan(make_preset("paper").campaign, ("sh", 10))


def test_paper_plan_is_full_rank_minus_the_constant(paper_check) -> None:
    """Paper Sec. V-A/V-C: two drones identify everything but one constant (SH-10: 199 of 200)."""
    c = paper_check
    assert c.n_columns == 2 * make_basis("sh", 10).n_coef
    assert c.rank == c.n_columns - 1
    assert c.null_dim == 1 == c.expected_null_dim
    assert c.decoupled and not c.absolute_gains
    assert np.isfinite(c.condition_number) and c.condition_number < 1e4
    # learning units only: three units at ~80 packets per second
    assert c.n_samples == pytest.approx(3 * 80 * c.units[0].duration_s, rel=0.01)
    assert [u.label for u in c.units] == ["learn_0", "learn_24", "learn_48"]
    assert "rank 199" in c.summary()


def test_wind_tilt_improves_conditioning() -> None:
    campaign = make_preset("paper").campaign
    calm = check_plan(campaign, ("sh", 10))
    windy = check_plan(campaign, ("sh", 10), attitude=NominalAttitude(wind_speed_m_s=10.0))
    assert windy.rank == calm.rank
    assert windy.condition_number < calm.condition_number


def test_level_drones_cannot_separate_elevation_only_components() -> None:
    """Exactly level drones see each other at opposite elevations: zonal terms move freely."""
    campaign = make_preset("paper").campaign
    level = check_plan(campaign, ("sh", 6), attitude=NominalAttitude(tilt_into_motion=False))
    # at least the 5 non-constant zonal harmonics of degrees 1..5 join the constant
    assert level.null_dim >= 6 and not level.decoupled


def test_coverage_counts_every_sample(paper_check) -> None:
    campaign = make_preset("paper").campaign.with_role("learning")
    dirs, tx, rx, nodes = plan_directions(campaign)
    assert nodes == ("A", "B")
    for i, node in enumerate(nodes):
        cov = paper_check.coverage[node]
        assert cov.counts.sum() == np.sum(tx == i) + np.sum(rx == i)
        assert 0.5 < cov.covered_fraction < 1.0
        # every elevation band is visited (the loops sweep -90..90)
        assert np.all(cov.counts.sum(axis=1) > 0)


def test_coverage_map_area_weighting() -> None:
    rng = np.random.default_rng(0)
    v = rng.standard_normal((20000, 3))
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    az, el = np.arctan2(v[:, 1], v[:, 0]), np.arcsin(v[:, 2])
    full = coverage_map("X", az, el, 30.0)
    assert full.covered_fraction == pytest.approx(1.0)
    north = coverage_map("X", az[el > 0], el[el > 0], 30.0)
    assert north.covered_fraction == pytest.approx(0.5)


def test_a_triangle_identifies_absolute_gains() -> None:
    opts = dict(n_loops=3, speed_m_s=3.0, distance_m=8.0, height_m=10.0)
    trio = group_campaign(("A", "B", "C"), learning_psi0_deg=(0.0, 40.0), testing_psi0_deg=(), **opts)
    check = check_plan(trio, ("sh", 4), packet_rate_hz=20.0)
    assert check.expected_null_dim == 0 and check.null_dim == 0
    assert check.absolute_gains and check.decoupled
    pair = paper_campaign(learning_psi0_deg=(0.0, 40.0), testing_psi0_deg=(), **opts)
    two = check_plan(pair, ("sh", 4), packet_rate_hz=20.0)
    assert two.null_dim == 1 and not two.absolute_gains


def test_limits_refuse_before_any_computation() -> None:
    with pytest.raises(PlanError, match="max_speed_m_s"):
        check_plan(make_preset("paper").campaign, ("sh", 4), limits=PlanLimits(max_speed_m_s=1.0))
