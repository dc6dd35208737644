"""P4: the path tracer: each ray's radiance, by paths that bounce off diffuse surfaces and sample the light at each."""
from __future__ import annotations

import numpy as np

from cs451.tracescene import spawn

from .geometry import closest_hit
from .light import direct_light
from .roulette import roulette
from .sampling import cosine_sample


def radiance(scene, origins: np.ndarray, directions: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """The radiance (n, 3) arriving along each ray (n, 3), estimated by one path each, with random numbers from ``rng``.

    Where a ray meets the light's front it sees L_e; a surface, what the surface reflects: at each bounce, the
    direct light (P2) times the path's weight β, then a cosine-distributed direction (P1) on which β is multiplied
    by the albedo, and from bounce ``scene.roulette_depth`` on, Russian roulette (P3). A path ends at a miss, at
    the light (whose light the last bounce's P2 already counted), when the roulette ends it, or after
    ``scene.max_depth`` bounces. Counts "camera" and "bounce" rays in ``scene.counters``.
    """
    # BEGIN SOLUTION P4: a wavefront of paths: hit, add β·direct light, sample a direction, β·ρ, roulette (handout §P4)
    o = np.asarray(origins, dtype=np.float64)
    d = np.asarray(directions, dtype=np.float64)
    n = len(o)
    colour = np.zeros((n, 3))
    beta = np.ones((n, 3))
    path = np.arange(n)
    scene.counters["camera"] += n
    t, tri = closest_hit(scene, o, d)
    front = (tri >= 0) & scene.emitter[np.maximum(tri, 0)] & (d @ scene.light_normal < 0)
    colour[front] = scene.light_radiance
    for depth in range(scene.max_depth):
        go = (tri >= 0) & ~scene.emitter[np.maximum(tri, 0)]
        o, d, t, tri, beta, path = o[go], d[go], t[go], tri[go], beta[go], path[go]
        if len(path) == 0:
            break
        x = o + t[:, None] * d
        normal = scene.normal[tri]
        normal = np.where((np.einsum("ij,ij->i", d, normal) < 0)[:, None], normal, -normal)   # the side we came from
        rho = scene.albedo[tri]
        u = rng.random((len(path), 2))
        colour[path] += beta * direct_light(scene, x, normal, rho, u)
        d = cosine_sample(normal, rng.random((len(path), 2)))
        beta = beta * rho
        if depth + 1 >= scene.roulette_depth:
            alive, beta = roulette(beta, rng.random(len(path)))
            x, normal, d, beta, path = x[alive], normal[alive], d[alive], beta[alive], path[alive]
        o = spawn(x, normal, d)
        scene.counters["bounce"] += len(path)
        t, tri = closest_hit(scene, o, d)
    return colour
    # END SOLUTION
