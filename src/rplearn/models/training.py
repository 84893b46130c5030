"""What a fit says about itself: the typed training summary every model carries.

:class:`TrainingSummary` names every entry a fit, a reference expansion or a baseline writes
(the solver's report, the environment term and link offsets, the automatic choice, the
spreads, the coverage grids, the plausibility findings, the decoupling certificate). It is
frozen: a later step that adds to it (the LTD, the coverage, the budget findings) makes a new
summary with :meth:`TrainingSummary.replace` and gives it to the model.

Model files store it as the JSON object ``training`` (:meth:`TrainingSummary.to_dict`);
:meth:`TrainingSummary.from_dict` reads that of any model file written so far, keeping
entries it does not know in ``extra`` (written back unchanged). For code written against the
former plain dictionary, the summary also reads as a read-only mapping
(``model.training["rank"]``, ``.get``, ``in``): the entries :meth:`to_dict` would write.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field, fields
from typing import Any

from rplearn._argtypes import check_types
from rplearn.errors import InputError, ModelFileError

_TUPLES = ("gauges", "warnings", "fixed_nodes")


@check_types
@dataclass(frozen=True, eq=False)
class TrainingSummary(Mapping[str, Any]):
    """The training summary of a model; every entry is optional (None: not written).

    Attributes
    ----------
    n_samples : int
        Learning samples (reference points of a reference expansion).
    n_columns, rank, null_dim, expected_null_dim : int
        The joint design: columns, numerical rank, free directions, and those the link
        graph predicts (:class:`rplearn.core.lsq.solution.FitReport`).
    condition_number : float
    ridge : float
    rmse_db : float
        Training RMSE [dB] (a reference: the expansion's residual).
    gauges : tuple of dict
        The gauge notes (``nodes``, ``side_a``, ``side_b``, ``rule``, ``text``).
    warnings : tuple of str
        Everything a user should read about the fit.
    frequency_hz : float
        Carrier of the learning samples.
    ltd_s : float
        Learning wall time (the paper's LTD).
    coverage_deg : dict of node to list of float
        Each node's coverage grid: the angle to the nearest learning direction [deg].
    smoothing, penalty_power : float
        The smoothness penalty's relative weight and power.
    selection : dict
        The automatic choice of order and smoothing and its validation curve.
    variance_inflation, noise_std_db, flight_level_std_db, new_flight_level_std_db : float
        The automatic choice's spreads (:func:`rplearn.models.auto.fit_from_statistics`).
    misfit_std_db : float
        Each node's spread of the error the model cannot represent [dB], added everywhere
        (:func:`rplearn.models.auto_spread.held_out_misfit_var`, halved between the two ends).
    planning_penalty_weight : float
        An automatic fit's smoothness penalty as an absolute weight (its smoothing times the
        penalty's scale at the chosen order, in the units of ``X^T X``): the prior the next
        flight's plan takes (``rplearn trajectory --optimize --from-model``).
    drift_std_db : float
        The block-offset spread of an error drifting over seconds, per 5-s block [dB]
        (:func:`rplearn.models.auto_spread.drift_std_db`): written by an automatic fit without
        priors of samples with times, in memory, streamed or on Dask alike.
    fixed_nodes : tuple of str
        The nodes that held still in every learning row (a ground station, a parked drone:
        :func:`rplearn.data.flight_layout.fixed_nodes`), written by every fit, in memory, streamed,
        on Dask or live alike (the last three from a bounded
        :class:`~rplearn.data.flight_layout.LayoutSketch`): the next flight's plan is made for the same layout.
    packet_rate_hz : float
        The rate a link direction reported at in the learning rows [Hz]
        (:func:`rplearn.data.flight_layout.packet_rate_hz`; written as ``fixed_nodes``): the next
        flight's plan counts the radio's packets at it.
    prior_std_db : dict of node to float
        Each node's predictive spread where the flight never looked [dB].
    prior_std_source : str
    prior_level : str
    prior : dict of node to str
        The prior models' names.
    path_loss : dict
        The environment term (``kind`` ... and a learned ``exponent``).
    directions : list of dict
        Samples of each directed link (``tx``, ``rx``, ``samples``).
    link_offsets_db : list of dict
        Learned electronics offsets (``tx``, ``rx``, ``offset_db``, ``se_db``).
    robust : dict
        The Huber fit's numbers.
    reference : dict of node to dict
        A reference expansion's sources and mounts.
    budget : list of dict
        The plausibility findings (:mod:`rplearn.analysis.budget`).
    decoupling : dict
        The decoupling certificate (:mod:`rplearn.analysis.decoupling`) and its ``summary`` text.
    extra : dict
        Entries of a model file this version does not know, written back unchanged.
    """

    n_samples: int | None = None
    n_columns: int | None = None
    rank: int | None = None
    null_dim: int | None = None
    expected_null_dim: int | None = None
    condition_number: float | None = None
    ridge: float | None = None
    rmse_db: float | None = None
    gauges: tuple[Mapping[str, Any], ...] | None = None
    warnings: tuple[str, ...] | None = None
    frequency_hz: float | None = None
    ltd_s: float | None = None
    coverage_deg: Mapping[str, Any] | None = None
    smoothing: float | None = None
    penalty_power: float | None = None
    selection: Mapping[str, Any] | None = None
    variance_inflation: float | None = None
    noise_std_db: float | None = None
    flight_level_std_db: float | None = None
    new_flight_level_std_db: float | None = None
    misfit_std_db: float | None = None
    planning_penalty_weight: float | None = None
    drift_std_db: float | None = None
    fixed_nodes: tuple[str, ...] | None = None
    packet_rate_hz: float | None = None
    prior_std_db: Mapping[str, float] | None = None
    prior_std_source: str | None = None
    prior_level: str | None = None
    prior: Mapping[str, str] | None = None
    path_loss: Mapping[str, Any] | None = None
    directions: list[Mapping[str, Any]] | None = None
    link_offsets_db: list[Mapping[str, Any]] | None = None
    robust: Mapping[str, Any] | None = None
    reference: Mapping[str, Any] | None = None
    budget: list[Mapping[str, Any]] | None = None
    decoupling: Mapping[str, Any] | None = None
    extra: Mapping[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        for name in _TUPLES:
            value = getattr(self, name)
            if value is not None and not isinstance(value, tuple):
                object.__setattr__(self, name, tuple(value))

    @classmethod
    def from_dict(cls, data: Mapping[str, Any] | TrainingSummary | None) -> TrainingSummary:
        """The summary of a model file's ``training`` object (any version; unknown entries kept
        in ``extra``), or of a summary itself.

        Raises
        ------
        InputError
            (``param="training"``) when ``data`` is not a mapping.
        """
        if isinstance(data, TrainingSummary):
            return data
        if data is None:
            return cls()
        if not isinstance(data, Mapping):
            raise InputError(f"training: expected an object of named entries, got {type(data).__name__}",
                             param="training")
        known = {f.name for f in fields(cls)} - {"extra"}
        values = {str(k): v for k, v in data.items()}
        return cls(**{k: v for k, v in values.items() if k in known},
                   extra={k: v for k, v in values.items() if k not in known})

    def to_dict(self) -> dict[str, Any]:
        """The JSON object of a model file: the entries written (not None), then ``extra``."""
        out: dict[str, Any] = {}
        for f in fields(self):
            if f.name == "extra":
                continue
            value = getattr(self, f.name)
            if value is not None:
                out[f.name] = list(value) if f.name in _TUPLES else value
        out.update(self.extra)
        return out

    def replace(self, **changes: Any) -> TrainingSummary:
        """A copy with ``changes`` (entry names as the attributes; an unknown name goes to ``extra``)."""
        known = {f.name for f in fields(self)}
        extra = {k: v for k, v in changes.items() if k not in known}
        if extra:
            changes = {k: v for k, v in changes.items() if k in known}
            changes["extra"] = {**self.extra, **extra}
        return dataclasses.replace(self, **changes)

    # -- read-only mapping of the entries written (code written against the former dict) -------
    def __getitem__(self, key: str) -> Any:
        return self.to_dict()[key]

    def __iter__(self) -> Iterator[str]:
        return iter(self.to_dict())

    def __len__(self) -> int:
        return len(self.to_dict())

    def __eq__(self, other: object) -> bool:
        if isinstance(other, Mapping):
            return self.to_dict() == dict(other)
        return NotImplemented

    __hash__ = None  # type: ignore[assignment]  # holds dictionaries


#: Entries that predictions read as spreads [dB] (or a factor): when written, a finite number >= 0.
_SPREADS = ("rmse_db", "noise_std_db", "flight_level_std_db", "new_flight_level_std_db", "misfit_std_db",
            "variance_inflation", "drift_std_db", "planning_penalty_weight", "packet_rate_hz")


def check_training_entries(training: Any, source: str) -> None:
    """Refuse entries of a model file's ``training`` object that predictions use and that no fit
    writes: a spread that is not a finite number >= 0, a coverage grid that is not
    :data:`~rplearn.core.coverage.COVERAGE_GRID_POINTS` angles in [0, 180] deg (a grid of
    another length would be read as another grid's points, a null as no coverage).

    Raises
    ------
    ModelFileError
        One line naming ``source`` (the file) and the entry.
    """
    import math

    from rplearn.core.coverage import COVERAGE_GRID_POINTS

    if not isinstance(training, Mapping):
        return  # TrainingSummary.from_dict names it
    for name in _SPREADS:
        v = training.get(name)
        if v is not None and (isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or v < 0):
            raise ModelFileError(f"{source}: training.{name}: expected a finite number >= 0, got {v!r}")
    still = training.get("fixed_nodes")
    if still is not None and (not isinstance(still, list) or not all(isinstance(n, str) for n in still)):
        raise ModelFileError(f"{source}: training.fixed_nodes: expected a list of node ids, got {still!r}"[:300])
    grids = training.get("coverage_deg")
    if grids is not None and not isinstance(grids, Mapping):
        raise ModelFileError(f"{source}: training.coverage_deg: expected an object of node grids, got {type(grids).__name__}")
    for node, grid in (grids or {}).items():
        if not isinstance(grid, list) or len(grid) != COVERAGE_GRID_POINTS:
            n = f"{len(grid)} entries" if isinstance(grid, list) else type(grid).__name__
            raise ModelFileError(f"{source}: training.coverage_deg.{node}: expected {COVERAGE_GRID_POINTS} angles, got {n}")
        bad = next((i for i, a in enumerate(grid)
                    if isinstance(a, bool) or not isinstance(a, (int, float)) or not 0.0 <= a <= 180.0), None)
        if bad is not None:
            raise ModelFileError(f"{source}: training.coverage_deg.{node}: entry {bad} is {grid[bad]!r}, "
                                 "expected an angle in [0, 180] deg")


def training_and_provenance(payload: Mapping[str, Any], source: str) -> tuple[TrainingSummary, dict[str, Any]]:
    """A model file payload's ``training`` summary (its entries checked,
    :func:`check_training_entries`) and ``provenance`` object, each optional.

    Raises
    ------
    ModelFileError
        One line naming ``source`` (the file) and the field.
    """
    check_training_entries(payload.get("training"), source)
    provenance = payload.get("provenance", {})
    if not isinstance(provenance, Mapping):
        raise ModelFileError(f"{source}: field 'provenance' must be an object, got {type(provenance).__name__}")
    try:
        training = TrainingSummary.from_dict(payload.get("training", {}))
    except InputError as exc:
        raise ModelFileError(f"{source}: {exc}") from None
    return training, dict(provenance)


__all__ = ["TrainingSummary", "check_training_entries", "training_and_provenance"]
