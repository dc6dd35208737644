"""The sandbox's folders: where a private run folder may live, the tmpfs a test's job folder gets, what any
user may write in (swept after a test), and removing what a test left without following its links.
"""
from __future__ import annotations

import ctypes
import os
import shutil
import stat
import subprocess
import sys
from pathlib import Path

MS_NOSUID, MS_NODEV = 2, 4
OUTPUT_LIMIT = 4000            # characters of printed output kept


def is_root() -> bool:
    """Whether the grader runs as root (never on Windows): only root may use throwaway uids, cgroups and mounts, and
    root never runs a submission without isolation."""
    return hasattr(os, "geteuid") and os.geteuid() == 0


def private_folder_above(path: Path) -> Path | None:
    """The first folder on the way to ``path`` (as written, and with its links resolved) that users who are neither
    its owner nor in its group may not pass through (no ``o+x``), or None."""
    seen: set[Path] = set()
    for route in (Path(os.path.abspath(path)), Path(path).resolve()):
        for folder in [*reversed(route.parents), route]:
            if folder in seen:
                continue
            seen.add(folder)
            try:
                mode = os.stat(folder).st_mode
            except OSError:
                continue
            if stat.S_ISDIR(mode) and not mode & stat.S_IXOTH:
                return folder
    return None


def world_writable_dirs() -> list[Path]:
    """Where any user may create files: the places a uid-only sandbox must sweep after a test."""
    found = []
    for top in (Path("/tmp"), Path("/var/tmp"), Path("/dev/shm"), Path("/dev/mqueue"), Path("/run/lock"),
                Path("/var/lock")):
        try:
            if top.is_dir() and not top.is_symlink() and top.stat().st_mode & 0o002:
                found.append(top)
                found += [c for c in top.iterdir() if c.is_dir() and not c.is_symlink() and c.stat().st_mode & 0o002]
        except OSError:
            continue
    return found


def mount_tmpfs(folder: Path, size: int) -> bool:
    """Mount a tmpfs of ``size`` bytes on ``folder`` (as root, where this machine lets us: not in most containers,
    or not with ``CS451_NO_MOUNT``, which the kit's tests use to run the watch that stands in for it)."""
    if not is_root() or os.environ.get("CS451_NO_MOUNT") or sys.platform != "linux":
        return False
    libc = ctypes.CDLL(None, use_errno=True)
    return libc.mount(b"tmpfs", str(folder).encode(), b"tmpfs", MS_NOSUID | MS_NODEV,
                      f"size={size},mode=0700".encode()) == 0


def free_bytes(folder: Path) -> int:
    """The bytes an ordinary user may still write on ``folder``'s file system (a job tmpfs nearly full: its answer
    may not have fitted)."""
    st = os.statvfs(folder)
    return st.f_bavail * st.f_frsize


def remove_tree(path: Path) -> None:
    """Remove a folder the sandbox wrote, however deep or strange (never following links)."""
    if not os.path.lexists(path):
        return
    if shutil.which("rm"):
        subprocess.run(["rm", "-rf", "--", str(path)], stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                       stderr=subprocess.DEVNULL, check=False)
    if os.path.lexists(path):
        shutil.rmtree(path, ignore_errors=True)


def read_log(log_path: Path) -> str:
    """A worker's printed output: its first OUTPUT_LIMIT bytes, bad bytes replaced, and a note of what was cut."""
    size = log_path.stat().st_size
    with open(log_path, "rb") as log:
        text = log.read(OUTPUT_LIMIT).decode("utf-8", "replace")
    if size > OUTPUT_LIMIT:
        text += f"\n… ({size - OUTPUT_LIMIT} more bytes of output cut)"
    return text

