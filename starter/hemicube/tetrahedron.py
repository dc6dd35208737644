"""H7, an optional extension: the cubic tetrahedron of Beran-Koch and Neumann (handout §H7).

A hemicube draws one full face and four half faces, five views in all. Tilt the cube so that
the patch's normal runs along its diagonal and three faces of a cube corner enclose the whole
hemisphere above the patch: three identical views, each a triangle of its face. Every view has
the same delta form factors, so one table serves all three.
"""
from __future__ import annotations

import numpy as np


def tetrahedron_delta_form_factors(resolution: int) -> np.ndarray:
    """The delta form factors of one face of the cubic tetrahedron, (resolution, resolution).

    In the frame where the patch sits at the origin with normal (1, 1, 1)/√3, a face is the square
    z = 1, -2 <= x, y <= 1, cut into resolution × resolution cells of area (3 / resolution)²;
    row j at y = -2 + (j + ½)·3/resolution, column i at x likewise. Only the triangle above the
    patch's plane (x + y + 1 > 0 at the cell's centre) sees anything: 0 elsewhere. A cell's value
    at its centre is cos θ_patch · cos θ_face · ΔA / (π r²) = (x + y + 1) ΔA / (√3 π (x² + y² + 1)²).
    """
    # TODO H7: cell centres over [-2, 1]², the formula, and 0 below the patch's plane (handout §H7)
    raise NotImplementedError("H7: cell centres over [-2, 1]², the formula, and 0 below the patch's plane (handout §H7)")
