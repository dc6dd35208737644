"""Stage 2, Whitted ray tracing: the functions you write, gathered for the kit to call.

The kit imports this package and calls only the names below (see
``cs451/stages/whitted/__init__.py`` for the interface). Keep them.
"""
from .bvh import build_bvh, closest_hit
from .camera import camera_rays
from .intersect import intersect_sphere, intersect_triangle
from .lens import thin_lens
from .optics import fresnel, reflect, refract
from .shading import local_shading, shadow_transmission
from .tracer import trace

__all__ = ["camera_rays", "intersect_sphere", "intersect_triangle", "build_bvh", "closest_hit", "local_shading",
           "shadow_transmission", "reflect", "refract", "fresnel", "trace",
           "thin_lens"]
