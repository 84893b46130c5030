"""Argument types checked at the public API: a wrong type is one clear :class:`ArgumentTypeError`.

Every public function and class of rplearn (each name a package exports) is decorated where it
is defined::

    @check_types
    def fit_model(samples: LinkSamples, spec: ModelSpec, ...) -> FittedModel: ...

    @check_types
    @dataclass(frozen=True)
    class ModelSpec: ...

so the checks are the same whatever the import path (``rplearn.models.fit_model`` and
``rplearn.models.fit.fit_model`` are one object). A function is wrapped
(``functools.wraps`` keeps its name, docstring and signature); a class keeps its identity and
gets its own ``__init__`` wrapped once, when the class is made (outermost decorator, so that a
dataclass's generated ``__init__`` is the one wrapped). The wrapper compares each argument with
the parameter's annotation and raises :class:`~rplearn.errors.ArgumentTypeError` (an
``RplearnError`` and a ``TypeError``) naming the parameter, the expected and the given type and
the function, before any work; instead of a ``TypeError`` or ``AttributeError`` from deep inside
numpy or pandas. The annotations are resolved on the first call, so that names defined later in
the module (or imported only for type checkers) cost nothing at import.

Only annotations that can be checked exactly are: classes (``int`` takes numpy integers and whole floats,
converted to ``int``; ``float`` any real number but ``bool``; ``str`` also an ``os.PathLike``, converted
to ``str``), ``None``, unions of
these, and the abstract containers ``Mapping``, ``Sequence`` and ``Iterable`` (the container
only, not its items; a bare string is not taken as a sequence), ``Callable``; numpy's ``ArrayLike`` and ``NDArray`` take numbers,
arrays and sequences (not text, not complex numbers). Anything else (``Any``,
``Literal``, type variables, names that do not resolve) is left to the function's own checks.
scikit-learn estimators are not decorated: by that library's convention their ``__init__`` only
stores its arguments, which ``fit`` checks.

This module is at the bottom of the layers and uses only the standard library.
"""

from __future__ import annotations

import collections.abc as cabc
import functools
import inspect
import math
import numbers
import os
import types
import typing
from collections.abc import Callable
from typing import Any, TypeVar

from rplearn.errors import ArgumentTypeError

#: The check of one annotation: a predicate on the value and the name of what it expects.
_Check = tuple[Callable[[Any], bool], str]

_ABSTRACT: dict[Any, tuple[type, str]] = {
    cabc.Mapping: (cabc.Mapping, "a mapping"),
    cabc.MutableMapping: (cabc.Mapping, "a mapping"),
    cabc.Sequence: (cabc.Iterable, "a sequence"),
    cabc.Iterable: (cabc.Iterable, "an iterable"),
    cabc.Collection: (cabc.Iterable, "a collection"),
    cabc.Iterator: (cabc.Iterator, "an iterator"),
    dict: (cabc.Mapping, "a dict"),
    list: (cabc.Iterable, "a list"),
    tuple: (cabc.Iterable, "a tuple"),
}


def _is_real(v: Any) -> bool:
    return isinstance(v, numbers.Real) and not isinstance(v, bool)


def is_finite_real(value: Any) -> bool:
    """Whether ``value`` is a finite real number (any :class:`numbers.Real`, numpy's included;
    not a bool).

    Parameters
    ----------
    value : object

    Returns
    -------
    bool
        False too for an integer too large for a float (``10**400``: no option takes it).
    """
    try:
        return _is_real(value) and math.isfinite(float(value))
    except OverflowError:
        return False


def _is_int(v: Any) -> bool:
    """An integer, or a number that is one (3.0, not 3.7); not a bool."""
    if isinstance(v, bool):
        return False
    return isinstance(v, numbers.Integral) or (isinstance(v, numbers.Real) and float(v).is_integer())


