"""ReaderOptions' geodetic positions: an altitude no place has is refused at the option."""

import pytest

from rplearn.errors import InputError
from rplearn.io.options import ReaderOptions, check_origin


@pytest.mark.parametrize("alt", [1e308, -3.4e38, 60_000.0, -1_500.0])
def test_an_implausible_altitude_is_refused_naming_the_option(alt):
    with pytest.raises(InputError, match=r"^station_geodetic: altitude .* m is outside -1000 to 50000 m") as err:
        ReaderOptions(station_geodetic=(49.0, 16.0, alt))
    assert err.value.param == "station_geodetic"


@pytest.mark.parametrize("alt", [-400.0, 0.0, 330.0, 8_848.0])
def test_a_plausible_altitude_is_kept(alt):
    assert check_origin((49.0, 16.0, alt), "origin_geodetic") == (49.0, 16.0, alt)
