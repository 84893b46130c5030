"""MSI Planet files: angle conventions, round trip, vendor variants, malformed files."""

from __future__ import annotations

import numpy as np
import pytest
from lobe import Lobe

from rplearn.core.bases import SphericalHarmonics
from rplearn.errors import InputError
from rplearn.io.msi import export_msi, msi_horizontal_directions_rad, msi_vertical_directions_rad, read_msi, write_msi
from rplearn.models.patterns import PatternSet


# -- MSI angle conventions -------------------------------------------------------------------
def test_msi_direction_mapping():
    az, el = msi_horizontal_directions_rad([0, 90, 180, 270])
    np.testing.assert_allclose(
        np.degrees(az), [0, -90, 180, 90], atol=1e-9
    )  # clockwise: 90 = right
    np.testing.assert_allclose(el, 0)
    az, el = msi_vertical_directions_rad([0, 30, 90, 150, 180, 270, 340])
    np.testing.assert_allclose(
        np.degrees(el), [0, -30, -90, -30, 0, 90, 20], atol=1e-9
    )  # 90 = nadir
    np.testing.assert_allclose(np.degrees(az)[[0, 1, 4, 6]], [0, 0, 180, 0], atol=1e-9)
    assert np.degrees(az[3]) == pytest.approx(180)  # 150 deg is past nadir: backward, 30 deg down


@pytest.mark.parametrize(
    "lobe_deg, h_min, v_min",
    [
        ((0.0, 20.0), 0, 340),  # forward, 20 deg up -> vertical 340 (20 deg above the horizon)
        ((30.0, 0.0), 330, 0),  # 30 deg left -> horizontal 330 (clockwise)
        ((-90.0, 0.0), 90, None),  # right
        ((180.0, 0.0), 180, 180),  # backward
        ((0.0, -60.0), 0, 60),  # 60 deg down, forward
        ((180.0, 45.0), 180, 225),  # backward and up: between back horizon (180) and zenith (270)
    ],
)
def test_msi_minimum_loss_where_the_convention_says(tmp_path, lobe_deg, h_min, v_min):
    truth = Lobe({"A": lobe_deg}, peak_dbi=6.0)
    msi = export_msi(truth, "A", tmp_path / "a.msi", frequency_hz=2.412e9)
    assert int(np.argmin(msi.horizontal_loss_db)) == h_min
    if v_min is not None:
        assert int(np.argmin(msi.vertical_loss_db)) == v_min
    if lobe_deg[0] in (0.0, 180.0):  # the lobe lies in the vertical cut
        assert msi.vertical_loss_db.min() < 0.01
    if lobe_deg[1] == 0.0:  # the lobe lies in the horizontal cut
        assert msi.horizontal_loss_db.min() < 0.01
    assert msi.gain_dbi == pytest.approx(6.0, abs=0.01)
    assert (msi.horizontal_loss_db >= -0.005).all() and (msi.vertical_loss_db >= -0.005).all()


def test_msi_round_trip(tmp_path):
    truth = Lobe({"A": (30.0, 20.0), "B": (-100.0, -40.0)}, peak_dbi=4.321)
    path = tmp_path / "b.msi"
    written = export_msi(truth, "B", path, frequency_hz=5.8e9, name="drone B", comment="test\nrun")
    text = path.read_text()
    lines = text.splitlines()
    assert lines[0] == "NAME drone B"
    assert "FREQUENCY 5800" in lines and "GAIN 4.32 dBi" in lines
    h = lines.index("HORIZONTAL 360")
    assert lines[h + 1].split()[0] == "0" and lines[h + 360].split()[0] == "359"
    assert lines[h + 361] == "VERTICAL 360"
    assert all(float(ln.split()[1]) >= 0 for ln in lines[h + 1 : h + 361])
    back = read_msi(path)
    assert back.name == "drone B"
    assert back.frequency_mhz == pytest.approx(5800.0)
    assert back.gain_dbi == pytest.approx(4.32)
    np.testing.assert_allclose(
        back.horizontal_loss_db, written.horizontal_loss_db, atol=0.005 + 1e-9
    )
    np.testing.assert_allclose(back.vertical_loss_db, written.vertical_loss_db, atol=0.005 + 1e-9)
    assert "\n" not in back.header["COMMENT"] and back.header["COMMENT"].endswith("test run")
    # writing what was read gives the same file
    write_msi(back, tmp_path / "c.msi")
    assert (
        read_msi(tmp_path / "c.msi").horizontal_loss_db.tolist() == back.horizontal_loss_db.tolist()
    )
    # and the cuts read back reproduce the pattern along them
    az, el = msi_vertical_directions_rad(np.arange(360))
    np.testing.assert_allclose(
        back.gain_dbi - back.vertical_loss_db, truth.evaluate("B", az, el), atol=0.011
    )


