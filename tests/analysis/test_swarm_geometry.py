"""A swarm's link directions from one rotation per pose (issue 30) equal the per-link ones."""

from __future__ import annotations

import numpy as np

from rplearn.analysis.swarm_geometry import pair_directions, pose_rotations
from rplearn.core.geometry import link_directions


def test_pair_directions_equal_link_directions_to_rounding():
    rng = np.random.default_rng(3)
    n, m = 5, 7
    position = rng.normal(0, 50, (n, m, 3))
    quat = rng.normal(size=(n, m, 4)) * rng.uniform(0.5, 2.0, (n, m, 1))  # any norm
    present = rng.uniform(size=(m, n)) < 0.8
    quat[~present.T] = np.nan  # absent poses may be NaN
    t, a, b = np.nonzero(present[:, :, None] & present[:, None, :] & ~np.eye(n, dtype=bool))
    pa, pb = position[a, t], position[b, t]
    got = pair_directions(pose_rotations(quat, present), m, t, a, b, pb - pa)
    want = link_directions(pa, quat[a, t], pb, quat[b, t])
    for g, w in zip(got, want):
        assert np.allclose(g, w, rtol=0, atol=1e-12)


def test_a_direction_straight_behind_has_azimuth_plus_pi():
    quat = np.array([[[1.0, 0.0, 0.0, 0.0]], [[1.0, 0.0, 0.0, 0.0]]])
    present = np.ones((1, 2), bool)
    zero = np.zeros(1, np.intp)
    d = pair_directions(pose_rotations(quat, present), 1, zero, zero, np.ones(1, np.intp), np.array([[-3.0, 0.0, 0.0]]))
    assert d.az_tx[0] == np.pi and d.az_rx[0] == 0.0 and d.el_tx[0] == 0.0
