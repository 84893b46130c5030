"""The public API: every package's ``__all__``, its lazy loading, and the README's examples.

Each package of rplearn (the root and the layer subpackages) declares its public names in its
``__init__.pyi`` (``from .module import name as name``), which type checkers and IDEs read and
``lazy_loader.attach_stub`` turns into ``__all__`` and a module ``__getattr__`` that imports a
name's module on first use, so that ``import rplearn`` stays light. The README's library
examples import only such public names.
"""

from __future__ import annotations

import ast
import importlib
import pkgutil
import re
import subprocess
import sys
import textwrap
import types
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"

#: The layer subpackages with a public API (the CLI has none: it is a program).
SUBPACKAGES: tuple[str, ...] = tuple(
    f"rplearn.{name}" for name in ("core", "data", "io", "plan", "sim", "models", "analysis", "viz", "integrations")
)
PACKAGES: tuple[str, ...] = ("rplearn", *SUBPACKAGES)

#: Types of public constants (their ``__module__``, if any, is not where they are defined).
CONSTANT_TYPES: tuple[type, ...] = (str, int, float, tuple, dict, frozenset)

#: Third-party libraries ``import rplearn`` must not import.
HEAVY: tuple[str, ...] = ("pandas", "sklearn", "matplotlib", "plotly", "typer", "rich")


def _run(code: str) -> subprocess.CompletedProcess[str]:
    """Run ``code`` in a fresh interpreter of this environment."""
    return subprocess.run(
        [sys.executable, "-c", textwrap.dedent(code)],
        capture_output=True, text=True, timeout=120, cwd=ROOT, check=False,
    )


# --- every public name resolves ---------------------------------------------------------------


@pytest.mark.parametrize("package", PACKAGES)
def test_all_is_sorted_without_duplicates(package: str) -> None:
    names = importlib.import_module(package).__all__
    assert names, f"{package}.__all__ is empty"
    assert list(names) == sorted(set(names))


@pytest.mark.parametrize("package", PACKAGES)
def test_every_public_name_resolves_and_is_listed_by_dir(package: str) -> None:
    module = importlib.import_module(package)
    listed = dir(module)
    unresolved = [name for name in module.__all__ if not hasattr(module, name)]
    assert unresolved == [], f"{package}: names in __all__ that do not resolve"
    assert [name for name in module.__all__ if name not in listed] == []


@pytest.mark.parametrize("package", PACKAGES)
def test_public_names_are_objects_of_the_package_not_modules(package: str) -> None:
    """A public name is an object defined in the package (or an error class), never a submodule.

    The submodules are imported first here, so that the import system has had its chance to
    replace an attribute.
    """
    module = importlib.import_module(package)
    for name in module.__all__:
        getattr(module, name)
    if package != "rplearn":  # the root's submodules are the layers (and the CLI)
        for info in pkgutil.iter_modules(module.__path__):
            importlib.import_module(f"{package}.{info.name}")
    outside = []
    for name in module.__all__:
        value = getattr(module, name)
        assert not isinstance(value, types.ModuleType), f"{package}.{name} is a module"
        where = getattr(value, "__module__", None)
        if not isinstance(where, str) or isinstance(value, CONSTANT_TYPES):
            continue  # constants carry no module
        if not (where == package or where.startswith(package + ".") or where == "rplearn.errors"):
            outside.append(f"{name} ({where})")
    assert outside == [], f"{package} exports objects defined outside it"


def test_every_layer_function_is_reachable_from_its_package() -> None:
    """The main entry points of each layer, as the README and the CLI use them."""
    from rplearn.analysis import best_swarm_headings, predict_swarm
    from rplearn.data import samples_of
    from rplearn.io import read_logs, read_table
    from rplearn.models import ModelSpec, PatternRegressor, evaluate_models, fit_model, load_model
    from rplearn.sim import simulate

    functions = (best_swarm_headings, predict_swarm, samples_of, read_logs, read_table,
                 evaluate_models, fit_model, load_model, simulate)
    for obj in functions:
        assert callable(obj) and not isinstance(obj, types.ModuleType)
    assert isinstance(ModelSpec, type) and isinstance(PatternRegressor, type)


def test_unknown_names_raise_attribute_error_and_import_error() -> None:
    import rplearn.models

    with pytest.raises(AttributeError, match="rplearn.models.*no_such_name"):
        rplearn.models.no_such_name  # noqa: B018
    with pytest.raises(ImportError):
        exec("from rplearn.models import no_such_name", {})


def test_root_errors_are_the_error_classes() -> None:
    import rplearn
    from rplearn import errors

    classes = ("RplearnError", "InputError", "FarFieldError", "IdentifiabilityError",
               "ModelFileError", "LogFormatError", "PlanError")
    for name in classes:
        assert name in rplearn.__all__
        assert getattr(rplearn, name) is getattr(errors, name)
    assert rplearn.__version__ == importlib.import_module("rplearn._version").__version__


# --- laziness ---------------------------------------------------------------------------------


def test_import_rplearn_imports_no_heavy_library() -> None:
    result = _run(
        f"""
        import sys
        import rplearn
        heavy = [m for m in {HEAVY!r} if m in sys.modules]
        print(",".join(heavy))
        """
    )
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == "", f"import rplearn imported {result.stdout.strip()}"


