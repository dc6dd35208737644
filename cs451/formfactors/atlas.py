"""The item-buffer atlas: every face of a batch of hemicubes in one instanced draw, read back once.

The scene's triangles go to the GPU once. Each hemicube face of a batch is one instance of
a single draw, placed into its tile of one R32UI atlas; clip distances keep it inside the
tile and cut away everything in or behind the shooter's plane. The student's H4 shaders
run inside a fixed interface (below): the kit defines the view and projection of the
instance, and moves the result into its tile.
"""
from __future__ import annotations

from typing import Any

import numpy as np

from ..errors import KitError
from ..patches import patch_triangles

#: Put in front of the student's vertex shader (H4); the kit defines the two functions after it.
VERTEX_INTERFACE = """#version 330
in vec3 in_position;          // a corner of a patch, world coordinates
in uint in_id;                // the index of its patch, 0 .. n-1
mat4 hemicube_view();         // this face's view matrix (H2)
mat4 hemicube_projection();   // this face's projection (H3)
"""
FRAGMENT_INTERFACE = """#version 330
out uint item;                // 0: no patch; k + 1: patch k
"""
#: After the student's vertex shader: the instance's matrices, and its placement into the atlas tile.
_VERTEX_ENGINE = """
#undef main
uniform sampler2D u_faces;          // per instance (shooter × face): 4 columns of the view, the tile rectangle, the base plane
uniform mat4 u_projections[2];      // top, side
uniform int u_face_base;            // the first face of this draw: 0 for one instanced draw, the face for one draw a face
out float gl_ClipDistance[5];
int hemicube_face() { return u_face_base + gl_InstanceID; }
mat4 hemicube_view() {
    int f = hemicube_face();
    return mat4(texelFetch(u_faces, ivec2(0, f), 0), texelFetch(u_faces, ivec2(1, f), 0),
                texelFetch(u_faces, ivec2(2, f), 0), texelFetch(u_faces, ivec2(3, f), 0));
}
mat4 hemicube_projection() { return u_projections[(hemicube_face() % 5) == 0 ? 0 : 1]; }
void main() {
    item_main();
    vec4 c = gl_Position;
    int f = hemicube_face();
    vec4 rect = texelFetch(u_faces, ivec2(4, f), 0);   // x0, y0, x1, y1 in the atlas's NDC
    gl_ClipDistance[0] = c.w + c.x;
    gl_ClipDistance[1] = c.w - c.x;
    gl_ClipDistance[2] = c.w + c.y;
    gl_ClipDistance[3] = c.w - c.y;
    vec4 plane = texelFetch(u_faces, ivec2(5, f), 0);  // the shooter's plane, raised by a hair
    gl_ClipDistance[4] = dot(plane.xyz, in_position) - plane.w;      // nothing in or behind the base plane is drawn
    vec2 scale = 0.5 * (rect.zw - rect.xy);
    vec2 offset = 0.5 * (rect.zw + rect.xy);
    gl_Position = vec4(c.xy * scale + offset * c.w, c.z, c.w);
}
"""
MAX_ATLAS = 4096      # pixels on a side of the item-buffer atlas


