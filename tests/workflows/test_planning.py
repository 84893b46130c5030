"""Planning a campaign from one options value (``CampaignOptions``), checked when made."""

from __future__ import annotations

import os

import pytest

from rplearn.errors import InputError
from rplearn.workflows.planning import PAPER_LEARNING_PSI0_DEG, CampaignOptions, plan_campaign


@pytest.mark.parametrize("bad, field", [
    ({"learning_psi0_deg": ()}, "learning_psi0_deg"),
    ({"testing_psi0_deg": [float("nan")]}, "testing_psi0_deg"),
    ({"distance_m": -1.0}, "distance_m"),
    ({"height_m": 4.0}, "height_m"),  # not above half the distance: the circle would touch the ground
    ({"n_loops": 0}, "n_loops"),
    ({"speed_m_s": 0.0}, "speed_m_s"),
])
def test_campaign_options_refuse_a_bad_value_naming_it(bad, field):
    with pytest.raises(InputError) as err:
        CampaignOptions(**bad)
    assert err.value.param == field and "\n" not in str(err.value)


def test_the_plan_has_the_units_the_options_ask_for(tmp_path):
    options = CampaignOptions(learning_psi0_deg=[0, 90], testing_psi0_deg=[45], distance_m=8.0, height_m=10.0,
                              n_loops=2, speed_m_s=3.0)
    plan = plan_campaign(str(tmp_path), options, rate_hz=2.0, check_model=None)
    assert [(u.role, u.psi0_deg, u.distance_m, u.n_loops) for u in plan.campaign.units] == [
        ("learning", 0.0, 8.0, 2), ("learning", 90.0, 8.0, 2), ("testing", 45.0, 8.0, 2)]
    assert plan.check is None and len(plan.paths) >= 3 and all(os.path.isfile(p) for p in plan.paths)
    assert CampaignOptions().learning_psi0_deg == PAPER_LEARNING_PSI0_DEG
