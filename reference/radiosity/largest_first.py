"""R7, an optional extension: the 1988 paper's order of shooting (handout §R7).

Cohen, Chen, Wallace and Greenberg choose the shooter again before every shot: always the patch
with the most unshot energy at that moment. The notes' sweeps (R3) fix an order for a whole sweep.
Both reorder the same iteration and reach the same answer; they differ in how many shots it takes,
most of all when overshooting.
"""
from __future__ import annotations

from typing import Callable

import numpy as np

from .shooting import shoot


def shoot_largest_first(row: Callable[[int], np.ndarray], areas: np.ndarray, reflectance: np.ndarray,
                        emission: np.ndarray, tolerance: float, max_shots: int, overshoot: float,
                        on_shot: Callable | None) -> tuple:
    """R3's contract (the same arguments, keys, overshooting, stopping rule, ``on_shot`` and result), but the shooter
    is the patch of the largest key now, before every shot (ties go to the lower index). Returns
    ``(radiosity, unshot, order)``."""
    # BEGIN SOLUTION R7: R3's loop without sweeps: the largest key before every shot (handout §R7)
    areas = np.asarray(areas, dtype=np.float64)
    radiosity = np.array(emission, dtype=np.float64)
    unshot = radiosity.copy()
    total_emitted = float((np.asarray(emission).sum(axis=1) * areas).sum())
    order: list[int] = []
    key = np.abs(unshot).sum(axis=1) * areas
    while len(order) < max_shots and key.sum() > tolerance * total_emitted:   # so some key is above 0
        i = int(np.argmax(key))                  # the first of equal keys
        left = (1.0 - overshoot) * unshot[i]
        unshot[i] = overshoot * unshot[i]
        radiosity, unshot = shoot(i, row(i), areas, reflectance, radiosity, unshot)
        unshot[i] = left
        order.append(i)
        key = np.abs(unshot).sum(axis=1) * areas
        if on_shot is not None:
            on_shot(len(order), i, radiosity, unshot)
    return radiosity, unshot, order
    # END SOLUTION