def _class_check(cls: type) -> _Check | None:
    """The check of a plain class annotation (None when it is not one that can be checked)."""
    if cls is float:
        return _is_real, "a number"
    if cls is int:
        return _is_int, "an integer"
    if cls is bool:
        return (lambda v: isinstance(v, bool) or type(v).__name__ == "bool_"), "True or False"
    if cls is str:
        return (lambda v: isinstance(v, (str, os.PathLike))), "a string"  # a path is converted to str
    if cls is complex or cls is object or cls is Any:
        return None
    try:
        isinstance(None, cls)
    except TypeError:  # a protocol that is not runtime-checkable, a special form
        return None
    if cls in _ABSTRACT:
        base, what = _ABSTRACT[cls]
        if base is cabc.Iterable and cls is not cabc.Iterator:  # a bare string is no sequence of names
            return (lambda v: isinstance(v, base) and not isinstance(v, (str, bytes))), what
        return (lambda v: isinstance(v, base)), what
    if isinstance(cls, type):
        return (lambda v: isinstance(v, cls)), f"a {cls.__name__}"
    return None


def _is_array_like(v: Any) -> bool:
    """Numbers, arrays and sequences of numbers (not text): what numpy turns into a float array."""
    if isinstance(v, (str, bytes, complex)):
        return False
    return _is_real(v) or hasattr(v, "__array__") or isinstance(v, (cabc.Sequence, numbers.Real))


def _numpy_array_hint(hint: Any) -> bool:
    """Whether ``hint`` is numpy's ``ArrayLike`` or an ``NDArray[...]`` (numpy already imported
    when such a hint resolves)."""
    import sys

    npt = sys.modules.get("numpy.typing")
    if npt is not None and hint is npt.ArrayLike:
        return True
    np = sys.modules.get("numpy")
    return np is not None and (hint is np.ndarray or typing.get_origin(hint) is np.ndarray)


def _check_of(hint: Any) -> _Check | None:
    """The check of an annotation, or None when it is not checked (see the module docstring)."""
    if hint is None or hint is type(None):
        return (lambda v: v is None), "None"
    if _numpy_array_hint(hint):
        return _is_array_like, "numbers or an array of numbers"
    origin = typing.get_origin(hint)
    if origin in (typing.Union, types.UnionType):
        parts = [_check_of(a) for a in typing.get_args(hint)]
        if any(p is None for p in parts):
            return None
        preds = [p[0] for p in parts]  # type: ignore[index]
        names = [p[1] for p in parts]  # type: ignore[index]
        return (lambda v: any(f(v) for f in preds)), " or ".join(names)
    if origin is not None:
        if origin in _ABSTRACT:
            return _class_check(origin)
        if origin is cabc.Callable:
            return callable, "a callable"
        if isinstance(origin, type):  # os.PathLike[str], type[X]: the class only
            return _class_check(origin)
        return None
    if hint is cabc.Callable:
        return callable, "a callable"
    if isinstance(hint, type):
        return _class_check(hint)
    return None


def _hints(func: Callable[..., Any]) -> dict[str, Any]:
    """Resolved annotations of ``func``; a name that does not resolve is left out."""
    try:
        return typing.get_type_hints(func)
    except Exception:  # a TYPE_CHECKING-only name: resolve one annotation at a time
        out = {}
        globalns = getattr(func, "__globals__", {})
        for name, text in getattr(func, "__annotations__", {}).items():
            try:
                out[name] = eval(text, globalns) if isinstance(text, str) else text  # noqa: S307 (own annotations)
            except Exception:
                continue
        return out


