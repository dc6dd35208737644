"""What the decks' figures share: the reference they draw with, scenes, matplotlib canvases of exact pixel sizes,
projections of scene points, grids of captioned panels. Nothing here is about one stage.
"""
from __future__ import annotations

import contextlib
import io
import json
from pathlib import Path
from dataclasses import dataclass
from typing import Any, Callable

import numpy as np

from ..errors import KitError
from ..impl import load_impl
from ..imageio import to_uint8
from ..scene import BUNDLED_DIR
from . import registry

#: Pixels per inch of every matplotlib canvas, in the slide's own pixels: figure sizes below are slide pixels.
DPI = 100
#: Device pixels per slide pixel: every figure is drawn at twice the size it is shown (a 1920 × 1080 projector
#: shows a slide pixel as 1.5 screen pixels, so nothing is ever enlarged), and pictures laid into a figure
#: (renders, item buffers) are made at twice their shown size too.
SCALE = 2
#: The smallest text a figure may hold, in points: 12 pt is 16.7 slide pixels, 16 screen pixels on a 1280 × 720
#: screen (tests/test_slides_readability.py).
MIN_FONT_PT = 12.0
#: The size (device pixels) of every text drawn on a canvas since the figure began (``figures.py`` keeps the
#: smallest in the PNG, for the readability check). One figure is drawn at a time.
TEXT_PX: list[float] = []


def reference_impl(stage: str) -> Any:
    """The reference of ``stage`` (from :data:`cs451.slides.registry.REFERENCE`, which tests point at a copy),
    imported under a private name."""
    folder = registry.REFERENCE / stage
    if not (folder / "__init__.py").is_file():
        raise KitError(f"{folder}: no reference package here (the figures draw with the kit's reference)")
    return load_impl(folder, stage)


def scene_data(file: str) -> dict[str, Any]:
    """A bundled scene as its JSON dict (to change a field before parsing it)."""
    return json.loads((BUNDLED_DIR / file).read_text())


def encoded(image: np.ndarray, scene: Any) -> np.ndarray:
    return to_uint8(image, scene.image.exposure, scene.image.srgb)



def project(matrix: np.ndarray, points: np.ndarray, size: tuple[int, int]) -> np.ndarray:
    """Pixel coordinates (x right, y down, pixel centres at integers) of points in front of the camera."""
    points = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    clip = np.c_[points, np.ones(len(points))] @ matrix.T
    ndc = clip[:, :2] / clip[:, 3:4]
    return np.c_[(ndc[:, 0] + 1) / 2 * size[0] - 0.5, (1 - ndc[:, 1]) / 2 * size[1] - 0.5]


def visible_segment(matrix: np.ndarray, a: np.ndarray, b: np.ndarray, size: tuple[int, int]) -> np.ndarray | None:
    """The part of segment a–b in front of the camera, in pixel coordinates (2, 2), or None if it is all behind."""
    wa, wb = (float(np.r_[p, 1.0] @ matrix[3]) for p in (a, b))
    eps = 1e-6
    if wa <= eps and wb <= eps:
        return None
    if wa <= eps:
        a = a + (b - a) * (eps - wa) / (wb - wa)
    elif wb <= eps:
        b = a + (b - a) * (eps - wa) / (wb - wa)
    return project(matrix, np.stack([a, b]), size)


@contextlib.contextmanager
def readable() -> Any:
    """matplotlib's defaults while a figure is drawn: every text (ticks, labels, legends, titles) at least
    :data:`MIN_FONT_PT` unless a figure asks for more."""
    try:
        import matplotlib
    except ImportError:
        raise KitError("the slides' figures draw with matplotlib: pip install -e '.[bench]'") from None
    sizes = {"font.size": MIN_FONT_PT, "axes.titlesize": MIN_FONT_PT, "axes.labelsize": MIN_FONT_PT,
             "xtick.labelsize": MIN_FONT_PT, "ytick.labelsize": MIN_FONT_PT, "legend.fontsize": MIN_FONT_PT,
             "legend.title_fontsize": MIN_FONT_PT, "figure.titlesize": MIN_FONT_PT + 2}
    with matplotlib.rc_context(sizes):
        yield


