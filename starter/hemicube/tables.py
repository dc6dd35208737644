"""H1: the delta form factors of the hemicube's cells (Cohen & Greenberg 1985)."""
from __future__ import annotations

import numpy as np


def delta_form_factors(resolution):
    """The delta form factor of every cell of a unit hemicube with ``resolution`` cells across the top face.

    The hemicube has half-width 1 and height 1: the top face is the square z = 1,
    -1 <= x, y <= 1, cut into resolution × resolution cells of area ΔA = (2 / resolution)²;
    each side face is the rectangle -1 <= y <= 1, 0 <= z <= 1, cut into
    (resolution / 2) rows × resolution columns of the same cells. Evaluate at cell centres:

        top:  ΔF = ΔA / (π (x² + y² + 1)²)
        side: ΔF = z ΔA / (π (y² + z² + 1)²)

    Returns ``(top, side)``: ``top`` has shape (resolution, resolution), row j at
    y = -1 + (j + ½)·2/resolution (rows from bottom to top, as OpenGL reads pixels),
    column i at x likewise; ``side`` has shape (resolution // 2, resolution), row j at
    height z = (j + ½)·2/resolution above the base (row 0 touches the base plane),
    column i at y = -1 + (i + ½)·2/resolution. ``resolution`` is even.
    """
    # TODO H1: cell centres on the top face and a side face, then the two formulas (handout §H1)
    raise NotImplementedError("H1: cell centres on the top face and a side face, then the two formulas (handout §H1)")
