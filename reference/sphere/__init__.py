"""Stage 1, the lit sphere: the functions you write, gathered for the kit to call.

The kit imports this package and calls only the names below (see
``cs451/stages/sphere/__init__.py`` for the interface). Keep them.
"""
from .camera import look_at, perspective, reshape
from .controls import handle_key
from .mesh import sphere_mesh
from .shaders import gouraud_shaders, phong_shaders
from .stereo import stereo_projection
from .transforms import model_view_matrices

__all__ = ["perspective", "look_at", "model_view_matrices", "sphere_mesh", "gouraud_shaders", "phong_shaders", "reshape", "handle_key",
           "stereo_projection"]
