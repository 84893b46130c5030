"""The core and rplearn.io import no format library until a file of its format is read."""

from __future__ import annotations

import json
import subprocess
import sys

FORMAT_LIBS = ("rosbags", "pyulog", "dpkt", "pymap3d", "pyarrow.parquet")


def test_format_libraries_are_imported_lazily():
    code = (
        "import sys, json\n"
        "import rplearn.io, rplearn.io.tables, rplearn.io.pcap, rplearn.io.rosbag, rplearn.io.ulog\n"
        "import rplearn.data.sync, rplearn.io.inspect\n"
        f"print(json.dumps([m for m in {FORMAT_LIBS!r} if m in sys.modules]))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], check=True, capture_output=True, text=True)
    assert json.loads(out.stdout) == []
