"""What a demo writes where there is no display: numbered PNG frames, an animated GIF, and captions on them."""
from __future__ import annotations

from pathlib import Path

import numpy as np


#: Pillow's built-in font has Latin letters only: symbols a caption uses, in letters it can draw
PLAIN = str.maketrans({"—": "-", "–": "-", "·": "*", "×": "x", "ρ": "rho", "β": "beta", "Δ": "d", "≤": "<=",
                       "≥": ">=", "→": "->", "…": "..."})


def captioned(frame: np.ndarray, caption: str) -> np.ndarray:
    """The frame (uint8 RGB) with a strip of text under it: what the frame shows (``shot 16``, ``W: shadows off``)."""
    from PIL import Image, ImageDraw, ImageFont

    height = max(16, frame.shape[0] // 12)
    strip = Image.new("RGB", (frame.shape[1], height), (24, 24, 24))
    draw = ImageDraw.Draw(strip)
    try:
        font = ImageFont.load_default(size=max(10, int(height * 0.7)))
    except TypeError:  # Pillow < 10.1: one size only
        font = ImageFont.load_default()
    text = caption.translate(PLAIN).encode("latin-1", "replace").decode("latin-1")   # never a box for a glyph
    draw.text((6, height // 2), text, fill=(235, 235, 235), font=font, anchor="lm")
    return np.vstack([frame, np.asarray(strip)])


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
