"""A self-contained HTML report (Table I, figures with captions, provenance) and its screenshot.

:func:`write_report` writes ONE file, ``report.html``: inline CSS, every image embedded as a
base64 ``data:`` URI and no external resource, so the page can be mailed or archived as it is
and opens offline. A report without interactive figures holds no JavaScript; one with
interactive figures (:class:`rplearn.viz.interactive.InteractiveFigure`, e.g. rotatable 3-D
patterns) embeds plotly.js once, inline, and each figure as a ``<div>`` and its ``<script>``.
:func:`screenshot_report` renders it to PNG with headless Chromium (software WebGL, no
network) when one is installed.

Text accepted by the report
---------------------------
- The Table I argument is either a simple Markdown pipe table (the output of
  :func:`rplearn.models.fit.scores_markdown`: a header row, a ``|---|---:|`` separator row whose
  colons give the alignment, then body rows) or a sequence of dict rows (keys = columns, in
  the order of the first row).
- A section's text is HTML when it starts with ``<`` (inserted as given: the caller vouches for
  it), else a Markdown subset: paragraphs separated by blank lines, ``- `` bullet lists, pipe
  tables, fenced code blocks (lines between two ```` ``` ```` lines, shown preformatted),
  ``**bold**``, ``*italic*`` and ```code```; everything else is escaped.
"""

from __future__ import annotations

import base64
import html
import json
import os
import re
import shutil
import struct
import subprocess
import tempfile
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from rplearn._argtypes import check_types
from rplearn._atomic import atomic_open
from rplearn._version import __version__
from rplearn.errors import InputError, RplearnError
from rplearn.viz.interactive import InteractiveFigure

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
PAGE_WIDTH_PX = 1400
CONTENT_WIDTH_PX = 1200
CHROMIUM_NAMES = ("chromium", "chromium-browser")
#: Virtual time Chromium gives the page's scripts before the screenshot [ms].
VIRTUAL_TIME_MS = 15000


class ScreenshotError(RplearnError):
    """Chromium is installed but failed to render the report."""


@check_types
@dataclass
class ReportSection:
    """One section of the report.

    Attributes
    ----------
    title : str
    text : str
        Markdown subset or HTML (see the module docstring).
    images : list of path
        PNG (or JPEG/SVG) files, embedded in order.
    captions : list of str, optional
        One caption per image; default the PNG's ``Description`` text (every figure of
        :mod:`rplearn.viz.plot` carries one), else the file name without extension.
    interactive : list of InteractiveFigure
        HTML figures (e.g. :func:`rplearn.viz.interactive.pattern_3d_html`), after the images,
        two to a row, numbered on from them; each carries its caption.
    """

    title: str
    text: str = ""
    images: Sequence[str | os.PathLike[str]] = field(default_factory=list)
    captions: list[str] | None = None
    interactive: list[InteractiveFigure] = field(default_factory=list)


# -- Markdown subset -----------------------------------------------------------------------
def _inline_md(text: str) -> str:
    out = html.escape(text, quote=False)
    out = re.sub(r"`([^`]+)`", r"<code>\1</code>", out)
    out = re.sub(r"\*\*([^*]+)\*\*", r"<strong>\1</strong>", out)
    out = re.sub(r"(?<![*\w])\*([^*\s][^*]*)\*(?![*\w])", r"<em>\1</em>", out)
    return out


def _split_row(line: str) -> list[str]:
    s = line.strip()
    s = s.removeprefix("|")
    s = s.removesuffix("|")
    return [c.strip() for c in s.split("|")]


_SEP_CELL = re.compile(r":?-{1,}:?")


def markdown_table_to_html(table_markdown: str) -> str:
    """Convert a simple Markdown pipe table to an HTML ``<table>``.

    Raises :class:`InputError` naming the line when the table has no separator row.
    """
    lines = [ln for ln in str(table_markdown).strip().splitlines() if ln.strip()]
    if len(lines) < 2:
        raise InputError(
            "table: expected a Markdown table with a header and a '|---|' separator line"
        )
    head = _split_row(lines[0])
    seps = _split_row(lines[1])
    if not all(_SEP_CELL.fullmatch(c.replace(" ", "")) for c in seps):
        raise InputError(
            f"table line 2: expected a '|---|---:|' separator row, got {lines[1].strip()!r}"
        )
    align = []
    for c in seps + [""] * (len(head) - len(seps)):
        c = c.replace(" ", "")
        align.append(
            "center"
            if c.startswith(":") and c.endswith(":")
            else "right"
            if c.endswith(":")
            else "left"
        )
    out = ["<table>", "<thead><tr>"]
    out += [f'<th style="text-align:{a}">{_inline_md(h)}</th>' for h, a in zip(head, align)]
    out += ["</tr></thead>", "<tbody>"]
    for ln in lines[2:]:
        cells = _split_row(ln)
        cells = (cells + [""] * len(head))[: len(head)]
        out.append(
            "<tr>"
            + "".join(
                f'<td style="text-align:{a}">{_inline_md(c)}</td>' for c, a in zip(cells, align)
            )
            + "</tr>"
        )
    out += ["</tbody>", "</table>"]
    return "\n".join(out)


