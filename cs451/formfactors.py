"""The form-factor engine (hemicubes on the rasteriser, and Monte Carlo ray casting); relied on by stage 3's grader, render and bench and by stage 4 (radiosity).

``HemicubeFormFactors(quads, impl)`` computes rows F_i· of the form-factor
matrix of planar patches (``cs451.patches``: (n, 4, 3) quads, counter-clockwise
seen from the front) with the hemicube of Cohen & Greenberg (1985). It holds no
solution: the delta form-factor tables, the five views, the projections, the
item-buffer shaders, the row sum and the point-to-polygon form factor all come
from ``impl``, a loaded stage-3 implementation (the reference or a student's).

How it is fast: the scene's triangles go to the GPU once; every hemicube face
of a batch of patches is one *instance* of a single instanced draw, placed into
its tile of one R32UI atlas (clip distances keep it inside the tile), so a batch
of hundreds of hemicubes costs one draw call and one read-back; each tile is
summed with ``np.bincount`` (the student's H5). Rows are computed only when asked
and cached; only geometry enters, so changing colours, albedos or emission
reuses every row. Patches behind or in a shooter's plane are counted as culled
(the clipper discards them); a patch seen from behind hides what is behind it and
receives nothing (H4).

Proximity: the hemicube treats the shooter as a point at its centre, an error
no resolution fixes when another patch is close to it. With ``proximity="contour"``
the form factor to every close patch j is replaced by the area average over the
shooter (Gauss points) of the exact point-to-polygon form factor (H6, Lambert's
contour formula) times the fraction of j that the hemicube found visible. With
``shooter_split=k`` each row averages k × k hemicubes spread over the shooter.
"""
from __future__ import annotations

import time
from typing import Any, Iterable

import numpy as np

from .errors import KitError
from .patches import as_quads, patch_areas, patch_centers, patch_normals, patch_triangles
from .stages import hemicube as H

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
out float gl_ClipDistance[5];
mat4 hemicube_view() {
    return mat4(texelFetch(u_faces, ivec2(0, gl_InstanceID), 0), texelFetch(u_faces, ivec2(1, gl_InstanceID), 0),
                texelFetch(u_faces, ivec2(2, gl_InstanceID), 0), texelFetch(u_faces, ivec2(3, gl_InstanceID), 0));
}
mat4 hemicube_projection() { return u_projections[(gl_InstanceID % 5) == 0 ? 0 : 1]; }
void main() {
    item_main();
    vec4 c = gl_Position;
    vec4 rect = texelFetch(u_faces, ivec2(4, gl_InstanceID), 0);   // x0, y0, x1, y1 in the atlas's NDC
    gl_ClipDistance[0] = c.w + c.x;
    gl_ClipDistance[1] = c.w - c.x;
    gl_ClipDistance[2] = c.w + c.y;
    gl_ClipDistance[3] = c.w - c.y;
    vec4 plane = texelFetch(u_faces, ivec2(5, gl_InstanceID), 0);  // the shooter's plane, raised by a hair
    gl_ClipDistance[4] = dot(plane.xyz, in_position) - plane.w;      // nothing in or behind the base plane is drawn
    vec2 scale = 0.5 * (rect.zw - rect.xy);
    vec2 offset = 0.5 * (rect.zw + rect.xy);
    gl_Position = vec4(c.xy * scale + offset * c.w, c.z, c.w);
}
"""
MAX_ATLAS = 4096      # pixels on a side of the item-buffer atlas
BLIND_ROW_SUM = 0.05  # a row summing to less sees (almost) nothing: with resample_blind, look again from over the patch
PROXIMITY_GAUSS = 5   # Gauss-Legendre points per side of the shooter for close pairs (C-14, 1 × 0.5 to 1 × 2: 0.07%)


def default_up(normal: np.ndarray) -> np.ndarray:
    """A unit vector perpendicular to ``normal``: the cross product with the least aligned coordinate axis."""
    axis = np.zeros(3)
    axis[int(np.argmin(np.abs(normal)))] = 1.0
    u = np.cross(normal, axis)
    return u / np.linalg.norm(u)


def hemicube_up(normal: np.ndarray, index: int, rotate: bool, seed: int) -> np.ndarray:
    """The hemicube's up vector for patch ``index``: seeded per patch, so a row never depends on the batch it was in."""
    u = default_up(normal)
    if not rotate:
        return u
    angle = np.random.default_rng([int(seed), int(index)]).uniform(0.0, 2 * np.pi)
    return np.cos(angle) * u + np.sin(angle) * np.cross(normal, u)


