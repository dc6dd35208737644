"""H6 (the proximity fix): the exact form factor from a point to a polygon, by Lambert's contour integral."""
from __future__ import annotations

import numpy as np


def point_polygon_form_factor(point, normal, polygon):
    """F from a differential area at ``point`` with unit ``normal`` to a planar ``polygon`` (m, 3) in front of it.

    Lambert's formula (Stokes' theorem on the unit hemisphere): with
    r_k = polygon[k] - point and the edge from r_k to r_{k+1} (wrapping around),

        F = 1/(2π) · | Σ_k θ_k  normal · (r_k × r_{k+1}) / |r_k × r_{k+1}| |,

    θ_k being the angle between r_k and r_{k+1}. The kit clips the polygon to the
    half-space in front of the point before calling. An edge whose |r_k × r_{k+1}| is at
    most 1e-300 (a repeated corner, as a triangle stored as a quad has) contributes
    nothing. Returns a float.
    """
    # BEGIN SOLUTION H6: sum θ_k n·γ_k over the edges (γ_k the unit r_k × r_k+1), skip edges whose cross product is 0, divide by 2π (handout §H6)
    p = np.asarray(point, dtype=np.float64)
    n = np.asarray(normal, dtype=np.float64)
    r = np.asarray(polygon, dtype=np.float64) - p
    a, b = r, np.roll(r, -1, axis=0)
    cross = np.cross(a, b)
    length = np.linalg.norm(cross, axis=1)
    theta = np.arctan2(length, np.einsum("ij,ij->i", a, b))
    ok = length > 1e-300
    total = np.sum(theta[ok] * (cross[ok] @ n) / length[ok])
    return float(abs(total) / (2 * np.pi))
    # END SOLUTION
