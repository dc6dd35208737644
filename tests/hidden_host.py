"""A command run as on a grading server that holds no other copy of the kit: this machine's own copies hidden.

The uid-only sandbox cannot hide a world-readable file, and its canary refuses to grade where the sandbox user
can read a copy of the kit's reference or answers anywhere (``cs451.grading.canary``). A Gradescope image holds
none; this machine holds this checkout, the tests' own corpora in ``/tmp`` (copies of the reference) and other
sessions' copies (a CI run's clean checkout sits beside the working one). :func:`hiding_host` runs a command in a
private mount namespace (as root) with a fresh ``/tmp`` holding only the folders it keeps, the checkout's secret
folders covered by empty private ones, and every other copy the canary would find (searched once a session, as a
throwaway uid, exactly as the canary searches) covered too: an empty folder over a folder, ``/dev/null`` over a file.
"""
from __future__ import annotations

import ctypes
import functools
import json
import os
import sys
import time
from pathlib import Path

MS_BIND = 4096


def hiding_host(command: list[str], keep: list[Path]) -> list[str]:
    """``command`` wrapped: a private mount namespace, a fresh ``/tmp`` with ``keep`` (folders in /tmp) bound back,
    the checkout's reference, specs, tests, history and caches covered."""
    from cs451.grading.runner import protected_paths
    hide = [str(p) for p in protected_paths() if p.is_dir() and not p.is_symlink()]
    spec = {"argv": command, "keep": [str(k) for k in keep],
            "hide": hide + [p for p in readable_copies() if p not in hide]}
    return ["unshare", "--mount", "--propagation", "private", sys.executable, __file__, json.dumps(spec)]


@functools.cache
def readable_copies() -> tuple[str, ...]:
    """What the canary finds outside ``/tmp`` as a throwaway uid: paths to copies of the kit's reference or answers
    that only this machine holds (other checkouts, their archives). Searched in a child that drops to the uid."""
    from cs451.grading.canary import search
    from cs451.grading.sandbox import UID_RANGE
    from cs451.stages import stage_names
    read, write = os.pipe()
    pid = os.fork()
    if pid == 0:
        try:
            os.close(read)
            os.setgroups([])
            os.setgid(UID_RANGE[0] + 7)
            os.setuid(UID_RANGE[0] + 7)
            found, complete, _ = search("/", set(stage_names()), ["/tmp"], time.monotonic() + 300, limit=100_000)
            os.write(write, json.dumps({"found": found, "complete": complete}).encode())
        finally:
            os._exit(0)
    os.close(write)
    with os.fdopen(read, "rb") as answer:
        data = answer.read()
    os.waitpid(pid, 0)
    result = json.loads(data)
    if not result["complete"]:
        raise RuntimeError("the search for this machine's readable copies of the kit did not finish in 300 s")
    return tuple(sorted({_cover_for(*line.partition(": ")[::2]) for line in result["found"]}))


def _cover_for(path: str, why: str) -> str:
    """What to cover so that the canary finds nothing there: a file found by its name (a ``hidden.py`` in
    ``autograder/<stage>/``) is found whatever it holds, so its folder; an archive or a solution region, itself."""
    if os.path.isdir(path) or "inside the archive" in why or "solution region" in why:
        return path
    return os.path.dirname(path)


def _mount(source: str, target: str, kind: str | None, flags: int, data: str | None) -> None:
    libc = ctypes.CDLL(None, use_errno=True)
    if libc.mount(source.encode(), target.encode(), kind.encode() if kind else None, flags,
                  data.encode() if data else None) != 0:
        raise OSError(ctypes.get_errno(), f"mount {source} on {target}: {os.strerror(ctypes.get_errno())}")


def main(spec: dict) -> None:
    kept = [(os.open(k, os.O_RDONLY | os.O_DIRECTORY), k) for k in spec["keep"]]
    _mount("tmpfs", "/tmp", "tmpfs", 0, "mode=1777")
    for fd, folder in kept:
        os.makedirs(folder, mode=0o755, exist_ok=True)
        _mount(f"/proc/self/fd/{fd}", folder, None, MS_BIND, None)
        os.close(fd)
    for path in spec["hide"]:
        if os.path.isdir(path):
            _mount("tmpfs", path, "tmpfs", 0, "mode=0700")
        elif os.path.exists(path):
            _mount("/dev/null", path, None, MS_BIND, None)
    os.execvp(spec["argv"][0], spec["argv"])


if __name__ == "__main__":
    main(json.loads(sys.argv[1]))
