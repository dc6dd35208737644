"""Image comparison for grading: per-pixel threshold, fraction of bad pixels, 3x3 shift tolerance.

As in Blender's render tests (threshold 0.016, at most 1% bad pixels), with
idiff's idea of forgiving one-pixel edge shifts: a pixel's error is the
smallest difference to any pixel in the other image's 3x3 neighbourhood,
taken both ways, so a silhouette one pixel off costs nothing while a wrong
colour anywhere does.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class ImageTolerance:
    """How close two renders must be; one object so every stage states its tolerance the same way."""
    threshold: float = 0.016      # per-pixel error (max over channels, linear [0,1]) above which a pixel is bad
    max_bad_fraction: float = 0.01  # fraction of bad pixels allowed
    shift: int = 1                # neighbourhood radius forgiven for edge shifts (0: exact pixels)

    def describe(self) -> str:
        return (f"per-pixel error ≤ {self.threshold:g} (after a {2 * self.shift + 1}×{2 * self.shift + 1} "
                f"shift allowance) on all but {self.max_bad_fraction:.1%} of pixels")


@dataclass(frozen=True)
class ImageComparison:
    passed: bool
    bad_fraction: float
    max_error: float
    mean_error: float
    error_map: np.ndarray          # (h, w) float: per-pixel error after the shift allowance
    message: str


def _neighbourhood_min_error(a: np.ndarray, b: np.ndarray, radius: int) -> np.ndarray:
    """For each pixel p of b: min over q within radius of p of max_c |a(q) - b(p)|."""
    h, w, _ = a.shape
    pad = np.pad(a, ((radius, radius), (radius, radius), (0, 0)), mode="edge")
    best = np.full((h, w), np.inf)
    for dy in range(2 * radius + 1):
        for dx in range(2 * radius + 1):
            diff = np.abs(pad[dy:dy + h, dx:dx + w] - b).max(axis=2)
            np.minimum(best, diff, out=best)
    return best


def compare_images(reference: np.ndarray, candidate: np.ndarray,
                   tol: ImageTolerance = ImageTolerance()) -> ImageComparison:
    """Compare two (h, w, 3) linear images; the message says why they differ."""
    ref = np.asarray(reference, dtype=np.float64)
    cand = np.asarray(candidate, dtype=np.float64)
    if cand.shape != ref.shape:
        return ImageComparison(False, 1.0, np.inf, np.inf, np.ones(ref.shape[:2]),
                               f"image has shape {cand.shape}, expected {ref.shape}")
    if not np.isfinite(cand).all():
        bad = ~np.isfinite(cand).all(axis=2)
        return ImageComparison(False, float(bad.mean()), np.inf, np.inf, bad.astype(float),
                               f"{int(bad.sum())} pixels are NaN or infinite")
    if tol.shift > 0:
        err = np.maximum(_neighbourhood_min_error(cand, ref, tol.shift),
                         _neighbourhood_min_error(ref, cand, tol.shift))
    else:
        err = np.abs(cand - ref).max(axis=2)
    bad = err > tol.threshold
    frac = float(bad.mean())
    passed = frac <= tol.max_bad_fraction
    msg = (f"{frac:.2%} of pixels differ by more than {tol.threshold:g} "
           f"(allowed {tol.max_bad_fraction:.1%}); largest difference {err.max():.3f}")
    return ImageComparison(passed, frac, float(err.max()), float(err.mean()), err, msg)


def error_heatmap(error: np.ndarray, threshold: float) -> np.ndarray:
    """A uint8 RGB picture of an error map: black where equal, yellow up to the threshold, red beyond."""
    e = np.clip(error / max(threshold, 1e-12), 0.0, 4.0)
    out = np.zeros(error.shape + (3,), dtype=np.float64)
    below = e <= 1.0
    out[below, 0] = e[below] * 0.8
    out[below, 1] = e[below] * 0.8
    out[~below, 0] = 0.6 + 0.1 * e[~below]
    return np.round(np.clip(out, 0, 1) * 255).astype(np.uint8)


def difference_image(reference: np.ndarray, candidate: np.ndarray, gain: float = 4.0) -> np.ndarray:
    """|reference - candidate| amplified, as uint8 RGB, for reports."""
    if reference.shape != candidate.shape:
        return np.zeros(reference.shape, dtype=np.uint8)
    d = np.abs(np.nan_to_num(candidate, nan=1.0, posinf=1.0, neginf=1.0) - reference) * gain
    return np.round(np.clip(d, 0, 1) * 255).astype(np.uint8)


def flip_error(reference: np.ndarray, test: np.ndarray) -> tuple[float, np.ndarray]:
    """NVIDIA's FLIP (flip-evaluator) between two images as a screen shows them (uint8, read as sRGB):
    the mean perceptual error in [0, 1] and its error map, coloured (magma: black where alike), as uint8."""
    import flip_evaluator  # local: only reports need it
    ref = np.asarray(reference, dtype=np.float32) / 255.0
    got = np.asarray(test, dtype=np.float32) / 255.0
    error_map, mean, _ = flip_evaluator.evaluate(ref, got, "LDR")
    return float(mean), np.round(np.clip(error_map, 0.0, 1.0) * 255.0).astype(np.uint8)
