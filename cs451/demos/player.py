"""Where a demo's frames go, and the loop an interactive demo runs: one layer for every stage's demo.

:class:`Screen` is the headless/windowed switch: with a window, each frame is shown as it
comes (q or Esc, closing the window, or ``--frames`` ends the demo by raising
:class:`Closed`), and keys and clicks come back as events; without one, the frames are kept
and written at the end as PNGs and an animated GIF (:mod:`.frames`). Either way a frame is a
picture with a caption (what it shows) and, until the first key, the help panel (every key):
the window draws them over the picture at its own resolution, the frames get them drawn in
(:mod:`.overlay`). Stage 1's demo draws into its window itself; the others make their
pictures as images and run :func:`play`.

:func:`play` runs an :class:`Interactive` demo. The window opens first and says what the demo
is preparing (loading the ray tracer's compiled kernels, building a hierarchy), so it is up in
a second or two whatever comes next. Then it renders in small pieces between frames (``step``
does a few tens of milliseconds of work), so the window answers keys while the picture
refines, and sleeps when there is nothing to do. Without a display it runs the demo's own
*script* (groups of keys and clicks, a frame after each group and at the milestones of the
first, as the picture refines): the headless frames are what a lecturer would see pressing
those keys. ``screenshot`` runs the same script in the window and grabs it at the end, so a
test can compare the window with the headless frame.
"""
from __future__ import annotations

from pathlib import Path
from typing import Any, Callable, Iterator, Protocol

import numpy as np

from .controls import QUIT_KEYS, help_keys, key_line
from .frames import write_frames
from .overlay import HELP_SECONDS, compose, framed_size

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

    ``size`` is the picture's (width, height): the window opens at it with the caption band under it (a band of
    ``caption_lines`` lines), or ``fullscreen``. The title lists the stage's keys and the help panel all the keys
    (:mod:`.controls`). ``frames``: a window closes after showing that many frames. ``scripted``: the help panel
    stays up until the first scripted key (:meth:`note`), not for a time, so a scripted window shows what the
    headless frames show. ``smooth``: the picture is interpolated when scaled (a rendered one, not ray-traced pixels).
    """

    def __init__(self, name: str, title: str, size: tuple[int, int], *, window: bool, frames: int | None = None,
                 output: Path = Path("demo"), stage: str | None = None, caption_lines: int = 1,
                 fullscreen: bool = False, scripted: bool = False, smooth: bool = False):
        self.name, self.output, self.frames = name, Path(output), frames
        self.keys = help_keys(stage or name)
        self.lines, self.smooth = caption_lines, smooth
        self.help_shown = True
        self.kept: list[tuple[np.ndarray, str, bool]] = []
        self._events: list[Event] = []
        self.win: Any = None
        if window:
            from .window import Window
            keys = key_line(stage or name)
            width, height = framed_size(size, caption_lines)
            self.win = Window(width, height, f"{title} — {keys}" if keys else title, keys=self.keys,
                              caption_lines=caption_lines, fullscreen=fullscreen,
                              help_seconds=None if scripted else HELP_SECONDS)

    @property
    def ctx(self) -> Any:
        """The window's GL context (draw into it, and let the engine render with it), or None without a window."""
        return self.win.ctx if self.win is not None else None

    def show(self, image: np.ndarray | None = None, caption: str | None = None,
             draw: Callable[[], Any] | None = None, preparing: bool = False) -> None:
        """Show (or keep) a frame: a uint8 picture and its caption, or, in a window, ``draw()`` drawing it.
        ``preparing``: a frame saying what the demo is still preparing (shown, never kept, not counted)."""
        if self.win is None:
            if image is not None and not preparing:
                self.kept.append((image, caption or "", self.help_shown))
            return
        self._poll()
        self.win.caption = caption or ""
        self.win.show(draw if draw is not None else (lambda: self.win.blit(image, self.smooth)), count=not preparing)
        if self.win.done(self.frames):
            raise Closed

    def note(self, event: Event) -> None:
        """A scripted key or click: the help panel toggles (h, ?) or hides, as for the user's own."""
        if event[0] == "key" and event[1] in ("h", "?"):
            self.help_shown = not self.help_shown
        else:
            self.help_shown = False
        if self.win is not None:
            self.win.help_shown, self.win._help_until = self.help_shown, None

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
        """Close the window (nothing written), or write the kept frames, each with its caption band and (until the
        first key) the help panel drawn in: the GIF first, then the PNGs."""
        if self.win is not None:
            self.win.close()
            return []
        lines = max([self.lines] + [len(c.split("\n")) for _, c, _ in self.kept])
        frames = [compose(p, c, lines, self.keys, shown) for p, c, shown in self.kept]
        return write_frames(self.output, self.name, frames)

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
    """A demo that makes its pictures as images: what :func:`play` asks of it."""
    name: str           # the stage, and the frames' file names
    title: str          # the window title, before the keys
    caption_lines: int  # lines its caption has (the band's height)
    smooth: bool        # its picture is rendered (interpolate when scaled), not ray-traced pixels

    def frame_size(self) -> tuple[int, int]:
        """(width, height) of its pictures, known before any work: the window opens at this size."""

    def prepare(self, ctx: Any) -> Iterator[str]:
        """The slow set-up, in steps: yields what it does next before each (the window says so), in the window's
        GL context ``ctx`` (None without a window: make a standalone one)."""

    def handle(self, event: Event) -> None:
        """A key or a click (in picture pixels)."""

    def busy(self) -> bool:
        """Whether it has work left (a picture refining, a patch to compute)."""

    def step(self, seconds: float) -> bool:
        """About ``seconds`` of work; True when a frame worth keeping is ready (a refinement level done)."""

    def frame(self) -> np.ndarray:
        """The current picture, uint8 RGB (h, w, 3), without its caption."""

    def caption(self) -> str:
        """What the picture shows, a line per slot of the band."""

    def script(self) -> list[list[Event]]:
        """What the headless run does: groups of events, a frame after each."""


