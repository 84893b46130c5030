"""A plan read back from its reference files, so that the simulator can fly what was written.

``rplearn trajectory`` (with or without ``--optimize``) writes one CSV per unit and drone,
``<label>_<node>.csv`` with columns ``t, x, y, z, yaw_deg`` (``t`` from 0 in each unit).
:func:`read_plan` reads a folder of them back into a :class:`~rplearn.plan.campaign.Campaign` of
:class:`ReferenceUnit` (units in the order of their labels: ``--optimize`` numbers them in flying
order), each interpolating its two drones' references (positions linearly, headings along the
shorter turn); velocity and acceleration are the references' finite differences.
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd

from rplearn._argtypes import check_types
from rplearn.errors import InputError
from rplearn.plan.campaign import Campaign
from rplearn.plan.trajectory import UnitReference, sample_times_s

_NAME = re.compile(r"^(?P<label>.+)_(?P<node>[^_]+)\.csv$")
_COLUMNS = ("t", "x", "y", "z", "yaw_deg")


@check_types
@dataclass(frozen=True)
class ReferenceUnit:
    """One unit of a written plan: two drones' references ``t, x, y, z, yaw_deg``.

    Attributes
    ----------
    nodes : (str, str)
    label : str
    tables : (DataFrame, DataFrame)
        The references of ``nodes[0]`` and ``nodes[1]``, ``t`` [s] from 0, increasing.
    role : str
    """

    nodes: tuple[str, str]
    label: str
    tables: tuple[Any, Any]
    role: str = "learning"

    @property
    def duration_s(self) -> float:
        return float(min(t["t"].iloc[-1] for t in self.tables))

    def sample(self, rate_hz: float, t_offset_s: float = 0.0) -> UnitReference:
        """References of both drones at ``rate_hz`` [Hz]."""
        return self.evaluate(sample_times_s(self.duration_s, rate_hz), t_offset_s)

    def evaluate(self, t_rel_s: np.ndarray, t_offset_s: float = 0.0) -> UnitReference:
        """References at unit times ``t_rel_s`` [s]."""
        t = np.clip(np.asarray(t_rel_s, np.float64), 0.0, self.duration_s)
        n = t.size
        pos, vel, acc, yaw = np.zeros((n, 2, 3)), np.zeros((n, 2, 3)), np.zeros((n, 2, 3)), np.zeros((n, 2))
        for j, table in enumerate(self.tables):
            tt = table["t"].to_numpy(np.float64)
            for c, col in enumerate("xyz"):
                v = table[col].to_numpy(np.float64)
                pos[:, j, c] = np.interp(t, tt, v)
                if tt.size > 2:
                    dv = np.gradient(v, tt)
                    vel[:, j, c] = np.interp(t, tt, dv)
                    acc[:, j, c] = np.interp(t, tt, np.gradient(dv, tt))
            yaw[:, j] = np.angle(np.exp(1j * np.interp(t, tt, np.unwrap(np.radians(table["yaw_deg"].to_numpy(np.float64))))))
        return UnitReference(self, t + t_offset_s, pos, vel, acc, yaw, np.zeros(n, np.int_))


def _table(path: str) -> pd.DataFrame:
    try:
        table = pd.read_csv(path)
    except (OSError, ValueError, pd.errors.ParserError) as exc:
        raise InputError(f"{path}: cannot read the reference file ({exc})", param="plan") from None
    missing = [c for c in _COLUMNS if c not in table.columns]
    if missing:
        raise InputError(f"{path}: missing column(s) {', '.join(missing)} (expected {', '.join(_COLUMNS)})", param="plan")
    values = table[list(_COLUMNS)].apply(pd.to_numeric, errors="coerce")
    bad = int((~np.isfinite(values.to_numpy(np.float64))).any(axis=1).sum())
    if bad or len(values) < 2:
        raise InputError(f"{path}: {bad} row(s) not finite numbers, {len(values)} rows (expected at least 2)", param="plan")
    if not np.all(np.diff(values["t"].to_numpy()) > 0) or values["t"].iloc[0] != 0.0:
        raise InputError(f"{path}: t must start at 0 and increase", param="plan")
    return values


@check_types
def read_plan(folder: str, gap_s: float = 10.0) -> Campaign:
    """The units of a folder of reference files (module docstring), flown ``gap_s`` apart.

    Raises
    ------
    InputError
        A folder without reference files, a unit without exactly two drones' files, or a file
        that is not a reference (naming it).
    """
    if not os.path.isdir(folder):
        raise InputError(f"{folder}: not a folder of reference files", param="plan")
    groups: dict[str, dict[str, str]] = {}
    for name in sorted(os.listdir(folder)):
        m = _NAME.match(name)
        if m:
            groups.setdefault(m.group("label"), {})[m.group("node")] = os.path.join(folder, name)
    if not groups:
        raise InputError(f"{folder}: no reference file <label>_<node>.csv", param="plan")
    units = []
    for label, files in sorted(groups.items()):
        if len(files) != 2:
            raise InputError(f"{folder}: unit {label} has {len(files)} drone file(s) ({', '.join(sorted(files))}), expected 2",
                             param="plan")
        a, b = sorted(files)
        units.append(ReferenceUnit((a, b), label, (_table(files[a]), _table(files[b]))))
    return Campaign(tuple(units), gap_s=gap_s)  # type: ignore[arg-type]


__all__ = ["ReferenceUnit", "read_plan"]
