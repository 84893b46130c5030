"""Acceptance 1 of issue 26: the report of the README's field-guide log, rendered by headless
Chromium with the network cut, shows every figure of the default model, and its 3-D surfaces
draw no extrapolated spike."""

from __future__ import annotations

import json
import os
import re
import subprocess
import tempfile
from pathlib import Path

import numpy as np
import pytest
from matplotlib.image import imread

from rplearn.viz import report

LOG = Path(__file__).resolve().parents[1] / "fixtures" / "ardupilot" / "mavlink-log_2013-10-13_16-58-51.tlog"
WIDTH_PX = 1400
#: Script appended to a copy of the page: the boxes of its figures, in page pixels, after the scripts ran.
BOXES_JS = """<script>window.addEventListener('load', () => setTimeout(() => {
  const boxes = [...document.querySelectorAll('figure')].map(f => { const b = f.getBoundingClientRect();
    return {x: b.left + scrollX, y: b.top + scrollY, w: b.width, h: b.height, webgl: !!f.querySelector('.js-plotly-plot'),
            caption: (f.querySelector('figcaption') || {textContent: ''}).textContent.slice(0, 400)}; });
  const out = document.createElement('pre'); out.id = 'rplearn-boxes'; out.textContent = JSON.stringify(boxes);
  document.body.appendChild(out); }, 500));</script>"""


def _chromium_or_skip() -> str:
    exe = report.find_chromium()
    if exe is None:
        if os.environ.get("CI", "").strip().lower() == "true":
            pytest.fail("CI=true but no chromium/chromium-browser on PATH: the report cannot be checked")
        pytest.skip("chromium not installed")
    return exe


def figure_boxes(exe: str, page: Path, height_px: int, png: Path | None = None) -> list[dict]:
    """Each ``<figure>``'s box [px] in the page as Chromium lays it out in a window of the screenshot's size;
    with ``png``, the same Chromium run (:func:`report.chromium_command`, as :func:`report.screenshot_report`
    runs it) also writes the screenshot there."""
    shot = [] if png is None else [f"--screenshot={png}"]
    with tempfile.TemporaryDirectory(prefix="rplearn-boxes-") as profile:
        cmd = report.chromium_command(exe, profile, WIDTH_PX, height_px, [*shot, "--dump-dom"]) + [page.as_uri()]
        dom = subprocess.run(cmd, capture_output=True, text=True, timeout=180, check=False).stdout
    found = re.search(r'<pre id="rplearn-boxes">(.*?)</pre>', dom, re.S)
    assert found, f"chromium gave no figure boxes: {dom[-300:]}"
    return json.loads(found.group(1).replace("&quot;", '"').replace("&amp;", "&"))


def plotly_surfaces(page: str) -> list[list[dict]]:
    """The traces of every plotly figure in the page, as plotly.js receives them."""
    decoder = json.JSONDecoder()
    figures = []
    for m in re.finditer(r'Plotly\.newPlot\(\s*"[^"]+",\s*', page):
        traces, _ = decoder.raw_decode(page, m.end())
        figures.append(traces)
    return figures


def _array(value) -> np.ndarray:
    """A plotly array: a list, or a base64 typed array ``{"dtype", "bdata", "shape"}``."""
    if isinstance(value, dict):
        import base64

        a = np.frombuffer(base64.b64decode(value["bdata"]), dtype=np.dtype(value["dtype"]))
        shape = value.get("shape")
        return a.reshape([int(v) for v in str(shape).split(",")]) if shape else a
    return np.asarray(value, dtype=np.float64)


@pytest.fixture(scope="module")
def field_guide_report(tmp_path_factory):
    from typer.testing import CliRunner

    from rplearn.cli import app

    d = tmp_path_factory.mktemp("guide")
    runner = CliRunner()
    for args in (["sync", "--poses", LOG, "--signals", LOG, "--tx-power", "20", "--frequency", "915e6", "--link", "all",
                  "--max-gap", "1.0", "-o", d / "matched.parquet"],
                 ["report", d / "matched.parquet", "-o", d / "report"]):
        res = runner.invoke(app, [str(a) for a in args], env={"COLUMNS": "400"})
        assert res.exit_code == 0, res.output
    return d, res.output


