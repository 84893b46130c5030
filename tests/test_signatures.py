"""Signatures stay short, and a fit request travels as one value.

Read from the sources with :mod:`ast` (nothing imported):

- no function or method of ``src/`` takes more than :data:`MAX_PARAMETERS` parameters. Counted:
  positional-only, positional and keyword-only parameters, and ``*args`` and ``**kwargs`` as
  one each (a catch-all still widens what a caller must know); not counted: ``self``/``cls`` of
  a method. Exempt: the ``rplearn`` commands of ``cli/`` (functions registered with
  ``@app.command()``), whose parameters are the command's flags, one each, which typer reads
  from the signature; each command turns them into option values (``FitOptions``,
  ``ReaderOptions``, ...) before calling the library.
- the fit options ``gauge``, ``path_loss`` and ``link_offsets`` are parameters only of the
  solver's entry points (``core/solver*.py``, or ``core/lsq/`` once the solver moves there),
  and of the scikit-learn estimator ``PatternRegressor.__init__`` (scikit-learn's convention:
  every hyper-parameter is a constructor argument, read by ``get_params``/``clone``; its
  documented public API); everywhere else they travel inside ``FitOptions``
  (``rplearn.models.options``).

:data:`PENDING` lists the functions still over the limit, to be split into option values (none
now: the last ones take frozen options dataclasses, ``JointFitOptions``, ``SwarmOptions``,
``YawOptions``, ...); the list may only shrink: a function not on it fails, and so does an
entry that no longer exceeds (remove it).
"""

from __future__ import annotations

import ast
from functools import cache
from pathlib import Path

SRC = Path(__file__).resolve().parents[1] / "src" / "rplearn"

MAX_PARAMETERS = 8

FIT_OPTION_NAMES = frozenset({"gauge", "path_loss", "link_offsets"})

#: Functions (``module:qualified name``) still over the limit, to be split into option values.
PENDING: frozenset[str] = frozenset()


def _is_solver_entry(module: str) -> bool:
    return module.startswith(("core/solver", "core/lsq/"))


@cache
def _functions() -> tuple[tuple[str, str, ast.FunctionDef | ast.AsyncFunctionDef, bool, bool], ...]:
    """``(module, qualified name, node, is a method, is a CLI command)`` of every function (the
    package parsed once for both checks: neither changes the trees)."""
    return tuple(_walk_functions())


def _walk_functions():
    for path in sorted(SRC.rglob("*.py")):
        module = path.relative_to(SRC).as_posix()
        tree = ast.parse(path.read_text(), str(path))

        def walk(node, prefix, in_class, module=module):
            for child in ast.iter_child_nodes(node):
                if isinstance(child, ast.ClassDef):
                    yield from walk(child, f"{prefix}{child.name}.", True, module)
                elif isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef)):
                    command = module.startswith("cli/") and any(
                        isinstance(d, ast.Call) and isinstance(d.func, ast.Attribute) and d.func.attr == "command"
                        for d in child.decorator_list)
                    yield module, f"{prefix}{child.name}", child, in_class, command
                    yield from walk(child, f"{prefix}{child.name}.", False, module)
                else:
                    yield from walk(child, prefix, in_class, module)

        yield from walk(tree, "", False)


def parameters(node: ast.FunctionDef | ast.AsyncFunctionDef, method: bool) -> list[str]:
    """The counted parameter names (see the module docstring)."""
    a = node.args
    names = [p.arg for p in (*a.posonlyargs, *a.args, *a.kwonlyargs)]
    is_static = any(isinstance(d, ast.Name) and d.id == "staticmethod" for d in node.decorator_list)
    if method and not is_static and names and names[0] in ("self", "cls"):
        names = names[1:]
    names += [f"*{a.vararg.arg}"] if a.vararg else []
    names += [f"**{a.kwarg.arg}"] if a.kwarg else []
    return names


def test_no_function_takes_more_than_eight_parameters():
    over, seen = [], set()
    for module, name, node, method, command in _functions():
        n = len(parameters(node, method))
        if n > MAX_PARAMETERS and not command:
            key = f"{module}:{name}"
            seen.add(key)
            if key not in PENDING:
                over.append(f"{key} ({n} parameters)")
    assert not over, "more than 8 parameters (bundle them in a frozen options dataclass): " + ", ".join(over)
    assert not PENDING - seen, f"no longer over the limit, remove from PENDING: {sorted(PENDING - seen)}"


def test_fit_options_travel_as_one_value():
    found = []
    for module, name, node, method, command in _functions():
        hits = FIT_OPTION_NAMES & set(parameters(node, method))
        if not hits or _is_solver_entry(module) or (module, name) == ("models/estimators.py", "PatternRegressor.__init__"):
            continue
        found.append(f"{module}:{name} ({', '.join(sorted(hits))})")
    assert not found, "pass FitOptions instead of gauge/path_loss/link_offsets: " + ", ".join(found)


def test_the_checks_catch_what_they_look_for():
    """The counting sees a long signature, keyword-only and catch-all parameters, and not ``self``."""
    tree = ast.parse("class C:\n def m(self, a, b, *c, d, e=1, **f): pass\n"
                     "def g(a, /, b, c, d, e, f, g, h, *, i): pass\n")
    method = tree.body[0].body[0]
    assert parameters(method, True) == ["a", "b", "d", "e", "*c", "**f"]
    assert len(parameters(tree.body[1], False)) == 9 > MAX_PARAMETERS
    from rplearn.models.options import FitOptions

    assert {"gauge", "path_loss", "link_offsets"} <= set(FitOptions.__dataclass_fields__)
