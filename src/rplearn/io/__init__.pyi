# Public names of rplearn.io: read by type checkers and IDEs, and by lazy_loader.attach_stub in
# __init__.py, which imports each name's module on first use. Only `from .module import name as
# name` lines here (tests/test_public_api.py).

import rplearn.errors

LogFormatError = rplearn.errors.LogFormatError  # re-exported (attach_stub reads only `from .x`)

from ._common import (
    Logs as Logs,
)
from .options import (
    NAN_POLICIES as NAN_POLICIES,
    ReaderOptions as ReaderOptions,
)
from .read import (
    detect_format as detect_format,
    read_logs as read_logs,
)
from .files import (
    check_output_path as check_output_path,
    check_table_path as check_table_path,
    iter_parts as iter_parts,
    iter_table as iter_table,
    provenance as provenance,
    read_dataset as read_dataset,
    read_table as read_table,
    table_rows as table_rows,
    write_json as write_json,
    write_table as write_table,
    write_table_chunks as write_table_chunks,
)
from .partitions import (
    Part as Part,
    dataset_parts as dataset_parts,
    is_partitioned as is_partitioned,
)
from .tables import (
    COLUMN_ALIASES as COLUMN_ALIASES,
    canonical_pose as canonical_pose,
    canonical_signal as canonical_signal,
    iter_signal_table as iter_signal_table,
    read_pose_table as read_pose_table,
    read_signal_table as read_signal_table,
    table_columns as table_columns,
)
from .rosbag import (
    bag_topics as bag_topics,
    read_rosbag as read_rosbag,
)
from .ulog import (
    read_ulog as read_ulog,
    read_ulogs as read_ulogs,
)
from .pcap import (
    read_pcap as read_pcap,
    write_radiotap_pcap as write_radiotap_pcap,
)
from .mavlink import (
    read_mavlink as read_mavlink,
    sik_rssi_to_dbm as sik_rssi_to_dbm,
)
from .tlog import (
    TlogDefects as TlogDefects,
    dbm_to_sik_rssi as dbm_to_sik_rssi,
    write_tlog as write_tlog,
)
from .dataflash_writer import (
    write_dataflash as write_dataflash,
)
from .geodetic import (
    geodetic_to_enu as geodetic_to_enu,
)
from .inspect import (
    InspectReport as InspectReport,
    LinkSummary as LinkSummary,
    NodeSummary as NodeSummary,
    inspect_logs as inspect_logs,
)
from .export import (
    GRID_COLUMNS as GRID_COLUMNS,
    MsiPattern as MsiPattern,
    PatternLike as PatternLike,
    export_grid as export_grid,
    export_msi as export_msi,
    export_msi_files as export_msi_files,
    msi_pattern as msi_pattern,
    node_file_names as node_file_names,
    read_msi as read_msi,
    safe_file_name as safe_file_name,
    write_msi as write_msi,
)
from .modelfile import (
    MODEL_SCHEMA as MODEL_SCHEMA,
    MODEL_SCHEMA_VERSION as MODEL_SCHEMA_VERSION,
    read_model_file as read_model_file,
    write_model_file as write_model_file,
)
