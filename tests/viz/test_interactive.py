"""interactive: learned patterns as rotatable 3-D surfaces (plotly) in the one-file report."""

from __future__ import annotations

import os
import re
from pathlib import Path

import numpy as np
import pytest
from matplotlib.image import imread

from rplearn.core.geometry import Directions
from rplearn.core.sh import SphericalHarmonics, sh_index
from rplearn.data.tables import LinkSamples
from rplearn.errors import InputError
from rplearn.models.fit import node_coverage_grids
from rplearn.models.patterns import PatternSet
from rplearn.viz import interactive, plot, report
from rplearn.viz.interactive import InteractiveFigure, pattern_3d_figures, pattern_3d_html, pattern_3d_plotly
from rplearn.viz.report import ReportSection, screenshot_report, write_report

#: The first line of the embedded library, once per report.
PLOTLY_BANNER = re.compile(r"\* plotly\.js v\d+\.\d+\.\d+")


def _forward_lobe(nodes=("A", "B")) -> PatternSet:
    """Node A: a broad lobe straight ahead (+x, Y_1,1), sphere mean 2 dBi; node B: one to the
    left (+y, Y_1,-1)."""
    b = SphericalHarmonics(3)
    coef = np.zeros((len(nodes), b.n_coef))
    coef[0, sh_index(0, 0)] = 2.0 * np.sqrt(4 * np.pi)  # Y_0,0 = 1 / sqrt(4 pi)
    coef[0, sh_index(1, 1)] = 8.0
    coef[0, sh_index(2, 0)] = 2.0
    if len(nodes) > 1:
        coef[1, sh_index(1, -1)] = 6.0
    return PatternSet(b, tuple(nodes), coef)


def _with_upper_coverage(model: PatternSet) -> PatternSet:
    """Learned only from directions above 20 deg elevation: the rest of the sphere is uncovered."""
    rng = np.random.default_rng(1)
    n = 4000
    az = rng.uniform(-np.pi, np.pi, (2, n))
    el = np.arcsin(rng.uniform(np.sin(np.radians(20)), 1.0, (2, n)))
    samples = LinkSamples(Directions(az[0], el[0], az[1], el[1]), np.zeros(n, int), np.ones(n, int), ("A", "B"),
                          np.zeros(n), np.full(n, 10.0))
    model.training = model.training.replace(coverage_deg=node_coverage_grids(samples))
    return model


def _traces(fig, kind: str) -> list:
    return [t for t in fig.data if t.type == kind]


def test_surface_radius_and_colour_are_the_gain_in_the_body_frame():
    model = _forward_lobe()
    fig = pattern_3d_plotly(model, "A", "SH-3")
    (surface,) = _traces(fig, "surface")
    s = plot.pattern_surface(model, "A")
    gain = np.asarray(surface.surfacecolor, float)
    np.testing.assert_allclose(gain, s.gain_db, atol=1e-4)  # colour = gain [dBi] ...
    assert surface.cmin == pytest.approx(s.floor_db) and surface.cmax == pytest.approx(s.max_db)
    assert "dBi" in surface.colorbar.title.text
    x, y, z = (np.asarray(c, float) for c in (surface.x, surface.y, surface.z))
    radius = np.sqrt(x**2 + y**2 + z**2)
    # ... and radius = gain: the largest radius lies where the gain peaks, straight ahead (+x)
    k = np.unravel_index(np.argmax(radius), radius.shape)
    assert k == np.unravel_index(np.argmax(gain), gain.shape)
    assert x[k] > 0 and abs(y[k]) < 0.1 * x[k] and abs(z[k]) < 0.2 * x[k]
    assert np.all(np.diff(radius.ravel()[np.argsort(gain.ravel())]) > -1.0)  # monotonic (int16 rounding)
    # node B's lobe points left (+y)
    surface_b = _traces(pattern_3d_plotly(model, "B"), "surface")[0]
    xb, yb = np.asarray(surface_b.x, float), np.asarray(surface_b.y, float)
    kb = np.unravel_index(np.argmax(xb**2 + yb**2), xb.shape)
    assert yb[kb] > 0 and abs(xb[kb]) < 0.1 * yb[kb]
    # body axes, labelled, along x, y, z
    labels = {}
    for t in _traces(fig, "scatter3d"):
        if t.mode == "lines+text":
            tip = np.array([t.x[1], t.y[1], t.z[1]], float)
            labels[re.sub(r"<[^>]+>", "", t.text[1])] = tip / np.linalg.norm(tip)
    assert set(labels) == {"x forward", "y left", "z up"}
    np.testing.assert_allclose(labels["x forward"], [1, 0, 0])
    np.testing.assert_allclose(labels["y left"], [0, 1, 0])
    np.testing.assert_allclose(labels["z up"], [0, 0, 1])
    assert len(_traces(fig, "cone")) == 3
    # centred: relative to the sphere mean
    centred = _traces(pattern_3d_plotly(model, "A", center=True), "surface")[0]
    assert "sphere mean" in centred.colorbar.title.text
    np.testing.assert_allclose(np.asarray(centred.surfacecolor, float), gain - 2.0, atol=1e-3)


