"""W1: a ray from the eye through the centre of every pixel."""
from __future__ import annotations

import numpy as np


def camera_rays(camera, width: int, height: int) -> tuple[np.ndarray, np.ndarray]:
    """Primary rays of a pinhole camera, one through the centre of each pixel.

    ``camera`` has ``eye``, ``center``, ``up`` (3-vectors, gluLookAt's) and ``fovy``
    (vertical field of view in degrees). Pixels are numbered row by row from the top
    left: ray ``j * width + i`` goes through the centre of column ``i`` of row ``j``.
    Returns ``(origins, directions)``, each (width·height, 3) float; the origins are the
    eye, the directions unit vectors.
    """
    # TODO W1: build the camera frame as gluLookAt does, then aim at pixel centres (handout §W1)
    raise NotImplementedError("W1: build the camera frame as gluLookAt does, then aim at pixel centres (handout §W1)")