def test_the_field_guide_report_renders_every_figure_offline(field_guide_report):
    exe = _chromium_or_skip()
    d, output = field_guide_report
    assert "model: SH-" in output and "log start" not in output.split("model:")[1]  # the epoch once, in the note
    html = d / "report" / "report.html"
    page = html.read_text(encoding="utf-8")
    probe = d / "probe.html"
    probe.write_text(page.replace("</body>", BOXES_JS + "</body>"), encoding="utf-8")
    height = report.estimate_page_height_px(page, WIDTH_PX)
    png = d / "shot.png"
    boxes = figure_boxes(exe, probe, height, png)  # one Chromium run for the boxes and the screenshot
    shot = imread(str(png))[..., :3]
    captions = " ".join(b["caption"] for b in boxes)
    # the default model's figures: time series with band, residual panels, coverage, polar cuts, maps, spread, 3-D
    for words in ("over time", "Residuals", "direction of the other end", "Polar cuts", "standard deviation",
                  "learned pattern in the body frame"):
        assert words.lower() in captions.lower(), (words, captions)
    assert sum(b["webgl"] for b in boxes) == 2 and len(boxes) == 8
    for b in boxes:
        x0, y0 = int(b["x"]), int(b["y"])
        x1, y1 = int(b["x"] + b["w"]), int(b["y"] + b["h"] * 0.85)  # above the caption
        assert y1 <= shot.shape[0], f"figure below the screenshot: {b['caption']}"
        region = shot[y0:y1, x0:x1]
        colours = len(np.unique(np.rint(region * 255).astype(np.uint8).reshape(-1, 3), axis=0))
        print(f"{colours:6d} distinct colours: {b['caption'][:60]}")
        assert colours > (1000 if b["webgl"] else 150), f"{colours} colours in {b['caption']!r}"
        b["colours"] = colours
    # the same probe without WebGL draws no 3-D scene: the colour count above has teeth
    blank = d / "blank.png"
    assert report.screenshot_report(probe, blank, width_px=WIDTH_PX, height_px=height,
                                     chromium_flags=["--disable-3d-apis"]) is True
    flat = imread(str(blank))[..., :3]
    b = next(b for b in boxes if b["webgl"])
    region = flat[int(b["y"]):int(b["y"] + 0.85 * b["h"]), int(b["x"]):int(b["x"] + b["w"])]
    without = len(np.unique(np.rint(region * 255).astype(np.uint8).reshape(-1, 3), axis=0))
    print(f"{without:6d} distinct colours without WebGL: {b['caption'][:60]}")
    assert without < 1000 and without * 3 < b["colours"]


def test_the_field_guide_3d_surfaces_draw_no_extrapolated_spike(field_guide_report):
    """No vertex of the drawn surface is more than 3 dB above the largest gain the data support
    within 10 deg (the model's gain over the directions within 10 deg of a learning sample,
    found here from the samples themselves, not from the model's stored coverage)."""
    from scipy.spatial import cKDTree

    from rplearn.analysis.pattern_error import node_directions
    from rplearn.data.units import samples_of, split_units, time_units
    from rplearn.io.files import read_dataset
    from rplearn.models.load import load_model

    d, _ = field_guide_report
    model = load_model(str(d / "report" / "model.json"))
    df, _ = time_units(read_dataset(str(d / "matched.parquet")))
    learn, _ = split_units(df)
    directions = node_directions(samples_of(df, learn))
    figures = plotly_surfaces((d / "report" / "report.html").read_text(encoding="utf-8"))
    assert len(figures) == 2
    raw_excess = []
    for node, traces in zip(model.nodes, figures):
        surfaces = [t for t in traces if t.get("type") == "surface"]
        assert surfaces and surfaces[0]["name"] == f"node {node}"
        custom = _array(surfaces[0]["customdata"]).reshape(-1, 5)
        az, el = np.radians(custom[:, 0].astype(np.float64)), np.clip(np.radians(custom[:, 1].astype(np.float64)), -np.pi / 2, np.pi / 2)

        def unit(a, e):
            return np.stack([np.cos(e) * np.cos(a), np.cos(e) * np.sin(a), np.sin(e)], axis=-1)

        learn_az, learn_el = directions[node]
        near = cKDTree(unit(learn_az, learn_el)).query(unit(az, el))[0] <= 2 * np.sin(np.radians(10.0) / 2)
        gain = np.asarray(model.evaluate(node, az, el))
        supported = float(gain[near].max())
        drawn = np.concatenate([_array(t["surfacecolor"]).ravel() for t in surfaces])
        assert np.isfinite(drawn).sum() >= custom.shape[0]  # every vertex is drawn, covered or faded
        assert np.nanmax(drawn) <= supported + 3.0, (node, float(np.nanmax(drawn)), supported)
        # the radius is the drawn gain (one affine map), so the shape shows what the colour says
        for t in surfaces:
            r = np.sqrt(sum(_array(t[k]).astype(np.float64).ravel() ** 2 for k in "xyz"))
            c = _array(t["surfacecolor"]).ravel()
            ok = np.isfinite(r) & np.isfinite(c) & (r > r[np.isfinite(r)].min() * 1.01)
            if ok.sum() > 10:
                slope, icpt = np.polyfit(c[ok], r[ok], 1)
                assert slope > 0 and np.max(np.abs(slope * c[ok] + icpt - r[ok])) < 0.01 * np.nanmax(r)
        raw_excess.append(float(gain.max()) - supported)
    print("largest model gain above the supported maximum (dB):", raw_excess)
