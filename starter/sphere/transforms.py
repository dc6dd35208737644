"""S3: the modelview matrix as OpenGL 1.x builds it: glTranslate, glRotate, glScale and the matrix stack.

Each call multiplies its matrix onto the right of the current one (notes §1), so
the call made last is the first applied to an object's vertices. Matrices act on
column vectors, as in ``camera.py``.
"""
from __future__ import annotations

import numpy as np


def translate(x: float, y: float, z: float) -> np.ndarray:
    """glTranslate's matrix: moves a point by (x, y, z)."""
    # TODO S3: the identity with the offset in the last column (handout §S3)
    raise NotImplementedError("S3: the identity with the offset in the last column (handout §S3)")


def rotate(angle: float, x: float, y: float, z: float) -> np.ndarray:
    """glRotate's matrix: ``angle`` degrees counter-clockwise about the axis (x, y, z), seen from its tip.

    The axis need not be unit length: glRotate normalises it.
    """
    # TODO S3: normalise the axis, then Rodrigues' formula c·I + (1 − c)·a·aᵀ + s·[a]× (handout §S3)
    raise NotImplementedError("S3: normalise the axis, then Rodrigues' formula c·I + (1 − c)·a·aᵀ + s·[a]× (handout §S3)")


def scale(x: float, y: float, z: float) -> np.ndarray:
    """glScale's matrix: stretches by x, y and z along the axes."""
    # TODO S3: the factors on the diagonal (handout §S3)
    raise NotImplementedError("S3: the factors on the diagonal (handout §S3)")


def model_view_matrices(view, calls) -> np.ndarray:
    """Run a list of modelview calls on a matrix stack that starts with ``view``; the matrix at each ``draw``.

    ``calls`` holds tuples in the order a program makes them: ``("translate", x, y, z)``,
    ``("rotate", angle, x, y, z)``, ``("scale", x, y, z)``, ``("push",)``, ``("pop",)`` and
    ``("draw",)``. Returns a (number of draws, 4, 4) float array: the current matrix at each draw.
    """
    # TODO S3: a list as the stack; push copies the top, each transform multiplies on the right (handout §S3)
    raise NotImplementedError("S3: a list as the stack; push copies the top, each transform multiplies on the right (handout §S3)")
