"""rplearn.data.units: the one rule that decides which units learn and which test."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from rplearn.data.units import evaluation_units, is_test_unit, learning_units, select_units, split_units, time_units
from rplearn.errors import InputError


def frame(units):
    return pd.DataFrame({"unit": list(units)})


def test_test_units_are_recognised_in_any_case():
    assert is_test_unit("test_36") and is_test_unit("TEST_1") and is_test_unit("Testing")
    assert not is_test_unit("learn_0") and not is_test_unit("contest")


def test_learning_units_default_to_every_non_test_unit_and_say_so():
    choice = learning_units(frame(["learn_0", "learn_24", "test_36", "learn_0"]))
    assert choice.units == ["learn_0", "learn_24"] and choice.defaulted
    assert choice.notes == ["learning from units learn_0, learn_24; left out test_36"]
    assert learning_units(frame(["a", "b"]), ["b"]).units == ["b"]
    assert learning_units(pd.DataFrame({"t": [0.0]})).units is None
    only_test = learning_units(frame(["test_1"]), source="d.parquet")
    assert only_test.units is None and "every unit is labelled test" in only_test.notes[0]


def test_evaluation_units_prefer_units_no_model_learned_from():
    df = frame(["learn_0", "learn_24", "test_36"])
    prov = [{"parameters": {"units": ["learn_0", "learn_24"], "dataset": "d.parquet"}}]
    unseen = evaluation_units(df, None, prov, "d.parquet")
    assert unseen.units == ["test_36"] and not unseen.warnings
    chosen = evaluation_units(df, ["learn_0"], prov, "d.parquet")
    assert chosen.units == ["learn_0"] and "training scores" in chosen.warnings[0]
    everything = evaluation_units(df, None, [{}], "d.parquet")
    assert everything.units == ["learn_0", "learn_24", "test_36"] and everything.notes


def test_evaluation_without_units_warns_on_the_training_file_name():
    prov = [{"parameters": {"dataset": "/somewhere/d.parquet"}}]
    choice = evaluation_units(pd.DataFrame({"t": [0.0]}), None, prov, "d.parquet")
    assert choice.units is None and "probably training scores" in choice.warnings[0]


def test_split_units_is_disjoint_and_refuses_what_cannot_be_split():
    df = frame(["learn_0", "learn_24", "test_36"])
    assert split_units(df) == (["learn_0", "learn_24"], ["test_36"])
    assert split_units(df, test_units=["learn_24"]) == (["learn_0", "test_36"], ["learn_24"])
    with pytest.raises(InputError, match="share learn_0") as err:
        split_units(df, ["learn_0"], ["learn_0"])
    assert err.value.param == "test_units"
    with pytest.raises(InputError, match="cannot split"):
        split_units(frame(["a", "b"]))
    with pytest.raises(InputError, match="'unit' column"):
        split_units(pd.DataFrame({"t": [0.0]}))


def test_select_units_names_unknown_units_and_the_parameter():
    with pytest.raises(InputError, match="unknown unit") as err:
        select_units(frame(["a"]), ["b"], "d.parquet")
    assert err.value.param == "units"
    assert len(select_units(frame(["a", "b", "a"]), ["a"])) == 2


def test_time_units_cut_a_flight_without_units_into_stretches_of_time():
    import numpy as np

    rng = np.random.default_rng(0)
    t = rng.permutation(np.arange(103, dtype=float))  # unsorted rows
    df = pd.DataFrame({"t": t, "rssi_dbm": -60.0})
    out, note = time_units(df, source="flight.parquet")
    assert len(out) == len(df) and (out["t"] == df["t"]).all()  # rows neither dropped nor moved
    counts = out["unit"].value_counts()
    assert sorted(counts.index) == ["flight[1/5]", "flight[2/5]", "flight[3/5]", "flight[4/5]", "test[5/5]"]
    assert counts.max() - counts.min() <= 1
    # contiguous in time: every stretch ends before the next begins, the test is last
    spans = out.groupby("unit")["t"].agg(["min", "max"]).sort_values("min")
    assert list(spans.index)[-1] == "test[5/5]"
    assert (spans["max"].to_numpy()[:-1] < spans["min"].to_numpy()[1:]).all()
    first_test = spans.loc["test[5/5]", "min"]
    start = float(out["t"].min())  # times relative to the log start, its epoch given once
    assert "flight.parquet has no 'unit' column" in note and f"from {first_test - start:.1f} s after the log start" in note
    assert note.count(f"t = {start:.3f} s") == 1 and f"{first_test:.3f}" not in note
    assert split_units(out) == (["flight[1/5]", "flight[2/5]", "flight[3/5]", "flight[4/5]"], ["test[5/5]"])
    # a dataset with units is left alone; too few or non-finite times are refused
    labelled = df.assign(unit="learn_0")
    assert time_units(labelled) == (labelled, None)
    with pytest.raises(InputError, match="3 sample"):
        time_units(df.head(3))
    # both directions of a telemetry report share their time: a pair is never split
    pairs = pd.DataFrame({"t": np.repeat(np.arange(49, dtype=float), 2), "tx": ["a", "b"] * 49})
    cut, _ = time_units(pairs)
    assert (cut.groupby("t")["unit"].nunique() == 1).all()
    assert cut["unit"].nunique() == 5
    with pytest.raises(InputError, match="too few distinct times"):
        time_units(pd.DataFrame({"t": [0.0] * 4 + [1.0] * 3 + [2.0] * 3}))
    with pytest.raises(InputError):
        time_units(df.assign(t=np.where(df["t"] == 5, np.nan, df["t"])))


def test_a_fleets_hundreds_of_units_are_summarised_in_notes():
    """A fleet dataset has a unit per flight and leg: a note lists the first and last few."""
    import pandas as pd

    from rplearn.data.units import learning_units, unit_list

    assert unit_list(["a", "b"]) == "a, b"
    units = [f"learn_{k}@f{f:04d}" for f in range(30) for k in (0, 24)] + [f"test_36@f{f:04d}" for f in range(30)]
    df = pd.DataFrame({"unit": units})
    note = learning_units(df).notes[0]
    assert "(60 units)" in note and "(30 units)" in note and len(note) < 400  # all 90 names: 1,378 characters
    assert note.startswith("learning from units learn_0@f0000, learn_0@f0001,") and ", ..., " in note


def test_one_naming_of_stretches_cut_at_instants():
    import numpy as np

    from rplearn.data.units import Stretches, is_stretch_label, refuse_streamed_stretches, stretch_labels, stretched

    assert stretch_labels() == ["flight[1/5]", "flight[2/5]", "flight[3/5]", "flight[4/5]", "test[5/5]"]
    assert stretch_labels(3, "learn_0") == ["learn_0[1/3]", "learn_0[2/3]", "learn_0[3/3]"]
    assert all(is_stretch_label(u) for u in stretch_labels()) and not is_stretch_label("learn_0[1/3]")
    assert not is_stretch_label("flight[6/5]") and not is_stretch_label("test_36")
    # three rows at each of 7 instants: equal-count cuts fall inside instants (as a cut by row counts
    # would split them) and move to their start
    t = np.repeat(np.arange(7.0), 3)[::-1]  # any order
    by_rows = np.array_split(np.sort(t), 5)
    assert any(a[-1] == b[0] for a, b in zip(by_rows[:-1], by_rows[1:]))
    cut = Stretches.of_times(t)
    k = cut.index(t)
    assert all(len(set(k[t == x])) == 1 for x in np.unique(t))  # no instant split
    assert np.all(np.diff(k[np.argsort(t)]) >= 0)  # contiguous in time
    assert sorted(set(cut.label(t))) == stretch_labels()
    # only a dataset without units, with units chosen, is cut; a streamed one is refused with the names
    df = pd.DataFrame({"t": t})
    assert stretched(df, None)[0] is df and "unit" in stretched(df, ["test[5/5]"])[0].columns
    with pytest.raises(InputError, match=r"flight\[1/5\]") as err:
        refuse_streamed_stretches(pd.DataFrame({"tx": ["a"], "n": [3]}), ["test[5/5]"], "big")
    assert err.value.param == "units"
    refuse_streamed_stretches(pd.DataFrame({"unit": ["u"], "n": [3]}), ["u"], "big")
    with pytest.raises(InputError, match=r"lacks \(a flight without units is cut into stretches"):
        select_units(df, ["test[5/5]"], "d.parquet")


def test_one_flight_cut_into_stretch_samples_the_way_time_units_cuts_it():
    """stretch_samples (the folds of a single unit) uses the one cut of data/units.py: every row
    in exactly one stretch, no instant split, named after the unit, the same rows time_units
    labels."""
    from rplearn.data.units import TIME_UNITS, samples_of, stretch_samples, time_units
    from rplearn.sim.flight import simulate

    df = simulate("smoke", seed=3).matched_truth.drop(columns=["unit"])
    # repeated instants (another reading at the time of one row in 7: not an exact copy, which
    # a dataset may not hold)
    df = pd.concat([df, df.iloc[::7].assign(rssi_dbm=lambda d: d["rssi_dbm"] - 1.0)]).sort_values("t", kind="stable")
    folds = stretch_samples(df, "u", "d.parquet")
    assert list(folds) == [f"u[{k}/{TIME_UNITS}]" for k in range(1, TIME_UNITS + 1)]
    assert sum(len(s) for s in folds.values()) == len(df)
    cut, _ = time_units(df)
    assert cut.groupby("t")["unit"].nunique().max() == 1  # no instant in two stretches
    for (label, samples), unit in zip(folds.items(), cut["unit"].drop_duplicates()):
        rows = samples_of(cut, [unit])
        assert len(samples) == len(rows), label
        np.testing.assert_array_equal(np.sort(samples.joint_gain_db), np.sort(rows.joint_gain_db))
    flight = stretch_samples(df)
    assert list(flight)[-1] == f"test[{TIME_UNITS}/{TIME_UNITS}]"
