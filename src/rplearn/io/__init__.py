"""Readers of flight and signal logs, each giving canonical pose and signal logs (docs/conventions.md).

=================  =========================================  ==================================
format             reader                                     gives
=================  =========================================  ==================================
CSV, Parquet       :func:`rplearn.io.tables.read_pose_table`,  pose or signal log
                   :func:`rplearn.io.tables.read_signal_table`
ROS 2 / ROS 1 bag  :func:`rplearn.io.rosbag.read_rosbag`       pose and signal logs
PX4 ULog           :func:`rplearn.io.ulog.read_ulog`           pose log
pcap / pcapng      :func:`rplearn.io.pcap.read_pcap`           signal log
MAVLink .tlog,     :func:`rplearn.io.mavlink.read_mavlink`     pose and signal logs
DataFlash .bin
=================  =========================================  ==================================

:func:`read_logs` chooses the reader of every path by its content (magic bytes) and, failing
that, its extension, and concatenates the results; :class:`~rplearn.io.options.ReaderOptions`
carries what the readers need beyond the files. Each format library (rosbags, pyulog,
dpkt, pymavlink, pymap3d) is imported only when a file of its format is read.

The other public names of the subpackage can be imported from here too, their modules being
imported on first use (:mod:`rplearn._lazy`): tables (:func:`~rplearn.io.files.read_table`,
:func:`~rplearn.io.files.write_table`, :func:`~rplearn.io.files.provenance`), per-format
readers, :func:`~rplearn.io.inspect.inspect_logs`, pattern export
(:func:`~rplearn.io.export.export_grid`), MSI antenna files (:func:`~rplearn.io.msi.read_msi`,
:func:`~rplearn.io.msi.write_msi`, :func:`~rplearn.io.msi.export_msi`) and model files
(:func:`~rplearn.io.modelfile.read_model_file`, :func:`~rplearn.io.modelfile.write_model_file`),
and a vehicle-to-station flight as a MAVLink telemetry log (:func:`~rplearn.io.tlog.write_tlog`,
the inverse of the ``.tlog`` reader, for simulated flights, with the defects of real logs:
:class:`~rplearn.io.tlog.TlogDefects`) or a DataFlash log
(:func:`~rplearn.io.dataflash_writer.write_dataflash`).
"""

from __future__ import annotations

from rplearn._lazy import lazy_exports
from rplearn.errors import LogFormatError as LogFormatError  # re-exported

_NAMES: dict[str, str] = {
    "Logs": "_common",
    "ReaderOptions": "options",
    "detect_format": "sniff",
    "read_logs": "read",
    # canonical tables as files, and what made an output
    "check_table_path": "files",
    "check_output_path": "files",
    "provenance": "files",
    "read_dataset": "files",
    "read_table": "files",
    "write_table": "files",
    "write_table_chunks": "files",
    "iter_table": "files",
    "table_rows": "files",
    "iter_parts": "files",
    # datasets in many files (a directory, a glob, a list, a URL)
    "Part": "partitions",
    "dataset_parts": "partitions",
    "is_partitioned": "partitions",
    # per-format readers
    "COLUMN_ALIASES": "tables",
    "canonical_pose": "tables",
    "canonical_signal": "tables",
    "iter_signal_table": "tables",
    "table_columns": "tables",
    "read_pose_table": "tables",
    "read_signal_table": "tables",
    "bag_topics": "rosbag",
    "read_rosbag": "rosbag",
    "read_ulog": "ulog",
    "read_ulogs": "ulog",
    "read_pcap": "pcap",
    "write_radiotap_pcap": "pcap",
    "read_mavlink": "mavlink",
    "sik_rssi_to_dbm": "mavlink",
    "write_tlog": "tlog",
    "TlogDefects": "tlog",
    "write_dataflash": "dataflash_writer",
    "dbm_to_sik_rssi": "tlog",
    "NAN_POLICIES": "options",
    "geodetic_to_enu": "geodetic",
    # looking at logs before learning
    "InspectReport": "inspect",
    "LinkSummary": "inspect",
    "NodeSummary": "inspect",
    "inspect_logs": "inspect",
    # pattern export
    "GRID_COLUMNS": "export",
    "MsiPattern": "msi",
    "PatternLike": "export",
    "export_grid": "export",
    "export_msi": "msi",
    "export_msi_files": "msi",
    "safe_file_name": "export",
    "node_file_names": "export",
    "write_json": "files",
    "msi_pattern": "msi",
    "read_msi": "msi",
    "write_msi": "msi",
    # model files
    "MODEL_SCHEMA": "modelfile",
    "MODEL_SCHEMA_VERSION": "modelfile",
    "read_model_file": "modelfile",
    "write_model_file": "modelfile",
}

__all__ = sorted(["LogFormatError", *_NAMES])
__getattr__, __dir__ = lazy_exports(__name__, _NAMES)
