"""Checks shared by every stage's specs: arrays against a truth, images against the reference render.

Every check has the signature ``check(out, expected, params, **kwargs) -> Verdict`` and
is named by :func:`cs451.grading.spec.check`; sub-checks of :func:`all_of` return
``None`` when they hold or a reason when they fail. Checks only compare: what an
answer should be comes from ``expected`` (the reference's answer or a truth's
arrays), never from code here, because this module ships to students.
"""
from __future__ import annotations

from typing import Any

import numpy as np

from ..compare import ImageTolerance, compare_images, difference_image, error_heatmap
from ..imageio import to_uint8
from ..stages.base import shape_text
from .spec import CHECK_MODULES, Outputs, Ref, Verdict, check


class ShapeError(ValueError):
    """An output does not have the shape the test's parameters call for."""


def output(out: Outputs, key: str, shape: tuple[int | None, ...] | None = None, what: str | None = None) -> np.ndarray:
    """``out[key]`` as float64 of exactly ``shape`` (``None``: any length), checked before any work is done on it."""
    if key not in out:
        raise ShapeError(f"{what or key} is missing from the answer")
    value = np.asarray(out[key])
    if value.dtype.kind not in "biuf":
        raise ShapeError(f"{what or key} holds {value.dtype} values, not numbers")
    if shape is not None and (value.ndim != len(shape) or any(s is not None and s != g for s, g in zip(shape, value.shape))):
        raise ShapeError(f"{what or key} has shape {value.shape}, expected {shape_text(shape)}")
    return value.astype(np.float64)


def _worst_entry(got: np.ndarray, want: np.ndarray) -> str:
    idx = np.unravel_index(np.argmax(np.abs(got - want)), want.shape)
    where = "[" + ", ".join(str(int(i)) for i in idx) + "]"
    return f"entry {where} is {got[idx]:.6g}, expected {want[idx]:.6g}"


def close_to(out: Outputs, expected: Outputs, params: dict, key: str, truth_key: str = "value", rtol: float = 1e-6,
             atol: float = 1e-9, what: str = "result", plural: bool = False) -> Verdict:
    """The output ``key`` equals ``expected[truth_key]`` within tolerance (same shape, finite, non-empty).

    ``what`` names the output in messages; ``plural`` when it is a plural noun ("the five view matrices match").
    """
    is_, has, match = ("are", "contain", "match") if plural else ("is", "contains", "matches")
    want = np.asarray(expected[truth_key], dtype=np.float64)
    try:
        got = output(out, key, want.shape, what)
    except ShapeError as err:
        return Verdict.of(False, str(err))
    if not np.isfinite(got).all():
        return Verdict.of(False, f"{what} {has} NaN or infinite values")
    if got.size == 0:
        return Verdict.of(False, f"{what} {is_} empty")
    if np.allclose(got, want, rtol=rtol, atol=atol):
        return Verdict.of(True, f"{what} {match}")
    return Verdict.of(False, f"{what} {is_} wrong: {_worst_entry(got, want)}")


def array_close(key: str, truth_key: str = "value", rtol: float = 1e-6, atol: float = 1e-9, what: str = "result",
                plural: bool = False) -> Ref:
    """The check that output ``key`` equals the truth's ``truth_key`` within tolerance (``plural``: see :func:`close_to`)."""
    return check(close_to, key=key, truth_key=truth_key, rtol=rtol, atol=atol, what=what, plural=plural)


def _shown(image: np.ndarray, params: dict) -> np.ndarray:
    """An image as ``cs451 render`` writes it: the test scene's exposure and encoding (sRGB or linear)."""
    settings = (params.get("scene") or {}).get("image", {}) if isinstance(params.get("scene"), dict) else {}
    return to_uint8(image, float(settings.get("exposure", 1.0)), bool(settings.get("srgb", False)))


def target_images(expected: Outputs | None, params: dict, key: str = "image") -> dict[str, np.ndarray]:
    """The reference's render of an image test, for a report whose submission drew nothing (it crashed, timed
    out or is not written yet): the student still sees the target."""
    image = (expected or {}).get(key)
    if image is None:
        return {}
    image = np.asarray(image)
    if image.ndim != 3 or image.shape[2] not in (3, 4) or image.dtype.kind not in "fu":
        return {}
    return {"reference": image if image.dtype == np.uint8 else _shown(image, params)}