def default_near_far(quads: np.ndarray) -> tuple[float, float]:
    """Near = 1e-3 of the scene's diagonal, far = 2 diagonals.

    Geometry closer than ``near`` is clipped away (the near-plane error), so near wants to be
    small; but a 24-bit depth buffer resolves depths about z²/(near·2²⁴) apart, so near must not
    be too small either. At 1e-5 of the diagonal, the Cornell box's light, 0.1 mm below the
    ceiling, lost the depth test to the ceiling behind it from every floor patch (F to the
    light came out 0). At 1e-3, surfaces 0.06 mm apart a diagonal away are still told apart.
    """
    diag = float(np.linalg.norm(np.ptp(quads.reshape(-1, 3), axis=0)))
    return 1e-3 * diag, 2.0 * diag


def hemicube_inputs(quads: np.ndarray, impl: Any, patch: int, rotate: bool = False, seed: int = 0,
                    near: float | None = None) -> tuple[np.ndarray, np.ndarray, float, float]:
    """The views and projections of patch ``patch``'s hemicube as ``impl`` computes them (H2, H3)."""
    q = as_quads(quads)
    n = patch_normals(q)[patch]
    c = patch_centers(q)[patch]
    d_near, far = default_near_far(q)
    near = d_near if near is None else near
    views = H.call_views(impl, c, n, hemicube_up(n, patch, rotate, seed))
    return views, H.call_projections(impl, near, far), near, far


def _sub_quads(quad: np.ndarray, k: int) -> np.ndarray:
    """The k × k bilinear cells of one quad, (k², 4, 3): where a split shooter's hemicubes stand."""
    t = np.linspace(0.0, 1.0, k + 1)
    s_, t_ = (g[:, :, None] for g in np.meshgrid(t, t, indexing="ij"))
    a, b, c, d = quad
    grid = (1 - s_) * (1 - t_) * a + s_ * (1 - t_) * b + s_ * t_ * c + (1 - s_) * t_ * d      # (k+1, k+1, 3)
    return np.stack([grid[:-1, :-1], grid[1:, :-1], grid[1:, 1:], grid[:-1, 1:]], axis=2).reshape(-1, 4, 3)


def clip_polygon_to_plane(polygon: np.ndarray, point: np.ndarray, normal: np.ndarray) -> np.ndarray:
    """The part of a convex polygon (m, 3) with (x - point)·normal >= 0 (Sutherland-Hodgman, one plane)."""
    d = (polygon - point) @ normal
    out = []
    m = len(polygon)
    for k in range(m):
        a, b, da, db = polygon[k], polygon[(k + 1) % m], d[k], d[(k + 1) % m]
        if da >= 0:
            out.append(a)
        if (da >= 0) != (db >= 0):
            t = da / (da - db)
            out.append(a + t * (b - a))
    return np.array(out).reshape(-1, 3)


def gauss_points(quad: np.ndarray, k: int) -> tuple[np.ndarray, np.ndarray]:
    """Gauss-Legendre points (k², 3) on a planar quad's bilinear map and their area weights (summing to its area)."""
    x, w = np.polynomial.legendre.leggauss(k)
    s, ws = 0.5 * (x + 1), 0.5 * w
    S, T = np.meshgrid(s, s, indexing="ij")
    W = np.outer(ws, ws)
    a, b, c, d = quad
    S, T, W = S.ravel()[:, None], T.ravel()[:, None], W.ravel()
    p = (1 - S) * (1 - T) * a + S * (1 - T) * b + S * T * c + (1 - S) * T * d
    ds = (1 - T) * (b - a) + T * (c - d)
    dt = (1 - S) * (d - a) + S * (c - b)
    jac = np.linalg.norm(np.cross(ds, dt), axis=1)
    return p, W * jac


class ItemBufferRenderer:
    """The scene's triangles on the GPU, and one instanced draw of a batch of hemicubes into an R32UI atlas."""

    def __init__(self, quads: np.ndarray, impl: Any, resolution: int, projections: np.ndarray, batch: int,
                 ctx: Any = None):
        from .gl import compile_program, create_context
        self.resolution = r = int(resolution)
        self.ctx = ctx = ctx or create_context()
        vs, fs = H.call_shaders(impl)
        for name, src in (("vertex", vs), ("fragment", fs)):
            if "#version" in src:
                raise KitError(f"H4 item_buffer_shaders(): the {name} shader must not have a #version line (the kit adds it)")
        self.program = compile_program(ctx, "H4", (VERTEX_INTERFACE + "#define main item_main\n", vs, _VERTEX_ENGINE),
                                       (FRAGMENT_INTERFACE, fs, ""))
        tris, ids = patch_triangles(quads)
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
        proj = np.asarray(projections, dtype=np.float64)
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

    def render(self, views: np.ndarray, planes: np.ndarray | None = None) -> list[tuple[np.ndarray, np.ndarray]]:
        """Item buffers of a batch in this renderer's own GL context, whichever context was made current since."""
        from .gl import make_current
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
        self.vao.render(instances=count * 5)
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