def new_canvas(width: int, height: int) -> Any:
    """A matplotlib figure of this many pixels, drawn by Agg (no pyplot, no global backend)."""
    try:
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.figure import Figure
    except ImportError:
        raise KitError("the slides' figures draw with matplotlib: pip install -e '.[bench]'") from None
    fig = Figure(figsize=(width / DPI, height / DPI), dpi=DPI * SCALE, facecolor="white")
    FigureCanvasAgg(fig)
    return fig


def canvas_pixels(fig: Any) -> np.ndarray:
    """The canvas as uint8 RGB (device pixels), noting the size of every visible text on it in :data:`TEXT_PX`.

    Refuses text under :data:`MIN_FONT_PT` (naming it), so that no figure can hold text the back row cannot read."""
    from matplotlib.text import Text

    fig.canvas.draw()
    for text in fig.findobj(Text):
        shown = text.get_visible() and text.get_text().strip()
        if shown and (text.axes is None or (text.axes.get_visible() and text.axes.axison)
                      or text in text.axes.texts or text is text.axes.title):
            if text.get_fontsize() < MIN_FONT_PT - 1e-6:
                raise KitError(f"figure text {text.get_text()[:40]!r} at {text.get_fontsize():g} pt, under the "
                               f"{MIN_FONT_PT:g} pt the back row reads (cs451.slides.canvas.MIN_FONT_PT)")
            TEXT_PX.append(text.get_fontsize() * fig.dpi / 72)
    return np.asarray(fig.canvas.buffer_rgba())[..., :3].copy()


def text_size(text: str, font: float = MIN_FONT_PT, weight: str = "normal") -> tuple[float, float]:
    """(width, height) in slide pixels of ``text`` (lines split at newlines) set at ``font`` points, as matplotlib
    sets it (line spacing 1.2): to lay out captions and titles before drawing them."""
    from matplotlib.backends.backend_agg import RendererAgg
    from matplotlib.font_manager import FontProperties

    renderer = RendererAgg(1, 1, DPI)
    prop = FontProperties(size=font, weight=weight)
    lines = text.split("\n")
    widths = [renderer.get_text_width_height_descent(line or " ", prop, ismath=False)[0] for line in lines]
    return max(widths), font * DPI / 72 * 1.2 * len(lines)


def line_height(font: float = MIN_FONT_PT) -> int:
    """The height of one line of text at ``font`` points, in slide pixels (a little room included)."""
    return round(font * DPI / 72 * 1.25)


def wrapped(text: str, width: float, font: float = MIN_FONT_PT) -> str:
    """``text`` broken at spaces into lines no wider than ``width`` slide pixels (a longer word keeps a line)."""
    lines: list[str] = []
    for paragraph in text.split("\n"):
        line = ""
        for word in paragraph.split(" "):
            candidate = f"{line} {word}" if line else word
            if line and text_size(candidate, font)[0] > width:
                lines.append(line)
                line = word
            else:
                line = candidate
        lines.append(line)
    return "\n".join(lines)


def png_pixels(path: Path) -> np.ndarray:
    from PIL import Image
    with Image.open(path) as image:
        return np.asarray(image.convert("RGB")).copy()


@dataclass
class Panel:
    """One picture of a grid, its caption, and what to draw over it (``overlay(ax)``, in pixel coordinates)."""
    image: np.ndarray
    caption: str = ""
    overlay: Callable[[Any], None] | None = None


#: A legend entry: its label and the matplotlib Line2D style of its sample (color, ls, lw, marker, ...).
Entry = tuple[str, dict[str, Any]]


def _device(v: float) -> float:
    """A slide-pixel position on a device pixel's edge (so that a picture is laid in without resampling)."""
    return round(v * SCALE) / SCALE


