"""rplearn.core.plausible: the one frequency check, the bands, the plausibility table."""

from __future__ import annotations

import numpy as np
import pytest

from rplearn.core.plausible import (
    BAND_SPAN,
    FREQUENCY_BAND_HZ,
    PLAUSIBLE,
    check_covariance,
    check_frequency_hz,
    check_one_band,
    check_plausible,
    check_same_band,
    describe_band,
    frequency_bands,
    same_band,
)
from rplearn.errors import InputError


@pytest.mark.parametrize(("value", "unit", "needle"), [
    (2412.0, "Hz", "frequency_hz: 2412 is not a radio carrier in Hz (expected 1e+07 to 3e+11 Hz); 2412 looks like MHz (2.412e+09 Hz)"),
    (2.412, "MHz", "x.msi:3: FREQUENCY 2.412 is not a radio carrier in MHz (expected 10 to 300000 MHz); 2.412 looks like GHz"),
    (5.8, "MHz", "5.8 looks like GHz (5.8e+09 Hz)"),
    (0.0, "Hz", "frequency_hz: expected a positive frequency in Hz, got 0"),
    (-2412.0, "MHz", "expected a positive frequency in MHz, got -2412"),
    (float("nan"), "Hz", "got nan"),
    (1e30, "Hz", "1e+30 is not a radio carrier"),
    (2.412e9, "MHz", "looks like Hz (2.412e+09 Hz)"),
    (60.0, "Hz", "looks like MHz (6e+07 Hz) or GHz (6e+10 Hz)"),
])
def test_frequency_check_refuses_with_the_unit_hint(value, unit, needle):
    where, field = ("x.msi:3", "FREQUENCY") if unit == "MHz" else ("frequency_hz", "frequency_hz")
    with pytest.raises(InputError) as err:
        check_frequency_hz(value, where, unit=unit, field=field)
    assert needle in str(err.value)


def test_frequency_check_accepts_radio_bands_and_names_the_row():
    for f in (27e6, 433e6, 868e6, 915e6, 2.412e9, 5.8e9, 24e9, 60e9):
        check_frequency_hz(f, "f")
    check_frequency_hz(2412.0, "FREQUENCY", unit="MHz", field="FREQUENCY")
    with pytest.raises(InputError, match="data.csv: frequency_hz 2412 at row 12 is not"):
        check_frequency_hz([2.4e9, 2412.0], "data.csv", row_offset=11)
    assert FREQUENCY_BAND_HZ == (1e7, 3e11)


def test_bands_group_channels_and_split_bands():
    assert frequency_bands([2.412e9, 2.437e9, 2.472e9, 2.412e9]) == ((2.412e9, 2.472e9, 4),)
    assert frequency_bands({5.8e9: 10, 2.412e9: 5, 5.18e9: 1}) == ((2.412e9, 2.412e9, 5), (5.18e9, 5.8e9, 11))
    assert frequency_bands([433e6, 915e6]) == ((433e6, 433e6, 1), (915e6, 915e6, 1))
    assert same_band(2.412e9, 2.412e9 * (1 + BAND_SPAN)) and not same_band(2.412e9, 5.8e9)
    assert describe_band(2.412e9, 2.472e9) == "2.412-2.472 GHz" and describe_band(433e6, 433e6) == "433 MHz"


def test_one_band_per_dataset_counts_each_band():
    check_one_band(np.full(5, 2.412e9), "d")
    with pytest.raises(InputError, match=r"d.parquet: carriers of 2 bands: 2.412 GHz \(1,336 samples\), 5.8 GHz \(2 samples\)"):
        check_one_band({2.412e9: 1336, 5.8e9: 2}, "d.parquet")


def test_a_pattern_used_at_another_band_is_refused():
    check_same_band(2.437e9, 2.412e9, "frequency_hz", "the model")
    check_same_band(5.8e9, None, "frequency_hz", "the model")  # a model that does not say
    with pytest.raises(InputError, match="frequency_hz: 5.8 GHz, but the SH-3 model learned at 2.412 GHz") as err:
        check_same_band(5.8e9, 2.412e9, "frequency_hz", "the SH-3 model")
    assert err.value.param == "frequency_hz"


@pytest.mark.parametrize(("quantity", "value", "needle"), [
    ("latitude_deg", 95.0, "lat 95 is outside -90 to 90 deg"),
    ("latitude_deg", 200.0, "lat 200 is outside"),
    ("altitude_m", 2e6, "lat 2e+06 is outside -1000 to 50000 m"),
    ("link_distance_m", 111e3, "is outside 0 to 100000 m"),
    ("height_above_ground_m", -5.0, "lat -5 is outside 0.01 to 50000 m"),
    ("gain_dbi", 5e6, "is outside -100 to 60 dBi"),
    ("mount_deg", 1e300, "lat 1e+300 is outside -360 to 360 deg"),
    ("gain_dbi", float("nan"), "lat nan is not a number"),
])
def test_plausibility_table_refuses_with_the_reason(quantity, value, needle):
    with pytest.raises(InputError) as err:
        check_plausible(quantity, value, "log.csv", field="lat")
    assert needle in str(err.value) and PLAUSIBLE[quantity].why in str(err.value)


def test_plausibility_table_accepts_real_values_and_names_rows():
    check_plausible("latitude_deg", [47.4, -33.9, 90.0], "x")
    check_plausible("altitude_m", [-430.0, 488.0, 12_000.0], "x")
    with pytest.raises(InputError, match="x: latitude_deg 95 at row 4"):
        check_plausible("latitude_deg", [1.0, 95.0], "x", row_offset=3)


def test_covariance_check():
    check_covariance(np.eye(3), "m.json")
    with pytest.raises(InputError, match=r"m.json: covariance: entry \(1, 0\) is nan"):
        check_covariance([[1.0, 0.0], [np.nan, 1.0]], "m.json")
    with pytest.raises(InputError, match="the variance on the diagonal at 1 is negative"):
        check_covariance(np.diag([1.0, -1.0]), "m.json")
    with pytest.raises(InputError, match="expected a square matrix"):
        check_covariance(np.zeros((2, 3)), "m.json")


def test_sionna_options_take_the_one_frequency_check():
    from rplearn.integrations.sionna import SceneLinkOptions

    with pytest.raises(InputError, match="frequency_hz: 2412 is not a radio carrier in Hz.*looks like MHz"):
        SceneLinkOptions(frequency_hz=2412)
    assert SceneLinkOptions(frequency_hz=2.412e9).frequency_hz == 2.412e9
