"""The demos' window: GLFW, an OpenGL 3.3 core context for moderngl, key names, full screen, and the overlay.

One window class for every stage: the sphere's (the notes' 500×500 window, resizable)
and the radiosity, ray tracing, hemicube and path tracing demos' alike. Keys arrive as names (``"q"``, ``"+"``,
``"escape"``), which is what task S8 and the demos' own controls understand. The window answers three keys
itself, in every demo: ``f`` (full screen on the monitor it is on, and back), ``h`` or ``?`` (the help panel).
Every frame ends with the overlay (:mod:`.overlay`): the caption band at the bottom and, for the first seconds or
until a key is pressed, the help panel, drawn at the window's own resolution (text stays sharp and at least 24 px
however the picture is scaled). A demo that makes its frames as images (:mod:`.player`) has them drawn by
:meth:`Window.blit`, scaled to fit above the band with their shape kept (letterboxed), and gets its clicks back in
the picture's own pixels (:meth:`Window.frame_point`).
"""
from __future__ import annotations

import os
import sys
import time
from pathlib import Path
from typing import Any, Callable, Sequence

import numpy as np

from ..errors import KitError
from . import overlay

#: GLFW key codes with no printable name, as the kit names them (S8's table).
SPECIAL_KEYS = {"ESCAPE": "escape", "EQUAL": "+", "KP_ADD": "+", "MINUS": "-", "KP_SUBTRACT": "-",
                "LEFT": "left", "RIGHT": "right", "UP": "up", "DOWN": "down", "SPACE": "space"}

VERTEX = """#version 330
in vec2 in_corner;
void main() { gl_Position = vec4(in_corner, 0.0, 1.0); }
"""
#: Draws a picture (RGB8) scaled by u_scale: the nearest pixel, or interpolated (u_smooth) for a rendered picture.
BLIT_FRAGMENT = """#version 330
uniform sampler2D u_frame;
uniform vec2 u_origin;     // the picture's lower left corner in window pixels
uniform float u_scale;     // window pixels per picture pixel
uniform bool u_smooth;
out vec4 colour;
void main() {
    ivec2 size = textureSize(u_frame, 0);
    vec2 at = (gl_FragCoord.xy - u_origin) / u_scale;
    if (u_smooth) {
        colour = vec4(texture(u_frame, vec2(at.x / size.x, 1.0 - at.y / size.y)).rgb, 1.0);
    } else {
        ivec2 p = clamp(ivec2(floor(at)), ivec2(0), size - 1);
        colour = vec4(texelFetch(u_frame, ivec2(p.x, size.y - 1 - p.y), 0).rgb, 1.0);   // image rows run top down
    }
}
"""
#: Draws an overlay layer (RGBA8) pixel for pixel, blended over what is there.
LAYER_FRAGMENT = """#version 330
uniform sampler2D u_layer;
uniform vec2 u_origin;
out vec4 colour;
void main() {
    ivec2 size = textureSize(u_layer, 0);
    ivec2 p = clamp(ivec2(gl_FragCoord.xy - u_origin), ivec2(0), size - 1);
    colour = texelFetch(u_layer, ivec2(p.x, size.y - 1 - p.y), 0);
}
"""


