"""plot: every figure writes a valid, non-blank PNG; content checks on the artists drawn."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest
from matplotlib.collections import PathCollection, QuadMesh
from matplotlib.image import imread

from rplearn.core.bases import SphericalHarmonics
from rplearn.core.geometry import unit_vector
from rplearn.errors import InputError
from rplearn.models.patterns import PatternSet
from rplearn.viz import charts, plot

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


class Lobe:
    """Analytic pattern: a cosine lobe of 10 dB toward (az0, el0) per node, -10 dB floor."""

    def __init__(self, lobes_deg: dict[str, tuple[float, float]]):
        self.lobes = {
            n: unit_vector(np.radians(a), np.radians(e)) for n, (a, e) in lobes_deg.items()
        }
        self.nodes = tuple(lobes_deg)

    def evaluate(self, node, az_rad, el_rad):
        u = unit_vector(az_rad, el_rad)
        return 10.0 * np.clip(u @ self.lobes[node], -1.0, 1.0)


@pytest.fixture(scope="module")
def truth():
    return Lobe({"A": (30.0, 20.0), "B": (-120.0, -10.0)})


@pytest.fixture(scope="module")
def learned():
    rng = np.random.default_rng(1)
    return PatternSet(basis=SphericalHarmonics(3), nodes=("A", "B"), coef=rng.normal(0, 3, (2, 9)))


def _samples(n: int, seed: int = 0):
    rng = np.random.default_rng(seed)
    return rng.uniform(-np.pi, np.pi, n), rng.uniform(-np.pi / 2, np.pi / 2, n)


def assert_valid_png(path, min_w: int = 300, min_h: int = 200) -> np.ndarray:
    with open(path, "rb") as f:
        data = f.read()
    assert data.startswith(PNG_SIGNATURE)
    assert len(data) > 5_000
    img = imread(path)
    assert img.shape[1] >= min_w and img.shape[0] >= min_h
    assert float(np.std(img[..., :3])) > 0.02, "blank image"
    return img


def test_every_plot_writes_a_valid_png(tmp_path, truth, learned):
    samples = {"A": _samples(500), "B": _samples(400, 1)}
    paths = [
        plot.plot_pattern_maps(
            {"SH-3": learned}, truth, None, samples, tmp_path / "maps.png", step_deg=6
        ),
        plot.plot_coverage(samples, {"A": _samples(50, 2)}, tmp_path / "cov.png"),
        charts.plot_rssi_time(
            np.arange(300) * 0.1,
            -60 + np.sin(np.arange(300) / 9),
            tmp_path / "rssi.png",
            unit_labels=["u1"] * 150 + ["u2"] * 150,
        ),
        charts.plot_order_sweep(
            [2, 4, 6, 8],
            [4.0, 2.5, 2.2, 2.6],
            [9e3, 7e3, 6.9e3, 7.4e3],
            [0.01, 0.02, 0.05, 0.2],
            tmp_path / "order.png",
        ),
        charts.plot_epsilon_sweep(np.logspace(-3, 6, 10), np.full(10, 2.3), tmp_path / "eps.png"),
        charts.plot_rank_study(
            [("2 antennas", 128, 127), ("3 antennas", 192, 192)], tmp_path / "rank.png"
        ),
        plot.plot_pattern_3d(truth, "A", tmp_path / "p3d.png", step_deg=10),
    ]
    for p in paths:
        assert isinstance(p, str)
        assert_valid_png(p)
        with open(p, "rb") as f:
            assert b"Description" in f.read(4096)  # a caption for the report


def test_coverage_draws_every_given_point(truth):
    fig = plot.coverage_figure({"A": _samples(120), "B": _samples(30, 1)}, {"A": _samples(45, 2)})
    axes = fig.axes
    assert [ax.get_title().split(":")[0] for ax in axes] == ["node A", "node B"]
    counts = [
        [len(c.get_offsets()) for c in ax.collections if isinstance(c, PathCollection)]
        for ax in axes
    ]
    assert counts == [[120, 45], [30]]
    colors = [c.get_facecolor()[0][:3] for c in axes[0].collections]
    assert colors[0][1] > colors[0][0]  # learning green
    assert colors[1][0] > colors[1][2]  # testing orange


def test_coverage_points_are_drawn_in_degrees():
    az = np.radians([10.0, -170.0])
    el = np.radians([45.0, -30.0])
    fig = plot.coverage_figure({"A": (az, el)})
    np.testing.assert_allclose(fig.axes[0].collections[0].get_offsets(), [[10, 45], [-170, -30]])
    assert fig.axes[0].get_xlim() == (-180, 180) and fig.axes[0].get_ylim() == (-90, 90)


def test_coverage_subsamples_large_sets():
    fig = plot.coverage_figure({"A": _samples(5000)}, max_points=1000)
    assert len(fig.axes[0].collections[0].get_offsets()) == 1000


def test_pattern_maps_rows_columns_shared_scale_and_dots(truth, learned):
    samples = {"A": _samples(5000), "B": _samples(100, 1)}
    fig = plot.pattern_maps_figure(
        {"SH-3": learned, "other": learned}, truth, ["A", "B"], samples, step_deg=6, max_dots=800
    )
    panels = [ax for ax in fig.axes if ": node " in ax.get_title()]
    assert len(panels) == 3 * 2
    titles = [ax.get_title() for ax in panels]
    assert titles[:2] == ["truth: node A", "truth: node B"] and titles[2] == "SH-3: node A"
    for col in range(2):
        clims = {
            next(c for c in panels[r * 2 + col].collections if isinstance(c, QuadMesh)).get_clim()
            for r in range(3)
        }
        assert len(clims) == 1, "colour scale must be shared per column"
    dots = [
        [len(c.get_offsets()) for c in ax.collections if isinstance(c, PathCollection)]
        for ax in panels
    ]
    assert dots[:2] == [[], []]  # no sample dots over the truth
    assert dots[2] == [800] and dots[3] == [100]


def test_pattern_maps_truth_values_and_centering(truth):
    fig = plot.pattern_maps_figure({}, truth, ["A"], None, step_deg=4)
    mesh = next(c for c in fig.axes[0].collections if isinstance(c, QuadMesh))
    az, el = plot.az_el_grid_deg(4)
    expected = plot.pattern_map_db(truth, "A", az, el)
    np.testing.assert_allclose(np.asarray(mesh.get_array()).reshape(expected.shape), expected)
    # the peak of the map sits at the lobe (az 30, el 20)
    i, j = np.unravel_index(np.argmax(expected), expected.shape)
    assert abs(az[j] - 30) <= 2 and abs(el[i] - 20) <= 2
    fig_c = plot.pattern_maps_figure({}, truth, ["A"], None, center=True, step_deg=4)
    centred = np.asarray(
        next(c for c in fig_c.axes[0].collections if isinstance(c, QuadMesh)).get_array()
    ).reshape(expected.shape)
    assert abs(plot.sphere_mean_db(centred, el)) < 1e-9
    np.testing.assert_allclose(centred, expected - plot.sphere_mean_db(expected, el))


def test_pattern_maps_of_a_fitted_two_node_model(tmp_path):
    from rplearn.analysis.pattern_error import node_directions
    from rplearn.data.units import samples_of
    from rplearn.models.fit import fit_model
    from rplearn.models.spec import ModelSpec
    from rplearn.sim.flight import simulate

    sim = simulate("smoke", 0)
    s = samples_of(sim.matched_truth, sim.units("learning"))
    model = fit_model(s, ModelSpec.parse("sh-4")).model
    samples = node_directions(s)
    d = s.directions
    assert sum(v[0].size for v in samples.values()) == 2 * len(s)
    k = s.tx_index[0]
    assert samples[s.nodes[k]][0][0] == d.az_tx[0]
    p = plot.plot_pattern_maps(
        {"SH-4": model},
        sim.ground_truth,
        s.nodes,
        samples,
        tmp_path / "fig9.png",
        center=True,
        step_deg=5,
    )
    assert_valid_png(p, min_w=600, min_h=400)


def test_order_sweep_marks_the_minima():
    fig = charts.order_sweep_figure(
        [2, 4, 6, 8], [4.0, 2.5, 2.2, 2.6], [9e3, 6.5e3, 6.9e3, 7.4e3], [0.01, 0.02, 0.05, 0.5]
    )
    labels = [ln.get_label() for ax in fig.axes for ln in ax.get_lines()]
    assert "min RMSE: SH-6 (2.20 dB)" in labels
    assert "min AIC: SH-4" in labels
    assert fig.axes[1].get_yscale() == "log"  # LTD panel spanning decades
    fig = charts.order_sweep_figure([2, 4], [3.0, 2.0], [8e3, 7e3], [0.05, 0.06])
    assert fig.axes[1].get_yscale() == "linear"


def test_order_sweep_best_order_marker_is_not_hidden_under_the_aic_marker():
    """Issue 26: where the lowest test RMSE and the lowest AIC fall on one order (and one spot of the
    figure), the best-order star is drawn on top, and the AIC's mark is a ring around it."""
    from matplotlib.colors import to_rgb

    rmse = np.array([4.0, 2.5, 2.2, 2.6])
    fig = charts.order_sweep_figure([2, 4, 6, 8], rmse, rmse * 2e3, [0.01, 0.02, 0.05, 0.06])
    fig.canvas.draw()
    ax = fig.axes[0]
    star = next(ln for ln in ax.get_lines() if ln.get_label().startswith("min RMSE"))
    ring = next(ln for a in fig.axes for ln in a.get_lines() if ln.get_label().startswith("min AIC"))
    xs, ys = ax.transData.transform((6.0, 2.2))
    xr, yr = ring.axes.transData.transform((6.0, 4.4))
    assert abs(xs - xr) < 2 and abs(ys - yr) < 2  # the two marks fall on one spot
    img = np.asarray(fig.canvas.buffer_rgba())[..., :3] / 255.0
    centre = img[int(round(img.shape[0] - ys)), int(round(xs))]
    assert np.allclose(centre, to_rgb(star.get_color()), atol=0.08), centre  # the green star shows
    assert ring.get_markerfacecolor() == "none" and ax.get_zorder() > ring.axes.get_zorder()


