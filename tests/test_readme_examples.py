"""The README's examples run as written, on files that the README's own commands write: the
command-line block line by line, then the library examples in the same folder. The
field-guide block is run by tests/test_field_guide.py; the pages of docs/ by tests/test_docs.py."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
#: README lines not run here, each with the test that runs it instead.
RUN_ELSEWHERE = {
    "rplearn demo -o rplearn-demo": "`make demo` (the paper preset, minutes); tests/workflows/test_demo.py "
    "runs the same demo on the smoke preset",
}


def _readme() -> str:
    return (ROOT / "README.md").read_text(encoding="utf-8")


def _command_block() -> list[str]:
    """The lines of the README's command-line block (the fenced block after '## Command line')."""
    section = _readme().split("## Command line", 1)[1]
    block = re.search(r"^```\n(.*?)^```", section, re.S | re.M)
    assert block, "README.md: no command block under '## Command line'"
    return [line for line in block.group(1).splitlines() if line.strip()]


def _env() -> dict[str, str]:
    return dict(
        os.environ,
        PATH=os.path.dirname(sys.executable) + os.pathsep + os.environ.get("PATH", ""),
        PYTHONPATH=str(ROOT / "src") + os.pathsep + os.environ.get("PYTHONPATH", ""),
        MPLBACKEND="Agg",
    )


def _run(args: list[str], cwd: Path, what: str) -> str:
    proc = subprocess.run(args, cwd=cwd, env=_env(), capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, f"{what}\n{proc.stdout}\n{proc.stderr}"
    return proc.stdout + proc.stderr


@pytest.mark.slow
def test_the_readme_commands_and_library_examples_run_on_files_its_commands_write(tmp_path):
    lines = _command_block()
    assert len(lines) >= 15 and set(RUN_ELSEWHERE) <= {ln.split("  #")[0].strip() for ln in lines}
    for line in lines:
        command = line.split("  #", 1)[0].strip()
        if command in RUN_ELSEWHERE:
            continue
        assert command.startswith("rplearn "), line
        _run(["bash", "-e", "-c", command], tmp_path, command)
    # every file a command reads was written by an earlier command of the block
    for name in ("data.parquet", "sh10.json", "grid.csv", "msi/A.msi", "swarm/pose_log.parquet"):
        assert (tmp_path / name).is_file(), name
    blocks = re.findall(r"^```python\n(.*?)^```", _readme(), re.S | re.M)
    # one session: the second block uses the first's `learn`, the third the first's sh10.json
    assert len(blocks) >= 3 and 'read_table("data.parquet")' in blocks[0]
    out = _run([sys.executable, "-c", "\n".join(blocks)], tmp_path, "README library examples")
    assert "Scores(model='SH-10'" in out and "'order': " in out and "bottleneck_rssi_dbm" in out, (
        out
    )
