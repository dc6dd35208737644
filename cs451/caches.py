"""Where the kit keeps what it computes once (slides' figures, compiled kernels, the reference's answers): beside
the kit, or the user's."""
from __future__ import annotations

import os
from pathlib import Path

from . import KIT_ROOT


def cache_home() -> Path:
    """``.cs451-cache`` in the kit (ignored by git, hidden from submissions), else ``$XDG_CACHE_HOME/cs451``
    (``~/.cache/cs451``) where the kit cannot be written (an installed wheel, a read-only checkout)."""
    folder = KIT_ROOT / ".cs451-cache"
    if os.access(folder if folder.exists() else KIT_ROOT, os.W_OK):
        return folder
    return Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "cs451"


def kit_cache(name: str) -> Path:
    """``<cache_home()>/<name>``: one kind of what the kit computes once."""
    return cache_home() / name
