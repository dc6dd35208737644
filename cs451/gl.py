"""Headless OpenGL contexts through EGL (Mesa llvmpipe on a laptop without a GPU)."""
from __future__ import annotations

import os
from typing import Any

from .errors import KitError

EGL_FIX = ("install Mesa's EGL driver: sudo apt-get install libegl1 libegl-mesa0 libgl1-mesa-dri "
           "(or run ./setup.sh, which does it for you)")


def _prepare_environment() -> None:
    # Without a display or GPU, Mesa's EGL must be told to use the surfaceless platform.
    if not os.environ.get("DISPLAY") and not os.environ.get("WAYLAND_DISPLAY"):
        os.environ.setdefault("EGL_PLATFORM", "surfaceless")


def create_context(require: int = 330) -> Any:
    """A standalone moderngl context through EGL; a clear one-line error and the fix when EGL is missing."""
    _prepare_environment()
    try:
        import moderngl
    except ImportError as err:  # pragma: no cover - setup installs it
        raise KitError(f"moderngl is not installed ({err}); run ./setup.sh") from None
    try:
        ctx = moderngl.create_standalone_context(backend="egl", require=require)
    except Exception as err:  # moderngl raises bare Exception for loader failures
        raise KitError(f"cannot create a headless OpenGL context through EGL ({str(err).strip()}); {EGL_FIX}") from None
    return ctx


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