def test_epsilon_sweep_axis():
    fig = charts.epsilon_sweep_figure(np.logspace(-3, 6, 19), np.full(19, 1.7))
    ax = fig.axes[0]
    assert ax.get_xscale() == "log"
    np.testing.assert_allclose(ax.get_xlim(), (1e-3, 1e6))
    lo, hi = ax.get_ylim()
    assert lo < 1.7 < hi  # a flat line is drawn in a visible band
    with pytest.raises(InputError):
        charts.epsilon_sweep_figure([0.0, 1.0], [1.0, 1.0])


def test_rank_study_bars():
    fig = charts.rank_study_figure([("two", 128, 127), ("three", 192, 192)])
    heights = [p.get_height() for p in fig.axes[0].patches]
    assert heights == [128, 192, 127, 192]
    texts = [t.get_text() for t in fig.axes[0].texts]
    assert texts == ["deficiency 1", "deficiency 0"]


@pytest.mark.parametrize(
    "call",
    [
        lambda: charts.rssi_time_figure([0, 1, 2], [1, 2]),
        lambda: charts.order_sweep_figure([1, 2], [1.0], [1.0, 2.0], [1.0, 2.0]),
        lambda: plot.coverage_figure({}),
        lambda: plot.pattern_maps_figure({"x": object()}, None),
        lambda: charts.rank_study_figure([]),
    ],
)
def test_bad_input_is_an_input_error(call):
    with pytest.raises(InputError):
        call()


