"""Reference antennas (ITU-R F.1336-5 and others), mountings, airframe lobes, ground truth."""

from __future__ import annotations

import json

import numpy as np
import pytest

from rplearn.errors import InputError, ModelFileError
from rplearn.sim.antennas import AirframeLobe, AntennaSpec, GroundTruth, Mounting, NodeAntenna, antenna_from_name, load_ground_truth
from rplearn.sim.gain_formulas import (
    half_wave_dipole_dbi,
    itu_f1336_omni_average_dbi,
    itu_f1336_omni_peak_dbi,
    itu_f1336_omni_theta3_deg,
    itu_f1336_sectoral_average_dbi,
    itu_f1336_sectoral_peak_dbi,
    itu_f1336_sectoral_theta3_deg,
)

# Hand computation for G0 = 2 dBi, k = 0.7 (ITU-R F.1336-5 eqs. 1b-1d):
#   theta3 = 107.6 * 10^-0.2 = 107.6 * 0.630957 = 67.8910 deg
#   theta4 = theta3 * sqrt(1 - log10(1.7)/1.2) = 67.8910 * sqrt(0.807959) = 61.0248 deg
#   theta5 = theta3 * sqrt(1.25 - log10(1.7)/1.2) = 67.8910 * sqrt(1.057959) = 69.8308 deg
#   (90/theta3)^-1.5 = 1.325654^-1.5 = 0.655169


def test_omni_theta3_eq_1b() -> None:
    assert itu_f1336_omni_theta3_deg(2.0) == pytest.approx(67.8910, abs=1e-3)
    assert itu_f1336_omni_theta3_deg(10.0) == pytest.approx(10.76, abs=1e-9)


@pytest.mark.parametrize(
    "el_deg, expected_dbi",
    [
        (0.0, 2.0),  # G0 on the horizon
        (30.0, -0.34317),  # 2 - 12 (30/67.891)^2 = 2 - 12 * 0.195264
        (-30.0, -0.34317),  # symmetric in elevation
        (65.0, -7.69551),  # theta4 <= 65 < theta3: 2 - 12 + 10 log10(1.7)
        (90.0, -8.68007),  # 2 - 12 + 10 log10(0.655169 + 0.7)
    ],
)
def test_omni_peak_clause_2_1_hand_computed(el_deg: float, expected_dbi: float) -> None:
    """ITU-R F.1336-5 recommends 2.1 (peak side-lobe), k = 0.7 (recommends 2.3)."""
    assert float(itu_f1336_omni_peak_dbi(el_deg, 2.0, 0.7)) == pytest.approx(expected_dbi, abs=2e-4)


@pytest.mark.parametrize(
    "el_deg, k, expected_dbi",
    [
        (30.0, 0.7, -0.34317),  # main lobe as in 2.1
        (68.5, 0.7, -10.69551),  # theta3 <= 68.5 < theta5: 2 - 15 + 10 log10(1.7)
        (90.0, 0.7, -11.68007),  # 2 - 15 + 10 log10(0.655169 + 0.7)
        (90.0, 0.0, -14.83648),  # improved side-lobes (recommends 2.4): 2 - 15 + 10 log10(0.655169)
    ],
)
def test_omni_average_clause_2_2_hand_computed(el_deg: float, k: float, expected_dbi: float) -> None:
    """ITU-R F.1336-5 recommends 2.2 (average side-lobe), k = 0.7 typical / 0 improved."""
    assert float(itu_f1336_omni_average_dbi(el_deg, 2.0, k)) == pytest.approx(expected_dbi, abs=2e-4)


