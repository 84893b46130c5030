"""One work budget for every size parameter: checked before any work, the largest value that fits named.

Every parameter that sets how much work a command or library call does (flights, loops, a
sample rate, a step, a time window, grid rows, a file's declared array sizes, links x times,
an order range, workers) goes through :func:`check_work` with a cost model: the memory
[bytes] and time [s] the work would take at a value of the parameter (``Cost``: estimates
from the sizes the work allocates and per-unit times measured on a modest machine, in the
module that does the work). The budget (:func:`budget`) is

- memory: ``RPLEARN_MAX_MEMORY`` (bytes, or with a ``K``/``M``/``G``/``T`` suffix, powers of
  1024) if set, else 80 % of the memory the system has available now
  (``MemAvailable`` of ``/proc/meminfo``, else of physical memory);
- time: ``RPLEARN_MAX_SECONDS`` if set, else :data:`DEFAULT_MAX_SECONDS`;
- disk (for work that writes, ``Cost.disk_bytes``): the free space of the output's folder.

A value beyond the budget is refused with one line naming the parameter, what it would need,
the budget, and the largest (for a step: the smallest) value that fits, found by bisection on
the cost model, so that no work starts, and the refusal itself takes milliseconds.
"""

from __future__ import annotations

import math
import os
import re
import shutil
from collections.abc import Callable
from dataclasses import dataclass

from rplearn._argtypes import check_types
from rplearn.errors import InputError

#: Time budget [s] of one step of work whose size a parameter sets, unless ``RPLEARN_MAX_SECONDS`` says otherwise.
DEFAULT_MAX_SECONDS = 300.0
#: Share of the memory available now that one step of work may take, unless ``RPLEARN_MAX_MEMORY`` says otherwise.
AVAILABLE_SHARE = 0.8
_UNITS = {"": 1, "K": 1 << 10, "M": 1 << 20, "G": 1 << 30, "T": 1 << 40}


@check_types
@dataclass(frozen=True)
class Cost:
    """What a piece of work takes.

    Attributes
    ----------
    memory_bytes : float
        Peak memory it allocates [bytes].
    seconds : float
        Time it runs [s].
    disk_bytes : float
        What it writes [bytes] (checked against the free space of the output's folder).
    """

    memory_bytes: float = 0.0
    seconds: float = 0.0
    disk_bytes: float = 0.0


@check_types
@dataclass(frozen=True)
class Budget:
    """Memory [bytes], time [s] and the folder whose free space bounds what is written."""

    memory_bytes: float
    seconds: float
    disk_folder: str | None = None

    def disk_bytes(self) -> float:
        """Free space of :attr:`disk_folder` (its nearest existing parent) [bytes]; inf without one."""
        folder = self.disk_folder
        if folder is None:
            return math.inf
        folder = os.path.abspath(folder)
        while folder and not os.path.isdir(folder):
            parent = os.path.dirname(folder)
            if parent == folder:
                return math.inf
            folder = parent
        try:
            return float(shutil.disk_usage(folder).free)
        except OSError:
            return math.inf

    def refusal(self, cost: Cost) -> str | None:
        """What of the budget ``cost`` exceeds (None: it fits)."""
        if not cost.memory_bytes <= self.memory_bytes:
            return f"about {size_text(cost.memory_bytes)} of memory (budget {size_text(self.memory_bytes)}, RPLEARN_MAX_MEMORY)"
        if not cost.seconds <= self.seconds:
            return f"about {time_text(cost.seconds)} (budget {time_text(self.seconds)}, RPLEARN_MAX_SECONDS)"
        if cost.disk_bytes > 0 and not cost.disk_bytes <= self.disk_bytes():
            return f"about {size_text(cost.disk_bytes)} of disk ({size_text(self.disk_bytes())} free in {self.disk_folder})"
        return None


def size_text(n: float) -> str:
    """Bytes as ``1.5 GiB``."""
    if not math.isfinite(n):
        return "unbounded"
    for unit in ("B", "KiB", "MiB", "GiB", "TiB", "PiB"):
        if abs(n) < 1024 or unit == "PiB":
            return f"{n:.3g} {unit}" if unit != "B" else f"{int(n)} B"
        n /= 1024
    return f"{n:.3g} EiB"  # pragma: no cover - unreachable


def time_text(s: float) -> str:
    """Seconds as ``45 s``, ``3.2 min``, ``5.1 h`` or ``2.3e+04 days``."""
    if not math.isfinite(s):
        return "unbounded time"
    if s < 120:
        return f"{s:.3g} s"
    if s < 7200:
        return f"{s / 60:.3g} min"
    if s < 172800:
        return f"{s / 3600:.3g} h"
    return f"{s / 86400:.3g} days"


def _parse_size(text: str) -> float:
    match = re.fullmatch(r"\s*([0-9.eE+]+)\s*([KMGT]?)(?:i?B)?\s*", text.upper())
    if not match:
        raise InputError(f"RPLEARN_MAX_MEMORY: expected bytes such as 8G or 8589934592, got {text!r}")
    try:
        value = float(match.group(1)) * _UNITS[match.group(2)]
    except ValueError:
        raise InputError(f"RPLEARN_MAX_MEMORY: expected bytes such as 8G or 8589934592, got {text!r}") from None
    if not (math.isfinite(value) and value > 0):
        raise InputError(f"RPLEARN_MAX_MEMORY: expected a positive size, got {text!r}")
    return value


