"""Pattern figures of the paper (Figs. 8a, 9) and 3-D pattern images, written as PNG files.

Figures are built on :class:`matplotlib.figure.Figure` with the Agg canvas (no pyplot, no
global state, no display needed); importing this module selects the Agg backend unless pyplot
is already in use (a notebook keeps its backend). Every ``plot_*`` function takes plain data
or objects, writes one PNG and returns its path; the matching ``*_figure`` function builds the
figure without writing it, so that tests and notebooks can inspect its artists. This module
holds the helpers every figure shares (:func:`save_figure`, the az-el grid) and the figures in
the az-el domain: pattern maps, coverage and 3-D patterns; the charts over time or over a
study's parameter (RSSI, order and epsilon sweeps, rank study, swarm links) are in
:mod:`rplearn.viz.charts`.

Angles are radians in the API and degrees on every axis (docs/conventions.md): azimuth ``az`` in
(-180, 180] deg, 0 = forward, +90 = left; elevation ``el`` in [-90, 90] deg, positive up.
"""
from __future__ import annotations

import os
import sys
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any, Protocol

import matplotlib

if "matplotlib.pyplot" not in sys.modules:  # headless by default; never switch a live session
    matplotlib.use("Agg")

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from numpy.typing import ArrayLike, NDArray

from rplearn._argtypes import check_types
from rplearn._atomic import atomic_path
from rplearn._version import __version__
from rplearn.errors import InputError

FloatArray = NDArray[np.float64]
AzEl = tuple[ArrayLike, ArrayLike]

DPI = 110
CMAP = "viridis"
LEARN_COLOR = "tab:green"
TEST_COLOR = "tab:orange"


class PatternLike(Protocol):
    """Anything with ``nodes`` and ``evaluate(node, az_rad, el_rad) -> gain [dB]``."""

    @property
    def nodes(self) -> Sequence[str]: ...

    def evaluate(self, node: str, az_rad: ArrayLike, el_rad: ArrayLike) -> FloatArray: ...


# -- helpers -------------------------------------------------------------------------------
def new_figure(width_in: float, height_in: float) -> Figure:
    fig = Figure(figsize=(width_in, height_in), dpi=DPI, layout="constrained")
    FigureCanvasAgg(fig)
    return fig


@check_types
def save_figure(fig: Figure, path: str | os.PathLike[str], caption: str | None = None) -> str:
    """Write ``fig`` as a PNG at :data:`DPI` and return the path as a string.

    ``caption`` is stored in the PNG's ``Description`` text chunk, where
    :func:`rplearn.viz.report.write_report` finds a default figure caption.
    """
    path = os.fspath(path)
    metadata = {"Software": f"rplearn {__version__}"}
    if caption:
        metadata["Description"] = " ".join(str(caption).split())
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=DPI, format="png", metadata=metadata)
    return path


def dot_size(n_points: int, lo: float = 1.5, hi: float = 8.0) -> float:
    """Marker area [pt^2] for a scatter of ``n_points``: small for dense, larger for sparse."""
    return float(np.clip(3.0e4 / max(n_points, 1), lo, hi))


def _check_pattern_like(obj: Any, name: str) -> None:
    if not (hasattr(obj, "nodes") and callable(getattr(obj, "evaluate", None))):
        raise InputError(
            f"{name}: expected a pattern (with .nodes and .evaluate(node, az, el)), got {type(obj).__name__}"
        )


def az_el_grid_deg(step_deg: float = 2.0) -> tuple[FloatArray, FloatArray]:
    """Cell centres of a regular azimuth x elevation grid [deg] covering the sphere.

    Returns ``(az_deg, el_deg)`` 1-D arrays: az in (-180, 180), el in (-90, 90).
    """
    if not np.isfinite(step_deg) or step_deg <= 0 or step_deg > 90:
        raise InputError(f"step_deg: expected a step in (0, 90] deg, got {step_deg}")
    n_az = max(round(float(360.0 / step_deg)), 4)
    n_el = max(round(float(180.0 / step_deg)), 2)
    az = -180.0 + (np.arange(n_az) + 0.5) * 360.0 / n_az
    el = -90.0 + (np.arange(n_el) + 0.5) * 180.0 / n_el
    return az, el