def test_omni_clause_2_1_is_continuous_and_2_2_lies_below() -> None:
    """Rec. 2.1 is continuous at theta4 and theta3; rec. 2.2 (average) never exceeds 2.1 (peak)."""
    for g0 in (2.0, 6.0, 10.0):
        for k in (0.0, 0.7):
            theta3 = itu_f1336_omni_theta3_deg(g0)
            theta4 = theta3 * np.sqrt(1 - np.log10(k + 1) / 1.2)
            for edge in (theta4, theta3):
                lo, hi = itu_f1336_omni_peak_dbi([edge - 1e-7, edge + 1e-7], g0, k)
                assert lo == pytest.approx(hi, abs=1e-4)
            el = np.linspace(-90, 90, 721)
            assert np.all(itu_f1336_omni_average_dbi(el, g0, k) <= itu_f1336_omni_peak_dbi(el, g0, k) + 1e-12)
            # the main lobe is 3 dB down at theta3/2 (the definition of the 3 dB beamwidth)
            assert float(itu_f1336_omni_peak_dbi(theta3 / 2, g0, k)) == pytest.approx(g0 - 3.0)


# Hand computation, sectoral, G0 = 15 dBi, phi3 = 65 deg, improved side-lobes (rec. 3.1.1.2:
# k_p = 0.7, k_h = 0.7, k_v = 0.3):
#   theta3 = 31000 * 10^-1.5 / 65 = 15.0816 deg
#   G180 = -12 + 10 log10(6.6) - 15 log10(180/15.0816) = -12 + 8.1954 - 16.1523 = -19.9569
#   lambda_kh = 3 (1 - 0.5^-0.7) = -1.8735
#   az 90: x_h = 1.38462, G_hr = -12 * 1.38462^1.3 + 1.8735 = -12 * 1.52660 + 1.8735 = -16.4457
#   el 20: x_v = 1.32612 in [x_k = 0.94446, 4), G_vr = -12 + 10 log10(1.32612^-1.5 + 0.3)
#          = -12 + 10 log10(0.954826) = -12.2008


@pytest.mark.parametrize(
    "az_deg, el_deg, expected_dbi",
    [
        (0.0, 0.0, 15.0),  # boresight
        (30.0, 0.0, 12.44379),  # x_h = 0.4615 <= 0.5: 15 - 12 * 0.4615^2
        (90.0, 0.0, -1.4457),  # 15 + G_hr(1.3846)
        (180.0, 0.0, -4.9569),  # back: 15 + G180 (R = 0)
        (0.0, 20.0, 2.7992),  # 15 + R G_vr with R = 1
        (0.0, 90.0, -4.9569),  # zenith: 15 + G180
    ],
)
def test_sectoral_peak_clause_3_1_1_hand_computed(az_deg: float, el_deg: float, expected_dbi: float) -> None:
    """ITU-R F.1336-5 recommends 3.1.1 (sectoral peak side-lobe), improved k (3.1.1.2)."""
    assert itu_f1336_sectoral_theta3_deg(15.0, 65.0) == pytest.approx(15.0816, abs=1e-4)
    g = float(itu_f1336_sectoral_peak_dbi(az_deg, el_deg, 15.0, 65.0, k_p=0.7, k_h=0.7, k_v=0.3))
    assert g == pytest.approx(expected_dbi, abs=2e-3)


# Typical side-lobes (rec. 3.1.1.1: k_h = 0.8, k_v = 0.7), same antenna:
#   lambda_kh = 3 (1 - 2^0.8) = -2.22330; az 90: G_hr = -12 * 1.38462^1.2 + 2.22330
#             = -12 * 1.477729 + 2.22330 = -15.50945
#   el 20 (peak): x_k = sqrt(1 - 0.252) = 0.86487 <= 1.32612: G_vr = -12 + 10 log10(0.654826 + 0.7)
#             = -12 + 1.31884 = -10.68116
# Average (rec. 3.1.2, k_a = 0.7): G180 = -15 + 8.1954 - 16.1523 = -22.9569
#   el 20: x_k = sqrt(1.33 - 0.231) = 1.04833 <= 1.32612: G_vr = -15 + 1.31884 = -13.68116
#   el 10: x_v = 0.66306 < x_k: G_vr = -12 * 0.66306^2 = -5.27577


