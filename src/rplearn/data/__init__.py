"""Canonical tables and matching: pose and signal logs, matched link datasets, unit selection.

============  ==================================================================================
module        public names
============  ==================================================================================
``tables``    the schemas (:data:`POSE_COLUMNS`, :data:`SIGNAL_COLUMNS`, :data:`MATCHED_COLUMNS`),
              their checks (:func:`validate_pose_log`, :func:`validate_signal_log`,
              :func:`validate_matched`) and :func:`link_samples` -> :class:`LinkSamples`
``poses``     :func:`pose_tracks` -> :class:`PoseTrack`, :func:`interpolate_nodes`
``sync``      :func:`synchronise` (paper Sec. V-B4) with :class:`SyncOptions` ->
              :class:`SyncResult`
``streaming`` the same for logs too big for memory: :func:`synchronise_stream`,
              :func:`synchronise_to_parquet`, :func:`row_hashes`
``readings``  one reading, one row: :func:`repeated_readings`, :func:`report_period_s`,
              :func:`report_rate_hz`
``phases``    flight phases: :func:`flight_phases` -> :class:`FlightPhases` (take-off
              altitudes, airborne), :func:`max_gap_advice`, :func:`calibration_problems`
``units``     :func:`samples_of`, :func:`learning_units`, :func:`evaluation_units`,
              :func:`split_units`, :func:`select_units` -> :class:`UnitChoice`; a flight
              without units cut into named stretches of time (:func:`time_units`,
              :class:`Stretches`, :func:`stretched`, :func:`stretch_samples`)
============  ==================================================================================

Every name of ``__all__`` can be imported from here (``from rplearn.data import samples_of``);
its module, and pandas, are imported on first use (:mod:`rplearn._lazy`).
"""

from __future__ import annotations

from rplearn._lazy import lazy_exports

_NAMES: dict[str, str] = {
    # canonical schemas and their checks
    "MATCHED_COLUMNS": "tables",
    "OPTIONAL_SIGNAL_COLUMNS": "tables",
    "POSE_COLUMNS": "tables",
    "SENTINEL_RSSI_DBM": "tables",
    "SIGNAL_COLUMNS": "tables",
    "LinkSamples": "tables",
    "link_samples": "tables",
    "normalise_times": "tables",
    "validate_matched": "tables",
    "validate_pose_log": "tables",
    "validate_signal_log": "tables",
    # pose tracks
    "PoseTrack": "poses",
    "interpolate_nodes": "poses",
    "pose_tracks": "poses",
    # pose-signal matching
    "DROP_REASONS": "sync",
    "SyncOptions": "sync",
    "SyncResult": "sync",
    "SyncSummary": "sync",
    "synchronise": "sync",
    "row_hashes": "streaming",
    "synchronise_stream": "streaming",
    "synchronise_to_parquet": "streaming",
    # one reading, one row; flight phases
    "REPEAT_FRACTION": "readings",
    "repeated_readings": "readings",
    "report_period_s": "readings",
    "report_rate_hz": "readings",
    "AIRBORNE_MARGIN_M": "phases",
    "FlightPhases": "phases",
    "calibration_problems": "phases",
    "flight_phases": "phases",
    "max_gap_advice": "phases",
    # learning and testing units
    "TEST_UNIT_PREFIX": "units",
    "UnitChoice": "units",
    "dataset_units": "units",
    "evaluation_units": "units",
    "is_test_unit": "units",
    "learning_units": "units",
    "samples_of": "units",
    "select_units": "units",
    "split_units": "units",
    "time_units": "units",
    "Stretches": "units",
    "is_stretch_label": "units",
    "stretch_labels": "units",
    "stretched": "units",
    "stretch_samples": "units",
    "refuse_streamed_stretches": "units",
    "whole_flight_note": "units",
    "TIME_UNITS": "units",
    "trained_units": "units",
}

__all__ = sorted(_NAMES)
__getattr__, __dir__ = lazy_exports(__name__, _NAMES)
