"""S5, S6: shaders that reproduce OpenGL 1.x fixed-function lighting.

The kit puts ``#version 330`` and the declarations of every uniform and input
in front of your source (see ``GLSL_INTERFACE`` in ``cs451/stages/sphere/__init__.py``):
the vertex shader receives ``in_position`` and ``in_normal`` in object space;
the fragment shader writes ``frag_color``.
"""
from __future__ import annotations



def gouraud_shaders() -> tuple[str, str]:
    """Per-vertex lighting, as glShadeModel(GL_SMOOTH): the colour is computed at each vertex and interpolated.

    Returns ``(vertex_source, fragment_source)`` without the ``#version`` line.
    """
    # TODO S5: light each vertex in eye space, pass the colour down, interpolate (handout §S5)
    raise NotImplementedError("S5: light each vertex in eye space, pass the colour down, interpolate (handout §S5)")


def phong_shaders() -> tuple[str, str]:
    """Per-fragment lighting (Phong shading): interpolate position and normal, light each pixel.

    Returns ``(vertex_source, fragment_source)`` without the ``#version`` line.
    """
    # TODO S6: pass eye-space position and normal down, renormalise, light per fragment (handout §S6)
    raise NotImplementedError("S6: pass eye-space position and normal down, renormalise, light per fragment (handout §S6)")
