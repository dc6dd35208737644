"""The item-buffer atlas: every face of a batch of hemicubes in one instanced draw, read back once.

The scene's triangles go to the GPU once. Each hemicube face of a batch is one instance of
a single draw, placed into its tile of one R32UI atlas; clip distances keep it inside the
tile and cut away everything in or behind the shooter's plane. The student's H4 shaders
run inside a fixed interface (below): the kit defines the view and projection of the
instance, and moves the result into its tile.
"""
from __future__ import annotations

import time
from typing import Any

import numpy as np

from ..errors import KitError
from ..patches import as_quads
from .grids import GRID_FRAGMENT, GRID_VERTEX, Grids

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
#: Placement into the atlas tile, shared by both ways of drawing (below): clip to the tile and above the base plane.
_PLACE = """
void place(vec4 rect, vec4 plane) {
    item_main();
    vec4 c = gl_Position;
    gl_ClipDistance[0] = c.w + c.x;
    gl_ClipDistance[1] = c.w - c.x;
    gl_ClipDistance[2] = c.w + c.y;
    gl_ClipDistance[3] = c.w - c.y;
    gl_ClipDistance[4] = dot(plane.xyz, in_position) - plane.w;      // nothing in or behind the base plane is drawn
    vec2 scale = 0.5 * (rect.zw - rect.xy);                            // rect: x0, y0, x1, y1 in the atlas's NDC
    vec2 offset = 0.5 * (rect.zw + rect.xy);
    gl_Position = vec4(c.xy * scale + offset * c.w, c.z, c.w);
}
"""
#: After the student's vertex shader, for one instanced draw of a whole batch: each instance is a face, its
#: matrices, tile and base plane fetched from a texture (columns 0-3 the view, 4 the tile, 5 the plane).
_VERTEX_INSTANCED = """
#undef main
uniform sampler2D u_faces;
uniform mat4 u_projections[2];      // top, side
out float gl_ClipDistance[5];
mat4 hemicube_view() {
    int f = gl_InstanceID;
    return mat4(texelFetch(u_faces, ivec2(0, f), 0), texelFetch(u_faces, ivec2(1, f), 0),
                texelFetch(u_faces, ivec2(2, f), 0), texelFetch(u_faces, ivec2(3, f), 0));
}
mat4 hemicube_projection() { return u_projections[(gl_InstanceID % 5) == 0 ? 0 : 1]; }
""" + _PLACE + """
void main() { place(texelFetch(u_faces, ivec2(4, gl_InstanceID), 0), texelFetch(u_faces, ivec2(5, gl_InstanceID), 0)); }
"""
#: The same for a face drawn on its own (culling): its matrices, tile and plane are uniforms, set per draw.
_VERTEX_ONE_FACE = """
#undef main
uniform mat4 u_view;
uniform mat4 u_projection;
uniform vec4 u_rect;
uniform vec4 u_plane;
out float gl_ClipDistance[5];
mat4 hemicube_view() { return u_view; }
mat4 hemicube_projection() { return u_projection; }
""" + _PLACE + """
void main() { place(u_rect, u_plane); }
"""
#: a patch's two triangles as indices into its four corners: the triangles of :func:`cs451.patches.patch_triangles`,
#: corners in the same order, so the same pixels. Indexed, the rasteriser shades each corner once, not six
#: vertices a patch: llvmpipe's draw calls, which shade, clip and bin on the calling thread, took a quarter less
#: time for the room's matrix (2.6-3.0 s against 3.4-4.2 s) and the matrix came out bit for bit the same
CORNER_INDICES = np.array([0, 1, 2, 0, 2, 3], dtype=np.uint32)
MAX_ATLAS = 4096      # pixels on a side of the item-buffer atlas, at most
#: bytes an atlas pixel costs: two atlases (R32UI items and 32-bit depth: one drawn while the other is summed),
#: and the read-back buffer
BYTES_PER_PIXEL = 2 * (4 + 4) + 4
#: what the atlases may take in all, before the batch is rounded up to whole rows of tiles: 51 hemicubes fit at
#: resolution 128 and the grid of 32 columns makes it 64 (63 MB); 12 at 256 (48 MB). Batches of 256 at 128 drew
#: the room's matrix no faster and took 500 MB more (llvmpipe's atlases are host memory)
ATLAS_BYTES = 48 << 20
FLUSH_FACES = 40      # faces binned before a software rasteriser is handed them (8 hemicubes, 40,000 triangles)
BLAS_ONE_THREAD = 1 << 18   # OpenBLAS runs a product of fewer multiply-adds (m·n·k) on the calling thread