@pytest.mark.parametrize(
    "func, az_deg, el_deg, expected_dbi",
    [
        ("peak", 90.0, 0.0, -0.50945),  # 3.1.1.1: 15 + G_hr
        ("peak", 0.0, 20.0, 4.31884),  # 3.1.1.1: 15 - 10.68116
        ("average", 90.0, 0.0, -0.50945),  # 3.1.2: same G_hr (G180 not reached)
        ("average", 0.0, 20.0, 1.31884),  # 3.1.2: 15 - 13.68116
        ("average", 0.0, 10.0, 9.72423),  # 3.1.2: 15 - 5.27577
        ("average", 180.0, 0.0, -7.9569),  # 3.1.2: 15 + G180 (back, R = 0)
    ],
)
def test_sectoral_typical_and_average_clause_3_1_hand_computed(
    func: str, az_deg: float, el_deg: float, expected_dbi: float
) -> None:
    """ITU-R F.1336-5 recommends 3.1.1.1 (typical peak) and 3.1.2 (average side-lobe)."""
    f = itu_f1336_sectoral_peak_dbi if func == "peak" else itu_f1336_sectoral_average_dbi
    assert float(f(az_deg, el_deg, 15.0, 65.0)) == pytest.approx(expected_dbi, abs=2e-3)


def test_sectoral_clause_3_1_1_beamwidths_and_continuity() -> None:
    """Rec. 3.1.1: 3 dB down at phi3/2 and theta3/2; G_vr reaches G180 continuously at 90 deg."""
    g0, phi3 = 18.0, 45.0
    theta3 = itu_f1336_sectoral_theta3_deg(g0, phi3)
    assert float(itu_f1336_sectoral_peak_dbi(phi3 / 2, 0.0, g0, phi3)) == pytest.approx(g0 - 3.0)
    assert float(itu_f1336_sectoral_peak_dbi(0.0, theta3 / 2, g0, phi3)) == pytest.approx(g0 - 3.0)
    # C and lambda_kv make G_vr continuous at x_v = 4 and let it reach G180 at 90 deg
    # (the recommendation's quadratic joins its second piece at x_k with a small step, which
    # is not checked here)
    for func, base in ((itu_f1336_sectoral_peak_dbi, -12.0), (itu_f1336_sectoral_average_dbi, -15.0)):
        g180 = base + 10 * np.log10(1 + 8 * 0.7) - 15 * np.log10(180 / theta3)
        lo, hi = func(0.0, [4 * theta3 - 1e-7, 4 * theta3 + 1e-7], g0, phi3)
        assert lo == pytest.approx(hi, abs=1e-5)
        near, at = func(0.0, [90.0 - 1e-7, 90.0], g0, phi3)
        assert near == pytest.approx(at, abs=1e-5) and at == pytest.approx(g0 + g180)
    # the average envelope lies below the peak one except where the peak pattern's main lobe
    # steps onto its shoulder at x_k (a step of a few tenths of a dB in the recommendation)
    el = np.linspace(-90.0, 90.0, 721)
    excess = itu_f1336_sectoral_average_dbi(0.0, el, g0, phi3) - itu_f1336_sectoral_peak_dbi(0.0, el, g0, phi3)
    assert excess.max() < 0.25 and np.mean(excess <= 1e-12) > 0.9
    az = np.linspace(-180.0, 180.0, 3601)
    ga = itu_f1336_sectoral_peak_dbi(az, 0.0, g0, phi3)
    assert np.argmax(ga) == 1800 and np.allclose(ga, ga[::-1])


def test_dipole_peak_and_directivity_normalisation() -> None:
    assert float(half_wave_dipole_dbi(0.0)) == pytest.approx(10 * np.log10(1.641), abs=1e-9)
    assert float(half_wave_dipole_dbi(90.0)) < -50.0
    # a lossless antenna radiates its power over the sphere: mean linear gain = 1
    for spec in (AntennaSpec("dipole"), antenna_from_name("itu_omni", g0_dbi=0.0, k=0.0)):
        el = np.radians(np.linspace(-89.95, 89.95, 1800))
        w = np.cos(el)
        lin = 10 ** (spec.gain_dbi(np.zeros_like(el), el) / 10)
        mean = np.sum(lin * w) / np.sum(w)
        if spec.kind == "dipole":
            assert mean == pytest.approx(1.0, rel=5e-3)
        else:  # the ITU envelope is a sharing-study envelope, not an energy-conserving pattern
            assert 0.2 < mean < 1.5


