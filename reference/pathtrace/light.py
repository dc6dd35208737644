"""P2: next-event estimation: the light that reaches a point straight from the area light, by one sample of it."""
from __future__ import annotations

import numpy as np

from cs451.tracescene import spawn

from .geometry import unoccluded


def direct_light(scene, points: np.ndarray, normals: np.ndarray, albedo: np.ndarray, u: np.ndarray) -> np.ndarray:
    """The radiance (n, 3) a diffuse surface reflects of the light that comes straight from the area light, estimated
    from one point of the light per surface point: the light's point is ``corner + u[:, 0]·edge_u + u[:, 1]·edge_v``.

    ``points`` (n, 3) on surfaces whose unit ``normals`` (n, 3) face the side the path came from, ``albedo`` ρ (n, 3).
    The estimate is L_e · ρ/π · cos θ · cos θ_L / r² · A where the light's point is seen (a shadow ray through
    ``unoccluded``, starting off the surface), θ at the surface and θ_L at the light are both under 90°, and 0
    elsewhere. Its mean over uniform ``u`` is the direct light, exactly.
    """
    # BEGIN SOLUTION P2: sample the light uniformly by area; the pdf 1/A turns dω into cos θ_L dA / r² (handout §P2)
    x = np.asarray(points, dtype=np.float64)
    n = np.asarray(normals, dtype=np.float64)
    u = np.asarray(u, dtype=np.float64)
    y = scene.light_corner + u[:, :1] * scene.light_u + u[:, 1:2] * scene.light_v
    d = y - x
    r2 = np.einsum("ij,ij->i", d, d)
    w = d / np.sqrt(r2)[:, None]
    cos_x = np.einsum("ij,ij->i", n, w)
    cos_l = -(w @ scene.light_normal)
    lit = (cos_x > 0) & (cos_l > 0)
    out = np.zeros_like(x)
    if lit.any():
        seen = unoccluded(scene, spawn(x[lit], n[lit], w[lit]), y[lit])
        geometry = cos_x[lit] * cos_l[lit] / r2[lit] * scene.light_area * seen
        out[lit] = scene.light_radiance * np.asarray(albedo, dtype=np.float64)[lit] / np.pi * geometry[:, None]
    return out
    # END SOLUTION
