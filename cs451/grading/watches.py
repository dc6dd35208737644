"""Watches over a running test where the kernel cannot cap it: the disk it keeps (no tmpfs of its own) and the
memory of everything it starts (no cgroup). Each polls from a thread and ends the test past its cap.
"""
from __future__ import annotations

import os
import signal
import stat
import threading
from typing import Callable
from pathlib import Path

from .processes import descendants, processes_of, rss
from .scratch import world_writable_dirs


def bytes_below(path: Path, limit_entries: int = 200_000) -> tuple[int, int]:
    """Bytes held on disk by ``path`` and everything below it (no link followed), and the entries counted."""
    total, entries, todo = 0, 0, [str(path)]
    while todo and entries < limit_entries:
        here = todo.pop()
        try:
            st = os.lstat(here)
        except OSError:
            continue
        entries += 1
        total += st.st_blocks * 512
        if stat.S_ISDIR(st.st_mode):
            try:
                todo += [e.path for e in os.scandir(here)]
            except OSError:
                continue
    return total, entries


class DiskWatch:
    """A disk quota where the job folder has no tmpfs of its own (no mount allowed) or the test may write in shared
    places (the uid mode): sum what the test keeps in its job folder and, for ``uid``, in ``/tmp``, ``/var/tmp``,
    ``/dev/shm``…, and end the test past ``cap`` bytes."""

    def __init__(self, job: Path, uid: int | None, cap: int, kill: Callable[[], None], every: float = 0.1):
        self.job, self.uid, self.cap, self.kill, self.every = job, uid, cap, kill, every
        self.tripped = False
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._watch, daemon=True)
        self._thread.start()

    def used(self) -> int:
        """Bytes the test keeps now: its job folder, and for a uid what it owns at the top of every world-writable
        folder."""
        total = bytes_below(self.job)[0]
        for folder in world_writable_dirs() if self.uid is not None else []:
            try:
                entries = list(os.scandir(folder))
            except OSError:
                continue
            for entry in entries:
                try:
                    if entry.stat(follow_symlinks=False).st_uid == self.uid:
                        total += bytes_below(Path(entry.path))[0]
                except OSError:
                    continue
        return total

    def _watch(self) -> None:
        while not self._stop.wait(self.every):
            if self.used() > self.cap:
                self.tripped = True
                self.kill()

    def stop(self) -> None:
        """End the watch and wait for its thread (after the test, before its files are removed); ``tripped`` stays."""
        self._stop.set()
        self._thread.join()


class Watchdog:
    """Where no cgroup can be made: sum the memory of the test's processes and kill them all past the cap."""

    def __init__(self, pid: int, uid: int | None, cap: int, every: float = 0.05):
        self.pid, self.uid, self.cap, self.every = pid, uid, cap, every
        self.peak, self.tripped = 0, False
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._watch, daemon=True)
        self._thread.start()

    def _members(self) -> list[int]:
        return processes_of(self.uid) if self.uid is not None else descendants(self.pid)

    def _watch(self) -> None:
        while not self._stop.wait(self.every):
            members = self._members()
            total = sum(rss(p) for p in members)
            self.peak = max(self.peak, total)
            if total > self.cap:
                self.tripped = True
                for p in members:
                    try:
                        os.kill(p, signal.SIGKILL)
                    except (ProcessLookupError, PermissionError):
                        pass

    def stop(self) -> None:
        """End the watch and wait for its thread; ``peak`` and ``tripped`` then hold for the whole test."""
        self._stop.set()
        self._thread.join()

