"""The README's library examples run as written, on the dataset the README's own commands write
(`rplearn simulate --preset paper` and `rplearn sync`). The field-guide block is run by
tests/test_field_guide.py; the pages of docs/ by tests/test_docs.py."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _readme() -> str:
    return (ROOT / "README.md").read_text(encoding="utf-8")


def _command(prefix: str) -> str:
    """The README's command line starting with ``prefix`` (its comment removed)."""
    for line in _readme().splitlines():
        if line.startswith(prefix):
            return line.split("  #", 1)[0].strip()
    raise AssertionError(f"README.md has no command starting with {prefix!r}")


def test_the_readme_library_examples_run_on_the_data_its_commands_write(tmp_path):
    blocks = re.findall(r"^```python\n(.*?)^```", _readme(), re.S | re.M)
    # the first two blocks are one session (the second uses the first's `learn`) on data.parquet
    session = [b for b in blocks if "swarm_plan.csv" not in b]
    assert len(session) >= 2 and 'read_table("data.parquet")' in session[0]
    env = dict(
        os.environ,
        PATH=os.path.dirname(sys.executable) + os.pathsep + os.environ.get("PATH", ""),
        PYTHONPATH=str(ROOT / "src") + os.pathsep + os.environ.get("PYTHONPATH", ""),
        MPLBACKEND="Agg",
    )
    for line in (
        _command("rplearn simulate --preset paper"),
        _command("rplearn sync --poses flight/"),
    ):
        proc = subprocess.run(
            ["bash", "-c", line], cwd=tmp_path, env=env, capture_output=True, text=True, timeout=300
        )
        assert proc.returncode == 0, f"{line}\n{proc.stdout}\n{proc.stderr}"
    proc = subprocess.run(
        [sys.executable, "-c", "\n".join(session)],
        cwd=tmp_path,
        env=env,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert "Scores(model='SH-10'" in proc.stdout and "'order': " in proc.stdout, proc.stdout
    assert (tmp_path / "sh10.json").stat().st_size > 1000
