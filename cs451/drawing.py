"""Drawing coloured surfaces with the scene's camera: colours interpolated across quads (Gouraud), into a
float framebuffer read back for images, or into a window's screen for demos.

Matrices never come from code of the kit's own (look-at and perspective are stage 1's tasks):
the projection from pyrender, the view from a stage's H2 (:mod:`cs451.viewing`).
"""
from __future__ import annotations

import math
from typing import Any, Callable

import numpy as np


VERTEX_SHADER = """#version 330
uniform mat4 u_mvp;
in vec3 in_position;
in vec3 in_color;
out vec3 v_color;
void main() { gl_Position = u_mvp * vec4(in_position, 1.0); v_color = in_color; }
"""
FRAGMENT_SHADER = """#version 330
in vec3 v_color;
uniform vec3 u_encoding;      // on (1) or off (0: values pass through), exposure, sRGB (1) or linear (0)
out vec4 frag_color;
vec3 srgb(vec3 c) {
    return mix(12.92 * c, 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, step(vec3(0.0031308), c));
}
void main() {
    vec3 c = clamp(v_color * u_encoding.y, 0.0, 1.0);
    frag_color = vec4(u_encoding.x < 0.5 ? v_color : (u_encoding.z > 0.5 ? srgb(c) : c), 1.0);
}
"""


def camera_matrix(scene: Any, width: int, height: int, view: np.ndarray) -> np.ndarray:
    """Projection · view of the scene camera: pyrender's projection (:mod:`cs451.viewing`), the view given."""
    from .viewing import camera_projection

    return camera_projection(scene.camera, width, height) @ view


class GouraudDrawer:
    """Draws coloured quads with colours interpolated across them, into a float framebuffer."""

    def __init__(self, ctx: Any = None):
        from .gl import create_context

        self.ctx = ctx or create_context()
        self.program = self.ctx.program(vertex_shader=VERTEX_SHADER, fragment_shader=FRAGMENT_SHADER)

    def draw(self, positions: np.ndarray, colors: np.ndarray, corners: np.ndarray, mvp: np.ndarray,
             width: int, height: int, background: Any = (0.0, 0.0, 0.0), fbo: Any = None,
             viewport: tuple[int, int, int, int] | None = None,
             encoding: tuple[float, bool] | None = None) -> np.ndarray | None:
        """Draw into ``fbo`` (a window's screen, at ``viewport``: nothing is read back) or a new float framebuffer (returned).

        ``encoding`` (exposure, sRGB) is applied in the shader, for a window; a framebuffer read back keeps linear values
        (the image is encoded when it is written). Without it, colours pass through unchanged and unclamped."""
        ctx = self.ctx
        read = fbo is None
        if read:
            fbo = ctx.framebuffer(color_attachments=[ctx.renderbuffer((width, height), 4, dtype="f4")],
                                  depth_attachment=ctx.depth_renderbuffer((width, height)))
        fbo.use()
        viewport = viewport or (0, 0, width, height)
        ctx.viewport = viewport
        ctx.enable(ctx.DEPTH_TEST)
        ctx.disable(ctx.CULL_FACE)                   # both sides of a patch show its radiosity
        fbo.clear(*background, 1.0, depth=1.0, viewport=viewport)
        triangles = np.concatenate([corners[:, [0, 1, 2]], corners[:, [0, 2, 3]]]).astype("i4")
        vbo = ctx.buffer(np.hstack([positions, colors]).astype("f4").tobytes())
        ibo = ctx.buffer(triangles.tobytes())
        vao = ctx.vertex_array(self.program, [(vbo, "3f 3f", "in_position", "in_color")], ibo)
        self.program["u_mvp"].write(np.asarray(mvp, dtype="f4").T.tobytes())
        exposure, srgb = encoding if encoding is not None else (1.0, False)
        self.program["u_encoding"].value = (1.0 if encoding is not None else 0.0, float(exposure), 1.0 if srgb else 0.0)
        vao.render()
        ctx.finish()
        for obj in (vao, ibo, vbo):
            obj.release()
        if not read:
            return None
        data = np.frombuffer(fbo.read(components=3, dtype="f4"), dtype=np.float32).reshape(height, width, 3)
        fbo.release()
        return np.flipud(data).astype(np.float64)


def draw_solution(scene: Any, vertex_colors: Callable, patches: Any, display: np.ndarray, size: tuple[int, int] | None,
                  view: np.ndarray, exposure: float = 1.0, drawer: GouraudDrawer | None = None) -> np.ndarray:
    """The Gouraud-shaded image of per-patch radiosities (shown as radiance B/π), through ``vertex_colors`` (R5)."""
    width, height = size or (scene.image.width, scene.image.height)
    positions, colors, corners = vertex_colors(patches.quads, patches.parent, display)
    drawer = drawer or GouraudDrawer()
    return drawer.draw(positions, colors * (exposure / math.pi), corners, camera_matrix(scene, width, height, view),
                       width, height, scene.image.background)
