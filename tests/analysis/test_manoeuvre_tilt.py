"""The drones' steady lean in a wind read from their poses (issue 27, the ranking's features)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from rplearn.analysis.manoeuvre_tilt import steady_tilt_accel
from rplearn.core.geometry import attitude_from_thrust
from rplearn.errors import InputError


def test_the_steady_tilt_is_read_back_from_poses_leaning_against_a_wind():
    """Drones leaning against a wind's drag (their thrust carrying ``a``) while turning give back
    ``a`` from their attitudes alone; a ground station's level pose is left out."""
    accel = np.array([0.4, -2.1, 0.0])
    t = np.linspace(0.0, 10.0, 41)
    yaw = np.radians(30.0 * t)
    q = attitude_from_thrust(np.tile(accel + [0.0, 0.0, 9.80665], (t.size, 1)), yaw)
    drone = pd.DataFrame({"t": t, "node": "D", "x": 0.0, "y": 0.0, "qw": q[:, 0], "qx": q[:, 1], "qy": q[:, 2], "qz": q[:, 3]})
    station = pd.DataFrame({"t": t, "node": "G", "x": 1.0, "y": 2.0, "qw": 0.9, "qx": 0.3, "qy": 0.3, "qz": 0.1})
    poses = pd.concat([drone, station], ignore_index=True)
    assert steady_tilt_accel(poses, ("G",)) == pytest.approx(tuple(accel), abs=1e-9)
    assert steady_tilt_accel(poses, ("G",), last_s=2.0) == pytest.approx(tuple(accel), abs=1e-9)
    assert steady_tilt_accel(poses, ("G",)) != pytest.approx(steady_tilt_accel(poses), abs=1e-3)  # the station's would count
    # a drone speeding up along x (0.5 m/s^2, no wind) leans into its own acceleration: none is left
    v_x = 0.5 * t
    qa = attitude_from_thrust(np.tile([0.5, 0.0, 9.80665], (t.size, 1)), yaw)
    speeding = pd.DataFrame({"t": t, "node": "D", "x": 0.25 * t**2, "y": 0.0 * v_x, "qw": qa[:, 0], "qx": qa[:, 1], "qy": qa[:, 2],
                             "qz": qa[:, 3]})
    assert steady_tilt_accel(speeding) == pytest.approx((0.0, 0.0, 0.0), abs=1e-9)
    with pytest.raises(InputError) as err:
        steady_tilt_accel(poses.drop(columns=["qw"]))
    assert err.value.param == "poses"
