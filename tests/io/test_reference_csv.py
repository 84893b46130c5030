"""rplearn.io.reference: the checks of a reference pattern's CSV (issue 29, class 4)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from rplearn.errors import InputError
from rplearn.io.reference import MIN_REFERENCE_DIRECTIONS, read_reference_pattern


def _grid(**columns) -> pd.DataFrame:
    az, el = np.meshgrid(np.arange(0.0, 360.0, 30.0), np.arange(-60.0, 61.0, 30.0))
    df = pd.DataFrame({"az_deg": az.ravel(), "el_deg": el.ravel()})
    df["gain_dbi"] = 2.0 * np.cos(np.radians(df["el_deg"]))
    return df.assign(**columns)


def _read(tmp_path, df: pd.DataFrame, **kwargs):
    path = tmp_path / "p.csv"
    df.to_csv(path, index=False)
    return read_reference_pattern(path, **kwargs)


def test_a_plausible_pattern_reads_with_its_frequency(tmp_path):
    ref = _read(tmp_path, _grid(frequency_hz=2.412e9))
    assert len(ref) == 60 and ref.frequency_hz == pytest.approx(2.412e9)
    assert _read(tmp_path, _grid()).frequency_hz is None


@pytest.mark.parametrize(("edit", "needle"), [
    (lambda d: d.assign(az_deg=np.radians(d["az_deg"]), el_deg=np.radians(d["el_deg"])), "column az_deg spans only"),
    (lambda d: d.rename(columns={"az_deg": "phi_rad"}).assign(theta_deg=lambda f: 90 - f["el_deg"]).drop(columns="el_deg"),
     "column phi_rad holds 330, beyond 2 pi: degrees?"),
    (lambda d: d.assign(phi_deg=d["az_deg"], theta_deg=90 - d["el_deg"]), "both body-frame"),
    (lambda d: d.assign(gain_db=d["gain_dbi"]), "both columns gain_dbi and gain_db"),
    (lambda d: d.iloc[:3], f"3 distinct measured direction(s); a pattern needs at least {MIN_REFERENCE_DIRECTIONS}"),
    (lambda d: pd.concat([d, d.assign(gain_dbi=d["gain_dbi"] - 30)]), "(30.0 dB apart, more than 6)"),
    (lambda d: d.assign(gain_dbi=np.where(d.index == 4, 5e6, d["gain_dbi"])), "gain_dbi 5e+06 at row 4 is outside -100 to 60 dBi"),
    (lambda d: d.assign(frequency_hz=2412.0), "frequency_hz 2412 at row 0 is not a radio carrier in Hz"),
    (lambda d: d.assign(frequency_hz=np.where(d.index < 5, 2.412e9, 5.8e9)), "holds 2 carriers"),
])
def test_a_bad_pattern_is_refused_naming_the_file(tmp_path, edit, needle):
    with pytest.raises(InputError) as err:
        _read(tmp_path, edit(_grid()))
    assert needle in str(err.value) and "p.csv" in str(err.value)


def test_repeats_within_the_tolerance_are_kept(tmp_path):
    df = _grid()
    assert len(_read(tmp_path, pd.concat([df, df.assign(gain_dbi=df["gain_dbi"] + 1.0)]))) == 120


def test_an_implausible_mount_is_refused(tmp_path):
    with pytest.raises(InputError, match="mount: angle 1e\\+300 at row 0 is outside -360 to 360 deg") as err:
        _read(tmp_path, _grid(), mount_rpy_deg=(1e300, 0.0, 0.0))
    assert err.value.param == "mount"
