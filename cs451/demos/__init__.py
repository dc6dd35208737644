"""``cs451 demo``: a stage's lecture demo, in a window where there is a display, as frames where there is none.

Every stage's demo draws through its stage interface (so a lecturer can demo the
reference or any submission) and shares the layer here: the window (:mod:`.window`:
GLFW, key names, clicks, an image drawn to fit), the frames written without a display
(:mod:`.frames`: PNGs, an animated GIF, captions), the switch between the two and the
loop an interactive demo runs (:mod:`.player`), and every demo's keys (:mod:`.controls`).
"""
from __future__ import annotations

import inspect
import os
from pathlib import Path
from typing import Any

from ..errors import KitError
from ..impl import load_impl, resolve_impl
from ..stages import get_stage


def has_display() -> bool:
    return bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))


def run_demo(*, stage: str, impl: str = "reference", output: str | Path = "demo",
             window: bool | None = None, frames: int | None = None, scene: str | None = None,
             size: str | tuple[int, int] | None = None, screenshot: str | Path | None = None) -> list[Path]:
    """Open the window (``window=None``: when there is a display) or write the demo's frames to ``output``.

    ``scene``, ``size`` (``"WxH"``) and ``screenshot`` go to demos that take them; each is refused, by its option's
    name, for one that does not. ``screenshot``: in a window, play the headless frames' script, save the window as
    the display shows it and close.
    """
    st = get_stage(stage)
    if st.demo is None:
        raise KitError(f"no demo for stage {stage!r} yet")
    if frames is not None and frames < 1:
        raise KitError(f"--frames: must be at least 1, got {frames}")
    show_window = window if window is not None else has_display()
    if screenshot is not None and not show_window:
        raise KitError("--screenshot: needs a window (a display, or --window under xvfb-run)")
    if isinstance(size, str):
        from ..render import parse_size
        size = parse_size(size)
    options: dict[str, Any] = {"scene": scene, "size": size, "screenshot": Path(screenshot) if screenshot else None}
    accepted = inspect.signature(st.demo).parameters
    for name, value in options.items():
        if value is not None and name not in accepted:
            raise KitError(f"--{name}: the {stage} demo does not take it")
    module = load_impl(resolve_impl(impl, stage), stage)
    return st.demo(module, Path(output), show_window, frames, **{k: v for k, v in options.items() if v is not None})