def test_subpackages_import_no_heavy_library_until_a_name_is_used() -> None:
    result = _run(
        f"""
        import sys
        import rplearn.core, rplearn.data, rplearn.plan, rplearn.sim, rplearn.models
        import rplearn.analysis, rplearn.viz
        assert not [m for m in {HEAVY!r} if m in sys.modules], sorted(sys.modules)
        from rplearn.models import fit_model
        assert "pandas" in sys.modules and "matplotlib" not in sys.modules
        """
    )
    assert result.returncode == 0, result.stderr


def test_no_public_name_is_also_a_submodule_of_its_package() -> None:
    """Importing such a submodule would replace the public name on the package."""
    import pkgutil

    clashes = []
    for package in PACKAGES:
        module = importlib.import_module(package)
        subs = {info.name for info in pkgutil.iter_modules(module.__path__)}
        clashes += [f"{package}.{name}" for name in module.__all__ if name in subs]
    assert clashes == []


def _stub(package: str) -> Path:
    return Path(importlib.import_module(package).__file__).with_suffix(".pyi")


@pytest.mark.parametrize("package", PACKAGES)
def test_the_stub_declares_every_public_name_with_its_module(package: str) -> None:
    """``__init__.pyi`` is the one list: explicit re-exports, each the object of its module.

    Every public name is imported in the stub as ``from .module import name as name`` (the
    form ``lazy_loader.attach_stub`` reads and ``mypy --strict`` takes as a re-export), and the
    package's attribute is the very object its module defines (one object, whatever the import
    path).
    """
    module = importlib.import_module(package)
    tree = ast.parse(_stub(package).read_text(encoding="utf-8"))
    declared: dict[str, str] = {}
    for node in tree.body:
        if isinstance(node, ast.ImportFrom):
            assert node.level == 1 and node.module, f"{package}: only `from .module import ...`"
            for alias in node.names:
                assert alias.asname == alias.name, f"{package}: `{alias.name} as {alias.name}`"
                declared[alias.name] = f"{package}.{node.module}"
    extra = set(module.__all__) - set(declared)
    assert extra <= {"LogFormatError"}, f"{package}: public names not in its stub: {sorted(extra)}"
    for name, where in declared.items():
        assert getattr(module, name) is getattr(importlib.import_module(where), name), name


@pytest.mark.parametrize("package", PACKAGES)
def test_packages_hold_no_table_of_names(package: str) -> None:
    """The runtime takes the names from the stub (no second list to keep in step)."""
    source = Path(importlib.import_module(package).__file__).read_text(encoding="utf-8")
    assert "lazy_loader.attach_stub(__name__, __file__)" in source
    assert not re.search(r"^_NAMES\b", source, re.MULTILINE)


def test_a_name_imports_its_module_on_first_use_and_dir_lists_the_public_names() -> None:
    result = _run(
        """
        import sys
        import rplearn.models as m
        assert "rplearn.models.fit" not in sys.modules
        f = m.fit_model
        assert "rplearn.models.fit" in sys.modules and m.fit_model is f
        print(sorted(set(dir(m)) ^ set(m.__all__)))
        """
    )
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == "[]"


# --- the README's library examples --------------------------------------------------------------


def _readme_python_blocks() -> list[str]:
    text = README.read_text(encoding="utf-8")
    return re.findall(r"^```python\n(.*?)^```", text, re.DOTALL | re.MULTILINE)


def _imports(blocks: list[str]) -> list[ast.Import | ast.ImportFrom]:
    out: list[ast.Import | ast.ImportFrom] = []
    for block in blocks:
        nodes = ast.walk(ast.parse(block))
        out += [n for n in nodes if isinstance(n, (ast.Import, ast.ImportFrom))]
    return out


def _top(module: str | None) -> str:
    """Top-level package of a module name (``""`` for None)."""
    return (module or "").split(".")[0]


def test_readme_examples_import_public_names_only() -> None:
    blocks = _readme_python_blocks()
    imports = _imports(blocks)
    assert any(isinstance(n, ast.ImportFrom) and _top(n.module) == "rplearn" for n in imports), (
        "no `from rplearn... import` in the README's python blocks"
    )
    problems = []
    for node in imports:
        if isinstance(node, ast.ImportFrom):
            if node.level or _top(node.module) != "rplearn":
                continue
            if node.module not in PACKAGES:
                problems.append(f"from {node.module} import ...: not the root or a subpackage")
                continue
            public = importlib.import_module(node.module).__all__
            problems += [
                f"from {node.module} import {a.name}: not in __all__"
                for a in node.names
                if a.name not in public
            ]
        else:
            problems += [
                f"import {a.name}: not the root or a subpackage"
                for a in node.names
                if _top(a.name) == "rplearn" and a.name not in PACKAGES
            ]
    assert problems == []


def test_readme_import_lines_run() -> None:
    """The import statements of every python block run (the examples themselves need data)."""
    source = "\n".join(ast.unparse(node) for node in _imports(_readme_python_blocks()))
    exec(compile(source, "README.md imports", "exec"), {})
