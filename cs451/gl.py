"""Headless OpenGL contexts: EGL on Linux (Mesa's llvmpipe on a laptop without a GPU), the platform's own elsewhere.

moderngl (through glcontext) opens a standalone context with EGL, with CGL on macOS and
with WGL on Windows. Linux tries EGL first (no display needed), then the display's GLX.
The reference images are llvmpipe's; the image tests' tolerance is what lets another
rasteriser give the same grades (README, "Tolerances").
"""
from __future__ import annotations

import os
import re
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
