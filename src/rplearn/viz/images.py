"""3-D pattern images of pattern-likes (:class:`rplearn.io.export.PatternLike`), one per node."""

from __future__ import annotations

import os
from collections.abc import Sequence
from typing import Any

from rplearn._argtypes import check_types
from rplearn.io.export import check_pattern_like, node_file_names, select_nodes
from rplearn.viz import plot


@check_types
def export_pattern_images(
    pattern_like: Any,
    out_dir: str | os.PathLike[str],
    nodes: Sequence[str] | None = None,
    step_deg: float = 3.0,
) -> list[str]:
    """One 3-D pattern image per node, ``<out_dir>/pattern_<node>.png``.

    Parameters
    ----------
    pattern_like : pattern-like
    out_dir : path
        Directory (created if needed).
    nodes : sequence of str, optional
        Default all nodes.
    step_deg : float
        Grid step of the surface [deg].

    Returns
    -------
    list of str
        The paths written, in node order (characters other than letters, digits, ``_.-``
        in a node id become ``_`` in the file name).
    """
    check_pattern_like(pattern_like)
    names = node_file_names(select_nodes(pattern_like, nodes))
    out_dir = os.fspath(out_dir)
    os.makedirs(out_dir, exist_ok=True)
    paths = []
    for n, safe in names.items():
        paths.append(
            plot.plot_pattern_3d(
                pattern_like, n, os.path.join(out_dir, f"pattern_{safe}.png"), step_deg
            )
        )
    return paths
