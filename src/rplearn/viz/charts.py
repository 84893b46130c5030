"""Charts of the paper (Figs. 5a, 6, 8b, 10) and of swarm links, written as PNG files.

Line and bar charts over time or over a study's parameter: the received signal strength over
time (Fig. 8b), the model order sweep (Fig. 10), the gauge epsilon sweep (Fig. 5a), the rank
study (Fig. 6) and the predicted links of a swarm. As in :mod:`rplearn.viz.plot` (whose
helpers they use, and which selects the Agg backend), every ``plot_*`` function writes one PNG
and returns its path, and the matching ``*_figure`` function builds the figure without writing
it.
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
from rplearn.viz.plot import FloatArray, dot_size, new_figure, save_figure, subsample_indices


# -- Fig. 8b: RSSI over time ---------------------------------------------------------------
@check_types
def rssi_time_figure(
    t_s: ArrayLike,
    rssi_dbm: ArrayLike,
    unit_labels: ArrayLike | None = None,
    max_points: int = 50000,
    legend_title: str = "unit",
) -> Figure:
    """Received signal strength over time (paper Fig. 8b), coloured by trajectory unit.

    Parameters
    ----------
    t_s : array
        Packet times [s]; drawn relative to the first one.
    rssi_dbm : array
        Received power [dBm].
    unit_labels : array of str, optional
        Trajectory unit (or link, ...) of each packet; one colour and legend entry per label.
    max_points : int
        Largest number of points drawn per label (a fixed random subset).
    legend_title : str
        Title of the legend (what the labels are).
    """
    t = np.asarray(t_s, np.float64).ravel()
    p = np.asarray(rssi_dbm, np.float64).ravel()
    if t.shape != p.shape or t.size == 0:
        raise InputError(
            f"rssi: expected equal, non-empty t_s and rssi_dbm, got {t.size} and {p.size} values"
        )
    labels = (
        np.full(t.size, "", dtype=object)
        if unit_labels is None
        else np.asarray(unit_labels, dtype=object).ravel()
    )
    if labels.shape != t.shape:
        raise InputError(f"rssi: unit_labels has {labels.size} values, expected {t.size}")
    t0 = float(np.nanmin(t))
    fig = new_figure(9.0, 3.0)
    ax = fig.add_subplot()
    for k, u in enumerate(dict.fromkeys(labels.tolist())):
        idx = np.flatnonzero(labels == u)
        idx = idx[subsample_indices(idx.size, max_points)]
        ax.scatter(
            t[idx] - t0,
            p[idx],
            s=dot_size(idx.size),
            marker=".",
            linewidths=0,
            color=f"C{k % 10}",
            label=str(u) if u != "" else None,
        )
    if unit_labels is not None:
        ax.legend(fontsize=7, markerscale=5, loc="best", title=legend_title, title_fontsize=7)
    ax.set_xlabel(f"time / s (since t = {t0:.3f} s)")
    ax.set_ylabel("RSSI / dBm")
    ax.grid(alpha=0.3)
    ax.set_title("Received signal strength")
    return fig


@check_types
def plot_rssi_time(
    t_s: ArrayLike,
    rssi_dbm: ArrayLike,
    path: str | os.PathLike[str],
    unit_labels: ArrayLike | None = None,
    legend_title: str = "unit",
    caption: str = "Received signal strength over time (paper Fig. 8b).",
) -> str:
    """Write the RSSI-over-time figure (paper Fig. 8b, :func:`rssi_time_figure`); return the path."""
    fig = rssi_time_figure(t_s, rssi_dbm, unit_labels, legend_title=legend_title)
    return save_figure(fig, path, caption)


# -- Fig. 10: model order sweep ------------------------------------------------------------
@check_types
def order_sweep_figure(
    orders: ArrayLike, test_rmse_db: ArrayLike, aic: ArrayLike, ltd_s: ArrayLike, family: str = "SH",
    validation_rmse_db: ArrayLike | None = None, chosen: tuple[int, float] | None = None,
) -> Figure:
    """Model order selection (paper Fig. 10): test RMSE and AIC (top), LTD (bottom).

    The minima of the test RMSE and of the AIC are marked. With ``validation_rmse_db`` (the
    cross-validated RMSE over the learning units at the automatic choice's smoothing) that
    curve is drawn too, and ``chosen`` (order, smoothing) is marked on it.

    Parameters
    ----------
    orders : array of int
        Model orders (e.g. SH-L for L in orders).
    test_rmse_db : array
        Prediction RMSE on the testing samples [dB].
    aic : array
        Akaike information criterion on the testing samples (``n ln MSE + 2k``).
    ltd_s : array
        Learning wall time [s].
    """
    x = np.asarray(orders, np.float64).ravel()
    r = np.asarray(test_rmse_db, np.float64).ravel()
    a = np.asarray(aic, np.float64).ravel()
    t = np.asarray(ltd_s, np.float64).ravel()
    if not (x.size == r.size == a.size == t.size) or x.size == 0:
        raise InputError(
            f"order sweep: expected equal, non-empty arrays, got {x.size}, {r.size}, {a.size}, {t.size}"
        )
    fig = new_figure(7.0, 5.0)
    ax, ax_t = fig.subplots(2, 1, sharex=True, height_ratios=[2, 1])
    ax.plot(x, r, "o-", color="tab:green", label="test RMSE")
    ax.set_ylabel("test RMSE / dB", color="tab:green")
    if np.isfinite(r).any():
        k = int(np.nanargmin(r))
        ax.plot(
            x[k],
            r[k],
            "*",
            ms=16,
            color="tab:green",
            mec="k",
            label=f"min RMSE: {family}-{x[k]:g} ({r[k]:.2f} dB)",
        )
    if validation_rmse_db is not None:
        v = np.asarray(validation_rmse_db, np.float64).ravel()
        ax.plot(x, v, "d:", color="tab:orange", label="cross-validated RMSE (learning units)")
        if chosen is not None and chosen[0] in x:
            k = int(np.flatnonzero(x == chosen[0])[0])
            ax.plot(x[k], v[k], "P", ms=13, color="tab:orange", mec="k",
                    label=f"auto: {family}-{chosen[0]}, smoothing {chosen[1]:.0e}")
    ax2 = ax.twinx()
    ax2.plot(x, a / 1e3, "s--", color="tab:purple", label="AIC")
    ax2.set_ylabel("AIC / 1e3", color="tab:purple")
    if np.isfinite(a).any():
        k = int(np.nanargmin(a))
        # a hollow ring, so that the best-order star drawn above it (ax over ax2) stays visible
        ax2.plot(x[k], a[k] / 1e3, "o", ms=22, mfc="none", mec="tab:purple", mew=2.0, label=f"min AIC: {family}-{x[k]:g}")
    ax.set_zorder(ax2.get_zorder() + 1)  # the RMSE curve and the best-order marker above the AIC's
    ax.patch.set_visible(False)
    h1, l1 = ax.get_legend_handles_labels()
    h2, l2 = ax2.get_legend_handles_labels()
    ax.legend(h1 + h2, l1 + l2, fontsize=8, loc="upper center")
    ax.grid(alpha=0.3)
    ax.set_title(f"Model order selection ({family})")
    ax_t.plot(x, t, "^-", color="tab:blue")
    ax_t.set_ylabel("LTD / s")
    t_ok = t[np.isfinite(t)]
    if t_ok.size and np.all(t_ok > 0) and t_ok.max() / t_ok.min() > 20.0:
        ax_t.set_yscale("log")  # learning time spans decades
    ax_t.set_xlabel(f"{family} order")
    ax_t.grid(alpha=0.3)
    return fig


@check_types
def plot_order_sweep(
    orders: ArrayLike,
    test_rmse_db: ArrayLike,
    aic: ArrayLike,
    ltd_s: ArrayLike,
    path: str | os.PathLike[str],
    family: str = "SH",
    validation_rmse_db: ArrayLike | None = None,
    chosen: tuple[int, float] | None = None,
) -> str:
    """Write the order-sweep figure (paper Fig. 10, :func:`order_sweep_figure`); return the path."""
    caption = (
        f"Model order selection: test RMSE and AIC against the {family} order (star: lowest test RMSE; ring: lowest AIC),"
        " and the learning time LTD (paper Fig. 10)."
    )
    if validation_rmse_db is not None:
        caption += " Dotted: the RMSE cross-validated over the learning units, from which --order auto chooses."
    return save_figure(order_sweep_figure(orders, test_rmse_db, aic, ltd_s, family, validation_rmse_db, chosen),
                       path, caption)


# -- Fig. 5a: epsilon sweep ----------------------------------------------------------------
@check_types
def epsilon_sweep_figure(eps: ArrayLike, error_db: ArrayLike) -> Figure:
    """Prediction RMSE vs a constant moved between two nodes' patterns (paper Fig. 5a).

    ``eps`` is added to one node's Y00 coefficient and subtracted from the other's; with two
    nodes the joint gain, hence the error, does not change (a flat line), whatever ``eps``.

    Parameters
    ----------
    eps : array
        The constant [dB-scale coefficient]; drawn on a log axis from 1e-3 to 1e6.
    error_db : array
        Prediction RMSE for each ``eps`` [dB].
    """
    e = np.asarray(eps, np.float64).ravel()
    y = np.asarray(error_db, np.float64).ravel()
    if e.shape != y.shape or e.size == 0:
        raise InputError(
            f"epsilon sweep: expected equal, non-empty arrays, got {e.size} and {y.size}"
        )
    if np.any(e <= 0):
        raise InputError("epsilon sweep: eps must be positive for a log axis")
    fig = new_figure(6.0, 3.3)
    ax = fig.add_subplot()
    ax.semilogx(e, y, "o-", color="tab:red", ms=3)
    ax.set_xlim(1e-3, 1e6)
    spread = float(np.nanmax(y) - np.nanmin(y)) if np.isfinite(y).any() else 0.0
    mid = float(np.nanmean(y)) if np.isfinite(y).any() else 0.0
    if spread < 1e-6 * max(1.0, abs(mid)):
        ax.set_ylim(mid - max(0.5, 0.1 * abs(mid)), mid + max(0.5, 0.1 * abs(mid)))
    ax.set_xlabel("epsilon (added to one node's Y00, subtracted from the other's)")
    ax.set_ylabel("prediction RMSE / dB")
    ax.set_title(f"Gauge freedom of two-node learning (RMSE spread {spread:.2e} dB)")
    ax.grid(alpha=0.3, which="both")
    return fig


@check_types
def plot_epsilon_sweep(eps: ArrayLike, error_db: ArrayLike, path: str | os.PathLike[str]) -> str:
    """Write the epsilon-sweep figure (paper Fig. 5a, :func:`epsilon_sweep_figure`); return the path."""
    caption = (
        "Prediction RMSE when epsilon is added to one antenna's Y00 coefficient and subtracted"
        " from the other's: with two antennas the error does not change (paper Fig. 5a)."
    )
    return save_figure(epsilon_sweep_figure(eps, error_db), path, caption)


# -- Fig. 6: rank study --------------------------------------------------------------------
@check_types
def rank_study_figure(cases: Sequence[tuple[str, int, int]]) -> Figure:
    """Columns vs rank of the design matrix for several problems (paper Figs. 5b, 6).

    Parameters
    ----------
    cases : sequence of (label, n_columns, rank)
        E.g. ``("2 antennas, SH-8", 128, 127)``; the deficiency ``n_columns - rank`` is
        written over each pair of bars.
    """
    if not cases:
        raise InputError("rank study: no case given")
    labels = [str(c[0]) for c in cases]
    cols = np.array([int(c[1]) for c in cases])
    ranks = np.array([int(c[2]) for c in cases])
    x = np.arange(len(cases))
    fig = new_figure(max(5.0, 1.6 * len(cases) + 1.5), 3.6)
    ax = fig.add_subplot()
    w = 0.38
    ax.bar(x - w / 2, cols, w, label="columns", color="tab:gray")
    ax.bar(x + w / 2, ranks, w, label="rank", color="tab:blue")
    for xi, c, r in zip(x, cols, ranks):
        ax.annotate(
            f"deficiency {c - r}",
            (xi, max(c, r)),
            textcoords="offset points",
            xytext=(0, 3),
            ha="center",
            fontsize=8,
        )
    ax.set_xticks(x, labels, fontsize=8)
    ax.set_ylabel("count")
    ax.set_ylim(0, 1.15 * max(int(cols.max()), 1))
    ax.legend(fontsize=8, loc="lower right")
    ax.set_title("Design matrix: columns vs rank")
    return fig


@check_types
def plot_rank_study(cases: Sequence[tuple[str, int, int]], path: str | os.PathLike[str]) -> str:
    """Write the rank-study bar chart (paper Fig. 6, :func:`rank_study_figure`); return the path."""
    caption = "Columns and rank of the design matrix of each problem (paper Figs. 5b and 6)."
    return save_figure(rank_study_figure(cases), path, caption)


# -- swarm links ---------------------------------------------------------------------------
def _break_gaps(t: ArrayLike, y: ArrayLike) -> tuple[FloatArray, FloatArray]:
    """Insert NaN where the time step exceeds 1.5 typical steps, so lines do not bridge gaps."""
    t = np.asarray(t, np.float64)
    y = np.asarray(y, np.float64)
    if t.size < 3:
        return t, y
    dt = np.diff(t)
    gap = np.flatnonzero(dt > 1.5 * np.median(dt))
    return np.insert(t, gap + 1, np.nan), np.insert(y, gap + 1, np.nan)


@check_types
def plot_swarm(prediction: Any, path: str | os.PathLike[str]) -> str:
    """RSSI of every pair (weaker direction) over time, the threshold and the bottleneck; return the path.

    ``prediction`` is a :class:`rplearn.analysis.swarm.SwarmPrediction`.
    """
    links = prediction.links
    fig = new_figure(9.0, 4.2)
    ax = fig.add_subplot()
    pairs = links.assign(pair=[f"{min(a, b)}-{max(a, b)}" for a, b in zip(links["tx"], links["rx"])])
    weaker = pairs.groupby(["pair", "t"])["rssi_pred_dbm"].min().reset_index()
    groups = list(weaker.groupby("pair"))
    many = len(groups) > 10  # beyond that a legend of pairs hides the plot
    for i, (name, g) in enumerate(groups):
        if many:
            ax.plot(*_break_gaps(g["t"], g["rssi_pred_dbm"]), lw=0.6, color="tab:gray", alpha=0.5,
                    label=f"{len(groups)} pairs" if i == 0 else None)
        else:
            ax.plot(*_break_gaps(g["t"], g["rssi_pred_dbm"]), lw=1.0, label=name)
    c = prediction.connectivity
    bottleneck = np.where(np.isinf(c["bottleneck_rssi_dbm"]), np.nan, c["bottleneck_rssi_dbm"])
    ax.plot(*_break_gaps(c["t"], bottleneck), color="black", lw=2.2, label="bottleneck (connected for thresholds below it)")
    ax.axhline(prediction.min_rssi_dbm, color="tab:red", ls="--", lw=1.2, label=f"threshold {prediction.min_rssi_dbm:g} dBm")
    down = c.loc[~c["connected"] & (c["n_missing"] == 0), "t"]
    if len(down):
        ax.plot(down, np.full(len(down), ax.get_ylim()[0]), "|", color="tab:red", ms=10, label="disconnected")
    unknown = c.loc[c["n_missing"] > 0, "t"]
    if len(unknown):
        ax.plot(unknown, np.full(len(unknown), ax.get_ylim()[0]), "|", color="tab:orange", ms=10, label="a drone without pose")
    ax.set_xlabel("time [s]")
    ax.set_ylabel("predicted RSSI, weaker direction [dBm]")
    ax.set_title("Swarm links predicted from the learned patterns")
    ax.legend(fontsize=7, ncol=2, loc="best")
    ax.grid(alpha=0.3)
    caption = (
        "Predicted received power of every pair of drones (the weaker of its two directions), the RSSI"
        " threshold a link needs, and the bottleneck: the swarm is connected whenever the black line is"
        " above the red one (marks at the bottom: disconnected, or a drone without a pose)."
    )
    return save_figure(fig, path, caption)
