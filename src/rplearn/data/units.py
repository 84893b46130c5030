"""Unit selection: which trajectory units a model learns from and which it is tested on.

The one place that decides it. A matched dataset may carry a ``unit`` column, the label of the
trajectory unit (paper Sec. IV-A) every sample was flown in. Units labelled ``test...`` (any
case) are held out for testing by default; every other unit is for learning. Functions return
a :class:`UnitChoice`: the units, plus the notes and warnings a user should read about the
choice (which units were left out, when a score would be a training score). A dataset without
units (one flight, e.g. a telemetry log) is cut into named stretches of time
(:class:`Stretches`, :func:`time_units`), which every command takes as units and the automatic
selection uses as its folds.
"""

from __future__ import annotations

import os
import re
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from rplearn._argtypes import check_types
from rplearn.data.tables import LinkSamples, link_samples
from rplearn.errors import InputError

#: Prefix (any case) of the unit labels held out for testing by default.
TEST_UNIT_PREFIX = "test"


@check_types
@dataclass(frozen=True)
class UnitChoice:
    """Units chosen for learning or testing, and what the user should know about the choice.

    Attributes
    ----------
    units : list of str or None
        The units; None means every row (the dataset has no ``unit`` column, or all are used).
    defaulted : bool
        True when the units were chosen by the default rule rather than given.
    notes : list of str
        Plain remarks (which units were used and which left out).
    warnings : list of str
        Things that may make a result misleading (training scores reported as test scores).
    """

    units: list[str] | None
    defaulted: bool = False
    notes: list[str] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)


@check_types
def is_test_unit(unit: object) -> bool:
    """Whether a unit label is held out for testing by default (``test...``, any case)."""
    return str(unit).lower().startswith(TEST_UNIT_PREFIX)


@check_types
def dataset_units(df: pd.DataFrame) -> list[str]:
    """Sorted unit labels of a dataset ([] without a ``unit`` column)."""
    return sorted(df["unit"].astype(str).unique()) if "unit" in df.columns else []


@check_types
def learning_units(df: pd.DataFrame, units: Sequence[str] | None = None, source: str = "dataset") -> UnitChoice:
    """Units to learn from: ``units`` as given, else every unit not labelled ``test...``.

    Without a ``unit`` column, or when every unit is a test unit, every row is used (and a
    note says so).
    """
    if units:
        return UnitChoice([str(u) for u in units])
    available = dataset_units(df)
    if not available:
        return UnitChoice(None, defaulted=True)
    learn = [u for u in available if not is_test_unit(u)]
    if not learn:
        return UnitChoice(None, True, [f"{source}: every unit is labelled {TEST_UNIT_PREFIX}...; learning from all of them"])
    left_out = [u for u in available if u not in learn]
    notes = [f"learning from units {unit_list(learn)}; left out {unit_list(left_out)}"] if left_out else []
    return UnitChoice(learn, True, notes)


#: Unit names a note lists in full; longer lists (a fleet logs hundreds of flights, a note per
#: command) show their first and last few and how many there are.
NOTE_UNITS = 8


def unit_list(units: Sequence[str], limit: int = NOTE_UNITS) -> str:
    """Unit names for a note: all of them, or the first and last few and their count."""
    units = [str(u) for u in units]
    if len(units) <= limit:
        return ", ".join(units)
    return f"{', '.join(units[: limit - 2])}, ..., {', '.join(units[-2:])} ({len(units):,} units)"


@check_types
def trained_units(provenances: Sequence[dict]) -> list[str]:
    """Units the models with these provenance records learned from (sorted, distinct)."""
    return sorted({str(u) for p in provenances for u in (p.get("parameters", {}).get("units") or [])})


