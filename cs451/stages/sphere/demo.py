"""Stage 1's demo: the course notes' window (500 × 500 at (100, 100), "Sphere", resizable), or its images.

Keys go through the student's S8 (q quits, s switches Gouraud/Phong, + and - change the
tessellation); the mesh is built once per tessellation, as the notes' display list was.
"""
from __future__ import annotations

from pathlib import Path
from typing import Any

from ...demos.window import Window
from ...imageio import save_png
from ...scene import load_scene
from .. import sphere as s1


def demo(module: Any, folder: Path, window: bool, frames: int | None) -> list[Path]:
    """The window, or three images where there is no display."""
    if window:
        _window(module, frames)
        return []
    scene = load_scene("sphere")
    shots = [("sphere-gouraud.png", None, "gouraud"), ("sphere-phong.png", None, "phong"),
             ("sphere-wide.png", (800, 400), "gouraud")]
    return [save_png(folder / name, s1.render(scene, module, size, shading=shading), scene.image.exposure,
                     scene.image.srgb) for name, size, shading in shots]


def _window(module: Any, frames: int | None) -> None:
    scene = load_scene("sphere")
    win = Window(scene.image.width, scene.image.height, "Sphere", position=(100, 100))
    try:
        state = s1.ViewState()
        renderers: dict[tuple, s1.SphereRenderer] = {}
        cam = scene.camera
        view = s1._look_at(module, cam.eye, cam.center, cam.up)
        model_views = s1._model_views(module, view, s1.drawing_calls(scene))
        while state.running and not win.done(frames):
            for key in win.keys():
                state = s1._key(module, key, state)
            tessellation = (state.shading, state.slices, state.stacks)
            if tessellation not in renderers:  # buffers built once per tessellation, like the notes' display list
                meshes = [s1._mesh(module, sp.radius, state.slices, state.stacks) for sp in s1.spheres(scene)]
                renderers[tessellation] = s1.SphereRenderer(win.ctx, s1._shaders(module, state.shading), meshes)
            width, height = win.size()
            viewport, projection = s1._reshape(module, width, height, cam)

            def draw() -> None:
                win.ctx.viewport = viewport
                renderers[tessellation].draw(scene, view, model_views, projection, s1.STAGE.options(scene).local_viewer)
            win.show(draw)
    finally:
        win.close()
