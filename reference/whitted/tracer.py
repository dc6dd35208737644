"""W11: Whitted's recursion, as a wavefront: every ray of a bounce is traced at once.

A ray carries a weight β (RGB): what its colour contributes to its pixel. The
camera rays start with β = 1; a reflected ray's β is the parent's times the
reflectance, a transmitted ray's the parent's times the transmittance. Camera rays
have depth 0, and a ray cast at a hit of a depth-k ray depth k + 1: it is cast only
where the max over RGB of its β is at least ``scene.min_weight`` (the cut-off) and
its depth at most ``scene.max_depth``.
"""
from __future__ import annotations

import numpy as np

from cs451.tracescene import TraceScene, spawn

from .bvh import closest_hit
from .optics import fresnel, reflect, refract
from .shading import local_shading, shadow_transmission


def trace(scene: TraceScene, origins: np.ndarray, directions: np.ndarray) -> np.ndarray:
    """The colour (n, 3) seen along each ray (n, 3): the camera rays of an image.

    For each ray the closest hit; there, emission + ambient, plus for each light sample
    the local shading times what reaches the point (shadow rays); then the reflected and
    transmitted rays, weighted, traced the same way. ``scene.background`` where nothing
    is hit. Counts the rays it casts in ``scene.counters`` ("camera", "reflection",
    "transmission"; shadow rays are counted by ``shadow_transmission``).
    """
    # BEGIN SOLUTION W11: a loop over bounces; each bounce shades every live ray, then spawns the next ones (handout §W11)
    origins = np.asarray(origins, dtype=np.float64)
    directions = np.asarray(directions, dtype=np.float64)
    n = len(origins)
    colour = np.zeros((n, 3))
    scene.counters["camera"] += n
    o, d, beta, pixel = origins, directions, np.ones((n, 3)), np.arange(n)
    for depth in range(scene.max_depth + 1):
        if len(o) == 0:
            break
        t, prim, normals = closest_hit(scene, o, d)
        miss = prim < 0
        np.add.at(colour, pixel[miss], beta[miss] * scene.background)
        hit = ~miss
        o, d, beta, pixel, t, prim, normals = o[hit], d[hit], beta[hit], pixel[hit], t[hit], prim[hit], normals[hit]
        points = o + t[:, None] * d
        m = scene.material_at(prim, points)
        cos = -np.einsum("ij,ij->i", d, normals)
        entering = cos >= 0
        facing = np.where(entering[:, None], normals, -normals)  # the normal on the ray's side
        local = scene.mat_emission[m] + scene.mat_ambient[m] * scene.ambient_light
        shiny = np.any(scene.mat_diffuse[m] > 0, axis=1) | np.any(scene.mat_specular[m] > 0, axis=1)
        for k in range(len(scene.light_position)):
            light_d, light_s, to_light, _ = scene.light_toward(k, points)
            lit = shiny & (np.einsum("ij,ij->i", facing, to_light) > 0) & (np.any(light_d > 0, axis=1) | np.any(light_s > 0, axis=1))
            if not lit.any():
                continue  # no shadow ray toward a light behind the surface
            p_lit = points[lit]
            starts = spawn(p_lit, facing[lit], to_light[lit])
            through = shadow_transmission(scene, starts, np.broadcast_to(scene.light_position[k], p_lit.shape))
            local[lit] += local_shading(facing[lit], -d[lit], to_light[lit], light_d[lit] * through,
                                        light_s[lit] * through, scene.mat_diffuse[m[lit]], scene.mat_specular[m[lit]],
                                        scene.mat_shininess[m[lit]])
        np.add.at(colour, pixel, beta * local)
        if depth == scene.max_depth:
            break
        kr, kt = scene.mat_reflectance[m], scene.mat_transmittance[m]
        eta = np.where(entering, 1.0 / scene.mat_ior[m], scene.mat_ior[m])
        glass = np.any(kt > 0, axis=1)
        refracted = np.zeros_like(d)
        tir = np.zeros(len(d), bool)
        if glass.any():
            refracted[glass], tir[glass] = refract(d[glass], facing[glass], eta[glass])
        f = np.zeros(len(d))
        use_fresnel = glass & scene.mat_fresnel[m]
        if use_fresnel.any():
            f[use_fresnel] = fresnel(np.abs(cos[use_fresnel]), eta[use_fresnel])
        f = np.where(tir, 1.0, f)[:, None]
        w_reflect = beta * (kr + kt * f)
        w_transmit = beta * kt * (1.0 - f)
        rays = []
        for kind, weight, side in (("reflection", w_reflect, 1.0), ("transmission", w_transmit, -1.0)):
            go = np.max(weight, axis=1) >= max(scene.min_weight, 1e-300)  # the β cut-off
            if not go.any():
                continue
            new_d = reflect(d[go], facing[go]) if side > 0 else refracted[go]
            new_d /= np.linalg.norm(new_d, axis=1, keepdims=True)
            scene.counters[kind] += int(go.sum())
            rays.append((spawn(points[go], facing[go], new_d), new_d, weight[go], pixel[go]))
        if not rays:
            break
        o, d, beta, pixel = (np.concatenate(parts) for parts in zip(*rays))
    return colour
    # END SOLUTION
