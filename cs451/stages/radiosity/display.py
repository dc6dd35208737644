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


#: the same drawing with the highlight of :mod:`cs451.stages.radiosity.highlight` added per pixel: the normalised Phong lobe of each
#: glossy patch, lit by every light sample (no shadows), on top of the interpolated radiosity
GLOSSY_VERTEX_SHADER = """#version 330
uniform mat4 u_mvp;
in vec3 in_position;
in vec3 in_color;
in vec3 in_normal;
in vec4 in_gloss;             // k_s (rgb), shininess n
out vec3 v_color;
out vec3 v_world;
flat out vec3 v_normal;
flat out vec4 v_gloss;
void main() {
    gl_Position = u_mvp * vec4(in_position, 1.0);
    v_color = in_color; v_world = in_position; v_normal = in_normal; v_gloss = in_gloss;
}
"""
GLOSSY_FRAGMENT_SHADER = """#version 330
in vec3 v_color;
in vec3 v_world;
flat in vec3 v_normal;
flat in vec4 v_gloss;
uniform vec3 u_encoding;
uniform vec3 u_eye;
uniform int u_samples;
uniform sampler2D u_lights;   // row k: position, unit normal of the emitting side, radiance x area share
out vec4 frag_color;
const float PI = 3.14159265358979;
vec3 srgb(vec3 c) {
    return mix(12.92 * c, 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, step(vec3(0.0031308), c));
}
vec3 highlight() {
    float n = v_gloss.a;
    vec3 wo = normalize(u_eye - v_world);
    vec3 normal = dot(v_normal, wo) < 0.0 ? -v_normal : v_normal;    // the side the viewer sees
    vec3 sum = vec3(0.0);
    for (int k = 0; k < u_samples; k++) {
        vec3 d = texelFetch(u_lights, ivec2(0, k), 0).xyz - v_world;
        float r2 = dot(d, d);
        vec3 wi = d * inversesqrt(r2);
        float cos_x = dot(normal, wi);
        float cos_y = -dot(texelFetch(u_lights, ivec2(1, k), 0).xyz, wi);
        if (cos_x <= 0.0 || cos_y <= 0.0) continue;
        float cos_a = max(dot(2.0 * cos_x * normal - wi, wo), 0.0);
        sum += texelFetch(u_lights, ivec2(2, k), 0).xyz * (pow(cos_a, n) * cos_x * cos_y / r2);
    }
    return v_gloss.rgb * ((n + 2.0) / (2.0 * PI)) * sum;
}
void main() {
    vec3 color = v_gloss.a > 0.0 ? v_color + highlight() : v_color;
    vec3 c = clamp(color * u_encoding.y, 0.0, 1.0);
    frag_color = vec4(u_encoding.x < 0.5 ? color : (u_encoding.z > 0.5 ? srgb(c) : c), 1.0);
}
"""


def camera_matrix(scene: Any, width: int, height: int, view: np.ndarray) -> np.ndarray:
    """Projection · view of the scene camera: pyrender's projection (:mod:`cs451.viewing`), the view given."""
    from ...viewing import camera_projection

    return camera_projection(scene.camera, width, height) @ view


