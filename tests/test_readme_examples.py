"""The README's examples run as written, on files that the README's own commands write: the
command-line block line by line, then the library examples in the same folder. The
field-guide block is run by tests/test_field_guide.py; the pages of docs/ by tests/test_docs.py."""

from __future__ import annotations

import importlib.util
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


#: What makes a line more than one plain command: it runs in bash.
_SHELL = re.compile(r"[$`|;&<>*?(){}\[\]~!\\]")


def _run_in_process(command: str, cwd: Path) -> None:
    """``rplearn ARGS`` in this process (typer's runner, the arguments split as a POSIX shell
    splits them), in ``cwd``: what a line does, without the second of interpreter start-up and
    imports each process would pay again."""
    import contextlib
    import shlex

    from typer.testing import CliRunner

    from rplearn.cli import app

    args = shlex.split(command)
    assert args[0] == "rplearn", command
    with contextlib.chdir(cwd):
        res = CliRunner().invoke(app, args[1:], env={"COLUMNS": "400", "MPLBACKEND": "Agg"})
    assert res.exit_code == 0, f"{command}\n{res.output}\n{res.exception!r}"


@pytest.fixture(scope="module")
def readme_folder(tmp_path_factory) -> Path:
    """A folder in which the README's command block ran, line by line, as written: the first
    line as a user's shell runs it (the ``rplearn`` script on the PATH), the others, plain
    commands all, in this process (a line with anything a shell would interpret runs in bash)."""
    folder = tmp_path_factory.mktemp("readme")
    lines = _command_block()
    assert len(lines) >= 15 and set(RUN_ELSEWHERE) <= {ln.split("  #")[0].strip() for ln in lines}
    for k, line in enumerate(lines):
        command = line.split("  #", 1)[0].strip()
        if command in RUN_ELSEWHERE:
            continue
        assert command.startswith("rplearn "), line
        if k == 0 or _SHELL.search(command):
            _run(["bash", "-e", "-c", command], folder, command)
        else:
            _run_in_process(command, folder)
    return folder


def _blocks(language: str | None = None) -> list[str]:
    """The README's fenced code blocks (of one info string, e.g. ``"python"``), in order."""
    blocks: list[tuple[str, list[str]]] = []
    current: tuple[str, list[str]] | None = None
    for line in _readme().splitlines():
        if line.startswith("```"):
            if current is None:
                current = (line[3:].strip(), [])
            else:
                blocks.append(current)
                current = None
        elif current is not None:
            current[1].append(line)
    return ["\n".join(body) + "\n" for info, body in blocks if language is None or info == language]


@pytest.mark.slow
def test_the_readme_commands_and_library_examples_run_on_files_its_commands_write(readme_folder):
    # every file a command reads was written by an earlier command of the block
    for name in ("data.parquet", "sh10.json", "grid.csv", "msi/A.msi", "swarm/pose_log.parquet"):
        assert (readme_folder / name).is_file(), name
    blocks = _blocks("python")
    # one session: the second block uses the first's `learn`, the third the first's sh10.json
    assert len(blocks) >= 3 and 'read_table("data.parquet")' in blocks[0]
    out = _run([sys.executable, "-c", "\n".join(blocks)], readme_folder, "README library examples")
    assert "Scores(model='SH-10'" in out and "'order': " in out and "bottleneck_rssi_dbm" in out, (
        out
    )


needs_sionna = pytest.mark.skipif(
    importlib.util.find_spec("sionna") is None and os.environ.get("CI") != "true",
    reason="the optional extra rplearn[sionna] is not installed; CI=true runs this test",
)


@pytest.mark.slow
@needs_sionna
def test_the_readme_sionna_example_runs_on_the_model_its_commands_learned(readme_folder):
    (block,) = [b for b in _blocks() if "from rplearn.integrations import" in b]
    assert 'load_model("sh10.json")' in block
    _run([sys.executable, "-c", block], readme_folder, "README Sionna RT example")


@pytest.mark.slow
def test_the_readme_live_block_runs_as_written(tmp_path):
    """The "Calibrate in flight" block: a session fed by a replay of the field guide's log."""
    (block,) = [b for b in _blocks() if b.startswith("rplearn live ")]
    os.symlink(ROOT / "tests", tmp_path / "tests")
    out = _run(["bash", "-e", "-c", block], tmp_path, "README live block")
    assert "stopped: end of stream" in out and "prequential RMSE" in out, out
    from rplearn.models.load import load_model

    assert load_model(str(tmp_path / "live.json")).label.startswith("SH-")
    assert (tmp_path / "flight.tlog").stat().st_size > 100_000


def test_the_readme_sionna_install_lines_are_what_ci_runs():
    """Installing is not run inside the tests; .ci/run does it, with these packages."""
    (block,) = [b for b in _blocks() if "pip install 'rplearn[sionna]'" in b]
    assert "apt-get install libllvm19" in block
    ci = (ROOT / ".ci" / "run").read_text(encoding="utf-8")
    assert (
        re.search(r"pip install .*-e \"\.\[[^\]]*sionna", ci) and "install -y -qq libllvm19" in ci
    )


def _kind(block: str) -> str | None:
    """Which test runs or checks a README block."""
    if all(ln.startswith("make ") for ln in block.split("\n") if ln.strip()):
        return "make targets (below)"
    if block.startswith("rplearn trajectory"):
        return "the command block (test_the_readme_commands_and_library_examples_run...)"
    if block.startswith("LOG=tests/fixtures/ardupilot/"):
        return "the field guide (tests/test_field_guide.py)"
    if block.startswith("rplearn live "):
        return "test_the_readme_live_block_runs_as_written"
    if "from rplearn.integrations import" in block:
        return "test_the_readme_sionna_example_runs..."
    if "pip install 'rplearn[sionna]'" in block:
        return "test_the_readme_sionna_install_lines_are_what_ci_runs"
    return None


def test_every_readme_block_is_run_or_checked():
    python = set(_blocks("python"))
    unaccounted = [b[:60] for b in _blocks() if b not in python and _kind(b) is None]
    assert not unaccounted, f"README blocks no test runs: {unaccounted}"
    targets = set(re.findall(r"^([\w-]+):", (ROOT / "Makefile").read_text(encoding="utf-8"), re.M))
    for block in _blocks():
        if _kind(block) == "make targets (below)":
            assert {ln.split()[1] for ln in block.split("\n") if ln.strip()} <= targets, block
