"""The preview as one self-contained HTML page: the annotated video embedded in it (base64 WebM, no file
beside it), the camera's state over time as inline SVG plots with a cursor that follows the video, and
the dataset card when the output has one.

One file that opens in any current browser with nothing else: no script or style is fetched, and the
card's pictures are embedded too. The card is markdown rendered by markdown-it-py (CommonMark and
tables, raw HTML escaped), or shown as preformatted text where that library is missing.
"""

from __future__ import annotations

import base64
import html
import io
import json
import mimetypes
from collections.abc import Sequence
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

PLOT_WIDTH_IN = 9.0
PLOT_PANEL_HEIGHT_IN = 1.6
PLOT_MARGIN_LEFT_IN, PLOT_MARGIN_RIGHT_IN, PLOT_MARGIN_TOP_IN, PLOT_MARGIN_BOTTOM_IN = 0.9, 0.15, 0.1, 0.5
PLOT_DPI = 96
"""SVG user units per inch: the plot is drawn at PLOT_WIDTH_IN · PLOT_DPI CSS pixels wide."""

PANELS = (
    ("angle, deg", (("pan_deg", "pan"), ("tilt_deg", "tilt")), False),
    ("zoom, x", (("zoom_x", "zoom"),), False),
    ("exposure, ms", (("exposure_time_s", "exposure time"),), True),
    ("gain, dB", (("gain_db", "gain"),), False),
)
"""(y label, ((camera.jsonl key, legend), …), log scale) of each plot panel; a panel none of whose keys the
states hold is left out. exposure_time_s is shown in ms."""
LOG_SCALE_RANGE = 10.0
"""A panel marked log is drawn on a log scale when its values span more than this factor."""

_STYLE = """
body { font-family: system-ui, sans-serif; margin: 1.5em auto; max-width: 1000px; color: #222; }
video { width: 100%; background: #000; }
table.facts td { padding: 0 1em 0 0; vertical-align: top; }
.plots { position: relative; width: 100%; }
.plots svg { width: 100%; height: auto; display: block; }
#cursor { position: absolute; width: 1px; background: #d00; pointer-events: none; }
.card { border-top: 1px solid #ccc; margin-top: 2em; }
.card table { border-collapse: collapse; }
.card td, .card th { border: 1px solid #ccc; padding: 0.2em 0.5em; }
.card img { max-width: 100%; }
pre { white-space: pre-wrap; }
"""

_CURSOR_SCRIPT = """
(function () {
  const video = document.getElementById("video");
  const cursor = document.getElementById("cursor");
  const box = document.getElementById("plots");
  const geometry = JSON.parse(box.dataset.axes);
  function place() {
    const t = geometry.t0_s + video.currentTime;
    const frac = geometry.left + geometry.width * (t - geometry.xmin) / (geometry.xmax - geometry.xmin);
    cursor.style.left = (100 * Math.min(Math.max(frac, 0), 1)) + "%";
    cursor.style.top = (100 * geometry.top) + "%";
    cursor.style.height = (100 * geometry.height) + "%";
  }
  video.addEventListener("timeupdate", place);
  video.addEventListener("seeked", place);
  place();
})();
"""


def camera_state_plot_svg(states: Sequence[dict]) -> tuple[str, dict] | None:
    """The camera's state over time as an SVG document, and where its plot area lies (figure fractions
    from the top-left: left, top, width, height; the x range, s), for the cursor. None when the states
    hold none of the plotted quantities.

    Parameters
    ----------
    states : camera.jsonl records in frame order; time_s is the x axis (the frame index where missing).
    """
    time_s = np.array([s.get("time_s", s.get("frame", k)) for k, s in enumerate(states)], dtype=np.float64)
    panels = []
    for label, series, log in PANELS:
        lines = []
        for key, legend in series:
            values = np.array([_number(state.get(key)) for state in states], dtype=np.float64)
            if np.isfinite(values).any():
                lines.append((legend, 1e3 * values if key == "exposure_time_s" else values))
        if lines:
            panels.append((label, lines, log))
    if not panels:
        return None
    height_in = PLOT_PANEL_HEIGHT_IN * len(panels) + PLOT_MARGIN_TOP_IN + PLOT_MARGIN_BOTTOM_IN
    figure = Figure(figsize=(PLOT_WIDTH_IN, height_in), dpi=PLOT_DPI)
    # Fixed margins instead of a layout engine: the plot area is known without drawing twice (and the
    # cursor needs it), and the layout engine's extra draws took most of the page's time.
    figure.subplots_adjust(
        left=PLOT_MARGIN_LEFT_IN / PLOT_WIDTH_IN,
        right=1 - PLOT_MARGIN_RIGHT_IN / PLOT_WIDTH_IN,
        top=1 - PLOT_MARGIN_TOP_IN / height_in,
        bottom=PLOT_MARGIN_BOTTOM_IN / height_in,
        hspace=0.15,
    )
    axes = figure.subplots(len(panels), 1, sharex=True, squeeze=False)[:, 0]
    for ax, (label, lines, log) in zip(axes, panels, strict=True):
        for legend, values in lines:
            ax.plot(time_s, values, label=legend, marker="." if len(time_s) < 30 else None)
        ax.set_ylabel(label)
        finite = np.concatenate([values[np.isfinite(values)] for _, values in lines])
        if log and (finite > 0).all() and finite.max() > LOG_SCALE_RANGE * finite.min():
            ax.set_yscale("log")
        if len(lines) > 1:
            ax.legend(loc="upper right", fontsize="small")
        ax.grid(alpha=0.3)
    axes[-1].set_xlabel("time, s")
    if len(time_s) == 1:
        axes[-1].set_xlim(time_s[0] - 0.5, time_s[0] + 0.5)
    boxes = [ax.get_position() for ax in axes]
    xmin, xmax = axes[-1].get_xlim()
    geometry = {
        "left": boxes[0].x0,
        "width": boxes[0].width,
        "top": 1 - max(b.y1 for b in boxes),
        "height": max(b.y1 for b in boxes) - min(b.y0 for b in boxes),
        "xmin": xmin,
        "xmax": xmax,
        "t0_s": float(time_s[0]),
    }
    buffer = io.StringIO()
    figure.savefig(buffer, format="svg", metadata={"Date": None})
    svg = buffer.getvalue()
    return svg[svg.index("<svg") :], geometry


