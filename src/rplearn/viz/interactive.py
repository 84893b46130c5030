"""Interactive figures for the HTML report: learned patterns as rotatable 3-D surfaces (plotly).

An :class:`InteractiveFigure` is an HTML fragment (a ``<div>`` and the ``<script>`` that draws
into it) without the plotting library: :func:`rplearn.viz.report.write_report` embeds
plotly.js once per report (:func:`plotly_library_script`), so that the report stays one file
that opens offline, however many figures it holds. plotly is imported inside the functions that
use it, so that importing this module (or ``rplearn``) costs nothing.

The 3-D view of a pattern (:func:`pattern_3d_plotly`) is the surface of
:func:`rplearn.viz.plot.pattern_surface`: radius and colour are the gain, in the node's body
frame (FLU: x forward, y left, z up, drawn as labelled arrows); directions further than
``UNCOVERED_DEG`` (10 deg) from every direction the node was learned from
(:func:`rplearn.viz.plot.uncovered_directions`, the hatched areas of the 2-D maps) are dotted
in dark grey, as a stipple over the surface.
"""

from __future__ import annotations

import html
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from rplearn._argtypes import check_types
from rplearn.errors import InputError

#: Height of one 3-D figure in the report [px].
FIGURE_HEIGHT_PX = 480
#: Most 3-D figures in one report: browsers keep about 16 WebGL contexts per page (Chromium),
#: one per figure; beyond that the oldest figures go blank.
MAX_3D_FIGURES = 12
#: Colours of the body axes x (forward), y (left), z (up), and of the dots on uncovered directions.
AXIS_COLOURS = ("#d62728", "#2ca02c", "#1f77b4")
DOT_COLOUR = "#333333"
#: Direction of the camera in the body frame (azimuth, elevation) [deg]: in front of the drone
#: and to its left, above it, so that the x, y and z arrows all point towards the viewer.
CAMERA_AZ_EL_DEG = (45.0, 30.0)
#: Spacing of the dots on uncovered directions [deg] (as the hatching of the 2-D maps).
STIPPLE_DEG = 6.0
_FONT = "DejaVu Sans, Arial, Helvetica, sans-serif"
_INT_RADIUS = 30000
_DOT_LIFT = 1.015


@check_types
@dataclass(frozen=True)
class InteractiveFigure:
    """An HTML figure for :class:`rplearn.viz.report.ReportSection` (``interactive``).

    Attributes
    ----------
    html : str
        A fragment (``<div>`` and ``<script>``) that draws the figure with plotly.js, which the
        report embeds once; no ``<html>`` wrapper and no library.
    caption : str
        Markdown subset (see :mod:`rplearn.viz.report`).
    height_px : int
        Height of the figure on the page [px].
    """

    html: str
    caption: str
    height_px: int = FIGURE_HEIGHT_PX


def plotly_library_script() -> str:
    """plotly.js (from the installed ``plotly`` package) in one inline ``<script>`` element."""
    from plotly.offline import get_plotlyjs

    js = get_plotlyjs().replace("</script", "<\\/script")  # never close the element early
    return f'<script type="text/javascript">{js}</script>'


def _axis_traces(length: float, go: Any) -> list[Any]:
    """Body axes as lines from the origin, labelled at their tips, with cone arrowheads."""
    traces = []
    for k, (name, colour) in enumerate(zip(("x forward", "y left", "z up"), AXIS_COLOURS)):
        tip = np.zeros(3)
        tip[k] = length
        traces.append(
            go.Scatter3d(
                x=[0.0, tip[0]], y=[0.0, tip[1]], z=[0.0, tip[2]], mode="lines+text",
                line={"color": colour, "width": 6}, text=["", f"<b>{name}</b>"],
                textposition="top center", textfont={"color": colour, "size": 14},
                hoverinfo="skip", showlegend=False, name=name,
            )
        )
        head = np.zeros(3)
        head[k] = 0.12 * length
        traces.append(
            go.Cone(
                x=[tip[0]], y=[tip[1]], z=[tip[2]], u=[head[0]], v=[head[1]], w=[head[2]],
                anchor="tip", sizemode="absolute", sizeref=0.1 * length, showscale=False,
                colorscale=[[0, colour], [1, colour]], hoverinfo="skip", showlegend=False, name=name,
            )
        )
    return traces


