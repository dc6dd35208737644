"""Stage 2's demo: the ray tracer refining in a window, switches for what it traces, and one pixel's ray tree.

Everything the submission computes is reached through the stage interface, every answer
checked: its camera rays (W1), its hierarchy (W4, through :func:`~cs451.stages.whitted.prepare`)
and its recursion (W11). The switches change what W11 is handed, never its code:

- shadows off: while it runs, its W7 is answered "all the light gets through"
  (:func:`~cs451.stages.base.functions_replaced`), so it casts no shadow rays;
- reflection off: every reflectance is 0 and Fresnel's term is dropped (total internal
  reflection still reflects: glass cannot refract there);
- refraction off: every transmittance is 0 (glass turns opaque, and casts a full shadow);
- the cut-off off: β = 0, so every ray goes on to the depth limit; ``+`` and ``-`` move that limit.

The picture refines coarse to fine: one pixel in every 16 × 16 block first (painted over its
block), then every 8th, 4th, 2nd pixel and the rest, each pixel traced once, in pieces sized by
the time the last piece took (half a step's work, at most :data:`PIECE_RAYS` rays): a slow
numpy submission keeps the window answering, a fast one traces a whole pass between two frames.
A finished picture is kept per setting, so switching back is instant.

A pixel's ray tree is what the submission's own W11 asks its W5 (closest hits) and W7 (shadow
rays) while it traces that pixel's camera ray, recorded as it goes: the kit draws the tree, it
does not trace it (the recursion is task W11's answer, and the engine ships to students). A
secondary ray's parent is the hit its origin leaves from; it is a reflection when it leaves
on the side the parent ray came from, a refraction otherwise. The tree is drawn through a
pinhole fitted to the submission's own camera rays (the kit writes no look-at of its own).

Through its speed hook the reference traces large images in one compiled kernel that calls neither W5
nor W7; while either is replaced (the shadow switch, the ray-tree recording) the speed layer runs its
W11 bounce by bounce, calling them, so the switches and the tree see what any W11 does.
"""
from __future__ import annotations

import dataclasses
import math
import time
from contextlib import AbstractContextManager, nullcontext
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType
from typing import Any, Callable, Iterator

import numpy as np

from ... import tracescene
from ...demos.player import Event, Prepared, play
from ...imageio import to_uint8
from ...scene import Sphere, load_scene
from .. import whitted as W
from ..base import functions_replaced
from .ray_tree import LEGEND, RAY_COLOURS, SHADOW_COLOURS, Pinhole, RayTree, build_tree

#: The most rays one piece hands to W11 (its memory); below that, a piece is what the last one says fits in
#: half a step.
PIECE_RAYS = 1 << 18
#: Frames are at least this wide: a small image is shown with each pixel as a square of pixels.
MIN_FRAME_WIDTH = 640
#: Block size of the first, coarsest pass (one pixel traced per block).
FIRST_BLOCK = 16


@dataclass(frozen=True)
class Settings:
    """What the picture traces: the switches and the depth limit."""
    shadows: bool = True
    reflection: bool = True
    refraction: bool = True
    cutoff: bool = True
    depth: int = 5


@dataclass
class _Render:
    """A picture refining under one setting: the scene it traces (with its counters), the image, how far it got."""
    scene: tracescene.TraceScene
    image: np.ndarray
    pos: int = 0
    level: int = 0


