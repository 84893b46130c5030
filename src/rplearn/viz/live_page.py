"""The self-refreshing page of ``rplearn live --html``: the live view's numbers, each node's
coverage map (angle to the nearest learning direction) and own-pattern spread map, as one
HTML file with its figures embedded (PNG, base64), rewritten atomically at every refit."""

from __future__ import annotations

import base64
import html
import io
from collections.abc import Sequence
from typing import Any

import numpy as np

from rplearn._argtypes import check_types
from rplearn._atomic import atomic_open
from rplearn.core.coverage import COVERED_WITHIN_DEG, coverage_at
from rplearn.models.patterns import PatternSet
from rplearn.viz.plot import DPI, az_el_grid_deg, new_figure, spread_maps_figure, style_az_el_axes


def _png(fig: Any) -> str:
    buf = io.BytesIO()
    fig.savefig(buf, dpi=DPI, format="png")
    return base64.b64encode(buf.getvalue()).decode("ascii")


@check_types
def coverage_maps_figure(model: PatternSet, step_deg: float = 3.0) -> Any:
    """Per node, the angle [deg] from every direction to the nearest learning direction (the
    coverage grid a model stores), directions within :data:`COVERED_WITHIN_DEG` outlined."""
    grids = model.training.coverage_deg or {}
    nodes = [str(n) for n in model.nodes if str(n) in grids]
    az, el = az_el_grid_deg(step_deg)
    azg, elg = np.meshgrid(np.radians(az), np.radians(el))
    fig = new_figure(3.6 * max(len(nodes), 1) + 0.6, 3.2)
    axes = fig.subplots(1, max(len(nodes), 1), squeeze=False)[0]
    im = None
    for ax, node in zip(axes, nodes):
        angle = coverage_at(grids[node], azg.ravel(), elg.ravel()).reshape(azg.shape)
        im = ax.pcolormesh(az, el, angle, cmap="viridis_r", vmin=0.0, vmax=90.0, shading="nearest", rasterized=True)
        ax.contour(az, el, angle, levels=[COVERED_WITHIN_DEG], colors="white", linewidths=0.8)
        style_az_el_axes(ax)
        ax.set_title(f"node {node}: {100 * np.mean(angle <= COVERED_WITHIN_DEG):.0f}% of the map within "
                     f"{COVERED_WITHIN_DEG:g} deg", fontsize=8)
    if im is not None:
        fig.colorbar(im, ax=list(axes), orientation="horizontal", fraction=0.06, aspect=40).set_label(
            "angle to the nearest learning direction / deg")
    return fig


@check_types
def write_live_page(path: str, title: str, rows: Sequence[tuple[str, str]], node_rows: Sequence[Sequence[str]],
                    model: PatternSet | None = None, refresh_s: float = 2.0, spread_known: bool = True) -> str:
    """Write the page atomically and return its path.

    Parameters
    ----------
    path : str
    title : str
    rows : sequence of (label, value)
        The session's numbers.
    node_rows : sequence of rows
        A header row then one row per node (texts).
    model : PatternSet, optional
        The current model, for its coverage and spread maps (none before the first refit).
    refresh_s : float
        The browser reloads the page every this many seconds.
    spread_known : bool
        False: the model's spread is not one the data give (a fit at the search's largest smoothing,
        :mod:`rplearn.workflows.live`): said instead of the spread maps.
    """
    esc = html.escape
    parts = [f"<!doctype html><html><head><meta charset='utf-8'><meta http-equiv='refresh' content='{refresh_s:g}'>",
             f"<title>{esc(title)}</title><style>body{{font-family:sans-serif;margin:1em}}td,th{{padding:2px 8px;"
             "text-align:left}}img{{max-width:100%}}</style></head><body>", f"<h1>{esc(title)}</h1><table>"]
    parts += [f"<tr><th>{esc(k)}</th><td>{esc(v)}</td></tr>" for k, v in rows]
    parts.append("</table>")
    if node_rows:
        head, *body = node_rows
        parts.append("<h2>Nodes</h2><table><tr>" + "".join(f"<th>{esc(h)}</th>" for h in head) + "</tr>")
        parts += ["<tr>" + "".join(f"<td>{esc(c)}</td>" for c in r) + "</tr>" for r in body]
        parts.append("</table>")
    if model is not None and getattr(model, "covariance", None) is not None:
        parts.append(f"<h2>Coverage</h2><img alt='coverage maps' src='data:image/png;base64,{_png(coverage_maps_figure(model))}'>")
        parts.append(f"<h2>Pattern spread</h2><img alt='spread maps' src='data:image/png;base64,"
                     f"{_png(spread_maps_figure({'live': model}))}'>" if spread_known else
                     "<h2>Pattern spread</h2><p>Not known yet: the fit took the largest smoothing the search tries "
                     "(the data do not yet tell the patterns' shape from flat).</p>")
    parts.append("</body></html>\n")
    with atomic_open(path) as fh:
        fh.write("".join(parts))
    return path


__all__ = ["coverage_maps_figure", "write_live_page"]
