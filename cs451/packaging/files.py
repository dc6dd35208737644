"""Copying parts of the kit tree without the build litter (caches, virtual environments, bytecode)."""
from __future__ import annotations

import shutil
from pathlib import Path

from .. import ENGINE_DIR, KIT_ROOT

LITTER_PATTERNS = ("__pycache__", "*.pyc", ".pytest_cache", "*.egg-info", ".cs451-cache")
LITTER = shutil.ignore_patterns(*LITTER_PATTERNS)


def copy_tree(rel: str, dest_root: Path, ignore=LITTER) -> Path:
    """Copy ``KIT_ROOT/rel`` (a file or a folder) to ``dest_root/rel``; ``cs451/…`` is the engine's own,
    wherever it is installed."""
    engine = rel == "cs451" or rel.startswith("cs451/")
    src, dst = (ENGINE_DIR.parent if engine else KIT_ROOT) / rel, dest_root / rel
    dst.parent.mkdir(parents=True, exist_ok=True)
    if src.is_dir():
        shutil.copytree(src, dst, ignore=ignore, dirs_exist_ok=True)
    else:
        shutil.copy2(src, dst)
    return dst


def write_executable(path: Path, text: str) -> Path:
    path.write_text(text)
    path.chmod(0o755)
    return path