def rows_to_html(rows: Sequence[Mapping[str, Any]]) -> str:
    """An HTML table of dict rows (columns in the order of the first row's keys, then new ones)."""
    if not rows:
        raise InputError("table: no row given")
    cols: list[str] = []
    for r in rows:
        cols += [str(k) for k in r if str(k) not in cols]

    def cell(v: Any) -> str:
        if isinstance(v, float):
            return f"{v:.4g}"
        return "" if v is None else str(v)

    out = [
        "<table>",
        "<thead><tr>" + "".join(f"<th>{html.escape(c)}</th>" for c in cols) + "</tr></thead>",
        "<tbody>",
    ]
    for r in rows:
        vals = {str(k): v for k, v in r.items()}
        out.append(
            "<tr>" + "".join(f"<td>{html.escape(cell(vals.get(c)))}</td>" for c in cols) + "</tr>"
        )
    out += ["</tbody>", "</table>"]
    return "\n".join(out)


def _blocks(text: str) -> list[tuple[str, list[str]]]:
    """Split text into ("code", lines) fenced blocks and ("text", lines) blank-line blocks."""
    blocks: list[tuple[str, list[str]]] = []
    current: list[str] = []
    code: list[str] | None = None
    for ln in text.splitlines():
        if code is not None:
            if ln.strip().startswith("```"):
                blocks.append(("code", code))
                code = None
            else:
                code.append(ln)
        elif ln.strip().startswith("```"):
            if current:
                blocks.append(("text", current))
                current = []
            code = []
        elif not ln.strip():
            if current:
                blocks.append(("text", current))
                current = []
        else:
            current.append(ln)
    if code is not None:  # an unclosed fence runs to the end
        blocks.append(("code", code))
    if current:
        blocks.append(("text", current))
    return blocks


def markdown_to_html(text: str) -> str:
    """The Markdown subset of the module docstring to HTML; text starting with ``<`` is HTML."""
    text = str(text or "")
    if text.lstrip().startswith("<"):
        return text
    out = []
    for kind, lines in _blocks(text):
        if kind == "code":
            out.append(f"<pre><code>{html.escape(chr(10).join(lines), quote=False)}</code></pre>")
        elif all(ln.strip().startswith("|") for ln in lines) and len(lines) >= 2:
            out.append(markdown_table_to_html("\n".join(lines)))
        elif all(ln.strip().startswith(("- ", "* ")) for ln in lines):
            items = "".join(f"<li>{_inline_md(ln.strip()[2:])}</li>" for ln in lines)
            out.append(f"<ul>{items}</ul>")
        else:
            out.append(f"<p>{_inline_md(' '.join(ln.strip() for ln in lines))}</p>")
    return "\n".join(out)


# -- images --------------------------------------------------------------------------------
def image_mime(data: bytes) -> str | None:
    """MIME type of PNG, JPEG or SVG bytes; None otherwise."""
    if data.startswith(PNG_SIGNATURE):
        return "image/png"
    if data.startswith(b"\xff\xd8\xff"):
        return "image/jpeg"
    head = data[:512].lstrip().lower()
    if head.startswith(b"<svg") or (head.startswith(b"<?xml") and b"<svg" in data[:2048].lower()):
        return "image/svg+xml"
    return None


def png_size_px(data: bytes) -> tuple[int, int]:
    """``(width, height)`` of PNG bytes from their IHDR chunk; InputError if not a PNG."""
    if not data.startswith(PNG_SIGNATURE) or len(data) < 24 or data[12:16] != b"IHDR":
        raise InputError("image: not a PNG (bad signature or IHDR)")
    return struct.unpack(">II", data[16:24])