class ItemBufferRenderer:
    """The scene's triangles on the GPU, and a batch of hemicubes drawn into an R32UI atlas, read back once.

    ``cull``: each face is drawn on its own, with only the patches whose bounding spheres reach into its
    frustum (and above the shooter's plane), tested on the CPU against the planes of projection · view;
    otherwise every face is one instance of a single draw of the whole scene. A face sees a fifth of what
    lies in front of the shooter at most, so culling draws a small part of the triangles for the same
    item buffers: what is culled lies wholly outside the clip volume, where the GPU would discard it.
    That holds for shaders that place vertices with ``hemicube_projection() * hemicube_view()``, as the
    reference's do; a submission's shaders (stage 3) are drawn unculled, so they are judged on what they draw.
    """

    def __init__(self, quads: np.ndarray, shaders: tuple[str, str], resolution: int, projections: np.ndarray,
                 batch: int, ctx: Any = None, cull: bool = False):
        from ..gl import compile_program, create_context
        self.resolution = r = int(resolution)
        self.ctx = ctx = ctx or create_context()
        vs, fs = shaders
        for name, src in (("vertex", vs), ("fragment", fs)):
            if "#version" in src:
                raise KitError(f"H4 item_buffer_shaders(): the {name} shader must not have a #version line (the kit adds it)")
        self.program = compile_program(ctx, "H4", (VERTEX_INTERFACE + "#define main item_main\n", vs, _VERTEX_ENGINE),
                                       (FRAGMENT_INTERFACE, fs, ""))
        tris, ids = patch_triangles(quads)
        self.n_triangles = len(tris)
        self.origin = quads.reshape(-1, 3).mean(axis=0)   # draw relative to the scene's middle: float32 keeps precision
        positions = (tris - self.origin).astype("f4").reshape(-1, 3)
        vbo = ctx.buffer(positions.tobytes())
        ibo = ctx.buffer(np.repeat(ids, 3).astype("u4").tobytes())
        attrs = [(vbo, "3f", "in_position")] if "in_position" in self.program else []
        if "in_id" in self.program:
            attrs.append((ibo, "u", "in_id"))
        if not attrs:
            raise KitError("H4: the vertex shader uses neither in_position nor in_id")
        self.vao = ctx.vertex_array(self.program, attrs)
        self.cull = bool(cull)
        if self.cull:
            self.indices = ctx.buffer(reserve=4 * 6 * len(quads))      # grows to what a batch's faces draw
            self.vao_culled = ctx.vertex_array(self.program, attrs, index_buffer=self.indices, index_element_size=4)
            self.centers = quads.mean(axis=1)
            self.radii = np.linalg.norm(quads - self.centers[:, None, :], axis=2).max(axis=1)
            # the culling test's operands, float32: centres as homogeneous columns, radii padded by rounding
            self._spheres = np.vstack([self.centers.T, np.ones(len(quads))]).astype(np.float32)
            reach = float(np.abs(self.centers).max() + self.radii.max())
            self._padded = (self.radii * (1 + 1e-5) + 1e-5 * reach).astype(np.float32)
        #: triangles drawn and triangles a draw of the whole scene per face would have drawn (culling's saving)
        self.triangles = {"drawn": 0, "scene_per_face": 0}
        if "u_face_base" in self.program:
            self.program["u_face_base"].value = 0
        proj = np.asarray(projections, dtype=np.float64)
        self.projections = proj
        if "u_projections" in self.program:
            self.program["u_projections"].write(np.ascontiguousarray(proj.transpose(0, 2, 1)).astype("f4").tobytes())
        # atlas: each hemicube is a tile r wide and 3r high (top r×r, then four sides r/2 high)
        self.cols = max(1, min(batch, MAX_ATLAS // r))
        self.rows_of_tiles = max(1, min(-(-batch // self.cols), max(1, MAX_ATLAS // (3 * r))))
        self.batch = self.cols * self.rows_of_tiles
        size = (self.cols * r, self.rows_of_tiles * 3 * r)
        self.atlas = ctx.texture(size, 1, dtype="u4")
        self.depth = ctx.depth_texture(size)
        self.fbo = ctx.framebuffer([self.atlas], self.depth)
        self.faces = ctx.texture((6, 5 * self.batch), 4, dtype="f4")
        #: geometry closer to a shooter's plane than this is not drawn: float32 cannot place it on either side
        self.plane_eps = 1e-6 * float(np.linalg.norm(np.ptp(quads.reshape(-1, 3), axis=0)))
        self.faces.filter = (ctx.NEAREST, ctx.NEAREST)
        self.size = size

    def _rects(self, count: int) -> np.ndarray:
        """Tile rectangles (count·5, 4) in the atlas's NDC: x0, y0, x1, y1."""
        r = self.resolution
        W, Hh = self.size
        out = np.zeros((count, 5, 4))
        for b in range(count):
            col, row = b % self.cols, b // self.cols
            x0, y0 = col * r, row * 3 * r
            boxes = [(x0, y0, x0 + r, y0 + r)] + [(x0, y0 + r + k * r // 2, x0 + r, y0 + r + (k + 1) * r // 2) for k in range(4)]
            for f, (a, b_, c, d) in enumerate(boxes):
                out[b, f] = (2 * a / W - 1, 2 * b_ / Hh - 1, 2 * c / W - 1, 2 * d / Hh - 1)
        return out.reshape(-1, 4)

    def visible_patches(self, views: np.ndarray, normals: np.ndarray, offsets: np.ndarray) -> np.ndarray:
        """(B·5, n) bool: whether patch j's bounding sphere reaches into face f's clip volume and above its
        shooter's base plane (n·x > offset). A patch outside one of those half-spaces draws nothing there.

        The six planes of each face are normalised once and tested against every patch in one float32 matrix
        product (faces·6 × 4 by 4 × n); each sphere is padded by a float32 rounding's worth so that nothing
        that could draw a pixel is dropped (drawing too much changes no pixel: the clipper discards it)."""
        count = len(views)
        kinds = np.where(np.arange(5) == 0, 0, 1)                                  # top, then four sides
        clip = (self.projections[kinds][None] @ views).reshape(-1, 4, 4)           # world to clip, per face
        w = clip[:, 3:4, :]
        planes = np.concatenate([w + clip[:, :3, :], w - clip[:, :3, :]], axis=1)   # -w <= x, y, z <= w
        planes /= np.maximum(np.linalg.norm(planes[:, :, :3], axis=2, keepdims=True), 1e-300)
        dist = planes.reshape(-1, 4).astype(np.float32) @ self._spheres         # (faces·6, n)
        inside = (dist.reshape(len(clip), 6, -1) > -self._padded).all(axis=1)
        above = normals @ self.centers.T - offsets[:, None] > -self.radii            # (B, n)
        return inside & np.repeat(above, 5, axis=0)[: count * 5]

    def _draw_culled(self, views: np.ndarray, normals: np.ndarray, offsets: np.ndarray) -> None:
        """One draw per face of a batch, of the patches that can land in it (:meth:`visible_patches`)."""
        visible = self.visible_patches(views, normals, offsets)
        counts = visible.sum(axis=1)
        patches = np.flatnonzero(visible) % visible.shape[1]                        # face-major, ascending per face
        indices = (6 * patches[:, None] + np.arange(6)).astype("u4").ravel()
        if indices.nbytes > self.indices.size:
            self.indices.orphan(indices.nbytes)
        if len(indices):
            self.indices.write(indices.tobytes())
        first = 0
        for f, k in enumerate(counts):
            if k:
                self.program["u_face_base"].value = f
                self.vao_culled.render(vertices=6 * int(k), first=first)
                first += 6 * int(k)
        self.program["u_face_base"].value = 0
        self.triangles["drawn"] += 2 * int(counts.sum())

    def render(self, views: np.ndarray, planes: np.ndarray | None = None) -> list[tuple[np.ndarray, np.ndarray]]:
        """Item buffers of a batch in this renderer's own GL context, whichever context was made current since."""
        from ..gl import make_current
        make_current(self.ctx)
        return self._render(views, planes)

    def _render(self, views: np.ndarray, planes: np.ndarray | None = None) -> list[tuple[np.ndarray, np.ndarray]]:
        """Item buffers of a batch: views (B, 5, 4, 4) world-to-eye -> [(top (r, r), sides (4, r/2, r))] per hemicube.

        ``planes`` (B, 4): each shooter's base plane (unit normal, n·centre); geometry not above it
        (by a hair) is clipped away. By default the plane is the top view's eye and view direction.
        """
        ctx, r = self.ctx, self.resolution
        count = len(views)
        assert count <= self.batch
        shift = np.eye(4)
        shift[:3, 3] = self.origin                  # the VBO holds positions minus origin
        data = np.zeros((count * 5, 6, 4), dtype="f4")
        mats = (views @ shift).reshape(-1, 4, 4)
        data[:, :4, :] = mats.transpose(0, 2, 1)    # columns of each matrix
        data[:, 4, :] = self._rects(count)
        if planes is None:
            rot, trans = views[:, 0, :3, :3], views[:, 0, :3, 3]
            normal = -rot[:, 2]                                     # the top face looks along the normal
            eye = -np.einsum("bji,bj->bi", rot, trans)              # eye = -R^T t
            planes = np.concatenate([normal, np.einsum("bi,bi->b", normal, eye)[:, None]], axis=1)
        planes = np.asarray(planes, dtype=np.float64)
        local = planes[:, 3] - planes[:, :3] @ self.origin + self.plane_eps
        data[:, 5, :3] = np.repeat(planes[:, :3], 5, axis=0)
        data[:, 5, 3] = np.repeat(local, 5)
        self.faces.write(np.ascontiguousarray(data).tobytes(), viewport=(0, 0, 6, count * 5))
        self.faces.use(location=0)
        if "u_faces" in self.program:
            self.program["u_faces"].value = 0
        self.fbo.use()
        ctx.viewport = (0, 0, *self.size)
        ctx.enable(ctx.DEPTH_TEST)
        ctx.disable(ctx.CULL_FACE)
        for i in range(5):
            ctx.enable_direct(0x3000 + i)           # GL_CLIP_DISTANCE0..4
        used_rows = -(-count // self.cols)
        h = used_rows * 3 * r
        self.fbo.clear(0, 0, 0, 0, depth=1.0, viewport=(0, 0, self.size[0], h))
        triangles = self.n_triangles
        self.triangles["scene_per_face"] += count * 5 * triangles
        if self.cull:
            self._draw_culled(views, planes[:, :3], planes[:, 3] + self.plane_eps)
        else:
            self.vao.render(instances=count * 5)
            self.triangles["drawn"] += count * 5 * triangles
        raw = self.fbo.read(viewport=(0, 0, self.size[0], h), components=1, dtype="u4")
        atlas = np.frombuffer(raw, dtype=np.uint32).reshape(h, self.size[0])
        out = []
        for b in range(count):
            col, row = b % self.cols, b // self.cols
            tile = atlas[row * 3 * r:(row + 1) * 3 * r, col * r:(col + 1) * r]
            out.append((tile[:r].copy(), tile[r:].reshape(4, r // 2, r).copy()))   # writable, for the student's H5
        for i in range(5):
            ctx.disable_direct(0x3000 + i)
        return out
