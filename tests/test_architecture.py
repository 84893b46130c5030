"""The package's layers: imports point downwards only, and there is no import cycle.

Parses every module of ``rplearn`` with :mod:`ast` (every import statement, including those
inside functions and ``TYPE_CHECKING`` blocks) and checks the rules of ARCHITECTURE.md. Each
distinct source text is parsed once per test session (:func:`parse_once`), so a planted-violation
test, on a copy of the package with one file changed, parses only that file again.
"""

from __future__ import annotations

import ast
import hashlib
import shutil
import sys
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path

import pytest

PACKAGE_DIR = Path(__file__).resolve().parents[1] / "src" / "rplearn"

#: Layers from the bottom up; a module may import its own layer's package and any layer below.
#: A module belongs to the longest layer its name starts with (``rplearn.core.lsq.solver`` to
#: ``rplearn.core.lsq``, ``rplearn.core.geometry`` to ``rplearn.core``); a package's
#: ``__init__`` may also re-export from the layers nested in it.
LAYERS: tuple[str, ...] = (
    "rplearn._version",
    "rplearn.errors",
    "rplearn._argtypes",
    "rplearn._atomic",
    "rplearn._budget",
    "rplearn.core",
    # the least-squares engine, a subpackage of core: it may use the maths modules at the top of
    # core (geometry, bases, links, ...), which never import it
    "rplearn.core.lsq",
    "rplearn.data",
    "rplearn.io",
    "rplearn.plan",
    "rplearn.sim",
    "rplearn.models",
    "rplearn.analysis",
    "rplearn.viz",
    "rplearn.integrations",
    "rplearn.workflows",
    "rplearn.cli",
    # ``python -m rplearn``: runs the command line
    "rplearn.__main__",
)

#: Third-party packages a layer may not import (docs/conventions.md: the core needs numpy and scipy only;
#: nothing below viz draws; nothing below the CLI parses arguments or styles text; only the
#: workflows run on a Dask cluster).
FORBIDDEN_THIRD_PARTY: dict[str, tuple[str, ...]] = {
    "rplearn.core": ("pandas", "pyarrow", "sklearn", "matplotlib", "plotly", "typer", "rich", "rosbags", "pyulog", "dpkt", "pymap3d", "dask", "distributed"),
    "rplearn.core.lsq": ("pandas", "pyarrow", "sklearn", "matplotlib", "plotly", "typer", "rich", "rosbags", "pyulog", "dpkt", "pymap3d", "dask",
                         "distributed"),
    "rplearn.data": ("matplotlib", "plotly", "typer", "rich", "dask", "distributed"),
    "rplearn.io": ("matplotlib", "plotly", "typer", "rich", "dask", "distributed"),
    "rplearn.plan": ("matplotlib", "plotly", "typer", "rich", "dask", "distributed"),
    "rplearn.sim": ("matplotlib", "plotly", "typer", "rich", "dask", "distributed"),
    "rplearn.models": ("matplotlib", "plotly", "typer", "rich", "dask", "distributed"),
    "rplearn.analysis": ("matplotlib", "plotly", "typer", "rich", "dask", "distributed"),
    "rplearn.viz": ("typer", "rich", "dask", "distributed"),
    # bridges to other tools (Sionna RT), which import their tool only where it is used
    "rplearn.integrations": ("typer", "rich", "dask", "distributed"),
    "rplearn.workflows": ("typer", "rich"),
    # the command line parses and prints; every computation on data is in the library
    "rplearn.cli": ("numpy", "pandas", "scipy", "sklearn", "matplotlib", "plotly"),
}

#: No module of the package is longer than this (lines).
MAX_MODULE_LINES = 600

#: Format libraries that io imports only inside the functions that need them.
LAZY_FORMAT_LIBRARIES: tuple[str, ...] = ("rosbags", "pyulog", "dpkt", "pymavlink")