def png_text_chunks(data: bytes) -> dict[str, str]:
    """Text chunks (``tEXt`` and uncompressed ``iTXt``) of PNG bytes; empty if not a PNG."""
    out: dict[str, str] = {}
    if not data.startswith(PNG_SIGNATURE):
        return out
    pos = len(PNG_SIGNATURE)
    while pos + 8 <= len(data):
        (length,) = struct.unpack(">I", data[pos : pos + 4])
        kind = data[pos + 4 : pos + 8]
        body = data[pos + 8 : pos + 8 + length]
        pos += 12 + length
        if kind == b"IDAT" or kind == b"IEND":
            break  # matplotlib writes text chunks before the image data
        if kind == b"tEXt" and b"\0" in body:
            key, _, text = body.partition(b"\0")
            out[key.decode("latin-1")] = text.decode("latin-1")
        elif kind == b"iTXt" and b"\0" in body:
            key, _, rest = body.partition(b"\0")
            if len(rest) >= 2 and rest[0] == 0:  # not compressed
                _lang, _, rest = rest[2:].partition(b"\0")
                _tkey, _, text = rest.partition(b"\0")
                out[key.decode("latin-1")] = text.decode("utf-8", errors="replace")
    return out


def default_caption(path: str | os.PathLike[str]) -> str:
    """A figure's caption: its PNG ``Description`` (written by :mod:`rplearn.viz.plot`), else its name."""
    p = os.fspath(path)
    try:
        with open(p, "rb") as f:
            head = f.read(65536)
    except OSError:
        head = b""
    text = png_text_chunks(head)
    return text.get("Description") or text.get("Title") or Path(p).stem.replace("_", " ")


def image_data_uri(path: str | os.PathLike[str]) -> str:
    """A base64 ``data:`` URI of an image file; InputError if missing or of an unknown type."""
    p = os.fspath(path)
    try:
        data = Path(p).read_bytes()
    except OSError as exc:
        raise InputError(f"{p}: cannot read image ({exc.strerror})") from None
    mime = image_mime(data)
    if mime is None:
        raise InputError(f"{p}: not a PNG, JPEG or SVG image")
    return f"data:{mime};base64,{base64.b64encode(data).decode('ascii')}"


# -- page ----------------------------------------------------------------------------------
_CSS = f"""
body {{ font-family: "DejaVu Sans", Arial, Helvetica, sans-serif; color: #222; background: #fff;
       margin: 0 auto; padding: 24px; max-width: {CONTENT_WIDTH_PX}px; line-height: 1.45; }}
h1 {{ font-size: 26px; border-bottom: 2px solid #2a6f4f; padding-bottom: 6px; }}
h2 {{ font-size: 20px; margin-top: 36px; color: #2a6f4f; }}
table {{ border-collapse: collapse; margin: 12px 0; font-size: 14px; }}
th, td {{ border: 1px solid #bbb; padding: 4px 10px; }}
th {{ background: #e8f1ec; }}
tbody tr:nth-child(even) {{ background: #f7f7f7; }}
figure {{ margin: 18px 0; text-align: center; }}
figure img {{ max-width: 100%; height: auto; border: 1px solid #ddd; }}
figcaption {{ font-size: 14px; color: #444; margin-top: 4px; }}
code {{ background: #f2f2f2; padding: 0 3px; }}
pre {{ background: #f6f6f6; border: 1px solid #ddd; padding: 8px; overflow-x: auto; font-size: 13px; }}
pre code {{ background: none; padding: 0; }}
.fig3d-grid {{ display: grid; grid-template-columns: repeat(2, minmax(0, 1fr)); gap: 14px; margin: 18px 0; }}
.fig3d-grid figure {{ margin: 0; border: 1px solid #ddd; }}
.fig3d-grid figcaption {{ padding: 0 8px 6px; }}
footer {{ margin-top: 40px; border-top: 1px solid #bbb; font-size: 12px; color: #555; }}
footer table {{ font-size: 12px; }}
"""


def _provenance_html(provenance: Mapping[str, Any]) -> str:
    prov = {str(k): v for k, v in provenance.items()}
    if "version" not in prov and "rplearn_version" not in prov:
        prov = {"version": __version__, **prov}
    rows = []
    for k, v in prov.items():
        text = v if isinstance(v, str) else json.dumps(v, default=str, sort_keys=True)
        rows.append(f"<tr><th>{html.escape(k)}</th><td><code>{html.escape(text)}</code></td></tr>")
    return "<table>" + "".join(rows) + "</table>"


