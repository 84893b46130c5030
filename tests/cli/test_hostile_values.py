"""Issue 29, classes 4 and 5 ("frequencies and units", "physical ranges"), run as the user ran them.

Each case is a command line on a small simulated flight, or on a file made bad on purpose, with
what must come out: a refusal (exit 1, one line ``error: ...`` naming the file, field or flag;
no traceback, nothing written) or a result that says what it did. The checks behind them are
one frequency check and one plausibility table (``rplearn.core.plausible``; unit tests in
tests/core/test_plausible.py).

The commands run in this process (:func:`cli_helpers.run_here`: the exit code, stdout and stderr a
user's process shows); one case of each refusal test (:data:`IN_A_PROCESS`) runs as a process of
its own (:func:`cli_helpers.run`), so that the process boundary stays covered.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from cli_helpers import D, M, P, S, answer, assert_one_line_error, invoke_in, listing, run_here, smoke_flight

ORIENT = ["orient", M, "--tx", "A", "--rx", "B", "--tx-pos", "0,0,20", "--rx-pos", "30,0,20"]
GHZ24, GHZ58 = 2.412e9, 5.8e9


def _reference_csv(**edits) -> pd.DataFrame:
    """A plausible measured pattern: az every 10 deg, el every 20 deg, a dipole-like gain."""
    az, el = np.meshgrid(np.arange(0.0, 360.0, 10.0), np.arange(-80.0, 81.0, 20.0))
    df = pd.DataFrame({"az_deg": az.ravel(), "el_deg": el.ravel()})
    df["gain_dbi"] = 2.0 + 3.0 * np.cos(np.radians(df["el_deg"])) - 3.0
    for k, v in edits.items():
        df[k] = v(df) if callable(v) else v
    return df


def _msi(text: str, frequency: str) -> str:
    return "\n".join(f"FREQUENCY {frequency}" if line.startswith("FREQUENCY") else line for line in text.splitlines()) + "\n"


def _bad_files(d: Path) -> None:
    from rplearn.models import load_model

    model = load_model(d / M)
    for name, f in {"mhz_model.json": 2412.0, "b58_model.json": GHZ58}.items():
        other = load_model(d / M)
        other.training = other.training.replace(frequency_hz=f)
        other.save(str(d / name))
    assert model.frequency_hz == pytest.approx(GHZ24)
    data = pd.read_parquet(d / D)
    half = np.arange(len(data)) % 2 == 1
    data.assign(frequency_hz=np.where(half, GHZ58, GHZ24)).to_parquet(d / "mixed.parquet")
    data[~half].to_parquet(d / "p24.parquet")
    data[half].assign(frequency_hz=GHZ58).to_parquet(d / "p58.parquet")
    data.assign(frequency_hz=GHZ58).to_parquet(d / "data58.parquet")
    ref = {
        "ref.csv": _reference_csv(),
        "rad_in_deg.csv": _reference_csv(az_deg=lambda f: np.radians(f["az_deg"]), el_deg=lambda f: np.radians(f["el_deg"])),
        "deg_in_rad.csv": _reference_csv().rename(columns={"az_deg": "phi_rad", "el_deg": "theta_deg"}).assign(
            theta_deg=lambda f: 90.0 - f["theta_deg"]),
        "both_frames.csv": _reference_csv(phi_deg=lambda f: f["az_deg"], theta_deg=lambda f: 90.0 - f["el_deg"]),
        "both_gains.csv": _reference_csv(gain_db=lambda f: f["gain_dbi"]),
        "one_direction.csv": _reference_csv().iloc[:1],
        "three_directions.csv": _reference_csv().iloc[:3],
        "twice_30db.csv": pd.concat([_reference_csv(), _reference_csv(gain_dbi=lambda f: f["gain_dbi"] - 30.0)]),
        "gain_5e6.csv": _reference_csv(gain_dbi=lambda f: np.where(f.index == 7, 5e6, f["gain_dbi"])),
    }
    for name, frame in ref.items():
        frame.to_csv(d / name, index=False)
    invoke_in(d, ["export", M, "--format", "msi", "-o", "msi"])
    text = next((d / "msi").glob("*A*.msi")).read_text()
    for name, freq in {"f2.412.msi": "2.412", "f0.msi": "0", "fneg.msi": "-2412", "f58.msi": "5800"}.items():
        (d / name).write_text(_msi(text, freq))
    invoke_in(d, ["reference", "B=ref.csv", "-o", "ref_B.json"])
    from rplearn.io.modelfile import read_model_file, write_model_file

    for name, entry in {"cov_null.json": None, "cov_neg.json": -1.0}.items():
        kind, payload = read_model_file(d / M)
        payload["covariance"][0][0] = entry  # null: a NaN written as strict JSON
        write_model_file(d / name, kind, payload)


ORIGIN = (47.3977, 8.5456, 488.0)  # lat, lon [deg], alt [m AMSL] of the tlog's ENU origin


def _tlogs(d: Path) -> None:
    """The first 90 s of the ``ground`` preset's flight (the first pass, at 15 m: what the
    checks read is the station and the vehicle's first rows; a quarter of the flight makes a
    quarter of the messages to write and merge) as .tlog files: as flown, and with the station
    (the HOME_POSITION written) moved 111 km and 3,000 km north of the flight."""
    from rplearn.core.geometry import quat_wxyz_from_yaw
    from rplearn.io._common import Logs
    from rplearn.io.tlog import write_tlog
    from rplearn.sim.flight import simulate

    sim = simulate("ground", seed=1)
    pose, signal = sim.pose_log[sim.pose_log["t"] <= 90.0], sim.signal_log[sim.signal_log["t"] <= 90.0]
    g = pose[pose["node"] == "G"]
    q = quat_wxyz_from_yaw(0.0)
    for name, north_m in {"flight.tlog": 0.0, "home111km.tlog": 111_000.0, "home3000km.tlog": 3_000_000.0}.items():
        station = pd.DataFrame({"t": [g["t"].min()], "node": ["G"], "x": [g["x"].median()], "y": [g["y"].median() + north_m],
                                "z": [g["z"].median()], "qw": [q[0]], "qx": [q[1]], "qy": [q[2]], "qz": [q[3]]})
        logs = Logs(pd.concat([pose[pose["node"] == "D"], station], ignore_index=True), signal)
        write_tlog(logs, d / name, vehicle="D", station="G", origin_geodetic=ORIGIN)
    write_tlog(logs, d / "sys2.tlog", vehicle="D", station="G", origin_geodetic=ORIGIN, system_id=2)
    _merge_second_vehicle(d / "flight.tlog", d / "sys2.tlog", d / "two_vehicles.tlog")
    (d / "sys2.tlog").unlink()


def _merge_second_vehicle(first: Path, second: Path, out: Path) -> None:
    """One .tlog with both vehicles' messages in time order, and the radio reports of the first only."""
    import struct

    from pymavlink import mavutil

    records = []
    for path, keep_radio in ((first, True), (second, False)):
        conn = mavutil.mavlink_connection(str(path), dialect="ardupilotmega")
        while (msg := conn.recv_msg()) is not None:
            if msg.get_type() == "BAD_DATA" or (not keep_radio and msg.get_type() in ("RADIO_STATUS", "RADIO")):
                continue
            records.append((round(msg._timestamp * 1e6), bytes(msg.get_msgbuf())))
    records.sort(key=lambda r: r[0])
    out.write_bytes(b"".join(struct.pack(">Q", t) + buf for t, buf in records))


