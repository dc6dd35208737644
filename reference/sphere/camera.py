"""S1, S2, S7: the matrices that replace gluPerspective, gluLookAt and the GLUT reshape callback.

Matrices are numpy float64 arrays of shape (4, 4) acting on column vectors
(``clip = P @ V @ p``), as in the OpenGL specification; the kit transposes them
for the GPU.
"""
from __future__ import annotations

import numpy as np


def perspective(fovy: float, aspect: float, near: float, far: float) -> np.ndarray:
    """gluPerspective: the projection for a vertical field of view ``fovy`` in degrees.

    Returns a (4, 4) float array mapping eye space to clip space.
    """
    # BEGIN SOLUTION S1: build the matrix of gluPerspective row by row (handout §S1)
    f = 1.0 / np.tan(np.radians(fovy) / 2.0)
    return np.array([
        [f / aspect, 0.0, 0.0, 0.0],
        [0.0, f, 0.0, 0.0],
        [0.0, 0.0, (far + near) / (near - far), 2.0 * far * near / (near - far)],
        [0.0, 0.0, -1.0, 0.0],
    ])
    # END SOLUTION


def look_at(eye, center, up) -> np.ndarray:
    """gluLookAt: the view matrix for a camera at ``eye`` looking at ``center``.

    ``eye``, ``center`` and ``up`` are 3-vectors. Returns a (4, 4) float array
    mapping world space to eye space (the camera at the origin looking down -z).
    """
    # BEGIN SOLUTION S2: the rows are s, u and -f, then a translation by -eye (handout §S2)
    eye, center, up = (np.asarray(v, dtype=np.float64) for v in (eye, center, up))
    f = center - eye
    f /= np.linalg.norm(f)
    s = np.cross(f, up)
    s /= np.linalg.norm(s)
    u = np.cross(s, f)
    rotation = np.eye(4)
    rotation[0, :3], rotation[1, :3], rotation[2, :3] = s, u, -f
    translation = np.eye(4)
    translation[:3, 3] = -eye
    return rotation @ translation
    # END SOLUTION


def reshape(width: int, height: int, camera) -> tuple:
    """The GLUT reshape callback: the viewport and a projection that keeps the aspect ratio.

    ``camera`` has ``fovy``, ``near`` and ``far``. Returns ``((x, y, w, h), projection)``
    where the viewport covers the whole window and ``projection`` is (4, 4), from your
    ``perspective`` (S1). A window may be minimised to a height of 0: do not divide by zero.
    """
    # BEGIN SOLUTION S7: cover the window, and use its aspect ratio in the projection (handout §S7)
    height = max(int(height), 1)
    width = max(int(width), 1)
    return (0, 0, width, height), perspective(camera.fovy, width / height, camera.near, camera.far)
    # END SOLUTION