def play(demo: Interactive, *, window: bool, frames: int | None = None, output: Path = Path("demo"),
         screenshot: Path | None = None, fullscreen: bool = False) -> list[Path]:
    """Run ``demo`` in a window (the user's keys, until q) or headless (its script); returns the files written.

    ``frames``: headless, or with ``screenshot``, keep the script's first that many frames; in a live window,
    close after that many. ``screenshot``: run the script in the window and save what the display shows.
    ``fullscreen``: open the window full screen.
    """
    scripted = not window or screenshot is not None
    screen = Screen(demo.name, demo.title, demo.frame_size(), window=window, frames=None if scripted else frames,
                    output=output, caption_lines=getattr(demo, "caption_lines", 1), fullscreen=fullscreen,
                    scripted=scripted, smooth=getattr(demo, "smooth", False))
    try:
        blank = np.full((*demo.frame_size()[::-1], 3), 0, np.uint8)
        for what in demo.prepare(screen.ctx):
            if screen.win is not None:
                screen.show(blank, f"{demo.title}: {what} …", preparing=True)
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
        screen.show(demo.frame(), demo.caption())
        kept += 1
        return frames is not None and kept >= frames

    for k, group in enumerate(demo.script()):
        for event in group:
            screen.note(event)
            demo.handle(event)
        while demo.busy():
            milestone = demo.step(STEP_SECONDS)
            screen.events()                       # a scripted window still answers q
            if milestone and k == 0 and demo.busy():
                if keep():
                    return
            elif screen.win is not None:
                screen.show(demo.frame(), demo.caption(), preparing=True)
        if keep():
            return


def _live(demo: Interactive, screen: Screen) -> None:
    frame = caption = None
    while True:
        changed = frame is None
        for event in screen.events():
            demo.handle(event)
            changed = True
        if demo.busy():
            demo.step(STEP_SECONDS)
            changed = True
        if changed:
            frame, caption = demo.frame(), demo.caption()
        else:
            screen.wait()
        screen.show(frame, caption)


class Prepared:
    """What a demo with a slow set-up shares: :meth:`prepare` runs its ``_preparing`` steps once, however far an
    earlier call got, and :meth:`ready` finishes them (a test, or a key pressed early, needs the demo ready)."""
    _steps: Iterator[str] | None = None
    _ctx: Any = None

    def prepare(self, ctx: Any) -> Iterator[str]:
        """The set-up's steps, each yielding what it does next; in ``ctx`` (None: a standalone context)."""
        if self._steps is None:
            self._ctx = ctx
            self._steps = self._preparing()
        yield from self._steps

    def ready(self) -> None:
        """Finish the set-up now."""
        for _ in self.prepare(self._ctx):
            pass

    def _preparing(self) -> Iterator[str]:
        yield from ()