def module_name(path: Path, package_dir: Path = PACKAGE_DIR) -> str:
    rel = path.relative_to(package_dir.parent).with_suffix("")
    parts = list(rel.parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def package_modules(package_dir: Path = PACKAGE_DIR) -> dict[str, Path]:
    return {module_name(p, package_dir): p for p in sorted(package_dir.rglob("*.py"))}


def layer_of(module: str) -> int | None:
    """Index of the (longest) layer a module belongs to; None for the package root."""
    found = [i for i, layer in enumerate(LAYERS) if module == layer or module.startswith(layer + ".")]
    return max(found, key=lambda i: len(LAYERS[i])) if found else None


def lazy_targets(path: Path, package: str) -> list[tuple[str, int]]:
    """Modules a package's ``__init__.pyi`` names: its public names, which ``lazy_loader``
    imports from them on first use (and type checkers read)."""
    stub = path.with_suffix(".pyi")
    if not stub.exists():
        return []
    found = []
    for node, _, _ in _import_nodes(stub.read_text(encoding="utf-8"), str(stub)):
        if isinstance(node, ast.ImportFrom):
            parts = package.split(".")
            base = parts[: len(parts) - (node.level - 1)] if node.level else []
            found.append((".".join(base + ([node.module] if node.module else [])), node.lineno))
        else:
            found += [(a.name, node.lineno) for a in node.names]
    return found


ImportNode = tuple[ast.Import | ast.ImportFrom, bool, bool]


@dataclass(frozen=True)
class Parsed:
    """What the checks read off one source text, found in one parse.

    Attributes
    ----------
    imports : tuple of (ast.Import or ast.ImportFrom, bool, bool)
        ``(import node, at module level, at module level or inside a module-level if/try)``
        for every import statement, in :func:`ast.walk` order.
    private_reads : tuple of (str, str, int)
        ``(name, attribute, line)`` of every ``name._attribute`` with a private attribute
        (``_x``, not ``__x``), in :func:`ast.walk` order.
    """

    imports: tuple[ImportNode, ...]
    private_reads: tuple[tuple[str, str, int], ...]


#: One parse per distinct source text for the whole test session, keyed by the text's SHA-256:
#: the planted-violation tests check copies of the package in which one file differs, so each
#: re-parses only that file. A text that fails to parse is never stored (it raises each time).
_PARSED: dict[str, Parsed] = {}


def parse_once(source: str, filename: str) -> Parsed:
    """The imports and private attribute reads of a source text, parsed on its first sight.

    Parameters
    ----------
    source : str
        The text of a module or stub.
    filename : str
        The file it was read from, named by the ``SyntaxError`` of a text that does not parse.

    Returns
    -------
    Parsed
        The session's one parse of this text.
    """
    key = hashlib.sha256(source.encode("utf-8")).hexdigest()
    if key in _PARSED:
        return _PARSED[key]
    tree = ast.parse(source, filename=filename)
    top_level = {id(n) for n in tree.body}
    # imports inside `if TYPE_CHECKING:` or `try:` at module level count as module level for third parties
    loose = set(top_level)
    for n in tree.body:
        if isinstance(n, (ast.If, ast.Try)):
            loose |= {id(c) for c in ast.walk(n)}
    imports: list[ImportNode] = []
    reads: list[tuple[str, str, int]] = []
    for node in ast.walk(tree):
        if isinstance(node, (ast.Import, ast.ImportFrom)):
            imports.append((node, id(node) in top_level, id(node) in loose))
        elif isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name) and _private(node.attr):
            reads.append((node.value.id, node.attr, node.lineno))
    parsed = Parsed(tuple(imports), tuple(reads))
    _PARSED[key] = parsed
    return parsed


def _import_nodes(source: str, filename: str) -> tuple[ImportNode, ...]:
    """``(import node, at module level, at module level or inside a module-level if/try)`` for
    every import statement of a source text (:func:`parse_once`)."""
    return parse_once(source, filename).imports


def imports_of(path: Path, module: str, known: set[str]) -> list[tuple[str, int, bool]]:
    """``(imported module, line, at module level)`` for every rplearn import in a file.

    ``from rplearn.x import y`` counts as an import of ``rplearn.x.y`` when that is a module.
    """
    is_package = path.name == "__init__.py"
    found: list[tuple[str, int, bool]] = []
    for node, top, _ in _import_nodes(path.read_text(encoding="utf-8"), str(path)):
        if isinstance(node, ast.Import):
            targets = [a.name for a in node.names]
        else:
            base = node.module or ""
            if node.level:
                pkg_parts = module.split(".") if is_package else module.split(".")[:-1]
                pkg_parts = pkg_parts[: len(pkg_parts) - (node.level - 1)]
                base = ".".join(pkg_parts + ([node.module] if node.module else []))
            targets = [f"{base}.{a.name}" if f"{base}.{a.name}" in known else base for a in node.names]
        for target in targets:
            if target == "rplearn" or target.startswith("rplearn."):
                found.append((target, node.lineno, top))
    if is_package:  # names loaded lazily on first use (__init__.pyi) depend on their modules too
        found += [(target, line, False) for target, line in lazy_targets(path, module) if target.startswith("rplearn")]
    return found


def third_party_imports(path: Path) -> list[tuple[str, int, bool]]:
    out = []
    for node, _, top in _import_nodes(path.read_text(encoding="utf-8"), str(path)):
        if isinstance(node, ast.Import):
            names = [a.name for a in node.names]
        elif not node.level and node.module:
            names = [node.module]
        else:
            continue
        out += [(n.split(".")[0], node.lineno, top) for n in names if not n.startswith("rplearn")]
    return out


