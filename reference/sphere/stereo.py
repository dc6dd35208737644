"""S9, an optional extension: the two projections of a stereo pair (handout §S9).

Each eye keeps the cyclops camera's axis (parallel axes: no toe-in, so no vertical parallax) and
looks through its own off-axis frustum, sheared so that both frusta share one window on the plane
at the convergence distance. Objects on that plane appear at the same place in both images.
"""
from __future__ import annotations

import numpy as np


def stereo_projection(fovy: float, aspect: float, near: float, far: float, separation: float, convergence: float,
                      eye: int) -> np.ndarray:
    """glFrustum's matrix (4, 4) for one eye of a parallel-axis stereo pair: ``eye`` −1 (left) or +1 (right) sits
    ``eye·separation/2`` along the camera's x axis; both frusta meet the cyclops frustum on the plane at distance
    ``convergence``. ``separation`` 0 gives gluPerspective's matrix."""
    # BEGIN SOLUTION S9: the cyclops window at the near plane, slid against the eye's offset (handout §S9)
    top = near * np.tan(np.radians(fovy) / 2.0)
    half_width = aspect * top
    shift = eye * (separation / 2.0) * near / convergence    # the eye's offset, seen at the near plane
    left, right = -half_width - shift, half_width - shift
    return np.array([
        [2.0 * near / (right - left), 0.0, (right + left) / (right - left), 0.0],
        [0.0, near / top, 0.0, 0.0],
        [0.0, 0.0, (far + near) / (near - far), 2.0 * far * near / (near - far)],
        [0.0, 0.0, -1.0, 0.0],
    ])
    # END SOLUTION
