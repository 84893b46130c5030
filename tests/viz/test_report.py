"""report: self-contained HTML (tables, embedded figures, provenance) and its Chromium screenshot."""

from __future__ import annotations

import base64
import io
import os
import re

import numpy as np
import pytest
from matplotlib.image import imread

from rplearn._version import __version__
from rplearn.errors import InputError
from rplearn.viz import charts, plot, report
from rplearn.viz.report import ReportSection, markdown_table_to_html, rows_to_html, screenshot_report, write_report

TABLE_MD = """| Method | RMSE/dB | MAE/dB | abs(phi) |
|---|---:|---:|:---:|
| SH-10 | 2.31 | 1.80 | 200 |
| M | 5.10 | 4.00 | 1 |"""

_IMG_SRC = re.compile(r"<img\b[^>]*\bsrc=\"([^\"]*)\"")


@pytest.fixture(scope="module")
def figures(tmp_path_factory):
    d = tmp_path_factory.mktemp("figs")
    rng = np.random.default_rng(0)
    samples = {"A": (rng.uniform(-3, 3, 300), rng.uniform(-1.5, 1.5, 300))}
    return [
        plot.plot_coverage(samples, None, d / "coverage.png"),
        charts.plot_order_sweep(
            [2, 4, 6], [3.0, 2.0, 2.4], [8e3, 6e3, 7e3], [0.01, 0.03, 0.1], d / "order_sweep.png"
        ),
        charts.plot_rank_study([("2 antennas", 128, 127), ("3 antennas", 192, 192)], d / "rank.png"),
    ]


def _report(tmp_path, figures):
    sections = [
        ReportSection(
            "Coverage",
            "Learning samples in **green**.\n\n- one\n- two `x < y`",
            figures[:1],
            ["Coverage (paper Fig. 8a)."],
        ),
        ReportSection("Model order", "<p>Raw <b>HTML</b> section.</p>", figures[1:]),
    ]
    prov = {"command": "rplearn demo --seed 7", "seed": 7, "parameters": {"models": ["sh-10", "m"]}}
    return write_report(tmp_path / "out", "rplearn test report", TABLE_MD, sections, prov)


def _decoded_images(page: str) -> list[bytes]:
    out = []
    for src in _IMG_SRC.findall(page):
        assert src.startswith("data:image/png;base64,"), src[:40]
        out.append(base64.b64decode(src.split(",", 1)[1], validate=True))
    return out


def test_markdown_table_to_html():
    t = markdown_table_to_html(TABLE_MD)
    assert t.count("<tr>") == 3 and t.count("<th ") == 4 and t.count("<td ") == 8
    assert '<td style="text-align:right">2.31</td>' in t
    assert (
        '<th style="text-align:left">Method</th>' in t
        and '<td style="text-align:center">200</td>' in t
    )
    with pytest.raises(InputError, match="separator"):
        markdown_table_to_html("| a | b |\n| 1 | 2 |")


def test_markdown_subset():
    page = report.markdown_to_html(
        "Intro *a* and **b**.\n\n```\nline 1\n\nx < 2\n```\n- item `c`\n- two"
    )
    assert page.startswith("<p>Intro <em>a</em> and <strong>b</strong>.</p>")
    assert "<pre><code>line 1\n\nx &lt; 2</code></pre>" in page
    assert "<ul><li>item <code>c</code></li><li>two</li></ul>" in page
    assert report.markdown_to_html("<div>raw</div>") == "<div>raw</div>"


def test_rows_table_and_escaping():
    t = rows_to_html([{"Method": "SH-10", "RMSE/dB": 2.3149}, {"Method": "<M>", "extra": None}])
    assert "<th>extra</th>" in t and "2.315" in t and "&lt;M&gt;" in t


def test_report_is_one_self_contained_page(tmp_path, figures):
    path = _report(tmp_path, figures)
    assert os.listdir(tmp_path / "out") == ["report.html"]
    with open(path, encoding="utf-8") as f:
        page = f.read()
    assert "<script" not in page.lower()
    assert not re.search(r"(src|href)=\"(https?:|//|file:)", page)
    assert "@import" not in page and "url(" not in page
    images = _decoded_images(page)
    assert len(images) == 3
    for data in images:
        img = imread(io.BytesIO(data), format="png")
        assert img.shape[0] > 100 and img.shape[1] > 100
    assert page.count("<figcaption>") == 3
    assert "Figure 1.</strong> Coverage (paper Fig. 8a)." in page  # given caption
    assert "Figure 3.</strong> Columns and rank of the design matrix" in page  # from the PNG
    assert (
        "<strong>green</strong>" in page
        and "<code>x &lt; y</code>" in page
        and "<b>HTML</b>" in page
    )
    assert '<td style="text-align:right">2.31</td>' in page
    assert "rplearn demo --seed 7" in page and __version__ in page and "Provenance" in page
    assert "<th>version</th>" in page


def test_default_caption_falls_back_to_the_file_name(tmp_path, figures):
    from matplotlib.image import imsave

    bare = tmp_path / "my_figure.png"
    imsave(bare, np.random.default_rng(0).random((20, 30)))
    assert report.default_caption(bare) == "my figure"
    assert report.default_caption(figures[1]).startswith("Model order selection")
    assert report.default_caption(figures[1]).endswith("(paper Fig. 10).")


def test_report_rejects_missing_or_bad_images(tmp_path):
    with pytest.raises(InputError, match="cannot read image"):
        write_report(tmp_path, "t", TABLE_MD, [ReportSection("s", "", [tmp_path / "nope.png"])], {})
    (tmp_path / "fake.png").write_bytes(b"not an image")
    with pytest.raises(InputError, match="not a PNG"):
        write_report(tmp_path, "t", None, [ReportSection("s", "", [tmp_path / "fake.png"])], {})


def test_screenshot_returns_false_without_chromium(tmp_path, monkeypatch):
    monkeypatch.setattr(report.shutil, "which", lambda name: None)
    html = tmp_path / "r.html"
    html.write_text("<html><body>x</body></html>")
    assert screenshot_report(html, tmp_path / "r.png") is False
    assert not (tmp_path / "r.png").exists()


def _chromium_or_skip() -> None:
    """Skip without Chromium, except under CI=true, where a missing Chromium is a failure."""
    if report.find_chromium() is None:
        if os.environ.get("CI", "").strip().lower() == "true":
            pytest.fail(
                "CI=true but no chromium/chromium-browser on PATH: the report screenshot cannot be checked"
            )
        pytest.skip("chromium not installed")


def test_report_screenshot_in_chromium(tmp_path, figures):
    _chromium_or_skip()
    path = _report(tmp_path, figures)
    png = tmp_path / "shot" / "report.png"
    assert screenshot_report(path, png) is True
    data = png.read_bytes()
    assert data.startswith(b"\x89PNG\r\n\x1a\n") and len(data) > 30_000
    img = imread(str(png))
    assert img.shape[1] == report.PAGE_WIDTH_PX and img.shape[0] >= 800
    rgb = img[..., :3]
    assert float(rgb.var()) > 0.005, "screenshot is blank"
    # the page is white with drawings: mostly light, some dark pixels (text, axes)
    dark = float((rgb.mean(axis=2) < 0.3).mean())
    assert 0.001 < dark < 0.5
    # the figures are rendered: many coloured (non-grey) pixels, e.g. the green/blue curves and bars
    chroma = rgb.max(axis=2) - rgb.min(axis=2)
    assert float((chroma > 0.25).mean()) > 0.002
