"""``rplearn inspect --json``: an :class:`~rplearn.io.inspect.InspectReport` as strict JSON.

Times are seconds from the log start (``start_s``, on the log's own clock, given once), as the
text report prints them; numbers that are not finite (a rate of a single row, an RSSI range of
no samples) become ``null``, so that every strict parser reads the output.
"""

from __future__ import annotations

import json
import math
from dataclasses import asdict
from typing import Any

from rplearn.io.inspect import InspectReport

#: Version of the JSON layout (bumped when a field changes meaning).
INSPECT_JSON_VERSION = 1
_TIMES = ("t_start_s", "t_end_s")


def _finite(value: Any) -> Any:
    """``value`` with every non-finite float replaced by None (recursively)."""
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, dict):
        return {str(k): _finite(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_finite(v) for v in value]
    if hasattr(value, "item") and not isinstance(value, (str, bytes)):  # numpy scalars
        return _finite(value.item())
    return value


def _relative(row: dict[str, Any], start_s: float) -> dict[str, Any]:
    return {k: (float(v) - start_s if k in _TIMES else v) for k, v in row.items()}


def inspect_to_dict(report: InspectReport) -> dict[str, Any]:
    """The report as plain data: files (with the readers' findings as text lines), nodes (each with
    ``fixed``: held at its pose by ``sync``) and links (times from the log start), problems, the
    reasons for no calibration flight, and the fixed nodes (``fixed_nodes``, sorted; ``fixed_note``,
    the line that says them, ``null`` without any)."""
    files = [{**{k: v for k, v in f.items()}, "findings": report.findings(f)} for f in report.files]
    return _finite({
        "schema": "rplearn.inspect", "version": INSPECT_JSON_VERSION, "start_s": report.start_s,
        "times": "seconds from start_s (the log start, on the log's clock)",
        "files": files,
        "nodes": [_relative(asdict(n), report.start_s) for n in report.nodes],
        "links": [_relative(asdict(lk), report.start_s) for lk in report.links],
        "problems": list(report.problems), "calibration": list(report.calibration), "ok": report.ok,
        "fixed_nodes": list(report.fixed_nodes), "fixed_note": report.fixed_note,
    })


def inspect_to_json(report: InspectReport) -> str:
    """:func:`inspect_to_dict` as strict JSON text (no NaN or Infinity)."""
    return json.dumps(inspect_to_dict(report), indent=1, allow_nan=False, default=str)


__all__ = ["INSPECT_JSON_VERSION", "inspect_to_dict", "inspect_to_json"]