def _checks(func: Callable[..., Any], skip_first: bool) -> tuple[inspect.Signature, dict[str, _Check]] | None:
    try:
        sig = inspect.signature(func)
    except (TypeError, ValueError):
        return None
    hints = _hints(func)
    checks: dict[str, _Check] = {}
    params = list(sig.parameters.values())[1 if skip_first else 0:]
    for p in params:
        if p.kind in (p.VAR_POSITIONAL, p.VAR_KEYWORD) or p.name not in hints:
            continue
        check = _check_of(hints[p.name])
        if check is not None:
            if p.default is None:  # a parameter defaulting to None takes None
                pred, what = check
                check = (lambda v, f=pred: v is None or f(v)), what
            checks[p.name] = check
    return (sig, checks) if checks else None


def _wrap(func: Callable[..., Any], label: str, skip_first: bool) -> Callable[..., Any]:
    """``func`` with its arguments checked; the checks are built on the first call."""
    state: list[Any] = []  # [signature, checks, names to str, names to int], or [None]

    def prepare() -> list[Any]:
        found = _checks(func, skip_first)
        if found is None:
            return [None]
        sig, checks = found
        hints = _hints(func)
        to_str = {n for n in checks if _plain(hints.get(n)) is str}
        to_int = {n for n in checks if _plain(hints.get(n)) is int}
        return [sig, checks, to_str, to_int]

    @functools.wraps(func)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        if not state:
            state[:] = prepare()
        if state[0] is None:
            return func(*args, **kwargs)
        sig, checks, to_str, to_int = state
        try:
            bound = sig.bind(*args, **kwargs)
        except TypeError as exc:
            raise ArgumentTypeError(f"{label}: {exc}") from None
        changed = False
        for name, value in list(bound.arguments.items()):
            check = checks.get(name)
            if check is None:
                continue
            if not check[0](value):
                raise ArgumentTypeError(
                    f"{name}: expected {check[1]}, got {type(value).__name__} {_short(value)} ({label})", param=name
                )
            if name in to_str and isinstance(value, os.PathLike):
                bound.arguments[name], changed = os.fspath(value), True
            elif name in to_int and isinstance(value, float):
                bound.arguments[name], changed = int(value), True
        if changed:
            return func(*bound.args, **bound.kwargs)
        return func(*args, **kwargs)

    wrapper.__rplearn_checked__ = True  # type: ignore[attr-defined]
    return wrapper


def _plain(hint: Any) -> Any:
    """The one class of ``hint`` or ``hint | None`` (None for anything else)."""
    if typing.get_origin(hint) in (typing.Union, types.UnionType):
        args = [a for a in typing.get_args(hint) if a is not type(None)]
        return args[0] if len(args) == 1 else None
    return hint


def _short(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 40 else text[:37] + "..."


_T = TypeVar("_T")


def _label(obj: Any) -> str:
    """``rplearn.<layer>.<name>``: where the public name is imported from."""
    layer = ".".join(str(getattr(obj, "__module__", "")).split(".")[:2])
    return f"{layer}.{obj.__qualname__}" if layer else obj.__qualname__


def check_types(obj: _T, label: str | None = None) -> _T:
    """Decorator: ``obj`` with its arguments checked (see the module docstring).

    Parameters
    ----------
    obj : function or class
        A function is returned wrapped; a class is returned itself, its own ``__init__`` wrapped
        (exceptions, classes without an ``__init__`` of their own and anything else are returned
        as they are).
    label : str, optional
        The name that error messages give; by default ``rplearn.<layer>.<name>``.

    Returns
    -------
    function or class
        The checked object, of the same type for static checkers.
    """
    name = label or _label(obj)
    if inspect.isclass(obj):
        init = obj.__dict__.get("__init__")
        if init is not None and not getattr(init, "__rplearn_checked__", False) and not issubclass(obj, BaseException):
            setattr(obj, "__init__", _wrap(init, name, skip_first=True))  # noqa: B010 (mypy: no assigning to a method)
        return obj
    if inspect.isfunction(obj) and not getattr(obj, "__rplearn_checked__", False):
        return typing.cast(_T, _wrap(obj, name, skip_first=False))  # functools.wraps: same signature
    return obj


__all__ = ["check_types", "is_finite_real"]