def pattern_map_db(
    pattern: PatternLike, node: str, az_deg: FloatArray, el_deg: FloatArray
) -> FloatArray:
    """Gain of ``node`` on the grid ``el_deg x az_deg`` [dB], shape ``(n_el, n_az)``."""
    az, el = np.meshgrid(np.radians(az_deg), np.radians(el_deg))
    return np.asarray(pattern.evaluate(node, az, el), np.float64).reshape(az.shape)


def sphere_mean_db(gain_db: FloatArray, el_deg: FloatArray) -> float:
    """Area-weighted (cos el) mean of a gain map on an ``el x az`` grid [dB]."""
    w = np.cos(np.radians(el_deg))[:, None] * np.ones_like(gain_db)
    return float(np.sum(w * gain_db) / np.sum(w))


def subsample_indices(n: int, max_n: int, seed: int = 0) -> NDArray[np.intp]:
    if n <= max_n:
        return np.arange(n)
    return np.sort(np.random.default_rng(seed).choice(n, max_n, replace=False))


def _az_el_deg(pair: AzEl, name: str) -> tuple[FloatArray, FloatArray]:
    az = np.degrees(np.asarray(pair[0], np.float64).ravel())
    el = np.degrees(np.asarray(pair[1], np.float64).ravel())
    if az.shape != el.shape:
        raise InputError(f"{name}: azimuth and elevation differ in length ({az.size} vs {el.size})")
    return az, el


def style_az_el_axes(ax: Any, xlabel: bool = True, ylabel: bool = True) -> None:
    ax.set_xlim(-180, 180)
    ax.set_ylim(-90, 90)
    ax.set_xticks(np.arange(-180, 181, 90))
    ax.set_yticks(np.arange(-90, 91, 45))
    if xlabel:
        ax.set_xlabel("azimuth / deg (0 fwd, +90 left)")
    if ylabel:
        ax.set_ylabel("elevation / deg")


# -- Fig. 9: pattern maps ------------------------------------------------------------------
def colour_limits_db(maps_db: FloatArray, has_truth: bool) -> tuple[float, float]:
    """Shared colour limits of one column of pattern maps [dB].

    With a truth (first map) the limits are the truth's range widened by 25 %, so that learned
    maps are read on the truth's scale (extrapolated lobes where no sample lies saturate
    instead of flattening everything else); without, the 1st..99th percentile of all maps.
    """
    ref = maps_db[0] if has_truth else maps_db
    finite = ref[np.isfinite(ref)]
    if finite.size == 0:
        return 0.0, 1.0
    if has_truth:
        lo, hi = float(finite.min()), float(finite.max())
        pad = 0.125 * max(hi - lo, 1.0)
        return lo - pad, hi + pad
    lo, hi = (float(v) for v in np.percentile(finite, [1.0, 99.0]))
    return (lo, hi) if hi > lo else (lo - 0.5, hi + 0.5)


@check_types
def uncovered_directions(model: Any, node: str, az_deg: FloatArray, el_deg: FloatArray) -> NDArray[np.bool_] | None:
    """Which directions of the grid ``el_deg x az_deg`` lie further than ``UNCOVERED_DEG`` from
    every direction ``model`` learned ``node`` from: a boolean ``(n_el, n_az)`` array, or None
    for a model that stores no coverage (references, baselines, older files)."""
    coverage = getattr(model, "coverage_deg", None)
    if coverage is None:
        return None
    from rplearn.models.predict import UNCOVERED_DEG

    el_g, az_g = np.meshgrid(el_deg, az_deg, indexing="ij")
    cov = coverage(str(node), np.radians(az_g.ravel()), np.radians(el_g.ravel()))
    if cov is None:
        return None
    return np.asarray(cov).reshape(el_g.shape) > UNCOVERED_DEG


def _hatch_uncovered(ax: Any, model: Any, node: str, az_deg: np.ndarray, el_deg: np.ndarray) -> None:
    """Hatch (and fade) the :func:`uncovered_directions` of ``node`` on an az-el map."""
    far = uncovered_directions(model, node, az_deg, el_deg)
    if far is not None and far.any():
        far = far.astype(float)
        ax.contourf(az_deg, el_deg, far, levels=[0.5, 1.5], colors=["white"], alpha=0.35)
        ax.contourf(az_deg, el_deg, far, levels=[0.5, 1.5], colors="none", hatches=["////"])