def _stipple(far: np.ndarray, el_deg: np.ndarray, step_deg: float) -> tuple[np.ndarray, np.ndarray]:
    """Row and column indices of the uncovered grid points that carry a dot: about
    ``STIPPLE_DEG`` apart on the sphere (fewer along a parallel near the poles), once per
    direction (the last column repeats the first)."""
    stride = max(1, round(STIPPLE_DEG / step_deg))
    rows, cols = [], []
    for i in range(0, far.shape[0], stride):
        c = np.cos(np.radians(el_deg[i]))
        along = far.shape[1] - 1 if c < 1e-6 else max(stride, round(stride / c))
        j = np.arange(0, far.shape[1] - 1, along)
        j = j[far[i, j]]
        rows.append(np.full(j.size, i))
        cols.append(j)
    return np.concatenate(rows), np.concatenate(cols)


@check_types
def pattern_3d_plotly(
    pattern_like: Any,
    node: str,
    label: str | None = None,
    step_deg: float = 3.0,
    dynamic_range_db: float = 40.0,
    center: bool = False,
    height_px: int = FIGURE_HEIGHT_PX,
) -> Any:
    """One node's pattern as a rotatable 3-D surface (a ``plotly.graph_objects.Figure``).

    Parameters
    ----------
    pattern_like : pattern-like
        ``PatternSet`` or anything with ``nodes`` and ``evaluate(node, az, el)`` [dB].
    node : str
    label : str, optional
        Model label in the title (e.g. ``SH-10``).
    step_deg : float
        Grid step [deg].
    dynamic_range_db : float
        The radius floor is this far below the maximum gain [dB] (or at the minimum).
    center : bool
        Gains relative to the sphere mean (two-node fits identify shapes only).
    height_px : int
        Figure height [px]; the width follows the page.

    Returns
    -------
    plotly.graph_objects.Figure
        The surface (radius and colour = gain, colour bar in dBi or, centred, in dB relative
        to the sphere mean), the body axes (x, y, z arrows), and, for a
        model that stores its coverage, dark grey dots over the directions further than 10 deg
        from every learning direction (in the legend).
    """
    import plotly.graph_objects as go

    from rplearn.models.predict import UNCOVERED_DEG
    from rplearn.viz.plot import pattern_surface, uncovered_directions

    s = pattern_surface(pattern_like, node, step_deg, dynamic_range_db, center)
    unit = "dB rel. sphere mean" if center else "dBi"
    # The axes are hidden, so the surface may be drawn in any unit: 16-bit integers (the figure's
    # arrays travel as base64 in the page) with the largest radius at _INT_RADIUS.
    scale = _INT_RADIUS / max(s.radius_max, 1e-9)
    x, y, z = (np.rint(c * scale).astype(np.int16) for c in (s.x, s.y, s.z))
    az_g, el_g = np.meshgrid(s.az_deg, s.el_deg)
    hover = ("az %{customdata[0]}°, el %{customdata[1]}°<br>"
             f"gain %{{surfacecolor:.1f}} {unit}<extra></extra>")
    traces = [
        go.Surface(
            x=x, y=y, z=z, surfacecolor=s.gain_db.astype(np.float32),
            customdata=np.rint(np.stack([az_g, el_g], axis=-1)).astype(np.int16), hovertemplate=hover,
            colorscale="Viridis", cmin=s.floor_db, cmax=max(s.max_db, s.floor_db + 1.0),
            colorbar={"title": {"text": f"gain / {unit}", "side": "right"}, "len": 0.8, "thickness": 14, "x": 1.0},
            lighting={"ambient": 0.75, "diffuse": 0.45, "specular": 0.05, "roughness": 0.9},
            name=html.escape(f"node {node}"), showlegend=False,
        )
    ]
    far = uncovered_directions(pattern_like, node, s.az_deg, s.el_deg)
    if far is not None and far.any():
        i, j = _stipple(far, s.el_deg, step_deg)
        lift = _DOT_LIFT * scale  # just outside the surface, so that the dots are not hidden in it
        traces.append(
            go.Scatter3d(
                x=(s.x[i, j] * lift).astype(np.float32), y=(s.y[i, j] * lift).astype(np.float32),
                z=(s.z[i, j] * lift).astype(np.float32), mode="markers",
                marker={"size": 2.2, "color": DOT_COLOUR, "opacity": 0.9}, hoverinfo="skip",
                name=f"not covered: > {UNCOVERED_DEG:g}° from every learning direction", showlegend=True,
            )
        )
    length = 1.2 * _INT_RADIUS
    traces += _axis_traces(length, go)
    hidden = {"visible": False, "range": [-1.05 * length, 1.05 * length]}
    az, el = np.radians(CAMERA_AZ_EL_DEG)
    eye = 1.6 * np.array([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)])
    # plotly reads text as a subset of HTML: names from logs are shown as they are, never as markup
    title = html.escape(f"{label}: node {node}" if label else f"node {node}")
    fig = go.Figure(traces)
    fig.update_layout(
        template="none", height=int(height_px), autosize=True,
        font={"family": _FONT, "size": 12, "color": "#222"},
        title={"text": title, "x": 0.02, "y": 0.97, "font": {"size": 15}},
        margin={"l": 0, "r": 0, "t": 36, "b": 0},
        scene={"xaxis": hidden, "yaxis": hidden, "zaxis": hidden, "aspectmode": "cube",
               "camera": {"eye": dict(zip("xyz", (float(v) for v in eye))), "up": {"x": 0, "y": 0, "z": 1}},
               "domain": {"x": [0.0, 0.86], "y": [0.0, 1.0]}},
        legend={"x": 0.01, "y": 0.01, "xanchor": "left", "yanchor": "bottom", "bgcolor": "rgba(255,255,255,0.7)",
                "itemsizing": "constant"},
        paper_bgcolor="white",
    )
    return fig