def _legend_columns(entries: list[Entry], width: float, font: float) -> int:
    """How many columns of ``entries`` fit across ``width`` slide pixels (matplotlib fills a column before the next,
    each column as wide as its widest label)."""
    em = font * DPI / 72
    widths = [text_size(label, font)[0] + 3.4 * em for label, _ in entries]     # handle, gaps
    for columns in range(len(entries), 1, -1):
        rows = -(-len(entries) // columns)
        if -(-len(entries) // rows) != columns:
            continue                                # matplotlib would leave a column empty
        if sum(max(widths[c * rows:(c + 1) * rows]) for c in range(columns)) <= width - 10:
            return columns
    return 1


def footer_height(width: float, legend: list[Entry] | None = None, note: str = "", font: float = MIN_FONT_PT) -> int:
    """The slide pixels a :func:`draw_footer` takes under a figure ``width`` wide: the legend's rows, the note's lines."""
    height = 0
    if legend:
        rows = -(-len(legend) // _legend_columns(legend, width, font))
        height += 8 + rows * (line_height(font) + 4)
    if note:
        height += 6 + line_height(font) * (wrapped(note, width - 20, font).count("\n") + 1)
    return height


def draw_footer(fig: Any, width: float, height: float, top: float, legend: list[Entry] | None = None,
                note: str = "", font: float = MIN_FONT_PT) -> None:
    """A legend (centred, in as many columns as fit) and a note (small grey text, wrapped: where a measurement
    comes from) from ``top`` (slide pixels from the figure's top) down, across the figure."""
    from matplotlib.lines import Line2D
    y = top
    if legend:
        columns = _legend_columns(legend, width, font)
        rows = -(-len(legend) // columns)
        handles = [Line2D([], [], **{"lw": 2, **style}) for _, style in legend]
        fig.legend(handles, [label for label, _ in legend], loc="upper center", ncol=columns, fontsize=font,
                   frameon=False, bbox_to_anchor=(0.5, 1 - (y + 2) / height), borderaxespad=0, borderpad=0.2,
                   handlelength=2.2, columnspacing=1.2, labelspacing=0.25)
        y += 8 + rows * (line_height(font) + 4)
    if note:
        fig.text(10 / width, 1 - (y + 4) / height, wrapped(note, width - 20, font), ha="left", va="top",
                 fontsize=font, color="#555555", linespacing=1.2)


def footer(width: float, legend: list[Entry] | None = None, note: str = "", font: float = MIN_FONT_PT) -> np.ndarray:
    """:func:`draw_footer` on a canvas of its own, to stack under a composed figure (device pixels)."""
    height = footer_height(width, legend, note, font) + 6
    fig = new_canvas(width, height)
    draw_footer(fig, width, height, 0, legend, note, font)
    return canvas_pixels(fig)


def panel_grid(rows: list[list[Panel]], title: str = "", pad: int = 10, min_width: int = 150,
               font: float = MIN_FONT_PT, legend: list[Entry] | None = None, note: str = "") -> np.ndarray:
    """Panels in rows, each caption above its panel, a title on top, a legend and a note under them; a panel's
    pixels are device pixels (:data:`SCALE` to a slide pixel), laid in without resampling. Sizes here are slide
    pixels. A column is as wide as its widest picture or caption line, so captions never run into each other; the
    figure is as wide as its title."""
    size = {id(p): (p.image.shape[0] / SCALE, p.image.shape[1] / SCALE) for row in rows for p in row}
    cell_w = max(min_width, max(size[id(p)][1] for row in rows for p in row),
                 max(text_size(p.caption, font)[0] + 6 for row in rows for p in row if p.caption) if
                 any(p.caption for row in rows for p in row) else 0)
    bands = [(6 + line_height(font) * max(p.caption.count("\n") + 1 for p in row)) if any(p.caption for p in row)
             else 0 for row in rows]
    heights = [max(size[id(p)][0] for p in row) for row in rows]
    columns = max(len(row) for row in rows)
    width = columns * cell_w + (columns + 1) * pad
    if title:
        width = max(width, text_size(title, font + 2, "bold")[0] + 2 * pad + 12)
    top = 8 + line_height(font + 2) * (title.count("\n") + 1) if title else 0
    body = top + sum(heights) + sum(bands) + (len(rows) + 1) * pad
    height = body + footer_height(width, legend, note, font)
    fig = new_canvas(width, height)
    left = (width - (columns * cell_w + (columns + 1) * pad)) / 2
    for r, row in enumerate(rows):
        row_x = left + (columns - len(row)) * (cell_w + pad) / 2           # a shorter row is centred
        for c, panel in enumerate(row):
            h, w = size[id(panel)]
            x = _device(row_x + pad + c * (cell_w + pad) + (cell_w - w) / 2)
            y = _device(top + pad + sum(heights[:r]) + sum(bands[:r + 1]) + r * pad)
            ax = fig.add_axes((x / width, 1 - (y + h) / height, w / width, h / height))
            ax.imshow(panel.image, interpolation="nearest")
            ax.set_axis_off()
            if panel.overlay is not None:
                panel.overlay(ax)
            ax.set_xlim(-0.5, panel.image.shape[1] - 0.5)
            ax.set_ylim(panel.image.shape[0] - 0.5, -0.5)
            if panel.caption:
                fig.text((x + w / 2) / width, 1 - (y - 3) / height, panel.caption, ha="center", va="bottom",
                         fontsize=font, linespacing=1.2)
    if title:
        fig.text(0.5, 1 - 6 / height, title, ha="center", va="top", fontsize=font + 2, weight="bold", linespacing=1.2)
    draw_footer(fig, width, height, body, legend, note, font)
    return canvas_pixels(fig)


def heading(width: float, title: str, font: float = MIN_FONT_PT) -> np.ndarray:
    """A figure's title on a strip of its own, ``width`` slide pixels wide (bold, centred), to stack over a composed
    figure (device pixels)."""
    height = 8 + line_height(font + 2) * (title.count("\n") + 1)
    fig = new_canvas(width, height)
    fig.text(0.5, 1 - 6 / height, title, ha="center", va="top", fontsize=font + 2, weight="bold", linespacing=1.2)
    return canvas_pixels(fig)


def stacked(images: list[np.ndarray], gap: int = 6) -> np.ndarray:
    """Images (device pixels) one above the other, centred on a white page, ``gap`` device pixels apart."""
    width = max(i.shape[1] for i in images)
    out = []
    for image in images:
        left = (width - image.shape[1]) // 2
        out.append(np.pad(image, ((0, gap), (left, width - image.shape[1] - left), (0, 0)), constant_values=255))
    joined = np.vstack(out)
    return joined[:joined.shape[0] - gap]


def side_by_side(images: list[np.ndarray], gap: int = 0) -> np.ndarray:
    """Images (device pixels) left to right, their tops aligned, on a white page, ``gap`` device pixels apart."""
    height = max(i.shape[0] for i in images)
    out = [np.pad(i, ((0, height - i.shape[0]), (0, gap), (0, 0)), constant_values=255) for i in images]
    joined = np.hstack(out)
    return joined[:, :joined.shape[1] - gap] if gap else joined


def axes_plot(width: int, height: int, draw: Callable[[Any], None]) -> np.ndarray:
    """A plot of this many slide pixels: ``draw(ax)`` on one axes, laid out to fit (its text at least
    :data:`MIN_FONT_PT`: the figures draw with it as matplotlib's base size)."""
    fig = new_canvas(width, height)
    ax = fig.add_subplot(1, 1, 1)
    draw(ax)
    fig.tight_layout(pad=0.6)
    place_labels(fig)
    return canvas_pixels(fig)


#: Where a point's label may go, in points from it (the first that meets nothing wins): right, left, above, below.
LABEL_SPOTS = ((6, 5), (6, -5), (-6, 5), (-6, -5), (0, 9), (0, -9), (9, 0), (-9, 0), (12, 12), (12, -12),
               (-12, 12), (-12, -12))


def label_points(ax: Any, xs: list[float], ys: list[float], texts: list[str], color: str = "black") -> None:
    """Label points, placed once the figure is laid out (:func:`place_labels`) where no label meets another label, a
    marker or the axes' edge: dense series stay readable."""
    pending = ax.__dict__.setdefault("_cs451_labels", [])
    pending += [(x, y, t, color) for x, y, t in zip(xs, ys, texts)]


def place_labels(fig: Any) -> None:
    """Place every axes' :func:`label_points` labels: each at the first of :data:`LABEL_SPOTS` where it stays inside
    the axes and meets no marker and no label placed before it (else where it meets the least)."""
    renderer = fig.canvas.get_renderer()
    for ax in fig.axes:
        pending = ax.__dict__.pop("_cs451_labels", [])
        if not pending:
            continue
        frame = ax.get_window_extent(renderer)
        marks = []
        for line in ax.get_lines():
            if line.get_marker() in (None, "None", "", " "):
                continue
            r = line.get_markersize() * fig.dpi / 72 / 2 + 1
            for px, py in ax.transData.transform(np.c_[line.get_xdata(), line.get_ydata()]):
                marks.append((px - r, py - r, px + r, py + r))
        taken: list[tuple[float, float, float, float]] = []

        def overlap(a: tuple[float, ...], b: tuple[float, ...]) -> float:
            return max(0.0, min(a[2], b[2]) - max(a[0], b[0])) * max(0.0, min(a[3], b[3]) - max(a[1], b[1]))
        for x, y, text, color in pending:
            best = None
            for dx, dy in LABEL_SPOTS:
                label = ax.annotate(text, (x, y), xytext=(dx, dy), textcoords="offset points", color=color,
                                    ha="left" if dx > 0 else "right" if dx < 0 else "center",
                                    va="bottom" if dy > 0 else "top" if dy < 0 else "center")
                box = label.get_window_extent(renderer)
                b = (box.x0, box.y0, box.x1, box.y1)
                outside = (box.width * box.height - overlap(b, (frame.x0, frame.y0, frame.x1, frame.y1)))
                cost = sum(overlap(b, o) for o in taken + marks) + 4 * outside
                if best is None or cost < best[0]:
                    if best is not None:
                        best[1].remove()
                    best = (cost, label, b)
                else:
                    label.remove()
                if cost == 0:
                    break
            taken.append(best[2])


def plain_log_ticks(ax: Any, axis: str = "both") -> None:
    """Log axes labelled in plain numbers (0.01, 0.1, 1) at the decades only: the minor ticks' labels
    (2×10⁻², 3×10⁻²) would run into each other at a readable size. A range within one decade keeps two labels."""
    from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter
    plain = FuncFormatter(lambda v, _: f"{v:g}")
    for which in ("x", "y") if axis == "both" else (axis,):
        target = ax.xaxis if which == "x" else ax.yaxis
        lo, hi = (ax.get_xlim() if which == "x" else ax.get_ylim())
        target.set_major_formatter(plain)
        target.set_minor_formatter(NullFormatter())
        if hi / max(lo, 1e-300) < 100:             # under two decades: label 1, 2 and 5 times the powers of ten
            target.set_major_locator(LogLocator(base=10, subs=(1.0, 2.0, 5.0)))


def plot_row(width: int, height: int, draws: list[Callable[[Any], None]], title: str = "",
             legend: list[Entry] | None = None, note: str = "", widths: list[float] | None = None,
             font: float = MIN_FONT_PT) -> np.ndarray:
    """Plots side by side (``draws[k](ax)`` on the k-th axes, ``widths`` their relative widths), ``height`` slide
    pixels tall, under a title and over a legend and a note (:func:`draw_footer`); laid out to fit."""
    top = 8 + line_height(font + 2) * (title.count("\n") + 1) if title else 0
    bottom = footer_height(width, legend, note, font)
    total = top + height + bottom
    fig = new_canvas(width, total)
    axes = fig.subplots(1, len(draws), gridspec_kw={"width_ratios": widths} if widths else None, squeeze=False)[0]
    for ax, draw in zip(axes, draws):
        draw(ax)
    fig.tight_layout(pad=0.6, w_pad=1.2, rect=(0, bottom / total, 1, 1 - top / total))
    place_labels(fig)
    if title:
        fig.text(0.5, 1 - 6 / total, title, ha="center", va="top", fontsize=font + 2, weight="bold", linespacing=1.2)
    draw_footer(fig, width, total, top + height, legend, note, font)
    return canvas_pixels(fig)


def quietly(work: Callable[[], Any]) -> Any:
    """Run a bench function without its printed tables (the figure shows them)."""
    with contextlib.redirect_stdout(io.StringIO()):
        return work()