@check_types
def pattern_maps_figure(
    models: Mapping[str, PatternLike],
    truth: PatternLike | None = None,
    nodes: Sequence[str] | None = None,
    samples_az_el: Mapping[str, AzEl] | None = None,
    center: bool = False,
    step_deg: float = 2.0,
    max_dots: int = 3000,
) -> Figure:
    """Learned (and true) patterns as az-el colour maps: rows = models, columns = nodes.

    Parameters
    ----------
    models : mapping of label -> pattern-like
        Learned patterns (``PatternSet`` or anything with ``nodes`` and ``evaluate``).
    truth : pattern-like, optional
        True patterns (``GroundTruth``), drawn as the first row.
    nodes : sequence of str, optional
        Columns; default: the nodes of the truth, else of the first model.
    samples_az_el : mapping of node -> (az [rad], el [rad]), optional
        Directions at which the node was sampled, drawn as small black dots (at most
        ``max_dots`` per node, a fixed random subset).
    center : bool
        Subtract each map's sphere mean (area-weighted): with two nodes only shapes are
        identified (paper Sec. V-A), so centred maps are the ones to compare.
    step_deg : float
        Grid step [deg].
    max_dots : int
        Largest number of sample dots drawn per panel.

    Returns
    -------
    Figure
        With one shared colour scale per column.
    """
    if not models and truth is None:
        raise InputError("models: nothing to draw (no model and no truth)")
    rows: list[tuple[str, PatternLike]] = []
    if truth is not None:
        _check_pattern_like(truth, "truth")
        rows.append(("truth", truth))
    for label, m in models.items():
        _check_pattern_like(m, f"model {label!r}")
        rows.append((str(label), m))
    if nodes is None:
        nodes = tuple(rows[0][1].nodes)
    nodes = [str(n) for n in nodes]
    if not nodes:
        raise InputError("nodes: no node to draw")
    az, el = az_el_grid_deg(step_deg)
    maps = np.empty((len(rows), len(nodes), el.size, az.size))
    for i, (_, m) in enumerate(rows):
        for j, n in enumerate(nodes):
            g = pattern_map_db(m, n, az, el)
            maps[i, j] = g - sphere_mean_db(g, el) if center else g
    unit = "dB rel. sphere mean" if center else "dBi"
    fig = new_figure(3.6 * len(nodes) + 0.6, 2.2 * len(rows) + 1.2)
    axes = fig.subplots(len(rows), len(nodes), squeeze=False, sharex=True, sharey=True)
    for j, n in enumerate(nodes):
        vmin, vmax = colour_limits_db(maps[:, j], has_truth=truth is not None)
        im = None
        for i, (label, _) in enumerate(rows):
            ax = axes[i, j]
            im = ax.pcolormesh(
                az,
                el,
                maps[i, j],
                cmap=CMAP,
                vmin=vmin,
                vmax=vmax,
                shading="nearest",
                rasterized=True,
            )
            _hatch_uncovered(ax, rows[i][1], n, az, el)
            if samples_az_el is not None and n in samples_az_el and label != "truth":
                saz, sel = _az_el_deg(samples_az_el[n], f"samples of {n}")
                keep = subsample_indices(saz.size, max_dots)
                ax.scatter(saz[keep], sel[keep], s=0.6, c="k", marker=".", linewidths=0, alpha=0.6)
            style_az_el_axes(ax, xlabel=i == len(rows) - 1, ylabel=j == 0)
            ax.set_title(f"{label}: node {n}", fontsize=9)
        assert im is not None  # one panel per node at least
        cb = fig.colorbar(
            im, ax=axes[:, j], orientation="horizontal", fraction=0.05, aspect=30, extend="both"
        )
        cb.set_label(f"G_{n} / {unit}")
    kind = "centred patterns (shapes)" if center else "patterns"
    hatched = any(getattr(m, "training", {}).get("coverage_deg") for _, m in rows)
    fig.suptitle(f"Learned {kind} in the az-el domain" + (" vs truth" if truth is not None else "")
                 + ("\nhatched: more than 10 deg from any learning direction (extrapolated, or the prior)" if hatched else ""))
    return fig


