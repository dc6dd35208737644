"""Stage 5's demo: the picture converging pass by pass, one path per pixel a pass, with the sample count, the
paths' mean length and the keys on screen.

Everything the submission computes is reached through the stage interface (its camera rays and P4, every answer
checked). ``d`` shows the direct light alone (every path ends after its first bounce: ``scene.max_depth`` 1), so the
room sees what the bounces add; ``r`` starts again; space pauses. Headless, the frames after 1, 2, 4, 8, … samples
per pixel, then the direct light alone, as PNGs and ``pathtrace.gif``.
"""
from __future__ import annotations

import math
import time
from pathlib import Path
from types import ModuleType
from typing import Iterator

import numpy as np

from ...demos.player import Event, Prepared, play
from ...imageio import to_uint8
from ...scene import load_scene
from .. import pathtrace as P

#: Frames are at least this wide: a small image is shown with each pixel as a square of pixels.
MIN_FRAME_WIDTH = 512
#: Passes a headless run shows (1, 2, 4, … samples per pixel up to this).
SCRIPT_SPP = 16


class PathDemo(Prepared):
    """The running mean of the passes so far, for the whole picture or for the direct light alone."""
    name = "pathtrace"
    caption_lines = 1

    def __init__(self, module: ModuleType, scene: str | Path = "cornell-box", size: tuple[int, int] | None = None):
        self.scene = load_scene(scene)
        P.STAGE.check_scene(self.scene)
        self.width, self.height = size or (128, 128)
        P.STAGE.check_cost(self.scene, (self.width, self.height))
        self.title = f"cs451 pathtrace: {self.scene.name}"
        self.module = module
        self.zoom = max(1, math.ceil(MIN_FRAME_WIDTH / self.width))
        self.opts = P.STAGE.options(self.scene)
        self.direct_only = False
        self.paused = False
        self.target = self.opts.spp * 64           # a live window refines far past the render's default
        self._frame: np.ndarray | None = None

    def _preparing(self) -> Iterator[str]:
        yield "the scene's paths"
        self._restart()

    def _restart(self) -> None:
        self.paths = P.prepare(self.scene, max_depth=1 if self.direct_only else None)
        self.rng = np.random.default_rng(self.opts.seed)
        self.total = np.zeros((self.width * self.height, 3))
        self.passes = 0
        self.seconds = 0.0
        self._frame: np.ndarray | None = None

    # --- the player's interface ---------------------------------------------------------------
    def frame_size(self) -> tuple[int, int]:
        """(width, height): the image with each pixel drawn as a ``zoom`` × ``zoom`` square, at least 512 wide."""
        return self.width * self.zoom, self.height * self.zoom

    def busy(self) -> bool:
        """Whether another pass is due: not paused, and fewer passes than the target."""
        self.ready()
        return not self.paused and self.passes < self.target

    def handle(self, event: Event) -> None:
        """Space pauses or resumes, r starts again, d toggles the direct light alone (and starts again); clicks do
        nothing."""
        self.ready()
        if event[0] != "key":
            return
        if event[1] in (" ", "space"):
            self.paused = not self.paused
        elif event[1] == "r":
            self._restart()
        elif event[1] == "d":
            self.direct_only = not self.direct_only
            self._restart()
        self._frame = None

    def step(self, seconds: float) -> bool:
        """One pass (a path per pixel); True when the sample count reaches a power of two (a frame worth keeping)."""
        self.ready()
        started = time.perf_counter()
        o, d = P.pixel_rays(self.module, self.scene.camera, self.width, self.height,
                             self.rng.random((self.width * self.height, 2)))
        self.total += P.STAGE.call(self.module, "P4", self.paths, o, d, self.rng)
        self.passes += 1
        self.seconds += time.perf_counter() - started
        self._frame = None
        return self.passes & (self.passes - 1) == 0

    def image(self) -> np.ndarray:
        """The running mean, linear radiance (h, w, 3)."""
        return (self.total / max(self.passes, 1)).reshape(self.height, self.width, 3)

    def frame(self) -> np.ndarray:
        """The running mean, tone-mapped and zoomed, made once per pass and kept until the next."""
        self.ready()
        if self._frame is None:
            image = to_uint8(self.image(), self.scene.image.exposure, self.scene.image.srgb)
            self._frame = np.repeat(np.repeat(image, self.zoom, axis=0), self.zoom, axis=1)
        return self._frame

    def caption(self) -> str:
        """One line: samples per pixel, all bounces or direct light only, mean bounces a path, passes a second."""
        self.ready()
        return "\n".join(self._caption())

    def script(self) -> list[list[Event]]:
        """Converge to SCRIPT_SPP samples per pixel; then the direct light alone, as far."""
        self.target = SCRIPT_SPP
        return [[], [("key", "d")]]

    def _caption(self) -> list[str]:
        c = self.paths.counters
        length = (c["bounce"] / c["camera"]) if c["camera"] else 0.0
        what = "direct light only (d)" if self.direct_only else "all bounces"
        rate = f", {self.passes / self.seconds:.1f} passes/s" if self.seconds > 0 else ""
        return [f"pathtrace · {self.scene.name}: {self.passes} samples per pixel · {what} · {length:.2f} bounces a path{rate}"
                + (" · paused" if self.paused else "")]


def demo(module: ModuleType, output: Path, window: bool, frames: int | None, scene: str | Path = "cornell-box",
         size: tuple[int, int] | None = None, screenshot: Path | None = None, fullscreen: bool = False) -> list[Path]:
    """In a window: the picture converging, until q. Headless: the frames at 1, 2, 4, … samples per pixel, then the
    direct light alone, as PNGs and ``pathtrace.gif``."""
    return play(PathDemo(module, scene, size), window=window, frames=frames, output=output, screenshot=screenshot,
                fullscreen=fullscreen)
