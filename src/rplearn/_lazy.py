"""Lazy public names of a package (PEP 562): a name's module is imported when it is first used.

Every package of rplearn lists its public names in ``__all__`` and resolves them on first
access, so that ``import rplearn`` (or ``import rplearn.models``) imports neither the modules
behind those names nor their third-party libraries (pandas, scikit-learn, matplotlib)::

    from rplearn._lazy import lazy_exports

    _NAMES = {"fit_model": "fit", "load_model": "load"}   # public name -> defining module
    __all__ = sorted(_NAMES)
    __getattr__, __dir__ = lazy_exports(__name__, _NAMES)

``from rplearn.models import fit_model`` then imports :mod:`rplearn.models.fit` and binds its
``fit_model``; the value is cached in the package, so later look-ups cost nothing. Each
public function and class comes with its argument types checked (:mod:`rplearn._argtypes`).

A public name must not equal the name of a submodule of its package (importing the
submodule would replace it); tests/test_public_api.py checks this.

This module is at the bottom of the layers (tests/test_architecture.py) and uses only the
standard library.
"""

from __future__ import annotations

import importlib
import sys
from collections.abc import Callable, Mapping
from typing import Any

from rplearn._argtypes import checked

__all__ = ["lazy_exports"]


def _absolute(package: str, module: str) -> str:
    """Full name of ``module``: absolute when it starts with the top-level package, else a
    submodule of ``package`` (a leading dot is allowed, ``"fit"`` and ``".fit"`` are the same)."""
    top = package.partition(".")[0]
    if module == top or module.startswith(top + "."):
        return module
    return f"{package}.{module.lstrip('.')}"


def lazy_exports(
    package: str, names: Mapping[str, str]
) -> tuple[Callable[[str], Any], Callable[[], list[str]]]:
    """Module ``__getattr__`` and ``__dir__`` that import public names on first use (PEP 562).

    Parameters
    ----------
    package : str
        ``__name__`` of the package whose ``__init__`` calls this; it must already be in
        :data:`sys.modules` (it is while its ``__init__`` runs).
    names : mapping of str to str
        Each public name and the module defining it: relative to ``package`` (``"fit"``) or
        absolute (``"rplearn.models.fit"``). The module must define the name.

    Returns
    -------
    __getattr__ : callable
        ``__getattr__(name)``: the object ``name`` of its module, imported now and cached as
        an attribute of the package; :class:`AttributeError` for any other name.
    __dir__ : callable
        ``__dir__()``: the package's attributes and every public name, sorted.
    """
    where = {name: _absolute(package, module) for name, module in names.items()}
    def __getattr__(name: str) -> Any:
        module = where.get(name)
        if module is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = checked(getattr(importlib.import_module(module), name), f"{package}.{name}")
        setattr(sys.modules[package], name, value)
        return value

    def __dir__() -> list[str]:
        return sorted(set(vars(sys.modules[package])) | set(where))

    return __getattr__, __dir__
