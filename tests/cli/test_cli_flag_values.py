"""A flag's value that is none of its words or not of its form is a usage error: one line naming
the flag, exit code 2, found before any input is read (``rplearn.cli._app.flag_values``). It
exited 1, as an error in the input does (``fit --loss xyz``: ``error: --loss: expected ls or
huber, got 'xyz'``, code 1). An error in the input or the run, a value out of its range and flags
that contradict each other still exit 1."""

from __future__ import annotations

import pytest
import typer
from cli_helpers import run, run_here

from rplearn.cli._app import flag_values, user_errors
from rplearn.errors import BadValueError, InputError

#: (command line, the one line it prints: the message it printed before, with exit code 1).
BAD_VALUES = {
    "fit --loss": (["fit", "m.parquet", "--loss", "xyz", "-o", "y.json"], "--loss: expected ls or huber, got 'xyz'"),
    "fit --order": (["fit", "m.parquet", "--order", "xyz", "-o", "y.json"], "--order: expected a whole number or 'auto', got 'xyz'"),
    "fit --prior-level": (["fit", "m.parquet", "--prior-level", "xyz", "-o", "y.json"],
                          "prior level: expected data or prior, got 'xyz' (set it with --prior-level)"),
    "fit --path-loss": (["fit", "m.parquet", "--path-loss", "xyz", "-o", "y.json"],
                        "path loss: expected free, log-distance, two-ray, got 'xyz' (set it with --path-loss)"),
    "fit --model": (["fit", "m.parquet", "--model", "xyz", "-o", "y.json"],
                    "unknown model 'xyz'; expected one of sh, bg, poly, mean, knn (e.g. sh-10, nn-400) (set it with --model)"),
    "fit --dask": (["fit", "m.parquet", "--dask", "xyz", "-o", "y.json"],
                   "--dask: expected local, local:N or a scheduler address such as tcp://host:8786, got 'xyz'"),
    "report --polarization": (["report", "m.parquet", "--path-loss", "two-ray", "--polarization", "xyz", "-o", "r"],
                              "--polarization: expected vertical or horizontal, got 'xyz'"),
    "sweep --orders": (["sweep", "m.parquet", "--orders", "xyz"], "--orders: expected A..B or a comma list, got 'xyz'"),
    # a k-NN sweep ran (its "order" a k, its AIC counting every sample as a parameter), exit 0
    "sweep --model knn": (["sweep", "m.parquet", "--model", "knn"],
                          "--model: expected sh, bg or poly (a pattern model swept by its order), got 'knn'"),
    "predict --sensitivity": (["predict", "m.json", "d.parquet", "-o", "p.csv", "--sensitivity", "xyz"],
                              "--sensitivity: 'xyz' is neither a level in dBm nor a radio preset; presets: sik, rfd900, "
                              "esp32-11b, wifi-6mbps, wifi-54mbps, rx5808"),
    "sync --link": (["sync", "--poses", "p.csv", "--signals", "s.csv", "-o", "o.parquet", "--link", "xyz"],
                    "--link: expected TX:RX (e.g. A:B) or 'all', got 'xyz'"),
    "sync --nan-policy": (["sync", "--poses", "p.csv", "--signals", "s.csv", "-o", "o.parquet", "--nan-policy", "xyz"],
                          "--nan-policy: expected 'error' or 'drop', got 'xyz'"),
    "sync --rssi-scale": (["sync", "--poses", "p.csv", "--signals", "s.csv", "-o", "o.parquet", "--rssi-scale", "xyz"],
                          "--rssi-scale: expected 'dbm' or 'relative', got 'xyz'"),
    "inspect --station": (["inspect", "p.csv", "--station", "xyz"],
                          "--station: expected LAT,LON,ALT (e.g. 41.185,-96.010,330), got 'xyz'"),
    "simulate --format": (["simulate", "--format", "xyz", "-o", "f"], "--format: expected parquet or csv, got 'xyz'"),
    "simulate --preset": (["simulate", "--preset", "xyz", "-o", "f"],
                          "--preset: expected one of paper, trio, smoke, ground, pathloss, tworay, campaign, got 'xyz'"),
    "trajectory --check-model": (["trajectory", "--check-model", "mean", "-o", "t"],
                                 "--check-model: M has no per-node pattern to check; use sh, bg or poly"),
    "export --format": (["export", "m.json", "--format", "xyz", "-o", "g.csv"], "--format: expected grid, msi or images, got 'xyz'"),
    "links --as": (["links", "m.json", "p.csv", "--tx-power", "20", "-o", "l.csv", "--as", "xyz"], "--as: expected KEY=VALUE, got 'xyz'"),
    "headings --pos": (["headings", "m.json", "--pos", "A=0,0", "--tx-power", "20"], "--pos A: expected x,y,z in metres, got '0,0'"),
    "live --spread-over": (["live", "a.csv,b.csv", "-o", "m.json", "--spread-over", "xyz"],
                           "--spread-over: expected sphere or covered, got 'xyz'"),
    "replay --to": (["replay", "f.tlog", "--to", "xyz"], "--to: expected HOST:PORT, got 'xyz'"),
    "reference --mount": (["reference", "A=x.csv", "--mount", "A=xyz", "-o", "r.json"],
                          "--mount: expected NODE=ROLL,PITCH,YAW in degrees, got A=xyz"),
}

