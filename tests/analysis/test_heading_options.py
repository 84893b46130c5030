"""The options of the swarm and heading searches: checked when made, each error naming its field."""

from __future__ import annotations

import pytest

from rplearn.analysis import SwarmHeadingOptions, SwarmOptions, YawOptions
from rplearn.errors import InputError

BAD = [
    (SwarmOptions, {"frequency_hz": 0.0}, "frequency_hz"),
    (SwarmOptions, {"pattern_of": ["C", "A"]}, "pattern_of"),
    (SwarmOptions, {"min_rssi_dbm": float("nan")}, "min_rssi_dbm"),
    (SwarmOptions, {"step_s": 0.0}, "step_s"),
    (SwarmOptions, {"max_gap_s": -1.0}, "max_gap_s"),
    (YawOptions, {"tx_yaw_deg": float("inf")}, "tx_yaw_deg"),
    (YawOptions, {"step_deg": -1.0}, "step_deg"),
    (YawOptions, {"tx_power_dbm": float("nan")}, "tx_power_dbm"),
    (YawOptions, {"caution_z": -1.0}, "caution_z"),
    (SwarmHeadingOptions, {"start_yaw_deg": [10.0]}, "start_yaw_deg"),
    (SwarmHeadingOptions, {"fixed": "B"}, "fixed"),
    (SwarmHeadingOptions, {"max_sweeps": 0}, "max_sweeps"),
    (SwarmHeadingOptions, {"restarts": 1.5}, "restarts"),
]


@pytest.mark.parametrize("cls, bad, field", BAD, ids=[f"{c.__name__}-{f}" for c, _, f in BAD])
def test_a_bad_option_is_refused_in_one_line_naming_it(cls, bad, field):
    with pytest.raises(InputError) as err:
        cls(**bad)
    assert err.value.param == field and str(err.value).startswith(field) and "\n" not in str(err.value)


def test_options_are_frozen_values_with_the_documented_defaults():
    opts = SwarmOptions(pattern_of={"C": "A"})
    assert opts.pattern_of == {"C": "A"} and opts.min_rssi_dbm == -85.0 and opts.step_s == 1.0
    with pytest.raises(AttributeError):
        opts.step_s = 2.0  # type: ignore[misc]
    assert SwarmOptions(step_s=0.0, times_s=[1.0]).times_s == [1.0]  # explicit times need no step
    assert SwarmHeadingOptions(fixed=["B"]).fixed == ("B",)
    assert YawOptions().caution_z == 1.28 and YawOptions().step_deg == 1.0
