"""Copying an upload into the grader's own folder before any of its code runs, as hostile data.

An upload may hold symbolic links (to the reference, to ``/dev/zero``, dangling),
FIFOs, devices, huge files and deep trees. The copy follows no link and opens no
file that is not regular (``O_NOFOLLOW | O_NONBLOCK``, then ``fstat``), works
from directory descriptors so no path is resolved twice, stops at caps on total
size, file count and depth, and leaves every file read-only to the sandbox:
the worker imports the submission from this copy and can change nothing in it
(so one test cannot leave data for the next). Anything skipped is listed, so the
student is told why a file was not graded.
"""
from __future__ import annotations

import os
import stat
from dataclasses import dataclass, field
from pathlib import Path

from ..errors import SubmissionError

MAX_BYTES = 64 << 20      # the whole upload
MAX_FILES = 5000
MAX_DEPTH = 24            # folders below the upload's root
#: Names never copied: build litter and version-control folders, which no submission needs.
SKIPPED_NAMES = {"__pycache__", ".git", ".hg", ".svn", ".venv", "venv", "node_modules", ".pytest_cache",
                 ".cs451-cache", ".mypy_cache", ".ipynb_checkpoints"}


class UploadError(SubmissionError):
    """The upload cannot be copied (too big, too deep, not a folder): the student can fix it."""


@dataclass
class StagedUpload:
    root: Path                       # the copy (read-only to the sandbox)
    files: int = 0
    bytes: int = 0
    skipped: list[str] = field(default_factory=list)   # "path (why)" for each entry not copied

    def note(self) -> str | None:
        """A one-line note for the results when something was skipped."""
        if not self.skipped:
            return None
        shown = ", ".join(self.skipped[:5]) + (f" and {len(self.skipped) - 5} more" if len(self.skipped) > 5 else "")
        return f"not graded (only regular files and folders are): {shown}"


_FILE_FLAGS = os.O_RDONLY | getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_CLOEXEC", 0)
_DIR_FLAGS = os.O_RDONLY | getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_DIRECTORY", 0) | getattr(os, "O_CLOEXEC", 0)


def stage_upload(source: str | Path, dest: Path) -> StagedUpload:
    """Copy the folder ``source`` to ``dest`` (which must not exist) under the caps; ``UploadError`` past them."""
    source = Path(source)
    try:
        st = os.lstat(source)
    except OSError:
        raise UploadError(f"{source}: submission folder not found") from None
    if stat.S_ISLNK(st.st_mode):
        raise UploadError(f"{source}: the submission folder is a symbolic link; submit the folder itself")
    if not stat.S_ISDIR(st.st_mode):
        raise UploadError(f"{source}: the submission is not a folder")
    staged = StagedUpload(dest)
    dest.mkdir(mode=0o755)
    fd = os.open(source, _DIR_FLAGS)
    try:
        _copy_dir(fd, dest, "", 0, staged)
    finally:
        os.close(fd)
    return staged


def _copy_dir(dir_fd: int, dest: Path, rel: str, depth: int, staged: StagedUpload) -> None:
    with os.scandir(dir_fd) as entries:
        names = sorted(e.name for e in entries)
    for name in names:
        path = f"{rel}{name}"
        if name in SKIPPED_NAMES or name.endswith((".pyc", ".egg-info")):
            continue
        try:
            st = os.stat(name, dir_fd=dir_fd, follow_symlinks=False)
        except OSError:
            staged.skipped.append(f"{path} (unreadable)")
            continue
        if stat.S_ISDIR(st.st_mode):
            if depth + 1 > MAX_DEPTH:
                raise UploadError(f"the upload is nested more than {MAX_DEPTH} folders deep (at {path}/)")
            child = os.open(name, _DIR_FLAGS, dir_fd=dir_fd)
            try:
                (dest / name).mkdir(mode=0o755)
                _copy_dir(child, dest / name, f"{path}/", depth + 1, staged)
            finally:
                os.close(child)
        elif stat.S_ISREG(st.st_mode):
            _copy_file(dir_fd, name, dest / name, path, staged)
        else:
            kind = "a symbolic link" if stat.S_ISLNK(st.st_mode) else "not a regular file"
            staged.skipped.append(f"{path} ({kind})")


def _copy_file(dir_fd: int, name: str, target: Path, path: str, staged: StagedUpload) -> None:
    staged.files += 1
    if staged.files > MAX_FILES:
        raise UploadError(f"the upload holds more than {MAX_FILES} files; submit only your package")
    fd = os.open(name, _FILE_FLAGS, dir_fd=dir_fd)
    try:
        if not stat.S_ISREG(os.fstat(fd).st_mode):  # replaced between the listing and the open
            staged.skipped.append(f"{path} (not a regular file)")
            return
        out = os.open(target, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o644)
        try:
            while chunk := os.read(fd, 1 << 20):
                staged.bytes += len(chunk)
                if staged.bytes > MAX_BYTES:
                    raise UploadError(f"the upload is larger than {MAX_BYTES >> 20} MiB; submit only your package")
                os.write(out, chunk)
        finally:
            os.close(out)
    finally:
        os.close(fd)
