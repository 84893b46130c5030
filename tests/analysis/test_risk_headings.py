"""Risk-aware headings (issue 28, item 3): ranked by availability, or by gain above a required
availability."""

from __future__ import annotations

import numpy as np
import pytest
from test_availability import PATTERN_OF, posterior_model

from rplearn.analysis.heading_options import SwarmHeadingOptions, YawOptions
from rplearn.analysis.headings import best_swarm_headings, best_yaw
from rplearn.analysis.risk_headings import best_link_yaws
from rplearn.core.availability import link_availability
from rplearn.errors import InputError


def test_a_sure_heading_beats_a_stronger_uncertain_one_unless_its_availability_suffices():
    """Heading 0 is predicted 3 dB weaker than heading 1 but known to 0.5 dB, heading 1 only to
    6 dB: at a sensitivity 2 dB below heading 0, availability picks 0 (0.93 against 0.77); a
    required 0.7 lets the stronger one through, a required 0.9 does not."""
    gains = (np.array([0.0, 3.0, 0.0]), np.zeros(3))
    stds = (np.array([0.5, 6.0, 0.0]), np.zeros(3))
    free = (np.array([0, 1]), np.array([2]))
    i, _, p = best_link_yaws(gains, stds, free, (-60.0, 1.0), -62.0, None)
    assert i == 0 and p == pytest.approx(float(link_availability(-60.0, np.hypot(0.5, 1.0), -62.0)))
    assert best_link_yaws(gains, stds, free, (-60.0, 1.0), -62.0, 0.7)[0] == 1
    assert best_link_yaws(gains, stds, free, (-60.0, 1.0), -62.0, 0.9)[0] == 0
    assert best_link_yaws(gains, stds, free, (-60.0, 1.0), -62.0, 0.99)[0] == 0  # none reaches it: the most available


def test_orient_by_availability_is_at_least_as_available_as_by_gain():
    model = posterior_model(scale=3.0)
    where = ([0.0, 0.0, 20.0], [150.0, 0.0, 25.0])
    gain = best_yaw(model, "A", "B", *where, "both", YawOptions(tx_power_dbm=20.0, step_deg=5.0, caution_z=0.0))
    sensitivity = gain.rssi_dbm - 3.0
    risk = best_yaw(model, "A", "B", *where, "both", YawOptions(tx_power_dbm=20.0, step_deg=5.0,
                                                                sensitivity_dbm=sensitivity))
    at_gain = best_yaw(model, "A", "B", *where, "both", YawOptions(
        tx_yaw_deg=gain.tx_yaw_deg, rx_yaw_deg=gain.rx_yaw_deg, tx_power_dbm=20.0, step_deg=90.0,
        sensitivity_dbm=sensitivity))
    assert risk.availability >= at_gain.baseline_availability - 1e-12
    assert 0 < risk.baseline_availability <= risk.availability < 1
    assert f"availability at {sensitivity:g} dBm" in risk.summary()
    need = best_yaw(model, "A", "B", *where, "both", YawOptions(tx_power_dbm=20.0, step_deg=5.0,
                                                                sensitivity_dbm=sensitivity, min_availability=0.5))
    assert need.availability >= 0.5 and need.rssi_dbm >= risk.rssi_dbm - 1e-9  # the strongest that is available enough


def test_swarm_headings_by_availability_never_lose_availability():
    model = posterior_model(scale=3.0)
    positions = {"A": [0.0, 0.0, 20.0], "B": [150.0, 0.0, 25.0], "C": [70.0, 130.0, 22.0], "D": [200.0, 200.0, 20.0]}
    plain = best_swarm_headings(model, positions, 20.0, SwarmHeadingOptions(pattern_of=PATTERN_OF, restarts=2))
    options = SwarmHeadingOptions(pattern_of=PATTERN_OF, restarts=2, sensitivity_dbm=plain.bottleneck_dbm - 2.0)
    risk = best_swarm_headings(model, positions, 20.0, options)
    assert risk.start_availability <= risk.availability <= 1.0 and plain.availability is None
    assert "availability of the weakest link" in risk.summary() and risk.to_dict()["availability"] == risk.availability


def test_risk_options_are_checked():
    with pytest.raises(InputError, match="min_availability"):
        YawOptions(tx_power_dbm=20.0, sensitivity_dbm=-90.0, min_availability=1.5)
    with pytest.raises(InputError, match="sensitivity"):
        YawOptions(tx_power_dbm=20.0, min_availability=0.9)
    with pytest.raises(InputError, match="tx_power_dbm"):
        YawOptions(sensitivity_dbm=-90.0)
    with pytest.raises(InputError, match="sensitivity_dbm"):
        SwarmHeadingOptions(sensitivity_dbm=float("nan"))
