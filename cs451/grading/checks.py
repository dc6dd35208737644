"""Checks shared by every stage's specs: arrays against a truth, images against the reference render."""
from __future__ import annotations

from typing import Callable

import numpy as np

from ..compare import ImageTolerance, compare_images, difference_image, error_heatmap
from ..imageio import to_uint8
from .spec import Check, Outputs, Verdict


def _worst_entry(got: np.ndarray, want: np.ndarray) -> str:
    idx = np.unravel_index(np.argmax(np.abs(got - want)), want.shape)
    where = "[" + ", ".join(str(int(i)) for i in idx) + "]"
    return f"entry {where} is {got[idx]:.6g}, expected {want[idx]:.6g}"


def array_close(key: str, truth: Callable[[dict], np.ndarray], rtol: float = 1e-6, atol: float = 1e-9,
                what: str = "result") -> Check:
    """The output ``key`` must equal ``truth(params)`` within tolerance."""
    def check(out: Outputs, expected: Outputs | None, params: dict) -> Verdict:
        want = np.asarray(truth(params), dtype=np.float64)
        got = np.asarray(out[key], dtype=np.float64)
        if got.shape != want.shape:
            return Verdict.of(False, f"{what} has shape {got.shape}, expected {want.shape}")
        if not np.isfinite(got).all():
            return Verdict.of(False, f"{what} contains NaN or infinite values")
        if np.allclose(got, want, rtol=rtol, atol=atol):
            return Verdict.of(True, f"{what} matches")
        return Verdict.of(False, f"{what} is wrong: {_worst_entry(got, want)}")
    return check


def image_matches(tol: ImageTolerance, key: str = "image") -> Check:
    """The submission's image must match the reference render within ``tol``; the report gets all four pictures."""
    def check(out: Outputs, expected: Outputs | None, params: dict) -> Verdict:
        assert expected is not None
        ref = np.asarray(expected[key], dtype=np.float64)
        got = np.asarray(out[key], dtype=np.float64)
        result = compare_images(ref, got, tol)
        images = {"reference": to_uint8(ref)}
        if got.shape == ref.shape:
            images.update(submission=to_uint8(np.nan_to_num(got)), difference=difference_image(ref, got),
                          error=error_heatmap(result.error_map, tol.threshold))
        detail = {"bad_fraction": result.bad_fraction, "max_error": result.max_error, "mean_error": result.mean_error}
        msg = ("image matches: " if result.passed else "image differs: ") + result.message
        return Verdict(1.0 if result.passed else 0.0, msg, images, detail)
    check.tolerance = tol  # for `cs451 bench tolerance`, which measures the margin
    return check


def all_of(checks: list[tuple[str, Callable[[Outputs, dict], str | None]]]) -> Check:
    """Partial credit over named sub-checks, each returning None when it holds or a reason when it fails."""
    def check(out: Outputs, expected: Outputs | None, params: dict) -> Verdict:
        failures = []
        for name, sub in checks:
            try:
                problem = sub(out, params)
            except Exception as err:  # a malformed answer fails this sub-check only
                problem = f"could not be checked ({type(err).__name__}: {err})"
            if problem:
                failures.append(f"{name}: {problem}")
        passed = len(checks) - len(failures)
        if not failures:
            return Verdict(1.0, f"all {len(checks)} checks hold")
        return Verdict(passed / len(checks), f"{passed}/{len(checks)} checks hold; " + "; ".join(failures))
    return check
