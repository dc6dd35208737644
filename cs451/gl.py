"""Headless OpenGL contexts: EGL on Linux (Mesa's llvmpipe on a laptop without a GPU), the platform's own elsewhere.

moderngl (through glcontext) opens a standalone context with EGL, with CGL on macOS and
with WGL on Windows. Linux tries EGL first (no display needed), then the display's GLX.
The reference images are llvmpipe's; the image tests' tolerance is what lets another
rasteriser give the same grades (docs/tolerances.md).
"""
from __future__ import annotations

import ctypes
import os
import re
import sys
from typing import Any

from .errors import KitError

#: GLVND's libraries for OpenGL through EGL on Linux, by the versioned names the runtime packages install.
#: glcontext and PyOpenGL look for ``libGL.so``/``libEGL.so`` by default: those unversioned names come only
#: with the -dev packages, and ``libGL.so.1`` carries GLX, which loads X libraries a GPU server may not have.
#: ``libOpenGL.so.0`` is desktop OpenGL without GLX (DESIGN.md, "Environment facts").
LINUX_LIBRARIES = {"libegl": "libEGL.so.1", "libgl": "libOpenGL.so.0"}
#: The Debian/Ubuntu package of each library the kit loads, and of Mesa's EGL driver (llvmpipe).
LINUX_PACKAGES = {"libEGL.so.1": "libegl1", "libOpenGL.so.0": "libopengl0"}
MESA_PACKAGES = ("libegl-mesa0", "libgl1-mesa-dri")

#: The fix for a missing OpenGL on the other platforms (Linux's names the missing library, see linux_fix).
FIXES = {
    "darwin": "macOS gives OpenGL 3.3 through CGL on every Mac since 2012; if this fails, use the kit's Docker "
              "image or dev container (docs/installing.md in the kit), which render with Mesa's llvmpipe",
    "win32": "use WSL2 (Ubuntu) and run ./setup.sh there, or update your graphics driver for OpenGL 3.3; "
             "the kit's Docker image and dev container work too (docs/installing.md in the kit)",
}


def missing_linux_libraries() -> list[str]:
    """Which of the GL libraries the kit loads on Linux cannot be loaded here."""
    missing = []
    for name in LINUX_PACKAGES:
        try:
            ctypes.CDLL(name)
        except OSError:
            missing.append(name)
    return missing


def linux_fix() -> str:
    """What to install on this Linux machine: the missing libraries' packages, else Mesa's EGL driver."""
    missing = missing_linux_libraries()
    if missing:
        packages = " ".join(LINUX_PACKAGES[name] for name in missing)
        return f"{' and '.join(missing)} cannot be loaded: sudo apt-get install {packages}"
    return ("the GL libraries load but no EGL driver made a context: install Mesa's "
            f"(sudo apt-get install {' '.join(MESA_PACKAGES)}) or your GPU's driver")


def _attempts() -> list[dict[str, str]]:
    """The moderngl context arguments to try on this platform, in order ({}: the platform's default)."""
    if sys.platform.startswith("linux"):
        attempts = [{"backend": "egl", **LINUX_LIBRARIES}, {"backend": "egl"}]
        return attempts + [{}] if os.environ.get("DISPLAY") else attempts
    return [{}]


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
    for kwargs in _attempts():
        try:
            return moderngl.create_standalone_context(require=require, **kwargs)
        except Exception as err:  # moderngl raises bare Exception for loader failures
            text = str(err).strip()
            errors.append(f"{kwargs.get('backend', 'default')}{'/' + kwargs['libgl'] if 'libgl' in kwargs else ''}: "
                          f"{text.splitlines()[0] if text else repr(err)}")
    fix = linux_fix() if sys.platform.startswith("linux") else FIXES.get(sys.platform, FIXES["win32"])
    raise KitError(f"cannot create an OpenGL {require // 100}.{require // 10 % 10} context ({'; '.join(errors)}); {fix}")


def renderer_name(ctx: Any) -> str:
    """E.g. 'llvmpipe (LLVM 15.0.6, 256 bits) / Mesa 22.3.6', for reports."""
    info = ctx.info
    return f"{info.get('GL_RENDERER', '?')} / {info.get('GL_VERSION', '?')}"


#: GL_RENDERER names of rasterisers that run on the CPU (Mesa's, Google's, Microsoft's, Apple's)
SOFTWARE_RENDERERS = ("llvmpipe", "softpipe", "swrast", "swiftshader", "software rasterizer", "gdi generic",
                      "basic render", "apple software renderer")


def is_software(ctx: Any) -> bool:
    """Whether ``ctx`` rasterises on the CPU: there, work kept off the rasteriser pays (culling on the CPU),
    and a GPU's strengths (thousands of threads, its own memory) are absent."""
    name = str(ctx.info.get("GL_RENDERER", "")).lower()
    return any(soft in name for soft in SOFTWARE_RENDERERS)


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
