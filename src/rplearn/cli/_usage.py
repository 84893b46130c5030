"""One line for a usage error: a flag's value that is no number, an unknown flag or command, a
missing argument, a flag without its value.

Click (inside typer) prints such an error as the usage line, a hint and ``Error: ...``; rplearn
prints one line ``error: ...`` naming the flag and the value, as its other refusals do, and keeps
the exit code 2 of a usage error (:class:`rplearn.cli._app.OneLineUsageGroup`). The exceptions
are read by their class name and attributes, so that typer's own copy of click and click itself
are read alike.
"""

from __future__ import annotations

from typing import Any

#: The words of a number's kind, by the validation error's type (typer >= 0.29 checks values
#: with pydantic) or by click's own type name (typer < 0.29).
_KINDS = {"float": "a number", "int": "a whole number", "bool": "true or false"}
_LIMITS = {"greater_than_equal": (">=", "ge"), "greater_than": (">", "gt"), "less_than_equal": ("<=", "le"),
           "less_than": ("<", "lt")}


def param_name(param: Any) -> str:
    """The flag of an option as the user types it (its long form), or an argument's metavar."""
    opts = [o for o in getattr(param, "opts", []) if o.startswith("-")]
    if opts:
        return max(opts, key=len)
    return str(getattr(param, "metavar", None) or str(getattr(param, "name", "") or "argument").upper())


def _validation(exc: BaseException) -> dict[str, Any] | None:
    """The first error of the pydantic validation that raised ``exc``, or None."""
    cause = exc.__cause__
    errors = getattr(cause, "errors", None)
    try:
        found = errors() if callable(errors) else None
    except Exception:  # not a pydantic error after all
        return None
    return found[0] if found and isinstance(found[0], dict) else None


def bad_value(exc: BaseException) -> str:
    """What is wrong with the value, with the value: ``'abc' is not a number``,
    ``expected a whole number >= 1, got '0'`` (the flag is not named here)."""
    message = str(getattr(exc, "message", "") or exc).strip().rstrip(".")
    error = _validation(exc)
    if error is None:  # click's own message names the value ("'abc' is not a valid float")
        return message[:1].lower() + message[1:]
    kind_name, value, limits = str(error.get("type", "")), error.get("input"), error.get("ctx") or {}
    shown = repr(value) if isinstance(value, str) else repr(str(value))
    kind = next((words for key, words in _KINDS.items() if kind_name.startswith(key)), None)
    if kind_name in _LIMITS:
        op, key = _LIMITS[kind_name]
        what = "a whole number" if isinstance(value, int) or str(limits.get(key, "")).lstrip("-").isdigit() else "a number"
        return f"expected {what} {op} {limits.get(key)}, got {shown}"
    if kind is not None:
        return f"{shown} is not {kind}"
    detail = str(error.get("msg", message)).rstrip(".")
    return f"{shown}: {detail[:1].lower() + detail[1:]}"


def usage_message(exc: BaseException) -> str:
    """One line (without ``error:``) for a click usage error: the flag, the value and what is
    wrong; for an unknown flag or command or a missing argument, where ``--help`` lists them."""
    kind = type(exc).__name__
    ctx = getattr(exc, "ctx", None)
    path = getattr(ctx, "command_path", None) or "rplearn"
    see = f" (see {path} --help)"
    message = " ".join(str(getattr(exc, "message", "") or exc).split()).rstrip(".")
    param = getattr(exc, "param", None)
    hint = getattr(exc, "param_hint", None)
    if kind == "MissingParameter":
        what = "argument" if param is not None and not getattr(param, "opts", [""])[0].startswith("-") else "option"
        name = param_name(param) if param is not None else str(hint or "")
        return f"{path}: missing {what} {name}{see}"
    if kind == "NoSuchOption":
        option = str(getattr(exc, "option_name", "") or message)
        near = sorted(getattr(exc, "possibilities", None) or [])
        guess = f"; did you mean {' or '.join(near)}?" if near else ""
        return f"{option}: no such flag of {path}{guess}{see}"
    if kind == "BadOptionUsage":
        option = str(getattr(exc, "option_name", ""))
        if "requires" in message and "argument" in message:
            return f"{option}: expects a value after it"
        if "does not take a value" in message:
            return f"{option}: takes no value"
        return f"{option}: {message[:1].lower() + message[1:]}"
    if param is not None or hint:
        name = str(hint) if isinstance(hint, str) else param_name(param)
        detail = bad_value(exc)
        return detail if detail.startswith(name) else f"{name}: {detail}"
    message = message.replace(". Did you mean", "; did you mean")
    return f"{path}: {message[:1].lower() + message[1:]}{see}"


__all__ = ["bad_value", "param_name", "usage_message"]
