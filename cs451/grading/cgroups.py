"""Control groups: one per test, capping the memory and processes of everything the submission starts, and one
per graded submission, giving it a fair share of the CPU.

Per-process limits (``RLIMIT_AS``) let four children hold four times the memory;
a cgroup counts them all, and its process list finds every process a test
left behind, daemons included. A submission's share (:func:`create_share`) has
the same CPU weight as every other submission's, however many processes it
starts or sessions it makes (the kernel's autogroup
gives each session a share of its own: a test whose children each call
``setsid`` took the CPU from a classmate graded beside it). Version 2 (one
unified tree) and version 1 (separate ``memory``, ``pids`` and ``cpu`` trees)
are both handled. Creating one needs root and a writable cgroup file system;
where that is missing, ``create`` returns None and the sandbox falls back to
watching the processes itself, and ``create_share`` returns None (no share).
"""
from __future__ import annotations

import os
import signal
import time
import uuid
from dataclasses import dataclass, field
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
    shared: list[Path] = field(default_factory=list)   # v1: the submission's CPU share, joined too, kept after

    @property
    def procs_files(self) -> list[Path]:
        """Where a process writes its pid to join (the worker does it before exec)."""
        return [f / "cgroup.procs" for f in self.folders] + self.shared

    def pids(self) -> list[int]:
        """Every process now in the group's folders, sorted: what :meth:`kill_all` must end (none once it has)."""
        found: set[int] = set()
        for folder in self.folders:
            found.update(int(p) for p in _read(folder / "cgroup.procs").split())
        return sorted(found)

    def peak_memory(self) -> int:
        """The most memory, in bytes, the group's processes held at once (0 where the kernel does not say)."""
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
        """Kill whatever the test left running and delete the group's own folders (a v1 share it joined stays)."""
        self.kill_all()
        for folder in self.folders:
            _rmdir(folder)


def _rmdir(folder: Path) -> None:
    """Remove an emptied cgroup folder, waiting for the kernel to let its last processes go."""
    for _ in range(100):
        try:
            folder.rmdir()
            return
        except FileNotFoundError:
            return
        except OSError:
            time.sleep(0.02)


def _version() -> int | None:
    if (ROOT / "cgroup.controllers").exists():
        return 2
    if (ROOT / "memory" / "cgroup.procs").exists() and (ROOT / "pids" / "cgroup.procs").exists():
        return 1
    return None


def _allowed() -> bool:
    return os.name == "posix" and os.geteuid() == 0 and not os.environ.get("CS451_NO_CGROUP")


@dataclass
class ShareGroup:
    """One graded submission's CPU share: the folder its tests' groups go in (v2) or that they also join (v1), and
    that the grader's own process grading it joins (:meth:`enter`), so its checks count against the share too."""
    folder: Path
    version: int
    _left: list[Path] = field(default_factory=list)   # where the grader's process was before each enter()

    @property
    def _grader(self) -> Path:
        return self.folder / "grader" if self.version == 2 else self.folder   # v2: processes only in leaves

    def enter(self) -> None:
        """Move the calling process (all its threads) into the share; :meth:`leave` moves it back."""
        try:
            here = _own_group(self.version)
            self._grader.mkdir(exist_ok=True)
            _write(self._grader / "cgroup.procs", str(os.getpid()))
            self._left.append(here)
        except OSError:
            pass

    def leave(self) -> None:
        """Move the calling process back to where each :meth:`enter` found it (or the nearest folder that takes it)."""
        while self._left:
            back = self._left.pop()
            for folder in (back, back.parent, ROOT / "cpu" if self.version == 1 else ROOT):
                try:
                    _write(folder / "cgroup.procs", str(os.getpid()))
                    break
                except OSError:
                    continue

    def remove(self) -> None:
        """Once its tests have ended (their own groups killed everything): v2's test groups go first."""
        self.leave()
        for folder in ([self._grader] if self.version == 2 else []) + [self.folder]:
            _rmdir(folder)


def _own_group(version: int) -> Path:
    """The calling process's cgroup folder in the cpu tree (v1) or the unified tree (v2)."""
    for line in _read(Path("/proc/self/cgroup")).splitlines():
        number, controllers, path = line.split(":", 2)
        if (version == 2 and number == "0") or (version == 1 and "cpu" in controllers.split(",")):
            return (ROOT / "cpu" if version == 1 else ROOT) / path.lstrip("/")
    return ROOT / "cpu" if version == 1 else ROOT


def create_share(weight: int = 100) -> ShareGroup | None:
    """A CPU share for one submission, of ``weight`` (v2's scale; every submission gets the same), or None where no
    cpu controller can be used (or ``CS451_NO_CPU_SHARE`` is set, which ``cs451 bench fair-share`` uses to measure
    grading without one)."""
    if not _allowed() or os.environ.get("CS451_NO_CPU_SHARE"):
        return None
    version = _version()
    folder = None
    try:
        if version == 2:
            if not {"cpu", "memory", "pids"} <= set(_read(ROOT / "cgroup.controllers").split()):
                return None
            parent = ROOT / "cs451"
            parent.mkdir(exist_ok=True)
            _write(ROOT / "cgroup.subtree_control", "+cpu +memory +pids")
            _write(parent / "cgroup.subtree_control", "+cpu +memory +pids")
            folder = parent / f"run-{uuid.uuid4().hex[:12]}"
            folder.mkdir()
            _write(folder / "cpu.weight", str(weight))
            _write(folder / "cgroup.subtree_control", "+memory +pids")   # its tests' groups hold the processes
            return ShareGroup(folder, 2)
        if version == 1 and (ROOT / "cpu" / "cgroup.procs").exists():
            folder = ROOT / "cpu" / "cs451" / f"run-{uuid.uuid4().hex[:12]}"
            folder.mkdir(parents=True)
            _write(folder / "cpu.shares", str(weight * 1024 // 100))
            return ShareGroup(folder, 1)
    except OSError:
        if folder is not None:
            _rmdir(folder)
    return None


def create(memory_bytes: int, max_pids: int, share: ShareGroup | None = None) -> TestGroup | None:
    """A fresh cgroup with the caps, inside ``share`` when given, or None where this machine does not let us make
    one (or ``CS451_NO_CGROUP`` is set, which the kit's tests use to run the watchdog that stands in for it)."""
    if not _allowed():
        return None
    version = _version()
    name = f"cs451-{uuid.uuid4().hex[:12]}"
    made: list[Path] = []
    try:
        if version == 2:
            parent = share.folder if share else ROOT / "cs451"
            parent.mkdir(exist_ok=True)
            controllers = _read(ROOT / "cgroup.controllers").split()
            if not {"memory", "pids"} <= set(controllers):
                return None
            if share is None:
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
            return TestGroup([mem, pids], mem, 1, [share.folder / "cgroup.procs"] if share else [])
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
