"""Availability of one link (core/availability.py)."""

import numpy as np
import pytest

from rplearn.core import link_availability
from rplearn.errors import InputError


def test_availability_is_the_normal_tail_above_the_sensitivity():
    p = link_availability([-80.0, -90.0, -100.0], [5.0, 5.0, 5.0], -90.0)
    assert p[1] == pytest.approx(0.5)
    assert p[0] == pytest.approx(0.97724987, abs=1e-7)  # 2 sigma above
    assert p[2] == pytest.approx(1 - 0.97724987, abs=1e-7)


def test_zero_spread_is_a_step_and_nan_stays_nan():
    p = link_availability([-90.0, -90.1, np.nan], [0.0, 0.0, 1.0], -90.0)
    assert p[0] == 1.0 and p[1] == 0.0 and np.isnan(p[2])


def test_bad_sensitivity_and_negative_spread_are_refused():
    with pytest.raises(InputError, match="sensitivity_dbm"):
        link_availability([-80.0], [1.0], float("nan"))
    with pytest.raises(InputError, match="rssi_std_db"):
        link_availability([-80.0], [-1.0], -90.0)
