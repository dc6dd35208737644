"""Image I/O: linear float RGB in memory, 8-bit PNG on disk.

Colours stay linear floats until an image is written; the scene's ``image``
block says the exposure and whether the sRGB curve is applied.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
from PIL import Image as PILImage

from .errors import KitError


def srgb_encode(linear: np.ndarray) -> np.ndarray:
    """The sRGB transfer curve (IEC 61966-2-1) on values clamped to [0, 1]."""
    x = np.clip(linear, 0.0, 1.0)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)


def to_uint8(image: np.ndarray, exposure: float = 1.0, srgb: bool = False) -> np.ndarray:
    """Linear float (h, w, 3) to displayable uint8 (h, w, 3)."""
    x = np.asarray(image, dtype=np.float64) * exposure
    x = srgb_encode(x) if srgb else np.clip(x, 0.0, 1.0)
    return np.round(x * 255.0).astype(np.uint8)


def check_output(path: str | Path, option: str = "-o") -> Path:
    """Refuse, before any work, an output that cannot become a PNG file: a folder, another type, a file in the way."""
    text = str(path)
    path = Path(path)
    if text.endswith(("/", "\\")) or path.is_dir():
        raise KitError(f"{option} {text}: is a folder; give a file name such as {path / 'image.png'}")
    if path.suffix.lower() != ".png":
        raise KitError(f"{option} {text}: images are written as PNG; give a name ending in .png")
    for parent in path.parents:
        if parent.exists():
            if not parent.is_dir():
                raise KitError(f"{option} {text}: {parent} is a file, not a folder")
            break
    return path


def save_png(path: str | Path, image: np.ndarray, exposure: float = 1.0, srgb: bool = False) -> Path:
    """Write a linear float image (or a uint8 image as it is) as PNG, creating folders as needed."""
    path = check_output(path)
    data = image if image.dtype == np.uint8 else to_uint8(image, exposure, srgb)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        PILImage.fromarray(data[..., :3]).save(path)
    except OSError as err:
        raise KitError(f"{path}: cannot write the image ({err.strerror or err})") from None
    return path


def load_png(path: str | Path) -> np.ndarray:
    """Read an image as float (h, w, 3) in [0, 1], without decoding sRGB."""
    try:
        with PILImage.open(path) as im:
            return np.asarray(im.convert("RGB"), dtype=np.float64) / 255.0
    except (OSError, ValueError) as err:
        raise KitError(f"{path}: cannot read image ({err})") from None
