"""What every demo shows beside its picture: a caption band saying what is on screen, and a help panel of its keys.

Both are drawn with Pillow into RGBA images (the scalable font Pillow ≥ 10.1 carries: no font file) and blended
over the picture: by the window as textures (:mod:`.window`), and into the frames written without a display
(:func:`compose`), at the same places and sizes, so that a window opened at a frame's size shows that frame. Text is
at least :data:`MIN_PX` pixels, readable from the back row on a 1080p projector (a taller window gets a little more);
a caption line too long for the width is set smaller until it fits, as :func:`cs451.demos.frames.captioned` does.
"""
from __future__ import annotations

from functools import lru_cache
from typing import Any, Sequence

import numpy as np

from .frames import PLAIN

#: The smallest text size (pixels per em) on screen and in frames: readable from the back row at 1080p.
MIN_PX = 24
#: The smallest a too-long line is shrunk to (a small window or frame; a full screen never needs it).
SHRUNK_PX = 8
#: Seconds the help panel stays up in a live window unless a key is pressed first.
HELP_SECONDS = 8.0
#: The window's background and the band's colours (RGB, RGBA).
BACKGROUND = (24, 24, 24)
BAND = (12, 12, 12, 216)        # translucent over a picture (stage 1's); opaque under one
PANEL = (0, 0, 0, 200)
TEXT = (240, 240, 240, 255)
KEY = (255, 205, 80, 255)
#: What the help panel says first.
HELP_TITLE = "keys (h or ? shows and hides this)"

Keys = Sequence[tuple[str, str]]