def test_msi_of_learned_and_true_patterns(tmp_path):
    rng = np.random.default_rng(3)
    model = PatternSet(
        basis=SphericalHarmonics(3),
        nodes=("A", "B"),
        coef=rng.normal(0, 2, (2, 9)),
        gauge=[{"rule": "equal-mean"}],
    )
    with pytest.raises(InputError, match="frequency"):
        export_msi(model, "A", tmp_path / "x.msi")
    msi = export_msi(model, "A", tmp_path / "x.msi", frequency_hz=2.4e9)
    assert "two-node fit" in msi.header["COMMENT"]
    model.training = model.training.replace(frequency_hz=2.437e9)
    assert export_msi(model, "A", tmp_path / "y.msi").frequency_mhz == pytest.approx(2437.0)
    with pytest.raises(InputError, match="unknown Q"):
        export_msi(model, "Q", tmp_path / "z.msi", frequency_hz=2.4e9)


def _msi_text(h_lines=None, v_lines=None, head="NAME x\nFREQUENCY 2400\nGAIN 10 dBi\n"):
    h = h_lines if h_lines is not None else [f"{a} {a / 100:.2f}" for a in range(360)]
    v = v_lines if v_lines is not None else [f"{a} 1.00" for a in range(360)]
    return head + "HORIZONTAL 360\n" + "\n".join(h) + "\nVERTICAL 360\n" + "\n".join(v) + "\n"


def test_msi_reader_accepts_vendor_variants(tmp_path):
    path = tmp_path / "vendor.msi"
    text = _msi_text(
        head="Vendor Antenna 9dBd\r\nMAKE ACME\r\nfrequency 2.437 GHz\r\nGAIN 10\r\nTILT ELECTRICAL\r\n"
    )
    path.write_text(text.replace("\n", "\r\n").replace("\r\r\n", "\r\n"))
    msi = read_msi(path)
    assert msi.name == "Vendor Antenna 9dBd"
    assert msi.frequency_mhz == pytest.approx(2437.0)
    assert msi.gain_dbi == pytest.approx(12.15)  # dBd without unit -> +2.15 dBi
    assert msi.header["MAKE"] == "ACME" and msi.header["TILT"] == "ELECTRICAL"
    assert msi.horizontal_loss_db[359] == pytest.approx(3.59)
    path.write_text(
        _msi_text(
            h_lines=[f"{a:.1f}\t{a / 100:.2f}" for a in range(360)], head="NAME\tx y\nGAIN\t3 dBi\n"
        )
    )
    assert read_msi(path).name == "x y" and read_msi(path).gain_dbi == 3.0
    assert read_msi(path).horizontal_loss_db[10] == pytest.approx(0.10)


_GOOD_H = [f"{a} {a / 100:.2f}" for a in range(360)]


@pytest.mark.parametrize(
    "text, line, what",
    [
        (_msi_text().split("VERTICAL")[0], None, "no VERTICAL"),
        (_msi_text().replace("GAIN 10 dBi\n", ""), 1, "no GAIN"),
        (_msi_text().replace("GAIN 10 dBi", "GAIN ten"), 3, "GAIN"),
        (_msi_text().replace("FREQUENCY 2400", "FREQUENCY 2400 furlongs"), 2, "FREQUENCY"),
        (_msi_text().replace("HORIZONTAL 360", "HORIZONTAL 359"), 4, "expected 360 points"),
        (_msi_text(h_lines=_GOOD_H[:5] + ["5 abc"] + _GOOD_H[6:]), 10, "expected '<angle> <loss>'"),
        (_msi_text(h_lines=_GOOD_H[:5] + ["6 0.10"] + _GOOD_H[6:]), 10, "expected angle 5"),
        (_msi_text(h_lines=_GOOD_H[:5] + ["nan 0.10"] + _GOOD_H[6:]), 10, "expected angle 5"),
        (_msi_text(h_lines=_GOOD_H[:5] + ["5 nan"] + _GOOD_H[6:]), 10, "loss must be"),
        (_msi_text().replace("GAIN 10 dBi", "GAIN 10 dBi\ngain 11"), 4, "repeated header key GAIN"),
        (_msi_text(h_lines=_GOOD_H[:5] + ["5 -3.0"] + _GOOD_H[6:]), 10, "loss must be"),
        (
            _msi_text(h_lines=_GOOD_H[:5] + ["5 1.0 2.0"] + _GOOD_H[6:]),
            10,
            "expected '<angle> <loss>'",
        ),
        (_msi_text() + "360 1.0\n", 726, "unexpected data line"),
        ("NAME x\nGAIN 1 dBi\nHORIZONTAL 360\n0 0.0\n1 0.0\n", 5, "ends after 2 of 360"),
        (_msi_text() + "HORIZONTAL 360\n", 726, "second HORIZONTAL"),
    ],
)
def test_malformed_msi_is_refused_with_file_and_line(tmp_path, text, line, what):
    path = tmp_path / "bad.msi"
    path.write_text(text)
    with pytest.raises(InputError) as err:
        read_msi(path)
    msg = str(err.value)
    assert "\n" not in msg
    assert msg.startswith(str(path))
    assert what in msg
    if line is not None:
        assert msg.startswith(f"{path}:{line}:"), msg


def test_missing_msi_file(tmp_path):
    with pytest.raises(InputError, match="cannot read"):
        read_msi(tmp_path / "nope.msi")