def _below_ground(d: Path) -> None:
    """A two-ray model, a pose log with drone A 5 m below the ground, a relative-RSSI model."""
    invoke_in(d, ["fit", D, "--degree", "3", "--path-loss", "two-ray", "-o", "tworay.json"])
    pose = pd.read_parquet(d / P)
    pose.assign(z=np.where(pose["node"] == "A", -5.0, pose["z"])).to_parquet(d / "below.parquet")
    invoke_in(d, ["sync", "--poses", P, "--signals", S, "--link", "all", "--rssi-scale", "relative", "-o", "rel.parquet"])
    invoke_in(d, ["fit", "rel.parquet", "--degree", "3", "-o", "rel.json"])


@pytest.fixture(scope="module")
def workdir(tmp_path_factory):
    d = tmp_path_factory.mktemp("values")
    smoke_flight(d)
    _bad_files(d)
    _tlogs(d)
    _below_ground(d)
    return d


#: Refusals: (command line, text the one error line must hold).
REFUSED = {
    # class 4: frequencies and units
    "model file at 2412 Hz": (["predict", "mhz_model.json", D, "-o", "p.csv"],
                              "mhz_model.json: training.frequency_hz 2412 is not a radio carrier in Hz"),
    "MSI FREQUENCY 2.412 (GHz meant)": (["reference", "A=f2.412.msi", "-o", "r.json"], "2.412 looks like GHz"),
    "MSI FREQUENCY 0": (["reference", "A=f0.msi", "-o", "r.json"], "f0.msi"),
    "MSI FREQUENCY -2412": (["reference", "A=fneg.msi", "-o", "r.json"], "expected a positive frequency in MHz, got -2412"),
    "export msi --frequency 2412": (["export", M, "--format", "msi", "--frequency", "2412", "-o", "msi2"],
                                    "--frequency: 2412 is not a radio carrier in Hz"),
    "export msi at another band": (["export", M, "--format", "msi", "--frequency", "5.8e9", "-o", "msi3"],
                                   "learned at 2.412 GHz"),
    "dataset mixing 2.412 and 5.8 GHz in one file": (["fit", "mixed.parquet", "--degree", "3", "-o", "x.json"],
                                                     "mixed.parquet: carriers of 2 bands: 2.412 GHz (673 samples), 5.8 GHz (672 samples)"),
    "dataset mixing bands across parts": (["fit", "p24.parquet,p58.parquet", "--degree", "3", "-o", "x.json"],
                                          "carriers of 2 bands"),
    "5.8 GHz prior for 2.412 GHz data": (["fit", D, "--degree", "auto", "--prior", "A=b58_model.json", "-o", "x.json"],
                                         "the prior of A learned at 5.8 GHz"),
    "2.412 GHz model evaluated on 5.8 GHz data": (["evaluate", M, "data58.parquet", "--units", "test_90"],
                                                  "data58.parquet: 1,327 row(s) at 5.8 GHz, but sh3.json learned at 2.412 GHz"),
    "2.412 GHz model predicting 5.8 GHz data": (["predict", M, "data58.parquet", "-o", "p.csv"], "learned at 2.412 GHz"),
    "orient --frequency 5.8e9": (ORIENT + ["--frequency", "5.8e9"], "--frequency: 5.8 GHz, but the"),
    "reference of two bands": (["reference", "A=f2.412.msi", "A=f58.msi", "-o", "r.json"], "f2.412.msi"),
    "radians in *_deg columns": (["reference", "A=rad_in_deg.csv", "-o", "r.json"], "rad_in_deg.csv: column az_deg spans only"),
    "degrees in phi_rad": (["reference", "A=deg_in_rad.csv", "-o", "r.json"], "deg_in_rad.csv: column phi_rad holds 350"),
    "az/el and phi/theta columns": (["reference", "A=both_frames.csv", "-o", "r.json"], "both body-frame"),
    "gain_dbi and gain_db": (["reference", "A=both_gains.csv", "-o", "r.json"], "both columns gain_dbi and gain_db"),
    "one measured direction": (["reference", "A=one_direction.csv", "-o", "r.json"], "1 distinct measured direction(s)"),
    "three measured directions": (["reference", "A=three_directions.csv", "-o", "r.json"], "3 distinct measured direction(s)"),
    "every direction twice, 30 dB apart": (["reference", "A=twice_30db.csv", "-o", "r.json"], "(30.0 dB apart"),
    "gain of 5e6 dBi": (["reference", "A=gain_5e6.csv", "-o", "r.json"], "gain_5e6.csv: gain_dbi 5e+06 at row 7 is outside"),
    "--mount A=1e300,0,0": (["reference", "A=ref.csv", "--mount", "A=1e300,0,0", "-o", "r.json"], "1e+300"),
    "prior holding only node B used for A": (["fit", D, "--degree", "auto", "--prior", "A=ref_B.json", "-o", "x.json"],
                                             "holds only node B"),
    # class 5: physical ranges
    "covariance with a negative variance": (["predict", "cov_neg.json", D, "-o", "p.csv"],
                                            "cov_neg.json: covariance: the variance on the diagonal at 0 is negative"),
    "covariance holding null (NaN)": (["predict", "cov_null.json", D, "-o", "p.csv"], "cov_null.json: covariance: entry (0, 0) is nan"),
    "two-ray ground 1,000 km below": (["fit", D, "--degree", "3", "--path-loss", "two-ray", "--ground-level", "-1e6",
                                       "-o", "x.json"], "--ground-level"),
    "latitude 95 (--station)": (["inspect", "flight.tlog", "--station", "95,8.5,488"], "--station: latitude must lie in [-90, 90]"),
    "latitude 200 (--station)": (["inspect", "flight.tlog", "--station", "200,8.5,488"], "--station: latitude must lie in [-90, 90]"),
    "altitude 2,000 km (--station)": (["inspect", "flight.tlog", "--station", "47.3977,8.5456,2e6"],
                                      "--station: altitude 2e+06 m is outside -1000 to 50000 m"),
    "drone below a two-ray ground in links": (["links", "tworay.json", "below.parquet", "--tx-power", "20", "-o", "l.csv"],
                                              "below.parquet: drone A: z [m] above the two-ray ground at 0 m -5"),
    "drone below a two-ray ground in orient": (["orient", "tworay.json", "--tx", "A", "--rx", "B", "--tx-pos", "0,0,-5",
                                                "--rx-pos", "30,0,20", "--tx-power", "20"], "above the two-ray ground at 0 m -5"),
    "orient 1,000 km apart": (["orient", M, "--tx", "A", "--rx", "B", "--tx-pos", "0,0,20", "--rx-pos", "1e6,0,20"],
                              "tx to rx: distance [m] 1e+06 is outside 0 to 100000 m"),
    "relative RSSI printed as dBm by links": (["links", "rel.json", P, "--tx-power", "20", "-o", "l.csv"],
                                              "learned from relative RSSI"),
}