def test_mountings_rotate_the_antenna_axis() -> None:
    dipole = AntennaSpec("dipole")
    vertical = NodeAntenna(dipole, Mounting.named("vertical"))
    horizontal = NodeAntenna(dipole, Mounting.named("horizontal"))
    lateral = NodeAntenna(dipole, Mounting.named("horizontal_lateral"))
    az = np.radians([0.0, 90.0, 180.0, 0.0])
    el = np.radians([0.0, 0.0, 0.0, 90.0])
    v, h, lat = vertical.gain_dbi(az, el), horizontal.gain_dbi(az, el), lateral.gain_dbi(az, el)
    assert np.allclose(v[:3], 10 * np.log10(1.641)) and v[3] < -50
    # axis along body x: null forward/back, maximum to the side and up
    assert h[0] < -50 and h[2] < -50 and h[1] == pytest.approx(v[0]) and h[3] == pytest.approx(v[0])
    # axis along body y: null to the left
    assert lat[1] < -50 and lat[0] == pytest.approx(v[0])
    # a tilted mounting moves the null off the zenith by the tilt
    tilted = NodeAntenna(dipole, Mounting(pitch_deg=30.0))
    null_dir = tilted.gain_dbi(np.radians(0.0), np.radians(60.0))
    assert float(null_dir) < -50


def test_sectoral_boresight_follows_mounting_yaw() -> None:
    node = NodeAntenna(antenna_from_name("itu_sectoral"), Mounting(yaw_deg=90.0))
    az = np.radians(np.arange(-180, 180, 1.0))
    g = node.gain_dbi(az, np.zeros_like(az))
    assert np.degrees(az[np.argmax(g)]) == pytest.approx(90.0)


def test_airframe_lobes_shadow_locally() -> None:
    lobe = AirframeLobe(az_deg=30.0, el_deg=-40.0, width_deg=15.0, depth_db=8.0, label="camera")
    assert float(lobe.delta_db(np.radians(30.0), np.radians(-40.0))) == pytest.approx(-8.0)
    assert float(lobe.delta_db(np.radians(30.0), np.radians(-25.0))) == pytest.approx(-8.0 * np.exp(-0.5))
    assert abs(float(lobe.delta_db(np.radians(-150.0), np.radians(40.0)))) < 1e-6
    bare = NodeAntenna(antenna_from_name("itu_omni"))
    shadowed = NodeAntenna(antenna_from_name("itu_omni"), lobes=(lobe,))
    az, el = np.radians(30.0), np.radians(-40.0)
    assert float(bare.gain_dbi(az, el) - shadowed.gain_dbi(az, el)) == pytest.approx(8.0)
    with pytest.raises(InputError, match="width_deg"):
        AirframeLobe(0.0, 0.0, 0.0, 1.0)


@pytest.mark.parametrize(
    "name",
    ["itu_omni", "itu_omni_improved", "itu_omni_peak", "itu_sectoral", "itu_sectoral_improved",
     "itu_sectoral_average", "dipole", "isotropic", "high_gain"],
)
def test_every_antenna_is_finite_on_the_sphere(name: str) -> None:
    spec = antenna_from_name(name)
    az, el = np.meshgrid(np.radians(np.linspace(-180, 180, 73)), np.radians(np.linspace(-90, 90, 37)))
    g = spec.gain_dbi(az, el)
    assert g.shape == az.shape and np.all(np.isfinite(g))
    assert g.max() <= spec.g0_dbi + 2.2 + 1e-9


