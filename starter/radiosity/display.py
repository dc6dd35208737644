"""R5: Gouraud display data: a colour per vertex, the average of the patches that meet there."""
from __future__ import annotations

import numpy as np


def vertex_colors(quads: np.ndarray, parent: np.ndarray, radiosity: np.ndarray) -> tuple:
    """Shared vertices for the patches, each coloured by the average radiosity of its adjoining patches.

    ``quads`` (m, 4, 3) patches, ``parent`` (m,) int the polygon each patch came from (R1),
    ``radiosity`` (m, 3) one colour per patch. Two patch corners are the same vertex when they
    belong to patches of the same polygon and lie at the same point, within 1e-9 of the scene's
    size (the largest extent, over x, y and z, of the box around all the corners); corners of
    different polygons are never merged, so creases between walls stay sharp.
    A vertex's colour is the plain average of the radiosities of the distinct patches that have
    it as a corner.

    Returns ``(positions, colors, corners)``: positions (k, 3) float, colors (k, 3) float and
    corners (m, 4) int, the vertex index of each patch corner (the kit draws each patch as the
    triangles (0, 1, 2) and (0, 2, 3) of its corners).
    """
    # TODO R5: merge equal corners of the same polygon (np.unique), average the patches per vertex (handout §R5)
    raise NotImplementedError("R5: merge equal corners of the same polygon (np.unique), average the patches per vertex (handout §R5)")