def layering_violations(package_dir: Path = PACKAGE_DIR) -> list[str]:
    """Every import that points up or sideways between layers, or into the package root."""
    modules = package_modules(package_dir)
    known = set(modules)
    problems = []
    for module, path in modules.items():
        own = layer_of(module)
        if own is None:
            continue  # the package root re-exports public names from every layer
        for target, line, _ in imports_of(path, module, known):
            if target == "rplearn":
                problems.append(f"{module}:{line} imports the package root (import from the layer instead)")
                continue
            theirs = layer_of(target)
            if path.name == "__init__.py" and target.startswith(module + "."):
                continue  # a package re-exports what it contains (rplearn.core from rplearn.core.lsq)
            if theirs is None:
                problems.append(f"{module}:{line} imports {target}, which belongs to no layer")
            elif theirs > own:
                problems.append(f"{module}:{line} imports {target} from the higher layer {LAYERS[theirs]}")
    return problems


def import_cycles(package_dir: Path = PACKAGE_DIR) -> list[list[str]]:
    """Cycles of the graph of module imports (function-local ones included)."""
    modules = package_modules(package_dir)
    known = set(modules)
    graph: dict[str, set[str]] = {m: set() for m in modules}
    for module, path in modules.items():
        for target, _, _ in imports_of(path, module, known):
            # the imported module (or package, whose __init__ must then complete) ...
            if target in known and target != module:
                graph[module].add(target)
            # ... and, from outside a package, the __init__ of every package above it
            parts = target.split(".")
            for k in range(2, len(parts)):
                prefix = ".".join(parts[:k])
                if prefix in known and prefix != module and not module.startswith(prefix + "."):
                    graph[module].add(prefix)
    cycles, state, stack = [], {}, []

    def visit(m: str) -> None:
        state[m] = 1
        stack.append(m)
        for n in sorted(graph[m]):
            if state.get(n) == 1:
                cycles.append(stack[stack.index(n):] + [n])
            elif n not in state:
                visit(n)
        stack.pop()
        state[m] = 2

    sys.setrecursionlimit(max(sys.getrecursionlimit(), 10_000))
    for m in sorted(graph):
        if m not in state:
            visit(m)
    return cycles


def third_party_violations(package_dir: Path = PACKAGE_DIR) -> list[str]:
    problems = []
    for module, path in package_modules(package_dir).items():
        own = layer_of(module)
        if own is None:
            continue
        forbidden = FORBIDDEN_THIRD_PARTY.get(LAYERS[own], ())
        for name, line, top in third_party_imports(path):
            if name in forbidden:
                problems.append(f"{module}:{line} imports {name}, which {LAYERS[own]} may not use")
            if LAYERS[own] == "rplearn.io" and name in LAZY_FORMAT_LIBRARIES and top:
                problems.append(f"{module}:{line} imports {name} at module level (import it where it is used)")
    return problems


def _private(name: str) -> bool:
    return name.startswith("_") and not name.startswith("__")


def _private_attributes(source: str, filename: str, modules: Iterable[str]) -> list[tuple[str, int, str]]:
    """``(name, line, module)`` of every ``alias._name`` read off a package module imported under
    ``alias`` (``from rplearn.io import tables as t``, ``import rplearn.io.tables as t``)."""
    known = set(modules)
    aliases: dict[str, str] = {}
    for node, _, _ in _import_nodes(source, filename):
        if isinstance(node, ast.ImportFrom) and not node.level and (node.module or "").startswith("rplearn"):
            aliases.update({a.asname or a.name: f"{node.module}.{a.name}" for a in node.names
                            if f"{node.module}.{a.name}" in known})
        elif isinstance(node, ast.Import):
            aliases.update({a.asname: a.name for a in node.names if a.asname and a.name in known})
    return [(attr, line, aliases[name]) for name, attr, line in parse_once(source, filename).private_reads
            if name in aliases]


def _private_names_imported(package_dir: Path = PACKAGE_DIR) -> dict[str, list[tuple[str, int, str]]]:
    """Per module, ``(name, line, from module)`` of every ``from rplearn.x import _name`` of
    another module's private name (function-local ones included), and of every private name read
    off another module imported whole (``tables._read``)."""
    found: dict[str, list[tuple[str, int, str]]] = {}
    modules = package_modules(package_dir)
    for module, path in modules.items():
        source = path.read_text(encoding="utf-8")
        for node, _, _ in _import_nodes(source, str(path)):
            if not isinstance(node, ast.ImportFrom) or node.level or not (node.module or "").startswith("rplearn"):
                continue
            found.setdefault(module, []).extend((a.name, node.lineno, str(node.module)) for a in node.names
                                                if _private(a.name))
        found.setdefault(module, []).extend(_private_attributes(source, str(path), modules))
    return found