def test_bad_antenna_parameters_name_the_field() -> None:
    with pytest.raises(InputError, match="kind"):
        AntennaSpec("yagi")
    with pytest.raises(InputError, match="phi3_deg"):
        AntennaSpec("itu_sectoral_peak", phi3_deg=170.0)
    with pytest.raises(InputError, match="mounting"):
        Mounting.named("sideways")
    with pytest.raises(InputError, match="antenna name"):
        antenna_from_name("whip")


def _truth() -> GroundTruth:
    return GroundTruth(
        node_antennas={
            "A": NodeAntenna(antenna_from_name("itu_omni"), Mounting.named("vertical"),
                             (AirframeLobe(0.0, -60.0, 20.0, 6.0, "battery"),), "omni"),
            "B": NodeAntenna(antenna_from_name("itu_sectoral"), Mounting(yaw_deg=45.0), (), "sectoral"),
        },
        link_offsets_db={"A->B": 1.5, "B->A": -2.0},
        metadata={"note": "test"},
    )


def test_ground_truth_json_round_trip(tmp_path) -> None:
    truth = _truth()
    path = truth.save(str(tmp_path / "gt.json"))
    loaded = load_ground_truth(path)
    assert loaded.nodes == ("A", "B")
    rng = np.random.default_rng(3)
    az, el = rng.uniform(-np.pi, np.pi, 500), rng.uniform(-np.pi / 2, np.pi / 2, 500)
    for node in truth.nodes:
        np.testing.assert_array_equal(loaded.evaluate(node, az, el), truth.evaluate(node, az, el))
    j = loaded.predict_joint_gain_db("A", "B", az, el, -az, -el)
    np.testing.assert_allclose(j, truth.evaluate("A", az, el) + truth.evaluate("B", -az, -el))
    jo = loaded.predict_joint_gain_db("B", "A", az, el, -az, -el, include_link_offset=True)
    np.testing.assert_allclose(jo - loaded.predict_joint_gain_db("B", "A", az, el, -az, -el), -2.0)
    assert loaded.link_offset_db("A", "C") == 0.0


def test_ground_truth_errors(tmp_path) -> None:
    with pytest.raises(InputError, match="unknown id 'C'"):
        _truth().evaluate("C", 0.0, 0.0)
    with pytest.raises(ModelFileError, match="no such file"):
        load_ground_truth(str(tmp_path / "missing.json"))
    bad = tmp_path / "bad.json"
    bad.write_text("{not json")
    with pytest.raises(ModelFileError, match="not a JSON"):
        load_ground_truth(str(bad))
    spec = _truth().to_dict()
    spec["version"] = 99
    other = tmp_path / "other.json"
    other.write_text(json.dumps(spec))
    with pytest.raises(ModelFileError, match="version"):
        load_ground_truth(str(other))
    spec["version"] = 1
    del spec["nodes"]["A"]["antenna"]
    other.write_text(json.dumps(spec))
    with pytest.raises(ModelFileError, match="malformed"):
        load_ground_truth(str(other))


@pytest.mark.parametrize("n", [1, 7, 4096, 4097, 9000])
def test_node_gain_equals_its_lobes_added_one_by_one_to_the_bit(n: int) -> None:
    # gain_dbi adds the lobes in blocks into reused arrays: the same operations in the same order
    lobes = tuple(AirframeLobe(az, el, w, d) for az, el, w, d in
                  [(0.0, -90.0, 25.0, 6.0), (135.0, 10.0, 12.0, -1.5), (-60.0, 45.0, 40.0, 3.0)])
    node = NodeAntenna(antenna_from_name("itu_omni"), Mounting.named("tilted"), lobes)
    rng = np.random.default_rng(n)
    az, el = rng.uniform(-np.pi, np.pi, n), rng.uniform(-np.pi / 2, np.pi / 2, n)
    expected = node.antenna.gain_dbi(*node.mounting.body_to_antenna(az, el))
    for lobe in lobes:
        expected = expected + lobe.delta_db(az, el)
    assert node.gain_dbi(az, el).tobytes() == expected.tobytes()
