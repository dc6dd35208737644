"""Running one trusted check on untrusted data with its own time and memory limit.

A check is the grader's code, but it walks arrays the submission chose: a valid
hierarchy of four million nodes, or a shape that makes an honest comparison
allocate gigabytes. Each check runs in a forked child with a CPU-time and an
address-space limit (above what the child already maps) and a wall-clock
deadline; the parent gets the result back through a pipe, or a reason. Where
``fork`` does not exist (Windows), the check runs in the grader's process.
"""
from __future__ import annotations

import os
import pickle
import select
import signal
import time
from typing import Any, Callable

CHECK_SECONDS = 60.0          # wall clock for one check (the largest honest check takes well under a second)
CHECK_MEMORY = 2 << 30        # bytes of address space a check may add to what the grader maps


class GuardError(Exception):
    """The check did not finish: it ran out of time or memory, or crashed."""


class CheckFailed(Exception):
    """The check raised on this answer (a shape or value it did not foresee); the message names the error."""


def _address_space() -> int:
    try:
        with open("/proc/self/status") as f:
            for line in f:
                if line.startswith("VmSize:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    return 0


def run_guarded(fn: Callable[..., Any], *args: Any, seconds: float = CHECK_SECONDS,
                memory: int = CHECK_MEMORY) -> Any:
    """``fn(*args)`` in a forked child under the limits: its return value, ``CheckFailed`` if it raised, else ``GuardError``."""
    if not hasattr(os, "fork"):
        return fn(*args)
    read_end, write_end = os.pipe()
    pid = os.fork()
    if pid == 0:  # the child: limits, the check, the pickled answer, and out without cleanup handlers
        code = 0
        try:
            os.close(read_end)
            import resource
            cpu = int(seconds) + 1
            resource.setrlimit(resource.RLIMIT_CPU, (cpu, cpu + 1))
            used = _address_space()
            if used:
                resource.setrlimit(resource.RLIMIT_AS, (used + memory, used + memory))
            try:
                payload = pickle.dumps(("ok", fn(*args)))
            except MemoryError:
                payload = pickle.dumps(("error", "the check ran out of memory on this answer"))
            except BaseException as err:  # noqa: BLE001 - any failure becomes the parent's CheckFailed
                payload = pickle.dumps(("raised", f"{type(err).__name__}: {err}"[:500]))
            view = memoryview(payload)
            while view:
                view = view[os.write(write_end, view):]
        except BaseException:  # noqa: BLE001
            code = 1
        finally:
            os._exit(code)
    os.close(write_end)
    chunks, deadline = [], time.monotonic() + seconds + 5
    try:
        while True:
            left = deadline - time.monotonic()
            if left <= 0:
                os.kill(pid, signal.SIGKILL)
                raise GuardError(f"checking this answer took longer than {seconds:g} s")
            ready, _, _ = select.select([read_end], [], [], left)
            if not ready:
                continue
            chunk = os.read(read_end, 1 << 20)
            if not chunk:
                break
            chunks.append(chunk)
    finally:
        os.close(read_end)
        _, status = os.waitpid(pid, 0)
    if not chunks:
        sig = os.WTERMSIG(status) if os.WIFSIGNALED(status) else None
        why = {signal.SIGXCPU: "took too much CPU time", signal.SIGKILL: "was killed"}.get(sig, "crashed")
        raise GuardError(f"checking this answer {why}")
    kind, value = pickle.loads(b"".join(chunks))
    if kind == "ok":
        return value
    if kind == "raised":
        raise CheckFailed(value)
    raise GuardError(value)
