"""rplearn._argtypes: a wrong argument type at the public API is one ArgumentTypeError naming the
parameter (an InputError and a TypeError), never a bare TypeError or AttributeError from deep
inside numpy or pandas (issue 10, class 6). The checks are applied where each public function or
class is defined (``@check_types``), so they are the same whatever the import path (issue 25)."""

from __future__ import annotations

import importlib
import inspect
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

from rplearn.errors import ArgumentTypeError, InputError, RplearnError

PACKAGES = ["rplearn"] + [f"rplearn.{p}" for p in ("core", "data", "io", "plan", "sim", "models", "analysis", "viz", "integrations", "workflows")]


def public_callables():
    for package in PACKAGES:
        mod = importlib.import_module(package)
        for name in mod.__all__:
            obj = getattr(mod, name)
            if not callable(obj) or (inspect.isclass(obj) and issubclass(obj, BaseException)):
                continue
            try:
                sig = inspect.signature(obj)
            except (TypeError, ValueError):
                continue
            required = [p for p in sig.parameters.values()
                        if p.default is p.empty and p.kind in (p.POSITIONAL_ONLY, p.POSITIONAL_OR_KEYWORD)]
            if required:
                yield pytest.param(obj, len(required), id=f"{package}.{name}")


@pytest.mark.parametrize("wrong", [object(), 3 + 4j], ids=["object", "complex"])
@pytest.mark.parametrize("func, n_required", list(public_callables()))
def test_a_wrong_type_is_an_rplearn_error(func, n_required, wrong):
    try:
        func(*([wrong] * n_required))
    except RplearnError:
        pass  # ArgumentTypeError, or the function's own check


def test_the_error_names_the_parameter_and_is_both_kinds():
    from rplearn.models import ModelSpec, fit_model

    with pytest.raises(ArgumentTypeError, match=r"^samples: expected a LinkSamples, got str 'x' \(rplearn.models.fit_model\)$") as e:
        fit_model("x", ModelSpec("sh", 3))
    assert e.value.param == "samples"
    assert isinstance(e.value, TypeError) and isinstance(e.value, InputError)
    with pytest.raises(ArgumentTypeError, match="^order: expected an integer"):
        ModelSpec("sh", 3.7)


def test_values_of_the_right_kind_pass_in_any_of_their_forms(tmp_path):
    from rplearn.core import wavelength_m
    from rplearn.models import ModelSpec, load_model

    assert ModelSpec("sh", np.int64(3)).order == 3 and ModelSpec("sh", 3.0).order == 3  # whole numbers
    assert wavelength_m(np.float32(2.4e9)) == pytest.approx(0.1249, abs=1e-4)  # numpy scalars are numbers
    fixture = Path(__file__).parent / "fixtures" / "models_v1" / "sh5.json"
    assert load_model(fixture).nodes == load_model(os.fspath(fixture)).nodes  # paths as str or PathLike
    with pytest.raises(ArgumentTypeError, match="^path: expected a string or a PathLike"):
        load_model(5)
    with pytest.raises(ArgumentTypeError, match="^x: expected True or False|^flag"):
        from rplearn._argtypes import check_types

        def f(x: bool) -> bool:
            return x

        check_types(f, "f")("yes")


def test_public_functions_keep_their_names_docstrings_and_signatures():
    from rplearn.models import fit_model
    from rplearn.models.fit import fit_model as same

    assert fit_model is same  # decorated where it is defined: one object
    raw = fit_model.__wrapped__
    assert fit_model.__name__ == raw.__name__ == "fit_model" and fit_model.__doc__ == raw.__doc__
    assert inspect.signature(fit_model) == inspect.signature(raw)


def _fresh(code: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-c", textwrap.dedent(code)], capture_output=True, text=True, timeout=120, check=False)


@pytest.mark.parametrize("module", ["rplearn.models", "rplearn.models.patterns", "rplearn"])
def test_the_same_class_with_the_same_checks_whatever_the_import_path(module):
    """In a fresh interpreter, whichever path is imported first: one class, one check."""
    result = _fresh(f"""
        from {module} import PatternSet
        try:  # before any other look-up of the name
            PatternSet("sh5", ("A", "B"), [[0.0]])
        except Exception as exc:
            print(type(exc).__name__, exc)
        import rplearn.models, rplearn.models.patterns
        assert PatternSet is rplearn.models.PatternSet is rplearn.models.patterns.PatternSet
    """)
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == (
        "ArgumentTypeError basis: expected a Basis, got str 'sh5' (rplearn.models.PatternSet)"
    )


def _public_objects():
    seen = {}
    for package in PACKAGES:
        mod = importlib.import_module(package)
        for name in mod.__all__:
            obj = getattr(mod, name)
            if inspect.isfunction(obj) or inspect.isclass(obj):
                seen[id(obj)] = (f"{package}.{name}", obj)
    return sorted(seen.values(), key=lambda item: item[0])


def test_every_public_function_and_class_is_checked_where_it_is_defined():
    """``@check_types`` on each one (nothing is wrapped when it is looked up)."""
    missing = []
    for label, obj in _public_objects():
        if inspect.isclass(obj):
            init = obj.__dict__.get("__init__")
            exempt = (issubclass(obj, BaseException) or hasattr(obj, "_get_param_names")  # scikit-learn
                      or getattr(obj, "_is_protocol", False) or init is None)
            if not exempt and not getattr(init, "__rplearn_checked__", False):
                missing.append(label)
        elif not getattr(obj, "__rplearn_checked__", False):
            missing.append(label)
    assert missing == [], "public names without @check_types where they are defined"


def test_paths_become_strings_whole_floats_integers_and_a_bare_string_is_no_sequence(tmp_path):
    from rplearn._argtypes import check_types

    def f(path: str, n: int, names: list[str] | None = None) -> tuple:
        return path, n, names

    g = check_types(f, "f")
    assert g(tmp_path / "x.csv", 2.0) == (str(tmp_path / "x.csv"), 2, None)
    assert type(g("a", 2.0)[1]) is int
    with pytest.raises(ArgumentTypeError, match="^names: expected a list"):
        g("a", 1, "AB")


def test_an_integer_too_large_for_a_float_is_a_clear_option_error():
    # review45: was OverflowError ("int too large to convert to float") out of the option checks
    from rplearn._argtypes import is_finite_real
    from rplearn.analysis.heading_options import YawOptions
    from rplearn.data.sync import SyncOptions
    from rplearn.errors import InputError

    assert not is_finite_real(10**400) and is_finite_real(10**300) and is_finite_real(3)
    with pytest.raises(InputError, match="tx_yaw_deg"):
        YawOptions(tx_yaw_deg=10**400)
    with pytest.raises(InputError, match="max_gap_s"):
        SyncOptions(max_gap_s=10**400)
