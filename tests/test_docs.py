"""The documentation site (mkdocs.yml) builds offline with warnings as errors, and its generated
parts hold what they promise: every command's --help and every public name of the packages."""

from __future__ import annotations

import importlib.util
import os
import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = (
    "rplearn",
    "rplearn.io",
    "rplearn.data",
    "rplearn.models",
    "rplearn.analysis",
    "rplearn.sim",
    "rplearn.viz",
    "rplearn.plan",
    "rplearn.workflows",
)

needs_mkdocs = pytest.mark.skipif(
    importlib.util.find_spec("mkdocs") is None and os.environ.get("CI") != "true",
    reason="mkdocs is not installed (pip install -e '.[docs]'); CI=true runs this test",
)


@pytest.fixture(scope="module")
def site(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("site")
    env = dict(os.environ, NO_MKDOCS_2_WARNING="1", PYTHONPATH=str(ROOT / "src"))
    proc = subprocess.run(
        [sys.executable, "-m", "mkdocs", "build", "--strict", "--site-dir", str(out)],
        cwd=ROOT,
        env=env,
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
    )
    assert proc.returncode == 0, proc.stdout + proc.stderr
    return out


@needs_mkdocs
def test_the_site_builds_strict_and_offline(site):
    pages = list(site.rglob("*.html"))
    assert len(pages) >= 15
    for page in pages:
        text = page.read_text(encoding="utf-8")
        # nothing fetched from elsewhere when the site is read: fonts, scripts, styles are local
        assert "fonts.googleapis" not in text and "fonts.gstatic" not in text, page
        assert not re.search(r'<(script|img)[^>]* src="(https?:)?//', text), page
        assert not re.search(r'<link[^>]* href="(https?:)?//[^"]*"[^>]*rel="stylesheet"', text), (
            page
        )
        assert not re.search(r'<link rel="stylesheet" href="(https?:)?//', text), page
    assert (site / "conventions.html").is_file()


@needs_mkdocs
def test_the_cli_reference_is_every_commands_help(site):
    from typer.main import get_command

    from rplearn.cli import app

    group = get_command(app)
    html = (site / "reference" / "cli.html").read_text(encoding="utf-8")
    commands = group.list_commands(None)
    assert len(commands) >= 15
    for name in commands:
        assert f'id="rplearn-{name}"' in html, name
        for param in group.get_command(None, name).params:
            for flag in getattr(param, "opts", []):
                if flag.startswith("--"):
                    assert flag in html, (name, flag)


@needs_mkdocs
def test_the_api_reference_has_every_public_name(site):
    import importlib

    anchors = "".join(
        p.read_text(encoding="utf-8") for p in (site / "reference" / "api").glob("*.html")
    )
    for package in PACKAGES:
        for name in importlib.import_module(package).__all__:
            if name.startswith("__"):
                continue
            assert f'.{name}"' in anchors, f"{package}.{name} is not in the API reference"


# ------------------------------------------------------------------ the pages' code blocks

DOCS = ROOT / "docs"
_BLOCK = re.compile(r"^```(bash|python)\n(.*?)^```", re.S | re.M)
_SETUP = re.compile(r"<!-- docs-test: setup=(\w+) -->")


def code_blocks(page: Path) -> list[tuple[str, str]]:
    """The ``bash`` and ``python`` blocks of a page, in order: (language, code)."""
    return [(m.group(1), m.group(2)) for m in _BLOCK.finditer(page.read_text(encoding="utf-8"))]


def _pages_with_code() -> list[Path]:
    return sorted(p for p in DOCS.rglob("*.md") if code_blocks(p))


def _make_targets() -> set[str]:
    text = (ROOT / "Makefile").read_text(encoding="utf-8")
    return set(re.findall(r"^([\w-]+):", text, re.M))


def _is_make_block(code: str) -> bool:
    lines = [ln.split("#", 1)[0].strip() for ln in code.splitlines()]
    return all(ln == "" or ln.startswith("make ") for ln in lines) and any(lines)


def run_page(page: Path, cwd: Path) -> str:
    """Run every code block of a page in ``cwd`` as a reader would, in order; return the output.

    Blocks of ``make`` targets are the repository's own entry points (``make demo`` and ``make
    test`` are what .ci/run and a fresh clone run; ``make docs`` is this module's build): they
    are checked to be targets of the Makefile, not run inside the test suite. A block of plain
    lines (:func:`plain_lines`) runs line by line, its ``rplearn`` commands in this process; any
    other block runs in bash.
    """
    (cwd / "tests").symlink_to(ROOT / "tests")  # the pages run from a clone's top folder
    bindir = os.path.dirname(sys.executable)
    env = dict(
        os.environ,
        PATH=bindir + os.pathsep + os.environ.get("PATH", ""),
        MPLBACKEND="Agg",
        PYTHONPATH=str(ROOT / "src") + os.pathsep + os.environ.get("PYTHONPATH", ""),
    )
    out = []
    for lang, code in code_blocks(page):
        if lang == "bash" and _is_make_block(code):
            for line in code.splitlines():
                target = line.split("#", 1)[0].split()[1:2]
                assert not target or target[0] in _make_targets(), (
                    f"{page.name}: no make target {target}"
                )
            continue
        lines = plain_lines(code) if lang == "bash" else None
        if lines is not None:
            out.append(_run_plain(lines, cwd, env, page))
            continue
        args = (
            ["bash", "-e", "-o", "pipefail", "-c", code]
            if lang == "bash"
            else [sys.executable, "-c", code]
        )
        out.append(_run_checked(args, cwd, env, page, code))
    return "\n".join(out)


def _run_checked(args: list[str], cwd: Path, env: dict[str, str], page: Path, code: str) -> str:
    """Run ``args`` in ``cwd``; assert that it succeeded (naming the page and the code)."""
    proc = subprocess.run(
        args, cwd=cwd, env=env, capture_output=True, text=True, timeout=300, check=False
    )
    assert proc.returncode == 0, (
        f"{page.relative_to(ROOT)}: block failed\n{code}\n{proc.stdout}\n{proc.stderr}"
    )
    return proc.stdout + proc.stderr


#: A variable set by a line of its own (``LOG=path``, ``TOPICS="..."``).
_ASSIGN = re.compile(r"^([A-Za-z_]\w*)=(.*)$")
#: A use of a variable (``$LOG``, ``${LOG}``).
_USE = re.compile(r"\$\{?(\w+)\}?")
#: What makes an ``rplearn`` line more than one plain command, but for ``$NAME``: it runs in bash.
_SHELL_CHARS = re.compile(r"[`|;&<>*?(){}\[\]~!\\\"]")


def plain_lines(code: str) -> list[tuple[str, str]] | None:
    """The lines of a bash block as ``("set", line)``, ``("rplearn", line)`` or ``("bash", line)``
    when each line is a whole command: a variable set to one word, an ``rplearn`` command whose
    only shell syntax is the quoting of words and the block's variables (each a value without
    quotes or backslashes), or another one-line command (``head``, ``ls``); ``None`` for a block
    that needs bash as a whole (a here-document, a continued line, a variable it did not set)."""
    if "<<" in code or "\\\n" in code:
        return None
    known: dict[str, str] = {}
    lines: list[tuple[str, str]] = []
    for line in (ln.strip() for ln in code.splitlines()):
        if not line or line.startswith("#"):
            continue
        assign = _ASSIGN.match(line)
        if assign:
            words = shlex.split(assign.group(2))
            if len(words) != 1 or re.search(r"[$'\"\\`]", words[0]):
                return None
            known[assign.group(1)] = words[0]
            lines.append(("set", line))
        elif line.startswith("rplearn "):
            used = _USE.findall(line)
            if any(name not in known for name in used) or (used and "'" in line) or _SHELL_CHARS.search(
                _USE.sub("", re.sub(r"'[^']*'", "", line))
            ):
                return None
            lines.append(("rplearn", line))
        elif _USE.search(line):
            return None
        else:
            lines.append(("bash", line))
    return lines


def _run_plain(lines: list[tuple[str, str]], cwd: Path, env: dict[str, str], page: Path) -> str:
    """Run a block's plain lines (:func:`plain_lines`) in order in ``cwd``: variables kept here,
    ``rplearn`` commands in this process (typer's runner, the line split as a POSIX shell splits
    it once its variables are put in: what it does, without the second of interpreter start-up
    and imports a process of its own would pay again; tests/test_readme_examples.py runs the
    ``rplearn`` script itself), other commands in bash. Assert that each succeeds."""
    import contextlib

    from typer.testing import CliRunner

    from rplearn.cli import app

    known: dict[str, str] = {}
    out = []
    for kind, line in lines:
        if kind == "set":
            name, value = _ASSIGN.match(line).groups()
            known[name] = shlex.split(value)[0]
        elif kind == "bash":
            out.append(_run_checked(["bash", "-e", "-o", "pipefail", "-c", line], cwd, env, page, line))
        else:
            args = shlex.split(_USE.sub(lambda m: known[m.group(1)], line))
            with contextlib.chdir(cwd):
                res = CliRunner().invoke(app, args[1:], env={"COLUMNS": "400", "MPLBACKEND": "Agg"})
            assert res.exit_code == 0, (
                f"{page.relative_to(ROOT)}: {line}\n{res.output}\n{res.exception!r}"
            )
            out.append(res.output)
    return "\n".join(out)


def _setup(page: Path, cwd: Path) -> None:
    """Files a page's commands read that no rplearn command writes: what a user brings."""
    found = _SETUP.search(page.read_text(encoding="utf-8"))
    if found:
        SETUPS[found.group(1)](cwd)


@pytest.mark.parametrize("page", _pages_with_code(), ids=lambda p: str(p.relative_to(DOCS)))
def test_every_code_block_of_the_docs_runs(page, tmp_path):
    _setup(page, tmp_path)
    text = page.read_text(encoding="utf-8")
    for name in SHOWN_FILES.get(page.name, ()):  # a file the page shows the head of, as it is
        shown = re.search(r"^```text\n(.*?)^```", text, re.S | re.M).group(1)
        assert (tmp_path / name).read_text().startswith(shown), (page.name, name)
    out = run_page(page, tmp_path)
    for pattern, quoted in FIGURES.get(page.name, ()):
        found = re.search(pattern, out)
        assert found, f"{page.name}: the output has no {pattern!r}\n{out}"
        assert quoted.format(*found.groups()) in " ".join(text.split()), (
            page.name,
            quoted.format(*found.groups()),
        )


#: Figures the pages quote, each checked against what the commands printed: page -> (pattern
#: of the output, the text the page must hold with the pattern's groups filled in).
FIGURES: dict[str, tuple[tuple[str, str], ...]] = {
    "ardupilot.md": (
        (r"signal samples in: (\d+), matched: (\d+)", "matches {1} of the {0} radio samples"),
        (r"(no calibration flight): nodes gcs and sys1", "**{0}**"),
        (r"outage events \(link lost, no RSSI\): (\d+) in, (\d+) kept", "{0} in, {1} kept"),
        (r"\(the learning data's share up\) [\d.]+, skill ([\d.]+)", "a Brier skill of {0} against"),
    ),
    "px4.md": (
        (r"signal samples in: (\d+), matched: (\d+)", "matches {1} of the {0} packets"),
        (r"(\d+) telemetry-radio reading\(s\) \(radio_status\) not read", "{0} telemetry-radio reading(s) (radio_status) not read"),
    ),
    "rosbag.md": (
        (
            r"signal samples in: (\d),?(\d+), matched: (\d),?(\d+)",
            "{2},{3} of the {0},{1} messages",
        ),
    ),
}


def _px4_radio(cwd: Path) -> None:
    """A radio log along the sample ULog's flight: free-space RSSI at 2.4 GHz between the drone
    and a station 30 m east of its take-off point (the station.csv the page writes), 20 dBm
    transmitted, 2 dBi of antennas, 2 dB of noise, 10 Hz each way, on the log's UTC clock."""
    import numpy as np
    import pandas as pd

    from rplearn.io import read_ulog

    pose, _ = read_ulog(ROOT / "tests" / "fixtures" / "px4-ulog" / "sample_px4_events.ulg", "px4")
    t = np.arange(np.ceil(pose["t"].min()) + 0.05, pose["t"].max(), 0.1)
    xyz = np.column_stack([np.interp(t, pose["t"], pose[c]) for c in "xyz"])
    d = np.linalg.norm(xyz - [30.0, 0.0, 1.5], axis=1)
    fspl_db = 20 * np.log10(299_792_458.0 / 2.4e9 / (4 * np.pi * d))
    rng = np.random.default_rng(0)
    rows = [
        pd.DataFrame(
            {
                "t": t + k * 0.01,
                "tx": tx,
                "rx": rx,
                "rssi_dbm": np.round(22.0 + fspl_db + rng.normal(0.0, 2.0, t.size)),
            }
        )
        for k, (tx, rx) in enumerate((("px4", "gcs"), ("gcs", "px4")))
    ]
    pd.concat(rows).sort_values("t").to_csv(cwd / "radio.csv", index=False)
    sys.path.insert(0, str(ROOT / "tests" / "io"))  # the sample ULog with radio_status packets
    try:
        from ulogfiles import radio_log
    finally:
        sys.path.remove(str(ROOT / "tests" / "io"))
    radio_log(cwd / "radio.ulg")


def _ros2_bag(cwd: Path) -> None:
    """A ROS 2 bag (MCAP) of the simulator's smoke flight on a UNIX clock, written with the
    tests' bag writer (tests/io/flightfiles.py): odometry and pose topics, LinkQuality RSSI."""
    sys.path.insert(0, str(ROOT / "tests" / "io"))
    try:
        from flightfiles import EPOCH_S, write_bag
    finally:
        sys.path.remove(str(ROOT / "tests" / "io"))
    from rplearn.sim import simulate

    flight = simulate("smoke", seed=0)
    pose, signal = flight.pose_log.copy(), flight.signal_log.copy()
    pose["t"] += EPOCH_S
    signal["t"] += EPOCH_S
    write_bag(cwd / "flight_bag", pose.iloc[::5], signal, "mcap")


#: Files the setup writes whose first lines a page shows in its first ``text`` block.
SHOWN_FILES = {"px4.md": ("radio.csv",)}
SETUPS = {"px4_radio": _px4_radio, "ros2_bag": _ros2_bag}
