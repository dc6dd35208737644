"""``cs451 demo``: a stage's lecture demo, in a window where there is a display, as frames where there is none.

Every stage's demo draws through its stage interface (so a lecturer can demo the
reference or any submission) and shares two things from here: the window
(:mod:`.window`: GLFW, key names, frame counting) and the frames written without a
display (:mod:`.frames`: PNGs, an animated GIF, captions).
"""
from __future__ import annotations

import os
from pathlib import Path

from ..errors import KitError
from ..impl import load_impl, resolve_impl
from ..stages import get_stage


def has_display() -> bool:
    return bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))


def run_demo(*, stage: str = "sphere", impl: str = "reference", output: str | Path = "demo",
             window: bool | None = None, frames: int | None = None) -> list[Path]:
    """Open the window (``window=None``: when there is a display) or write the demo's frames to ``output``."""
    st = get_stage(stage)
    if st.demo is None:
        raise KitError(f"no demo for stage {stage!r} yet")
    show_window = window if window is not None else has_display()
    return st.demo(load_impl(resolve_impl(impl, stage), stage), Path(output), show_window, frames)
