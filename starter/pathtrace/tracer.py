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
    # TODO P4: a wavefront of paths: hit, add β·direct light, sample a direction, β·ρ, roulette (handout §P4)
    raise NotImplementedError("P4: a wavefront of paths: hit, add β·direct light, sample a direction, β·ρ, roulette (handout §P4)")
