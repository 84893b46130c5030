"""The per-node coding and block interpolation behind synchronise (issue 30) equal the per-row forms."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from rplearn.core.geometry import slerp_wxyz
from rplearn.data.poses import PoseTrack, TrackSet, interpolate_nodes
from rplearn.data.readings import _distinct
from rplearn.data.sync_match import float_block, interpolate_end, node_codes, pose_before, slerp_into
from rplearn.data.tables import empty_ids, node_ids

ODD_IDS = [
    (pd.Series(["A", "B", None, "A", ""], dtype="str"), pd.Series(["B", "A", "A", np.nan, "C"], dtype="str")),
    (pd.Series([1, "1", None, 2.0, np.nan], dtype=object), pd.Series(["x", 1, "", None, 2], dtype=object)),
    (pd.Series([1, 2, 3]), pd.Series([1.0, np.nan, 3.5])),
    (pd.Series(pd.Categorical(["a", None, "b"])), pd.Series(["b", "a", None], dtype="string")),
    (pd.Series([], dtype="str"), pd.Series([], dtype=object)),
]


@pytest.mark.parametrize(("tx", "rx"), ODD_IDS)
def test_node_codes_equal_node_ids_row_by_row(tx: pd.Series, rx: pd.Series) -> None:
    tx_code, rx_code, uniques = node_codes(tx, rx)
    assert list(uniques[tx_code]) == list(node_ids(tx))
    assert list(uniques[rx_code]) == list(node_ids(rx))
    assert len(set(uniques)) == len(uniques)  # "1" from 1 and from "1" is one node


def test_empty_ids_per_distinct_id() -> None:
    ids = np.array(["a", " ", "", "b ", None, 1, "\t"], dtype=object)
    assert empty_ids(ids).tolist() == [False, True, True, False, False, False, True]


@pytest.mark.parametrize(("tx", "rx"), ODD_IDS[:4])
def test_distinct_cells_hash_as_the_object_column(tx: pd.Series, rx: pd.Series) -> None:
    for col in (tx, rx):
        codes, values = _distinct(col, "\x00missing")
        want = pd.util.hash_array(col.to_numpy(dtype=object, na_value="\x00missing"))
        np.testing.assert_array_equal(pd.util.hash_array(values)[codes], want)


def test_interpolate_end_equals_interpolate_nodes() -> None:
    rng = np.random.default_rng(3)
    tk = np.cumsum(rng.uniform(0.005, 0.02, 400))
    tk[200:] += 1.0  # a pose gap
    q = rng.normal(size=(400, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    tracks = {
        "A": PoseTrack("A", tk, rng.normal(size=(400, 3)), q),
        "G": PoseTrack("G", np.array([0.0]), np.array([[1.0, 2.0, 3.0]]), np.array([[-1.0, 0.0, 0.0, 0.0]])),
    }
    n = 5000
    t = rng.uniform(tk[0] - 1, tk[-1] + 1, n)
    code = rng.integers(0, 3, n)  # 2: a node without a track
    rows = (code < 2) & (rng.uniform(size=n) < 0.9)
    names = ["A", "G", "X"]
    pos, quat, status = interpolate_nodes(tracks, names, code, t, 0.2, rows)
    block = float_block(n)
    got_status = interpolate_end(tracks, names, code, t, 0.2, rows, block[4:11])
    np.testing.assert_array_equal(got_status, status)
    ok = rows & (status == 0)  # the poses of rows with another status are meaningless
    np.testing.assert_array_equal(block[4:7].T[ok], pos[ok])  # bit for bit
    np.testing.assert_array_equal(block[7:11].T[ok], quat[ok])
    assert np.isnan(block[4:11, ~rows]).all()


@pytest.mark.parametrize("m", [1, 3, 4, 1000, 40_000])
def test_slerp_into_equals_slerp_wxyz_bit_for_bit(m: int) -> None:
    rng = np.random.default_rng(m)
    q0 = rng.normal(size=(m, 4))
    q0 /= np.linalg.norm(q0, axis=1, keepdims=True)
    q1 = q0 + rng.choice([1e-9, 1e-3, 0.3, 3.0], size=(m, 1)) * rng.normal(size=(m, 4))
    q1[::5] = q0[::5]  # equal: the normalised linear interpolation
    q1[1::7] = -q1[1::7]  # the other sign: the shorter arc
    q1 /= np.linalg.norm(q1, axis=1, keepdims=True)
    fraction = rng.uniform(size=m)
    fraction[::3] = rng.choice([0.0, 1.0], size=fraction[::3].size)
    out = np.empty((4, m))
    slerp_into(q0, q1, fraction, out)
    want = slerp_wxyz(q0, q1, fraction)
    assert out.T.tobytes() == np.ascontiguousarray(want).tobytes()


@pytest.mark.parametrize("start_s", [0.0, 1.7e9])
def test_pose_before_is_the_clipped_searchsorted(start_s: float) -> None:
    rng = np.random.default_rng(5)
    tk = np.cumsum(rng.uniform(1e-3, 0.05, 3000)) + start_s  # just below a pose time, interp rounds up
    store = TrackSet.of({"Z": PoseTrack("Z", np.array([0.0]), np.zeros((1, 3)), np.array([[1.0, 0, 0, 0]])),
                         "A": PoseTrack("A", tk, rng.normal(size=(tk.size, 3)), np.tile([1.0, 0, 0, 0], (tk.size, 1)))})
    t = np.r_[rng.uniform(tk[0] - 1, tk[-1] + 1, 20000), tk, np.nextafter(tk, -np.inf), np.nextafter(tk, np.inf),
              -np.inf, np.inf]
    for times in (t, np.sort(t)):
        want = np.clip(np.searchsorted(tk, times, side="right") - 1, 0, tk.size - 2) + store.first_row["A"]
        np.testing.assert_array_equal(pose_before(store, "A", times), want)
