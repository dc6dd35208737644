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
    # TODO W11: a loop over bounces; each bounce shades every live ray, then spawns the next ones (handout §W11)
    raise NotImplementedError("W11: a loop over bounces; each bounce shades every live ray, then spawns the next ones (handout §W11)")
