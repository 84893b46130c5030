# Public names of rplearn.data: read by type checkers and IDEs, and by lazy_loader.attach_stub in
# __init__.py, which imports each name's module on first use. Only `from .module import name as
# name` lines here (tests/test_public_api.py).

from .tables import (
    LinkSamples as LinkSamples,
    MATCHED_COLUMNS as MATCHED_COLUMNS,
    OPTIONAL_SIGNAL_COLUMNS as OPTIONAL_SIGNAL_COLUMNS,
    POSE_COLUMNS as POSE_COLUMNS,
    SENTINEL_RSSI_DBM as SENTINEL_RSSI_DBM,
    SIGNAL_COLUMNS as SIGNAL_COLUMNS,
    link_samples as link_samples,
    normalise_times as normalise_times,
    validate_matched as validate_matched,
    validate_pose_log as validate_pose_log,
    validate_signal_log as validate_signal_log,
)
from .poses import (
    PoseTrack as PoseTrack,
    interpolate_nodes as interpolate_nodes,
    pose_tracks as pose_tracks,
)
from .sync import (
    DROP_REASONS as DROP_REASONS,
    SyncOptions as SyncOptions,
    SyncResult as SyncResult,
    SyncSummary as SyncSummary,
    synchronise as synchronise,
)
from .streaming import (
    row_hashes as row_hashes,
    synchronise_stream as synchronise_stream,
    synchronise_to_parquet as synchronise_to_parquet,
)
from .readings import (
    REPEAT_FRACTION as REPEAT_FRACTION,
    repeated_readings as repeated_readings,
    report_period_s as report_period_s,
    report_rate_hz as report_rate_hz,
)
from .phases import (
    AIRBORNE_MARGIN_M as AIRBORNE_MARGIN_M,
    FlightPhases as FlightPhases,
    calibration_problems as calibration_problems,
    flight_phases as flight_phases,
    max_gap_advice as max_gap_advice,
)
from .units import (
    Stretches as Stretches,
    TEST_UNIT_PREFIX as TEST_UNIT_PREFIX,
    TIME_UNITS as TIME_UNITS,
    UnitChoice as UnitChoice,
    dataset_units as dataset_units,
    evaluation_units as evaluation_units,
    is_stretch_label as is_stretch_label,
    is_test_unit as is_test_unit,
    learning_units as learning_units,
    refuse_streamed_stretches as refuse_streamed_stretches,
    samples_of as samples_of,
    select_units as select_units,
    split_units as split_units,
    stretch_labels as stretch_labels,
    stretched as stretched,
    time_units as time_units,
    trained_units as trained_units,
    whole_flight_note as whole_flight_note,
)
