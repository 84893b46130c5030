"""Reference patterns as models (issue 11, item 2a and acceptance 4): an MSI export read back
predicts its cuts; a CSV in the antenna's spherical frame with a hanging mount predicts what a
hand computation says; the command line builds a model the other commands use."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from rplearn.errors import InputError
from rplearn.io.msi import export_msi_files, msi_horizontal_directions_rad, msi_vertical_directions_rad
from rplearn.io.reference import mount_rotation, read_reference_pattern
from rplearn.models import load_model
from rplearn.models.reference import reference_model

FIXTURES = Path(__file__).resolve().parents[1] / "fixtures" / "models_v1"


def test_an_msi_export_read_back_predicts_its_cuts_within_0_1_db(tmp_path):
    learned = load_model(FIXTURES / "sh5.json")
    files = export_msi_files(learned, str(tmp_path))
    ref = reference_model({n: read_reference_pattern(f) for n, f in zip(learned.nodes, files)})
    angles = np.arange(360.0)
    worst = 0.0
    for node in learned.nodes:
        for cut in (msi_horizontal_directions_rad, msi_vertical_directions_rad):
            az, el = cut(angles)
            worst = max(worst, float(np.max(np.abs(ref.evaluate(node, az, el) - learned.evaluate(node, az, el)))))
    assert worst < 0.1, worst


def antenna_frame_csv(path):
    """g(theta, phi) = 2 + 3 cos(theta) + 1.5 sin(theta) cos(phi) on a 5-degree grid."""
    theta, phi = np.meshgrid(np.arange(0.0, 181.0, 5.0), np.arange(0.0, 360.0, 5.0), indexing="ij")
    t, p = np.radians(theta.ravel()), np.radians(phi.ravel())
    pd.DataFrame({"theta_deg": theta.ravel(), "phi_deg": phi.ravel(),
                  "gain_dbi": 2 + 3 * np.cos(t) + 1.5 * np.sin(t) * np.cos(p)}).to_csv(path, index=False)


def test_a_hanging_antenna_in_its_own_frame_predicts_the_hand_computation(tmp_path):
    antenna_frame_csv(tmp_path / "ant.csv")
    ref = reference_model({"A": read_reference_pattern(tmp_path / "ant.csv", mount_rpy_deg=(180.0, 0.0, 0.0))})
    # Hanging upside down (roll 180): the antenna's +z is the body's -z, its +x the body's +x,
    # so in the body frame g = 2 - 3 sin(el) + 1.5 cos(el) cos(az).
    by_hand = {"down": (0.0, -90.0, 5.0), "up": (0.0, 90.0, -1.0), "forward": (0.0, 0.0, 3.5),
               "backward": (180.0, 0.0, 0.5), "left": (90.0, 0.0, 2.0)}
    for name, (az, el, expected) in by_hand.items():
        got = float(ref.evaluate("A", np.radians([az]), np.radians([el]))[0])
        assert got == pytest.approx(expected, abs=0.05), name


def test_the_mount_rotates_directions_as_an_attitude():
    az, el = mount_rotation(np.array([0.0]), np.array([np.pi / 2]), (0.0, 90.0, 0.0))  # antenna +z, pitched 90
    assert (float(np.degrees(az[0])) % 360, float(np.degrees(el[0]))) == pytest.approx((0.0, 0.0), abs=1e-9)
    with pytest.raises(InputError, match="mount"):
        mount_rotation(np.array([0.0]), np.array([0.0]), (0.0, 90.0))


def test_bad_pattern_files_are_refused_in_one_line(tmp_path):
    (tmp_path / "noangle.csv").write_text("x,gain_dbi\n1,2\n")
    (tmp_path / "theta.csv").write_text("theta_deg,phi_deg,gain_dbi\n200,0,1\n")
    (tmp_path / "nan.csv").write_text("az_deg,el_deg,gain_dbi\n0,0,\n")
    for name, needle in (("noangle.csv", "missing direction columns"), ("theta.csv", "theta outside"),
                         ("nan.csv", "gain_dbi holds a missing")):
        with pytest.raises(InputError, match=needle):
            read_reference_pattern(tmp_path / name)


def test_reference_cli_makes_a_model_the_other_commands_use(tmp_path, monkeypatch):
    from typer.testing import CliRunner

    from rplearn.cli import app

    def rplearn(*args: str):  # in this process: the outputs are checked, not the process boundary
        return CliRunner().invoke(app, list(args), env={"COLUMNS": "400"})

    antenna_frame_csv(tmp_path / "ant.csv")
    monkeypatch.chdir(tmp_path)
    proc = rplearn("reference", "A=ant.csv", "B=ant.csv", "--mount", "A=180,0,0", "-o", "ref.json")
    assert proc.exit_code == 0 and "A: ant.csv, mount (roll, pitch, yaw) (180.0, 0.0, 0.0) deg" in proc.stdout, proc.output
    proc = rplearn("orient", "ref.json", "--tx", "A", "--rx", "B", "--tx-pos", "0,0,20", "--rx-pos", "30,0,20", "--frequency", "2.4e9")
    assert proc.exit_code == 0 and "best yaw" in proc.stdout, proc.output
    model = load_model(tmp_path / "ref.json")
    assert model.training["reference"]["A"]["mount_rpy_deg"] == [180.0, 0.0, 0.0]
