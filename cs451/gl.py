"""Headless OpenGL contexts through EGL (Mesa llvmpipe on a laptop without a GPU)."""
from __future__ import annotations

import os
import re
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


_GLSL_LOCATION = re.compile(r"\b0:(\d+)\((\d+)\):\s*")


def _student_line(message: str, prefix: str, source: str) -> str:
    """A GLSL compiler message with its ``0:LINE(COL)`` counted in the student's own source (the kit's lines taken off)."""
    first, lines = prefix.count("\n"), source.count("\n") + 1

    def where(m: re.Match) -> str:
        line = int(m.group(1)) - first
        if line < 1:
            return "in the kit's interface before your source: "
        if line > lines:
            return "in the kit's code after your source (is main() there?): "
        return f"line {line}, column {m.group(2)}: "
    return _GLSL_LOCATION.sub(where, message, count=1)


def compile_program(ctx: Any, task: str, vertex: tuple[str, str, str], fragment: tuple[str, str, str]) -> Any:
    """``ctx.program`` of two shaders, each given as (the kit's prefix, the student's source, the kit's suffix).

    A compile error becomes a one-line KitError that names the shader and gives the line in the
    student's own source, the kit's prepended lines taken off; a link error says the two do not link.
    """
    try:
        return ctx.program(vertex_shader="".join(vertex), fragment_shader="".join(fragment))
    except Exception as err:  # moderngl reports compile and link errors as plain Exceptions
        text = str(err).strip()
        lines = text.splitlines() or ["unknown error"]
        first = next((ln.strip() for ln in lines if "error" in ln.lower() and "failed" not in ln.lower()), lines[0].strip())
        for name, (prefix, source, _) in (("vertex", vertex), ("fragment", fragment)):
            if f"{name}_shader" in text:
                raise KitError(f"{task}: the {name} shader does not compile: {_student_line(first, prefix, source)}") from None
        raise KitError(f"{task}: the vertex and fragment shaders do not link: {first}") from None
