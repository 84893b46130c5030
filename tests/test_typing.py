"""The public API reads for static tools: mypy on the package finds no error (issue 25, item 3).

Every package's ``__init__.pyi`` names its public objects and the modules defining them; mypy
checks those stubs and every module of ``src/rplearn`` with the flags of ``[tool.mypy]`` in
pyproject.toml. Run by hand: ``python -m mypy`` from the repository root.
"""

from __future__ import annotations

import importlib.util
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

needs_mypy = pytest.mark.skipif(
    importlib.util.find_spec("mypy") is None and not os.environ.get("CI"),
    reason="mypy is not installed (pip install -e .[test]); CI always runs this",
)


def _mypy(*args: str, cwd: Path = ROOT) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "mypy", "--no-error-summary", *args],
        capture_output=True, text=True, timeout=900, cwd=cwd, check=False,
    )


@pytest.mark.slow
@needs_mypy
def test_mypy_finds_no_error_in_the_package() -> None:
    result = _mypy()  # files and flags: [tool.mypy] in pyproject.toml
    errors = [line for line in result.stdout.splitlines() if ": error:" in line]
    assert errors == [], "\n".join(errors[:40])
    assert result.returncode == 0, result.stdout[-2000:] + result.stderr[-2000:]


@pytest.mark.slow
@needs_mypy
def test_a_caller_sees_the_public_types_through_the_packages(tmp_path: Path) -> None:
    """Names imported from a package have their real types (not ``Any``), and a wrong
    argument is a type error, whichever path they are imported from; a caller checked with
    ``mypy --strict`` gets no other error (the stubs re-export explicitly)."""
    user = tmp_path / "user.py"
    user.write_text(textwrap.dedent(
        """
        from rplearn import PatternSet as Root
        from rplearn.models import PatternSet, fit_model, load_model
        from rplearn.models.patterns import PatternSet as Defined

        reveal_type(fit_model)
        reveal_type(load_model("m.json"))
        same: type[Defined] = PatternSet
        also: type[PatternSet] = Root
        fit_model("not samples", 3)
        """
    ))
    config = tmp_path / "mypy.ini"
    config.write_text("[mypy]\nstrict = True\nfollow_imports = silent\n")
    # an incremental cache of its own beside the package check's (.mypy_cache, git-ignored): the
    # first run in a clone analyses rplearn and its dependencies (~13 s of CPU), later runs re-check
    # only what changed; mypy's cache is keyed by file contents and these options, so the errors
    # are the same as without it
    cache = ROOT / ".mypy_cache" / "public-types-strict"
    env_path = os.pathsep.join([str(ROOT / "src"), os.environ.get("MYPYPATH", "")])
    result = subprocess.run(
        [sys.executable, "-m", "mypy", "--config-file", str(config), "--cache-dir", str(cache), str(user)],
        capture_output=True, text=True, timeout=900, cwd=tmp_path, check=False,
        env={**os.environ, "MYPYPATH": env_path},
    )
    out = result.stdout
    assert 'Revealed type is "def (samples: rplearn.data.tables.LinkSamples, spec: rplearn.models.spec.ModelSpec' in out, out
    assert 'Revealed type is "rplearn.models.base.Model"' in out, out
    wrong = [line for line in out.splitlines() if ": error:" in line]
    assert len(wrong) == 2 and all("fit_model" in line for line in wrong), out  # the two wrong arguments