#: The cases that run as a process of their own (one per refusal test).
IN_A_PROCESS = {"orient 1,000 km apart", "home 111 km from the flight"}


@pytest.mark.parametrize("case", sorted(REFUSED))
def test_refused_in_one_line_and_nothing_written(workdir, case):
    args, needle = REFUSED[case]
    before = listing(workdir)
    assert_one_line_error(answer(args, workdir, case in IN_A_PROCESS), needle, case)
    assert listing(workdir) == before  # nothing written, no temporary file left


#: A log refused as a whole (exit 1; the line naming it may come before the count of unread files).
LOG_REFUSED = {
    "station 1,000 km away (--station)": (["inspect", "flight.tlog", "--station", "56.4,8.5456,488"],
                                          "flight.tlog: the vehicle: distance from the station [m] 1"),
    "home 111 km from the flight": (["inspect", "home111km.tlog"],
                                    "home111km.tlog: the vehicle: distance from the station [m] 111004 at row 0 is outside 0 to 100000 m"),
    "home 3,000 km from the flight": (["inspect", "home3000km.tlog"], "home3000km.tlog: geodetic position: origin altitude [m] 670674 is outside"),
}


assert IN_A_PROCESS <= REFUSED.keys() | LOG_REFUSED.keys()


@pytest.mark.parametrize("case", sorted(LOG_REFUSED))
def test_implausible_places_refuse_the_log(workdir, case):
    args, needle = LOG_REFUSED[case]
    proc = answer(args, workdir, case in IN_A_PROCESS)
    out = proc.stdout + proc.stderr
    assert proc.returncode == 1 and needle in out and "Traceback" not in out, (case, out)


