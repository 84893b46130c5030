"""Link budget (paper eqs. 1 and 5)."""

import numpy as np
import pytest

from rplearn.core import link
from rplearn.errors import FarFieldError, InputError


def test_wavelength_at_2_4_ghz():
    assert link.wavelength_m(2.4e9) == pytest.approx(0.124913524, rel=1e-8)


def test_fspl_by_hand():
    # textbook form: 20 log10(d / km) + 20 log10(f / MHz) + 32.4478 = -40 + 67.6042 + 32.4478
    assert link.free_space_path_loss_db(10.0, 2.4e9) == pytest.approx(60.0520, abs=1e-3)


def test_observed_gain_inverts_received_power():
    g = np.array([-3.0, 0.0, 7.5])
    d = np.array([5.0, 10.0, 20.0])
    p = link.received_power_dbm(20.0, g, d, 2.437e9)
    np.testing.assert_allclose(link.observed_joint_gain_db(p, 20.0, d, 2.437e9), g, atol=1e-12)


def test_near_field_samples_are_refused():
    lam = link.wavelength_m(2.4e9)
    with pytest.raises(FarFieldError, match="1 of 2 sample"):
        link.free_space_path_loss_db([10.0, 1.5 * lam], 2.4e9)
    with pytest.raises(FarFieldError):
        link.observed_joint_gain_db(-50, 20, 2 * lam, 2.4e9)  # d must exceed 2 lambda strictly


def test_the_far_field_limit_is_two_wavelengths_and_refuses_what_wavelength_refuses():
    from rplearn.core import far_field_limit_m

    np.testing.assert_allclose(far_field_limit_m([2.4e9, 5.8e9]), 2.0 * 299_792_458.0 / np.array([2.4e9, 5.8e9]), rtol=0)
    with pytest.raises(InputError, match="frequency_hz"):
        far_field_limit_m(0.0)
