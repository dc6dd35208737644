"""W12, an optional extension: depth of field with a thin lens (handout §W12).

A pinhole sees everything sharp. A real camera gathers light over a lens: only the plane at the
focus distance is sharp, and points off it blur into discs (the circle of confusion). A thin lens
needs no new geometry: move each camera ray's origin to a point of the lens disc, and aim it at
the point where the pinhole ray meets the plane of focus.
"""
from __future__ import annotations

import numpy as np


def thin_lens(camera, directions: np.ndarray, aperture: float, focus: float, u: np.ndarray
              ) -> tuple[np.ndarray, np.ndarray]:
    """Camera rays through a thin lens of radius ``aperture`` focused at distance ``focus`` (along the view axis).

    ``directions`` (n, 3): pinhole rays from ``camera.eye`` (W1's); ``u`` (n, 2) uniform numbers in [0, 1): ray k's
    lens point is at radius ``aperture·√u[k, 0]`` and angle ``2π·u[k, 1]`` from the camera's right axis towards its
    up axis (W1's frame). Returns ``(origins, directions)`` (n, 3) each, the directions unit vectors.
    """
    # TODO W12: a point of the lens disc, and the pinhole ray's point on the plane of focus (handout §W12)
    raise NotImplementedError("W12: a point of the lens disc, and the pinhole ray's point on the plane of focus (handout §W12)")