class GouraudDrawer:
    """Draws coloured quads with colours interpolated across them, into a float framebuffer."""

    def __init__(self, ctx: Any = None):
        from ...gl import create_context

        self.ctx = ctx or create_context()
        self.program = self.ctx.program(vertex_shader=VERTEX_SHADER, fragment_shader=FRAGMENT_SHADER)
        self._glossy: Any = None          # compiled when a highlight is first drawn

    @property
    def glossy(self) -> Any:
        """The program that adds a glossy highlight per pixel, compiled on first use (most scenes never need it)."""
        if self._glossy is None:
            self._glossy = self.ctx.program(vertex_shader=GLOSSY_VERTEX_SHADER, fragment_shader=GLOSSY_FRAGMENT_SHADER)
        return self._glossy

    def draw(self, positions: np.ndarray, colors: np.ndarray, corners: np.ndarray, mvp: np.ndarray,
             width: int, height: int, background: Any = (0.0, 0.0, 0.0), fbo: Any = None,
             viewport: tuple[int, int, int, int] | None = None,
             encoding: tuple[float, bool] | None = None, highlight: Any = None) -> np.ndarray | None:
        """Draw into ``fbo`` (a window's screen, at ``viewport``: nothing is read back) or a new float framebuffer (returned).

        ``encoding`` (exposure, sRGB) is applied in the shader, for a window; a framebuffer read back keeps linear values
        (the image is encoded when it is written). Without it, colours pass through unchanged and unclamped.
        ``highlight`` (a :class:`cs451.stages.radiosity.highlight.Highlight` with one row per vertex) adds the glossy reflection of the
        lights per pixel; without it the drawing is the plain Gouraud one."""
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
        ibo = ctx.buffer(triangles.tobytes())
        extra: list[Any] = []
        if highlight is None:
            program = self.program
            vbo = ctx.buffer(np.hstack([positions, colors]).astype("f4").tobytes())
            vao = ctx.vertex_array(program, [(vbo, "3f 3f", "in_position", "in_color")], ibo)
        else:
            program = self.glossy
            vertices = np.hstack([positions, colors, highlight.normals, highlight.coefficients])
            vbo = ctx.buffer(vertices.astype("f4").tobytes())
            vao = ctx.vertex_array(program, [(vbo, "3f 3f 3f 4f", "in_position", "in_color", "in_normal", "in_gloss")],
                                   ibo)
            lights = np.ascontiguousarray(highlight.lights, dtype="f4")
            texture = ctx.texture((3, max(len(lights), 1)), 3, lights.tobytes() if len(lights) else bytes(36),
                                  dtype="f4")
            texture.filter = (ctx.NEAREST, ctx.NEAREST)
            texture.use(location=0)
            extra.append(texture)
            for name, value in (("u_lights", 0), ("u_samples", len(lights)),
                                ("u_eye", tuple(float(x) for x in highlight.eye))):
                uniform = program.get(name, None)      # a uniform the compiler found unused is not there
                if uniform is not None:
                    uniform.value = value
        program["u_mvp"].write(np.asarray(mvp, dtype="f4").T.tobytes())
        exposure, srgb = encoding if encoding is not None else (1.0, False)
        program["u_encoding"].value = (1.0 if encoding is not None else 0.0, float(exposure), 1.0 if srgb else 0.0)
        vao.render()
        ctx.finish()
        for obj in (vao, ibo, vbo, *extra):
            obj.release()
        if not read:
            return None
        data = np.frombuffer(fbo.read(components=3, dtype="f4"), dtype=np.float32).reshape(height, width, 3)
        fbo.release()
        return np.flipud(data).astype(np.float64)


def with_highlight(positions: np.ndarray, colors: np.ndarray, corners: np.ndarray, highlight: Any
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray, Any]:
    """R5's vertices split into one vertex per patch corner, each carrying its patch's normal and Phong coefficients.

    The highlight belongs to the patch, not to R5's shared vertex (a vertex R5 merged across polygons would have
    no one normal); the colours stay R5's, so the interpolated radiosity is exactly what the plain drawing shows.
    """
    corners = np.asarray(corners)
    flat = corners.reshape(-1)
    own = np.arange(len(flat), dtype=np.int64).reshape(corners.shape)
    return positions[flat], colors[flat], own, highlight.per_corner(corners.shape[1])


def flat_corners(quads: np.ndarray, parent: np.ndarray, values: np.ndarray) -> tuple[np.ndarray, ...]:
    """Vertex colours shaped as R5 returns them, but each patch's own corners in its own value: flat patches (the
    demo's ``g`` and the deck's flat pictures), to set beside R5's Gouraud colours."""
    return quads.reshape(-1, 3), np.repeat(values, quads.shape[1], axis=0), np.arange(quads.size // 3).reshape(-1, 4)


def draw_solution(scene: Any, vertex_colors: Callable, patches: Any, display: np.ndarray, size: tuple[int, int] | None,
                  view: np.ndarray, exposure: float = 1.0, drawer: GouraudDrawer | None = None,
                  highlight: Any = None) -> np.ndarray:
    """The Gouraud-shaded image of per-patch radiosities (shown as radiance B/π), through ``vertex_colors`` (R5).

    ``highlight`` (a :class:`cs451.stages.radiosity.highlight.Highlight`, one row per patch) adds the glossy materials' direct
    reflection of the lights, in radiance like the rest, times ``exposure``."""
    width, height = size or (scene.image.width, scene.image.height)
    positions, colors, corners = vertex_colors(patches.quads, patches.parent, display)
    if highlight is not None:
        positions, colors, corners, highlight = with_highlight(positions, colors, corners, highlight.scaled(exposure))
    drawer = drawer or GouraudDrawer()
    return drawer.draw(positions, colors * (exposure / math.pi), corners, camera_matrix(scene, width, height, view),
                       width, height, scene.image.background, highlight=highlight)
