"""Export learned or true patterns: a regular az-el grid as CSV; what every export shares.

"Pattern-like" (:class:`PatternLike`) means any object with ``nodes`` and
``evaluate(node, az_rad, el_rad)`` returning the gain [dBi]: a learned
:class:`rplearn.models.patterns.PatternSet` or a :class:`rplearn.sim.antennas.GroundTruth`.
Two attributes are optional: ``frequency_hz``, the carrier [Hz] written into MSI files when
none is given (:mod:`rplearn.io.msi`), and ``gauge``, the notes of a fit that could not
identify absolute gains. 3-D images are :mod:`rplearn.viz.images`.
"""

from __future__ import annotations

import math
import os
import re
from collections.abc import Sequence
from typing import Any, Protocol, runtime_checkable

import numpy as np
import pandas as pd
from numpy.typing import ArrayLike, NDArray

from rplearn._argtypes import check_types
from rplearn._atomic import atomic_path
from rplearn.errors import InputError

FloatArray = NDArray[np.float64]

GRID_COLUMNS = ("node", "az_deg", "el_deg", "gain_db")


# -- pattern-likes ---------------------------------------------------------------------------
@runtime_checkable
class PatternLike(Protocol):
    """Per-node patterns: node ids and the gain of a node toward body-frame directions.

    Attributes
    ----------
    nodes : sequence of str
        Node ids.
    """

    @property
    def nodes(self) -> Sequence[str]: ...

    def evaluate(self, node: str, az_rad: ArrayLike, el_rad: ArrayLike) -> FloatArray:
        """Gain of ``node`` toward directions (az, el) [rad] of its body frame [dBi]."""
        ...


def check_pattern_like(obj: Any) -> None:
    """Refuse an object that is not pattern-like (see :class:`PatternLike`).

    Raises
    ------
    InputError
        Naming the type received.
    """
    if not (isinstance(obj, PatternLike) and callable(obj.evaluate)):
        raise InputError(
            f"pattern: expected an object with .nodes and .evaluate(node, az, el), got {type(obj).__name__}"
        )


def select_nodes(pattern_like: PatternLike, nodes: Sequence[str] | None) -> list[str]:
    """The nodes to export: ``nodes`` (checked against the pattern's), or all of them.

    Raises
    ------
    InputError
        (``param="nodes"``) naming the unknown nodes and the known ones.
    """
    known = [str(n) for n in pattern_like.nodes]
    if nodes is None:
        return known
    wanted = [str(n) for n in nodes]
    unknown = [n for n in wanted if n not in known]
    if unknown:
        raise InputError(
            f"nodes: unknown {', '.join(unknown)}; the pattern knows {', '.join(known)}",
            param="nodes",
        )
    return wanted


# -- regular grid CSV ----------------------------------------------------------------------


#: Finest grid step [deg]: 3,600 x 1,801 directions per node.
MIN_GRID_STEP_DEG = 0.1


def grid_angles_deg(step_deg: float) -> tuple[FloatArray, FloatArray]:
    """Azimuths [-180, 180) and elevations [-90, 90] (both ends) of a regular grid [deg].

    Raises :class:`InputError` unless ``step_deg`` divides 180.
    """
    step = float(step_deg)
    if not math.isfinite(step) or step < MIN_GRID_STEP_DEG or step > 180:
        raise InputError(
            f"step_deg: expected a step in [{MIN_GRID_STEP_DEG}, 180] deg (finer grids do not fit in memory), got {step_deg}",
            param="step_deg",
        )
    n_half = round(180.0 / step)
    if abs(n_half * step - 180.0) > 1e-9 * 180.0:
        raise InputError(
            f"step_deg: {step_deg} does not divide 180 deg (try 1, 2, 2.5, 5, 10)", param="step_deg"
        )
    az = np.asarray(-180.0 + step * np.arange(2 * n_half), np.float64)
    el = np.asarray(-90.0 + step * np.arange(n_half + 1), np.float64)
    return az, el


@check_types
def export_grid(
    model_or_truth: Any,
    step_deg: float,
    path: str | os.PathLike[str] | None,
    nodes: Sequence[str] | None = None,
) -> pd.DataFrame:
    """Gain of every node on a regular az-el grid, as a CSV file and a DataFrame.

    Parameters
    ----------
    model_or_truth : pattern-like
        ``PatternSet`` or ``GroundTruth``.
    step_deg : float
        Grid step [deg]; must divide 180. Azimuth runs over [-180, 180) (end excluded, it
        equals -180), elevation over [-90, 90] (both ends).
    path : path or None
        CSV file to write (columns ``node, az_deg, el_deg, gain_db``); None writes nothing.
    nodes : sequence of str, optional
        Nodes to export (default all).

    Returns
    -------
    DataFrame
        Rows ordered by node, elevation, azimuth; ``gain_db`` [dBi] equals
        ``evaluate(node, radians(az_deg), radians(el_deg))``.
    """
    check_pattern_like(model_or_truth)
    az, el = grid_angles_deg(step_deg)
    el_g, az_g = np.meshgrid(el, az, indexing="ij")
    az_flat, el_flat = az_g.ravel(), el_g.ravel()
    parts = []
    for n in select_nodes(model_or_truth, nodes):
        g = np.asarray(
            model_or_truth.evaluate(n, np.radians(az_flat), np.radians(el_flat)), np.float64
        ).ravel()
        parts.append(pd.DataFrame({"node": n, "az_deg": az_flat, "el_deg": el_flat, "gain_db": g}))
    df = pd.concat(parts, ignore_index=True)
    if path is not None:
        with atomic_path(path) as tmp:
            df.to_csv(tmp, index=False, float_format="%.10g")
    return df


# -- file names ------------------------------------------------------------------------------
@check_types
def safe_file_name(name: str, fallback: str = "node") -> str:
    """A node id as a file name: characters other than letters, digits and ``_.-`` become ``_``
    (so an id never names a path outside the output folder)."""
    safe = re.sub(r"[^A-Za-z0-9_.-]+", "_", str(name)).strip(".")
    return safe or fallback


@check_types
def node_file_names(nodes: Sequence[str]) -> dict[str, str]:
    """Node id -> file name (:func:`safe_file_name`) for every node; two nodes whose ids give
    the same name are refused rather than one file overwriting the other."""
    names: dict[str, str] = {}
    for node in nodes:
        name = safe_file_name(node)
        clash = next((other for other, taken in names.items() if taken == name), None)
        if clash is not None:
            raise InputError(
                f"nodes {clash!r} and {node!r} would both be written as {name!r}; rename one",
                param="nodes",
            )
        names[node] = name
    return names
