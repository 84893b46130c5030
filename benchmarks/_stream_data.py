"""What the streamed-fit benchmarks share (``stream_copies.py``, ``stream_drift.py``, ``stream_layout.py``).

Their options (``--rows``, ``--repeats``, ``--tiny``), a file of distinct rows made from a simulated flight, a streamed
fit timed, and the runs with and without the thing measured, alternately. Not a benchmark itself (its name starts
with ``_``: tests/test_benchmarks.py runs none such); a script imports it as ``_stream_data``, its own folder being
first on ``sys.path`` when it is run as ``python benchmarks/SCRIPT.py``.
"""

from __future__ import annotations

import argparse
import os
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import TypeVar

import pandas as pd

from rplearn.models.options import FitOptions
from rplearn.models.spec import ModelSpec
from rplearn.sim import simulate
from rplearn.workflows import learning
from rplearn.workflows.logs import sync_logs

T = TypeVar("T")

#: The rows and repeats of ``--tiny``.
TINY_ROWS, TINY_REPEATS = 20_000, 1


@dataclass(frozen=True)
class StreamOptions:
    """A streamed-fit benchmark's options.

    Attributes
    ----------
    rows : int
        Rows of the file fitted.
    repeats : int
        Runs of each side (with and without the thing measured); the best is printed.
    tiny : bool
        The case of seconds (``--tiny``): its time targets are not enforced.
    """

    rows: int
    repeats: int
    tiny: bool


def parse_options(description: str, tiny_help: str) -> StreamOptions:
    """``--rows`` (default 1,000,000), ``--repeats`` (3) and ``--tiny`` (20,000 rows, once) from the command line."""
    parser = argparse.ArgumentParser(description=description)
    parser.add_argument("--rows", type=float, default=1e6)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--tiny", action="store_true", help=tiny_help)
    args = parser.parse_args()
    if args.tiny:
        return StreamOptions(TINY_ROWS, TINY_REPEATS, True)
    return StreamOptions(int(args.rows), args.repeats, False)


def stream_every_file() -> None:
    """Make ``rplearn fit`` stream every file, in chunks of ``PART_CHUNK_ROWS``."""
    learning.STREAM_FIT_ROWS = 0
    learning.STREAM_FIT_BYTES = 0


def print_load() -> None:
    """Print the machine's load (1, 5 and 15 minutes): a run's figures are read against it."""
    with open("/proc/loadavg") as fh:
        print(f"load {fh.read().split()[:3]}")


def start(description: str, tiny_help: str) -> StreamOptions:
    """A benchmark's start: its options parsed (:func:`parse_options`), every file streamed
    (:func:`stream_every_file`) and the machine's load printed (:func:`print_load`)."""
    opts = parse_options(description, tiny_help)
    stream_every_file()
    print_load()
    return opts


def repeated_flight(folder: str, rows: int, preset: str, seed: int) -> pd.DataFrame:
    """``rows`` distinct rows: the preset's matched dataset (simulated and synced in ``folder``)
    repeated at later times, its units spread over four labels."""
    simulate(preset, seed=seed, out_dir=os.path.join(folder, "f"))
    one = os.path.join(folder, "m.parquet")
    sync_logs([os.path.join(folder, "f", "pose_log.parquet")], [os.path.join(folder, "f", "signal_log.parquet")], one)
    df = pd.read_parquet(one)
    span = float(df["t"].max() - df["t"].min()) + 1.0
    copies = -(-rows // len(df))
    return pd.concat([df.assign(t=df["t"] + k * span, unit=df["unit"] + f"_{k % 4}") for k in range(copies)],
                     ignore_index=True).iloc[:rows]


def dataset_file(folder: str, rows: int, preset: str, seed: int) -> str:
    """:func:`repeated_flight` written to ``folder/big.parquet``: its path."""
    path = os.path.join(folder, "big.parquet")
    repeated_flight(folder, rows, preset, seed).to_parquet(path, index=False)
    return path


def timed_fit(path: str, spec: str, options: FitOptions | None = None) -> tuple[float, float, learning.FitOutcome]:
    """``rplearn fit`` of ``path`` (``learning.fit_dataset``): its wall and CPU seconds, and its outcome."""
    w0, c0 = time.perf_counter(), time.process_time()
    out = learning.fit_dataset(path, ModelSpec.parse(spec), options=options)
    return time.perf_counter() - w0, time.process_time() - c0, out


def alternately(repeats: int) -> Iterator[bool]:
    """``True`` (with the thing measured) and ``False`` (without), ``repeats`` times each, each first in turn."""
    for k in range(repeats):
        yield from (True, False) if k % 2 == 0 else (False, True)


def best_alternating(run: Callable[[bool], tuple[tuple[float, ...], T]],
                     repeats: int) -> tuple[dict[bool, tuple[float, ...]], dict[bool, T]]:
    """``run(True)`` and ``run(False)`` :func:`alternately`, each giving its figures and an output.

    Returns
    -------
    best : dict
        Per side, the least of each figure over its runs.
    last : dict
        Per side, the output of its last run.
    """
    best: dict[bool, tuple[float, ...]] = {}
    last: dict[bool, T] = {}
    for side in alternately(repeats):
        figures, last[side] = run(side)
        best[side] = tuple(map(min, best[side], figures)) if side in best else figures
    return best, last