@check_types
def evaluation_units(
    df: pd.DataFrame,
    units: Sequence[str] | None,
    provenances: Sequence[dict],
    source: str = "dataset",
) -> UnitChoice:
    """Units to score models on: as given, else those no model learned from.

    Parameters
    ----------
    df : DataFrame
        Matched dataset.
    units : sequence of str or None
        Units the user chose; None applies the default rule.
    provenances : sequence of dict
        The models' provenance records (their ``parameters.units`` and ``parameters.dataset``).
    source : str
        Dataset file name, for messages and to recognise a model's own training file.

    Returns
    -------
    UnitChoice
        With a warning when a score would be a training score.
    """
    trained = trained_units(provenances)
    available = dataset_units(df)
    warnings: list[str] = []
    if not available:
        sources = {os.path.basename(str(p.get("parameters", {}).get("dataset"))) for p in provenances}
        if os.path.basename(source) in sources:
            warnings.append(
                f"{source} has no unit column and a model learned from a file of this name: "
                "these are probably training scores"
            )
    if units is None and trained and available:
        unseen = [u for u in available if u not in trained]
        if unseen:
            return UnitChoice(unseen, True, [f"scoring on units {unit_list(unseen)}, which no model learned from"], warnings)
    chosen = [str(u) for u in units] if units is not None else (available or None)
    overlap = sorted(set(chosen or available) & set(trained))
    notes: list[str] = []
    if overlap:
        warnings.append(f"scoring on unit(s) {unit_list(overlap)} that a model learned from: these are training scores")
    elif units is None and available:
        notes.append(f"scoring on all units ({unit_list(available)})")
    return UnitChoice(chosen, units is None, notes, warnings)


#: A dataset without units (one flight, e.g. a telemetry log) is cut into this many contiguous
#: stretches of time for a report or a sweep (the last one the test), which ``fit --units`` and
#: ``evaluate --units`` accept by name; a single learning unit is cross-validated over as many.
TIME_UNITS = 5

#: A stretch label: ``flight[k/n]``, ``test[n/n]`` or ``UNIT[k/n]`` (a stretch of one unit).
_STRETCH = re.compile(r"^(?P<unit>.+)\[(?P<k>\d+)/(?P<n>\d+)\]$")


@check_types
def stretch_labels(blocks: int = TIME_UNITS, unit: str | None = None) -> list[str]:
    """Names of the ``blocks`` stretches of time of a flight, in time order.

    Without ``unit`` (a dataset without units): ``flight[1/n]`` .. ``flight[n-1/n]`` and
    ``test[n/n]``, the last held out by the unit rule (:func:`is_test_unit`); the stretches of
    one unit ``u`` (the folds of its cross-validation) are ``u[1/n]`` .. ``u[n/n]``.
    """
    if unit is None:
        return [f"flight[{j}/{blocks}]" for j in range(1, blocks)] + [f"test[{blocks}/{blocks}]"]
    return [f"{unit}[{j}/{blocks}]" for j in range(1, blocks + 1)]


@check_types
def is_stretch_label(label: object) -> bool:
    """Whether a unit label names a stretch of time of a flight without units (``flight[2/5]``)."""
    m = _STRETCH.match(str(label))
    return m is not None and m.group("unit") in ("flight", "test") and 1 <= int(m.group("k")) <= int(m.group("n"))