def card_html(markdown: str, card_directory: Path | None = None) -> str:
    """The dataset card as HTML: markdown-it-py's CommonMark with tables (raw HTML escaped), pictures the card
    names by a relative path embedded as data URIs; preformatted text where markdown-it-py is missing."""
    try:
        from markdown_it import MarkdownIt
    except ImportError:
        return f"<pre>{html.escape(markdown)}</pre>"
    parser = MarkdownIt("commonmark", {"html": False}).enable("table")
    tokens = parser.parse(markdown)
    if card_directory is not None:
        for token in tokens:
            for child in token.children or ():
                if child.type == "image":
                    child.attrSet("src", _embedded(str(child.attrGet("src") or ""), card_directory))
    return parser.renderer.render(tokens, parser.options, {})


def preview_page(
    *,
    title: str,
    facts: Sequence[tuple[str, str]],
    video_webm: bytes,
    states: Sequence[dict],
    card_markdown: str | None = None,
    card_directory: Path | None = None,
) -> str:
    """The whole page.

    Parameters
    ----------
    title : the page's heading (job and camera).
    facts : (name, value) rows shown under it (scene, profile, frames, size …).
    video_webm : the annotated video's bytes, embedded as ``data:video/webm;base64,…``.
    states : camera.jsonl records in frame order, for the plots.
    card_markdown, card_directory : the dataset card and the directory its relative picture paths start from.
    """
    rows = "".join(f"<tr><td>{html.escape(k)}</td><td>{html.escape(v)}</td></tr>" for k, v in facts)
    video_uri = "data:video/webm;base64," + base64.b64encode(video_webm).decode("ascii")
    parts = [
        "<!DOCTYPE html>",
        '<html lang="en"><head><meta charset="utf-8">',
        f"<title>{html.escape(title)}</title><style>{_STYLE}</style></head><body>",
        f"<h1>{html.escape(title)}</h1>",
        f'<table class="facts">{rows}</table>',
        f'<video id="video" controls loop muted autoplay playsinline src="{video_uri}"></video>',
        "<h2>Camera state</h2>",
    ]
    plot = camera_state_plot_svg(states)
    if plot is None:
        parts.append("<p>No per-frame camera state: the render wrote no camera.jsonl (outputs.camera_metadata).</p>")
    else:
        svg, geometry = plot
        axes = html.escape(json.dumps(geometry), quote=True)
        parts.append(f'<div class="plots" id="plots" data-axes="{axes}">{svg}<div id="cursor"></div></div>')
        parts.append(f"<script>{_CURSOR_SCRIPT}</script>")
    if card_markdown is not None:
        parts.append(f'<section class="card" id="card">{card_html(card_markdown, card_directory)}</section>')
    parts.append("</body></html>")
    return "\n".join(parts) + "\n"


def _embedded(src: str, directory: Path) -> str:
    """`src` as a data URI when it names a file under `directory`; otherwise as it was."""
    if not src or ":" in src or src.startswith("/"):
        return src
    path = directory / src
    if not path.is_file():
        return src
    mime = mimetypes.guess_type(path.name)[0] or "application/octet-stream"
    return f"data:{mime};base64," + base64.b64encode(path.read_bytes()).decode("ascii")


def _number(value) -> float:
    return float(value) if isinstance(value, int | float) and not isinstance(value, bool) else np.nan
