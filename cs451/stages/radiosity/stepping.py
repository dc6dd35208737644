"""A loop the submission drives, run one step at a time: the shooting loop (R3) calls back after each shot, and a
demo must pause it there, step it one shot, or drop it and start again.

The loop runs in a thread of its own (:class:`Stepper`), held at each callback until the demo asks for the next
step. Everything else it asks for is done in the demo's (main) thread: ``ask(fn, *args)`` hands the call over and
waits for its answer, so OpenGL (the hemicube engine's rows, drawn in the window's context) never leaves the thread
that owns the context, and a KitError the submission earns is raised in the demo as it would be without a thread.
"""
from __future__ import annotations

import queue
import threading
import time
from typing import Any, Callable


#: The loop's thread's name (a test counts them).
THREAD_NAME = "cs451-demo-loop"


class Stopped(Exception):
    """Raised inside the loop's thread when the demo drops the loop (reset, or the window closed)."""


class Stepper:
    """``run(ask, on_step)`` in a thread: ``ask(fn, *args)`` runs ``fn`` in the demo's thread; ``on_step(*state)``
    hands a step's state to the demo and holds the loop until :meth:`advance` is called again."""

    def __init__(self, run: Callable[[Callable[..., Any], Callable[..., None]], Any]):
        self._to_demo: queue.Queue = queue.Queue()
        self._to_loop: queue.Queue = queue.Queue()
        self._held = False
        self.finished = False
        self.result: Any = None
        self._thread = threading.Thread(target=self._main, args=(run,), daemon=True, name=THREAD_NAME)
        self._thread.start()

    # --- in the loop's thread ------------------------------------------------------------------------------
    def _main(self, run: Callable) -> None:
        try:
            self._to_demo.put(("done", run(self._ask, self._on_step)))
        except Stopped:
            self._to_demo.put(("stopped", None))
        except BaseException as err:             # the demo's thread raises it
            self._to_demo.put(("error", err))

    def _ask(self, fn: Callable, *args: Any) -> Any:
        self._to_demo.put(("ask", (fn, args)))
        kind, value = self._to_loop.get()
        if kind == "stop":
            raise Stopped
        if kind == "error":
            raise value
        return value

    def _on_step(self, *state: Any) -> None:
        self._to_demo.put(("step", state))
        if self._to_loop.get()[0] == "stop":
            raise Stopped

    # --- in the demo's thread ------------------------------------------------------------------------------
    def advance(self, seconds: float) -> tuple[Any, ...] | None:
        """Let the loop run to its next step, answering what it asks, for at most about ``seconds``: the step's
        state, or None (not there yet, or the loop finished: then ``finished`` and ``result``)."""
        if self.finished:
            return None
        if self._held:
            self._held = False
            self._to_loop.put(("go", None))
        stop = time.perf_counter() + seconds
        while True:
            try:
                kind, value = self._to_demo.get(timeout=max(0.0, stop - time.perf_counter()))
            except queue.Empty:
                return None
            if kind == "ask":
                fn, args = value
                try:
                    answer = ("value", fn(*args))
                except Exception as err:          # the loop sees it (the submission's code may handle it)
                    answer = ("error", err)
                self._to_loop.put(answer)
            elif kind == "step":
                self._held = True
                return value
            elif kind == "done":
                self.finished, self.result = True, value
                return None
            elif kind == "error":
                self.finished = True
                raise value
            else:
                self.finished = True
                return None

    def stop(self, timeout: float = 10.0) -> None:
        """Drop the loop: it raises :class:`Stopped` at its next callback or request; wait until its thread ends (a
        loop that swallows the exception and runs on is left to die with the process, a daemon, after ``timeout``)."""
        give_up = time.perf_counter() + timeout
        while self._thread.is_alive() and time.perf_counter() < give_up:
            if self._held:
                self._held = False
                self._to_loop.put(("stop", None))
            try:
                kind, _ = self._to_demo.get(timeout=0.5)
            except queue.Empty:
                continue
            if kind == "step":
                self._held = True
            elif kind == "ask":
                self._to_loop.put(("stop", None))
        self.finished = True