@check_types
@dataclass(frozen=True)
class Stretches:
    """Contiguous stretches of time of one flight: where they start and what they are called.

    The one cut of a flight into stretches, used alike by ``fit`` (learning units and the
    folds of ``--order auto``), ``evaluate``, ``sweep`` and ``report``, in memory and streamed.
    Rows of one instant (both directions of a telemetry report) share a stretch: a stretch
    starts at an instant, never inside one.

    Attributes
    ----------
    starts_s : tuple of float
        Start time [s] of every stretch but the first (increasing; a row at a start time
        belongs to the later stretch).
    labels : tuple of str
        One name per stretch (:func:`stretch_labels`), in time order.
    """

    starts_s: tuple[float, ...]
    labels: tuple[str, ...]

    @classmethod
    def of_times(cls, t: np.ndarray, blocks: int = TIME_UNITS, unit: str | None = None) -> Stretches:
        """Stretches of about equal sample counts of the times ``t`` [s] (any order).

        Each start is the time of the sample at an equal-count quantile, so that every row of
        the instant it falls in goes to the later stretch; with many rows at one instant a
        stretch may hold none (:meth:`index` never yields it).
        """
        t = np.sort(np.asarray(t, np.float64))
        if t.size == 0:
            return cls((), tuple(stretch_labels(1, unit)[:1]))
        return cls(tuple(float(x) for x in t[[t.size * j // blocks for j in range(1, blocks)]]),
                   tuple(stretch_labels(blocks, unit)))

    def index(self, t: np.ndarray) -> np.ndarray:
        """The stretch (0-based) of every time ``t`` [s]."""
        return np.searchsorted(np.asarray(self.starts_s, np.float64), np.asarray(t, np.float64), side="right")

    def label(self, t: np.ndarray) -> np.ndarray:
        """The stretch name of every time ``t`` [s]."""
        return np.asarray(self.labels, dtype=object)[self.index(t)]


@check_types
def stretch_samples(
    df: pd.DataFrame, unit: str | None = None, source: str = "dataset", nodes: Sequence[str] | None = None
) -> dict[str, LinkSamples]:
    """The rows of one flight cut into its :data:`TIME_UNITS` stretches of time
    (:class:`Stretches`, the folds of a single unit's cross-validation), as learning-ready
    samples by stretch name; a stretch that holds no row is left out.

    Parameters
    ----------
    df : DataFrame
        Matched rows of one flight (one unit, or a dataset without units), with ``t`` [s].
    unit : str, optional
        The unit's label, which names the stretches (``u[1/5]``); None: ``flight[1/5]``.
    source : str
        Dataset name, for messages.
    nodes : sequence of str, optional
        Node ids in model order (:func:`rplearn.data.tables.link_samples`).
    """
    t = pd.to_numeric(df["t"], errors="coerce").to_numpy(np.float64)
    stretches = Stretches.of_times(t, TIME_UNITS, unit)
    k = stretches.index(t)
    return {label: samples_of(df[k == j], None, source, nodes=nodes)
            for j, label in enumerate(stretches.labels) if np.any(k == j)}


@check_types
def time_units(df: pd.DataFrame, blocks: int = TIME_UNITS, source: str = "dataset") -> tuple[pd.DataFrame, str | None]:
    """A dataset without a ``unit`` column, labelled by contiguous stretches of time.

    Rows are cut by time into ``blocks`` stretches of about equal sample counts
    (:class:`Stretches`: rows of one instant never split), labelled ``flight[k/blocks]`` and
    the last ``test[blocks/blocks]``: learning on the first ones and testing on the last keeps
    neighbouring (correlated) packets on one side. A dataset with a ``unit`` column is
    returned as it is.

    Returns
    -------
    df : DataFrame
        The dataset with a ``unit`` column (the input when it had one).
    note : str or None
        What was done, for the user; None when nothing was.

    Raises
    ------
    InputError
        When the dataset has fewer rows than ``blocks`` or times that are not finite.
    """
    if "unit" in df.columns:
        return df, None
    if "t" not in df.columns:
        raise InputError(f"{source}: neither a 'unit' column nor a 't' column to split learning from testing samples")
    t = pd.to_numeric(df["t"], errors="coerce").to_numpy(dtype=float)
    if len(t) < blocks or not (t == t).all():
        raise InputError(f"{source}: cannot cut {len(t)} sample(s) with finite times into {blocks} stretches of time",
                         param="t")
    stretches = Stretches.of_times(t, blocks)
    k = stretches.index(t)  # 0 .. blocks-1
    if len(np.unique(k)) < blocks:
        raise InputError(f"{source}: its {len(t)} sample(s) have too few distinct times to cut into {blocks} "
                         "stretches of time", param="t")
    out = df.assign(unit=stretches.label(t))
    labels = stretches.labels
    note = (f"{source} has no 'unit' column: its flight is cut into {blocks} stretches of time with about equal "
            f"sample counts, {labels[0]}..{labels[-2]} and {labels[-1]} (from {t[k == blocks - 1].min() - t.min():.1f} s after "
            f"the log start, t = {t.min():.3f} s); "
            "these names choose stretches (fit --units, evaluate --units, sweep --learn-units/--test-units, "
            "report --test-units)")
    return out, note


@check_types
def stretched(df: pd.DataFrame, units: Sequence[str] | None, source: str = "dataset") -> tuple[pd.DataFrame, str | None]:
    """A dataset ready for choosing ``units``: a dataset without units, when units are chosen,
    labelled by its stretches of time (:func:`time_units`); otherwise as it is."""
    if "unit" in df.columns or not units:
        return df, None
    return time_units(df, source=source)


@check_types
def whole_flight_note(source: str = "dataset") -> str:
    """The note of a fit on the whole of a flight without units: how to name its stretches."""
    names = stretch_labels()
    return (f"{source} has no 'unit' column: learning from its whole flight; its {len(names)} stretches of time "
            f"{names[0]}..{names[-1]} can be chosen (e.g. --units {','.join(names[:-1])} holds out {names[-1]} "
            f"for evaluate --units {names[-1]})")


@check_types
def refuse_streamed_stretches(index: pd.DataFrame, units: Sequence[str] | None, source: str = "dataset") -> None:
    """Refuse units chosen in a dataset without units that is read part by part (its stretches
    of time are cut only when it is read whole).

    Raises
    ------
    InputError
        When ``units`` are given and ``index`` (the dataset's rows per unit and link) has no
        ``unit`` column.
    """
    if units and "unit" not in index.columns:
        raise InputError(f"{source}: has no 'unit' column and is read part by part: stretches of time "
                         f"({', '.join(stretch_labels())}) are chosen in a dataset read whole; label its rows "
                         "with a 'unit' column to choose units", param="units")


@check_types
def split_units(
    df: pd.DataFrame,
    learn_units: Sequence[str] | None = None,
    test_units: Sequence[str] | None = None,
    source: str = "dataset",
) -> tuple[list[str], list[str]]:
    """Disjoint learning and testing units for a sweep or a report.

    Testing units default to those labelled ``test...``, learning units to all others.

    Raises
    ------
    InputError
        Without a ``unit`` column, when either side is empty, or when they share a unit
        (a test must use unseen data).
    """
    if "unit" not in df.columns:
        raise InputError(f"{source}: needs a 'unit' column to split learning from testing samples")
    available = dataset_units(df)
    for param, given in (("learn_units", learn_units), ("test_units", test_units)):  # before any learning
        unknown = [str(u) for u in given or () if str(u) not in available]
        if unknown:
            raise InputError(f"{source}: unknown unit(s) {unit_list(unknown)}; the dataset has {unit_list(available)}",
                             param=param)
    test = [str(u) for u in test_units] if test_units else [u for u in available if is_test_unit(u)]
    learn = [str(u) for u in learn_units] if learn_units else [u for u in available if u not in test]
    if not test or not learn:
        raise InputError(f"{source}: cannot split units {unit_list(available)} into learning and testing", param="test_units")
    shared = sorted(set(test) & set(learn))
    if shared:
        raise InputError(f"learning and testing units share {', '.join(shared)}; a test must use unseen data", param="test_units")
    return learn, test


@check_types
def select_units(df: pd.DataFrame, units: Sequence[str] | None, source: str = "dataset") -> pd.DataFrame:
    """Rows whose ``unit`` label is among ``units`` (all rows when ``units`` is None)."""
    if not units:
        return df
    if "unit" not in df.columns:
        raise InputError(f"{source}: choosing units needs a 'unit' column, which this dataset lacks (a flight "
                         f"without units is cut into stretches of time named {', '.join(stretch_labels())})", param="units")
    wanted = [str(u) for u in units]
    known = dataset_units(df)
    unknown = [u for u in wanted if u not in known]
    if unknown:
        raise InputError(f"{source}: unknown unit(s) {unit_list(unknown)}; the dataset has {unit_list(known)}", param="units")
    return df[df["unit"].astype(str).isin(wanted)]


@check_types
def samples_of(
    df: pd.DataFrame, units: Sequence[str] | None = None, source: str = "dataset", nodes: Sequence[str] | None = None
) -> LinkSamples:
    """Learning-ready samples of the chosen units of a matched dataset."""
    part = select_units(df, units, source)
    if len(part) == 0:
        raise InputError(f"{source}: no samples selected", param="units")
    return link_samples(part, source, nodes=nodes)
