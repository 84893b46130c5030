"""Readable metavars in ``--help``: FILE, HZ, DB, DEG, NODE=MODEL.json, [tx|rx|both], never a
Python type such as ``<str>`` or ``<list[str]>``.

Each option gets, in order of preference:

1. its own ``metavar`` when the command module set one;
2. the listed choices (``[a|b|c]``) of an option that takes one of a few words
   (:data:`CHOICES`; the library checks the value and names the flag when it is wrong);
3. the value pattern its help text starts with (``NODE=MODEL.json: ...`` -> ``NODE=MODEL.json``);
4. the unit its help text ends a sentence with (``... [Hz].`` -> ``HZ``);
5. ``FILE`` for a file option (:data:`FILE_OPTIONS`);
6. by its type: ``TEXT``, ``NUMBER``, ``INTEGER``.
"""

from __future__ import annotations

import re
from typing import Any

#: Options that take one of a few words: (command or "*", flag) -> the words.
CHOICES: dict[tuple[str, str], tuple[str, ...]] = {
    ("*", "--turn"): ("tx", "rx", "both"),
    ("*", "--grid"): ("paper", "fibonacci"),
    ("*", "--prior-level"): ("data", "prior"),
    ("*", "--loss"): ("ls", "huber"),
    ("*", "--path-loss"): ("free", "log-distance", "two-ray"),
    ("*", "--polarization"): ("vertical", "horizontal"),
    ("*", "--nan-policy"): ("error", "drop"),
    ("*", "--on-unknown-node"): ("drop", "error"),
    ("*", "--rssi-scale"): ("dbm", "relative"),
    ("simulate", "--format"): ("parquet", "csv"),
    ("export", "--format"): ("grid", "msi", "images"),
    ("simulate", "--preset"): ("paper", "trio", "smoke", "ground", "pathloss", "tworay", "campaign", "fleet"),
    ("demo", "--preset"): ("paper", "trio", "smoke", "ground", "pathloss", "tworay", "campaign"),
}
#: Options whose value is not one word but a short grammar: (command or "*", flag) -> metavar.
METAVARS: dict[tuple[str, str], str] = {
    ("*", "--model"): "KIND",
    ("*", "--models"): "KIND,KIND...",
    ("*", "--order"): "ORDER|auto",
    ("*", "--orders"): "ORDERS",
    ("*", "--units"): "UNIT,UNIT...",
    ("*", "--learn-units"): "UNIT,UNIT...",
    ("*", "--test-units"): "UNIT,UNIT...",
    ("*", "--link"): "TX:RX",
    ("*", "--dask"): "local[:N]|tcp://HOST:PORT",
    ("*", "--rssi-field"): "FIELD",
    ("*", "--tx-pos"): "X,Y,Z",
    ("*", "--rx-pos"): "X,Y,Z",
    ("*", "--offset"): "NODE=SECONDS",
    ("*", "--gauge-node"): "NODE",
    ("*", "--station-node"): "NODE",
    ("*", "--estimate-offset"): "NODE",
    ("*", "--tx"): "NODE",
    ("*", "--rx"): "NODE",
    ("*", "--fixed"): "DRONE,DRONE...",
    ("*", "--max-accel"): "M/S^2",
}
#: Options (parameter names) whose value is a file to read or write.
FILE_OPTIONS = frozenset({"output", "plot", "plot_out", "json_out", "markdown_out", "spread", "connectivity", "connectivity_out", "dataset",
                          "truth", "poses", "signals", "html", "model_path", "check_model", "plot_path", "report"})
#: Units as help texts write them, and their metavars.
UNITS: dict[str, str] = {"hz": "HZ", "mhz": "MHZ", "dbm": "DBM", "db": "DB", "dbi": "DBI", "deg": "DEG", "m": "M",
                         "s": "SECONDS", "m/s": "M/S", "rad^2": "RAD^2", "deg/s": "DEG/S"}
_UNIT = re.compile(r"\[([A-Za-z^/0-9]+)[^\]]*\]")
_TYPES = {"str": "TEXT", "float": "NUMBER", "int": "INTEGER", "list[str]": "TEXT", "list[float]": "NUMBER",
          "list[int]": "INTEGER", "Path": "FILE", "list[Path]": "FILE"}


def choices_of(command: str, flags: list[str]) -> tuple[str, ...] | None:
    """The words an option of ``command`` with these flags takes (:data:`CHOICES`), or None."""
    for flag in flags:
        for key in ((command, flag), ("*", flag)):
            if key in CHOICES:
                return CHOICES[key]
    return None


def readable_metavar(command: str, name: str, flags: list[str], help_text: str, bare_type: str) -> str:
    """The metavar of one option or argument (module docstring, rules 2-6)."""
    for flag in flags:
        for key in ((command, flag), ("*", flag)):
            if key in METAVARS:
                return METAVARS[key]
    words = choices_of(command, flags)
    if words:
        return "[" + "|".join(words) + "]"
    text = " ".join((help_text or "").split())
    first = text.split(" ", 1)[0].rstrip(":") if text else ""
    if any(c.isupper() for c in first) and any(c in first for c in "=,:"):
        return first  # a value pattern: NODE=MODEL.json, LAT,LON,ALT, TOPIC=TX:RX
    units = [u for u in _UNIT.findall(text) if u.lower() in UNITS]
    if units:
        return UNITS[units[0].lower()]
    if name in FILE_OPTIONS:
        return "FILE"
    return _TYPES.get(bare_type, "TEXT")


def _bare(param: Any) -> str:
    try:
        return str(param.bare_type())
    except Exception:  # an option type typer describes otherwise
        return "str"


def _plain_argument(param: Any, metavar: str) -> None:
    """An argument shown as ``METAVAR`` (``METAVAR...`` when it takes several), in the usage line
    and the help, with no Python type beside it (typer prints ``{name} <str>`` otherwise)."""
    param.metavar = metavar
    shown = metavar + ("..." if getattr(param, "nargs", 1) != 1 else "")
    param._usage_display_name = lambda: shown if param.required else f"[{shown}]"
    param._rich_display_name = lambda: shown
    param.display_type_rich = lambda ctx: None


def apply_readable_metavars(group: Any) -> Any:
    """Set a readable metavar on every option and argument of every command of a click/typer
    group that has none (flags excepted); returns the group."""
    for command_name, command in getattr(group, "commands", {}).items():
        for param in command.params:
            if getattr(param, "is_flag", False):
                continue
            if param.metavar is not None:
                if not [o for o in param.opts if o.startswith("-")]:
                    _plain_argument(param, param.metavar)
                continue
            flags = [o for o in param.opts if o.startswith("-")]
            if not flags:  # an argument: its name, upper case, without a type beside it
                _plain_argument(param, param.name.upper())
                continue
            param.metavar = readable_metavar(command_name, param.name, flags, getattr(param, "help", "") or "",
                                             _bare(param))
    return group


__all__ = ["CHOICES", "FILE_OPTIONS", "METAVARS", "UNITS", "apply_readable_metavars", "choices_of", "readable_metavar"]
