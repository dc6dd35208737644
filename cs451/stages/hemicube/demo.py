"""Stage 3's demo: pick a patch of the Cornell box and see its hemicube — the five views, the unfolded item buffer,
the delta form factors, and the row of form factors painted on the scene, with its sum.

Everything goes through the stage interface: the form-factor engine
(:class:`~cs451.formfactors.HemicubeFormFactors`) draws the hemicube with the submission's
tables (H1), views (H2), projections (H3) and shaders (H4) and sums the row with its H5
(and H6 where the proximity fix is on), all through :func:`cs451.stages.hemicube.calls`,
every answer checked. The item buffers shown are the ones the row is summed from
(:meth:`~cs451.formfactors.HemicubeFormFactors.item_buffers`), summed again here with the
submission's H5 for the caption; the row painted is the engine's, with the settings
``cs451 render --stage hemicube`` uses (the proximity fix on by default), so the caption
shows both sums: what this hemicube sees, and the row after the fix.

The scene is seen from its camera through H2 (the top view of a hemicube at the eye) and
pyrender's projection, as the stage's own form-factor picture is (:mod:`cs451.viewing`);
each patch is drawn with its id beside its colour, so a click picks the patch under it.
A click on the unfolded item buffer picks the patch seen there.
"""
from __future__ import annotations

import time
from pathlib import Path
from types import ModuleType
from typing import Any, Iterator

import numpy as np

from ...demos import overlay
from ...demos.player import Event, Prepared, play
from ...errors import KitError
from ...formfactors import HemicubeFormFactors, palette, unfold
from ...imageio import to_uint8
from ...patches import patch_triangles, scene_polygons
from ...scene import load_scene
from .. import hemicube as H

#: Seconds each patch stays up in a sweep (space) in the window.
SWEEP_SECONDS = 1.5
#: Resolutions + and - step through.
RESOLUTIONS = (8, 16, 32, 64, 128, 256, 512)
#: What the shooter is painted in (the row's ramp runs from dark blue through red to yellow).
SHOOTER = (0.1, 0.8, 1.0)

PAINT_VERTEX = """#version 330
in vec3 in_position;
in vec3 in_colour;
in uint in_id;
uniform mat4 u_mvp;
out vec3 v_colour;
flat out uint v_id;
void main() { gl_Position = u_mvp * vec4(in_position, 1.0); v_colour = in_colour; v_id = in_id; }
"""
PAINT_FRAGMENT = """#version 330
in vec3 v_colour;
flat in uint v_id;
layout(location = 0) out vec4 colour;
layout(location = 1) out uint item;
void main() { colour = vec4(v_colour, 1.0); item = v_id + 1u; }
"""


def row_colours(row: np.ndarray) -> np.ndarray:
    """The stage's ramp for a row (:func:`cs451.formfactors.formfactor_image`): F over the largest F, warm when large."""
    value = row / max(float(row.max()), 1e-300)
    return np.stack([value, value ** 2, 0.2 * (1 - value)], axis=1)


def heat(values: np.ndarray) -> np.ndarray:
    """Values in [0, 1] as uint8 colours from black through purple and orange to pale yellow; NaN: dark grey."""
    stops = np.array([[0, 0, 4], [87, 16, 110], [188, 55, 84], [249, 142, 9], [252, 255, 164]], dtype=np.float64)
    x = np.nan_to_num(np.clip(values, 0, 1), nan=0.0) * (len(stops) - 1)
    k = np.minimum(x.astype(int), len(stops) - 2)
    t = (x - k)[..., None]
    out = (1 - t) * stops[k] + t * stops[k + 1]
    out[np.isnan(values)] = (40, 40, 40)
    return np.round(out).astype(np.uint8)


def nearest(image: np.ndarray, width: int, height: int) -> np.ndarray:
    """``image`` resampled to (height, width) by nearest pixels (item ids must stay ids)."""
    rows = np.arange(height) * image.shape[0] // height
    cols = np.arange(width) * image.shape[1] // width
    return image[rows][:, cols]