#: Checked only after an input was read before (a model file, the dataset, the simulated flight):
#: now before it, a usage error too; ``report --paper-models`` named ``--model`` (report's MODEL.json).
CHECKED_FIRST_NOW = {
    "orient --turn": (["orient", "m.json", "--tx", "A", "--rx", "B", "--tx-pos", "0,0,1", "--rx-pos", "1,0,1", "--turn", "xyz"],
                      "--turn: expected 'tx', 'rx' or 'both', got 'xyz'"),
    "fit --grid": (["fit", "m.parquet", "--model", "bg", "--grid", "xyz", "-o", "y.json"],
                   "BG grid must be 'paper' or 'fibonacci', got 'xyz' (set it with --grid)"),
    "demo --preset": (["demo", "--preset", "xyz", "-o", "d"],
                      "--preset: expected one of paper, trio, smoke, ground, pathloss, tworay, campaign, got 'xyz'"),
    "sweep --model": (["sweep", "m.parquet", "--model", "xyz"],  # was "unknown basis 'xyz'; ..." naming no flag
                      "unknown model 'xyz'; expected one of sh, bg, poly, mean, knn (e.g. sh-10, nn-400) (set it with --model)"),
    "report --paper-models": (["report", "m.parquet", "--paper-models", "xyz", "-o", "r"],
                              "unknown model 'xyz'; expected one of sh, bg, poly, mean, knn (e.g. sh-10, nn-400) "
                              "(set it with --paper-models)"),
}


def _usage_error(proc, expected: str) -> None:
    assert (proc.returncode, proc.stdout, proc.stderr) == (2, "", f"error: {expected}\n"), (proc.returncode, proc.stderr)


@pytest.mark.parametrize("case", sorted(BAD_VALUES) + sorted(CHECKED_FIRST_NOW))
def test_a_flags_bad_value_is_a_usage_error_in_one_line(tmp_path, case):
    args, expected = {**BAD_VALUES, **CHECKED_FIRST_NOW}[case]
    _usage_error(run_here(args, tmp_path, ok=False), expected)
    assert list(tmp_path.iterdir()) == []  # nothing written


def test_a_bad_value_in_a_users_process(tmp_path):
    _usage_error(run(["fit", "m.parquet", "--loss", "xyz", "-o", "y.json"], tmp_path), "--loss: expected ls or huber, got 'xyz'")


@pytest.mark.parametrize("args, needle", [
    (["fit", "m.parquet", "--loss", "huber", "--order", "3", "-o", "y.json"], "m.parquet: no such file"),  # the input
    (["fit", "m.parquet", "--ridge", "-1", "-o", "y.json"], "--ridge must be a non-negative number"),  # out of its range
    (["fit", "m.parquet", "--prior-level", "prior", "-o", "y.json"], "give --prior too"),  # against another flag
    (["sweep", "m.parquet", "--orders", "0..3"], "--orders: expected positive orders"),
    (["simulate", "--preset", "fleet", "--format", "csv", "-o", "f"], "the fleet preset writes Parquet"),
])
def test_errors_of_the_input_the_range_or_other_flags_still_exit_1(tmp_path, args, needle):
    proc = run_here(args, tmp_path, ok=False)
    lines = proc.stderr.splitlines()
    assert proc.returncode == 1 and len(lines) == 1 and lines[0].startswith("error: ") and needle in lines[0], proc.stderr


def test_only_a_bad_value_met_while_the_options_are_built_from_the_flags_exits_2(capsys):
    """The same library error outside :func:`flag_values` (a model file's field, read as input)
    exits 1; inside it a range or contradiction error (a plain InputError) exits 1 too."""

    def command(raised: Exception, in_flags: bool) -> None:
        if in_flags:
            with flag_values():
                raise raised
        raise raised

    bad = BadValueError("loss: expected ls or huber, got 'x'", param="loss")
    for raised, in_flags, code in ((bad, True, 2), (bad, False, 1), (InputError("loss: out of range", param="loss"), True, 1)):
        with pytest.raises(typer.Exit) as exit_:
            user_errors(command)(raised, in_flags)
        assert exit_.value.exit_code == code
        assert capsys.readouterr().err.splitlines()[-1].startswith("error: loss: ")
