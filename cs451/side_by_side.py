"""``cs451 compare``: a render beside its target, with the grader's per-pixel verdict and ꟻLIP.

The picture a student wants when a test fails: target, mine, the error map the grader uses (after its
3×3 allowance) and the perceptual error, in one PNG with a label over each.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from PIL import Image as PILImage, ImageDraw

from .compare import ImageTolerance, compare_images, error_heatmap, flip_error
from .errors import KitError
from .imageio import check_output, load_png, save_png

LABEL_HEIGHT = 16


@dataclass(frozen=True)
class Comparison:
    passed: bool
    message: str            # the grader's words: "17.02% of pixels differ by more than 0.016 …"
    flip_mean: float
    output: Path


def _labelled(image: np.ndarray, label: str) -> np.ndarray:
    canvas = PILImage.new("RGB", (image.shape[1], image.shape[0] + LABEL_HEIGHT), (255, 255, 255))
    canvas.paste(PILImage.fromarray(image), (0, LABEL_HEIGHT))
    ImageDraw.Draw(canvas).text((3, 2), label, fill=(0, 0, 0))
    return np.asarray(canvas)


def compare_files(mine: str | Path, target: str | Path, output: str | Path,
                  tolerance: ImageTolerance = ImageTolerance()) -> Comparison:
    """Compare two PNGs as the image tests do (the 8-bit values as written) and write them side by side."""
    check_output(output)
    a, b = load_png(target), load_png(mine)
    if a.shape != b.shape:
        raise KitError(f"{mine}: is {b.shape[1]}x{b.shape[0]}, the target {target} is {a.shape[1]}x{a.shape[0]}; "
                       f"render at the target's size (--size {a.shape[1]}x{a.shape[0]})")
    return side_by_side(a, b, output, tolerance)


def side_by_side(target: np.ndarray, mine: np.ndarray, output: str | Path,
                 tolerance: ImageTolerance = ImageTolerance(), labels: tuple[str, str] = ("target", "mine")) -> Comparison:
    """Two images of one size (linear, 0-1) judged as the image tests judge them, and written to ``output`` side by
    side with the grader's error map and ꟻLIP's: the picture a failing image test points at."""
    result = compare_images(target, mine, tolerance)
    target8, mine8 = (np.round(np.clip(x, 0.0, 1.0) * 255).astype(np.uint8) for x in (target, mine))
    flip_mean, flip_map = flip_error(target8, mine8)
    panels = [_labelled(target8, labels[0]), _labelled(mine8, labels[1]),
              _labelled(error_heatmap(result.error_map, tolerance.threshold), "error (grader)"),
              _labelled(flip_map, f"FLIP {flip_mean:.3f}")]
    gap = np.full((panels[0].shape[0], 4, 3), 255, np.uint8)
    row = np.concatenate([p for panel in panels for p in (panel, gap)][:-1], axis=1)
    path = save_png(output, row)
    return Comparison(result.passed, result.message, flip_mean, path)

