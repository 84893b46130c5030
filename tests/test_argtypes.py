"""rplearn._argtypes: a wrong argument type at the public API is one ArgumentTypeError naming the
parameter (an InputError and a TypeError), never a bare TypeError or AttributeError from deep
inside numpy or pandas (issue 10, class 6)."""

from __future__ import annotations

import importlib
import inspect
import os
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
        from rplearn._argtypes import checked

        def f(x: bool) -> bool:
            return x

        checked(f, "f")("yes")


def test_public_functions_keep_their_names_and_docstrings():
    from rplearn.models import fit_model
    from rplearn.models.fit import fit_model as raw

    assert fit_model.__name__ == "fit_model" and fit_model.__doc__ == raw.__doc__
    assert fit_model.__wrapped__ is raw


def test_paths_become_strings_whole_floats_integers_and_a_bare_string_is_no_sequence(tmp_path):
    from rplearn._argtypes import checked

    def f(path: str, n: int, names: "list[str] | None" = None) -> tuple:
        return path, n, names

    g = checked(f, "f")
    assert g(tmp_path / "x.csv", 2.0) == (str(tmp_path / "x.csv"), 2, None)
    assert type(g("a", 2.0)[1]) is int
    with pytest.raises(ArgumentTypeError, match="^names: expected a list"):
        g("a", 1, "AB")