def test_uncovered_directions_are_dotted():
    model = _with_upper_coverage(_forward_lobe())
    fig = pattern_3d_plotly(model, "A", "SH-3")
    dots = [t for t in _traces(fig, "scatter3d") if t.mode == "markers"]
    assert len(dots) == 1 and dots[0].showlegend and "10°" in dots[0].name
    x, y, z = (np.asarray(c, float) for c in (dots[0].x, dots[0].y, dots[0].z))
    el = np.degrees(np.arctan2(z, np.hypot(x, y)))
    assert x.size > 100
    assert el.max() < 14.0  # only below the flight's directions (20 deg, less the 10 deg radius)
    assert el.min() < -80.0  # down to the nadir
    # dots sit just outside the drawn surface (its covered and faded parts, NaN outside each)
    s = plot.pattern_surface(model, "A")
    parts = _traces(fig, "surface")
    assert len(parts) == 2 and parts[1].opacity < 1.0
    grid = np.fmax(*[np.sqrt(np.asarray(t.x, float) ** 2 + np.asarray(t.y, float) ** 2 + np.asarray(t.z, float) ** 2)
                     for t in parts])
    i = np.rint((el - s.el_deg[0]) / (s.el_deg[1] - s.el_deg[0])).astype(int)
    j = np.rint((np.degrees(np.arctan2(y, x)) - s.az_deg[0]) / (s.az_deg[1] - s.az_deg[0])).astype(int)
    ratio = np.sqrt(x**2 + y**2 + z**2) / grid[i, j]
    assert np.all((ratio > 1.0) & (ratio < 1.05))
    fig_html = pattern_3d_html(model, "A", "SH-3")
    assert "dark grey dots" in fig_html.caption and "10°" in fig_html.caption
    # a model without stored coverage: no dots, no claim
    bare = pattern_3d_html(_forward_lobe(), "A", "SH-3")
    assert "dots" not in bare.caption


def test_html_fragment_has_no_library_and_no_network():
    fig = pattern_3d_html(_forward_lobe(), "A", "SH-3")
    assert isinstance(fig, InteractiveFigure) and fig.height_px == interactive.FIGURE_HEIGHT_PX
    assert "<html" not in fig.html.lower() and "Plotly.newPlot" in fig.html
    assert not PLOTLY_BANNER.search(fig.html)  # the library is the report's, not the figure's
    assert not re.search(r"<script[^>]*\bsrc=", fig.html, re.IGNORECASE)
    assert "mathjax" not in fig.html.lower()
    assert '"bdata"' in fig.html  # arrays travel as base64 (plotly >= 6), not as long JSON lists


def test_names_from_logs_are_text_not_markup(tmp_path):
    bad = "</script><img src=x onerror=alert(1)>"
    model = PatternSet(SphericalHarmonics(2), (bad,), np.ones((1, 4)))
    fig = pattern_3d_html(model, bad, label="<b>SH-2</b>")
    assert fig.html.count("</script>") == 1 and "<img" not in fig.html
    title = pattern_3d_plotly(model, bad, label="<b>SH-2</b>").layout.title.text
    assert "<" not in title and "&lt;b&gt;SH-2" in title
    path = write_report(tmp_path, "t", None, [ReportSection("3-D", "", interactive=[fig])], {})
    page = Path(path).read_text(encoding="utf-8")
    assert "<img" not in page.split("<body>", 1)[1]  # the caption is escaped too


