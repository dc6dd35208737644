"""The demos' window: GLFW, an OpenGL 3.3 core context for moderngl, key names, and a frame count.

One window class for every stage: the sphere's (the notes' 500×500 window, resizable)
and the radiosity and ray tracing demos' alike. Keys arrive as names (``"q"``, ``"+"``,
``"escape"``), which is what task S8 and the demos' own controls understand.
"""
from __future__ import annotations

from typing import Any, Callable

from ..errors import KitError

#: GLFW key codes with no printable name, as the kit names them (S8's table).
SPECIAL_KEYS = {"ESCAPE": "escape", "EQUAL": "+", "KP_ADD": "+", "MINUS": "-", "KP_SUBTRACT": "-",
                "LEFT": "left", "RIGHT": "right", "UP": "up", "DOWN": "down", "SPACE": "space"}


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

    def show(self, draw: Callable[[], Any]) -> None:
        """Draw one frame into the window and swap it in."""
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
