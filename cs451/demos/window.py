"""The demos' window: GLFW, an OpenGL 3.3 core context for moderngl, key names, and a frame count.

One window class for every stage: the sphere's (the notes' 500×500 window, resizable)
and the radiosity, ray tracing and hemicube demos' alike. Keys arrive as names (``"q"``, ``"+"``,
``"escape"``), which is what task S8 and the demos' own controls understand. A demo that makes
its frames as images (:mod:`.player`) has them drawn by :meth:`Window.blit`, scaled to the window
and letterboxed, and gets its clicks back in the frame's own pixels (:meth:`Window.frame_point`).
"""
from __future__ import annotations

import os
import sys
import time
from pathlib import Path
from typing import Any, Callable

import numpy as np

from ..errors import KitError

#: GLFW key codes with no printable name, as the kit names them (S8's table).
SPECIAL_KEYS = {"ESCAPE": "escape", "EQUAL": "+", "KP_ADD": "+", "MINUS": "-", "KP_SUBTRACT": "-",
                "LEFT": "left", "RIGHT": "right", "UP": "up", "DOWN": "down", "SPACE": "space"}

#: Draws a frame (an RGB8 texture) pixel for pixel: each window pixel takes the frame pixel it falls in.
BLIT_VERTEX = """#version 330
in vec2 in_corner;
void main() { gl_Position = vec4(in_corner, 0.0, 1.0); }
"""
BLIT_FRAGMENT = """#version 330
uniform sampler2D u_frame;
uniform vec2 u_origin;     // the frame's lower left corner in window pixels
uniform float u_scale;     // window pixels per frame pixel
out vec4 colour;
void main() {
    ivec2 size = textureSize(u_frame, 0);
    ivec2 p = ivec2(floor((gl_FragCoord.xy - u_origin) / u_scale));
    p = clamp(p, ivec2(0), size - 1);
    colour = vec4(texelFetch(u_frame, ivec2(p.x, size.y - 1 - p.y), 0).rgb, 1.0);   // image rows run top down
}
"""


