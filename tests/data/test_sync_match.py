"""The per-node coding and block interpolation behind synchronise (issue 30) equal the per-row forms."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from rplearn.data.poses import PoseTrack, interpolate_nodes
from rplearn.data.readings import _distinct
from rplearn.data.sync_match import float_block, interpolate_end, node_codes
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
    np.testing.assert_allclose(block[4:7].T, pos, rtol=0, atol=1e-12)
    np.testing.assert_allclose(block[7:11].T, quat, rtol=0, atol=1e-12)
    assert np.isnan(block[4:11, ~rows]).all()