@check_types
def plot_pattern_maps(
    models: Mapping[str, PatternLike],
    truth: PatternLike | None,
    nodes: Sequence[str] | None,
    samples_az_el: Mapping[str, AzEl] | None,
    path: str | os.PathLike[str],
    center: bool = False,
    step_deg: float = 2.0,
    max_dots: int = 3000,
) -> str:
    """Write the paper's Fig. 9 (see :func:`pattern_maps_figure`) as a PNG; return the path."""
    fig = pattern_maps_figure(models, truth, nodes, samples_az_el, center, step_deg, max_dots)
    what = (
        "relative to its own sphere mean (two-node fits identify shapes only)"
        if center
        else "in dBi"
    )
    caption = (
        f"Learned radiation patterns of each node over azimuth and elevation, {what}"
        + ("; first row: the true patterns" if truth is not None else "")
        + ("; black dots: learning sample directions" if samples_az_el else "")
        + " (paper Fig. 9)."
    )
    return save_figure(fig, path, caption)


def _own_std_map(model: Any, node: str, az_rad: np.ndarray, el_rad: np.ndarray) -> np.ndarray:
    """The posterior std of ``node``'s own gain on an az-el mesh [dB]: from the decoupling
    certificate's map (nearest point of its Fibonacci grid) when ``fit`` stored one (an automatic fit's posterior
    continued to the largest order), else from the model's covariance."""
    stored = ((getattr(model, "training", {}) or {}).get("decoupling", {}).get("own_std_db") or {}).get(node)
    if stored is not None:
        from rplearn.core.coverage import grid_value_at

        return grid_value_at(stored, az_rad.ravel(), el_rad.ravel()).reshape(az_rad.shape)
    return np.asarray(model.standard_error(node, az_rad.ravel(), el_rad.ravel())).reshape(az_rad.shape)


@check_types
def spread_maps_figure(models: Mapping[str, Any], nodes: Sequence[str] | None = None, step_deg: float = 3.0) -> Figure:
    """Posterior std of each node's own pattern [dB] as az-el maps (rows = models, columns =
    nodes), the directions further than ``UNCOVERED_DEG`` from any learning direction hatched;
    each title gives the node's spread where the flight looked and over the sphere, from the
    model's decoupling certificate (``training["decoupling"]``, written by ``fit``) when stored,
    whose own-pattern map (an automatic fit's posterior continued to the largest candidate
    order) is drawn when present, else the model's covariance."""
    rows = [(str(k), m) for k, m in models.items()]
    if not rows:
        raise InputError("models: nothing to draw")
    for label, m in rows:
        if getattr(m, "covariance", None) is None:
            raise InputError(f"model {label!r}: it carries no covariance, so no spread to draw", param="models")
    nodes = [str(n) for n in (nodes or rows[0][1].nodes)]
    az, el = az_el_grid_deg(step_deg)
    azg, elg = np.meshgrid(np.radians(az), np.radians(el))
    maps = np.array([[_own_std_map(m, n, azg, elg) for n in nodes] for _, m in rows])
    fig = new_figure(3.6 * len(nodes) + 0.6, 2.2 * len(rows) + 1.2)
    axes = fig.subplots(len(rows), len(nodes), squeeze=False, sharex=True, sharey=True)
    vmax = float(np.nanpercentile(maps, 99)) or 1.0
    im = None
    for i, (label, m) in enumerate(rows):
        cert = (getattr(m, "training", {}) or {}).get("decoupling", {}).get("nodes", {})
        for j, n in enumerate(nodes):
            ax = axes[i, j]
            im = ax.pcolormesh(az, el, maps[i, j], cmap="magma", vmin=0.0, vmax=vmax, shading="nearest", rasterized=True)
            _hatch_uncovered(ax, m, n, az, el)
            style_az_el_axes(ax, xlabel=i == len(rows) - 1, ylabel=j == 0)
            extra = (f"\n{cert[n]['covered_std_db']:.2f} dB where looked, {cert[n]['sphere_std_db']:.2f} dB on the sphere"
                     if n in cert else "")
            ax.set_title(f"{label}: node {n}{extra}", fontsize=8)
    assert im is not None  # one panel per node at least
    cb = fig.colorbar(im, ax=axes, orientation="horizontal", fraction=0.05, aspect=40, extend="max")
    cb.set_label("posterior std of the node's own gain / dB")
    fig.suptitle("Own-pattern spread (1 sigma)\nhatched: more than 10 deg from any learning direction")
    return fig


