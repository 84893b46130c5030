# Public names of this package: read by type checkers and IDEs, and by lazy_loader.attach_stub
# in __init__.py, which imports each name's module on first use. Only `from .module import name
# as name` lines here (tests/test_public_api.py).

import rplearn.errors

from ._common import Logs as Logs
from .dataflash_writer import write_dataflash as write_dataflash
from .export import GRID_COLUMNS as GRID_COLUMNS
from .export import PatternLike as PatternLike
from .export import export_grid as export_grid
from .export import node_file_names as node_file_names
from .export import safe_file_name as safe_file_name
from .files import check_output_path as check_output_path
from .files import check_table_path as check_table_path
from .files import iter_parts as iter_parts
from .files import iter_table as iter_table
from .files import provenance as provenance
from .files import read_dataset as read_dataset
from .files import read_table as read_table
from .files import source_date_epoch as source_date_epoch
from .files import table_rows as table_rows
from .files import write_json as write_json
from .files import write_table as write_table
from .files import write_table_chunks as write_table_chunks
from .geodetic import geodetic_to_enu as geodetic_to_enu
from .inspect import InspectReport as InspectReport
from .inspect import LinkSummary as LinkSummary
from .inspect import NodeSummary as NodeSummary
from .inspect import inspect_logs as inspect_logs
from .live_sources import CsvTail as CsvTail
from .live_sources import MavlinkSource as MavlinkSource
from .live_sources import Poll as Poll
from .live_sources import replay_tlog as replay_tlog
from .mavlink import MavlinkOptions as MavlinkOptions
from .mavlink import read_mavlink as read_mavlink
from .mavlink import sik_rssi_to_dbm as sik_rssi_to_dbm
from .modelfile import MODEL_SCHEMA as MODEL_SCHEMA
from .modelfile import MODEL_SCHEMA_VERSION as MODEL_SCHEMA_VERSION
from .modelfile import read_model_file as read_model_file
from .modelfile import write_model_file as write_model_file
from .msi import MsiPattern as MsiPattern
from .msi import export_msi as export_msi
from .msi import export_msi_files as export_msi_files
from .msi import msi_pattern as msi_pattern
from .msi import read_msi as read_msi
from .msi import write_msi as write_msi
from .options import NAN_POLICIES as NAN_POLICIES
from .options import ReaderOptions as ReaderOptions
from .partitions import Part as Part
from .partitions import dataset_parts as dataset_parts
from .partitions import file_identity as file_identity
from .partitions import is_partitioned as is_partitioned
from .pcap import read_pcap as read_pcap
from .pcap import write_radiotap_pcap as write_radiotap_pcap
from .read import read_logs as read_logs
from .resolve import check_outputs as check_outputs
from .resolve import distinct_inputs as distinct_inputs
from .resolve import input_files as input_files
from .rosbag import RosbagOptions as RosbagOptions
from .rosbag import bag_topics as bag_topics
from .rosbag import read_rosbag as read_rosbag
from .sniff import detect_format as detect_format
from .tables import COLUMN_ALIASES as COLUMN_ALIASES
from .tables import canonical_pose as canonical_pose
from .tables import canonical_signal as canonical_signal
from .tables import iter_signal_table as iter_signal_table
from .tables import read_pose_table as read_pose_table
from .tables import read_signal_table as read_signal_table
from .tables import table_columns as table_columns
from .tlog import TlogDefects as TlogDefects
from .tlog import dbm_to_sik_rssi as dbm_to_sik_rssi
from .tlog import write_tlog as write_tlog
from .tlog_tail import TlogTail as TlogTail
from .ulog import read_ulog as read_ulog
from .ulog import read_ulogs as read_ulogs

LogFormatError = rplearn.errors.LogFormatError  # re-exported (attach_stub reads only `from .x`)
