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
in dark grey, as a stipple over the surface. There the model extrapolates, so the surface is
never drawn at full strength (:func:`supported_gain_db`): it fades from the model's gain to the
node's prior level (the median gain where the flight looked) between 10 and
``FADE_END_DEG`` from the nearest learning direction, is drawn faded (grey, translucent), and
never above the largest gain the covered directions support. The hover text gives the model's
own gain, its spread and the learning samples within 10 deg.
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
#: Beyond this angle from every learning direction [deg] an uncovered direction is drawn at the
#: node's prior level; from ``UNCOVERED_DEG`` to here the drawn gain fades to it.
FADE_END_DEG = 25.0
#: Opacity of the faded (uncovered) part of a 3-D surface.
FADED_OPACITY = 0.45


@check_types
@dataclass(frozen=True)
class SupportedGain:
    """A pattern on a grid as the report draws it (see :func:`supported_gain_db`).

    Attributes
    ----------
    drawn_db : ndarray
        The gain drawn [dB]: the model's where covered, faded to ``prior_db`` beyond, never
        above ``support_max_db``.
    coverage_deg : ndarray
        Angle to the nearest learning direction [deg].
    prior_db : float
        The node's prior level: the median model gain over the covered grid points [dB].
    support_max_db : float
        The largest model gain over the covered grid points [dB].
    """

    drawn_db: np.ndarray
    coverage_deg: np.ndarray
    prior_db: float
    support_max_db: float


@check_types
def supported_gain_db(gain_db: np.ndarray, coverage_deg: np.ndarray, within_deg: float = 10.0,
                      fade_end_deg: float = FADE_END_DEG) -> SupportedGain | None:
    """The gain a figure may draw: the model's within ``within_deg`` of a learning direction,
    beyond it a blend toward the prior level that reaches it at ``fade_end_deg``, capped at the
    largest covered gain (no extrapolated lobe stands out). None when no grid point is covered."""
    g = np.asarray(gain_db, np.float64)
    c = np.asarray(coverage_deg, np.float64)
    covered = c <= within_deg
    if not covered.any():
        return None
    prior = float(np.median(g[covered]))
    top = float(np.max(g[covered]))
    w = np.clip((fade_end_deg - c) / max(fade_end_deg - within_deg, 1e-9), 0.0, 1.0)
    drawn = np.where(covered, g, np.minimum(w * g + (1.0 - w) * prior, top))
    return SupportedGain(drawn, c, prior, top)


def _radius_xyz(gain_db: np.ndarray, az_deg: np.ndarray, el_deg: np.ndarray,
                dynamic_range_db: float) -> tuple[float, float, np.ndarray, np.ndarray, np.ndarray]:
    """Floor, top and the surface (x, y, z) of a gain grid, as :func:`rplearn.viz.plot.pattern_surface`."""
    g_max = float(np.nanmax(gain_db))
    floor = max(float(np.nanmin(gain_db)), g_max - dynamic_range_db)
    r = np.clip(gain_db - floor, 0.0, None) + 0.05 * max(g_max - floor, 20.0)
    az, el = np.meshgrid(np.radians(az_deg), np.radians(el_deg))
    return floor, g_max, r * np.cos(el) * np.cos(az), r * np.cos(el) * np.sin(az), r * np.sin(el)


@check_types
def samples_nearby(az_deg: np.ndarray, el_deg: np.ndarray, learn_az_rad: np.ndarray, learn_el_rad: np.ndarray,
                   within_deg: float = 10.0) -> np.ndarray:
    """Number of learning directions within ``within_deg`` of every grid point (az x el mesh)."""
    from scipy.spatial import cKDTree

    def unit(az: np.ndarray, el: np.ndarray) -> np.ndarray:
        return np.stack([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)], axis=-1)

    az, el = np.meshgrid(np.radians(az_deg), np.radians(el_deg))
    tree = cKDTree(unit(np.asarray(learn_az_rad, np.float64).ravel(), np.asarray(learn_el_rad, np.float64).ravel()))
    chord = 2.0 * np.sin(np.radians(within_deg) / 2.0)
    return np.asarray(tree.query_ball_point(unit(az, el).reshape(-1, 3), chord, return_length=True)).reshape(az.shape)


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


