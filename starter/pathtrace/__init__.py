"""Stage 5, Monte Carlo path tracing: the functions you write, gathered for the kit to call.

The kit imports this package and calls only the names below (see ``cs451/stages/pathtrace/__init__.py`` for
the interface). ``camera_rays``, ``closest_hit`` and ``unoccluded`` (geometry.py) are given: plain versions of
what your Whitted tracer does, so that this stage stands on its own. Keep them, or put your own in their place.
"""
from .geometry import camera_rays, closest_hit, unoccluded
from .light import direct_light
from .roulette import roulette
from .sampling import cosine_sample
from .strata import stratified_direct_light
from .tracer import radiance

__all__ = ["camera_rays", "closest_hit", "unoccluded", "cosine_sample", "direct_light", "roulette", "radiance",
           "stratified_direct_light"]
