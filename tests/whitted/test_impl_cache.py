"""A package's compiled kernels survive the package being copied or moved with its ``__pycache__`` (issue 33).

Each implementation folder is imported under a private name made from its path (cs451/impl.py, ``load_impl``), and
numba's cached machine code refers to the module by that name. When the cache sat in ``__pycache__``, a copy made
with ``cp -a`` (or a ``git mv``) loaded the original's entry under the old name and failed at once with
``ModuleNotFoundError: _cs451_impl_whitted_<hash>``. The cache now lives in the kit's cache folder, by path.
"""
from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from cs451 import KIT_ROOT

KERNEL = '''from numba import njit


@njit(cache=True)
def twice(x):
    return 2 * x
'''
LOAD = "import sys; from pathlib import Path; from cs451.impl import load_impl; " \
       "print(load_impl(Path(sys.argv[1]), 'whitted').twice(21))"


def load_in_a_new_process(folder: Path) -> subprocess.CompletedProcess:
    """Load the package as a fresh ``cs451`` process does (numba's cache where the kit puts it; bytecode written)."""
    env = {k: v for k, v in os.environ.items() if k not in ("NUMBA_CACHE_DIR", "PYTHONDONTWRITEBYTECODE")}
    return subprocess.run([sys.executable, "-c", LOAD, str(folder)], cwd=KIT_ROOT, env=env, capture_output=True,
                          text=True, timeout=300)


@pytest.mark.spawns
@pytest.mark.parametrize("how", ["cp -a", "mv"])
def test_a_copied_or_moved_package_loads_its_kernels(tmp_path, how):
    original = tmp_path / "mine" / "whitted"
    original.mkdir(parents=True)
    (original / "__init__.py").write_text(KERNEL)
    first = load_in_a_new_process(original)
    assert first.returncode == 0 and first.stdout.strip() == "42", first.stderr[-1500:]
    elsewhere = tmp_path / "elsewhere" / "whitted"
    elsewhere.parent.mkdir()
    if how == "cp -a":
        shutil.copytree(original, elsewhere, symlinks=True)
    else:
        original.rename(elsewhere)
    again = load_in_a_new_process(elsewhere)
    assert again.returncode == 0 and again.stdout.strip() == "42", again.stderr[-1500:]
    assert not list(elsewhere.glob("__pycache__/*.nbi")), "numba still caches beside the source"