def test_orient_on_a_relative_model_says_db_not_dbm(workdir):
    """A relative-RSSI model still ranks headings by joint gain, printed in dB, never dBm."""
    proc = run_here(["orient", "rel.json", "--tx", "A", "--rx", "B", "--tx-pos", "0,0,20", "--rx-pos", "30,0,20", "--tx-power", "20"],
                    workdir, ok=False)
    assert proc.returncode == 0 and "dBm" not in proc.stdout and "predicted joint gain" in proc.stdout, proc.stdout + proc.stderr


def test_a_second_vehicle_is_counted_and_named(workdir):
    """Two vehicles (system ids 1 and 2) in one .tlog with one radio: the second is named, not dropped silently."""
    proc = run_here(["inspect", "two_vehicles.tlog"], workdir, ok=False)
    out = proc.stdout + proc.stderr
    assert proc.returncode == 0, out
    assert "2 vehicles in one log: read system id" in out and "not read: system id" in out, out
    assert "ATTITUDE message(s)" in out


def test_the_real_flight_still_reads(workdir):
    """The unmoved .tlog reads as before: the checks refuse only what is implausible."""
    proc = run_here(["inspect", "flight.tlog"], workdir, ok=False)
    assert proc.returncode == 0, proc.stderr


# Shown elsewhere:
# - MHz in a signal log, 1e30 Hz, orient --frequency 2412 / 0: tests/cli/test_hostile_examples.py
# - Sionna SceneLinkOptions(frequency_hz=2412), the table and the checks: tests/core/test_plausible.py