@check_types
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
    directions: tuple[Any, Any] | None = None,
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
    directions : pair of arrays, optional
        The node's learning directions (az, el) [rad]: the hover text then counts the samples
        within 10 deg of each point.

    Returns
    -------
    plotly.graph_objects.Figure
        The surface (radius and colour = gain, colour bar in dBi or, centred, in dB relative
        to the sphere mean), the body axes (x, y, z arrows), and, for a
        model that stores its coverage, dark grey dots over the directions further than 10 deg
        from every learning direction (in the legend), where the surface is drawn faded, at
        most at the largest covered gain (:func:`supported_gain_db`): the first trace is the
        covered part (NaN elsewhere), the second the faded part.
    """
    import plotly.graph_objects as go

    from rplearn.models.predict import UNCOVERED_DEG
    from rplearn.viz.plot import pattern_surface, uncovered_directions

    s = pattern_surface(pattern_like, node, step_deg, dynamic_range_db, center)
    unit = "dB rel. sphere mean" if center else "dBi"
    az_g, el_g = np.meshgrid(s.az_deg, s.el_deg)
    coverage = (pattern_like.coverage_deg(node, np.radians(az_g), np.radians(el_g))
                if hasattr(pattern_like, "coverage_deg") else None)
    support = None if coverage is None else supported_gain_db(s.gain_db, np.asarray(coverage).reshape(s.gain_db.shape))
    drawn = s.gain_db if support is None else support.drawn_db
    floor, top, xs, ys, zs = _radius_xyz(drawn, s.az_deg, s.el_deg, dynamic_range_db)
    spread = (np.asarray(pattern_like.standard_error(node, np.radians(az_g), np.radians(el_g)), np.float64).reshape(az_g.shape)
              if getattr(pattern_like, "covariance", None) is not None else np.full(s.gain_db.shape, np.nan))
    nearby = (samples_nearby(s.az_deg, s.el_deg, *directions) if directions is not None
              else np.full(s.gain_db.shape, -1))
    # The axes are hidden, so the surface may be drawn in any unit: the largest radius at _INT_RADIUS.
    scale = _INT_RADIUS / max(float(np.nanmax(np.sqrt(xs**2 + ys**2 + zs**2))), 1e-9)
    x, y, z = (np.rint(c * scale).astype(np.float32) for c in (xs, ys, zs))
    custom = np.stack([az_g, el_g, s.gain_db, spread, nearby], axis=-1).astype(np.float32)
    hover = ("az %{customdata[0]:.0f}°, el %{customdata[1]:.0f}°<br>"
             f"model gain %{{customdata[2]:.1f}} {unit}, spread ±%{{customdata[3]:.1f}} dB (1σ)<br>"
             + ("%{customdata[4]:.0f} learning samples within 10°<br>" if directions is not None else "")
             + f"drawn %{{surfacecolor:.1f}} {unit}<extra></extra>")
    common = {"customdata": custom, "hovertemplate": hover, "cmin": floor, "cmax": max(top, floor + 1.0),
              "lighting": {"ambient": 0.75, "diffuse": 0.45, "specular": 0.05, "roughness": 0.9}}
    if support is None:
        covered = np.ones(drawn.shape, bool)
    else:  # one grid step of overlap, so that the two parts join without a gap
        covered = support.coverage_deg <= UNCOVERED_DEG
        grown = covered.copy()
        grown[1:] |= covered[:-1]
        grown[:-1] |= covered[1:]
        grown[:, 1:] |= covered[:, :-1]
        grown[:, :-1] |= covered[:, 1:]
        covered = grown

    def part(mask: np.ndarray) -> tuple[np.ndarray, ...]:
        return tuple(np.where(mask, a, np.nan).astype(np.float32) for a in (x, y, z, drawn))

    cx, cy, cz, cc = part(covered)
    traces = [
        go.Surface(
            x=cx, y=cy, z=cz, surfacecolor=cc, colorscale="Viridis",
            colorbar={"title": {"text": f"gain / {unit}", "side": "right"}, "len": 0.8, "thickness": 14, "x": 1.0},
            name=html.escape(f"node {node}"), showlegend=False, **common,
        )
    ]
    if support is not None and not covered.all():
        fx, fy, fz, fc = part(~(support.coverage_deg <= UNCOVERED_DEG))
        traces.append(go.Surface(
            x=fx, y=fy, z=fz, surfacecolor=fc, colorscale="Greys", reversescale=True, showscale=False,
            opacity=FADED_OPACITY, name=f"not covered: faded to {support.prior_db:.1f} {unit}", showlegend=False,
            **common,
        ))
    far = uncovered_directions(pattern_like, node, s.az_deg, s.el_deg)
    if far is not None and far.any():
        i, j = _stipple(far, s.el_deg, step_deg)
        lift = _DOT_LIFT * scale  # just outside the surface, so that the dots are not hidden in it
        traces.append(
            go.Scatter3d(
                x=(xs[i, j] * lift).astype(np.float32), y=(ys[i, j] * lift).astype(np.float32),
                z=(zs[i, j] * lift).astype(np.float32), mode="markers",
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


@check_types
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
    directions: tuple[Any, Any] | None = None,
) -> InteractiveFigure:
    """:func:`pattern_3d_plotly` as a captioned :class:`InteractiveFigure` for the report."""
    from rplearn.models.predict import UNCOVERED_DEG

    fig = pattern_3d_plotly(pattern_like, node, label, step_deg, dynamic_range_db, center, directions=directions)
    dotted = any(t.type == "scatter3d" and t.showlegend for t in fig.data)
    name = f"{label}, node {node}" if label else f"Node {node}"
    floor = fig.data[0].cmin
    unit = "dB relative to its sphere mean" if center else "dBi"
    caption = (
        f"{name}: learned pattern in the body frame (x forward, y left, z up); radius and colour = gain in "
        f"{unit} (radius from a floor of {floor:.1f} {'dB' if center else 'dBi'}, at most {dynamic_range_db:g} dB "
        "below the peak)"
        + (f"; dark grey dots: directions more than {UNCOVERED_DEG:g}° from every learning direction (not "
           f"covered by the data), drawn faded toward the pattern's median covered gain (reached {FADE_END_DEG:g}° "
           "out) and never above its largest covered gain: the model there is an extrapolation" if dotted else "")
        + "; hover for the model's gain, its spread" + (" and the learning samples nearby" if directions is not None else "")
        + ". Drag to rotate, scroll to zoom."
    )
    return figure_html(fig, caption)


@check_types
def pattern_3d_figures(
    models: Mapping[str, Any],
    nodes: Sequence[str] | None = None,
    center: bool = False,
    max_figures: int = MAX_3D_FIGURES,
    directions: Mapping[str, tuple[Any, Any]] | None = None,
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
    figures = [pattern_3d_html(m, n, label, center, directions=None if directions is None else directions.get(n))
               for label, m, n in pairs[:max_figures]]
    if not figures:
        return [], ""
    text = ("Each learned pattern in 3-D (drag to rotate, scroll to zoom): radius and colour are the gain, the "
            "arrows the drone's body axes (x forward, y left, z up)")
    if any("dark grey dots" in f.caption for f in figures):
        text += (", and dark grey dots mark the directions the learning samples never looked at (hatched on the maps), "
                 "where the surface is faded: the model extrapolates there")
    text += "."
    if len(pairs) > max_figures:
        text += (f" Shown: the first {max_figures} of {len(pairs)} node patterns (a browser draws about 16 3-D "
                 "figures per page); the maps show them all.")
    return figures, text


__all__ = [
    "FADE_END_DEG",
    "FIGURE_HEIGHT_PX",
    "MAX_3D_FIGURES",
    "InteractiveFigure",
    "SupportedGain",
    "figure_html",
    "pattern_3d_figures",
    "pattern_3d_html",
    "pattern_3d_plotly",
    "plotly_library_script",
    "samples_nearby",
    "supported_gain_db",
]
