"""rplearn.core.environment: the log-distance column and the two-ray term (issue 12, item 1)."""

from __future__ import annotations

import numpy as np
import pytest

from rplearn.core.environment import DEFAULT_RELATIVE_PERMITTIVITY, TWO_RAY_FLOOR_DB, PathLoss, log_distance_column, reflection_coefficient, two_ray_excess_db
from rplearn.core.link import wavelength_m
from rplearn.errors import InputError


def test_log_distance_column_is_minus_ten_log_distance():
    np.testing.assert_allclose(log_distance_column([1.0, 10.0, 100.0]), [0.0, -10.0, -20.0])
    with pytest.raises(InputError, match="positive distances"):
        log_distance_column([1.0, 0.0])


def test_reflection_coefficient_limits():
    # grazing incidence: both polarizations reflect with -1
    for pol in ("vertical", "horizontal"):
        assert abs(reflection_coefficient(1e-9, 15.0, pol) + 1.0) < 1e-6
    # normal incidence: (1 - sqrt(eps)) / (1 + sqrt(eps)) for horizontal, the opposite sign for vertical
    r = (1 - np.sqrt(15.0)) / (1 + np.sqrt(15.0))
    assert reflection_coefficient(1.0, 15.0, "horizontal") == pytest.approx(r)
    assert reflection_coefficient(1.0, 15.0, "vertical") == pytest.approx(-r)
    # Brewster angle: the vertical coefficient vanishes at tan(psi) = 1 / sqrt(eps)
    psi = np.arctan(1 / np.sqrt(15.0))
    assert abs(reflection_coefficient(np.sin(psi), 15.0, "vertical")) < 1e-9
    with pytest.raises(InputError, match="polarization"):
        reflection_coefficient(0.5, 15.0, "circular")


def test_two_ray_matches_the_textbook_far_form():
    """Far away over a near-perfect conductor with horizontal polarization (Gamma = -1) the field
    is 2 |sin(k h_t h_r / d)| times the direct ray's."""
    f = 2.4e9
    k = 2 * np.pi / wavelength_m(f)
    ht, hr = 5.0, 8.0
    d = np.linspace(300.0, 2000.0, 50)
    got = two_ray_excess_db(d, ht, hr, f, relative_permittivity=1e9, polarization="horizontal")
    want = np.abs(2 * np.sin(k * ht * hr / d))  # field amplitude relative to the direct ray
    np.testing.assert_allclose(10 ** (got / 20), want, atol=0.01)


def test_two_ray_vanishes_without_a_reflection_and_is_floored():
    d = np.array([50.0, 80.0])
    assert np.allclose(two_ray_excess_db(d, 5.0, 8.0, 2.4e9, gain_ratio=0.0), 0.0)
    assert np.all(two_ray_excess_db(np.linspace(100, 3000, 2000), 5.0, 8.0, 2.4e9, 1e9, "horizontal") >= TWO_RAY_FLOOR_DB)


def test_two_ray_refuses_an_antenna_below_the_ground():
    with pytest.raises(InputError, match="at or below the ground level"):
        two_ray_excess_db([10.0], [-1.0], [5.0], 2.4e9)
    pl = PathLoss("two-ray", ground_level_m=3.0)
    with pytest.raises(InputError, match="ground level"):
        pl.known_db([10.0], [2.0], [5.0], [2.4e9])
    # predictions: NaN where an antenna is on or below the ground, a value elsewhere
    got = pl.known_db([10.0, 10.0], [2.0, 6.0], [5.0, 5.0], [2.4e9, 2.4e9], strict=False)
    assert np.isnan(got[0]) and np.isfinite(got[1])


def test_path_loss_spec_round_trips_and_checks_its_fields():
    for pl in (PathLoss(), PathLoss("log-distance"), PathLoss("two-ray", 2.5, 30.0, "horizontal")):
        assert PathLoss.from_dict(pl.to_dict()) == pl
    assert PathLoss.from_dict(None) == PathLoss()
    assert PathLoss().relative_permittivity == DEFAULT_RELATIVE_PERMITTIVITY
    with pytest.raises(InputError, match="free, log-distance, two-ray"):
        PathLoss("okumura-hata")
    with pytest.raises(InputError, match="permittivity"):
        PathLoss("two-ray", relative_permittivity=0.5)
    with pytest.raises(InputError, match="ground level"):
        PathLoss("two-ray", ground_level_m=float("nan"))
    assert PathLoss("free").known_db([1.0], None, None, None) is None
    with pytest.raises(InputError, match="no antenna heights"):
        PathLoss("two-ray").known_db([10.0], None, None, [2.4e9])
