"""export: grid CSV equals evaluate(), 3-D images, file names (MSI files: test_msi.py)."""

from __future__ import annotations

import os

import numpy as np
import pandas as pd
import pytest
from lobe import Lobe

from rplearn.core.bases import SphericalHarmonics
from rplearn.errors import InputError
from rplearn.io.export import export_grid, grid_angles_deg
from rplearn.models.patterns import PatternSet
from rplearn.viz.images import export_pattern_images


# -- grid ------------------------------------------------------------------------------------
def test_grid_csv_shape_columns_and_values(tmp_path):
    rng = np.random.default_rng(0)
    model = PatternSet(
        basis=SphericalHarmonics(3), nodes=("A", "B", "C"), coef=rng.normal(0, 2, (3, 9))
    )
    path = tmp_path / "grid.csv"
    df = export_grid(model, 10, path)
    assert list(df.columns) == ["node", "az_deg", "el_deg", "gain_db"]
    assert len(df) == 3 * 36 * 19
    assert df["az_deg"].min() == -180 and df["az_deg"].max() == 170
    assert df["el_deg"].min() == -90 and df["el_deg"].max() == 90
    back = pd.read_csv(path)
    assert list(back.columns) == list(df.columns) and len(back) == len(df)
    for n in model.nodes:
        part = back[back["node"] == n]
        want = model.evaluate(n, np.radians(part["az_deg"]), np.radians(part["el_deg"]))
        np.testing.assert_allclose(part["gain_db"], want, rtol=1e-9, atol=1e-9)


def test_grid_subset_of_nodes_and_no_file():
    truth = Lobe({"A": (0, 0), "B": (90, 0)})
    df = export_grid(truth, 45, None, nodes=["B"])
    assert set(df["node"]) == {"B"} and len(df) == 8 * 5
    az, el = grid_angles_deg(2.5)
    assert az.size == 144 and el.size == 73 and el[-1] == 90.0


@pytest.mark.parametrize("step", [0, -1, 7, float("nan"), 200])
def test_grid_rejects_bad_steps(step):
    with pytest.raises(InputError, match="step_deg"):
        export_grid(Lobe({"A": (0, 0)}), step, None)


def test_grid_rejects_unknown_node():
    with pytest.raises(InputError, match="unknown Z"):
        export_grid(Lobe({"A": (0, 0)}), 10, None, nodes=["Z"])


# -- images ----------------------------------------------------------------------------------
def test_export_pattern_images(tmp_path):
    truth = Lobe({"A": (0, 0), "B/1": (90, 30)})
    paths = export_pattern_images(truth, tmp_path / "img", step_deg=10)
    assert [os.path.basename(p) for p in paths] == ["pattern_A.png", "pattern_B_1.png"]
    for p in paths:
        with open(p, "rb") as f:
            assert f.read(8) == b"\x89PNG\r\n\x1a\n"


def test_node_ids_become_safe_distinct_file_names():
    from rplearn.io.export import node_file_names, safe_file_name

    assert safe_file_name("../etc/x") == "_etc_x" and safe_file_name("..") == "node"
    assert node_file_names(["A", "B/1"]) == {"A": "A", "B/1": "B_1"}
    with pytest.raises(InputError, match="'A B' and 'A_B' would both be written as 'A_B'"):
        node_file_names(["A B", "A_B"])
