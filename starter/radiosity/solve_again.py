"""R6: solving again after a change of colours or lights, without computing form factors again (notes §2.2).

A form factor F_ij depends on the two patches' shapes and positions and on what stands between them, and on
nothing else: not on their reflectances, not on what emits. So once a scene has been solved, the rows of form
factors its shooters fetched serve every later solve of the same patches, whatever their colours or lights.
"""
from __future__ import annotations

from typing import Callable

import numpy as np

from .shooting import progressive_refinement


def solve_again(known: dict, row: Callable[[int], np.ndarray], areas: np.ndarray, reflectance: np.ndarray,
            emission: np.ndarray, tolerance: float, max_shots: int, overshoot: float,
            on_shot: Callable | None) -> tuple:
    """Solve the same patches again with new ``reflectance`` and ``emission``, as R3 does, reusing rows.

    ``known`` maps a patch index (int) to its row of form factors, (n,), kept from earlier solves of these
    patches. Take a patch's row from ``known`` when it is there; otherwise compute it with ``row(i)``, once,
    and add it to ``known`` under ``int(i)``, so that later shots and later solves find it. Every other
    argument, the order of shots and the result are R3's: returns ``(radiosity, unshot, order)``.
    """
    # TODO R6: a row function that looks in known first and remembers what it computes; then R3's loop (handout §R6)
    raise NotImplementedError("R6: a row function that looks in known first and remembers what it computes; then R3's loop (handout §R6)")