def progressive_order(width: int, height: int) -> tuple[np.ndarray, list[int], list[int]]:
    """Pixel numbers (row by row from the top left) coarse to fine, each once: every b-th pixel of every b-th row
    for b = 16 (or less on a small image), 8, 4, 2, 1; with each pass's end in that order and its block size."""
    b = 1
    while b * 2 <= min(FIRST_BLOCK, max(1, min(width, height) // 4)):
        b *= 2
    taken = np.zeros((height, width), bool)
    order, ends, blocks = [], [], []
    while b >= 1:
        ys, xs = np.mgrid[0:height:b, 0:width:b]
        new = ~taken[ys, xs]
        order.append((ys * width + xs)[new])
        taken[ys, xs] = True
        ends.append(sum(len(o) for o in order))
        blocks.append(b)
        b //= 2
    return np.concatenate(order), ends, blocks


def next_piece(this: tuple[int, float], last: tuple[int, float] | None, target: float, most: int) -> int:
    """How many pixels the next piece traces to take about ``target`` seconds, from the last two (pixels, seconds).

    The two fit a line, seconds = overhead + cost · pixels: a W11 whose per-bounce numpy work costs the same
    for 100 rays as for 1,000 gets larger pieces (doubling while the overhead alone exceeds the target), not
    smaller ones, as a proportional rule would make them.
    """
    n, took = this
    cost, overhead = took / max(n, 1), 0.0
    if last is not None and last[0] != n:
        slope = (took - last[1]) / (n - last[0])
        if slope > 0:
            cost, overhead = slope, took - slope * n
    if overhead >= target or cost <= 0:
        want = 2 * n
    else:
        want = (target - overhead) / cost
    return int(np.clip(want, 16, most))


def _all_light(scene: Any, origins: np.ndarray, targets: np.ndarray) -> np.ndarray:
    """W7's answer with shadows off: every light sample reaches every point, and no shadow ray is cast."""
    return np.ones((len(np.asarray(origins)), 3))


def _recorded(own: Callable, log: list, columns: tuple[int, ...]) -> Callable:
    """``own`` (W5 or W7), recording each call's rays and answers where they have the interface's shapes."""
    def recording(scene: Any, origins: Any, second: Any) -> Any:
        out = own(scene, origins, second)
        try:
            parts = [np.array(origins, dtype=np.float64), np.array(second, dtype=np.float64)]
            parts += [np.array(v, dtype=np.float64) for v in (out if isinstance(out, (tuple, list)) else (out,))]
            n = len(parts[0])
            if len(parts) == len(columns) and all(p.shape == ((n, c) if c else (n,)) for p, c in zip(parts, columns)):
                log.append(parts)
        except (TypeError, ValueError):
            pass                        # not the interface's shapes: W11's own checks say what is wrong
        return out
    return recording


class WhittedDemo(Prepared):
    """The demo's state: the camera rays, one refining picture per setting, and the ray tree shown.

    Made at once (the window opens at its size); the camera rays (W1, which loads the reference's compiled kernels)
    and the hierarchy (W4) are its preparation, which the player runs with the window up.
    """
    name = "whitted"
    caption_lines = 6

    def __init__(self, module: ModuleType, scene: str | Path = "whitted", size: tuple[int, int] | None = None):
        self.scene = load_scene(scene)
        W.STAGE.check_scene(self.scene)
        self.opts = W.STAGE.options(self.scene)
        self.width, self.height = size or (self.scene.image.width, self.scene.image.height)
        W.STAGE.check_cost(self.scene, (self.width, self.height))
        self.title = f"cs451 whitted: {self.scene.name}"
        self.k = math.isqrt(self.opts.spp)
        self.zoom = max(1, math.ceil(MIN_FRAME_WIDTH / self.width))
        self.tracer = module
        self.reach = float(np.linalg.norm(np.subtract(self.scene.camera.center, self.scene.camera.eye))) + 1.0
        self.piece = max(1, 256 // self.k ** 2)
        self._last_piece: tuple[int, float] | None = None
        self.settings = Settings(depth=self.opts.max_depth)
        self.renders: dict[Settings, _Render] = {}
        self.tree: RayTree | None = None
        self._frame: np.ndarray | None = None

    def _preparing(self) -> Iterator[str]:
        yield "the camera rays (W1)"
        self.origins, self.directions = W.STAGE.call(self.tracer, "W1", self.scene.camera, self.width * self.k,
                                                     self.height * self.k)
        self.camera = Pinhole(self.origins, self.directions, self.width, self.height, self.k)
        yield "the scene's hierarchy (W4)"
        self.base = W.prepare(self.scene, self.tracer)
        self.order, self.ends, self.blocks = progressive_order(self.width, self.height)
        wk = self.width * self.k
        self.first_ray = (self.order // self.width) * self.k * wk + (self.order % self.width) * self.k
        self.sub_rays = (np.arange(self.k)[:, None] * wk + np.arange(self.k)[None, :]).ravel()
        self._use(self.settings)

    # --- the player's interface ---------------------------------------------------------------
    def frame_size(self) -> tuple[int, int]:
        """(width, height): the image with each pixel drawn as a ``zoom`` × ``zoom`` square, at least 640 wide."""
        return self.width * self.zoom, self.height * self.zoom

    def busy(self) -> bool:
        """Whether the picture under the current setting still has pixels to trace."""
        self.ready()
        return self.render.pos < len(self.order)

    def handle(self, event: Event) -> None:
        """A click shows that pixel's ray tree; s, r, t and c toggle shadows, reflection, refraction and the cut-off,
        + and - move the depth limit (a tree shown is traced again under the new setting); x clears the tree."""
        self.ready()
        if event[0] == "click":
            x, y = int(event[1]) // self.zoom, int(event[2]) // self.zoom
            if 0 <= x < self.width and 0 <= y < self.height:
                self.tree = self.ray_tree(x, y)
                self._frame = None
            return
        key, s = event[1], self.settings
        changes = {"s": {"shadows": not s.shadows}, "r": {"reflection": not s.reflection},
                   "t": {"refraction": not s.refraction}, "c": {"cutoff": not s.cutoff},
                   "+": {"depth": min(s.depth + 1, W.MAX_DEPTH)}, "-": {"depth": max(s.depth - 1, 0)}}
        if key == "x":
            self.tree, self._frame = None, None
        elif key in changes:
            self._use(dataclasses.replace(s, **changes[key]))
            if self.tree is not None:
                self.tree = self.ray_tree(*self.tree.pixel)

    def step(self, seconds: float) -> bool:
        """Trace pieces of the current pass for about ``seconds``, each sized by :func:`next_piece`; True when a pass
        ends (a frame worth keeping)."""
        self.ready()
        r, stop = self.render, time.perf_counter() + seconds
        while r.pos < len(self.order):
            end = self.ends[r.level]
            n = min(self.piece, end - r.pos)
            started = time.perf_counter()
            self._trace(r, self.order[r.pos:r.pos + n], self.first_ray[r.pos:r.pos + n], self.blocks[r.level])
            took = time.perf_counter() - started
            self.piece = next_piece((n, took), self._last_piece, 0.5 * seconds, PIECE_RAYS // self.k ** 2)
            self._last_piece = (n, took)
            r.pos += n
            self._frame = None
            if r.pos == end:
                r.level += 1
                return True
            if time.perf_counter() >= stop:
                break
        return False

    def frame(self) -> np.ndarray:
        """The current picture, zoomed, with the ray tree drawn over it when one is shown; made once per change."""
        self.ready()
        if self._frame is None:
            r, z = self.render, self.zoom
            image = to_uint8(r.image, self.scene.image.exposure, self.scene.image.srgb)
            image = np.repeat(np.repeat(image, z, axis=0), z, axis=1)
            if self.tree is not None:
                image = self._draw_tree(image, self.tree)
            self._frame = image
        return self._frame

    def caption(self) -> str:
        """Six lines: the scene and how far it has refined, the switches, the rays cast by kind, the ray tree's
        summary (or how to get one), and the legend."""
        self.ready()
        return "\n".join(self._caption())

    def script(self) -> list[list[Event]]:
        """Refine; click the default pixel; shadows, reflection, refraction and the cut-off off in turn; all back on."""
        self.ready()
        x, y = self.default_pixel()
        click = ("click", x * self.zoom + self.zoom // 2, y * self.zoom + self.zoom // 2)
        k = [("key", c) for c in "ssrrttcc"]
        return [[], [click], [k[0]], [k[1], k[2]], [k[3], k[4]], [k[5], k[6]], [k[7], ("key", "x")]]

    # --- the picture ----------------------------------------------------------------------------
    def _use(self, settings: Settings) -> None:
        self.settings = settings
        if settings not in self.renders:
            if len(self.renders) >= 16:
                self.renders.pop(next(iter(self.renders)))
            self.renders[settings] = _Render(self.scene_for(settings), np.zeros((self.height, self.width, 3)))
        self.render = self.renders[settings]
        self._frame = None

    def scene_for(self, s: Settings) -> tracescene.TraceScene:
        """The traced scene under ``s``: materials and limits changed, the geometry and hierarchy shared, counters 0."""
        ts = dataclasses.replace(self.base, max_depth=s.depth, min_weight=self.opts.min_weight if s.cutoff else 0.0,
                                 counters={k: 0 for k in tracescene.COUNTERS})
        if not s.reflection:
            ts.mat_reflectance = np.zeros_like(ts.mat_reflectance)
            ts.mat_fresnel = np.zeros_like(ts.mat_fresnel)
        if not s.refraction:
            ts.mat_transmittance = np.zeros_like(ts.mat_transmittance)
        return ts

    def _switched(self, s: Settings, extra: dict[str, Callable] | None = None) -> AbstractContextManager:
        wrappers = dict(extra or {})
        if not s.shadows:
            wrappers["W7"] = lambda own: _all_light
        return functions_replaced(W.STAGE, self.tracer, wrappers) if wrappers else nullcontext()

    def _trace(self, r: _Render, pixels: np.ndarray, first: np.ndarray, block: int) -> None:
        rays = (first[:, None] + self.sub_rays[None, :]).ravel()
        with self._switched(self.settings):
            colours = W.STAGE.call(self.tracer, "W11", r.scene, self.origins[rays], self.directions[rays])
        colours = colours.reshape(len(pixels), self.k ** 2, 3).mean(axis=1)
        y, x = np.divmod(pixels, self.width)
        for dy in range(block):          # each pixel paints its block until finer passes fill it in
            for dx in range(block):
                r.image[np.minimum(y + dy, self.height - 1), np.minimum(x + dx, self.width - 1)] = colours

    def image(self) -> np.ndarray:
        """The current picture, linear (h, w, 3): the finished render once :meth:`busy` is False."""
        return self.render.image

    # --- one pixel's ray tree -------------------------------------------------------------------
    def ray_tree(self, x: int, y: int) -> RayTree:
        """Trace pixel (x, y)'s camera ray (its middle sample) with the submission's W11, recording its W5 and W7."""
        self.ready()
        ray = (y * self.k + self.k // 2) * self.width * self.k + x * self.k + self.k // 2
        hits: list[list[np.ndarray]] = []
        shadows: list[list[np.ndarray]] = []
        extra = {"W5": lambda own: _recorded(own, hits, (3, 3, 0, 0, 3))}
        if self.settings.shadows:
            extra["W7"] = lambda own: _recorded(own, shadows, (3, 3, 3))
        ts = self.scene_for(self.settings)
        with self._switched(self.settings, extra):
            W.STAGE.call(self.tracer, "W11", ts, self.origins[ray:ray + 1], self.directions[ray:ray + 1])
        traced = build_tree(hits, shadows, self.reach)
        rays = [r for r in traced if r.kind != "shadow"]
        lights = [(r.start, r.end, float(np.max(r.through))) for r in traced if r.kind == "shadow"]
        self._frame = None
        return RayTree((x, y), rays, lights, dict(ts.counters))

    def _draw_tree(self, image: np.ndarray, tree: RayTree) -> np.ndarray:
        from PIL import Image, ImageDraw
        z = self.zoom
        picture = Image.fromarray(image)
        draw = ImageDraw.Draw(picture)
        x, y = tree.pixel
        draw.rectangle((x * z - 3, y * z - 3, (x + 1) * z + 2, (y + 1) * z + 2), outline=(255, 255, 255), width=2)
        if not self.camera.ok:
            return np.asarray(picture)

        def line(a: np.ndarray, b: np.ndarray, colour: tuple[int, int, int], width: int) -> None:
            seg = self.camera.segment(a, b)
            if seg is not None:
                (x0, y0), (x1, y1) = seg
                pts = [(x0 * z, y0 * z), (x1 * z, y1 * z)]
                draw.line(pts, fill=(0, 0, 0), width=width + 2)
                draw.line(pts, fill=colour, width=width)

        for start, target, passed in tree.shadows:
            line(start, target, SHADOW_COLOURS[tree.shadow_state(passed)], 2)
        for ray in tree.rays:
            if ray.kind != "camera":
                line(ray.start, ray.end, RAY_COLOURS[ray.kind], 3)
        for ray in tree.rays:
            p = self.camera.point(ray.end) if ray.hit else None
            if p is not None:
                px, py = p[0] * z, p[1] * z
                draw.ellipse((px - 4, py - 4, px + 4, py + 4), fill=RAY_COLOURS[ray.kind], outline=(0, 0, 0))
        return np.asarray(picture)

    def default_pixel(self) -> tuple[int, int]:
        """A pixel with a tree worth showing: beside the middle of the first glass sphere (else a mirror, else the
        image's middle), off its centre so that the refracted rays bend."""
        self.ready()
        for want in ("mat_transmittance", "mat_reflectance"):
            for obj in self.scene.objects:
                if isinstance(obj, Sphere):
                    index = self.base.material_names.index(obj.material)
                    if np.any(getattr(self.base, want)[index] > 0):
                        c, up = np.asarray(obj.center, float), np.asarray(self.scene.camera.up, float)
                        p, q = self.camera.point(c), self.camera.point(c + obj.radius * up / np.linalg.norm(up))
                        if p is not None and q is not None:
                            r = math.hypot(q[0] - p[0], q[1] - p[1])
                            x, y = int(p[0] - 0.35 * r), int(p[1] - 0.35 * r)
                            if 0 <= x < self.width and 0 <= y < self.height:
                                return x, y
        return self.width // 2, self.height // 2

    def _caption(self) -> list[str]:
        r, s = self.render, self.settings
        if r.pos < len(self.order):
            level = r.level if r.pos > (self.ends[r.level - 1] if r.level else 0) else r.level - 1
            progress = f"refining: {r.pos / len(self.order):.0%} traced, blocks of {self.blocks[max(level, 0)]} px"
        else:
            progress = f"done: {self.width}x{self.height}"
        switches = (f"shadows {'on' if s.shadows else 'off'}, reflection {'on' if s.reflection else 'off'}, "
                    f"refraction {'on' if s.refraction else 'off'}, cut-off "
                    f"{f'β = {self.opts.min_weight:g}' if s.cutoff else 'off'}, depth {s.depth}")
        c = r.scene.counters
        rays = (f"rays: {c['camera']:,} camera, {c['reflection']:,} reflection, {c['transmission']:,} transmission, "
                f"{c['shadow']:,} shadow")
        tree = self.tree.summary() if self.tree is not None else ["click a pixel: its ray tree", ""]
        return [f"whitted · {self.scene.name} · {progress}", switches, rays, *tree, LEGEND]


def demo(module: ModuleType, output: Path, window: bool, frames: int | None, scene: str | Path = "whitted",
         size: tuple[int, int] | None = None, screenshot: Path | None = None, fullscreen: bool = False) -> list[Path]:
    """In a window: the picture refining, the switches and a clicked pixel's ray tree. Headless: the script's frames
    (the refinement, a ray tree, each switch off in turn, all back on) as PNGs and ``whitted.gif``."""
    return play(WhittedDemo(module, scene, size), window=window, frames=frames, output=output, screenshot=screenshot,
                fullscreen=fullscreen)
