"""H2 and H3: where the hemicube's five cameras look, and their frusta."""
from __future__ import annotations

import numpy as np


# BEGIN SOLUTION
def _cross(a, b):
    """a × b of two 3-vectors, written out: np.cross is ten times slower on one pair, and radiosity asks for
    five views per hemicube, thousands of hemicubes a solve."""
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])


def _look_at(eye, center, up):
    f = center - eye
    f = f / np.sqrt(f @ f)
    s = _cross(f, up)
    s = s / np.sqrt(s @ s)
    u = _cross(s, f)
    m = np.eye(4)
    m[0, :3], m[1, :3], m[2, :3] = s, u, -f
    m[:3, 3] = -m[:3, :3] @ eye
    return m


def _frustum(left, right, bottom, top, near, far):
    m = np.zeros((4, 4))
    m[0, 0] = 2 * near / (right - left)
    m[0, 2] = (right + left) / (right - left)
    m[1, 1] = 2 * near / (top - bottom)
    m[1, 2] = (top + bottom) / (top - bottom)
    m[2, 2] = -(far + near) / (far - near)
    m[2, 3] = -2 * far * near / (far - near)
    m[3, 2] = -1.0
    return m
# END SOLUTION


def hemicube_views(center, normal, up):
    """The five view matrices (world to eye, 4×4 each, gluLookAt's convention) of a hemicube at ``center``.

    ``normal`` is the patch's unit normal and ``up`` a unit vector perpendicular to it
    (it fixes the hemicube's rotation about the normal); let ``side = normal × up``.
    Face 0 (top) looks along ``normal`` with ``up`` as its up vector; faces 1 to 4 look
    along ``up``, ``-up``, ``side`` and ``-side``, each with ``normal`` as its up vector,
    so the upper half of their image is the half-space in front of the patch.
    Returns an array of shape (5, 4, 4).
    """
    # BEGIN SOLUTION H2: five gluLookAt matrices from the centre, one per face direction (handout §H2)
    c, n, u = (np.asarray(a, dtype=np.float64) for a in (center, normal, up))
    s = _cross(n, u)
    looks = [(n, u), (u, n), (-u, n), (s, n), (-s, n)]
    return np.stack([_look_at(c, c + d, up_) for d, up_ in looks])
    # END SOLUTION


def hemicube_projections(near, far):
    """The projection matrices (4×4, glFrustum's convention) of the top face and of a side face.

    Top: a 90° square frustum, glFrustum(-near, near, -near, near, near, far).
    Side: only the upper half of the same frustum, glFrustum(-near, near, 0, near, near, far),
    drawn into an image half as high as it is wide. Returns an array of shape (2, 4, 4): (top, side).
    """
    # BEGIN SOLUTION H3: glFrustum with the top face's square window and the side face's upper half (handout §H3)
    return np.stack([_frustum(-near, near, -near, near, near, far), _frustum(-near, near, 0.0, near, near, far)])
    # END SOLUTION
