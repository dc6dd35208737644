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
    """The canvas as uint8 RGB (device pixels), noting the size of every visible text on it in :data:`TEXT_PX`."""
    from matplotlib.text import Text

    fig.canvas.draw()
    for text in fig.findobj(Text):
        shown = text.get_visible() and text.get_text().strip()
        if shown and (text.axes is None or (text.axes.get_visible() and text.axes.axison)
                      or text in text.axes.texts or text is text.axes.title):
            TEXT_PX.append(text.get_fontsize() * fig.dpi / 72)
    return np.asarray(fig.canvas.buffer_rgba())[..., :3].copy()


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


def panel_grid(rows: list[list[Panel]], title: str = "", pad: int = 10, min_width: int = 150,
          font: float = MIN_FONT_PT) -> np.ndarray:
    """Panels in rows, each caption above its panel, a title on top; a panel's pixels are device pixels
    (:data:`SCALE` to a slide pixel), laid in without resampling. Sizes here are slide pixels."""
    band = 8 + round(font * 1.75) * max(p.caption.count("\n") + 1 for row in rows for p in row)
    size = {id(p): (p.image.shape[0] / SCALE, p.image.shape[1] / SCALE) for row in rows for p in row}
    cell_w = max(min_width, max(size[id(p)][1] for row in rows for p in row))
    heights = [max(size[id(p)][0] for p in row) for row in rows]
    columns = max(len(row) for row in rows)
    top = 10 + round((font + 2) * 1.6) * (title.count("\n") + 1) if title else 0
    width = columns * cell_w + (columns + 1) * pad
    height = top + sum(heights) + len(rows) * band + (len(rows) + 1) * pad
    fig = new_canvas(width, height)
    for r, row in enumerate(rows):
        row_x = (columns - len(row)) * (cell_w + pad) // 2           # a shorter row is centred
        for c, panel in enumerate(row):
            h, w = size[id(panel)]
            x = row_x + pad + c * (cell_w + pad) + (cell_w - w) / 2
            y = top + pad + sum(heights[:r]) + r * (band + pad) + band
            ax = fig.add_axes((x / width, 1 - (y + h) / height, w / width, h / height))
            ax.imshow(panel.image, interpolation="nearest")
            ax.set_axis_off()
            if panel.overlay is not None:
                panel.overlay(ax)
            ax.set_xlim(-0.5, panel.image.shape[1] - 0.5)
            ax.set_ylim(panel.image.shape[0] - 0.5, -0.5)
            if panel.caption:
                fig.text((x + w / 2) / width, 1 - (y - 4) / height, panel.caption, ha="center", va="bottom",
                         fontsize=font, linespacing=1.2)
    if title:
        fig.text(0.5, 1 - 6 / height, title, ha="center", va="top", fontsize=font + 2, weight="bold")
    return canvas_pixels(fig)


def stacked(images: list[np.ndarray], gap: int = 6) -> np.ndarray:
    """Images one above the other, centred on a white page."""
    width = max(i.shape[1] for i in images)
    out = []
    for image in images:
        left = (width - image.shape[1]) // 2
        out.append(np.pad(image, ((0, gap), (left, width - image.shape[1] - left), (0, 0)), constant_values=255))
    return np.vstack(out)[:-gap]


def axes_plot(width: int, height: int, draw: Callable[[Any], None]) -> np.ndarray:
    """A plot of this many pixels: ``draw(ax)`` on one axes."""
    fig = new_canvas(width, height)
    ax = fig.add_subplot(1, 1, 1)
    draw(ax)
    fig.tight_layout()
    return canvas_pixels(fig)



def quietly(work: Callable[[], Any]) -> Any:
    """Run a bench function without its printed tables (the figure shows them)."""
    with contextlib.redirect_stdout(io.StringIO()):
        return work()