def _available_memory() -> float:
    """Memory the system can give now [bytes]: ``MemAvailable``, else physical memory, else 8 GiB."""
    try:
        with open("/proc/meminfo", encoding="ascii") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    return float(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    try:
        return float(os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES"))
    except (AttributeError, ValueError, OSError):
        return float(8 << 30)


@check_types
def budget(disk_folder: str | None = None) -> Budget:
    """The work budget now (module docstring), with ``disk_folder`` the output's folder."""
    memory = os.environ.get("RPLEARN_MAX_MEMORY")
    seconds = os.environ.get("RPLEARN_MAX_SECONDS")
    mem = _parse_size(memory) if memory else AVAILABLE_SHARE * _available_memory()
    if seconds:
        try:
            secs = float(seconds)
        except ValueError:
            secs = math.nan
        if not (math.isfinite(secs) and secs > 0):
            raise InputError(f"RPLEARN_MAX_SECONDS: expected a positive number of seconds, got {seconds!r}")
    else:
        secs = DEFAULT_MAX_SECONDS
    return Budget(mem, secs, disk_folder)


def _largest(value: float, fits: Callable[[float], bool], integer: bool, smallest: float) -> float | None:
    """The largest value in ``[smallest, value]`` that fits (the cost grows with it), or None."""
    if not fits(smallest):
        return None
    lo, hi = smallest, value
    for _ in range(200):
        if integer and hi - lo <= 1:
            break
        mid = math.floor((lo + hi) / 2) if integer else (math.sqrt(lo * hi) if lo > 0 else (lo + hi) / 2)
        if not integer and hi - lo <= 1e-4 * abs(hi):
            break
        if fits(mid):
            lo = mid
        else:
            hi = mid
    return lo


def _smallest(value: float, fits: Callable[[float], bool], largest: float) -> float | None:
    """The smallest value in ``[value, largest]`` that fits (the cost falls as it grows), or None."""
    if not fits(largest):
        return None
    lo, hi = value, largest
    for _ in range(200):
        if hi - lo <= 1e-4 * abs(hi):
            break
        mid = math.sqrt(lo * hi) if lo > 0 else (lo + hi) / 2
        if fits(mid):
            hi = mid
        else:
            lo = mid
    return hi


def _number(v: float, integer: bool, up: bool, fits: Callable[[float], bool]) -> str:
    """``v`` as the user types it: whole, or 3 significant digits, rounded toward the side that
    fits (the rounder neighbour when it fits too: 1 rather than 1.01 for a bisection's 1.00005)."""
    if integer:
        return f"{int(v):,}"
    scale = 10 ** (2 - math.floor(math.log10(abs(v)))) if v else 1
    near, safe = (math.floor(v * scale) / scale, math.ceil(v * scale) / scale)
    if not up:
        near, safe = safe, near
    return f"{near:g}" if near > 0 and fits(near) else f"{safe:g}"


@check_types
def check_work(
    param: str,
    value: float,
    cost: Callable[[float], Cost],
    what: str,
    integer: bool = True,
    bounds: tuple[float, float] = (1.0, math.inf),
    falling: bool = False,
    limits: Budget | None = None,
) -> Cost:
    """Refuse ``value`` of ``param`` when the ``cost`` of the work it sets exceeds the budget.

    Parameters
    ----------
    param : str
        The parameter (its flag in the CLI), named at the start of the message.
    value : float
        Its value.
    cost : callable
        Cost of the work at a value (monotone: growing with it, or falling with ``falling``).
    what : str
        What the value counts, e.g. ``"flights"``, ``"Hz"`` or ``"deg"``.
    integer : bool
        Whether the parameter is a whole number.
    bounds : (float, float)
        The parameter's own range, searched for the value that fits.
    falling : bool
        The cost falls as the value grows (a step): the smallest step that fits is named.
    limits : Budget, optional
        The budget (default :func:`budget`).

    Returns
    -------
    Cost
        The cost at ``value``, which fits.

    Raises
    ------
    InputError
        Naming ``param``, the need, the budget and the value that fits (``param`` set).
    """
    limits = budget() if limits is None else limits
    at = cost(value)
    over = limits.refusal(at)
    if over is None:
        return at

    def fits(v: float) -> bool:
        return limits.refusal(cost(v)) is None

    if falling:
        best = _smallest(float(value), fits, float(bounds[1]))
        hint = f"use a step of at least {_number(best, integer, True, fits)} {what}" if best is not None else f"no value of {param} fits"
    else:
        best = _largest(float(value), fits, integer, float(bounds[0]))
        hint = f"the largest that fits is {_number(best, integer, False, fits)} {what}" if best is not None else f"no value of {param} fits"
    shown = f"{int(value):,}" if integer else f"{value:g}"
    raise InputError(f"{param}: {shown} {what} would take {over}; {hint}", param=param)


__all__ = ["AVAILABLE_SHARE", "DEFAULT_MAX_SECONDS", "Budget", "Cost", "budget", "check_work", "size_text", "time_text"]