class ItemBufferRenderer:
    """The scene's triangles on the GPU, and a batch of hemicubes drawn into an R32UI atlas, read back once.

    ``cull``: each face is drawn on its own, with only the patches whose bounding spheres reach into its
    frustum (and above the shooter's plane), tested on the CPU against the planes of projection · view;
    otherwise every face is one instance of a single draw of the whole scene. A face sees a fifth of what
    lies in front of the shooter at most, so culling draws a small part of the triangles for the same
    item buffers: what is culled lies wholly outside the clip volume, where the GPU would discard it.
    That holds for shaders that place vertices with ``hemicube_projection() * hemicube_view()``, as the
    reference's do; a submission's shaders (stage 3) are drawn unculled, so they are judged on what they draw.

    ``grids`` (:mod:`.grids`): draw each grid of patches as one quad with the kit's grid shaders instead of
    every patch with H4's (culled, or not, a grid at a time): a few triangles a face instead of a thousand.
    """

    def __init__(self, quads: np.ndarray, shaders: tuple[str, str], resolution: int, projections: np.ndarray,
                 batch: int, ctx: Any = None, cull: bool = False, grids: Grids | None = None):
        from ..gl import compile_program, create_context
        self.resolution = r = int(resolution)
        self.ctx = ctx = ctx or create_context()
        vs, fs = shaders if grids is None else (GRID_VERTEX, GRID_FRAGMENT)
        for name, src in (("vertex", vs), ("fragment", fs)):
            if "#version" in src:
                raise KitError(f"H4 item_buffer_shaders(): the {name} shader must not have a #version line (the kit adds it)")
        self.cull = bool(cull)
        front = VERTEX_INTERFACE + "#define main item_main\n"
        # culling draws each face on its own: the face's data are uniforms, not texels fetched per vertex
        self.program = compile_program(ctx, "H4" if grids is None else "the kit's grid shaders",
                                       (front, vs, _VERTEX_ONE_FACE if self.cull else _VERTEX_INSTANCED),
                                       (FRAGMENT_INTERFACE, fs, ""))
        quads = as_quads(quads)
        self.origin = quads.reshape(-1, 3).mean(axis=0)   # draw relative to the scene's middle: float32 keeps precision
        corners = quads if grids is None else grids.corners     # what is drawn: patches, or grids of them
        n = len(corners)
        self.n_triangles = 2 * n
        # each quad's four corners once, its two triangles indexed (see CORNER_INDICES)
        vbo = ctx.buffer((corners - self.origin).astype("f4").tobytes())
        attrs = [(vbo, "3f", "in_position")] if "in_position" in self.program else []
        if grids is not None:
            attrs += _grid_attributes(ctx, self.program, grids)
        elif "in_id" in self.program:
            attrs.append((ctx.buffer(np.repeat(np.arange(n), 4).astype("u4").tobytes()), "u", "in_id"))
        if not attrs:
            raise KitError("H4: the vertex shader uses neither in_position nor in_id")
        if self.cull:
            self.indices = ctx.buffer(reserve=4 * 6 * n)               # grows to what a batch's faces draw
            self.vao = ctx.vertex_array(self.program, attrs, index_buffer=self.indices, index_element_size=4)
            self.centers = corners.mean(axis=1)
            self.radii = np.linalg.norm(corners - self.centers[:, None, :], axis=2).max(axis=1)
            # the culling test's operands, float32: centres as homogeneous columns, radii padded by rounding
            self._spheres = np.vstack([self.centers.T, np.ones(n)]).astype(np.float32)
            reach = float(np.abs(self.centers).max() + self.radii.max())
            self._padded = (self.radii * (1 + 1e-5) + 1e-5 * reach).astype(np.float32)
        else:
            every = ctx.buffer(patch_indices(np.arange(n)).tobytes())
            self.vao = ctx.vertex_array(self.program, attrs, index_buffer=every, index_element_size=4)
        #: triangles drawn and triangles a draw of the whole scene per face would have drawn (culling's saving)
        self.triangles = {"drawn": 0, "scene_per_face": 0}
        #: seconds spent drawing (culling and the draw calls) and reading the atlas back (with any wait for the
        #: rasteriser still at work on it: a software rasteriser draws in threads after the calls return)
        self.seconds = {"draw": 0.0, "readback": 0.0}
        proj = np.asarray(projections, dtype=np.float64)
        self.projections = proj
        self._projections32 = np.ascontiguousarray(proj.transpose(0, 2, 1)).astype("f4")   # column-major, per kind
        if "u_projections" in self.program:
            self.program["u_projections"].write(self._projections32.tobytes())
        # atlas: each hemicube is a tile r wide and 3r high (top r×r, then four sides r/2 high)
        side = atlas_side(ctx)
        if side < 3 * r:
            raise KitError(f"a hemicube of resolution {r} needs a {r} × {3 * r} atlas tile, over this GL's limit of {side}")
        batch = max(1, min(int(batch), ATLAS_BYTES // (3 * r * r * BYTES_PER_PIXEL)))   # within the memory budget
        self.cols = max(1, min(batch, side // r))
        self.rows_of_tiles = max(1, min(-(-batch // self.cols), side // (3 * r)))
        self.batch = self.cols * self.rows_of_tiles
        size = (self.cols * r, self.rows_of_tiles * 3 * r)
        # an atlas per batch in flight: a second is made only when a batch is drawn while the last is summed
        self.fbos: list = [None, None]
        self._next = 0
        self._pending: set[int] = set()
        self._parking: Any = None
        self.faces = ctx.texture((6, 5 * self.batch), 4, dtype="f4")
        #: geometry closer to a shooter's plane than this is not drawn: float32 cannot place it on either side
        self.plane_eps = 1e-6 * float(np.linalg.norm(np.ptp(quads.reshape(-1, 3), axis=0)))
        self.faces.filter = (ctx.NEAREST, ctx.NEAREST)
        self.size = size
        self._pixels = np.empty((size[1], size[0]), dtype=np.uint32)    # the read-back, reused by every batch

    def _rects(self, count: int) -> np.ndarray:
        """Tile rectangles (count·5, 4) in the atlas's NDC: x0, y0, x1, y1."""
        r = self.resolution
        W, H = self.size
        b = np.arange(count)
        x0, y0 = (b % self.cols) * r, (b // self.cols) * 3 * r
        out = np.zeros((count, 5, 4))
        out[:, :, 0], out[:, :, 2] = x0[:, None], x0[:, None] + r
        out[:, 0, 1], out[:, 0, 3] = y0, y0 + r
        out[:, 1:, 1] = y0[:, None] + r + np.arange(4) * (r // 2)
        out[:, 1:, 3] = out[:, 1:, 1] + r // 2
        out[..., 0::2] = 2 * out[..., 0::2] / W - 1
        out[..., 1::2] = 2 * out[..., 1::2] / H - 1
        return out.reshape(-1, 4)

    def visible_patches(self, views: np.ndarray, normals: np.ndarray, offsets: np.ndarray) -> np.ndarray:
        """(B·5, n) bool: whether patch j's bounding sphere reaches into face f's clip volume and above its
        shooter's base plane (n·x > offset). A patch outside one of those half-spaces draws nothing there.

        The six planes of each face are normalised once and tested against every patch by float32 products
        (faces·6 × 4 by 4 × n) in slices small enough that BLAS runs them on this thread (:func:`one_thread_product`);
        each sphere is padded by a float32 rounding's worth so that nothing that could draw a pixel is dropped
        (drawing too much changes no pixel: the clipper discards it)."""
        count = len(views)
        kinds = np.where(np.arange(5) == 0, 0, 1)                                  # top, then four sides
        clip = np.einsum("kij,bkjl->bkil", self.projections[kinds], views).reshape(-1, 4, 4)   # world to clip, per face
        w = clip[:, 3:4, :]
        planes = np.concatenate([w + clip[:, :3, :], w - clip[:, :3, :]], axis=1)   # -w <= x, y, z <= w
        planes /= np.maximum(np.linalg.norm(planes[:, :, :3], axis=2, keepdims=True), 1e-300)
        planes32 = planes.reshape(-1, 4).astype(np.float32)
        inside = np.empty((len(clip), self._spheres.shape[1]), dtype=bool)
        step = max(1, BLAS_ONE_THREAD // (24 * self._spheres.shape[1]))               # faces per slice
        for start in range(0, len(clip), step):                                     # a slice at a time: small
            dist = planes32[6 * start:6 * (start + step)] @ self._spheres             # (faces·6, n), on one thread
            inside[start:start + step] = (dist.reshape(-1, 6, dist.shape[1]) > -self._padded).all(axis=1)
        above = one_thread_product(normals, self.centers.T) - offsets[:, None] > -self.radii     # (B, n)
        return inside & np.repeat(above, 5, axis=0)[: count * 5]

    def _draw_culled(self, data: np.ndarray, normals: np.ndarray, offsets: np.ndarray, views: np.ndarray,
                     target: Any) -> None:
        """One draw per face of a batch, of the patches that can land in it (:meth:`visible_patches`)."""
        visible = self.visible_patches(views, normals, offsets)
        counts = visible.sum(axis=1)
        patches = np.flatnonzero(visible) % visible.shape[1]                        # face-major, ascending per face
        indices = patch_indices(patches)
        if indices.nbytes > self.indices.size:
            self.indices.orphan(indices.nbytes)
        if len(indices):
            self.indices.write(indices.tobytes())
        uniforms = [self.program.get(name, None) for name in ("u_view", "u_projection", "u_rect", "u_plane")]
        view_u, projection_u, rect_u, plane_u = uniforms
        first = 0
        for f, k in enumerate(counts.tolist()):
            if k:
                for uniform, value in ((view_u, data[f, :4]), (projection_u, self._projections32[0 if f % 5 == 0 else 1]),
                                       (rect_u, data[f, 4]), (plane_u, data[f, 5])):
                    if uniform is not None:
                        uniform.write(value.tobytes())
                self.vao.render(vertices=6 * k, first=first)
                first += 6 * k
            if f % FLUSH_FACES == FLUSH_FACES - 1:       # bounded binning memory (see _flush)
                self._flush()
                target.use()
        self.triangles["drawn"] += 2 * int(counts.sum())

    def render(self, views: np.ndarray, planes: np.ndarray | None = None) -> list[tuple[np.ndarray, np.ndarray]]:
        """Item buffers of a batch: views (B, 5, 4, 4) world-to-eye -> [(top (r, r), sides (4, r/2, r))] per hemicube,
        drawn in this renderer's own GL context, whichever context was made current since.

        ``planes`` (B, 4): each shooter's base plane (unit normal, n·centre); geometry not above it
        (by a hair) is clipped away. By default the plane is the top view's eye and view direction.
        """
        atlas = self.draw(views, planes)
        r, out = self.resolution, []
        for b in range(len(views)):
            col, row = b % self.cols, b // self.cols
            tile = atlas[row * 3 * r:(row + 1) * 3 * r, col * r:(col + 1) * r]
            out.append((tile[:r].copy(), tile[r:].reshape(4, r // 2, r).copy()))   # writable, for the student's H5
        return out

    def draw(self, views: np.ndarray, planes: np.ndarray | None = None) -> np.ndarray:
        """Draw a batch (as :meth:`render`) and return the atlas rows it uses, (tile rows · 3r, cols · r) uint32:
        hemicube b's tile is at tile row b // cols, column b % cols. A view of a buffer the next read overwrites."""
        return self.collect(self.submit(views, planes))

    def submit(self, views: np.ndarray, planes: np.ndarray | None = None) -> tuple[int, int]:
        """Issue a batch's draw calls into the next of the two atlases and return its ticket for :meth:`collect`
        without waiting: the GL may still be drawing it while the caller sums the batch before."""
        from ..gl import make_current
        make_current(self.ctx)
        start = time.perf_counter()
        ctx, r = self.ctx, self.resolution
        count = len(views)
        if not 0 < count <= self.batch:
            raise KitError(f"a batch holds 1 .. {self.batch} hemicubes, got {count}")
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
        slot = self._next if self._next not in self._pending else 1 - self._next
        self._next = 1 - slot
        if self.fbos[slot] is None:
            self.fbos[slot] = ctx.framebuffer([ctx.texture(self.size, 1, dtype="u4")], ctx.depth_texture(self.size))
        fbo = self.fbos[slot]
        self._pending.add(slot)
        fbo.use()
        ctx.viewport = (0, 0, *self.size)
        ctx.enable(ctx.DEPTH_TEST)
        ctx.disable(ctx.CULL_FACE)
        for i in range(5):
            ctx.enable_direct(0x3000 + i)           # GL_CLIP_DISTANCE0..4
        h = -(-count // self.cols) * 3 * r
        fbo.clear(0, 0, 0, 0, depth=1.0, viewport=(0, 0, self.size[0], h))
        self.triangles["scene_per_face"] += count * 5 * self.n_triangles
        if self.cull:
            self._draw_culled(data, planes[:, :3], planes[:, 3] + self.plane_eps, views, fbo)
        else:
            self.faces.write(np.ascontiguousarray(data).tobytes(), viewport=(0, 0, 6, count * 5))
            self.faces.use(location=0)
            if "u_faces" in self.program:
                self.program["u_faces"].value = 0
            self.vao.render(instances=count * 5)
            self.triangles["drawn"] += count * 5 * self.n_triangles
        for i in range(5):
            ctx.disable_direct(0x3000 + i)
        self._flush()
        self.seconds["draw"] += time.perf_counter() - start
        return slot, h

    def _flush(self) -> None:
        """Hand the batch drawn so far to the rasteriser without waiting for it.

        moderngl has no glFlush; clearing another framebuffer (a 1 × 1 one kept for this) makes llvmpipe close
        its scene and rasterise it in its threads while this thread goes on (culling the next batch, summing
        the last). Done every ``FLUSH_FACES`` faces too: llvmpipe keeps every triangle binned until its scene
        closes, about 300 bytes each, 100 MB for a batch of 64 hemicubes at 128 (measured: a batch's peak fell
        from 251 to 224 MB). A GPU driver sends its commands on its own."""
        if self._parking is None:
            self._parking = self.ctx.framebuffer(self.ctx.renderbuffer((1, 1), 1, dtype="u1"))
        self._parking.use()
        self._parking.clear()       # something must be done with it: the GL applies a binding at the next draw or clear

    def texture(self, ticket: tuple[int, int]) -> Any:
        """The R32UI atlas texture of a submitted batch, for a reduction on the device (which collects it)."""
        self._pending.discard(ticket[0])
        return self.fbos[ticket[0]].color_attachments[0]

    def collect(self, ticket: tuple[int, int]) -> np.ndarray:
        """The pixels of a submitted batch (see :meth:`draw`), once the GL has drawn them."""
        from ..gl import make_current
        make_current(self.ctx)
        start = time.perf_counter()
        slot, h = ticket
        self._pending.discard(slot)
        pixels = self._pixels[:h]
        self.fbos[slot].read_into(pixels, viewport=(0, 0, self.size[0], h), components=1, dtype="u4")
        self.seconds["readback"] += time.perf_counter() - start
        return pixels


def patch_indices(patches: np.ndarray) -> np.ndarray:
    """The index buffer that draws ``patches`` (ids, in order) from the corners buffer: six uint32 per patch."""
    return (4 * np.asarray(patches, dtype=np.uint32)[:, None] + CORNER_INDICES).ravel()


def _grid_attributes(ctx: Any, program: Any, grids: Grids) -> list:
    """The grid shaders' inputs besides the positions, four vertices a grid (:data:`.grids.GRID_VERTEX`): a buffer
    each, for those the linked program kept."""
    plane = grids.plane_coordinates()                                                 # (g, 4, 2)
    at_every_vertex = lambda values: np.repeat(values[:, None], 4, axis=1)            # noqa: E731
    inputs = {"in_local": (plane.astype("f4"), "2f"),
              **{name: (at_every_vertex(plane[:, k]).astype("f4"), "2f") for k, name in ((1, "in_b"), (2, "in_c"), (3, "in_d"))},
              "in_grid": (at_every_vertex(np.column_stack([grids.first, grids.shape])).astype("u4"), "3u")}
    return [(ctx.buffer(np.ascontiguousarray(values).tobytes()), layout, name)
            for name, (values, layout) in inputs.items() if name in program]


def atlas_side(ctx: Any) -> int:
    """Pixels on a side of the atlas: as large as this GL draws and reads (its texture and viewport limits), up to
    ``MAX_ATLAS``, which keeps the read-back buffer (side² · 4 bytes) and the depth buffer at 64 MB each."""
    limits = [MAX_ATLAS]
    for name in ("GL_MAX_TEXTURE_SIZE", "GL_MAX_RENDERBUFFER_SIZE"):
        value = ctx.info.get(name)
        if isinstance(value, int) and value > 0:
            limits.append(value)
    dims = ctx.info.get("GL_MAX_VIEWPORT_DIMS")
    if isinstance(dims, (tuple, list)) and dims:
        limits.append(int(min(dims)))
    return int(min(limits))


def one_thread_product(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``a @ b`` (m, k) × (k, n) for a short k, in slices of rows small enough that BLAS keeps each on one thread.

    OpenBLAS splits a product of m·n·k over 2^18 across threads, whose workers then spin for a while waiting
    for more; beside a software rasteriser on two cores that spinning took a sixth of a full matrix's CPU time.
    In slices under that size the same product ran 3.6× faster here (2.8 ms against 10 for the culling of a
    batch: 7,680 planes by 2,408 patches)."""
    m, n = a.shape[0], b.shape[1]
    step = max(1, BLAS_ONE_THREAD // max(1, n * a.shape[1]))
    if step >= m:
        return a @ b
    out = np.empty((m, n), dtype=np.result_type(a, b))
    for start in range(0, m, step):
        np.matmul(a[start:start + step], b, out=out[start:start + step])
    return out
