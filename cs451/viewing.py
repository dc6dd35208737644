"""The scene camera's matrices for the engine's own drawings (form-factor pictures, the radiosity display).

The engine writes no look-at or perspective of its own: those are tasks S1 and S2, and
the engine ships to students. The projection comes from pyrender's camera model (a
library); the view from a stage's own view function, the top face of a hemicube (H2)
standing at the eye and facing where the camera looks: the kit's reference in the
instructor's kit, the student's own code in a student's render.
"""
from __future__ import annotations

import math
from typing import Any, Callable

import numpy as np


def import_in_background() -> None:
    """Start importing pyrender (1.1 s here: trimesh and scipy come with it) on a thread, for a job that draws with
    :func:`camera_projection` only at its end and has GL work to do first, which releases the GIL."""
    import sys
    import threading

    def load() -> None:
        try:
            __import__("cs451.pyrender_shim")
        except Exception:   # noqa: BLE001 - whatever failed fails again, with its message, where the projection is made
            pass
    if "cs451.pyrender_shim" not in sys.modules:
        threading.Thread(target=load, name="cs451-import-pyrender", daemon=True).start()


def camera_projection(camera: Any, width: int, height: int) -> np.ndarray:
    """Eye to clip space for ``camera`` (fovy, near, far) at this window size, from pyrender."""
    from .pyrender_shim import pyrender

    return pyrender.PerspectiveCamera(yfov=math.radians(camera.fovy), znear=camera.near, zfar=camera.far,
                                      aspectRatio=width / height).get_projection_matrix(width, height)


def camera_view(camera: Any, hemicube_views: Callable[[np.ndarray, np.ndarray, np.ndarray], np.ndarray]) -> np.ndarray:
    """World to eye for ``camera``: the top view of a hemicube at the eye facing the centre, ``up`` made perpendicular."""
    eye, center, up = (np.asarray(v, dtype=np.float64) for v in (camera.eye, camera.center, camera.up))
    forward = (center - eye) / np.linalg.norm(center - eye)
    up = up - (up @ forward) * forward
    return np.asarray(hemicube_views(eye, forward, up / np.linalg.norm(up)), dtype=np.float64)[0]
