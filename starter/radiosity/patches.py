"""R1: discretising the scene into patches small enough for the lighting."""
from __future__ import annotations

import numpy as np


def subdivide(quads: np.ndarray, max_edge: float) -> tuple:
    """Split every quad into a grid of smaller quads whose edges are at most ``max_edge`` long.

    ``quads`` is (n, 4, 3) float: planar convex quads, corners counter-clockwise seen from the
    front; a triangle is a quad whose last corner repeats the third. Quad k becomes a grid of
    ``nu × nv`` quads, ``nu = max(1, ceil(longest of edges 0-1 and 3-2 / max_edge))`` and
    ``nv = max(1, ceil(longest of edges 0-3 and 1-2 / max_edge))``, with corners placed by bilinear
    interpolation of the four corners, in the same (counter-clockwise) order. A ``max_edge`` of 0
    or less keeps every quad as it is.

    Returns ``(patches, parent)``: patches (m, 4, 3) float, parent (m,) int, the index of the quad
    each patch came from. Patches of quad 0 come first, then quad 1's, and so on; within a quad,
    row by row along the 0→3 edge, each row along the 0→1 edge.
    """
    # TODO R1: a grid of bilinearly interpolated corners per quad, cells as patches (handout §R1)
    raise NotImplementedError("R1: a grid of bilinearly interpolated corners per quad, cells as patches (handout §R1)")
