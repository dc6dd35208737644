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
    # BEGIN SOLUTION W2: the quadratic in the stable form of Ray Tracing Gems ch. 7 (handout §W2)
    o = np.asarray(origins, dtype=np.float64)
    d = np.asarray(directions, dtype=np.float64)
    f = o - np.asarray(center, dtype=np.float64)
    a = np.einsum("ij,ij->i", d, d)
    b = np.einsum("ij,ij->i", f, d)                   # half of the textbook b
    perp = f - (b / a)[:, None] * d                   # f's part perpendicular to the ray
    disc = radius * radius - np.einsum("ij,ij->i", perp, perp)
    c = np.einsum("ij,ij->i", f, f) - radius * radius
    hit = disc >= 0
    root = np.sqrt(np.where(hit, a * disc, 0.0))
    q = -(b + np.copysign(root, b))
    hit &= q != 0
    q = np.where(hit, q, 1.0)
    t0, t1 = c / q, q / a
    lo, hi = np.minimum(t0, t1), np.maximum(t0, t1)
    return np.where(hit, lo, np.inf), np.where(hit, hi, np.inf)
    # END SOLUTION


def intersect_triangle(origins: np.ndarray, directions: np.ndarray, v0: np.ndarray, v1: np.ndarray,
                       v2: np.ndarray) -> np.ndarray:
    """Ray parameter t (n,) where ray i meets triangle (v0[i], v1[i], v2[i]); ``inf`` where it misses.

    All inputs are (n, 3). Only hits with t > 0 count. Watertight: a ray through an edge or a
    vertex shared by two triangles hits at least one of them. A degenerate (zero-area)
    triangle, such as one with a repeated corner, is never hit: its edge functions sum to
    exactly 0.
    """
    # BEGIN SOLUTION W3: the watertight test of Woop, Benthin and Wald (2013), as in pbrt-v4 (handout §W3)
    o = np.asarray(origins, dtype=np.float64)
    d = np.asarray(directions, dtype=np.float64)
    n = len(o)
    rows = np.arange(n)
    kz = np.argmax(np.abs(d), axis=1)
    kx = (kz + 1) % 3
    ky = (kx + 1) % 3
    dz = d[rows, kz]
    sx, sy, sz = -d[rows, kx] / dz, -d[rows, ky] / dz, 1.0 / dz
    pts = []
    for v in (v0, v1, v2):
        p = np.asarray(v, dtype=np.float64) - o
        px, py, pz = p[rows, kx], p[rows, ky], p[rows, kz]
        pts.append((px + sx * pz, py + sy * pz, pz * sz))
    (x0, y0, z0), (x1, y1, z1), (x2, y2, z2) = pts
    e0 = x1 * y2 - y1 * x2
    e1 = x2 * y0 - y2 * x0
    e2 = x0 * y1 - y0 * x1
    mixed = ((e0 < 0) | (e1 < 0) | (e2 < 0)) & ((e0 > 0) | (e1 > 0) | (e2 > 0))
    det = e0 + e1 + e2
    t_scaled = e0 * z0 + e1 * z1 + e2 * z2
    ok = ~mixed & (det != 0) & (t_scaled * np.sign(det) > 0)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = t_scaled / det
    return np.where(ok & np.isfinite(t), t, np.inf)
    # END SOLUTION
