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
    # BEGIN SOLUTION R1: a grid of bilinearly interpolated corners per quad, cells as patches (handout §R1)
    quads = np.asarray(quads, dtype=np.float64)
    patches, parent = [], []
    for k, (p0, p1, p2, p3) in enumerate(quads):
        if max_edge > 0:
            nu = max(1, int(np.ceil(max(np.linalg.norm(p1 - p0), np.linalg.norm(p2 - p3)) / max_edge)))
            nv = max(1, int(np.ceil(max(np.linalg.norm(p3 - p0), np.linalg.norm(p2 - p1)) / max_edge)))
        else:
            nu = nv = 1
        u = np.linspace(0.0, 1.0, nu + 1)[None, :, None]
        v = np.linspace(0.0, 1.0, nv + 1)[:, None, None]
        grid = (1 - u) * (1 - v) * p0 + u * (1 - v) * p1 + u * v * p2 + (1 - u) * v * p3  # (nv+1, nu+1, 3)
        cells = np.stack([grid[:-1, :-1], grid[:-1, 1:], grid[1:, 1:], grid[1:, :-1]], axis=2)  # (nv, nu, 4, 3)
        patches.append(cells.reshape(-1, 4, 3))
        parent.append(np.full(nu * nv, k))
    return np.concatenate(patches), np.concatenate(parent).astype(np.int64)
    # END SOLUTION