@check_types
def render_report_html(
    title: str,
    table: str | Sequence[Mapping[str, Any]] | None,
    sections: Sequence[ReportSection],
    provenance: Mapping[str, Any],
    table_title: str = "Table I: performance of the learned models on the testing samples",
) -> str:
    """The report page as a string (see :func:`write_report`)."""
    parts = [
        "<!DOCTYPE html>",
        '<html lang="en"><head><meta charset="utf-8">',
        f"<title>{html.escape(title)}</title>",
        f"<style>{_CSS}</style>",
    ]
    if any(s.interactive for s in sections):  # the library once, before every figure's script
        from rplearn.viz.interactive import plotly_library_script

        parts.append(plotly_library_script())
    parts += [
        "</head><body>",
        f"<h1>{html.escape(title)}</h1>",
    ]
    if table is not None and (not isinstance(table, str) or table.strip()):
        parts.append(f"<h2>{html.escape(table_title)}</h2>")
        parts.append(
            markdown_table_to_html(table) if isinstance(table, str) else rows_to_html(table)
        )
    n_fig = 0
    for s in sections:
        parts.append(f"<section><h2>{html.escape(s.title)}</h2>")
        parts.append(markdown_to_html(s.text))
        captions = list(s.captions or [])
        if captions and len(captions) != len(s.images):
            raise InputError(
                f"section {s.title!r}: {len(captions)} captions for {len(s.images)} images"
            )
        for k, img in enumerate(s.images):
            n_fig += 1
            cap = captions[k] if captions else default_caption(img)
            parts.append(
                f'<figure><img src="{image_data_uri(img)}" alt="{html.escape(cap)}">'
                f"<figcaption><strong>Figure {n_fig}.</strong> {_inline_md(cap)}</figcaption></figure>"
            )
        if s.interactive:
            rows = (len(s.interactive) + 1) // 2
            height = sum(max(f.height_px for f in s.interactive[2 * r : 2 * r + 2]) + 70 for r in range(rows))
            parts.append(f'<div class="fig3d-grid" data-rplearn-height="{height}">')
            for fig in s.interactive:
                n_fig += 1
                parts.append(
                    f"<figure>{fig.html}<figcaption><strong>Figure {n_fig}.</strong> "
                    f"{_inline_md(fig.caption)}</figcaption></figure>"
                )
            parts.append("</div>")
        parts.append("</section>")
    parts.append(f"<footer><h3>Provenance</h3>{_provenance_html(provenance)}</footer>")
    parts.append("</body></html>")
    return "\n".join(parts) + "\n"


@check_types
def write_report(
    out_dir: str | os.PathLike[str],
    title: str,
    table_markdown: str | Sequence[Mapping[str, Any]] | None,
    sections: Sequence[ReportSection],
    provenance: Mapping[str, Any],
    filename: str = "report.html",
    table_title: str = "Table I: performance of the learned models on the testing samples",
) -> str:
    """Write one self-contained HTML report and return its path.

    Parameters
    ----------
    out_dir : path
        Directory (created if needed).
    title : str
    table_markdown : str or sequence of dict, or None
        Table I as a Markdown pipe table (e.g. :func:`rplearn.models.fit.scores_markdown`) or as
        dict rows; None for no table.
    sections : sequence of ReportSection
        Text and figures, each figure captioned and numbered.
    provenance : mapping
        Version, command, parameters, seed... shown in the footer (``version`` defaults to
        the library's).
    filename : str
    table_title : str
        Heading of the table.

    Returns
    -------
    str
        Path of ``<out_dir>/<filename>``.
    """
    page = render_report_html(title, table_markdown, sections, provenance, table_title)
    out = Path(os.fspath(out_dir))
    out.mkdir(parents=True, exist_ok=True)
    path = out / filename
    with atomic_open(path, "w", encoding="utf-8") as fh:
        fh.write(page)
    return str(path)


# -- screenshot ----------------------------------------------------------------------------
def find_chromium() -> str | None:
    """Path of a Chromium executable on PATH (``chromium`` or ``chromium-browser``), or None."""
    for name in CHROMIUM_NAMES:
        exe = shutil.which(name)
        if exe:
            return exe
    return None


_DATA_PNG = re.compile(r'src="data:image/png;base64,([A-Za-z0-9+/=]+)"')
_SCRIPT = re.compile(r"<script\b.*?</script>", re.DOTALL | re.IGNORECASE)
_GRID_HEIGHT = re.compile(r'data-rplearn-height="(\d+)"')


