"""Stage 4's demo: progressive refinement shot by shot, paused, stepped and started again, with the patch that just
shot outlined and the energy left to shoot as a number and a bar.

The shooting loop is the submission's own R3, run one shot at a time (:class:`cs451.stages.radiosity.stepping.Stepper`: the
loop in a thread, held at each ``on_shot``, its rows drawn by stage 3's hemicube engine in the demo's thread and
context). What is drawn is the submission's too: R5's vertex colours, Gouraud-shaded (``g`` shows each patch flat,
its own B, to see what R5's interpolation adds), plus ρ·ambient (R4) while the ambient preview is on (``a``), the
notes' display of a solution in progress. The scene's exposure and encoding (sRGB for the Cornell box) are applied
as the picture is drawn; a scene with glossy materials (``glossy-box``) shows their highlight (:mod:`cs451.stages.radiosity.highlight`)
in the Gouraud display, as ``cs451 render`` does.
"""
from __future__ import annotations

import math
import time
from pathlib import Path
from types import ModuleType
from typing import Any, Callable, Iterator

import numpy as np

from ...demos.player import Event, Prepared, play
from .display import GouraudDrawer, camera_matrix, flat_corners, with_highlight
from ...imageio import to_uint8
from ...scene import Scene, load_scene
from .solvers import energy
from .stepping import Stepper
from .. import radiosity as R

#: The picture is drawn at least this tall (the scene's size times a whole factor): it is shown scaled to the screen.
MIN_HEIGHT = 480
#: What outlines the patch that just shot, and fills the bar of energy left to shoot.
SHOOTER = (0, 235, 255)
BAR = (255, 170, 40)


def default_size(scene: Scene) -> tuple[int, int]:
    """The scene's image size, times the whole factor that makes it at least MIN_HEIGHT tall."""
    w, h = scene.image.width, scene.image.height
    k = max(1, math.ceil(MIN_HEIGHT / h))
    return w * k, h * k


def percent(x: float) -> str:
    """``3.1%``, or two significant digits under 1% (``0.042%``)."""
    return f"{100 * x:.1f}%" if abs(x) >= 0.01 or x == 0 else f"{100 * x:.2g}%"


class _AskedRows:
    """The hemicube engine's rows as the shooting loop's thread sees them: each asked of the demo's thread."""

    def __init__(self, rows: Any, ask: Callable[..., Any]):
        self._rows, self._ask = rows, ask

    def row(self, i: int) -> np.ndarray:
        return self._ask(self._rows.row, i)

    def rows(self, indices: Any) -> np.ndarray:
        return self._ask(self._rows.rows, list(indices))

    def has_row(self, i: int) -> bool:
        return self._rows.has_row(i)       # a look-up in a dict: safe from the loop's thread


