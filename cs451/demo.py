"""``cs451 demo``: the original program's window where there is a display, images where there is none.

The window is GLFW's (resizable; the keys of task S7: q quits, s switches shading,
+ and - change the tessellation). Everything drawn goes through the stage's
interface, so a lecturer can demo the reference or any submission.
"""
from __future__ import annotations

import os
from pathlib import Path
from typing import Any

from .errors import KitError
from .imageio import save_png
from .impl import load_impl, resolve_impl
from .scene import load_scene
from .stages import get_stage

GLFW_KEYS = {"ESCAPE": "escape", "EQUAL": "+", "KP_ADD": "+", "MINUS": "-", "KP_SUBTRACT": "-"}


def has_display() -> bool:
    return bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))


def run_demo(*, stage: str = "sphere", impl: str = "reference", output: str | Path = "demo",
             window: bool | None = None, frames: int | None = None) -> list[Path]:
    """Open the window (``window=None``: when there is a display) or write the demo's images to ``output``."""
    st = get_stage(stage)
    if st.demo is None:
        raise KitError(f"no demo for stage {stage!r} yet")
    show_window = window if window is not None else has_display()
    return st.demo(load_impl(resolve_impl(impl, stage), stage), Path(output), show_window, frames)


def sphere_demo(module: Any, folder: Path, window: bool, frames: int | None) -> list[Path]:
    """Stage 1's demo: the window, or three images where there is no display."""
    if window:
        _sphere_window(module, frames)
        return []
    return _sphere_images(module, folder)


def _sphere_images(module: Any, folder: Path) -> list[Path]:
    """Headless: the sphere in both shadings and at a wide aspect ratio, as the window would show them."""
    st = get_stage("sphere")
    scene = load_scene("sphere")
    shots = [("sphere-gouraud.png", None, "gouraud"), ("sphere-phong.png", None, "phong"),
             ("sphere-wide.png", (800, 400), "gouraud")]
    paths = []
    for name, size, shading in shots:
        paths.append(save_png(folder / name, st.render(scene, module, size, shading=shading)))
    return paths


def _sphere_window(module: Any, frames: int | None) -> None:
    try:
        import glfw
        import moderngl
    except ImportError as err:
        raise KitError(f"the demo window needs glfw ({err}); run ./setup.sh") from None
    from .stages import sphere as s1

    if not glfw.init():
        raise KitError("cannot open a window (glfw.init failed): is DISPLAY set? Use --no-window for images")
    try:
        glfw.window_hint(glfw.CONTEXT_VERSION_MAJOR, 3)
        glfw.window_hint(glfw.CONTEXT_VERSION_MINOR, 3)
        glfw.window_hint(glfw.OPENGL_PROFILE, glfw.OPENGL_CORE_PROFILE)
        scene = load_scene("sphere")
        win = glfw.create_window(scene.image.width, scene.image.height, "cs451 sphere (q quits, s shading, +/- tessellation)", None, None)
        if not win:
            raise KitError("cannot open a window (glfw.create_window failed); use --no-window for images")
        glfw.make_context_current(win)
        ctx = moderngl.create_context()
        state = s1.ViewState()
        renderers: dict[tuple, s1.SphereRenderer] = {}
        keys: list[str] = []

        def on_key(_w, key, _scancode, action, _mods):
            if action != glfw.PRESS:
                return
            name = glfw.get_key_name(key, 0) or ""
            for attr, label in GLFW_KEYS.items():
                if key == getattr(glfw, f"KEY_{attr}"):
                    name = label
            if name:
                keys.append(name)

        glfw.set_key_callback(win, on_key)
        cam = scene.camera
        view = s1._look_at(module, cam.eye, cam.center, cam.up)
        drawn = 0
        while not glfw.window_should_close(win) and state.running and (frames is None or drawn < frames):
            glfw.poll_events()
            for key in keys:
                state = module.handle_key(key, state)
            keys.clear()
            key = (state.shading, state.slices, state.stacks)
            if key not in renderers:  # buffers built once per tessellation, like a display list
                meshes = [s1._mesh(module, sp.radius, state.slices, state.stacks) for sp in s1.spheres(scene)]
                renderers[key] = s1.SphereRenderer(ctx, s1._shaders(module, state.shading), meshes)
            width, height = glfw.get_framebuffer_size(win)
            viewport, projection = s1._reshape(module, width, height, cam)
            ctx.screen.use()
            ctx.viewport = viewport
            renderers[key].draw(scene, view, projection, s1.options(scene).local_viewer)
            glfw.swap_buffers(win)
            drawn += 1
    finally:
        glfw.terminate()
