"""``trajectory --optimize`` (with ``--from-model``) on hostile figures, run as the user runs it.

A model file whose training figures are finite and >= 0 (what the model reader checks) but no
radio's (a noise of 0, 1e-300 or 1e300 dB, a variance inflation of 0, a roughness power of -1),
a reference pattern model, and flags beyond what a radio or a drone does: each is one line
naming the file and field, or the flag, and nothing is written. Were: an ``OverflowError``
traceback, a plan whose spreads were NaN or 1e150 dB, a refusal blaming ``--noise`` that was
never given, 'a fixed-order fit (SH-20)' for a reference pattern, 'no manoeuvre lowers the
spread' when the prior already met the target, and a penalty weight of 1e300 planned as 'nothing
to fly'.
"""

from __future__ import annotations

from pathlib import Path

import pytest
from cli_helpers import D, answer, assert_one_line_error, invoke_in, listing, run_here, smoke_flight

PLAN = ["trajectory", "--optimize", "--check-model", "sh-3", "--target-spread", "2.5", "--budget-s", "30"]


@pytest.fixture(scope="module")
def flight(tmp_path_factory) -> Path:
    """The smoke flight with an automatic fit (``auto.json``), copies of it with hostile training
    figures, and a reference pattern model (``ref.json``)."""
    from rplearn.io.modelfile import read_model_file, write_model_file

    d = smoke_flight(tmp_path_factory.mktemp("plan_from_model"))
    invoke_in(d, ["fit", D, "--order", "auto", "-o", "auto.json"])
    for name, field, value in (("noise_big", "noise_std_db", 1e300), ("noise_zero", "noise_std_db", 0.0),
                               ("noise_tiny", "noise_std_db", 1e-300), ("inflation_zero", "variance_inflation", 0.0),
                               ("inflation_big", "variance_inflation", 1e300), ("drift_big", "drift_std_db", 1e300),
                               ("power_neg", "penalty_power", -1.0), ("power_big", "penalty_power", 1e300),
                               ("weight_big", "planning_penalty_weight", 1e300), ("at_cap", "smoothing", 1e6)):
        kind, payload = read_model_file(d / "auto.json")
        payload["training"][field] = value
        write_model_file(d / f"{name}.json", kind, payload)
    (d / "ref.csv").write_text("az_deg,el_deg,gain_dbi\n" + "".join(
        f"{az},{el},{1.0 if el == 0 else 0.0}\n" for az in range(0, 360, 30) for el in range(-60, 61, 30)))
    invoke_in(d, ["reference", "A=ref.csv", "B=ref.csv", "-o", "ref.json"])
    return d


MODEL_CASES = [
    ("noise_big.json", "training.noise_std_db is 1e+300, not a radio's RSSI scatter [dB]: expected 0.01 to 90; give --noise"),
    ("noise_zero.json", "training.noise_std_db is 0, not a radio's RSSI scatter"),
    ("noise_tiny.json", "training.noise_std_db is 1e-300"),
    ("inflation_zero.json", "training.variance_inflation is 0, not a fit's variance inflation (at least 1)"),
    ("inflation_big.json", "training.variance_inflation is 1e+300"),
    ("drift_big.json", "training.drift_std_db is 1e+300, not a radio's drifting error [dB]: expected 0 to 90; give --drift"),
    ("power_neg.json", "training.penalty_power is -1, not a smoothness penalty's roughness power"),
    ("power_big.json", "training.penalty_power is 1e+300"),
    ("weight_big.json", "training.planning_penalty_weight is 1e+300, not a fit's smoothness penalty weight for its samples "
                        "(units of X^T X): expected 0 to "),
    ("at_cap.json", "training.smoothing is 1e+06, the largest the search tries: its flight did not tell the patterns' "
                    "shape from flat"),
    ("ref.json", "ref.json is a reference pattern model (rplearn reference), not a fit of a flight"),
]


@pytest.mark.parametrize(("model", "needle"), MODEL_CASES, ids=[m for m, _ in MODEL_CASES])
def test_a_models_figures_no_radio_has_are_refused_naming_file_and_field(flight, model, needle):
    before = listing(flight)
    proc = answer([*PLAN, "--from-model", model, "-o", "plan"], flight, process=model == "noise_big.json")
    assert_one_line_error(proc, f"--from-model: {model}", model)
    assert needle in proc.stderr and "--noise: expected" not in proc.stderr, proc.stderr
    assert listing(flight) == before


FLAG_CASES = [
    (["--noise", "1e300"], "--noise: 1e+300 dB is not a radio's RSSI scatter: expected 0.01 to 90 dB"),
    (["--noise", "1e-300"], "--noise: 1e-300 dB is not a radio's RSSI scatter"),
    (["--drift", "1e300"], "--drift: 1e+300 dB is not"),
    (["--packet-rate", "1e300"], "--packet-rate: 1e+300 Hz is not packets a radio reports per second"),
    (["--speed", "1e-300"], "--speed: 1e-300 m/s is not a drone's cruise speed: expected 0.5 to 50 m/s"),
    (["--speed", "1e300"], "--speed: 1e+300 m/s is not a drone's cruise speed"),
    (["--height", "1e300"], "--height: 1e+300 m is not a drone's height"),
    (["--distance", "1e300"], "--distance: 1e+300 m is not a drone radio link"),
    (["--rate", "inf"], "--rate: expected a sample rate of at least 1 Hz, got inf"),
    (["--rate", "1e-300"], "--rate: expected a sample rate of at least 1 Hz"),
    (["--rate", "1e300"], "--rate: 1e+300 Hz would take"),
]


@pytest.mark.parametrize(("flags", "needle"), FLAG_CASES, ids=[" ".join(f) for f, _ in FLAG_CASES])
def test_flags_beyond_a_radio_or_a_drone_are_refused_naming_the_flag(flight, flags, needle):
    before = listing(flight)
    proc = answer([*PLAN, "--from-model", "auto.json", *flags, "-o", "plan"], flight)
    assert_one_line_error(proc, needle, " ".join(flags))
    assert listing(flight) == before


def test_a_prior_already_within_the_target_is_said_so(flight):
    for args in (["--target-spread", "100"],):
        proc = run_here([*PLAN, *args, "-o", "plan"], flight)
        assert "the prior's spread is already at most the target" in proc.stdout, proc.stdout
        assert "no manoeuvre lowers the spread" not in proc.stdout
        assert not (flight / "plan").exists() or not list((flight / "plan").iterdir())


def test_a_stated_prior_capped_by_the_ridge_is_said_and_the_models_nodes_named(flight):
    """--noise 1 --prior-std 6 planned with 2.81 dB, shown only on the '(prior)' line: now one
    note line says so; a plan from a model names the nodes it was a fit of."""
    proc = run_here([*PLAN, "--noise", "1", "--prior-std", "6", "-o", "capped"], flight)
    notes = [line for line in proc.stdout.splitlines() if line.startswith("note: the stated prior")]
    assert len(notes) == 1 and "6 dB is more than SH-3's ridge" in notes[0] and "1-dB noise" in notes[0], proc.stdout
    proc = run_here([*PLAN, "--station", "--from-model", "auto.json", "-o", "station"], flight)
    assert "prior from auto.json: a fit of nodes A, B, taken for the plan's D, G: noise" in proc.stdout, proc.stdout
