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
imported on first use (``__init__.pyi``, lazy_loader): tables (:func:`~rplearn.io.files.read_table`,
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

import lazy_loader

from rplearn.errors import LogFormatError as LogFormatError  # re-exported

# The public names are those of __init__.pyi, each imported on first use.
__getattr__, _dir, _all = lazy_loader.attach_stub(__name__, __file__)
__all__ = sorted([*_all, "LogFormatError"])


def __dir__() -> list[str]:
    return list(__all__)
