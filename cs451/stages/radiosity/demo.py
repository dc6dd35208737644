"""Stage 4's demo: B beside B + ρ·ambient as the shots go by, in a window or as captioned frames and a GIF.

Everything goes through the stage interface (the submission's R1, R3, R4 and R5) and the shared
screen (:class:`cs451.demos.player.Screen`: the window or the frames and GIF, q and --frames). The window
shows what the frames show: the scene's exposure and encoding (sRGB for the Cornell box) are
applied as the panels are drawn, not left linear. A scene with glossy materials (``glossy-box``) shows their
highlight (:mod:`cs451.specular`) on both panels, as ``cs451 render`` does.
"""
from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from ...demos.player import Closed, Screen
from ...drawing import GouraudDrawer, camera_matrix, with_highlight
from ...imageio import to_uint8
from ...scene import load_scene
from .. import radiosity as R


def demo_shots(total_hint: int, frames: int | None) -> list[int]:
    """Shots after which to show a frame: 0, 1, 2, 4, 8, … (the picture changes fastest early on)."""
    shots = [0] + [2 ** k for k in range(0, 40) if 2 ** k <= max(total_hint, 1)]
    return shots[:frames] if frames else shots


def demo(module: Any, output: Path, window: bool, frames: int | None, scene_name: str = "cornell-box",
         size: tuple[int, int] = (256, 256)) -> list[Path]:
    """Headless: frames (B alone | B + ρ·ambient) after 0, 1, 2, 4, … shots, as PNGs and one animated GIF."""
    scene = load_scene(scene_name)
    opts = R.STAGE.options(scene)
    calls = R.calls(module)
    patches = R.make_patches(scene, module, opts.patch_size)
    wanted = set(demo_shots(50 * len(patches), frames))
    width, height = size
    mvp = camera_matrix(scene, width, height, R.camera_view(scene))
    a, rho = patches.areas, patches.reflectance
    screen = Screen("radiosity", "cs451 radiosity: B | B + ambient", (2 * width, height), window=window,
                    frames=frames, output=output)
    win = screen.win
    drawer = GouraudDrawer(screen.ctx)
    rows = R.hemicube_formfactors(patches.quads, opts.resolution, opts.proximity, ctx=drawer.ctx, batch=R.ROWS_PER_BATCH)
    encoding = (scene.image.exposure, scene.image.srgb)
    gloss = R.glossy.highlight(scene, patches, opts.specular_samples) if opts.specular else None
    gloss = gloss.scaled(opts.exposure) if gloss is not None else None     # the highlight on both panels

    def panels(B: np.ndarray, dB: np.ndarray) -> list[np.ndarray]:
        out = []
        for k, values in enumerate((B, B + rho * calls.ambient(a, rho, dB))):
            positions, colors, corners = calls.corner_colors(patches.quads, patches.parent, values)
            shine = None
            if gloss is not None:
                positions, colors, corners, shine = with_highlight(positions, colors, corners, gloss)
            scaled = colors * (opts.exposure / math.pi)
            if win is not None:
                drawer.draw(positions, scaled, corners, mvp, width, height, scene.image.background, win.ctx.screen,
                            viewport=(k * width, 0, width, height), encoding=encoding, highlight=shine)
            else:
                out.append(drawer.draw(positions, scaled, corners, mvp, width, height, scene.image.background,
                                       highlight=shine))
        return out

    def show(shots: int, B: np.ndarray, dB: np.ndarray, last: bool = False) -> None:
        if win is None:
            screen.show(to_uint8(np.hstack(panels(B, dB)), *encoding),
                        f"{'the answer: ' if last else ''}{shots} shots — left: B, right: B + ρ·ambient")
        else:
            screen.show(draw=lambda: panels(B, dB))      # raises Closed: q, closed, or --frames shown

    try:                                            # between frames, each shot polls the window: q still quits
        show(0, patches.emission.copy(), patches.emission.copy())
        sol = R.solve_progressive(module, rows, a, rho, patches.emission, opts.tolerance, opts.max_shots, opts.overshoot,
                                  True, lambda shots, i, B, dB: show(shots, B, dB) if shots in wanted else screen.events(),
                                  rows_ahead=R.ROWS_PER_BATCH - 1)
        if win is None:
            show(len(sol.order), sol.radiosity, sol.unshot, last=True)
        else:                                       # the answer stays up until the window is closed
            while True:
                show(len(sol.order), sol.radiosity, sol.unshot)
                screen.wait()                       # idle: sleep until an event, not spin
    except Closed:
        pass
    finally:
        written = screen.close()
    return written