class ScenePainter:
    """The scene from its camera, each patch in a colour given per draw, and the patch under every pixel (-1: none)."""

    def __init__(self, ctx: Any, scene: Any, quads: np.ndarray, calls: Any, size: tuple[int, int]):
        from ...viewing import camera_projection, camera_view
        self.ctx, self.size = ctx, size
        width, height = size
        self.mvp = camera_projection(scene.camera, width, height) @ camera_view(scene.camera, calls.views)
        tris, ids = patch_triangles(quads)
        self.ids = np.repeat(ids, 3)
        self.program = ctx.program(vertex_shader=PAINT_VERTEX, fragment_shader=PAINT_FRAGMENT)
        self.program["u_mvp"].write(self.mvp.T.astype("f4").tobytes())
        self.colours = ctx.buffer(reserve=len(self.ids) * 12)
        positions = ctx.buffer(tris.reshape(-1, 3).astype("f4").tobytes())
        self.vao = ctx.vertex_array(self.program, [(positions, "3f", "in_position"), (self.colours, "3f", "in_colour"),
                                                   (ctx.buffer(self.ids.astype("u4").tobytes()), "u", "in_id")])
        self.fbo = ctx.framebuffer([ctx.texture(size, 4, dtype="f4"), ctx.texture(size, 1, dtype="u4")],
                                   ctx.depth_renderbuffer(size))

    def paint(self, colours: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Draw with ``colours`` (n, 3) per patch: the linear image (h, w, 3), top row first, and the ids (h, w)."""
        from ...gl import make_current
        make_current(self.ctx)
        width, height = self.size
        self.colours.write(np.asarray(colours, dtype="f4")[self.ids].tobytes())
        self.fbo.use()
        self.ctx.viewport = (0, 0, width, height)
        self.ctx.enable(self.ctx.DEPTH_TEST)
        self.fbo.clear(0, 0, 0, 1, depth=1.0)
        self.vao.render()
        image = np.frombuffer(self.fbo.read(components=3, dtype="f4"), np.float32).reshape(height, width, 3)
        ids = np.frombuffer(self.fbo.read(components=1, dtype="u4", attachment=1), np.uint32).reshape(height, width)
        return np.flipud(image).astype(np.float64), np.flipud(ids).astype(np.int64) - 1


class _Shown:
    """What the frame shows for one patch: the hemicube (buffers, views, sums) and the painted row."""

    def __init__(self, patch: int, row: np.ndarray, hemicube_row: np.ndarray, top: np.ndarray, sides: np.ndarray,
                 views: np.ndarray, tables: tuple[np.ndarray, np.ndarray], final: bool = True):
        self.patch, self.row, self.hemicube_row, self.final = patch, row, hemicube_row, final
        self.top, self.sides, self.views, self.tables = top, sides, views, tables


class HemicubeDemo(Prepared):
    """The demo's state: the patches, the engines by setting, the patch shown and how it looks."""
    name = "hemicube"
    caption_lines = 3

    def __init__(self, module: ModuleType, scene: str | Path = "cornell-box", size: tuple[int, int] | None = None):
        self.scene = load_scene(scene)
        H.STAGE.check_scene(self.scene)
        opts = H.STAGE.options(self.scene)
        self.title = f"cs451 hemicube: {self.scene.name}"
        self.quads, self.materials, _ = scene_polygons(self.scene)
        self.n = len(self.quads)
        if opts.patch >= self.n:
            raise KitError(f"{self.scene.label}: options.hemicube.patch: the scene has {self.n} patches, got {opts.patch}")
        self.calls = H.calls(module)
        self.width, self.height = size or (self.scene.image.width, self.scene.image.height)
        H.STAGE.check_cost(self.scene)
        self.patch, self.resolution, self.rotate, self.proximity = opts.patch, opts.resolution, opts.rotate, True
        self.sweeping, self._swept = False, 0.0
        self.ctx: Any = None
        self.engines: dict[tuple, HemicubeFormFactors] = {}
        self.shown: _Shown | None = None
        self.ids = np.full((self.height, self.width), -1)
        self.cross_ids = np.zeros((2, 2), np.int64)
        self._frame: np.ndarray | None = None
        side = self.height
        self.views_height = side // 2
        self.layout = {"scene": (0, 0, self.width, self.height), "items": (self.width, 0, side, side),
                       "weights": (self.width + side, 0, side, side)}
        self.size = (self.width + 2 * side, self.height + self.views_height)

    # --- the player's interface ---------------------------------------------------------------
    def frame_size(self) -> tuple[int, int]:
        """(width, height): the scene, the unfolded item buffer and the delta form factors side by side, the five
        views in a strip below."""
        return self.size

    def _preparing(self) -> Iterator[str]:
        from ...gl import create_context
        yield "the scene's patches, seen from its camera"
        self.ctx = self._ctx or create_context()
        self.painter = ScenePainter(self.ctx, self.scene, self.quads, self.calls, (self.width, self.height))

    def start(self, ctx: Any) -> None:
        """Prepare in ``ctx`` (None: a standalone context) at once."""
        for _ in self.prepare(ctx):
            pass

    def busy(self) -> bool:
        """Whether there is work: no patch shown yet, another patch picked, the shown row still to be fixed, or the
        sweep's next patch due."""
        due = self.sweeping and time.perf_counter() - self._swept >= SWEEP_SECONDS
        return self.shown is None or self.shown.patch != self.patch or not self.shown.final or due

    def step(self, seconds: float) -> bool:
        """The patch's hemicube first (a frame at once), then its row with the proximity fix (seconds, for a patch
        touching others)."""
        self.ready()
        s = self.shown
        if s is not None and s.patch == self.patch and not s.final:
            s.row, s.final, self._frame = self.engine(self.proximity).row(s.patch), True, None
            return False
        if self.sweeping and s is not None and s.patch == self.patch:
            self.patch = (self.patch + 1) % self.n
        self.show(self.patch, fixed=False)
        self._swept = time.perf_counter()
        return False

    def handle(self, event: Event) -> None:
        """Arrows step through the patches, a click picks one, space sweeps; p, r and + - toggle the fix or the
        rotation, or change the resolution, and drop what is shown."""
        if event[0] == "click":
            picked = self.pick(int(event[1]), int(event[2]))
            if picked is not None:
                self.patch, self.sweeping = picked, False
            return
        key = event[1]
        if key in ("right", "left"):
            self.patch = (self.patch + (1 if key == "right" else -1)) % self.n
        elif key == "space":
            self.sweeping, self._swept = not self.sweeping, time.perf_counter()
        elif key in ("p", "r", "+", "-"):
            if key == "p":
                self.proximity = not self.proximity
            elif key == "r":
                self.rotate = not self.rotate
            else:
                at = int(np.searchsorted(RESOLUTIONS, self.resolution))
                self.resolution = RESOLUTIONS[int(np.clip(at + (1 if key == "+" else -1), 0, len(RESOLUTIONS) - 1))]
            self.shown = None

    def script(self) -> list[list[Event]]:
        """A sweep over every patch, from the first."""
        return [[]] + [[("key", "right")] for _ in range(self.n - 1)]

    def frame(self) -> np.ndarray:
        """The current picture, composed once for what is shown and kept until that changes."""
        self.ready()
        if self.shown is None:
            self.show(self.patch)
        if self._frame is None:
            self._frame = self._compose()
        return self._frame

    def caption(self) -> str:
        """Three lines: the patch and its row sum (with or without the fix), H5's row alone and F to the light, and
        the settings."""
        self.frame()
        return "\n".join(self._caption())

    # --- the hemicube -----------------------------------------------------------------------------
    def engine(self, proximity: bool) -> HemicubeFormFactors:
        """The form-factor engine under the current settings, with the fix (as `cs451 render`) or without."""
        key = (self.resolution, self.rotate, proximity)
        if key not in self.engines:
            self.engines[key] = HemicubeFormFactors(self.quads, self.calls, resolution=self.resolution, rotate=self.rotate,
                                                    proximity="contour" if proximity else "none", ctx=self.ctx)
        return self.engines[key]

    def show(self, patch: int, fixed: bool = True) -> None:
        """Compute what the frame shows for ``patch``: its hemicube's buffers and H5 row, and the engine's row (not
        ``fixed``: the hemicube's row stands in for it until the next step, when the proximity fix takes a while)."""
        bare = self.engine(False)
        tops, sides = bare.item_buffers([patch])
        tables = bare.tables
        hemicube_row = self.calls.row(tops[0].copy(), sides[0].copy(), tables[0], tables[1], self.n)
        engine = self.engine(self.proximity)
        final = fixed or not self.proximity or engine.has_row(patch)
        row = engine.row(patch) if final else hemicube_row
        self.shown = _Shown(patch, row, hemicube_row, tops[0], sides[0], bare.views_for(patch), tables, final)
        self._frame = None

    def painted_row(self) -> np.ndarray:
        """The row the scene panel paints (F from the shown patch to every patch)."""
        assert self.shown is not None
        return self.shown.row

    def pick(self, x: int, y: int) -> int | None:
        """The patch under frame pixel (x, y): on the scene, or seen in the unfolded item buffer; None elsewhere."""
        for name, ids in (("scene", self.ids), ("items", self.cross_ids)):
            left, top, w, h = self.layout[name]
            if left <= x < left + w and top <= y < top + h:
                got = int(ids[(y - top) * ids.shape[0] // h, (x - left) * ids.shape[1] // w])
                got = got - 1 if name == "items" else got
                return got if 0 <= got < self.n else None
        return None

    # --- the frame --------------------------------------------------------------------------------
    def _compose(self) -> np.ndarray:
        from PIL import Image, ImageDraw
        s, enc = self.shown, (self.scene.image.exposure, self.scene.image.srgb)
        assert s is not None
        W_, H_ = self.size
        frame = np.full((H_, W_, 3), 24, np.uint8)
        colours = row_colours(s.row)
        colours[s.patch] = SHOOTER
        scene_image, self.ids = self.painter.paint(colours)
        side = self.height
        r = self.resolution
        cross = unfold(s.top.astype(np.int64), s.sides.astype(np.int64), s.views)
        self.cross_ids = np.flipud(cross)
        cells = np.arange(r * r).reshape(r, r) + 1
        side_cells = np.broadcast_to(np.arange(r * r // 2).reshape(r // 2, r) + 1 + r * r, (4, r // 2, r))
        where = np.flipud(unfold(cells, np.ascontiguousarray(side_cells), s.views))
        weights = np.concatenate([s.tables[0].ravel(), s.tables[1].ravel()])
        cross_w = np.where(where > 0, weights[np.maximum(where, 1) - 1], np.nan)
        panels = {"scene": to_uint8(scene_image, *enc),
                  "items": nearest(to_uint8(palette(self.cross_ids), *enc), side, side),
                  "weights": nearest(heat(cross_w / np.nanmax(cross_w)), side, side)}
        for name, image in panels.items():
            left, top, w, h = self.layout[name]
            frame[top:top + h, left:left + w] = image
        # the five views: the top face, then the four sides (base down), each at half the panels' height
        vh = self.views_height
        x = 0
        faces = [("top", s.top, vh, vh)] + [(f"side {k + 1}", s.sides[k], vh, vh // 2) for k in range(4)]
        for _, ids, w, h in faces:
            image = nearest(to_uint8(palette(np.flipud(ids.astype(np.int64))), *enc), w, h)
            frame[side + vh - h:side + vh, x:x + w] = image
            x += w + 4
        picture = Image.fromarray(frame)
        draw = ImageDraw.Draw(picture)
        labels = [("scene: F from the cyan patch", self.layout["scene"]), ("item buffer, unfolded", self.layout["items"]),
                  ("delta form factors (H1)", self.layout["weights"])]
        x = 0
        for name, _, w, h in faces:
            labels.append((name, (x, side + vh - h, w, h)))
            x += w + 4
        font = overlay.font(max(11, side // 20))          # scaled with the picture: ~30 px on a 1080p screen
        for text, (left, top, _, _) in labels:
            right, bottom = left + draw.textlength(text, font=font) + 6, top + getattr(font, "size", 10) + 4
            draw.rectangle((left, top, right, bottom), fill=(0, 0, 0))
            draw.text((left + 3, top + 2), text, fill=(240, 240, 240), font=font)
        return np.asarray(picture)

    def _caption(self) -> list[str]:
        s = self.shown
        assert s is not None
        light = [j for j, m in enumerate(self.materials) if m == "light"]
        fix = ("with the proximity fix (H6)" if s.final else "(the proximity fix (H6): computing …)") \
            if self.proximity else "without the proximity fix"
        biggest = int(np.argmax(s.row))
        return [f"hemicube · {self.scene.name} · patch {s.patch} of {self.n} ({self.materials[s.patch]}): "
                f"row sum {s.row.sum():.4f} {fix}",
                f"this hemicube alone (H5): {s.hemicube_row.sum():.4f} · F to the light {s.row[light].sum():.4f} · "
                f"largest F {s.row[biggest]:.4f} (to patch {biggest}) · sees {int((s.hemicube_row > 0).sum())} patches",
                f"resolution {self.resolution}, rotation {'on' if self.rotate else 'off'}"
                + (", sweeping" if self.sweeping else "")]


def demo(module: ModuleType, output: Path, window: bool, frames: int | None, scene: str | Path = "cornell-box",
         size: tuple[int, int] | None = None, screenshot: Path | None = None, fullscreen: bool = False) -> list[Path]:
    """In a window: a patch's hemicube and its row, patches picked by keys or clicks. Headless: a sweep over every
    patch, a frame each, as PNGs and ``hemicube.gif``."""
    return play(HemicubeDemo(module, scene, size), window=window, frames=frames, output=output, screenshot=screenshot,
                fullscreen=fullscreen)