class HemicubeFormFactors:
    """Rows of the form-factor matrix of ``quads`` by hemicubes, lazily, cached, many hemicubes per read-back.

    Parameters: ``impl`` a loaded stage-3 implementation; ``resolution`` cells across the
    top face (even); ``near`` the near plane (default 1e-3 of the scene's diagonal);
    ``rotate`` a seeded random rotation of each hemicube about its normal (breaks
    aliasing between the cells and regular geometry); ``proximity`` "contour" (exact
    point-to-polygon form factors averaged over the shooter for close pairs, H6) or
    "none"; ``proximity_distance`` how close is close, in shooter radii (centre to
    farthest corner) between the shooter's centre and the receiver's bounding sphere;
    ``batch`` hemicubes per read-back (capped by the atlas size); ``shooter_split`` k renders
    k × k hemicubes per row, at the centres of the shooter's k × k sub-quads, and averages
    their rows by area (the other answer to the proximity error, and to occluders close to
    the shooter, at k² the cost). ``resample_blind`` k (0: off): a row that sees almost
    nothing from the patch centre (sum under ``BLIND_ROW_SUM``) is looked at again from the
    centres of k × k sub-quads, and the rows of those that see are averaged by area. A patch
    whose centre lies under a box resting on it (a floor patch straddling a block's footprint)
    is lit on its exposed part, and that part must shoot its light; from the centre alone the
    light would vanish.

    ``counters``: hemicubes_rendered (k² per row with a split shooter), rows_computed,
    rows_cached_hits (rows asked for again), patches_culled (summed over rows: patches wholly
    in or behind the shooter's plane, which the base-plane clip discards), patches_backfacing
    (in front of the plane but facing away: drawn, they hide what is behind them, receive 0),
    proximity_pairs (close pairs the contour fix replaced), blind_rows_resampled, readbacks (one per batch).
    ``seconds``: render (draw and read back), sum (H5), proximity (the fix).
    """

    def __init__(self, quads: Any, impl: Any, resolution: int = 128, near: float | None = None, rotate: bool = True,
                 seed: int = 0, proximity: str = "contour", batch: int = 256, proximity_distance: float = 2.0,
                 shooter_split: int = 1, resample_blind: int = 0, ctx: Any = None):
        self.quads = as_quads(quads)
        if len(self.quads) == 0:
            raise KitError("no patches")
        if int(resolution) != resolution or resolution < 2 or resolution % 2:
            raise KitError(f"hemicube resolution must be an even integer >= 2, got {resolution}")
        if proximity not in ("contour", "none"):
            raise KitError(f"proximity must be 'contour' or 'none', got {proximity!r}")
        self.impl = impl
        self.n = len(self.quads)
        self.resolution = int(resolution)
        self.rotate, self.seed, self.proximity = bool(rotate), int(seed), proximity
        self.proximity_distance = float(proximity_distance)
        if int(shooter_split) != shooter_split or shooter_split < 1:
            raise KitError(f"shooter_split must be a positive integer, got {shooter_split}")
        self.shooter_split = int(shooter_split)
        if int(resample_blind) != resample_blind or resample_blind < 0:
            raise KitError(f"resample_blind must be a non-negative integer, got {resample_blind}")
        self.resample_blind = int(resample_blind)
        self.normals = patch_normals(self.quads)
        self.areas = patch_areas(self.quads)
        self.centers = patch_centers(self.quads)
        self.radii = np.linalg.norm(self.quads - self.centers[:, None, :], axis=2).max(axis=1)
        d_near, self.far = default_near_far(self.quads)
        self.near = d_near if near is None else float(near)
        if not 0 < self.near < self.far:
            raise KitError(f"near plane must lie in (0, {self.far:g}), got {self.near}")
        self._batch_request = max(1, min(int(batch), self.n))   # no bigger an atlas than the scene needs
        self._ctx = ctx
        self._renderer: ItemBufferRenderer | None = None
        self._tables: tuple[np.ndarray, np.ndarray] | None = None
        self._rows: dict[int, np.ndarray] = {}
        self.counters = {"hemicubes_rendered": 0, "rows_computed": 0, "rows_cached_hits": 0, "patches_culled": 0,
                         "patches_backfacing": 0, "proximity_pairs": 0, "blind_rows_resampled": 0, "readbacks": 0}
        self.seconds = {"render": 0.0, "sum": 0.0, "proximity": 0.0}

    # -- lazily built GPU state ------------------------------------------------
    @property
    def tables(self) -> tuple[np.ndarray, np.ndarray]:
        if self._tables is None:
            self._tables = H.call_tables(self.impl, self.resolution)
        return self._tables

    @property
    def renderer(self) -> ItemBufferRenderer:
        if self._renderer is None:
            projections = H.call_projections(self.impl, self.near, self.far)
            self._renderer = ItemBufferRenderer(self.quads, self.impl, self.resolution, projections,
                                                self._batch_request, self._ctx)
        return self._renderer

    # -- rows --------------------------------------------------------------------
    def row(self, i: int) -> np.ndarray:
        """Row F_i· (n,): computed on first request, then cached."""
        return self.rows([i])[0]

    def rows(self, indices: Iterable[int]) -> np.ndarray:
        """Rows (k, n) for ``indices``; the missing ones are rendered in batches (many hemicubes per read-back)."""
        idx = [int(i) for i in indices]
        for i in idx:
            if not 0 <= i < self.n:
                raise KitError(f"patch index {i} out of range 0 .. {self.n - 1}")
        missing = list(dict.fromkeys(i for i in idx if i not in self._rows))
        self.counters["rows_cached_hits"] += len(idx) - len(missing)
        if missing:
            step = self.renderer.batch
            for start in range(0, len(missing), step):
                self._compute(missing[start:start + step])
        out = np.zeros((len(idx), self.n))
        for k, i in enumerate(idx):
            out[k] = self._rows[i]
        return out

    def matrix(self) -> np.ndarray:
        """The full matrix F (n, n); F[i, j] is the fraction of the energy leaving i that reaches j."""
        return self.rows(range(self.n))

    def cached(self) -> list[int]:
        """Indices of the rows computed so far."""
        return sorted(self._rows)

    def matches(self, quads: Any) -> bool:
        """Whether ``quads`` is this object's geometry: then every cached row still holds, whatever the
        colours, albedos or emission (form factors depend on geometry only), and the object can be reused."""
        q = np.asarray(quads, dtype=np.float64)
        return q.shape == self.quads.shape and bool(np.array_equal(q, self.quads))

    def views_for(self, i: int, point: np.ndarray | None = None) -> np.ndarray:
        """The five views (H2) of patch i's hemicube, at its centre or at ``point`` on it."""
        return self._views(self.centers[i] if point is None else point, self.normals[i], i)

    def _views(self, eye: np.ndarray, normal: np.ndarray, index: int) -> np.ndarray:
        """The five views (H2) of a hemicube at ``eye`` facing ``normal``, turned by hemicube ``index``'s seeded rotation."""
        return H.call_views(self.impl, eye, normal, hemicube_up(normal, index, self.rotate, self.seed))

    def shooter_points(self, i: int, split: int | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Where patch i's hemicubes stand: its centre, or with ``shooter_split`` k (or ``split``) the centres of
        its k × k bilinear sub-quads, with their area weights (summing to 1)."""
        split = self.shooter_split if split is None else split
        if split == 1:
            return self.centers[i][None], np.ones(1)
        sub = _sub_quads(self.quads[i], split)
        areas = patch_areas(sub)
        return patch_centers(sub), areas / areas.sum()

    def item_buffers(self, indices: Iterable[int]) -> tuple[np.ndarray, np.ndarray]:
        """The item buffers of the hemicubes at the centres of patches ``indices``, as rows are computed from them:
        tops (k, r, r) and sides (k, 4, r/2, r), uint32 (0: nothing, j + 1: patch j). For the grader's trusted inputs."""
        idx = [int(i) for i in indices]
        r, tops, sides = self.resolution, [], []
        for start in range(0, len(idx), self.renderer.batch):
            chunk = idx[start:start + self.renderer.batch]
            views = np.stack([self.views_for(i) for i in chunk])
            planes = np.array([[*self.normals[i], float(self.normals[i] @ self.centers[i])] for i in chunk])
            for top, side in self.renderer.render(views, planes):
                tops.append(top)
                sides.append(side)
        return (np.asarray(tops, dtype=np.uint32).reshape(-1, r, r),
                np.asarray(sides, dtype=np.uint32).reshape(-1, 4, r // 2, r))

    def proximity_fixed(self, i: int, row: np.ndarray) -> np.ndarray:
        """Row ``row`` of patch i (from its hemicube) with the proximity fix applied to its close patches (H6)."""
        return self._proximity_fix(int(i), np.asarray(row, dtype=np.float64))

    def rows_at(self, points: Any, normals: Any, lift: Any = 0.0, ids: Any = None) -> np.ndarray:
        """Rows (k, n) for shooters that are not among the receivers: one hemicube at each point.

        For substructuring, where a patch shoots to the finer elements it is made of: the
        hemicube stands at the patch's centre, facing its normal, and sees the receivers
        (``quads``). ``lift`` (k,) raises each base plane, so that the shooter's own elements,
        which lie in (or, on a slightly warped quad, a hair above) that plane, are not drawn.
        ``ids`` (k,) pick each hemicube's seeded rotation (default 0 .. k-1): give every shooter
        its own, or their aliasing lines up. Not cached, and not counted as rows of this matrix.
        """
        points = np.asarray(points, dtype=np.float64).reshape(-1, 3)
        normals = np.asarray(normals, dtype=np.float64).reshape(-1, 3)
        lift = np.broadcast_to(np.asarray(lift, dtype=np.float64), (len(points),))
        normals = normals / np.linalg.norm(normals, axis=1, keepdims=True)
        ids = range(len(points)) if ids is None else [int(i) for i in np.ravel(ids)]
        jobs = [(k, points[k], normals[k], float(normals[k] @ points[k] + lift[k]), i, 1.0) for k, i in enumerate(ids)]
        return self._render_rows(jobs, len(points))

    def _render_rows(self, jobs: list, count: int) -> np.ndarray:
        """Sum hemicube rows: jobs are (row, eye, normal, plane offset, rotation index, weight)."""
        rows = np.zeros((count, self.n))
        top_w, side_w = self.tables
        step = self.renderer.batch
        for start in range(0, len(jobs), step):
            chunk = jobs[start:start + step]
            t0 = time.perf_counter()
            views = np.stack([self._views(eye, n, index) for _, eye, n, _, index, _ in chunk])
            planes = np.array([[*n, d] for _, _, n, d, _, _ in chunk])
            buffers = self.renderer.render(views, planes)     # the base plane from the geometry, not from H2
            t1 = time.perf_counter()
            self.counters["readbacks"] += 1
            self.counters["hemicubes_rendered"] += len(chunk)
            for (k, _, _, _, _, w), (top, sides) in zip(chunk, buffers):
                rows[k] += w * H.call_row(self.impl, top, sides, top_w, side_w, self.n)
            self.seconds["render"] += t1 - t0
            self.seconds["sum"] += time.perf_counter() - t1
        return rows

    def _compute(self, batch: list[int]) -> None:
        jobs = [(k, p, self.normals[i], float(self.normals[i] @ self.centers[i]), i, w)
                for k, i in enumerate(batch) for p, w in zip(*self.shooter_points(i))]
        rows = self._render_rows(jobs, len(batch))
        if self.resample_blind:
            blind = [k for k, i in enumerate(batch) if rows[k].sum() < BLIND_ROW_SUM]
            if blind:
                for k, row in zip(blind, self._resampled_rows([batch[k] for k in blind])):
                    if row is not None:
                        rows[k] = row
        t2 = time.perf_counter()
        for k, i in enumerate(batch):
            self._count_culled(i)
            self._rows[i] = self._proximity_fix(i, rows[k]) if self.proximity == "contour" else rows[k]
            self.counters["rows_computed"] += 1
        self.seconds["proximity"] += time.perf_counter() - t2

    def _resampled_rows(self, patches: list[int]) -> list[np.ndarray | None]:
        """Rows of patches blind from their centres: the area-weighted mean over the sub-quad centres that see
        (None where none sees: the patch faces an opening, and its centre's row stands)."""
        points = [self.shooter_points(i, self.resample_blind) for i in patches]
        stands = [(i, p) for i, (ps, _) in zip(patches, points) for p in ps]
        jobs = [(k, p, self.normals[i], float(self.normals[i] @ self.centers[i]), i, 1.0) for k, (i, p) in enumerate(stands)]
        sub = self._render_rows(jobs, len(jobs))
        out: list[np.ndarray | None] = []
        start = 0
        for ps, weights in points:
            rows = sub[start:start + len(ps)]
            start += len(ps)
            sums = rows.sum(axis=1)
            seeing = sums >= max(0.5 * sums.max(), BLIND_ROW_SUM)
            out.append(weights[seeing] @ rows[seeing] / weights[seeing].sum() if seeing.any() else None)
        self.counters["blind_rows_resampled"] += len(patches)
        return out

    def _count_culled(self, i: int) -> None:
        heights = (self.quads - self.centers[i]) @ self.normals[i]                  # (n, 4)
        behind = heights.max(axis=1) <= 1e-9 * max(self.radii[i], 1e-300)
        behind[i] = False                                                          # not the shooter itself
        self.counters["patches_culled"] += int(behind.sum())
        facing_away = ((self.centers - self.centers[i]) * self.normals).sum(axis=1) >= 0
        self.counters["patches_backfacing"] += int((facing_away & ~behind).sum())

    def close_patches(self, i: int) -> np.ndarray:
        """Indices of the patches close to patch i (not i, not wholly behind its plane)."""
        gap = np.linalg.norm(self.centers - self.centers[i], axis=1) - self.radii
        heights = (self.quads - self.centers[i]) @ self.normals[i]
        close = (gap < self.proximity_distance * self.radii[i]) & (heights.max(axis=1) > 1e-9 * self.radii[i])
        close[i] = False
        return np.flatnonzero(close)

    def _proximity_fix(self, i: int, row: np.ndarray) -> np.ndarray:
        close = self.close_patches(i)
        if not len(close):
            return row
        row = row.copy()
        c, n = self.centers[i], self.normals[i]
        points, weights = gauss_points(self.quads[i], PROXIMITY_GAUSS)
        weights = weights / weights.sum()
        for j in close:
            poly = clip_polygon_to_plane(self.quads[j], c, n)
            if len(poly) < 3:
                continue
            at_center = H.call_contour(self.impl, c, n, poly)
            if at_center > 1e-12:
                visible = min(max(row[j] / at_center, 0.0), 1.0)
            else:
                visible = 1.0  # seen edge-on from the centre: the hemicube cannot tell; assume unoccluded
            if visible == 0.0:
                continue
            average = sum(w * H.call_contour(self.impl, p, n, poly) for p, w in zip(points, weights))
            row[j] = visible * average
            self.counters["proximity_pairs"] += 1
        return row

    # -- checks reported for every run ----------------------------------------------
    def report(self) -> dict[str, Any]:
        """Row sums, reciprocity (A_i F_ij against A_j F_ji over pairs whose rows are both computed), closure."""
        done = self.cached()
        if not done:
            return {"rows": 0, **self.counters}
        F = np.stack([self._rows[i] for i in done])
        sums = F.sum(axis=1)
        idx = np.array(done)
        sub = F[:, idx] * self.areas[idx, None]              # A_i F_ij for i, j both computed
        diff = np.abs(sub - sub.T)
        scale = np.maximum(sub, sub.T)
        # the max is over pairs that both see each other clearly; the total weighs every pair
        significant = np.minimum(sub, sub.T) > 1e-3 * max(scale.max(), 1e-300)
        recip_rel = float((diff[significant] / scale[significant]).max()) if significant.any() else 0.0
        recip_total = float(diff.sum() / max(2 * sub.sum(), 1e-300))
        return {"rows": len(done), "row_sum_min": float(sums.min()), "row_sum_max": float(sums.max()),
                "row_sum_mean": float(sums.mean()), "closure_error_max": float(np.abs(1 - sums).max()),
                "reciprocity_error_max": recip_rel, "reciprocity_error_total": recip_total,
                "resolution": self.resolution, **self.counters}

    def summary(self) -> str:
        r = self.report()
        if not r["rows"]:
            return "no rows computed yet"
        return (f"{r['rows']} rows at resolution {self.resolution}: row sums {r['row_sum_min']:.4f} .. {r['row_sum_max']:.4f}, "
                f"reciprocity error max {r['reciprocity_error_max']:.2%} (total {r['reciprocity_error_total']:.2%}); "
                f"{r['hemicubes_rendered']} hemicubes in {r['readbacks']} read-backs, {r['rows_cached_hits']} cache hits, "
                f"{r['patches_culled']} patches culled, {r['proximity_pairs']} close pairs fixed")


# --- pictures -----------------------------------------------------------------

def palette(ids: np.ndarray) -> np.ndarray:
    """A colour per item id (0: black): hues by the golden ratio, so neighbouring ids differ."""
    ids = np.asarray(ids, dtype=np.int64)
    h = (ids * 0.6180339887498949) % 1.0
    k = (np.array([5.0, 3.0, 1.0]) + h[..., None] * 6) % 6
    rgb = 0.85 - 0.6 * np.clip(np.minimum(k, 4 - k), 0, 1)
    rgb = np.where((ids > 0)[..., None], rgb, 0.0)
    return rgb


def unfold(top: np.ndarray, sides: np.ndarray, views: np.ndarray) -> np.ndarray:
    """A hemicube's five item buffers unfolded into a cross (2r × 2r): top in the middle, each side against its edge.

    Each cross pixel is a direction in the hemicube's frame; it takes the item of the cell
    that direction passes through (found with the views' axes), so the picture is right
    whatever the views' conventions, as long as the views are the five faces.
    """
    r = top.shape[0]
    size = 2 * r
    X, Y = np.meshgrid((np.arange(size) + 0.5) / size * 4 - 2, (np.arange(size) + 0.5) / size * 4 - 2)
    rot = views[0][:3, :3]            # rows s, u, -f of the top view: right, up, -normal
    right, up, normal = rot[0], rot[1], -rot[2]
    z = np.ones_like(X)
    x, y = X.copy(), Y.copy()
    for mask, setter in (((Y > 1) & (np.abs(X) <= 1), lambda: (X, np.ones_like(X), 2 - Y)),
                         ((Y < -1) & (np.abs(X) <= 1), lambda: (X, -np.ones_like(X), 2 + Y)),
                         ((X > 1) & (np.abs(Y) <= 1), lambda: (np.ones_like(X), Y, 2 - X)),
                         ((X < -1) & (np.abs(Y) <= 1), lambda: (-np.ones_like(X), Y, 2 + X))):
        a, b, c = setter()
        x, y, z = np.where(mask, a, x), np.where(mask, b, y), np.where(mask, c, z)
    inside = (np.abs(X) <= 1) | (np.abs(Y) <= 1)
    d = x[..., None] * right + y[..., None] * up + z[..., None] * normal
    out = np.zeros(X.shape, dtype=np.int64)
    for f in range(5):
        R = views[f][:3, :3]
        fwd, fright, fup = -R[2], R[0], R[1]
        depth = d @ fwd
        with np.errstate(divide="ignore", invalid="ignore"):
            u_, v_ = (d @ fright) / depth, (d @ fup) / depth
        if f == 0:
            col, row, rows = np.floor((u_ + 1) / 2 * r), np.floor((v_ + 1) / 2 * r), r
            img = top
        else:
            col, row, rows = np.floor((u_ + 1) / 2 * r), np.floor(v_ * r / 2), r // 2
            img = sides[f - 1]
        ok = inside & (depth > 1e-9) & (col >= 0) & (col < r) & (row >= 0) & (row < rows) & (out == 0)
        ok &= np.abs(u_) <= 1
        out[ok] = img[row[ok].astype(int), col[ok].astype(int)]
    return out


def item_buffer_image(ff: HemicubeFormFactors, patch: int, size: tuple[int, int] | None = None,
                      given: dict[str, np.ndarray] | None = None) -> np.ndarray:
    """The unfolded hemicube of ``patch`` as a float image (image rows top to bottom), ids in palette colours.

    ``given`` may hold trusted ``views`` (5, 4, 4) and ``projections`` (2, 4, 4) replacing H2 and H3.
    """
    if given and "projections" in given:
        renderer = ItemBufferRenderer(ff.quads, ff.impl, ff.resolution, given["projections"], 1, ff._ctx)
    else:
        renderer = ff.renderer
    views = given["views"] if given and "views" in given else ff.views_for(patch)
    top, sides = renderer.render(np.asarray(views, dtype=np.float64)[None])[0]
    cross = unfold(top.astype(np.int64), sides.astype(np.int64), np.asarray(views, dtype=np.float64))
    image = np.flipud(palette(cross))
    if size is not None and size != (image.shape[1], image.shape[0]):
        w, h = size
        rows = (np.arange(h) * image.shape[0] // h)
        cols = (np.arange(w) * image.shape[1] // w)
        image = image[rows][:, cols]
    return image


def formfactor_image(scene: Any, quads: np.ndarray, row: np.ndarray, impl: Any,
                     size: tuple[int, int] | None = None) -> np.ndarray:
    """The scene from its camera, each patch painted with F from the chosen patch to it (scaled to the largest).

    ``impl`` (a stage-3 implementation) places the camera: see :mod:`cs451.viewing`."""
    from .gl import create_context
    from .viewing import camera_projection, camera_view
    width, height = size or (scene.image.width, scene.image.height)
    view = camera_view(scene.camera, lambda c, n, u: H.call_views(impl, c, n, u))
    proj = camera_projection(scene.camera, width, height)
    value = row / max(row.max(), 1e-300)
    colours = np.stack([value, value ** 2, 0.2 * (1 - value)], axis=1)   # a warm ramp; dark blue is "sees nothing"
    tris, ids = patch_triangles(quads)
    ctx = create_context()
    prog = ctx.program(vertex_shader="""#version 330
in vec3 in_position; in vec3 in_colour; uniform mat4 u_mvp; out vec3 v_colour;
void main() { gl_Position = u_mvp * vec4(in_position, 1.0); v_colour = in_colour; }""",
                       fragment_shader="""#version 330
in vec3 v_colour; out vec4 colour; void main() { colour = vec4(v_colour, 1.0); }""")
    data = np.hstack([tris.reshape(-1, 3), np.repeat(colours[ids], 3, axis=0)]).astype("f4")
    vao = ctx.vertex_array(prog, [(ctx.buffer(data.tobytes()), "3f 3f", "in_position", "in_colour")])
    prog["u_mvp"].write((proj @ view).T.astype("f4").tobytes())
    fbo = ctx.framebuffer([ctx.texture((width, height), 4, dtype="f4")], ctx.depth_renderbuffer((width, height)))
    fbo.use()
    ctx.enable(ctx.DEPTH_TEST)
    fbo.clear(0, 0, 0, 1, depth=1.0)
    vao.render()
    img = np.frombuffer(fbo.read(components=3, dtype="f4"), dtype=np.float32).reshape(height, width, 3)
    return np.flipud(img).astype(np.float64)


# --- Monte Carlo ray casting, for comparison -----------------------------------------

def formfactor_matrix_raycast(quads: Any, samples: int, seed: int = 0, rows: Iterable[int] | None = None,
                              origin: str = "area") -> np.ndarray:
    """Form factors by Monte Carlo ray casting (Embree through embreex): ``samples`` cosine-weighted rays per patch.

    Each ray leaves patch i in a cosine-distributed direction about its normal, from a
    uniformly random point of the patch (``origin="area"``: estimates the true F_ij, the
    area average) or from its centre (``origin="center"``: estimates what a hemicube
    computes, the form factor of the centre's differential area). F_ij is the fraction of
    i's rays whose first hit is the front of patch j (a back face absorbs the ray, as in
    the hemicube). Unbiased; the standard error of F_ij is sqrt(F_ij (1 - F_ij) / samples).
    Returns (len(rows), n).
    """
    if origin not in ("area", "center"):
        raise KitError(f"origin must be 'area' or 'center', got {origin!r}")
    try:
        import embreex.mesh_construction as mc
        import embreex.rtcore_scene as rtcs
    except ImportError:
        raise KitError("ray casting runs on Embree, an optional peer: pip install -e '.[peers]'") from None

    q = as_quads(quads)
    n = len(q)
    rows = list(range(n)) if rows is None else [int(i) for i in rows]
    tris, ids = patch_triangles(q)
    scene = rtcs.EmbreeScene()
    mc.TriangleMesh(scene, tris.astype(np.float32))
    normals, centers = patch_normals(q), patch_centers(q)
    rng = np.random.default_rng(seed)
    out = np.zeros((len(rows), n))
    chunk = max(1, 2_000_000 // max(samples, 1))
    tri_area = 0.5 * np.linalg.norm(np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0]), axis=1)
    for start in range(0, len(rows), chunk):
        block = rows[start:start + chunk]
        m = len(block)
        b = np.repeat(np.array(block), samples)
        # a uniform point on patch i: pick one of its two triangles by area, then a uniform point in it
        a0, a1 = tri_area[2 * b], tri_area[2 * b + 1]
        second = rng.random(len(b)) * (a0 + a1) >= a0
        t = 2 * b + second
        r1, r2 = rng.random(len(b)), rng.random(len(b))
        s1 = np.sqrt(r1)
        p = (1 - s1)[:, None] * tris[t, 0] + (s1 * (1 - r2))[:, None] * tris[t, 1] + (s1 * r2)[:, None] * tris[t, 2]
        if origin == "center":
            p = centers[b]
        nrm = normals[b]
        tangent = np.cross(nrm, np.where(np.abs(nrm[:, :1]) < 0.9, [[1.0, 0, 0]], [[0, 1.0, 0]]))
        tangent /= np.linalg.norm(tangent, axis=1, keepdims=True)
        bitangent = np.cross(nrm, tangent)
        u1, u2 = rng.random(len(b)), rng.random(len(b))
        rad, phi = np.sqrt(u1), 2 * np.pi * u2
        d = (rad * np.cos(phi))[:, None] * tangent + (rad * np.sin(phi))[:, None] * bitangent + np.sqrt(1 - u1)[:, None] * nrm
        start_at = p + nrm * (1e-5 * (1 + np.abs(p).max(axis=1)))[:, None]   # offset off the surface, scaled with |p|
        hit = scene.run(start_at.astype(np.float32), d.astype(np.float32))
        hit = np.asarray(hit)
        valid = hit >= 0
        j = ids[np.where(valid, hit, 0)]
        front = valid & (np.einsum("ij,ij->i", d, normals[j]) < 0)
        key = np.repeat(np.arange(m), samples)[front] * n + j[front]
        out[start:start + m] = np.bincount(key, minlength=m * n).reshape(m, n) / samples
    return out
