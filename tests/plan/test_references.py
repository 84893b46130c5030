"""A plan read back from its reference files flies what was written (``simulate --plan``)."""

from __future__ import annotations

import numpy as np
import pytest

from rplearn.errors import InputError
from rplearn.plan.campaign import Campaign, write_references
from rplearn.plan.manoeuvres import ManoeuvreUnit
from rplearn.plan.references import read_plan
from rplearn.plan.trajectory import TrajectoryUnit


def test_a_written_plan_reads_back_unit_by_unit_in_label_order(tmp_path):
    units = (ManoeuvreUnit(nodes=("B", "A"), kind="spiral", anchor_enu_m=(5.0, 0.0, 20.0), start_enu_m=(-5.0, 0.0, 20.0),
                           elevation_deg=30.0, label="01_spiral"),
             TrajectoryUnit(nodes=("A", "B"), n_loops=1, label="02_unit"))
    write_references(Campaign(units), str(tmp_path), rate_hz=20.0)  # type: ignore[arg-type]
    plan = read_plan(str(tmp_path))
    assert [u.label for u in plan.units] == ["01_spiral", "02_unit"]
    for written, read in zip(units, plan.units):
        assert read.duration_s == pytest.approx(written.duration_s, abs=0.05)
        t = np.arange(0.0, read.duration_s, 0.05)
        a, b = written.evaluate(t), read.evaluate(t)
        for j, node in enumerate(written.nodes):
            k = list(read.nodes).index(node)
            assert np.allclose(a.position_enu_m[:, j], b.position_enu_m[:, k], atol=2e-4)
            assert np.allclose(np.angle(np.exp(1j * (a.yaw_rad[:, j] - b.yaw_rad[:, k]))), 0.0, atol=1e-4)
        speed = np.linalg.norm(b.velocity_enu_m_s, axis=2).max()
        assert speed == pytest.approx(np.linalg.norm(a.velocity_enu_m_s, axis=2).max(), rel=0.05)


def test_a_folder_that_is_not_a_plan_is_refused_naming_the_file(tmp_path):
    with pytest.raises(InputError, match="no reference file"):
        read_plan(str(tmp_path))
    (tmp_path / "u1_A.csv").write_text("t,x,y,z,yaw_deg\n0,0,0,10,0\n1,1,0,10,0\n")
    with pytest.raises(InputError, match="unit u1 has 1 drone file"):
        read_plan(str(tmp_path))
    (tmp_path / "u1_B.csv").write_text("t,x,y\n0,0,0\n1,1,0\n")
    with pytest.raises(InputError, match="u1_B.csv: missing column"):
        read_plan(str(tmp_path))
    (tmp_path / "u1_B.csv").write_text("t,x,y,z,yaw_deg\n0,0,0,10,0\n0,1,0,10,0\n")
    with pytest.raises(InputError, match="u1_B.csv: t must start at 0 and increase"):
        read_plan(str(tmp_path))
