"""Where a command will write, checked before any work: a wrong ``--results`` or ``-o`` is refused in one line
naming it, not after a grading run or a benchmark has been waited for."""
from __future__ import annotations

import os
import tempfile
from pathlib import Path

from .errors import KitError


def check_writable(path: str | Path, option: str, *, folder: bool = False, example: str = "results.json") -> Path:
    """Refuse, in one line naming ``option`` and the path, an output that cannot be written: a file where a folder is
    wanted (or a folder where a file is), a file in the way of a folder to make, a folder that takes no new file.

    Folders that do not exist yet are fine (the command makes them, as ``cs451 render -o`` does); the folder they
    will be made in is the one tried. A file is tried by making an unnamed temporary file beside it, which no
    permission bit can fool (a root user, a read-only mount, ``/proc``)."""
    text = str(path)
    path = Path(path).expanduser()
    if folder:
        if path.exists() and not path.is_dir():
            raise KitError(f"{option} {text}: is a file, not a folder")
    elif text.endswith(("/", "\\")) or path.is_dir():
        raise KitError(f"{option} {text}: is a folder; give a file name such as {path / example}")
    elif path.exists() and not os.access(path, os.W_OK):
        raise KitError(f"{option} {text}: cannot be written (Permission denied)")
    start = path if folder else path.parent
    existing = next((p for p in (start, *start.parents) if p.exists()), None)
    if existing is None:        # nothing of it exists, not even its root: the write would say why
        return path
    if not existing.is_dir():
        raise KitError(f"{option} {text}: {existing} is a file, not a folder")
    try:
        with tempfile.TemporaryFile(dir=existing):
            pass
    except OSError as err:
        raise KitError(f"{option} {text}: the folder {existing} cannot be written ({err.strerror or err})") from None
    return path
