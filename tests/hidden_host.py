"""A command run as on a grading server that holds no other copy of the kit: this machine's own copies hidden.

The uid-only sandbox cannot hide a world-readable file, and its canary refuses to grade where the sandbox user
can read a copy of the kit's reference or answers anywhere (``cs451.grading.canary``). A Gradescope image holds
none; this machine holds this checkout, the tests' own corpora in ``/tmp`` (copies of the reference) and other
sessions' copies. :func:`hiding_host` runs a command in a private mount namespace (as root) with a fresh ``/tmp``
holding only the folders it keeps, and the checkout's secret folders covered by empty private ones.
"""
from __future__ import annotations

import ctypes
import json
import os
import sys
from pathlib import Path

MS_BIND = 4096


def hiding_host(command: list[str], keep: list[Path]) -> list[str]:
    """``command`` wrapped: a private mount namespace, a fresh ``/tmp`` with ``keep`` (folders in /tmp) bound back,
    the checkout's reference, specs, tests, history and caches covered."""
    from cs451.grading.runner import protected_paths
    spec = {"argv": command, "keep": [str(k) for k in keep],
            "hide": [str(p) for p in protected_paths() if p.is_dir() and not p.is_symlink()]}
    return ["unshare", "--mount", "--propagation", "private", sys.executable, __file__, json.dumps(spec)]


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
    for folder in spec["hide"]:
        _mount("tmpfs", folder, "tmpfs", 0, "mode=0700")
    os.execvp(spec["argv"][0], spec["argv"])


if __name__ == "__main__":
    main(json.loads(sys.argv[1]))