class RadiosityDemo(Prepared):
    """The demo's state: the patches, the loop (running, paused, stepped), the last shot and how it is drawn."""
    name = "radiosity"
    caption_lines = 3
    smooth = True

    def __init__(self, module: ModuleType, scene: str | Path = "cornell-box", size: tuple[int, int] | None = None):
        self.scene = load_scene(scene)
        R.STAGE.check_scene(self.scene)
        self.opts = R.STAGE.options(self.scene)
        self.width, self.height = size or default_size(self.scene)
        R.STAGE.check_cost(self.scene, (self.width, self.height))
        self.module, self.calls = module, R.calls(module)
        self.title = f"cs451 radiosity: {self.scene.name}"
        self.bar = max(10, self.height // 24)
        self.paused = self.flat = False
        self.ambient = True
        self.wanted = 0                       # shots asked for one at a time (n) while paused
        self.stepper: Stepper | None = None
        self._frame: np.ndarray | None = None

    def _preparing(self) -> Iterator[str]:
        yield "the patches (R1)"
        self.patches = p = R.make_patches(self.scene, self.module, self.opts.patch_size)
        gloss = R.glossy.highlight(self.scene, p, self.opts.specular_samples) if self.opts.specular else None
        self.gloss = gloss.scaled(self.opts.exposure) if gloss is not None else None
        yield "the form-factor engine (stage 3's hemicubes)"
        self.drawer = GouraudDrawer(self._ctx)
        self.rows = R.hemicube_formfactors(p.quads, self.opts.resolution, self.opts.proximity, ctx=self.drawer.ctx,
                                           batch=R.ROWS_PER_BATCH)
        self.mvp = camera_matrix(self.scene, self.width, self.height, R.camera_view(self.scene))
        self.emitted = energy(p.emission, p.areas)
        # with every patch reflecting all of a colour, R = 1/(1 - ρ_avg) is infinite: no ambient term (as solvers)
        self.ambient_defined = not np.all(p.reflectance >= 1.0, axis=0).any()
        self._reset()

    def _reset(self) -> None:
        if self.stepper is not None:
            self.stepper.stop()
        self.stepper = None
        p = self.patches
        self.B, self.dB = p.emission.copy(), p.emission.copy()
        self.shots, self.shooter, self.shot_power = 0, None, 0.0
        self.done, self.reported, self._frame = False, -1, None

    def _run(self, ask: Callable[..., Any], on_step: Callable[..., None]) -> Any:
        """In the loop's thread: the submission's R3 on the engine's rows, held after each shot."""
        p, o = self.patches, self.opts

        def on_shot(shots: int, i: int, radiosity: np.ndarray, unshot: np.ndarray) -> None:
            on_step(int(shots), int(i), np.array(radiosity, dtype=np.float64), np.array(unshot, dtype=np.float64))
        return R.solve_progressive(self.module, _AskedRows(self.rows, ask), p.areas, p.reflectance, p.emission,
                                   o.tolerance, o.max_shots, o.overshoot, False, on_shot, rows_ahead=R.ROWS_PER_BATCH - 1)

    # --- the player's interface ---------------------------------------------------------------
    def frame_size(self) -> tuple[int, int]:
        """(width, height): the picture, with the bar of energy left to shoot under it."""
        return self.width, self.height + self.bar

    def busy(self) -> bool:
        """Whether there is work: the first frame not yet kept, or shots left while running, or shots asked for
        (n) while paused."""
        self.ready()
        return self.reported < 0 or (not self.done and (not self.paused or self.wanted > 0))

    def handle(self, event: Event) -> None:
        """Space pauses or resumes, n or → asks for one more shot (paused), r starts again, g toggles flat patches,
        a the ambient preview; clicks do nothing."""
        self.ready()
        if event[0] != "key":
            return
        key = event[1]
        if key == "space":
            self.paused, self.wanted = not self.paused, 0
        elif key in ("n", "right"):
            self.paused, self.wanted = True, self.wanted + 1
        elif key == "r":
            self._reset()
        elif key == "g":
            self.flat = not self.flat
        elif key == "a":
            self.ambient = not self.ambient
        self._frame = None

    def step(self, seconds: float) -> bool:
        """Shots for about ``seconds`` (one, when stepping); True at 0, 1, 2, 4, … shots (a frame worth keeping)."""
        self.ready()
        if self.reported < 0:
            self.reported = 0
            return True
        stop = time.perf_counter() + seconds
        while not self.done and (not self.paused or self.wanted > 0):
            if self.stepper is None:
                self.stepper = Stepper(self._run)
            state = self.stepper.advance(max(0.0, stop - time.perf_counter()))
            if state is None:
                if self.stepper.finished:
                    sol = self.stepper.result
                    self.B, self.dB, self.shots, self.done = sol.radiosity, sol.unshot, len(sol.order), True
                    self._frame = None
                    return self.shots > self.reported
                return False
            shots, i, B, dB = state
            self.shot_power = float(np.abs(self.dB[i]).sum() * self.patches.areas[i]) / max(self.emitted, 1e-300)
            self.shots, self.shooter, self.B, self.dB, self._frame = shots, i, B, dB, None
            self.wanted = max(0, self.wanted - 1)
            if shots & (shots - 1) == 0:
                self.reported = shots
                return True
            if time.perf_counter() >= stop:
                break
        return False

    def unshot(self) -> float:
        """The energy left to shoot, over the energy emitted."""
        return energy(self.dB, self.patches.areas) / self.emitted if self.emitted > 0 else 0.0

    def display(self) -> np.ndarray:
        """What each patch shows: B, plus ρ·ambient (R4) while the preview is on."""
        p = self.patches
        if self.ambient and self.ambient_defined:
            return self.B + p.reflectance * self.calls.ambient(p.areas, p.reflectance, self.dB)
        return self.B

    def frame(self) -> np.ndarray:
        """The current picture, drawn once per change (a shot, a key) and kept until the next."""
        self.ready()
        if self._frame is None:
            self._frame = self._draw()
        return self._frame

    def _draw(self) -> np.ndarray:
        from PIL import Image, ImageDraw
        p, values, shine = self.patches, self.display(), None
        if self.flat:
            positions, colours, corners = flat_corners(p.quads, p.parent, values)
        else:
            positions, colours, corners = self.calls.corner_colors(p.quads, p.parent, values)
            if self.gloss is not None:
                positions, colours, corners, shine = with_highlight(positions, colours, corners, self.gloss)
        image = self.drawer.draw(positions, colours * (self.opts.exposure / math.pi), corners, self.mvp, self.width,
                                 self.height, self.scene.image.background, highlight=shine)
        picture = np.full((self.height + self.bar, self.width, 3), 40, np.uint8)
        picture[:self.height] = to_uint8(image, self.scene.image.exposure, self.scene.image.srgb)
        filled = int(round(self.width * min(1.0, self.unshot())))
        picture[self.height + 2:self.height + self.bar - 2, :filled] = BAR
        if self.shooter is not None:
            outline = self._projected(p.quads[self.shooter])
            if outline is not None:
                canvas = Image.fromarray(picture)
                width = max(2, self.height // 160)
                ImageDraw.Draw(canvas).polygon(outline, outline=(0, 0, 0), width=width + 2)
                ImageDraw.Draw(canvas).polygon(outline, outline=SHOOTER, width=width)
                picture = np.asarray(canvas)
        return picture

    def _projected(self, quad: np.ndarray) -> list[tuple[float, float]] | None:
        """A patch's corners in picture pixels (None when one is behind the camera)."""
        clip = np.c_[quad, np.ones(len(quad))] @ self.mvp.T
        if np.any(clip[:, 3] <= 1e-9):
            return None
        ndc = clip[:, :2] / clip[:, 3:]
        return [(float((x + 1) / 2 * self.width), float((1 - y) / 2 * self.height)) for x, y in ndc]

    def caption(self) -> str:
        """Three lines: the scene and what is drawn; the last shot and the loop's state; the unshot energy against
        R3's tolerance."""
        self.ready()
        p = self.patches
        state = "converged" if self.done else ("paused" if self.paused else "shooting")
        shown = ("flat patches" if self.flat else "Gouraud (R5)") + (", B + ρ·ambient (R4)" if self.ambient else ", B")
        if self.shooter is None:
            last = "no shot yet: B is the emitted light"
        else:
            last = f"patch {self.shooter} ({p.labels[p.parent[self.shooter]]}) shot {percent(self.shot_power)} of the power"
        return (f"radiosity · {self.scene.name}, {len(p)} patches · {shown}\n"
                f"shot {self.shots} ({state}): {last}\n"
                f"unshot energy {percent(self.unshot())} (the bar; R3 stops at {percent(self.opts.tolerance)})")

    def script(self) -> list[list[Event]]:
        """Shoot to the end (a frame at 0, 1, 2, 4, … shots); flat; from the start again, paused; two shots stepped;
        the ambient preview off; Gouraud again."""
        return [[], [("key", "g")], [("key", "r"), ("key", "space")], [("key", "n")], [("key", "n")],
                [("key", "a")], [("key", "g")]]

    def close(self) -> None:
        """Stop the shooting loop's thread, where one is running (:func:`demo` calls it once play ends)."""
        if self.stepper is not None:
            self.stepper.stop()


def demo(module: ModuleType, output: Path, window: bool, frames: int | None, scene: str | Path = "cornell-box",
         size: tuple[int, int] | None = None, screenshot: Path | None = None, fullscreen: bool = False) -> list[Path]:
    """In a window: the shots as they go, until q. Headless: the script's frames (the shots to the end, then flat
    patches, two shots stepped from the start, the ambient preview off) as PNGs and ``radiosity.gif``."""
    shown = RadiosityDemo(module, scene, size)
    try:
        return play(shown, window=window, frames=frames, output=output, screenshot=screenshot, fullscreen=fullscreen)
    finally:
        if shown._steps is not None:
            shown.close()
