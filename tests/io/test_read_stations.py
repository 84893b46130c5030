"""rplearn.io.read: a ground station several files place (ULogs read with their radio, MAVLink
logs): at one pose it is one static station for every flight; at different poses (a station
moved between flights, two vehicles' homes) it is refused naming both files, both positions and
``--station`` as the way out."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from ulogfiles import FIXTURES, radio_log, ulog_times_us, with_radio

from rplearn.errors import InputError
from rplearn.io import read_logs
from rplearn.io.damage import one_station
from rplearn.io.options import ReaderOptions

SMALL_LOG = FIXTURES / "sample_log_small.ulg"  # another flight, another place, no home_position


@pytest.fixture(scope="module")
def two_flights(tmp_path_factory) -> tuple[Path, Path]:
    d = tmp_path_factory.mktemp("flights")
    a, _ = radio_log(d / "a.ulg")
    first, last = ulog_times_us(SMALL_LOG)
    t = np.arange(first + 500_000, last - 500_000, 500_000, dtype=np.int64)
    b = with_radio(d / "b.ulg", t, np.full(t.size, 160), np.full(t.size, 160), src=SMALL_LOG)
    return a, b


def _options(*paths: Path, **kw) -> ReaderOptions:
    return ReaderOptions(ulog_radio=True, tx_power_dbm=20.0, frequency_hz=915e6,
                         nodes={str(p): f"d{k}" for k, p in enumerate(paths)}, **kw)


def test_two_flights_with_different_homes_are_refused_naming_both_files_homes_and_station(two_flights):
    """Was read with the station moving between the two places over the years between the
    flights, every sample dropped, and the advice of a max_gap_s that bridges years."""
    a, b = two_flights
    with pytest.raises(InputError) as e:
        read_logs([str(a), str(b)], _options(a, b))
    msg = str(e.value)
    assert msg.startswith(f"{b} and {a} place the ground station gcs at (")  # in time order: b flew first
    assert "home_position" in msg and "first position" in msg and "ReaderOptions.station_geodetic" in msg
    assert "\n" not in msg and e.value.param == "station_geodetic"


def _flight(node: str, t0: float, station_xyz: tuple[float, float, float]) -> pd.DataFrame:
    t = t0 + np.arange(5.0)
    vehicle = pd.DataFrame({"t": t, "node": node, "x": 10.0 * np.arange(5), "y": 0.0, "z": 20.0, "qw": 1.0,
                            "qx": 0.0, "qy": 0.0, "qz": 0.0})
    station = pd.DataFrame({"t": [t0], "node": ["gcs"], "x": [station_xyz[0]], "y": [station_xyz[1]],
                            "z": [station_xyz[2]], "qw": [1.0], "qx": [0.0], "qy": [0.0], "qz": [0.0]})
    return pd.concat([vehicle, station], ignore_index=True)


def test_two_flights_an_hour_apart_from_one_home_share_one_static_station():
    """Two station rows an hour apart made the station a node logged over that hour only: the
    later flight's samples fell out of its span."""
    files = [{"source": "a.ulg", "station": "gcs"}, {"source": "b.ulg", "station": "gcs"}]
    logs = one_station([_flight("d0", 0.0, (1.0, 2.0, 0.5)), _flight("d1", 3600.0, (1.0, 2.0, 0.5))], [0, 1], files)
    station = pd.concat(logs)[lambda df: df["node"] == "gcs"]
    assert station["t"].tolist() == [0.0] and len(logs[1]) == 5
    assert files[1]["notes"] == ["b.ulg: ground station gcs at the pose a.ulg gives it: one static station for both flights"]
    with pytest.raises(InputError, match=r"^a.ulg and b.ulg place the ground station gcs at \(1.00, 2.30, 0.50\) m and at "
                                         r"\(1.00, 2.00, 0.50\) m"):
        one_station([_flight("d1", 3600.0, (1.0, 2.0, 0.5)), _flight("d0", 0.0, (1.0, 2.3, 0.5))], [0, 1],
                    [{"source": "b.ulg", "station": "gcs"}, {"source": "a.ulg", "station": "gcs"}])


def test_inspect_says_the_two_homes_sync_refuses(two_flights):
    from rplearn.io.inspect import inspect_logs

    a, b = two_flights
    report = inspect_logs([str(a), str(b)], _options(a, b))
    [line] = [p for p in report.problems if "place the ground station gcs" in p]
    assert line.startswith(f"{b} and {a} place the ground station gcs at (") and line.endswith("(sync refuses these files)")
