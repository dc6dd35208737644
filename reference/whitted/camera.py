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
    # BEGIN SOLUTION W1: build the camera frame as gluLookAt does, then aim at pixel centres (handout §W1)
    eye, center, up = (np.asarray(v, dtype=np.float64) for v in (camera.eye, camera.center, camera.up))
    forward = center - eye
    forward /= np.linalg.norm(forward)
    right = np.cross(forward, up)
    right /= np.linalg.norm(right)
    true_up = np.cross(right, forward)
    tan_y = np.tan(np.radians(camera.fovy) / 2.0)
    tan_x = tan_y * width / height
    x = (2.0 * (np.arange(width) + 0.5) / width - 1.0) * tan_x
    y = (1.0 - 2.0 * (np.arange(height) + 0.5) / height) * tan_y
    across = forward + x[:, None] * right                  # (width, 3): each column's part, then each row's
    directions = (across[None, :, :] + (y[:, None] * true_up)[:, None, :]).reshape(-1, 3)
    sq = directions * directions
    directions /= np.sqrt(sq[:, 0] + sq[:, 1] + sq[:, 2])[:, None]
    origins = np.empty_like(directions)
    origins[:] = eye
    return origins, directions
    # END SOLUTION
