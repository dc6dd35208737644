"""pyrender 0.1.45 (the last release) on NumPy 2 and without a display: the one place that adapts it.

pyrender uses ``np.infty`` (removed in NumPy 2) and picks its GL platform from
``PYOPENGL_PLATFORM`` at import time. Import pyrender from here, never directly.
"""
import os

import numpy as np

if not hasattr(np, "infty"):
    np.infty = np.inf  # type: ignore[attr-defined]
if not os.environ.get("DISPLAY"):
    os.environ.setdefault("PYOPENGL_PLATFORM", "egl")
    os.environ.setdefault("EGL_PLATFORM", "surfaceless")

import pyrender  # noqa: E402

__all__ = ["pyrender"]