def test_at_most_max_figures_with_a_note():
    model = _forward_lobe(("A", "B"))
    figures, text = pattern_3d_figures({"SH-3": model, "again": model}, max_figures=3)
    assert len(figures) == 3 and "first 3 of 4" in text
    assert "body axes" in text and "dots" not in text  # no coverage stored, no dots to explain
    assert figures[0].caption.startswith("SH-3, node A") and figures[2].caption.startswith("again, node A")
    figures, text = pattern_3d_figures({"SH-3": _with_upper_coverage(model)}, nodes=["B"])
    assert len(figures) == 1 and figures[0].caption.startswith("SH-3, node B")
    assert "dark grey dots" in text and "first" not in text
    assert pattern_3d_figures({}) == ([], "")
    with pytest.raises(InputError, match="max_figures"):
        pattern_3d_figures({"SH-3": model}, max_figures=0)


def _report_3d(tmp_path, png: str | None = None, n_figures: int = 2) -> str:
    model = _with_upper_coverage(_forward_lobe())
    figures = [pattern_3d_html(model, n, "SH-3") for n in ("A", "B")[:n_figures]]
    sections = [ReportSection("Interactive 3-D patterns", "Drag to rotate.", interactive=figures)]
    if png:
        sections.append(ReportSection("Coverage", "", [png]))
    return write_report(tmp_path / "out", "rplearn 3-D report", None, sections, {"seed": 1})


def test_report_embeds_plotly_once_and_fetches_nothing(tmp_path):
    rng = np.random.default_rng(0)
    png = plot.plot_coverage({"A": (rng.uniform(-3, 3, 200), rng.uniform(-1.5, 1.5, 200))}, None,
                             tmp_path / "coverage.png")
    path = _report_3d(tmp_path, png)
    assert os.listdir(tmp_path / "out") == ["report.html"]
    page = Path(path).read_text(encoding="utf-8")
    assert len(PLOTLY_BANNER.findall(page)) == 1  # the library once ...
    assert page.count("Plotly.newPlot(") == 2  # ... and one script per figure
    assert page.index("plotly.js v") < page.index("<body>")  # loaded before any figure's script
    # nothing from the network: no script, image, style or frame from a URL (in the markup; the
    # library's own text holds URLs of map tiles that only map traces would fetch)
    assert not re.search(r"<script[^>]*\bsrc=", page, re.IGNORECASE)
    markup = re.sub(r"(<script\b[^>]*>).*?</script>", r"\1</script>", page, flags=re.DOTALL | re.IGNORECASE)
    assert len(markup) < len(page) / 10  # the rest is scripts
    assert not re.search(r"""\b(src|href)\s*=\s*["']?(https?:|//|file:)""", markup, re.IGNORECASE)
    assert not re.search(r"<(link|iframe|object|embed)\b", markup, re.IGNORECASE)
    assert "@import" not in page
    after_library = page[page.index("</script>"):]  # the figures' scripts and the rest of the page
    assert "cdn.plot.ly" not in after_library and "https://cdn" not in after_library
    assert "mathjax" not in after_library.lower()
    # PNG figures still work and the numbering runs on after the 3-D figures' section
    assert page.count('<img src="data:image/png;base64,') == 1
    assert "<strong>Figure 1.</strong> SH-3, node A" in page
    assert "<strong>Figure 2.</strong> SH-3, node B" in page
    assert "<strong>Figure 3.</strong> Direction of the other end" in page
    assert page.count('class="fig3d-grid"') == 1
    # the screenshot is tall enough for the figures, and the script text is not counted as text
    height = report.estimate_page_height_px(page)
    assert interactive.FIGURE_HEIGHT_PX + 300 < height < 4000


def _chromium_or_skip() -> None:
    """Skip without Chromium, except under CI=true, where a missing Chromium is a failure."""
    if report.find_chromium() is None:
        if os.environ.get("CI", "").strip().lower() == "true":
            pytest.fail("CI=true but no chromium/chromium-browser on PATH: the 3-D figures cannot be checked")
        pytest.skip("chromium not installed")