def figure_html(fig: Any, caption: str, height_px: int = FIGURE_HEIGHT_PX) -> InteractiveFigure:
    """A plotly figure as an :class:`InteractiveFigure` (no library, no MathJax, no network)."""
    import plotly.io as pio

    fragment = pio.to_html(
        fig, include_plotlyjs=False, include_mathjax=False, full_html=False,
        default_width="100%", default_height=f"{int(height_px)}px",
        config={"displaylogo": False, "responsive": True},
    )
    return InteractiveFigure(fragment, caption, int(height_px))


@check_types
def pattern_3d_html(
    pattern_like: Any,
    node: str,
    label: str | None = None,
    center: bool = False,
    step_deg: float = 3.0,
    dynamic_range_db: float = 40.0,
) -> InteractiveFigure:
    """:func:`pattern_3d_plotly` as a captioned :class:`InteractiveFigure` for the report."""
    from rplearn.models.predict import UNCOVERED_DEG

    fig = pattern_3d_plotly(pattern_like, node, label, step_deg, dynamic_range_db, center)
    dotted = any(t.type == "scatter3d" and t.showlegend for t in fig.data)
    name = f"{label}, node {node}" if label else f"Node {node}"
    floor = fig.data[0].cmin
    unit = "dB relative to its sphere mean" if center else "dBi"
    caption = (
        f"{name}: learned pattern in the body frame (x forward, y left, z up); radius and colour = gain in "
        f"{unit} (radius from a floor of {floor:.1f} {'dB' if center else 'dBi'}, at most {dynamic_range_db:g} dB "
        "below the peak)"
        + (f"; dark grey dots: directions more than {UNCOVERED_DEG:g}° from every learning direction (not "
           "covered by the data)" if dotted else "")
        + ". Drag to rotate, scroll to zoom."
    )
    return figure_html(fig, caption)


@check_types
def pattern_3d_figures(
    models: Mapping[str, Any],
    nodes: Sequence[str] | None = None,
    center: bool = False,
    max_figures: int = MAX_3D_FIGURES,
) -> tuple[list[InteractiveFigure], str]:
    """3-D views of every (model, node) pattern, at most ``max_figures``, and the paragraph that
    introduces them in a report.

    Returns
    -------
    figures : list of InteractiveFigure
        Model by model, node by node.
    text : str
        How to read the figures (what the dots mark, when a figure has any) and which patterns
        were left out (over ``max_figures``); empty without figures.
    """
    if max_figures < 1:
        raise InputError(f"max_figures: expected at least 1, got {max_figures}", param="max_figures")
    pairs = [(label, m, str(n)) for label, m in models.items() for n in (nodes if nodes is not None else m.nodes)]
    figures = [pattern_3d_html(m, n, label, center) for label, m, n in pairs[:max_figures]]
    if not figures:
        return [], ""
    text = ("Each learned pattern in 3-D (drag to rotate, scroll to zoom): radius and colour are the gain, the "
            "arrows the drone's body axes (x forward, y left, z up)")
    if any("dark grey dots" in f.caption for f in figures):
        text += ", and dark grey dots mark the directions the learning samples never looked at (hatched on the maps)"
    text += "."
    if len(pairs) > max_figures:
        text += (f" Shown: the first {max_figures} of {len(pairs)} node patterns (a browser draws about 16 3-D "
                 "figures per page); the maps show them all.")
    return figures, text


__all__ = [
    "FIGURE_HEIGHT_PX",
    "MAX_3D_FIGURES",
    "InteractiveFigure",
    "figure_html",
    "pattern_3d_figures",
    "pattern_3d_html",
    "pattern_3d_plotly",
    "plotly_library_script",
]