class Window:
    """A GLFW window with its moderngl context; ``keys()`` drains the key presses since the last call."""

    def __init__(self, width: int, height: int, title: str, position: tuple[int, int] | None = None,
                 resizable: bool = True):
        try:
            import glfw
            import moderngl
        except ImportError as err:
            raise KitError(f"the demo window needs glfw ({err}); run ./setup.sh") from None
        if not glfw.init():
            raise KitError("cannot open a window (glfw.init failed): is DISPLAY set? Use --no-window for frames")
        glfw.window_hint(glfw.CONTEXT_VERSION_MAJOR, 3)
        glfw.window_hint(glfw.CONTEXT_VERSION_MINOR, 3)
        glfw.window_hint(glfw.OPENGL_PROFILE, glfw.OPENGL_CORE_PROFILE)
        glfw.window_hint(glfw.OPENGL_FORWARD_COMPAT, True)   # macOS asks for it
        glfw.window_hint(glfw.RESIZABLE, resizable)
        self.glfw = glfw
        self.win = glfw.create_window(int(width), int(height), title, None, None)
        if not self.win:
            glfw.terminate()
            raise KitError("cannot open a window (glfw.create_window failed); use --no-window for frames")
        if position is not None:
            glfw.set_window_pos(self.win, *position)
        glfw.make_context_current(self.win)
        self.ctx = moderngl.create_context()
        self._keys: list[str] = []
        self._clicks: list[tuple[float, float]] = []
        glfw.set_key_callback(self.win, self._on_key)
        glfw.set_mouse_button_callback(self.win, self._on_click)
        self.frames = 0
        self.closed = False
        self._blit: Any = None                 # program, quad and texture, made at the first blit
        self._placed: tuple[int, int, int, int, float] | None = None   # where the last frame went (x, y, w, h, scale)

    def _on_key(self, _win: Any, key: int, _scancode: int, action: int, _mods: int) -> None:
        if action != self.glfw.PRESS:
            return
        name = self.glfw.get_key_name(key, 0) or ""
        for attr, label in SPECIAL_KEYS.items():
            if key == getattr(self.glfw, f"KEY_{attr}", None):
                name = label
        if name:
            self._keys.append(name)

    def _on_click(self, _win: Any, button: int, action: int, _mods: int) -> None:
        if action == self.glfw.PRESS and button == self.glfw.MOUSE_BUTTON_LEFT:
            self._clicks.append(self.glfw.get_cursor_pos(self.win))

    def keys(self) -> list[str]:
        """Key names pressed since the last call (polls the window)."""
        self.glfw.poll_events()
        keys, self._keys = self._keys, []
        self.closed = self.closed or bool(self.glfw.window_should_close(self.win))
        return keys

    def clicks(self) -> list[tuple[float, float]]:
        """Left clicks since the last call, in window pixels from the top left."""
        clicks, self._clicks = self._clicks, []
        return clicks

    def size(self) -> tuple[int, int]:
        """The framebuffer's size in pixels (it may differ from the window's on high-DPI screens)."""
        return tuple(self.glfw.get_framebuffer_size(self.win))  # type: ignore[return-value]

    def frame_point(self, x: float, y: float) -> tuple[int, int] | None:
        """A click at window position (x, y) as a pixel (column, row) of the last blitted frame; None outside it."""
        if self._placed is None:
            return None
        wx, wy = self.glfw.get_window_size(self.win)
        fw, fh = self.size()
        sx, sy = fw / max(wx, 1), fh / max(wy, 1)                 # window units to framebuffer pixels (high DPI)
        left, bottom, w, h, scale = self._placed
        col = int((x * sx - left) // scale)
        row = int((y * sy - (fh - bottom - h * scale)) // scale)
        return (col, row) if 0 <= col < w and 0 <= row < h else None

    def blit(self, frame: np.ndarray) -> None:
        """Draw a uint8 RGB frame (h, w, 3) as large as the window allows, its shape kept (whole multiples when it
        fits at least once, so pixels stay square and sharp), on a dark background."""
        ctx = self.ctx
        h, w = frame.shape[:2]
        if self._blit is None:
            program = ctx.program(vertex_shader=BLIT_VERTEX, fragment_shader=BLIT_FRAGMENT)
            quad = ctx.buffer(np.array([-1, -1, 1, -1, -1, 1, 1, 1], dtype="f4").tobytes())
            self._blit = [program, ctx.vertex_array(program, [(quad, "2f", "in_corner")]), None, None]
        program, vao, texture, shown = self._blit
        if texture is None or texture.size != (w, h):
            if texture is not None:
                texture.release()
            texture = ctx.texture((w, h), 3, dtype="f1", alignment=1)
            texture.filter = (ctx.NEAREST, ctx.NEAREST)
            shown = None
        if shown is not frame:                             # the same frame again: no upload
            texture.write(np.ascontiguousarray(frame[..., :3], dtype=np.uint8).tobytes())
        self._blit[2:] = [texture, frame]
        fw, fh = self.size()
        scale = min(fw / w, fh / h)
        scale = float(int(scale)) if scale >= 1 else scale
        left, bottom = int((fw - w * scale) // 2), int((fh - h * scale) // 2)
        self._placed = (left, bottom, w, h, scale)
        ctx.viewport = (0, 0, fw, fh)
        ctx.clear(0.1, 0.1, 0.1)
        ctx.viewport = (left, bottom, int(round(w * scale)), int(round(h * scale)))
        texture.use(location=0)
        program["u_frame"].value = 0
        program["u_origin"].value = (float(left), float(bottom))
        program["u_scale"].value = scale
        vao.render(ctx.TRIANGLE_STRIP)

    def wait(self, seconds: float) -> None:
        """Sleep until an event arrives or ``seconds`` pass (an idle demo leaves the CPU alone)."""
        self.glfw.wait_events_timeout(seconds)

    def screenshot(self, path: str | Path) -> Path:
        """The window as the display shows it, as a PNG: grabbed from the X server where there is one (what a
        viewer sees, not what the program meant to draw), else read back from the framebuffer."""
        from PIL import Image
        self.ctx.finish()
        for _ in range(3):                                  # let the server take the last swap
            self.glfw.poll_events()
            time.sleep(0.1)
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        image = None
        if sys.platform.startswith("linux") and os.environ.get("DISPLAY"):
            from PIL import ImageGrab
            x, y = self.glfw.get_window_pos(self.win)
            w, h = self.glfw.get_window_size(self.win)
            try:
                image = ImageGrab.grab(bbox=(x, y, x + w, y + h), xdisplay=os.environ["DISPLAY"]).convert("RGB")
            except OSError:
                image = None
        if image is None:
            fw, fh = self.size()
            data = np.frombuffer(self.ctx.screen.read(viewport=(0, 0, fw, fh), components=3), dtype=np.uint8)
            image = Image.fromarray(np.flipud(data.reshape(fh, fw, 3)))
        image.save(path)
        return path

    def show(self, draw: Callable[[], Any]) -> None:
        """Draw one frame into the window and swap it in."""
        self.glfw.make_context_current(self.win)   # an engine may have made its own context current since
        self.ctx.screen.use()
        draw()
        self.glfw.swap_buffers(self.win)
        self.frames += 1
        self.closed = self.closed or bool(self.glfw.window_should_close(self.win))

    def done(self, frames: int | None) -> bool:
        """Closed by the user, or shown ``frames`` frames (a scripted demo)."""
        return self.closed or (frames is not None and self.frames >= frames)

    def close(self) -> None:
        self.glfw.terminate()
