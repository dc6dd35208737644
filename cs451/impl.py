"""Finding and importing an implementation of a stage: the reference, the starter, or a student's folder."""
from __future__ import annotations

import hashlib
import importlib.util
import os
import sys
from pathlib import Path
from types import ModuleType

from . import KIT_ROOT
from .caches import kit_cache
from .errors import KitError, SubmissionError


def resolve_impl(spec: str | Path, stage: str) -> Path:
    """'reference', 'starter', or a path (to the stage folder itself or to a folder holding it)."""
    spec = str(spec)
    if spec in ("reference", "starter"):
        root = KIT_ROOT / spec
    else:
        root = Path(spec).expanduser()
        if not root.exists():
            raise SubmissionError(f"{root}: submission folder not found")
    root = root.resolve()
    for candidate in (root / stage, root):
        if (candidate / "__init__.py").is_file():
            return candidate
    nested = _nested_packages(root, stage)
    if len(nested) == 1:  # an upload of a whole repository: <repo>/starter/sphere/, say
        return nested[0]
    if nested:
        raise SubmissionError(f"{root}: more than one '{stage}' package in it ({', '.join(str(p) for p in nested)}); "
                       f"submit just one")
    raise SubmissionError(f"{root}: no '{stage}' package here (expected {root / stage / '__init__.py'}; "
                   f"copy starter/{stage}/ and edit it)")


def earlier_stage_impl(stage: str) -> Path:
    """The implementation of an earlier stage that a later stage's engine runs (stage 4 runs stage 3's hemicube).

    The kit's reference where this copy has it (the instructor's kit, or a student copy released with
    ``--include-reference``); in a student copy without it, the student's own package of that stage,
    copied beside this one. Student code of the current stage never gets here, and no grading worker
    does: a sandbox holds the engine alone, and the tests pass the earlier stage's results in as arrays.
    """
    for root in (KIT_ROOT / "reference", KIT_ROOT):
        if (root / stage / "__init__.py").is_file():
            return root / stage
    raise KitError(f"this stage draws with a stage-'{stage}' implementation, and this copy has none: copy your "
                   f"own {stage}/ package from that stage's repository into {KIT_ROOT} (or ask your instructor "
                   f"for a release built with --include-reference {stage})")


def _keep_numba_cache_by_path() -> None:
    """Make numba cache by the source's absolute folder, in the kit's cache (``numba``), not in ``__pycache__``.

    A package is imported under a name made from its path (below), and numba's machine code refers to the
    module by that name. In ``__pycache__`` the code travels with a copy of the package (``cp -a``, ``git mv``)
    and is loaded there under the old name: ``ModuleNotFoundError: _cs451_impl_whitted_…``. Kept by folder,
    a copy compiles its own. Set before any kernel is decorated; numba reads the variable when it is imported.
    """
    if os.environ.get("NUMBA_CACHE_DIR"):
        return
    folder = str(kit_cache("numba"))
    os.environ["NUMBA_CACHE_DIR"] = folder
    config = sys.modules.get("numba.core.config")
    if config is not None:
        config.CACHE_DIR = folder   # type: ignore[attr-defined]


def load_impl(folder: Path, stage: str) -> ModuleType:
    """Import a stage package from a folder under a private name, so two implementations never clash."""
    digest = hashlib.sha1(str(folder).encode()).hexdigest()[:10]
    name = f"_cs451_impl_{stage}_{digest}"
    if name in sys.modules:
        return sys.modules[name]
    _keep_numba_cache_by_path()
    spec = importlib.util.spec_from_file_location(name, folder / "__init__.py",
                                                  submodule_search_locations=[str(folder)])
    if spec is None or spec.loader is None:
        raise KitError(f"{folder}: cannot import")
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    try:
        spec.loader.exec_module(module)
    except SyntaxError as err:
        del sys.modules[name]
        raise KitError(f"{err.filename}:{err.lineno}: syntax error: {err.msg}") from None
    except Exception as err:
        del sys.modules[name]
        raise KitError(f"{folder}: importing the submission failed: {type(err).__name__}: {err}") from None
    return module


def _nested_packages(root: Path, stage: str, depth: int = 3) -> list[Path]:
    """Folders named ``stage`` holding an ``__init__.py`` up to ``depth`` levels below ``root``."""
    found, level = [], [root]
    for _ in range(depth):
        nxt = []
        for folder in level:
            try:
                children = [c for c in folder.iterdir() if c.is_dir() and not c.is_symlink()]
            except OSError:
                continue
            for child in children:
                if child.name.startswith(".") or child.name in ("__pycache__", "node_modules", "venv"):
                    continue
                if child.name == stage and (child / "__init__.py").is_file():
                    found.append(child)
                else:
                    nxt.append(child)
        level = nxt
    return sorted(found)
