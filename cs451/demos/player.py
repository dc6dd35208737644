"""Where a demo's frames go, and the loop an interactive demo runs: one layer for every stage's demo.

:class:`Screen` is the headless/windowed switch: with a window, each frame is shown as it
comes (q or Esc, closing the window, or ``--frames`` ends the demo by raising
:class:`Closed`), and keys and clicks come back as events; without one, the frames are kept
and written at the end as PNGs and an animated GIF (:mod:`.frames`). Stage 4's demo draws
into the screen itself; stages 2 and 3 make their frames as images and run :func:`play`.

:func:`play` runs an :class:`Interactive` demo. In a window it renders in small pieces
between frames (``step`` does a few tens of milliseconds of work), so the window answers
keys while the picture refines, and sleeps when there is nothing to do. Without a display
it runs the demo's own *script* (groups of keys and clicks, a frame after each group and at
the milestones of the first, as the picture refines): the headless frames are what a
lecturer would see pressing those keys. ``screenshot`` runs the same script in the window
and grabs it at the end, so a test can compare the window with the headless frame.
"""
from __future__ import annotations

from pathlib import Path
from typing import Any, Callable, Protocol

import numpy as np

from .controls import QUIT_KEYS, key_line
from .frames import captioned, write_frames

#: Seconds of work between two frames of a live window (responsive, yet mostly rendering).
STEP_SECONDS = 0.04
#: How long an idle window sleeps waiting for events before it draws again.
IDLE_SECONDS = 0.05

#: ("key", name) or ("click", column, row) in the frame's pixels
Event = tuple


class Closed(Exception):
    """The window was closed (q, Esc, its close button), or showed the frames it was asked for."""


class Screen:
    """A window (``window=True``) or a list of frames written to ``output`` as ``name.gif`` and ``name-NN.png``.

    ``size`` is the first frame's (width, height): the window opens at it. The title lists the stage's keys
    (:mod:`.controls`). ``frames``: a window closes after showing that many frames.
    """

    def __init__(self, name: str, title: str, size: tuple[int, int], *, window: bool, frames: int | None = None,
                 output: Path = Path("demo"), stage: str | None = None):
        self.name, self.output, self.frames = name, Path(output), frames
        self.kept: list[np.ndarray] = []
        self._events: list[Event] = []
        self.win: Any = None
        if window:
            from .window import Window
            keys = key_line(stage or name)
            self.win = Window(size[0], size[1], f"{title} — {keys}" if keys else title)

    @property
    def ctx(self) -> Any:
        """The window's GL context (draw into it, and let the engine render with it), or None without a window."""
        return self.win.ctx if self.win is not None else None

    def show(self, image: np.ndarray | None = None, caption: str | None = None,
             draw: Callable[[], Any] | None = None) -> None:
        """Show (or keep) a frame: a uint8 image with an optional caption, or, in a window, ``draw()`` drawing it."""
        frame = captioned(image, caption) if image is not None and caption is not None else image
        if self.win is None:
            if frame is not None:
                self.kept.append(frame)
            return
        self._poll()
        self.win.show(draw if draw is not None else (lambda: self.win.blit(frame)))
        if self.win.done(self.frames):
            raise Closed

    def events(self) -> list[Event]:
        """Keys and clicks since the last call (none without a window); raises Closed when the user quit."""
        if self.win is None:
            return []
        self._poll()
        events, self._events = self._events, []
        return events

    def wait(self, seconds: float = IDLE_SECONDS) -> None:
        if self.win is not None:
            self.win.wait(seconds)

    def screenshot(self, path: Path) -> Path:
        return self.win.screenshot(path)

    def close(self) -> list[Path]:
        """Close the window (nothing written), or write the kept frames: the GIF first, then the PNGs."""
        if self.win is not None:
            self.win.close()
            return []
        return write_frames(self.output, self.name, self.kept)

    def _poll(self) -> None:
        for key in self.win.keys():
            if key in QUIT_KEYS:
                self.win.closed = True
            else:
                self._events.append(("key", key))
        for x, y in self.win.clicks():
            point = self.win.frame_point(x, y)
            if point is not None:
                self._events.append(("click", *point))
        if self.win.closed:
            raise Closed


class Interactive(Protocol):
    """A demo that makes its frames as images: what :func:`play` asks of it."""
    name: str      # the stage, and the frames' file names
    title: str     # the window title, before the keys

    def frame_size(self) -> tuple[int, int]:
        """(width, height) of its frames, caption included: the window opens at this size."""

    def start(self, ctx: Any) -> None:
        """Make GL objects, in the window's context ``ctx`` (None without a window: make a standalone one)."""

    def handle(self, event: Event) -> None:
        """A key or a click (in frame pixels)."""

    def busy(self) -> bool:
        """Whether it has work left (a picture refining, a patch to compute)."""

    def step(self, seconds: float) -> bool:
        """About ``seconds`` of work; True when a frame worth keeping is ready (a refinement level done)."""

    def frame(self) -> np.ndarray:
        """The current frame, uint8 RGB (h, w, 3), caption included."""

    def script(self) -> list[list[Event]]:
        """What the headless run does: groups of events, a frame after each."""


def play(demo: Interactive, *, window: bool, frames: int | None = None, output: Path = Path("demo"),
         screenshot: Path | None = None) -> list[Path]:
    """Run ``demo`` in a window (the user's keys, until q) or headless (its script); returns the files written.

    ``frames``: headless, or with ``screenshot``, keep the script's first that many frames; in a live window,
    close after that many. ``screenshot``: run the script in the window and save what the display shows.
    """
    scripted = not window or screenshot is not None
    screen = Screen(demo.name, demo.title, demo.frame_size(), window=window, frames=None if scripted else frames,
                    output=output)
    try:
        demo.start(screen.ctx)
        if scripted:
            _scripted(demo, screen, frames)
            if screenshot is not None:
                screen.screenshot(screenshot)
        else:
            _live(demo, screen)
    except Closed:
        pass
    finally:
        paths = screen.close()
    return paths


def _scripted(demo: Interactive, screen: Screen, frames: int | None) -> None:
    kept = 0

    def keep() -> bool:
        nonlocal kept
        screen.show(demo.frame())
        kept += 1
        return frames is not None and kept >= frames

    for k, group in enumerate(demo.script()):
        for event in group:
            demo.handle(event)
        while demo.busy():
            milestone = demo.step(STEP_SECONDS)
            screen.events()                       # a scripted window still answers q
            if milestone and k == 0 and demo.busy():
                if keep():
                    return
            elif screen.win is not None:
                screen.show(demo.frame())
        if keep():
            return


def _live(demo: Interactive, screen: Screen) -> None:
    frame = None
    while True:
        changed = frame is None
        for event in screen.events():
            demo.handle(event)
            changed = True
        if demo.busy():
            demo.step(STEP_SECONDS)
            changed = True
        if changed:
            frame = demo.frame()
        else:
            screen.wait()
        screen.show(frame)
