"""Simulated campaigns that several test modules read (tests/models, tests/analysis): each
simulated, synced, split and fitted once per process (per xdist worker), then handed out
read-only.

The paper-preset and ground-preset acceptance tests of calibration, priors, orientation and
availability learn from the same flights: the ``paper`` campaign of seed 0 (A->B), the ``ground``
campaigns of seeds 0-5, the ``campaign`` preset of seed 0. Each is the same data whoever makes it
(one preset, seed and link give one flight), so it is made once per process and key:

- :func:`simulated`: the simulator's files (``preset`` and ``seed``; every link's :func:`synced`
  and the tests reading the raw logs or the simulation share them);
- :func:`synced`: the simulator's files and the synced dataset in a folder of this process's
  (callers copy the files they need with :func:`copy_files`; nothing writes in that folder), with
  the learning units' samples and the held-out samples, their arrays read-only;
- :func:`auto_fit`: ``fit_auto`` of those learning units with its default options.

Imported by test modules of the subfolders (pytest puts this folder on ``sys.path``: it holds
conftest.py and no ``__init__.py``).
"""

from __future__ import annotations

import atexit
import dataclasses
import functools
import os
import shutil
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

#: The folder of this process's flights (one subfolder per key), removed when the process ends.
_ROOT = Path(tempfile.mkdtemp(prefix="rplearn-flights-"))
atexit.register(shutil.rmtree, _ROOT, True)


@dataclass(frozen=True)
class SyncedFlight:
    """One simulated campaign, synced: its folder (``f/pose_log.parquet``, ``f/signal_log.parquet``,
    ``m.parquet``), the simulation, and the samples of its learning units (each, and all) and of its
    held-out units."""

    folder: Path
    sim: Any
    per_unit: dict[str, Any]
    learn: Any
    test: Any


def _read_only(value: Any) -> Any:
    """``value`` with every array inside it (a dataclass's fields, a tuple's items) made read-only."""
    if isinstance(value, np.ndarray):
        value.flags.writeable = False
    elif dataclasses.is_dataclass(value) and not isinstance(value, type):
        for field in dataclasses.fields(value):
            _read_only(getattr(value, field.name))
    elif isinstance(value, tuple):
        for item in value:
            _read_only(item)
    return value


def simulated(preset: str, seed: int) -> tuple[Path, Any]:
    """``simulate(preset, seed=seed)`` with its files (``pose_log.parquet``, ``signal_log.parquet``,
    ``matched_truth.parquet``, ``ground_truth.json``, ``references/``) in a folder of this process's,
    once per process: (the folder, the simulation). Callers read both and change neither."""
    return _simulated(preset, seed)  # one cache key however the caller spells the arguments


@functools.cache
def _simulated(preset: str, seed: int) -> tuple[Path, Any]:
    """:func:`simulated`."""
    from rplearn.sim import simulate

    d = _ROOT / f"{preset}-{seed}-sim"
    return d, simulate(preset, seed=seed, out_dir=str(d))


def synced(preset: str, seed: int, link: tuple[str, str] | None = None) -> SyncedFlight:
    """``preset``'s flights of ``seed`` simulated and synced (only ``link`` when given), once per
    process; the samples' arrays are read-only."""
    return _synced(preset, seed, link)  # one cache key however the caller spells the arguments


@functools.cache
def _synced(preset: str, seed: int, link: tuple[str, str] | None) -> SyncedFlight:
    """:func:`synced`, its arguments all given."""
    from rplearn.data.sync import SyncOptions
    from rplearn.data.units import samples_of, split_units
    from rplearn.io.files import read_dataset
    from rplearn.workflows.logs import sync_logs

    d = _ROOT / f"{preset}-{seed}-{'-'.join(link or ('all',))}"
    files, sim = simulated(preset, seed)
    shutil.copytree(files, d / "f", copy_function=os.link)  # the same files (nobody writes in them)
    sync_logs([str(d / "f" / "pose_log.parquet")], [str(d / "f" / "signal_log.parquet")], str(d / "m.parquet"),
              sync_options=SyncOptions(link=link))
    df = read_dataset(str(d / "m.parquet"))
    learn, test = split_units(df, None, None)
    nodes = sorted(set(df["tx"]) | set(df["rx"]))
    per_unit = {u: _read_only(samples_of(df, [u], "d", nodes=nodes)) for u in learn}
    return SyncedFlight(d, sim, per_unit, _read_only(samples_of(df, learn, "d", nodes=nodes)),
                        _read_only(samples_of(df, test, "d", nodes=nodes)))


def auto_fit(preset: str, seed: int, link: tuple[str, str] | None = None) -> tuple[Any, Any]:
    """``fit_auto`` (default options) of the learning units of :func:`synced`, once per process:
    (the fitted model, the selection). Callers read it and do not change it."""
    return _auto_fit(preset, seed, link)  # one cache key however the caller spells the arguments


@functools.cache
def _auto_fit(preset: str, seed: int, link: tuple[str, str] | None) -> tuple[Any, Any]:
    """:func:`auto_fit`, its arguments all given."""
    from rplearn.models.auto import fit_auto

    return fit_auto(synced(preset, seed, link).per_unit)


def copy_files(flight: SyncedFlight, dest: Path) -> Path:
    """Copy the flight's files (``f/``, ``m.parquet``) into ``dest`` (made if missing); return ``dest``."""
    shutil.copytree(flight.folder, dest, dirs_exist_ok=True)
    return dest