@check_types
def plot_spread_maps(models: Mapping[str, Any], path: str | os.PathLike[str], nodes: Sequence[str] | None = None,
                     step_deg: float = 3.0) -> str:
    """Write :func:`spread_maps_figure` as a PNG; return the path."""
    caption = ("Posterior standard deviation of each node's own learned pattern over azimuth and elevation; "
               "hatched: directions the flight never looked at.")
    return save_figure(spread_maps_figure(models, nodes, step_deg), path, caption)


# -- Fig. 8a: coverage ---------------------------------------------------------------------
@check_types
def coverage_figure(
    learn_az_el: Mapping[str, AzEl],
    test_az_el: Mapping[str, AzEl] | None = None,
    max_points: int = 20000,
) -> Figure:
    """Directions sampled per node, learning in green and testing in orange (paper Fig. 8a).

    Parameters
    ----------
    learn_az_el, test_az_el : mapping of node -> (az [rad], el [rad])
    max_points : int
        Largest number of points drawn per node and set (a fixed random subset).

    Returns
    -------
    Figure
        One panel per node; each panel holds the learning scatter, then the testing one.
    """
    test_az_el = test_az_el or {}
    nodes = list(dict.fromkeys([*learn_az_el, *test_az_el]))
    if not nodes:
        raise InputError("coverage: no node given")
    fig = new_figure(4.0 * len(nodes) + 0.4, 3.3)
    axes = fig.subplots(1, len(nodes), squeeze=False, sharey=True)[0]
    for j, n in enumerate(nodes):
        ax = axes[j]
        for data, color, label in (
            (learn_az_el, LEARN_COLOR, "learning"),
            (test_az_el, TEST_COLOR, "testing"),
        ):
            if n not in data:
                continue
            az, el = _az_el_deg(data[n], f"{label} samples of {n}")
            keep = subsample_indices(az.size, max_points)
            ax.scatter(
                az[keep],
                el[keep],
                s=dot_size(keep.size),
                c=color,
                marker=".",
                linewidths=0,
                label=f"{label} ({az.size:,})",
            )
        style_az_el_axes(ax, ylabel=j == 0)
        ax.set_title(f"node {n}: direction of the other end", fontsize=9)
        ax.legend(loc="lower right", fontsize=7, markerscale=4)
    fig.suptitle("Coverage of the az-el domain")
    return fig


@check_types
def plot_coverage(
    learn_az_el: Mapping[str, AzEl],
    test_az_el: Mapping[str, AzEl] | None,
    path: str | os.PathLike[str],
    max_points: int = 20000,
) -> str:
    """Write the coverage figure (paper Fig. 8a, :func:`coverage_figure`); return the path."""
    caption = (
        "Direction of the other end seen by each node, in its body frame: learning samples green,"
        " testing samples orange (paper Fig. 8a)."
    )
    return save_figure(coverage_figure(learn_az_el, test_az_el, max_points), path, caption)


# -- 3-D pattern image ---------------------------------------------------------------------
@check_types
@dataclass(frozen=True)
class PatternSurface:
    """One node's pattern on a closed az-el grid, drawn as a surface whose radius is the gain.

    Attributes
    ----------
    az_deg, el_deg : ndarray
        Grid [deg]: az -180..180 and el -90..90, both ends included (a closed surface).
    gain_db : ndarray
        Gain on the grid ``(n_el, n_az)`` [dBi, or dB relative to the sphere mean if centred].
    floor_db, max_db, offset_db : float
        ``radius = max(gain - floor, 0) + offset`` [dB].
    x, y, z : ndarray
        The surface in the body frame (FLU: x forward, y left, z up) [dB of radius].
    """

    az_deg: FloatArray
    el_deg: FloatArray
    gain_db: FloatArray
    floor_db: float
    max_db: float
    offset_db: float
    x: FloatArray
    y: FloatArray
    z: FloatArray

    @property
    def radius_max(self) -> float:
        """Largest radius of the surface [dB]."""
        return float(np.nanmax(np.sqrt(self.x**2 + self.y**2 + self.z**2)))


