"""Headless OpenGL contexts: EGL on Linux (Mesa's llvmpipe on a laptop without a GPU), the platform's own elsewhere.

moderngl (through glcontext) opens a standalone context with EGL, with CGL on macOS and
with WGL on Windows. Linux tries EGL first (no display needed), then the display's GLX.
The reference images are llvmpipe's; the image tests' tolerance is what lets another
rasteriser give the same grades (README, "Tolerances").
"""
from __future__ import annotations

import os
import sys
from typing import Any

from .errors import KitError

#: The fix for a missing OpenGL, per platform: the error names the one for the machine it is on.
FIXES = {
    "linux": "install Mesa's EGL driver: sudo apt-get install libegl1 libegl-mesa0 libgl1-mesa-dri "
             "(or run ./setup.sh, which does it for you)",
    "darwin": "macOS gives OpenGL 3.3 through CGL on every Mac since 2012; if this fails, use the kit's Docker "
              "image or dev container (README, 'Every platform'), which render with Mesa's llvmpipe",
    "win32": "use WSL2 (Ubuntu) and run ./setup.sh there, or update your graphics driver for OpenGL 3.3; "
             "the kit's Docker image and dev container work too (README, 'Every platform')",
}
EGL_FIX = FIXES["linux"]


def _backends() -> list[str | None]:
    """Which moderngl backends to try on this platform, in order (None: the platform's default)."""
    if sys.platform.startswith("linux"):
        return ["egl", None] if os.environ.get("DISPLAY") else ["egl"]
    return [None]


def _prepare_environment() -> None:
    # Without a display or GPU, Mesa's EGL must be told to use the surfaceless platform.
    if not os.environ.get("DISPLAY") and not os.environ.get("WAYLAND_DISPLAY"):
        os.environ.setdefault("EGL_PLATFORM", "surfaceless")


def create_context(require: int = 330) -> Any:
    """A standalone moderngl context; a clear one-line error and this platform's fix when none can be made."""
    _prepare_environment()
    try:
        import moderngl
    except ImportError as err:  # pragma: no cover - setup installs it
        raise KitError(f"moderngl is not installed ({err}); run ./setup.sh") from None
    errors = []
    for backend in _backends():
        try:
            kwargs = {"backend": backend} if backend else {}
            return moderngl.create_standalone_context(require=require, **kwargs)
        except Exception as err:  # moderngl raises bare Exception for loader failures
            errors.append(f"{backend or 'default'}: {str(err).strip().splitlines()[0] if str(err).strip() else err!r}")
    platform = "linux" if sys.platform.startswith("linux") else sys.platform
    fix = FIXES.get(platform, FIXES["linux"])
    raise KitError(f"cannot create an OpenGL {require // 100}.{require // 10 % 10} context ({'; '.join(errors)}); {fix}")


def renderer_name(ctx: Any) -> str:
    """E.g. 'llvmpipe (LLVM 15.0.6, 256 bits) / Mesa 22.3.6', for reports."""
    info = ctx.info
    return f"{info.get('GL_RENDERER', '?')} / {info.get('GL_VERSION', '?')}"


def make_current(ctx: Any) -> None:
    """Make ``ctx`` the current GL context and leave it so.

    moderngl draws into whichever context is current; a second context (a demo
    window, another engine) silently takes over. ``with ctx:`` is no answer with
    EGL: leaving the block makes *no* context current.
    """
    ctx.__enter__()
