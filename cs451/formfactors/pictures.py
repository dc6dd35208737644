"""Pictures of hemicubes for people: an item buffer unfolded into a cross, and a row painted on the scene."""
from __future__ import annotations

from typing import Any

import numpy as np

from ..patches import patch_triangles
from .atlas import ItemBufferRenderer
from .calls import StageCalls
from .rows import HemicubeFormFactors


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
        renderer = ItemBufferRenderer(ff.quads, ff.calls.shaders(), ff.resolution, given["projections"], 1, ff._ctx)
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


def formfactor_image(scene: Any, quads: np.ndarray, row: np.ndarray, calls: StageCalls,
                     size: tuple[int, int] | None = None) -> np.ndarray:
    """The scene from its camera, each patch painted with F from the chosen patch to it (scaled to the largest).

    ``calls`` (a stage-3 implementation's) place the camera: see :mod:`cs451.viewing`."""
    from ..viewing import camera_view
    value = row / max(row.max(), 1e-300)
    colours = np.stack([value, value ** 2, 0.2 * (1 - value)], axis=1)   # a warm ramp; dark blue is "sees nothing"
    return paint_patches(scene, quads, colours, camera_view(scene.camera, calls.views), size)


def paint_patches(scene: Any, quads: np.ndarray, colours: np.ndarray, view: np.ndarray,
                  size: tuple[int, int] | None = None, background: Any = (0.0, 0.0, 0.0)) -> np.ndarray:
    """The scene from its camera, each patch flat in its own colour (linear, unclamped), image rows top to bottom.

    ``view`` is the camera's view matrix as a stage's H2 places it (:func:`cs451.viewing.camera_view`); the
    projection is pyrender's. Both sides of a patch show its colour. Stage 3's pictures of a row and its deck's
    pictures of patches share it, so a picture of patches never needs stage 4's display."""
    from ..gl import create_context
    from ..viewing import camera_projection
    width, height = size or (scene.image.width, scene.image.height)
    proj = camera_projection(scene.camera, width, height)
    tris, ids = patch_triangles(quads)
    ctx = create_context()
    prog = ctx.program(vertex_shader="""#version 330
in vec3 in_position; in vec3 in_colour; uniform mat4 u_mvp; out vec3 v_colour;
void main() { gl_Position = u_mvp * vec4(in_position, 1.0); v_colour = in_colour; }""",
                       fragment_shader="""#version 330
in vec3 v_colour; out vec4 colour; void main() { colour = vec4(v_colour, 1.0); }""")
    data = np.hstack([tris.reshape(-1, 3), np.repeat(np.asarray(colours)[ids], 3, axis=0)]).astype("f4")
    vao = ctx.vertex_array(prog, [(ctx.buffer(data.tobytes()), "3f 3f", "in_position", "in_colour")])
    prog["u_mvp"].write((proj @ np.asarray(view)).T.astype("f4").tobytes())
    fbo = ctx.framebuffer([ctx.texture((width, height), 4, dtype="f4")], ctx.depth_renderbuffer((width, height)))
    fbo.use()
    ctx.enable(ctx.DEPTH_TEST)
    ctx.disable(ctx.CULL_FACE)
    fbo.clear(*background, 1.0, depth=1.0)
    vao.render()
    img = np.frombuffer(fbo.read(components=3, dtype="f4"), dtype=np.float32).reshape(height, width, 3)
    return np.flipud(img).astype(np.float64)
