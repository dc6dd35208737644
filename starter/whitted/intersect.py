"""W2, W3: where rays meet a sphere and a triangle, robustly.

Both functions work on many rays at once (no Python loop over rays) and never
return NaN: a miss is ``inf``.
"""
from __future__ import annotations

import numpy as np


def intersect_sphere(origins: np.ndarray, directions: np.ndarray, center, radius: float) -> tuple[np.ndarray, np.ndarray]:
    """Both ray parameters where rays (n, 3) meet the sphere, smaller first: ``(t0, t1)``, each (n,).

    ``center`` is the sphere's centre, ``radius`` its radius; ``directions`` need not be unit
    length. Where a ray misses, both are ``inf``. Negative values are returned as they are (a ray
    that starts inside has t0 < 0 < t1), and t0 <= t1 always. Must stay accurate for a small
    sphere far away (no cancellation in the quadratic: the handout's stable form).
    """
    # TODO W2: the quadratic in the stable form of Ray Tracing Gems ch. 7 (handout §W2)
    raise NotImplementedError("W2: the quadratic in the stable form of Ray Tracing Gems ch. 7 (handout §W2)")


def intersect_triangle(origins: np.ndarray, directions: np.ndarray, v0: np.ndarray, v1: np.ndarray,
                       v2: np.ndarray) -> np.ndarray:
    """Ray parameter t (n,) where ray i meets triangle (v0[i], v1[i], v2[i]); ``inf`` where it misses.

    All inputs are (n, 3). Only hits with t > 0 count. Watertight: a ray through an edge or a
    vertex shared by two triangles hits at least one of them. A degenerate (zero-area)
    triangle, such as one with a repeated corner, is never hit: its edge functions sum to
    exactly 0.
    """
    # TODO W3: the watertight test of Woop, Benthin and Wald (2013), as in pbrt-v4 (handout §W3)
    raise NotImplementedError("W3: the watertight test of Woop, Benthin and Wald (2013), as in pbrt-v4 (handout §W3)")