def image_check(out: Outputs, expected: Outputs, params: dict, threshold: float, max_bad_fraction: float, shift: int,
                key: str = "image") -> Verdict:
    """The submission's image matches the reference render (compared in linear values); the report gets all four
    pictures, the two renders shown as ``cs451 render`` writes them."""
    tol = ImageTolerance(threshold, max_bad_fraction, shift)
    ref = np.asarray(expected[key], dtype=np.float64)
    try:
        got = output(out, key, ref.shape, "the image")
    except ShapeError as err:
        return Verdict(0.0, str(err), {"reference": _shown(ref, params)})
    result = compare_images(ref, got, tol)
    images = {"reference": _shown(ref, params), "submission": _shown(np.nan_to_num(got), params),
              "difference": difference_image(ref, got), "error": error_heatmap(result.error_map, tol.threshold)}
    detail = {"bad_fraction": result.bad_fraction, "max_error": result.max_error, "mean_error": result.mean_error}
    msg = ("image matches: " if result.passed else "image differs: ") + result.message
    return Verdict(1.0 if result.passed else 0.0, msg, images, detail)


def image_part(out: Outputs, expected: Outputs, params: dict, threshold: float, max_bad_fraction: float, shift: int,
               key: str = "image") -> str | None:
    """As a sub-check: None when the image matches the reference's, else why not."""
    verdict = image_check(out, expected, params, threshold, max_bad_fraction, shift, key)
    return None if verdict.passed else verdict.message


def image_matches(tol: ImageTolerance, key: str = "image") -> Ref:
    """The check that the image ``key`` matches the reference's within ``tol``."""
    return check(image_check, threshold=tol.threshold, max_bad_fraction=tol.max_bad_fraction, shift=tol.shift, key=key)


def image_part_of(tol: ImageTolerance, key: str = "image") -> Ref:
    """The sub-check form of :func:`image_matches`, for tests that judge an image and something beside it."""
    return check(image_part, threshold=tol.threshold, max_bad_fraction=tol.max_bad_fraction, shift=tol.shift, key=key)


def image_tolerance(ref: Ref) -> ImageTolerance | None:
    """The tolerance of an image check (for `cs451 bench tolerance`, which measures the margin)."""
    if ref.name != "image_check":
        return None
    k = ref.kwargs
    return ImageTolerance(k["threshold"], k["max_bad_fraction"], k["shift"])


def all_checks(out: Outputs, expected: Outputs, params: dict, parts: list, require: list | None = None,
               earn_with: list | None = None) -> Verdict:
    """Partial credit over named sub-checks, never for an answer that passes them by doing nothing.

    ``require``: sub-checks whose failure makes the whole test fail (the counts of a mesh, say).
    ``earn_with``: sub-checks of which at least one must hold for any credit (the key presses that
    change the state: an unchanged state passes the others, and earns nothing for it).
    """
    failures, required_failed = [], False
    for label, module, name, kwargs in parts:
        sub = Ref(module, name).resolve(CHECK_MODULES)
        try:
            problem = sub(out, expected, params, **kwargs)
        except ShapeError as err:
            problem = str(err)
        except Exception as err:  # a malformed answer fails this sub-check only
            problem = f"could not be checked ({type(err).__name__}: {err})"
        if problem:
            failures.append(f"{label}: {problem}")
            required_failed |= label in (require or [])
    passed = len(parts) - len(failures)
    if not failures:
        return Verdict(1.0, f"all {len(parts)} checks hold")
    failed = {f.split(":", 1)[0] for f in failures}
    nothing_earned = bool(earn_with) and all(label in failed for label in earn_with)
    fraction = 0.0 if required_failed or nothing_earned else passed / len(parts)
    return Verdict(fraction, f"{passed}/{len(parts)} checks hold; " + "; ".join(failures))


def all_of(parts: list[tuple[str, Ref]], require: list[str] | None = None, earn_with: list[str] | None = None) -> Ref:
    """Partial credit over named sub-checks (each a :class:`Ref` to ``sub(out, expected, params, **kw) -> str | None``)."""
    labels = [label for label, _ in parts]
    if len(set(labels)) != len(labels) or not set(require or []) | set(earn_with or []) <= set(labels):
        raise ValueError(f"sub-check labels must be unique and name the parts: {labels}")
    return check(all_checks, parts=[[label, ref.module, ref.name, ref.kwargs] for label, ref in parts],
                 require=list(require or []), earn_with=list(earn_with or []))


def sub(fn: Any, **kwargs: Any) -> Ref:
    """Name a sub-check for :func:`all_of`."""
    return check(fn, **kwargs)
