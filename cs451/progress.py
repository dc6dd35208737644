"""A small progress bar on stderr for anything that takes more than a second."""
from __future__ import annotations

import sys
import time
from typing import Iterable, Iterator, TypeVar

T = TypeVar("T")


class Progress:
    """Shows ``label [####....] 3/8 1.2s`` once the work has run past ``delay`` seconds."""

    def __init__(self, label: str, total: int, delay: float = 1.0, stream=None):
        self.label, self.total, self.delay = label, max(total, 1), delay
        self.stream = stream or sys.stderr
        self.start = time.perf_counter()
        self.done = 0
        self.shown = False
        self.live = hasattr(self.stream, "isatty") and self.stream.isatty()  # no carriage-return noise in logs

    def advance(self, n: int = 1, note: str = "") -> None:
        self.done += n
        if not self.live:
            return
        elapsed = time.perf_counter() - self.start
        if elapsed < self.delay and self.done < self.total:
            return
        if elapsed < self.delay and not self.shown:
            return
        width = 24
        filled = int(width * self.done / self.total)
        line = f"\r{self.label} [{'#' * filled}{'.' * (width - filled)}] {self.done}/{self.total} {elapsed:.1f}s {note}"
        self.stream.write(line[:120].ljust(80))
        self.stream.flush()
        self.shown = True

    def close(self) -> None:
        if self.shown:
            self.stream.write("\n")
            self.stream.flush()


def track(items: Iterable[T], label: str, total: int | None = None) -> Iterator[T]:
    """Iterate with a progress bar."""
    items = list(items) if total is None else items
    bar = Progress(label, total if total is not None else len(items))  # type: ignore[arg-type]
    try:
        for item in items:
            yield item
            bar.advance()
    finally:
        bar.close()