class Window:
    """A GLFW window with its moderngl context; ``keys()`` drains the key presses since the last call.

    ``keys``: the help panel's (key, what) rows; ``caption_lines``: the band's height in lines (it grows for a
    longer caption); ``over_picture``: the band is blended over the bottom of the picture (a demo drawing the
    whole window itself, stage 1) instead of under it; ``help_seconds``: the help hides after that long (None:
    only on a key, as a scripted run wants); ``fullscreen``: open full screen.
    """

    def __init__(self, width: int, height: int, title: str, position: tuple[int, int] | None = None,
                 resizable: bool = True, *, keys: Sequence[tuple[str, str]] = (), caption_lines: int = 1,
                 over_picture: bool = False, help_seconds: float | None = overlay.HELP_SECONDS,
                 fullscreen: bool = False):
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
        self.caption = ""
        self.help_keys = list(keys)
        self.help_shown = bool(self.help_keys)
        self._help_until = time.monotonic() + help_seconds if help_seconds is not None else None
        self.caption_lines, self.over_picture = caption_lines, over_picture
        self._windowed: tuple[int, int, int, int] | None = None    # position and size before full screen
        self._gl: dict[str, Any] = {}                              # programs, quad and textures, made when first used
        self._layers: dict[str, tuple[Any, Any]] = {}              # overlay layer -> (what it shows, texture)
        self._placed: tuple[int, int, int, int, float] | None = None   # the picture's (left, top, w, h, scale)
        if fullscreen:
            self.toggle_fullscreen()

    # --- input -------------------------------------------------------------------------------------
    def _on_key(self, _win: Any, key: int, _scancode: int, action: int, mods: int) -> None:
        if action != self.glfw.PRESS:
            return
        name = self.glfw.get_key_name(key, 0) or ""
        for attr, label in SPECIAL_KEYS.items():
            if key == getattr(self.glfw, f"KEY_{attr}", None):
                name = label
        if name == "/" and mods & self.glfw.MOD_SHIFT:
            name = "?"
        if name == "f":
            self.toggle_fullscreen()
        elif name in ("h", "?"):
            self.help_shown, self._help_until = not self.help_shown and bool(self.help_keys), None
        elif name:
            self.help_shown = False
            self._keys.append(name)

    def _on_click(self, _win: Any, button: int, action: int, _mods: int) -> None:
        if action == self.glfw.PRESS and button == self.glfw.MOUSE_BUTTON_LEFT:
            self.help_shown = False
            self._clicks.append(self.glfw.get_cursor_pos(self.win))

    def keys(self) -> list[str]:
        """Key names pressed since the last call (polls the window); f, h and ? are the window's own."""
        self.glfw.poll_events()
        keys, self._keys = self._keys, []
        self.closed = self.closed or bool(self.glfw.window_should_close(self.win))
        return keys

    def clicks(self) -> list[tuple[float, float]]:
        """Left clicks since the last call, in window pixels from the top left."""
        clicks, self._clicks = self._clicks, []
        return clicks

    # --- full screen ---------------------------------------------------------------------------------
    @property
    def fullscreen(self) -> bool:
        return bool(self.glfw.get_window_monitor(self.win))

    def toggle_fullscreen(self) -> None:
        """Full screen on the monitor holding the window's middle (at its own video mode), or back to the window's
        place and size before."""
        glfw = self.glfw
        if self.fullscreen:
            x, y, w, h = self._windowed or (100, 100, *glfw.get_window_size(self.win))
            glfw.set_window_monitor(self.win, None, x, y, w, h, 0)
            return
        self._windowed = (*glfw.get_window_pos(self.win), *glfw.get_window_size(self.win))
        monitor = self.monitor()
        if monitor is None:
            return
        mode = glfw.get_video_mode(monitor)
        glfw.set_window_monitor(self.win, monitor, 0, 0, mode.size.width, mode.size.height, mode.refresh_rate)

    def monitor(self) -> Any:
        """The monitor the window's middle is on (the primary one when none holds it)."""
        glfw = self.glfw
        x, y = glfw.get_window_pos(self.win)
        w, h = glfw.get_window_size(self.win)
        cx, cy = x + w // 2, y + h // 2
        for monitor in glfw.get_monitors() or []:
            mx, my = glfw.get_monitor_pos(monitor)
            mode = glfw.get_video_mode(monitor)
            if mx <= cx < mx + mode.size.width and my <= cy < my + mode.size.height:
                return monitor
        return glfw.get_primary_monitor()

    # --- drawing -------------------------------------------------------------------------------------
    def size(self) -> tuple[int, int]:
        """The framebuffer's size in pixels (it may differ from the window's on high-DPI screens)."""
        return tuple(self.glfw.get_framebuffer_size(self.win))  # type: ignore[return-value]

    def _text_px(self) -> int:
        return overlay.text_px(self.size()[1])

    def band(self) -> int:
        """The caption band's height in framebuffer pixels."""
        lines = max(self.caption_lines, len(self.caption.split("\n")) if self.caption else 1)
        return overlay.band_height(lines, self._text_px())

    def frame_point(self, x: float, y: float) -> tuple[int, int] | None:
        """A click at window position (x, y) as a pixel (column, row) of the last blitted picture; None outside it."""
        if self._placed is None:
            return None
        wx, wy = self.glfw.get_window_size(self.win)
        fw, fh = self.size()
        sx, sy = fw / max(wx, 1), fh / max(wy, 1)                 # window units to framebuffer pixels (high DPI)
        left, top, w, h, scale = self._placed
        col, row = int((x * sx - left) // scale), int((y * sy - top) // scale)
        return (col, row) if 0 <= col < w and 0 <= row < h else None

    def _program(self, name: str, fragment: str) -> Any:
        if name not in self._gl:
            ctx = self.ctx
            program = ctx.program(vertex_shader=VERTEX, fragment_shader=fragment)
            if "quad" not in self._gl:
                self._gl["quad"] = ctx.buffer(np.array([-1, -1, 1, -1, -1, 1, 1, 1], dtype="f4").tobytes())
            self._gl[name] = (program, ctx.vertex_array(program, [(self._gl["quad"], "2f", "in_corner")]))
        return self._gl[name]

    def _texture(self, key: str, what: Any, make: Callable[[], np.ndarray]) -> Any:
        """The texture ``key``, holding ``make()``: made again only when ``what`` (what it shows) changed."""
        known = self._layers.get(key)
        if known is not None and (known[0] is what or (not isinstance(what, np.ndarray) and
                                                       not isinstance(known[0], np.ndarray) and known[0] == what)):
            return known[1]
        image = make()
        h, w, c = image.shape
        texture = known[1] if known is not None else None
        if texture is None or texture.size != (w, h) or texture.components != c:
            if texture is not None:
                texture.release()
            texture = self.ctx.texture((w, h), c, dtype="f1", alignment=1)
        texture.write(np.ascontiguousarray(image, dtype=np.uint8).tobytes())
        self._layers[key] = (what, texture)
        return texture

    def blit(self, frame: np.ndarray, smooth: bool = False) -> None:
        """Draw a uint8 RGB picture (h, w, 3) as large as the window allows above the caption band, its shape kept
        (letterboxed), on the dark background; ``smooth`` interpolates (a rendered picture), else each window
        pixel takes the picture pixel it falls in (a ray-traced one keeps its pixels)."""
        ctx = self.ctx
        h, w = frame.shape[:2]
        texture = self._texture("picture", frame, lambda: frame[..., :3])
        texture.filter = (ctx.LINEAR, ctx.LINEAR) if smooth else (ctx.NEAREST, ctx.NEAREST)
        fw, fh = self.size()
        room = fh if self.over_picture else max(1, fh - self.band())
        scale = min(fw / w, room / h)
        left, top = int((fw - w * scale) // 2), int((room - h * scale) // 2)
        self._placed = (left, top, w, h, scale)
        bottom = fh - top - int(round(h * scale))
        ctx.viewport = (0, 0, fw, fh)
        ctx.clear(*(c / 255 for c in overlay.BACKGROUND))
        ctx.viewport = (left, bottom, int(round(w * scale)), int(round(h * scale)))
        program, vao = self._program("blit", BLIT_FRAGMENT)
        texture.use(location=0)
        program["u_frame"].value = 0
        program["u_origin"].value = (float(left), float(bottom))
        program["u_scale"].value = scale
        program["u_smooth"].value = smooth
        vao.render(ctx.TRIANGLE_STRIP)

    def _layer(self, key: str, what: Any, make: Callable[[], np.ndarray], left: int, top: int) -> None:
        """Blend the RGBA layer ``key`` (``make()``, redrawn when ``what`` changed) over the window at (left, top)."""
        ctx = self.ctx
        texture = self._texture(key, what, make)
        w, h = texture.size
        bottom = self.size()[1] - top - h
        ctx.viewport = (left, bottom, w, h)
        program, vao = self._program("layer", LAYER_FRAGMENT)
        texture.use(location=0)
        program["u_layer"].value = 0
        program["u_origin"].value = (float(left), float(bottom))
        vao.render(ctx.TRIANGLE_STRIP)

    def draw_overlay(self) -> None:
        """The caption band at the bottom and, while shown, the help panel over the picture's top left."""
        ctx = self.ctx
        if self._help_until is not None and time.monotonic() > self._help_until:
            self.help_shown, self._help_until = False, None
        fw, fh = self.size()
        px = self._text_px()
        lines = max(self.caption_lines, len(self.caption.split("\n")) if self.caption else 1)
        ctx.disable(ctx.DEPTH_TEST | ctx.CULL_FACE)
        ctx.enable(ctx.BLEND)
        ctx.blend_func = ctx.SRC_ALPHA, ctx.ONE_MINUS_SRC_ALPHA
        caption, over = self.caption, self.over_picture
        self._layer("band", (fw, caption, lines, px), lambda: overlay.band_image(fw, caption, lines, px, over),
                    0, fh - overlay.band_height(lines, px))
        if self.help_shown and self.help_keys:
            if self._placed is not None and not self.over_picture:
                left, top, w, h, scale = self._placed
                picture = (left, top, int(w * scale), int(h * scale))
            else:
                picture = (0, 0, fw, fh - (0 if self.over_picture else self.band()))
            (x, y), room = overlay.help_place(picture, px)
            keys = tuple(self.help_keys)
            self._layer("help", (keys, px, room), lambda: overlay.help_image(keys, px, room), x, y)
        ctx.disable(ctx.BLEND)

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

    def show(self, draw: Callable[[], Any], count: bool = True) -> None:
        """Draw one frame into the window, the overlay over it, and swap it in; ``count``: it counts towards
        ``--frames`` (a frame saying the demo is still preparing does not)."""
        self.glfw.make_context_current(self.win)   # an engine may have made its own context current since
        self.ctx.screen.use()
        draw()
        self.ctx.screen.use()
        self.draw_overlay()
        self.glfw.swap_buffers(self.win)
        self.frames += int(count)
        self.closed = self.closed or bool(self.glfw.window_should_close(self.win))

    def done(self, frames: int | None) -> bool:
        """Closed by the user, or shown ``frames`` frames (a scripted demo)."""
        return self.closed or (frames is not None and self.frames >= frames)

    def close(self) -> None:
        self.glfw.terminate()
