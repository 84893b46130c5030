"""Figures about one learned model on its dataset: what a radio engineer looks at first.

- :func:`prediction_time_figure`: measured and predicted RSSI over time, one panel per unit
  (flight or stretch of time), with the 90 % band of a new packet's RSSI, learning and
  held-out samples marked;
- :func:`residuals_figure`: the residual (measured minus predicted) against distance and
  against each end's elevation and azimuth in its body frame, as binned median and spread;
- :func:`polar_cuts_figure`: each node's pattern cut at 0 deg elevation (the usual antenna
  plot) and at the elevation the flight covered most, with the 90 % band of the pattern's
  own spread, the directions the flight never covered dotted.

Each ``plot_*`` writes the PNG with its caption (:func:`rplearn.viz.plot.save_figure`).
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from typing import Any

import numpy as np
from matplotlib.figure import Figure
from numpy.typing import ArrayLike

from rplearn._argtypes import check_types
from rplearn.errors import InputError
from rplearn.viz.plot import dot_size, new_figure, save_figure, subsample_indices

#: The two-sided 90 % band of a normal spread: +- this many standard deviations.
Z90 = 1.6448536269514722
#: Most panels of the time-series figure (held-out units first, then learning ones in order).
MAX_TIME_PANELS = 6
#: A direction within this angle of a learning direction is covered [deg] (as the maps' hatching).
COVERED_DEG = 10.0
LEARN_COLOUR = "tab:blue"
HELD_OUT_COLOUR = "tab:red"


def _arrays(*values: ArrayLike, names: Sequence[str]) -> list[np.ndarray]:
    out = [np.asarray(v, np.float64).ravel() for v in values]
    if len({a.size for a in out}) != 1 or out[0].size == 0:
        raise InputError(f"{', '.join(names)}: expected equal, non-empty arrays, got sizes {[a.size for a in out]}")
    return out


@check_types
def panel_units(units: Sequence[str], held_out: Sequence[str], max_panels: int = MAX_TIME_PANELS) -> list[str]:
    """Units drawn as panels: every held-out one (up to ``max_panels``), then learning ones in
    the order of first appearance."""
    order = list(dict.fromkeys(str(u) for u in units))
    test = [u for u in order if u in set(map(str, held_out))]
    learn = [u for u in order if u not in set(test)]
    chosen = test[:max_panels]
    chosen += learn[: max(0, max_panels - len(chosen))]
    return [u for u in order if u in set(chosen)]


@check_types
def prediction_time_figure(
    t_s: ArrayLike,
    measured_dbm: ArrayLike,
    predicted_dbm: ArrayLike,
    spread_db: ArrayLike | None,
    units: Sequence[str],
    held_out: Sequence[str],
    quantity: str = "RSSI / dBm",
    links: Sequence[str] | None = None,
) -> Figure:
    """Measured and predicted RSSI (or joint gain) over time, one panel per unit (at most
    :data:`MAX_TIME_PANELS`: every held-out unit first, then learning ones).

    Parameters
    ----------
    t_s : array
        Time of each sample relative to the log start [s].
    measured_dbm, predicted_dbm : array
        Measured and predicted value of each sample.
    spread_db : array or None
        Standard deviation of a new packet's value about the prediction [dB] (the model's
        predictive spread with the noise); the band is +- :data:`Z90` of it. None: no band.
    units : sequence of str
        Unit (flight or stretch of time) of each sample.
    held_out : sequence of str
        The units the model did not learn from (drawn in red, the others in blue).
    links : sequence of str, optional
        Link direction of each sample (``"A->B"``): one prediction line and band per direction
        (the two directions of a link may differ by an electronics offset).
    """
    t, y, p = _arrays(t_s, measured_dbm, predicted_dbm, names=("t_s", "measured", "predicted"))
    s = None if spread_db is None else _arrays(spread_db, t_s, names=("spread", "t_s"))[0]
    u = np.asarray([str(v) for v in units])
    if u.size != t.size:
        raise InputError(f"units: expected one label per sample ({t.size}), got {u.size}")
    link = np.asarray([""] * u.size if links is None else [str(v) for v in links])
    if link.size != t.size:
        raise InputError(f"links: expected one label per sample ({t.size}), got {link.size}")
    shown = panel_units(list(u), held_out, MAX_TIME_PANELS)
    test = set(map(str, held_out))
    fig = new_figure(11.0, 2.1 * len(shown) + 0.9)
    axes = fig.subplots(len(shown), 1, squeeze=False)[:, 0]
    for ax, unit in zip(axes, shown):
        sel = np.flatnonzero(u == unit)
        sel = sel[np.argsort(t[sel], kind="stable")]
        colour = HELD_OUT_COLOUR if unit in test else LEARN_COLOUR
        role = "held out" if unit in test else "learning"
        title = f"{unit} ({role}, {sel.size:,} samples)"
        if s is not None:
            inside = float(np.mean(np.abs(y[sel] - p[sel]) <= Z90 * s[sel]))
            title += f"; {inside:.0%} of the measured values inside the 90 % band"
        pick = sel[subsample_indices(sel.size, 6000)]
        ax.scatter(t[pick], y[pick], s=dot_size(pick.size, 1.0, 6.0), color=colour, alpha=0.6, lw=0,
                   label=f"measured ({role})", rasterized=True, zorder=3)
        names = link[sel]
        for k, name in enumerate(dict.fromkeys(names.tolist())):
            one = sel[names == name]
            tag = f" {name}" if name else ""
            if s is not None:
                ax.fill_between(t[one], p[one] - Z90 * s[one], p[one] + Z90 * s[one], color=f"{0.55 + 0.15 * (k % 2):.2f}",
                                alpha=0.3, lw=0, label=f"90 % band{tag}")
            ax.plot(t[one], p[one], color="k", lw=0.9, ls=("-", "--", ":", "-.")[k % 4], label=f"predicted{tag}", zorder=4)
        ax.set_title(title, fontsize=9, loc="left")
        ax.set_ylabel(quantity, fontsize=8)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, loc="upper right", ncols=5)
    axes[-1].set_xlabel("time since the log start / s")
    omitted = len(set(u.tolist())) - len(shown)
    fig.suptitle("Measured and predicted over time" + (f" ({omitted} more units not drawn)" if omitted else ""))
    return fig


@check_types
def plot_prediction_time(path: str | os.PathLike[str], *args: Any, **kwargs: Any) -> str:
    """Write :func:`prediction_time_figure` (same arguments after ``path``); return the path."""
    caption = ("Measured (dots: blue learning, red held out) and predicted (line) received power over time since the "
               "log start, one panel per flight or stretch of time, with the 90 % band of a new packet (the "
               "model's predictive spread and the noise); each title says how many measured values fall inside it.")
    return save_figure(prediction_time_figure(*args, **kwargs), path, caption)


@check_types
def binned_stats(x: np.ndarray, r: np.ndarray, bins: int = 16, min_count: int = 5) -> tuple[np.ndarray, ...]:
    """Centres, median and 10 % / 90 % quantiles of ``r`` in ``bins`` equal-count bins of ``x``
    (bins with fewer than ``min_count`` samples left out)."""
    ok = np.isfinite(x) & np.isfinite(r)
    x, r = x[ok], r[ok]
    if x.size < min_count:
        return (np.empty(0),) * 4
    edges = np.unique(np.quantile(x, np.linspace(0.0, 1.0, bins + 1)))
    idx = np.clip(np.searchsorted(edges, x, side="right") - 1, 0, max(edges.size - 2, 0))
    rows = []
    for k in range(max(edges.size - 1, 1)):
        v = r[idx == k]
        if v.size >= min_count:
            rows.append((float(np.median(x[idx == k])), *np.quantile(v, [0.5, 0.1, 0.9])))
    if not rows:
        return (np.empty(0),) * 4
    return tuple(np.array(c) for c in zip(*rows))


def _binned_panel(ax: Any, x: np.ndarray, r: np.ndarray, colour: str, label: str) -> None:
    c, med, lo, hi = binned_stats(x, r)
    if c.size:
        ax.fill_between(c, lo, hi, color=colour, alpha=0.2, lw=0)
        ax.plot(c, med, "o-", color=colour, ms=3, lw=1.2, label=f"{label}: median, 10-90 %")


@check_types
def residuals_figure(
    residual_db: ArrayLike,
    distance_m: ArrayLike,
    el_deg: tuple[ArrayLike, ArrayLike],
    az_deg: tuple[ArrayLike, ArrayLike],
    held_out: ArrayLike | None = None,
) -> Figure:
    """The residual (measured minus predicted joint gain) against distance, elevation and
    azimuth: binned median and 10-90 % spread, over a faint scatter.

    Parameters
    ----------
    residual_db, distance_m : array
    el_deg, az_deg : pair of arrays
        Elevation and azimuth [deg] of the other end in the transmitter's and in the
        receiver's body frame (the directions each pattern is read at).
    held_out : array of bool, optional
        Samples of held-out units; the median of those is drawn too.
    """
    r, d = _arrays(residual_db, distance_m, names=("residual_db", "distance_m"))
    ends = [_arrays(a, r, names=("direction", "residual"))[0] for a in (*el_deg, *az_deg)]
    test = np.zeros(r.size, bool) if held_out is None else np.asarray(held_out, bool).ravel()
    fig = new_figure(12.0, 3.6)
    axes = fig.subplots(1, 3, sharey=True)
    pick = subsample_indices(r.size, 5000)
    panels = [("distance / m", [(d, "all samples", "tab:green")], True),
              ("elevation in the body frame / deg", [(ends[0], "tx end", "tab:blue"), (ends[1], "rx end", "tab:orange")], False),
              ("azimuth in the body frame / deg", [(ends[2], "tx end", "tab:blue"), (ends[3], "rx end", "tab:orange")], False)]
    for ax, (xlabel, series, log_x) in zip(axes, panels):
        for x, label, colour in series:
            ax.scatter(x[pick], r[pick], s=1.5, color=colour, alpha=0.15, lw=0, rasterized=True)
            _binned_panel(ax, x, r, colour, label)
        if test.any() and test.sum() >= 20:
            _binned_panel(ax, series[0][0][test], r[test], "tab:red", f"held out ({series[0][1]})")
        ax.axhline(0.0, color="k", lw=0.8)
        if log_x and np.all(d > 0) and d.max() / max(d.min(), 1e-9) > 20:
            ax.set_xscale("log")
        ax.set_xlabel(xlabel)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, loc="upper right")
    axes[0].set_ylabel("measured - predicted / dB")
    q = np.nanquantile(r, [0.01, 0.99]) if np.isfinite(r).any() else np.array([-1.0, 1.0])
    axes[0].set_ylim(float(q[0]) - 1.0, float(q[1]) + 1.0)
    fig.suptitle(f"Residuals (RMS {float(np.sqrt(np.nanmean(r**2))):.2f} dB over {r.size:,} samples)")
    return fig


@check_types
def plot_residuals(path: str | os.PathLike[str], *args: Any, **kwargs: Any) -> str:
    """Write :func:`residuals_figure` (same arguments after ``path``); return the path."""
    caption = ("Residuals (measured minus predicted joint gain) against distance and against the elevation and "
               "azimuth at which each end saw the other in its body frame: binned median (line) and 10-90 % spread "
               "(band); a trend away from 0 dB is what the model misses.")
    return save_figure(residuals_figure(*args, **kwargs), path, caption)


@check_types
def best_covered_elevation_deg(model: Any, node: str, step_deg: float = 5.0, max_abs_deg: float = 60.0) -> float | None:
    """The elevation [deg] (a multiple of ``step_deg`` within +-``max_abs_deg``) whose azimuth cut
    the flight covered most (within :data:`COVERED_DEG` of a learning direction); None for a model
    that stores no coverage."""
    az = np.radians(np.arange(-180.0, 180.0, 2.0))
    best, share = None, -1.0
    for el in np.arange(-max_abs_deg, max_abs_deg + step_deg / 2, step_deg):
        c = model.coverage_deg(node, az, np.full(az.shape, np.radians(el)))
        if c is None:
            return None
        frac = float(np.mean(np.asarray(c) <= COVERED_DEG))
        if frac > share + 1e-12:
            best, share = float(el), frac
    return best


def _cut(model: Any, node: str, el_deg: float, az: np.ndarray) -> tuple[np.ndarray, np.ndarray | None, np.ndarray | None]:
    el = np.full(az.shape, np.radians(el_deg))
    g = np.asarray(model.evaluate(node, az, el), np.float64)
    std = (np.asarray(model.standard_error(node, az, el), np.float64)
           if getattr(model, "covariance", None) is not None else None)
    cov = model.coverage_deg(node, az, el) if hasattr(model, "coverage_deg") else None
    return g, std, None if cov is None else np.asarray(cov) <= COVERED_DEG


@check_types
def polar_cuts_figure(model: Any, nodes: Sequence[str] | None = None, label: str = "") -> Figure:
    """Each node's pattern cut at 0 deg elevation and at its best-covered elevation (polar,
    0 deg = forward (x), counter-clockwise to the left (y), as seen from above), with the
    90 % band of the pattern's own spread; dotted where the flight never looked."""
    if not (hasattr(model, "evaluate") and hasattr(model, "nodes")):
        raise InputError(f"model: expected a pattern model (nodes, evaluate), got {type(model).__name__}", param="model")
    nodes = [str(n) for n in (nodes or model.nodes)]
    if not nodes:
        raise InputError("nodes: nothing to draw")
    az = np.radians(np.linspace(-180.0, 180.0, 361))
    fig = new_figure(4.6 * len(nodes) + 0.4, 6.0)
    cuts = []
    for n in nodes:
        best = best_covered_elevation_deg(model, n)
        els = [0.0] + ([best] if best is not None and abs(best) > 1e-9 else [])
        cuts.append([(el, *_cut(model, n, el, az)) for el in els])
    values = np.concatenate([g - (Z90 * s if s is not None else 0.0) for c in cuts for _, g, s, _ in c])
    tops = np.concatenate([g + (Z90 * s if s is not None else 0.0) for c in cuts for _, g, s, _ in c])
    top = float(np.nanmax(tops)) + 1.0
    floor = max(float(np.nanmin(values)), top - 40.0) - 1.0
    for k, (n, node_cuts) in enumerate(zip(nodes, cuts)):
        ax: Any = fig.add_subplot(1, len(nodes), k + 1, projection="polar")
        ax.set_theta_zero_location("N")
        ax.set_theta_direction(1)
        for (el, g, s, covered), colour in zip(node_cuts, ("tab:blue", "tab:orange")):
            name = "0 deg elevation" if el == 0.0 else "best-covered elevation"
            if s is not None:
                ax.fill_between(az, np.clip(g - Z90 * s, floor, None), np.clip(g + Z90 * s, floor, None),
                                color=colour, alpha=0.2, lw=0)
            shown = np.clip(g, floor, None)
            if covered is None:
                ax.plot(az, shown, color=colour, lw=1.6, label=name)
            else:
                ax.plot(az, np.where(covered, shown, np.nan), color=colour, lw=1.8, label=f"{name}, covered")
                ax.plot(az, np.where(covered, np.nan, shown), color=colour, lw=1.0, ls=":", label=f"{name}, not covered")
        ax.set_rlim(floor, top)
        others = [el for el, *_ in node_cuts if el != 0.0]
        ax.set_title(f"{label + ': ' if label else ''}node {n}"
                     + (f"\nbest-covered elevation {others[0]:+.0f} deg" if others else ""), fontsize=10)
        ax.tick_params(labelsize=7)
        if k == 0:
            handles, labels = ax.get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside lower center", ncols=2, fontsize=8)
    fig.suptitle("Azimuth cuts of each pattern / dBi (0 deg forward, 90 deg left; band: 90 % of its own spread)")
    return fig


@check_types
def plot_polar_cuts(model: Any, path: str | os.PathLike[str], nodes: Sequence[str] | None = None, label: str = "") -> str:
    """Write :func:`polar_cuts_figure`; return the path."""
    caption = ("Polar cuts of each learned pattern at 0 deg elevation (the usual antenna plot) and at the "
               "elevation the flight covered most; 0 deg is forward, 90 deg left; band: 90 % of the pattern's own "
               "spread; dotted: directions more than 10 deg from every learning direction.")
    return save_figure(polar_cuts_figure(model, nodes, label), path, caption)


__all__ = [
    "Z90",
    "best_covered_elevation_deg",
    "binned_stats",
    "panel_units",
    "plot_polar_cuts",
    "plot_prediction_time",
    "plot_residuals",
    "polar_cuts_figure",
    "prediction_time_figure",
    "residuals_figure",
]