@check_types
def pattern_surface(
    pattern_like: PatternLike,
    node: str,
    step_deg: float = 3.0,
    dynamic_range_db: float = 40.0,
    center: bool = False,
) -> PatternSurface:
    """One node's pattern as a 3-D surface in its body frame (FLU: x forward, y left, z up).

    The gain comes from :func:`pattern_map_db` on a closed grid of step ``step_deg``; with
    ``center`` its sphere mean (:func:`sphere_mean_db`) is removed. The radius is the gain
    shifted to be positive, ``max(G - floor, 0) + offset`` with ``floor = max(G_min, G_max -
    dynamic_range_db)`` and ``offset`` 5 % of the range (at least 1 dB, so that nulls and
    isotropic patterns stay visible) [dB].
    """
    _check_pattern_like(pattern_like, "pattern")
    if not np.isfinite(dynamic_range_db) or dynamic_range_db <= 0:
        raise InputError(f"dynamic_range_db: expected > 0, got {dynamic_range_db}")
    if not np.isfinite(step_deg) or step_deg <= 0 or step_deg > 90:
        raise InputError(f"step_deg: expected a step in (0, 90] deg, got {step_deg}")
    az_deg = np.linspace(-180.0, 180.0, round(float(360 / step_deg)) + 1)
    el_deg = np.linspace(-90.0, 90.0, round(float(180 / step_deg)) + 1)
    g = pattern_map_db(pattern_like, str(node), az_deg, el_deg)
    if center:
        g = g - sphere_mean_db(g[:, :-1], el_deg)  # az = 180 repeats az = -180
    g_max = float(np.nanmax(g))
    floor = max(float(np.nanmin(g)), g_max - dynamic_range_db)
    offset_db = 0.05 * max(g_max - floor, 20.0)  # keeps nulls (and isotropic patterns) visible
    r = np.clip(g - floor, 0.0, None) + offset_db
    az, el = np.meshgrid(np.radians(az_deg), np.radians(el_deg))
    x, y, z = r * np.cos(el) * np.cos(az), r * np.cos(el) * np.sin(az), r * np.sin(el)
    return PatternSurface(az_deg, el_deg, g, floor, g_max, offset_db, x, y, z)


@check_types
def pattern_3d_figure(
    pattern_like: PatternLike,
    node: str,
    step_deg: float = 3.0,
    dynamic_range_db: float = 40.0,
    unit: str = "dBi",
) -> Figure:
    """One node's pattern as a 3-D surface in its body frame (FLU: x forward, y left, z up).

    Radius and colour are the gain (:func:`pattern_surface`); the colour is in ``unit``.
    """
    s = pattern_surface(pattern_like, node, step_deg, dynamic_range_db)
    g, floor, g_max, offset_db, x, y, z = s.gain_db, s.floor_db, s.max_db, s.offset_db, s.x, s.y, s.z
    from matplotlib import cm
    from matplotlib.colors import Normalize
    from mpl_toolkits.mplot3d import Axes3D  # noqa: F401  (registers the projection)

    norm = Normalize(vmin=floor, vmax=g_max if g_max > floor else floor + 1.0)
    fig = new_figure(6.4, 5.8)
    ax = fig.add_subplot(projection="3d")
    colors = matplotlib.colormaps[CMAP](norm(g))
    ax.plot_surface(
        x,
        y,
        z,
        facecolors=colors,
        rstride=1,
        cstride=1,
        linewidth=0,
        antialiased=False,
        shade=False,
    )
    lim = s.radius_max
    ax.set_xlim(-lim, lim)
    ax.set_ylim(-lim, lim)
    ax.set_zlim(-lim, lim)
    ax.set_box_aspect((1, 1, 1))
    ax.set_xlabel("x forward / dB")
    ax.set_ylabel("y left / dB")
    ax.set_zlabel("z up / dB")
    ax.tick_params(labelsize=6)
    ax.view_init(elev=25, azim=-60)
    sm = cm.ScalarMappable(norm=norm, cmap=CMAP)
    cb = fig.colorbar(sm, ax=ax, shrink=0.7, pad=0.08)
    cb.set_label(f"gain / {unit}")
    ax.set_title(
        f"node {node}: radiation pattern\n(radius = gain - floor + {offset_db:.1f} dB, floor {floor:.1f} {unit})",
        fontsize=9,
    )
    return fig


@check_types
def plot_pattern_3d(
    pattern_like: PatternLike, node: str, path: str | os.PathLike[str], step_deg: float = 3.0
) -> str:
    """Write a 3-D image of one node's pattern (:func:`pattern_3d_figure`); return the path."""
    caption = f"Radiation pattern of node {node} in its body frame (x forward, y left, z up)."
    return save_figure(pattern_3d_figure(pattern_like, node, step_deg), path, caption)
