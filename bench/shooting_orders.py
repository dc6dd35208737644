"""The 1988 paper's order of shooting, for the benchmark beside the notes' sweeps (the student's R3).

Cohen, Chen, Wallace and Greenberg pick the shooter again before every shot: always the patch
with the most unshot energy now. Here that is one numpy ``argmax`` over the keys per shot
(O(n), a few microseconds for thousands of patches), not a heap push for every key a shot
changes. It lives in ``bench/``, never in what a student's release ships: with the engine's
rows it is a working shooting loop.
"""
from __future__ import annotations

from types import SimpleNamespace
from typing import Any, Callable

import numpy as np


def always_the_maximum(row: Callable[[int], np.ndarray], areas: np.ndarray, reflectance: np.ndarray,
                       emission: np.ndarray, tolerance: float, max_shots: int, overshoot: float,
                       on_shot: Callable | None) -> tuple[np.ndarray, np.ndarray, list[int]]:
    """R3's contract (same arguments, same stopping rule), shooting from the current maximum every time."""
    areas = np.asarray(areas, dtype=np.float64)
    radiosity = np.array(emission, dtype=np.float64)
    unshot = radiosity.copy()
    key = np.abs(unshot).sum(axis=1) * areas
    total_emitted = float((np.asarray(emission).sum(axis=1) * areas).sum())
    reflects = reflectance.max(axis=1) > 0
    order: list[int] = []
    while len(order) < max_shots and key.sum() > tolerance * total_emitted:
        i = int(np.argmax(key))                      # the first of equal keys: ties go to the lower index
        if key[i] == 0.0:
            break
        shot = overshoot * unshot[i]
        left = unshot[i] - shot
        f = row(i)
        received = reflectance * (f * (areas[i] / areas))[:, None] * shot[None, :]
        radiosity += received
        unshot += received
        unshot[i] = left
        order.append(i)
        changed = reflects & (f != 0)
        changed[i] = True
        key[changed] = np.abs(unshot[changed]).sum(axis=1) * areas[changed]
        if on_shot is not None:
            on_shot(len(order), i, radiosity, unshot)
    return radiosity, unshot, order


def with_maximum_order(impl: Any) -> Any:
    """The implementation ``impl`` with its R3 replaced by :func:`always_the_maximum` (its other tasks kept)."""
    names = ("subdivide", "shoot", "ambient_term", "vertex_colors")
    return SimpleNamespace(**{n: getattr(impl, n) for n in names}, progressive_refinement=always_the_maximum,
                           __name__=getattr(impl, "__name__", "maximum-order"))
