"""The processes a test leaves and the throwaway uids tests run as: finding, counting, measuring and killing them.

A test's processes are found by uid (under the uid-only sandbox) or by descent from the test's first process, since
a submission may ``setsid`` or double-fork away from its process group.
"""
from __future__ import annotations

import os
import random
import signal
import subprocess
import time
from pathlib import Path

from ..errors import KitError

UID_RANGE = (2_000_000_000, 2_100_000_000)   # throwaway uids: far above any real account


class IsolationError(KitError):
    """The sandbox cannot be set up as required here: grading must not go on (the message says why)."""


def drop_to(uid: int) -> None:
    """Become ``uid`` for good (its own gid, no supplementary groups), in the child before exec; exits 111
    rather than go on as anyone else."""
    os.setgroups([])
    os.setgid(uid)
    os.setuid(uid)
    if os.getuid() != uid or os.geteuid() != uid:  # never go on as anyone else
        os._exit(111)


def count_processes(uid: int) -> int:
    """How many live processes ``uid`` has: RLIMIT_NPROC counts them all, so the sandbox adds its allowance to it."""
    return len(processes_of(uid))


def processes_of(uid: int) -> list[int]:
    """Live processes of ``uid`` (zombies are dead already: they wait only for a parent to reap them)."""
    found = []
    for status in Path("/proc").glob("[0-9]*/status"):
        try:
            fields = dict(line.split(":", 1) for line in status.read_text().splitlines() if ":" in line)
            if int(fields["Uid"].split()[0]) == uid and not fields["State"].strip().startswith(("Z", "X")):
                found.append(int(status.parent.name))
        except (OSError, ValueError, KeyError):
            continue
    return found


def descendants(root: int) -> list[int]:
    """``root`` and every process below it, from one reading of /proc (what the watchdog sums when no uid is given)."""
    children: dict[int, list[int]] = {}
    for stat_file in Path("/proc").glob("[0-9]*/stat"):
        try:
            text = stat_file.read_text()
            ppid = int(text[text.rindex(")") + 2:].split()[1])
        except (OSError, ValueError):
            continue
        children.setdefault(ppid, []).append(int(stat_file.parent.name))
    out, todo = [], [root]
    while todo:
        pid = todo.pop()
        out.append(pid)
        todo.extend(children.get(pid, []))
    return out


def rss(pid: int) -> int:
    """A process's resident memory in bytes (0 once it is gone): what the watchdog sums over a test's processes."""
    try:
        for line in Path(f"/proc/{pid}/status").read_text().splitlines():
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) * 1024
    except (OSError, ValueError):
        pass
    return 0


def kill_uid(uid: int) -> None:
    """Kill every process of ``uid``: a child drops to it and signals everyone it may (``kill(-1)``)."""
    for _ in range(100):
        if not processes_of(uid):
            return
        pid = os.fork()
        if pid == 0:
            try:
                drop_to(uid)
                os.kill(-1, signal.SIGKILL)
            finally:
                os._exit(0)
        os.waitpid(pid, 0)
        time.sleep(0.01)


def free_uid() -> int:
    """A throwaway uid in ``UID_RANGE`` that no process runs as now, for one test (IsolationError if none is found)."""
    for _ in range(1000):
        uid = random.randrange(*UID_RANGE)
        if not processes_of(uid):
            return uid
    raise IsolationError("no free uid for the sandbox")


def remove_ipc(uid: int) -> None:
    """System V shared memory, queues and semaphores the uid made (they outlive processes)."""
    for kind, flag in (("shm", "-m"), ("msg", "-q"), ("sem", "-s")):
        try:
            lines = Path(f"/proc/sysvipc/{kind}").read_text().splitlines()[1:]
        except OSError:
            continue
        header = Path(f"/proc/sysvipc/{kind}").read_text().splitlines()[0].split()
        for line in lines:
            cols = dict(zip(header, line.split()))
            if cols.get("uid") == str(uid) or cols.get("cuid") == str(uid):
                subprocess.run(["ipcrm", flag, cols.get("shmid") or cols.get("msqid") or cols.get("semid", "")],
                               stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=False)


def wait_for(proc: subprocess.Popen, seconds: float) -> bool:
    """Wait up to ``seconds`` for the worker, then SIGKILL its process group either way and reap it; True where it ran
    out of time."""
    timed_out = False
    try:
        proc.wait(timeout=seconds)
    except subprocess.TimeoutExpired:
        timed_out = True
    finally:
        try:
            os.killpg(proc.pid, signal.SIGKILL)
        except (ProcessLookupError, PermissionError, AttributeError):
            pass
        proc.wait()
    return timed_out