def test_core_modules_do_not_import_matplotlib():
    code = (
        "import sys, rplearn.io.export, rplearn.viz.report, rplearn.models.patterns, rplearn.models.fit, rplearn.sim.antennas; "
        "assert not any(m == 'matplotlib' or m.startswith('matplotlib.') for m in sys.modules), 'matplotlib imported'"
    )
    subprocess.run([sys.executable, "-c", code], check=True, timeout=60)


def test_a_figure_is_never_written_into_a_missing_folder(truth, tmp_path):
    """One rule for every output file: its folder must exist (no folder is made silently)."""
    from rplearn.errors import InputError

    with pytest.raises(InputError, match="non-existent directory"):
        plot.plot_pattern_3d(truth, "A", tmp_path / "sub" / "p3d.png", step_deg=10)
    assert not (tmp_path / "sub").exists()


def test_spread_maps_of_an_automatic_fit(tmp_path):
    """Issue 24, item 5: each node's own-pattern spread, uncovered directions hatched, the
    certificate's figures in the titles."""
    from rplearn.analysis.decoupling import certify
    from rplearn.data.units import samples_of
    from rplearn.models.auto import fit_auto
    from rplearn.sim.flight import simulate

    sim = simulate("smoke", 0)
    s = samples_of(sim.matched_truth, sim.units("learning"))
    blocks = np.array_split(np.arange(len(s)), 3)
    from rplearn.core.geometry import Directions
    from rplearn.data.tables import LinkSamples

    part = lambda b: LinkSamples(Directions(*(np.asarray(v)[b] for v in s.directions)), s.tx_index[b], s.rx_index[b],  # noqa: E731
                                 s.nodes, s.joint_gain_db[b], s.distance_m[b])
    model = fit_auto({f"u{k}": part(b) for k, b in enumerate(blocks)})[0].model
    cert = certify(model, [s])
    fig = plot.spread_maps_figure({"auto": model}, step_deg=6)
    maps = [ax for ax in fig.axes if ax.get_title()]  # the colour bar has no title
    meshes = [a for ax in maps for a in ax.collections if isinstance(a, QuadMesh)]
    assert len(maps) == len(meshes) == len(model.nodes)
    values = np.asarray(meshes[0].get_array())
    assert values.min() >= 0 and values.max() > values.min()
    titles = [ax.get_title() for ax in maps]
    assert any(f"{cert.nodes['A'].covered_std_db:.2f} dB where looked" in t for t in titles)
    assert all(len(ax.collections) > 1 for ax in maps)  # the hatched uncovered region
    assert_valid_png(plot.plot_spread_maps({"auto": model}, tmp_path / "spread.png", step_deg=6), min_w=600, min_h=300)
    model.covariance = None
    with pytest.raises(InputError, match="no covariance"):
        plot.spread_maps_figure({"auto": model})
