"""The repository stands on its own: licence, citation file, the paper cited where the method
is described, and no document outside the repository named as a source."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

#: The paper rplearn implements (arXiv identifier and its DOI).
ARXIV_ID = "2604.02827"
PAPER_DOI = f"10.48550/arXiv.{ARXIV_ID}"
PAPER_AUTHORS = ("Zoula", "Bonilla Licea", "Faigl", "Navrátil", "Saska")


def _citation() -> dict:
    yaml = pytest.importorskip("yaml")  # pyyaml: the `test` extra
    return yaml.safe_load((ROOT / "CITATION.cff").read_text(encoding="utf-8"))


def test_citation_file_is_valid_cff_citing_the_software_and_the_paper():
    cff = _citation()
    # the keys CFF 1.2.0 requires, and the types it gives them
    assert cff["cff-version"] == "1.2.0"
    assert isinstance(cff["message"], str) and cff["message"].strip()
    assert cff["type"] == "software" and cff["title"].startswith("rplearn")
    assert cff["authors"] and all(("name" in a) or ("family-names" in a) for a in cff["authors"])
    assert cff["license"] == "BSD-3-Clause"
    assert re.fullmatch(r"\d+\.\d+\.\d+", str(cff["version"]))
    paper = cff["preferred-citation"]
    assert paper["type"] == "article" and isinstance(paper["year"], int)
    assert " ".join(paper["title"].split()).startswith(
        "Orientation Matters: Learning Radiation Patterns"
    )
    assert tuple(a["family-names"] for a in paper["authors"]) == PAPER_AUTHORS
    assert all(a["given-names"] for a in paper["authors"])
    assert paper["doi"] == PAPER_DOI and ARXIV_ID in paper["url"]
    for ident in paper.get("identifiers", []):
        assert ident["type"] in ("doi", "url", "swh", "other") and ident["value"]


def test_version_of_the_citation_is_the_package_version():
    cff = _citation()
    text = (ROOT / "pyproject.toml").read_text(encoding="utf-8")
    assert f'version = "{cff["version"]}"' in text


def test_license_file_matches_the_declared_license():
    text = (ROOT / "LICENSE").read_text(encoding="utf-8")
    assert text.startswith("BSD 3-Clause License")
    assert "the rplearn authors" in text and "Neither the name of the copyright holder" in text
    pyproject = (ROOT / "pyproject.toml").read_text(encoding="utf-8")
    assert 'license = "BSD-3-Clause"' in pyproject and 'license-files = ["LICENSE"]' in pyproject


def test_readme_and_package_docstring_cite_the_paper():
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    docstring = subprocess.run(
        [sys.executable, "-c", "import rplearn; print(rplearn.__doc__)"],
        capture_output=True,
        text=True,
        check=True,
        cwd=ROOT,
    ).stdout
    for text in (readme, docstring):
        assert f"arXiv:{ARXIV_ID}" in text and PAPER_DOI in text
        assert "Zoula" in text and "Hert et al" not in text


def _tracked_text_files() -> list[Path]:
    out = subprocess.run(["git", "ls-files"], capture_output=True, text=True, cwd=ROOT)
    if out.returncode != 0:
        pytest.skip("not a git checkout")
    files = []
    for name in out.stdout.splitlines():
        path = ROOT / name
        if path.suffix in (".py", ".md", ".toml", ".cff", ".txt", ".cfg") or path.name in (
            "Makefile",
            "run",
        ):
            files.append(path)
    return files


def test_no_document_outside_the_repository_is_named():
    outside = ("DESIGN" + ".md", "../" + "shared", "/work/" + "shared")
    found = [
        f"{p.relative_to(ROOT)}: {word}"
        for p in _tracked_text_files()
        if p.is_file()
        for word in outside
        if word in p.read_text(encoding="utf-8", errors="replace")
    ]
    assert not found, found
    assert (ROOT / "docs" / "conventions.md").is_file()
    # every reference to the conventions names the file as it is spelt
    wrong = [
        str(p.relative_to(ROOT))
        for p in _tracked_text_files()
        if p.is_file() and "CONVENTIONS" + ".md" in p.read_text(encoding="utf-8", errors="replace")
    ]
    assert not wrong, wrong


def test_ruff_finds_nothing():
    """The lint rules of pyproject.toml hold on the whole tree (.ci/run runs the same command)."""
    import importlib.util
    import os

    if importlib.util.find_spec("ruff") is None:
        if os.environ.get("CI") == "true":
            raise AssertionError("ruff is not installed: .ci/run installs the test extra")
        pytest.skip("ruff is not installed (pip install -e '.[test]')")
    proc = subprocess.run([sys.executable, "-m", "ruff", "check", "src", "tests", "benchmarks", "docs"], cwd=ROOT,
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stdout[-3000:]
