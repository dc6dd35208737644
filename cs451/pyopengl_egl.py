"""PyOpenGL's EGL platform with GLVND's versioned libraries (``libOpenGL.so.0``, ``libEGL.so.1``) first.

PyOpenGL 3.1.0 finds its libraries by ``ctypes.util.find_library("GL")``, which gives ``libGL.so.1``: desktop
GL with GLX, so it loads X libraries, and a minimal Debian or a GPU server without X has none. Through EGL,
``libOpenGL.so.0`` is all the desktop GL needed. cs451/pyrender_shim.py points PyOpenGL's ``egl`` platform
plugin here before OpenGL is first imported; PyOpenGL's own lookup stays as the fallback.
"""
import ctypes

from OpenGL.platform import baseplatform
from OpenGL.platform.egl import EGLPlatform

from .gl import LINUX_LIBRARIES


def _load(name: str) -> ctypes.CDLL | None:
    try:
        return ctypes.CDLL(name, mode=ctypes.RTLD_GLOBAL)
    except OSError:
        return None


class GlvndEGLPlatform(EGLPlatform):
    """EGLPlatform, loading GLVND's versioned libraries before PyOpenGL's own names."""

    @baseplatform.lazy_property
    def GL(self):  # noqa: N802 (PyOpenGL's name)
        return _load(LINUX_LIBRARIES["libgl"]) or EGLPlatform.GL.fget(self)

    @baseplatform.lazy_property
    def EGL(self):  # noqa: N802
        return _load(LINUX_LIBRARIES["libegl"]) or EGLPlatform.EGL.fget(self)