def text_px(height: int) -> int:
    """Text size for a canvas ``height`` pixels tall: :data:`MIN_PX`, or 1/40 of a taller one (27 px at 1080p)."""
    return max(MIN_PX, int(height) // 40)


def line_height(px: int) -> int:
    return px * 4 // 3


def band_height(lines: int, px: int) -> int:
    """The caption band's height for ``lines`` lines of ``px`` text."""
    return max(1, lines) * line_height(px) + px // 2


def framed_size(size: tuple[int, int], lines: int) -> tuple[int, int]:
    """(width, height) of a frame: the picture of ``size`` with a band of ``lines`` caption lines under it."""
    w, h = size
    px = text_px(h + band_height(lines, MIN_PX))
    return w, h + band_height(lines, px)


#: Symbols spelt out in letters the built-in font draws (its middle dot and ellipsis it has).
SPELT = {k: v for k, v in PLAIN.items() if chr(k) not in "·…"}


def plain(text: str) -> str:
    """``text`` in the letters the built-in font draws (×, ρ, → spelt out; never a box for a missing glyph)."""
    return "".join(c if c == "…" or ord(c) < 256 else "?" for c in text.translate(SPELT))


@lru_cache(maxsize=64)
def font(px: int) -> Any:
    from PIL import ImageFont
    try:
        return ImageFont.load_default(size=px)
    except TypeError:  # Pillow < 10.1: one bitmap size only
        return ImageFont.load_default()


def _fitting(text: str, px: int, width: float) -> Any:
    """The font at ``px``, or smaller (down to SHRUNK_PX) until ``text`` fits in ``width`` pixels."""
    f = font(px)
    while px > SHRUNK_PX and hasattr(f, "getlength") and f.getlength(text) > width:
        px -= 1
        f = font(px)
    return f


def band_image(width: int, caption: str, lines: int, px: int, over_picture: bool = False) -> np.ndarray:
    """The caption band (h, width, 4): each line of ``caption`` in a slot of its own, ``lines`` slots at least;
    opaque under a picture (so the window's blending and :func:`blend` agree to the bit), see-through over one."""
    from PIL import Image, ImageDraw
    texts = caption.split("\n") if caption else []
    lh = line_height(px)
    image = Image.new("RGBA", (max(1, width), band_height(max(lines, len(texts)), px)),
                      BAND if over_picture else (*BAND[:3], 255))
    draw = ImageDraw.Draw(image)
    for k, line in enumerate(texts):
        text = plain(line)
        draw.text((px // 2, px // 4 + k * lh + lh // 2), text, fill=TEXT, font=_fitting(text, px, width - px),
                  anchor="lm")
    return np.asarray(image)


def help_image(keys: Keys, px: int, room: tuple[int, int]) -> np.ndarray:
    """The help panel (h, w, 4): a title, then each key beside what it does; set smaller until it fits ``room``."""
    from PIL import Image, ImageDraw
    rows = [(plain(k), plain(what)) for k, what in keys]
    title = plain(HELP_TITLE)
    while True:
        f, lh, pad = font(px), line_height(px), px // 2
        column = max((f.getlength(k) for k, _ in rows), default=0) + px
        w = int(max(f.getlength(title), column + max((f.getlength(v) for _, v in rows), default=0)) + 2 * pad)
        h = (len(rows) + 1) * lh + 2 * pad
        if px <= SHRUNK_PX or (w <= room[0] and h <= room[1]):
            break
        px -= 1
    image = Image.new("RGBA", (w, h), PANEL)
    draw = ImageDraw.Draw(image)
    draw.text((pad, pad + lh // 2), title, fill=TEXT, font=f, anchor="lm")
    for k, (key, what) in enumerate(rows, 1):
        y = pad + k * lh + lh // 2
        draw.text((pad, y), key, fill=KEY, font=f, anchor="lm")
        draw.text((pad + column, y), what, fill=TEXT, font=f, anchor="lm")
    return np.asarray(image)


def help_place(picture: tuple[int, int, int, int], px: int) -> tuple[tuple[int, int], tuple[int, int]]:
    """Where the help panel goes over a picture at (left, top, width, height): its top left, and the room it has."""
    left, top, w, h = picture
    margin = px // 2
    return (left + margin, top + margin), (max(1, w - 2 * margin), max(1, h - 2 * margin))


def blend(frame: np.ndarray, layer: np.ndarray, x: int, y: int) -> None:
    """Blend the RGBA ``layer`` over the RGB ``frame`` at (x, y), in place, as OpenGL's SRC_ALPHA blending does."""
    h = min(layer.shape[0], frame.shape[0] - y)
    w = min(layer.shape[1], frame.shape[1] - x)
    if h <= 0 or w <= 0:
        return
    src = layer[:h, :w].astype(np.uint32)
    dst = frame[y:y + h, x:x + w].astype(np.uint32)
    a = src[..., 3:4]
    frame[y:y + h, x:x + w] = ((src[..., :3] * a + dst * (255 - a) + 127) // 255).astype(np.uint8)


def compose(picture: np.ndarray, caption: str, lines: int = 1, keys: Keys = (), show_help: bool = False
            ) -> np.ndarray:
    """A frame as the window shows it at the frame's size: the picture (uint8 RGB), the caption band under it, and
    the help panel over its top left when ``show_help``."""
    h, w = picture.shape[:2]
    lines = max(lines, len(caption.split("\n")) if caption else 1)
    width, height = framed_size((w, h), lines)
    px = text_px(height)
    frame = np.empty((height, w, 3), np.uint8)
    frame[:h] = picture[..., :3]
    frame[h:] = BACKGROUND
    blend(frame, band_image(w, caption, lines, px), 0, h)
    if show_help and keys:
        (x, y), room = help_place((0, 0, w, h), px)
        blend(frame, help_image(keys, px, room), x, y)
    return frame


def help_layer(picture_size: tuple[int, int], keys: Keys, lines: int = 1) -> tuple[int, int, np.ndarray]:
    """The help panel of a composed frame and where it goes: (left, top, RGBA panel) (what a test looks for)."""
    w, h = picture_size
    px = text_px(framed_size((w, h), lines)[1])
    (x, y), room = help_place((0, 0, w, h), px)
    return x, y, help_image(keys, px, room)


def help_rect(picture_size: tuple[int, int], keys: Keys, lines: int = 1) -> tuple[int, int, int, int]:
    """(left, top, width, height) of the help panel in a composed frame (what a test leaves out of a comparison)."""
    x, y, panel = help_layer(picture_size, keys, lines)
    return x, y, panel.shape[1], panel.shape[0]
