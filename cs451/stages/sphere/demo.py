"""Stage 1's demo: the course notes' window (500 × 500 at (100, 100), "Sphere", resizable), or its images.

Keys go through the student's S8 (q quits, s switches Gouraud/Phong, + and - change the
tessellation); the mesh is built once per tessellation, as the notes' display list was. The window
answers f (full screen) and h (help) itself, before S8 sees a key; a resize or full screen reaches the
picture through the student's S7 (the notes' reshape keeps the sphere's shape at any window size). The
caption says what is drawn, over the bottom of the picture, since S7 owns the whole window.
"""
from __future__ import annotations

from pathlib import Path
from typing import Any

from ...demos.controls import help_keys
from ...demos.overlay import HELP_SECONDS
from ...demos.player import Screen
from ...demos.window import Window
from ...imageio import save_png, to_uint8
from ...scene import Scene, load_scene
from .. import sphere as s1


def caption(scene: Scene, state: Any) -> str:
    """``sphere · orrery: Gouraud, 32×32 spheres (all 5)``: what the window draws, from S8's state."""
    n = len(s1.spheres(scene))
    what = "sphere" if n == 1 else f"spheres (all {n})"
    shading = "Phong" if state.shading == "phong" else "Gouraud"
    return f"sphere · {scene.name}: {shading}, {state.slices}×{state.stacks} {what}"


def demo(module: Any, folder: Path, window: bool, frames: int | None, scene: str | Path = "sphere",
         size: tuple[int, int] | None = None, screenshot: Path | None = None, fullscreen: bool = False) -> list[Path]:
    """The window, or three images where there is no display (as ``cs451 render`` draws them), with the
    captioned frames beside them (``sphere.gif``: Gouraud with the help panel, then Phong)."""
    loaded = load_scene(scene)
    s1.STAGE.check_scene(loaded)
    size = size or (loaded.image.width, loaded.image.height)
    s1.STAGE.check_cost(loaded, size)
    if window:
        _window(module, loaded, size, frames, screenshot, fullscreen)
        return []
    shots = [(f"{loaded.name}-gouraud.png", size, "gouraud"), (f"{loaded.name}-phong.png", size, "phong"),
             (f"{loaded.name}-wide.png", (800, 400), "gouraud")]
    screen = Screen(loaded.name, "Sphere", size, window=False, output=folder, stage="sphere")
    paths = []
    for k, (name, shot_size, shading) in enumerate(shots):
        image = s1.render(loaded, module, shot_size, shading=shading)
        paths.append(save_png(folder / name, image, loaded.image.exposure, loaded.image.srgb))
        if shot_size == size and (frames is None or len(screen.kept) < frames):
            screen.show(to_uint8(image, loaded.image.exposure, loaded.image.srgb),
                        caption(loaded, s1.ViewState(shading=shading)))
            screen.note(("key", "s"))             # the help is up until the first key, as in the window
    return paths + screen.close()


def _window(module: Any, scene: Scene, size: tuple[int, int], frames: int | None, screenshot: Path | None,
            fullscreen: bool) -> None:
    win = Window(size[0], size[1], "Sphere", position=(100, 100), keys=help_keys("sphere"), over_picture=True,
                 fullscreen=fullscreen, help_seconds=None if screenshot else HELP_SECONDS)
    try:
        state = s1.ViewState()
        renderers: dict[tuple, s1.SphereRenderer] = {}
        cam = scene.camera
        view = s1._look_at(module, cam.eye, cam.center, cam.up)
        model_views = s1._model_views(module, view, s1.drawing_calls(scene))
        wanted = frames if frames is not None else (2 if screenshot else None)
        while state.running and not win.done(wanted):
            for key in win.keys():
                state = s1._key(module, key, state)
            tessellation = (state.shading, state.slices, state.stacks)
            if tessellation not in renderers:  # buffers built once per tessellation, like the notes' display list
                meshes = [s1._mesh(module, sp.radius, state.slices, state.stacks) for sp in s1.spheres(scene)]
                renderers[tessellation] = s1.SphereRenderer(win.ctx, s1._shaders(module, state.shading), meshes)
            width, height = win.size()
            viewport, projection = s1._reshape(module, width, height, cam)
            win.caption = caption(scene, state)

            def draw() -> None:
                win.ctx.clear(0.0, 0.0, 0.0)
                win.ctx.viewport = viewport
                renderers[tessellation].draw(scene, view, model_views, projection, s1.STAGE.options(scene).local_viewer)
            win.show(draw)
        if screenshot is not None:
            win.screenshot(screenshot)
    finally:
        win.close()
