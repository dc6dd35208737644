"""Where the kit keeps what it computes once (slides' figures, compiled kernels): beside the kit, or the user's."""
from __future__ import annotations

import os
from pathlib import Path

from . import KIT_ROOT


def kit_cache(name: str) -> Path:
    """``.cs451-cache/<name>`` in the kit (ignored by git, hidden from submissions), else ``$XDG_CACHE_HOME/cs451/
    <name>`` (``~/.cache``) where the kit cannot be written (an installed wheel, a read-only checkout)."""
    folder = KIT_ROOT / ".cs451-cache"
    if os.access(folder if folder.exists() else KIT_ROOT, os.W_OK):
        return folder / name
    return Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "cs451" / name
