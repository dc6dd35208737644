"""A control group per test: one memory cap and one process cap for everything the submission starts.

Per-process limits (``RLIMIT_AS``) let four children hold four times the memory;
a cgroup counts them all, and its process list finds every process a test
left behind, daemons included. Version 2 (one unified tree) and version 1
(separate ``memory`` and ``pids`` trees) are both handled. Creating one needs
root and a writable cgroup file system; where that is missing, ``create``
returns None and the sandbox falls back to watching the processes itself.
"""
from __future__ import annotations

import os
import signal
import time
import uuid
from dataclasses import dataclass
from pathlib import Path

ROOT = Path("/sys/fs/cgroup")


def _write(path: Path, value: str) -> None:
    with open(path, "w") as f:
        f.write(value)


def _read(path: Path) -> str:
    try:
        return path.read_text()
    except OSError:
        return ""


@dataclass
class TestGroup:
    """The cgroup folders of one test (one on v2, two on v1) and how to read them."""
    folders: list[Path]
    memory: Path          # the folder holding the memory files
    version: int

    @property
    def procs_files(self) -> list[Path]:
        """Where a process writes its pid to join (the worker does it before exec)."""
        return [f / "cgroup.procs" for f in self.folders]

    def pids(self) -> list[int]:
        found: set[int] = set()
        for folder in self.folders:
            found.update(int(p) for p in _read(folder / "cgroup.procs").split())
        return sorted(found)

    def peak_memory(self) -> int:
        name = "memory.peak" if self.version == 2 else "memory.max_usage_in_bytes"
        text = _read(self.memory / name).strip()
        return int(text) if text.isdigit() else 0

    def out_of_memory(self) -> bool:
        """Whether the kernel killed a process of this group for memory."""
        name = "memory.events" if self.version == 2 else "memory.oom_control"
        counts = dict(line.split() for line in _read(self.memory / name).splitlines() if len(line.split()) == 2)
        return counts.get("oom_kill", "0").isdigit() and int(counts.get("oom_kill", "0")) > 0

    def kill_all(self) -> None:
        """SIGKILL every process in the group until none is left (a fork in flight joins the group)."""
        for folder in self.folders:
            if (folder / "cgroup.kill").exists():
                try:
                    _write(folder / "cgroup.kill", "1")
                except OSError:
                    pass
        for _ in range(200):
            pids = self.pids()
            if not pids:
                return
            for pid in pids:
                try:
                    os.kill(pid, signal.SIGKILL)
                except ProcessLookupError:
                    pass
            time.sleep(0.01)

    def remove(self) -> None:
        self.kill_all()
        for folder in self.folders:
            for _ in range(100):
                try:
                    folder.rmdir()
                    break
                except FileNotFoundError:
                    break
                except OSError:
                    time.sleep(0.02)


def _version() -> int | None:
    if (ROOT / "cgroup.controllers").exists():
        return 2
    if (ROOT / "memory" / "cgroup.procs").exists() and (ROOT / "pids" / "cgroup.procs").exists():
        return 1
    return None


def create(memory_bytes: int, max_pids: int) -> TestGroup | None:
    """A fresh cgroup with the caps, or None where this machine does not let us make one (or ``CS451_NO_CGROUP`` is set,
    which the kit's tests use to run the watchdog that stands in for it)."""
    if os.name != "posix" or os.geteuid() != 0 or os.environ.get("CS451_NO_CGROUP"):
        return None
    version = _version()
    name = f"cs451-{uuid.uuid4().hex[:12]}"
    made: list[Path] = []
    try:
        if version == 2:
            parent = ROOT / "cs451"
            parent.mkdir(exist_ok=True)
            controllers = _read(ROOT / "cgroup.controllers").split()
            if not {"memory", "pids"} <= set(controllers):
                return None
            _write(ROOT / "cgroup.subtree_control", "+memory +pids")
            _write(parent / "cgroup.subtree_control", "+memory +pids")
            folder = parent / name
            folder.mkdir()
            made.append(folder)
            _write(folder / "memory.max", str(memory_bytes))
            if (folder / "memory.swap.max").exists():
                _write(folder / "memory.swap.max", "0")
            _write(folder / "pids.max", str(max_pids))
            return TestGroup([folder], folder, 2)
        if version == 1:
            mem, pids = ROOT / "memory" / "cs451" / name, ROOT / "pids" / "cs451" / name
            for folder in (mem, pids):
                folder.mkdir(parents=True)
                made.append(folder)
            _write(mem / "memory.limit_in_bytes", str(memory_bytes))
            if (mem / "memory.memsw.limit_in_bytes").exists():
                _write(mem / "memory.memsw.limit_in_bytes", str(memory_bytes))
            _write(pids / "pids.max", str(max_pids))
            return TestGroup([mem, pids], mem, 1)
    except OSError:
        for folder in made:
            try:
                folder.rmdir()
            except OSError:
                pass
    return None


def join(group_procs: list[Path]) -> None:
    """Move the calling process into the group (run in the child before it execs the worker)."""
    pid = str(os.getpid())
    for path in group_procs:
        _write(path, pid)