def private_imports(package_dir: Path = PACKAGE_DIR) -> list[str]:
    """Every import of another module's private name: a module's ``_name`` is its own, and what
    another module needs has a public name (in a private module, ``io/_mavlink_records.py``, too)."""
    return [f"{module}:{line} imports the private {name} of {source}"
            for module, names in _private_names_imported(package_dir).items() for name, line, source in names]


#: Each check by the kind of violation it catches.
CHECKS = {"layer": layering_violations, "third": third_party_violations, "cycle": import_cycles, "private": private_imports}


def test_no_module_imports_another_modules_private_names() -> None:
    assert private_imports() == []


def test_every_module_belongs_to_a_layer() -> None:
    strays = [m for m in package_modules() if m != "rplearn" and layer_of(m) is None]
    assert strays == []


def test_imports_point_down_only() -> None:
    assert layering_violations() == []


def test_no_import_cycles() -> None:
    assert import_cycles() == []


def test_third_party_imports_respect_the_layers() -> None:
    assert third_party_violations() == []


def test_no_module_is_longer_than_the_limit() -> None:
    lengths = {m: len(p.read_text(encoding="utf-8").splitlines()) for m, p in package_modules().items()}
    assert {m: n for m, n in lengths.items() if n > MAX_MODULE_LINES} == {}


@pytest.mark.parametrize(
    "where, source, kind",
    [
        ("core/geometry.py", "from rplearn.models.patterns import PatternSet\n", "layer"),
        ("core/coverage.py", "from rplearn.core.lsq.solver import DEFAULT_RIDGE\n", "layer"),
        ("core/bases.py", "def f():\n    from rplearn.core.lsq import solution\n", "layer"),
        ("core/lsq/solver.py", "from rplearn.data.tables import LinkSamples\n", "layer"),
        ("core/lsq/refined.py", "import pandas\n", "third"),
        ("data/sync.py", "def f():\n    from rplearn.viz import plot\n", "layer"),
        ("io/files.py", "import rplearn.cli\n", "layer"),
        ("models/spec.py", "from rplearn import RplearnError\n", "layer"),
        ("core/link.py", "import matplotlib\n", "third"),
        ("cli/swarm.py", "def f():\n    import numpy as np\n", "third"),
        ("core/bases.py", "def f():\n    from rplearn.core.lsq.solver import DEFAULT_RIDGE\n", "cycle"),
        ("io/options.py", "from rplearn.io import read_logs\n", "cycle"),
        ("core/__init__.pyi", "import rplearn.viz.plot\n", "layer"),
        ("viz/charts.py", "from rplearn.viz.plot import _hatch_uncovered\n", "private"),
        ("viz/charts.py", "def f():\n    from rplearn.viz import plot as p\n    return p._hatch_uncovered\n", "private"),
        ("viz/charts.py", "import rplearn.viz.plot as p\nX = p._hatch_uncovered\n", "private"),
    ],
)
def test_the_checks_catch_a_planted_violation(tmp_path: Path, where: str, source: str, kind: str) -> None:
    """Each check fails on a copy of the package with one bad import added."""
    copy = _copy_of_the_package(tmp_path)
    assert all(check(copy) == [] for check in CHECKS.values())
    _plant(copy, where, source)
    found = CHECKS[kind](copy)
    assert found, f"planted {source.strip()!r} in {where} was not caught"


def test_a_planted_copy_is_parsed_again_only_where_it_differs(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Every check reads the session's one parse of a text: on a copy of the package with one
    file changed, the changed file is parsed once (for all the checks) and no other file is."""
    copy = _copy_of_the_package(tmp_path)
    assert all(check(copy) == [] for check in CHECKS.values())
    # a text no other test plants, so that this session has not parsed it yet
    target = _plant(copy, "viz/charts.py", "import rplearn.viz.plot as once\nONCE = once._hatch_uncovered\n")
    parsed: list[str] = []
    parse = ast.parse

    def counted(source: str, filename: str = "<unknown>", *args: object, **kwargs: object) -> ast.AST:
        parsed.append(str(filename))
        return parse(source, filename, *args, **kwargs)  # type: ignore[call-overload]

    monkeypatch.setattr(ast, "parse", counted)
    found = {kind: check(copy) for kind, check in CHECKS.items()}
    assert parsed == [str(target)]
    assert found["private"] and found["layer"] == found["third"] == found["cycle"] == []


def _copy_of_the_package(tmp_path: Path) -> Path:
    copy = tmp_path / "rplearn"
    shutil.copytree(PACKAGE_DIR, copy, ignore=shutil.ignore_patterns("__pycache__"))
    return copy


def _plant(copy: Path, where: str, source: str) -> Path:
    """Append ``source`` to the file ``where`` of a copy of the package; the file's path."""
    target = copy / where
    target.write_text(target.read_text(encoding="utf-8") + "\n" + source, encoding="utf-8")
    return target