def _scene_crop(png) -> np.ndarray:
    """RGB of the first 3-D figure's scene (top left of the grid, left of its colour bar)."""
    img = imread(str(png))[..., :3]
    # page 1400 px wide, content 1200 px from x = 100; h1 and h2 above the grid (about 170 px);
    # the figure is 480 px tall and about 590 px wide, its colour bar at the right
    return img[200:620, 110:560]


def _distinct_colours(rgb: np.ndarray) -> int:
    return len(np.unique(np.rint(rgb * 255).astype(np.uint8).reshape(-1, 3), axis=0))


def test_chromium_renders_the_3d_figures_offline(tmp_path):
    """The screenshot shows the 3-D surface (thousands of colours), not a blank canvas, with
    Chromium's network cut (screenshot_report: no host resolves, a dead proxy)."""
    _chromium_or_skip()
    path = _report_3d(tmp_path)
    png = tmp_path / "shot.png"
    assert screenshot_report(path, png, height_px=900) is True
    crop = _scene_crop(png)
    colours = _distinct_colours(crop)
    chroma = crop.max(axis=2) - crop.min(axis=2)
    assert colours > 1000, f"3-D figure not rendered: {colours} distinct colours"
    assert float((chroma > 0.2).mean()) > 0.05  # the viridis surface, not grey text
    # the same page without WebGL: plotly draws no scene, and the check above would fail
    blank = tmp_path / "no_webgl.png"
    assert screenshot_report(path, blank, height_px=900, chromium_flags=["--disable-3d-apis"]) is True
    assert _distinct_colours(_scene_crop(blank)) < 400


def test_chromium_with_a_network_only_library_draws_nothing(tmp_path):
    """The offline check has teeth: a page that loads plotly.js from a CDN shows no figure."""
    _chromium_or_skip()
    path = _report_3d(tmp_path, n_figures=1)
    page = Path(path).read_text(encoding="utf-8")
    start = page.index('<script type="text/javascript">')
    end = page.index("</script>", start) + len("</script>")
    cdn = page[:start] + '<script src="https://cdn.plot.ly/plotly-3.0.1.min.js"></script>' + page[end:]
    cdn_path = tmp_path / "cdn.html"
    cdn_path.write_text(cdn, encoding="utf-8")
    png = tmp_path / "cdn.png"
    assert screenshot_report(cdn_path, png, height_px=900) is True
    assert _distinct_colours(_scene_crop(png)) < 400


def test_uncovered_directions_are_drawn_faded_never_as_full_strength_lobes():
    """Beyond 10 deg from every learning direction the surface fades to the covered median and never
    rises above the largest covered gain (issue 26: SH-10 drew a star of extrapolated spikes)."""
    from rplearn.viz.interactive import FADE_END_DEG, supported_gain_db

    model = _with_upper_coverage(_forward_lobe())
    s = plot.pattern_surface(model, "A")
    az, el = np.meshgrid(np.radians(s.az_deg), np.radians(s.el_deg))
    cov = np.asarray(model.coverage_deg("A", az, el)).reshape(az.shape)
    support = supported_gain_db(s.gain_db, cov)
    covered = cov <= 10.0
    assert covered.any() and (~covered).any()
    np.testing.assert_array_equal(support.drawn_db[covered], s.gain_db[covered])
    assert support.drawn_db.max() <= s.gain_db[covered].max() + 1e-12
    far = cov >= FADE_END_DEG
    np.testing.assert_allclose(support.drawn_db[far], np.minimum(np.median(s.gain_db[covered]), support.support_max_db))
    fig = pattern_3d_plotly(model, "A", "SH-3", directions=(np.radians([0.0, 5.0]), np.radians([30.0, 30.0])))
    shown = np.concatenate([np.asarray(t.surfacecolor, float).ravel() for t in _traces(fig, "surface")])
    assert np.nanmax(shown) <= s.gain_db[covered].max() + 1e-3
    custom = np.asarray(_traces(fig, "surface")[0].customdata, float)
    assert custom.shape[-1] == 5 and custom[..., 4].max() == 2  # both learning directions near some point
    assert "learning samples within 10°" in _traces(fig, "surface")[0].hovertemplate
    assert supported_gain_db(s.gain_db, np.full(cov.shape, 90.0)) is None
