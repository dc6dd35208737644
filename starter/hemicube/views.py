"""H2 and H3: where the hemicube's five cameras look, and their frusta."""
from __future__ import annotations

import numpy as np




def hemicube_views(center, normal, up):
    """The five view matrices (world to eye, 4×4 each, gluLookAt's convention) of a hemicube at ``center``.

    ``normal`` is the patch's unit normal and ``up`` a unit vector perpendicular to it
    (it fixes the hemicube's rotation about the normal); let ``side = normal × up``.
    Face 0 (top) looks along ``normal`` with ``up`` as its up vector; faces 1 to 4 look
    along ``up``, ``-up``, ``side`` and ``-side``, each with ``normal`` as its up vector,
    so the upper half of their image is the half-space in front of the patch.
    Returns an array of shape (5, 4, 4).
    """
    # TODO H2: five gluLookAt matrices from the centre, one per face direction (handout §H2)
    raise NotImplementedError("H2: five gluLookAt matrices from the centre, one per face direction (handout §H2)")


def hemicube_projections(near, far):
    """The projection matrices (4×4, glFrustum's convention) of the top face and of a side face.

    Top: a 90° square frustum, glFrustum(-near, near, -near, near, near, far).
    Side: only the upper half of the same frustum, glFrustum(-near, near, 0, near, near, far),
    drawn into an image half as high as it is wide. Returns an array of shape (2, 4, 4): (top, side).
    """
    # TODO H3: glFrustum with the top face's square window and the side face's upper half (handout §H3)
    raise NotImplementedError("H3: glFrustum with the top face's square window and the side face's upper half (handout §H3)")