def estimate_page_height_px(page_html: str, width_px: int = PAGE_WIDTH_PX) -> int:
    """A window height [px] tall enough for the whole report (images, tables, text)."""
    content = min(CONTENT_WIDTH_PX, width_px - 48)
    page_html = _SCRIPT.sub("", page_html)  # plotly.js and figure data are no text
    h = 300 + sum(int(v) for v in _GRID_HEIGHT.findall(page_html))
    for m in _DATA_PNG.finditer(page_html):
        try:
            w, hh = png_size_px(base64.b64decode(m.group(1)))
        except (InputError, ValueError):
            continue
        h += int(hh * min(1.0, content / max(w, 1))) + 80
    h += 34 * page_html.count("<tr")
    text = re.sub(r"<[^>]+>", " ", _DATA_PNG.sub("", page_html))
    h += 24 * (len(" ".join(text.split())) // 120 + 1) + 60 * page_html.count("<h2")
    return int(min(max(h, 800), 30000))


def chromium_command(exe: str, profile: str, width_px: int, height_px: int, flags: Sequence[str] = ()) -> list[str]:
    """Headless Chromium without network (every host name unresolvable, a dead proxy), with
    software WebGL (SwiftShader) and :data:`VIRTUAL_TIME_MS` for the page's scripts; the page's
    URI is to be appended."""
    return [
        exe, "--headless", "--no-sandbox", "--disable-gpu",
        # WebGL for 3-D figures on SwiftShader (software); Chromium no longer falls back to it silently
        "--use-angle=swiftshader", "--enable-unsafe-swiftshader",
        # no network: the report must render from itself
        "--proxy-server=127.0.0.1:9", "--proxy-bypass-list=<-loopback>", "--host-resolver-rules=MAP * ~NOTFOUND",
        "--disable-quic", "--no-first-run", "--disable-background-networking", "--disable-component-update",
        "--disable-sync", "--disable-dev-shm-usage", "--hide-scrollbars", f"--user-data-dir={profile}",
        f"--window-size={int(width_px)},{int(height_px)}", f"--virtual-time-budget={VIRTUAL_TIME_MS}",
        *[str(f) for f in flags],
    ]


@check_types
def screenshot_report(
    html_path: str | os.PathLike[str],
    png_path: str | os.PathLike[str],
    width_px: int = PAGE_WIDTH_PX,
    height_px: int | None = None,
    timeout_s: float = 120.0,
    chromium_flags: Sequence[str] = (),
) -> bool:
    """Render the report to PNG with headless Chromium.

    Chromium runs without network (every host name unresolvable, a dead proxy), so the
    screenshot shows what the report holds itself, and with software WebGL (SwiftShader), so
    that 3-D figures are drawn without a GPU; it waits for scripts (a virtual time budget).

    Parameters
    ----------
    html_path, png_path : path
    width_px : int
        Window width [px].
    height_px : int, optional
        Window height [px]; default estimated from the page (:func:`estimate_page_height_px`).
    timeout_s : float
        Time limit of the Chromium run [s].
    chromium_flags : sequence of str
        More command-line flags for Chromium (after the default ones).

    Returns
    -------
    bool
        True when the PNG was written, False when no Chromium is installed.

    Raises
    ------
    ScreenshotError
        When Chromium runs but writes no image.
    """
    exe = find_chromium()
    if exe is None:
        return False
    html_file = Path(os.fspath(html_path)).resolve()
    if not html_file.is_file():
        raise InputError(f"{html_file}: no such report")
    png = Path(os.fspath(png_path)).resolve()
    png.parent.mkdir(parents=True, exist_ok=True)
    if png.exists():
        png.unlink()
    if height_px is None:
        height_px = estimate_page_height_px(
            html_file.read_text(encoding="utf-8", errors="replace"), width_px
        )
    with tempfile.TemporaryDirectory(prefix="rplearn-chromium-") as profile:
        cmd = chromium_command(exe, profile, width_px, height_px, [f"--screenshot={png}", *chromium_flags])
        cmd.append(html_file.as_uri())
        try:
            proc = subprocess.run(
                cmd, capture_output=True, text=True, timeout=timeout_s, check=False
            )
        except subprocess.TimeoutExpired:
            raise ScreenshotError(
                f"{html_file}: chromium did not finish within {timeout_s:g} s"
            ) from None
    if not png.is_file() or png.stat().st_size == 0:
        tail = (proc.stderr or proc.stdout or "").strip().splitlines()[-1:] or ["no output"]
        raise ScreenshotError(
            f"{html_file}: chromium (exit {proc.returncode}) wrote no screenshot: {tail[0]}"
        )
    return True
