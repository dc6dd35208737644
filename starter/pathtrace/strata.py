"""P5, an optional extension: stratified samples of the light (handout §P5).

Independent random points on the light can bunch together and leave part of it unsampled; their
error falls as 1/√N. Cut the light into k × k cells and put one jittered point in each: no part is
left out, and for a smooth integrand the error falls faster (as N^(-3/4) for a light's edge that
crosses the cells, faster still where the light is whole). The estimate stays unbiased: each
cell's point is uniform within its cell.
"""
from __future__ import annotations

import numpy as np

from .light import direct_light


def stratified_direct_light(scene, points: np.ndarray, normals: np.ndarray, albedo: np.ndarray,
                            jitter: np.ndarray) -> np.ndarray:
    """P2's estimate of the direct light at each point, averaged over one light sample per cell of a k × k grid.

    ``jitter`` (n, k, k, 2): uniform numbers in [0, 1); point p's sample in cell (a, b) is P2's
    ``u = ((a + jitter[p, a, b, 0]) / k, (b + jitter[p, a, b, 1]) / k)``. The other arguments are
    P2's. Returns the radiance (n, 3), the mean over the k² cells of the point's P2 values.
    """
    # TODO P5: every cell's u for every point, one P2 call on them all, a mean per point (handout §P5)
    raise NotImplementedError("P5: every cell's u for every point, one P2 call on them all, a mean per point (handout §P5)")
