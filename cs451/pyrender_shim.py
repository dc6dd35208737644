"""pyrender 0.1.45 (the last release) on NumPy 2, without a display and without X libraries: the one place that
adapts it. Import pyrender from here, never directly.

- pyrender uses ``np.infty``, removed in NumPy 2.
- On Linux, PyOpenGL draws through EGL (``PYOPENGL_PLATFORM``, read when OpenGL is first imported), and its
  desktop-GL library is GLVND's ``libOpenGL.so.0`` (cs451/pyopengl_egl.py) instead of ``libGL.so.1``, which
  carries GLX and so loads X libraries: a minimal Debian has no ``libGL.so.1``, a GPU server may have no X.
- pyrender imports its interactive viewer, a pyglet window, at import; pyglet then loads ``libGL.so.1`` and
  Xlib (``XRenderFindVisualFormat``) even though the kit never opens that viewer. The kit uses pyrender's
  cameras and ``OffscreenRenderer`` only, so the viewer module is replaced by one whose ``Viewer`` says so.
"""
import os
import sys
import types

import numpy as np

from .errors import KitError
from .gl import LINUX_LIBRARIES, linux_fix

if not hasattr(np, "infty"):
    np.infty = np.inf  # type: ignore[attr-defined]

LINUX = sys.platform.startswith("linux")
if LINUX:
    os.environ.setdefault("PYOPENGL_PLATFORM", "egl")
    if not os.environ.get("DISPLAY") and not os.environ.get("WAYLAND_DISPLAY"):
        os.environ.setdefault("EGL_PLATFORM", "surfaceless")
    if "OpenGL.platform" not in sys.modules:        # PyOpenGL has not chosen its libraries yet: ours, then
        from OpenGL.plugins import PlatformPlugin   # (importing OpenGL registers the plugins, loads nothing)
        PlatformPlugin.by_name("egl").import_path = "cs451.pyopengl_egl.GlvndEGLPlatform"


class _NoViewer:
    """pyrender's interactive viewer, which the kit never opens (see the module's docstring)."""

    def __init__(self, *args: object, **kwargs: object) -> None:
        raise KitError("pyrender's interactive viewer is not available in cs451 (it needs pyglet and X); "
                       "use pyrender.OffscreenRenderer")


_viewer = types.ModuleType("pyrender.viewer", _NoViewer.__doc__)
_viewer.Viewer = _NoViewer  # type: ignore[attr-defined]
sys.modules.setdefault("pyrender.viewer", _viewer)

try:
    import pyrender  # noqa: E402
    import OpenGL.platform  # noqa: E402
except ImportError as err:
    raise KitError(f"pyrender cannot be imported ({err}); {linux_fix() if LINUX else 'reinstall the kit'}") from None
if getattr(OpenGL.platform.PLATFORM, "GL", None) is None:
    raise KitError(f"PyOpenGL found no OpenGL library ({LINUX_LIBRARIES['libgl']} or libGL.so.1); "
                   f"{linux_fix() if LINUX else 'install your graphics driver'}")

__all__ = ["pyrender"]
