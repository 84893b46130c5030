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
its module, and pandas, are imported on first use (``__init__.pyi``, lazy_loader).
"""

from __future__ import annotations

import lazy_loader

# The public names are those of __init__.pyi, each imported on first use.
__getattr__, __dir__, __all__ = lazy_loader.attach_stub(__name__, __file__)
