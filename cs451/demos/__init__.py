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
from typing import Any, Callable

from ..errors import KitError
from ..impl import load_impl, resolve_impl
from ..stages import get_stage


def has_display() -> bool:
    return bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))


def run_demo(*, stage: str, impl: str = "reference", output: str | Path = "demo",
             window: bool | None = None, frames: int | None = None, scene: str | None = None,
             size: str | tuple[int, int] | None = None, screenshot: str | Path | None = None,
             fullscreen: bool = False) -> list[Path]:
    """Open the window (``window=None``: when there is a display) or write the demo's frames to ``output``.

    ``scene`` must be one the stage draws (else one line naming the stages that do); ``size`` (``"WxH"``) is the
    picture's. ``screenshot``: in a window, play the headless frames' script, save the window as the display shows
    it and close. ``fullscreen``: open the window full screen. An option a demo does not take is refused by name.
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
    if scene is not None:
        check_demo_scene(stage, scene)
    options: dict[str, Any] = {"scene": scene, "size": size, "screenshot": Path(screenshot) if screenshot else None,
                               "fullscreen": fullscreen or None}
    entry = demo_entry(stage)
    accepted = inspect.signature(entry).parameters
    for name, value in options.items():
        if value is not None and name not in accepted:
            raise KitError(f"--{name}: the {stage} demo does not take it")
    module = load_impl(resolve_impl(impl, stage), stage)
    return entry(module, Path(output), show_window, frames, **{k: v for k, v in options.items() if v is not None})


def demo_entry(stage: str) -> Callable[..., list[Path]]:
    """The stage's demo function itself: ``demo`` in the ``demo`` module beside the stage's package (what its
    registered ``Stage.demo`` loads when called), so that its options are read from the function that takes them."""
    import importlib
    registered = get_stage(stage).demo
    if registered is None:
        raise KitError(f"no demo for stage {stage!r} yet")
    try:
        return importlib.import_module(f"{registered.__module__}.demo").demo
    except (ImportError, AttributeError):
        return registered


def check_demo_scene(stage: str, scene: str | Path) -> None:
    """Refuse, in one line, a scene the stage's demo cannot draw, naming the scene and the stages that can."""
    from ..scene import load_scene
    from ..stages import check_options, stage_names
    loaded = load_scene(scene)                       # an unknown name or a bad file: its own one line
    check_options(loaded)
    try:
        get_stage(stage).check_scene(loaded)
        return
    except KitError as err:
        why = str(err).removeprefix(f"{loaded.label}: ")
    able = []
    for name in stage_names():
        try:
            get_stage(name).check_scene(loaded)
        except KitError:
            continue
        able.append(name)
    raise KitError(f"--scene {scene}: the {stage} demo cannot draw it ({why}); the demos that can: "
                   f"{', '.join(able) or 'none'}")
