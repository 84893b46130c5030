"""MkDocs hook: the generated parts of the documentation site, rendered at build time.

- ``<!-- cli-reference -->`` in a page becomes the ``--help`` of every ``rplearn`` command, as
  the installed typer application prints it (so the page cannot drift from the commands);
- ``<!-- api: PACKAGE -->`` becomes one mkdocstrings block (``::: module.name``) per public name
  in ``PACKAGE.__all__``, grouped by the module that defines it. A name is rendered on the page
  of the first package that exports it; the others link to it (the top-level ``rplearn`` page
  renders only what no subpackage exports). Packages are imported to read ``__all__`` (their
  lazy ``__getattr__`` tables are invisible to static analysis); constants, which carry no
  ``__module__``, are found by the module that assigns them.
"""

from __future__ import annotations

import ast
import importlib
import inspect
import re
import sys
from functools import cache
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[2]
SRC = ROOT / "src"
#: Packages of the API reference, in the order a name is claimed (the root last).
PACKAGES = (
    "rplearn.io",
    "rplearn.data",
    "rplearn.models",
    "rplearn.analysis",
    "rplearn.sim",
    "rplearn.viz",
    "rplearn.plan",
    "rplearn.workflows",
    "rplearn",
)
_API = re.compile(r"<!-- api: ([\w.]+) -->")
_CLI = "<!-- cli-reference -->"
_HELP_WIDTH = 80


def _import(name: str) -> Any:
    if str(SRC) not in sys.path:  # the repository's sources, whether or not rplearn is installed
        sys.path.insert(0, str(SRC))
    return importlib.import_module(name)


# ----------------------------------------------------------------------------------- CLI


def cli_reference() -> str:
    """Markdown of ``rplearn --help`` and ``rplearn COMMAND --help`` for every command."""
    import click
    import typer

    app = _import("rplearn.cli").app
    group = typer.main.get_command(app)
    root = click.Context(
        group, info_name="rplearn", terminal_width=_HELP_WIDTH, max_content_width=_HELP_WIDTH
    )
    parts = ["## rplearn", "", "```text", group.get_help(root).rstrip(), "```", ""]
    for name in group.list_commands(root):
        command = group.get_command(root, name)
        if command is None or command.hidden:
            continue
        ctx = click.Context(
            command,
            info_name=name,
            parent=root,
            terminal_width=_HELP_WIDTH,
            max_content_width=_HELP_WIDTH,
        )
        summary = (command.get_short_help_str(limit=200) or "").strip()
        parts += [
            f"## rplearn {name}",
            "",
            summary,
            "",
            "```text",
            command.get_help(ctx).rstrip(),
            "```",
            "",
        ]
    return "\n".join(parts)


# ----------------------------------------------------------------------------------- API


@cache
def _top_level_assignments(path: Path) -> frozenset[str]:
    """The names a module's top level assigns (each module parsed once per build)."""
    names: set[str] = set()
    for node in ast.parse(path.read_text(encoding="utf-8")).body:
        targets = (
            node.targets
            if isinstance(node, ast.Assign)
            else [node.target]
            if isinstance(node, ast.AnnAssign)
            else []
        )
        names |= {t.id for t in targets if isinstance(t, ast.Name)}
    return frozenset(names)


def _assigning_module(package: str, name: str) -> str | None:
    """The module of ``package`` whose top level assigns ``name`` (a constant)."""
    folder = SRC.joinpath(*package.split("."))
    for path in sorted(folder.rglob("*.py")):
        if name in _top_level_assignments(path):
            module = ".".join(path.relative_to(SRC).with_suffix("").parts)
            return module.removesuffix(".__init__")
    return None


@cache
def _object_path(package: str, name: str) -> str | None:
    """Dotted path of the definition of public name ``name`` of ``package`` (asked by every page
    that exports it, and again when that page is rendered)."""
    obj = getattr(_import(package), name)
    if inspect.isclass(obj) or inspect.isfunction(obj):
        return f"{obj.__module__}.{obj.__qualname__}"
    module = _assigning_module(package, name)
    return None if module is None else f"{module}.{name}"


@cache
def _claims() -> dict[str, str]:
    """Definition path -> the package page that renders it."""
    owner: dict[str, str] = {}
    for package in PACKAGES:
        for name in _import(package).__all__:
            path = _object_path(package, name)
            if path is not None:
                owner.setdefault(path, package)
    return owner


def _page_of(package: str) -> str:
    return "rplearn" if package == "rplearn" else package.split(".", 1)[1]


def api_reference(package: str) -> str:
    """Markdown of the public names of ``package``, one mkdocstrings block each."""
    owner = _claims()
    by_module: dict[str, list[str]] = {}
    links: list[str] = []
    for name in sorted(_import(package).__all__, key=str.lower):
        if name.startswith("__"):
            continue
        path = _object_path(package, name)
        if path is None:
            raise RuntimeError(f"{package}.{name}: its definition was not found")
        if owner[path] == package:
            by_module.setdefault(path.rsplit(".", 1)[0], []).append(path)
        else:
            links.append(f"| `{name}` | [{path}][{path}] ({_page_of(owner[path])} page) |")
    parts: list[str] = []
    for module in sorted(by_module):
        parts += [f"## `{module}`", ""]
        for path in by_module[module]:
            parts += [f"::: {path}", ""]
    if links:
        parts += [
            "## Documented elsewhere",
            "",
            f"Public names of `{package}` documented with the package that defines them:",
            "",
            "| name | documented at |",
            "| --- | --- |",
            *links,
            "",
        ]
    return "\n".join(parts)


# --------------------------------------------------------------------------------- hook


def on_page_markdown(markdown: str, **kwargs: Any) -> str:
    """MkDocs hook: expand the generated parts of a page."""
    if _CLI in markdown:
        markdown = markdown.replace(_CLI, cli_reference())
    return _API.sub(lambda m: api_reference(m.group(1)), markdown)
