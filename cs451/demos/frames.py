"""What a demo writes where there is no display: numbered PNG frames, an animated GIF, and captions on them."""
from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np


#: Pillow's built-in font has Latin letters only: symbols a caption uses, in letters it can draw
PLAIN = str.maketrans({"—": "-", "–": "-", "·": "*", "×": "x", "ρ": "rho", "β": "beta", "Δ": "d", "≤": "<=",
                       "≥": ">=", "→": "->", "←": "<-", "…": "..."})
#: The tallest a caption line's strip gets (a large frame keeps its text readable, not huge).
LINE_HEIGHT = 28


def captioned(frame: np.ndarray, caption: str) -> np.ndarray:
    """The frame (uint8 RGB) with a strip of text under it: what the frame shows (``shot 16``, ``W: shadows off``).

    Each line of ``caption`` gets a strip of its own; a line too long for the frame is set smaller until it fits.
    """
    from PIL import Image, ImageDraw

    lines = caption.split("\n")
    height = max(16, min(frame.shape[0] // 12, LINE_HEIGHT))
    strip = Image.new("RGB", (frame.shape[1], height * len(lines)), (24, 24, 24))
    draw = ImageDraw.Draw(strip)
    for k, line in enumerate(lines):
        text = line.translate(PLAIN).encode("latin-1", "replace").decode("latin-1")   # never a box for a glyph
        size = max(10, int(height * 0.7))
        font = _font(size)
        while size > 8 and hasattr(font, "getlength") and font.getlength(text) > frame.shape[1] - 12:
            size -= 1
            font = _font(size)
        draw.text((6, k * height + height // 2), text, fill=(235, 235, 235), font=font, anchor="lm")
    return np.vstack([frame, np.asarray(strip)])


def _font(size: int) -> Any:
    from PIL import ImageFont
    try:
        return ImageFont.load_default(size=size)
    except TypeError:  # Pillow < 10.1: one size only
        return ImageFont.load_default()


def write_frames(folder: Path, name: str, frames: list[np.ndarray], captions: list[str] | None = None,
                 ms_per_frame: int = 400, last_ms: int = 2000) -> list[Path]:
    """``folder/name.gif`` and ``folder/name-00.png`` …; returns the GIF first, then the frames."""
    from PIL import Image

    if not frames:
        return []
    if captions is not None:
        frames = [captioned(f, c) for f, c in zip(frames, captions)]
    folder.mkdir(parents=True, exist_ok=True)
    paths = []
    for k, frame in enumerate(frames):
        path = folder / f"{name}-{k:02d}.png"
        Image.fromarray(frame).save(path)
        paths.append(path)
    gif = folder / f"{name}.gif"
    images = [Image.fromarray(f) for f in frames]
    images[0].save(gif, save_all=True, append_images=images[1:], duration=[ms_per_frame] * (len(images) - 1) + [last_ms],
                   loop=0)
    return [gif, *paths]
