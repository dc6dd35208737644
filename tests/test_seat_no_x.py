"""Seat: a GPU machine without X (issue 33). The kit renders, grades and runs its demos' windowless mode with every
X, GLX and GLUT library unloadable, and a missing GL library is named in one line with the package that has it.

The libraries are hidden in a private mount namespace (tests/seats/no_x.py: each file covered by /dev/null), so
loading one fails as it would on a server that never installed it; the kit's console script runs there in a clean
environment (only its venv on PATH). Needs root and util-linux's ``unshare``. The whole-kit runs are marked
``seat`` (CI runs them: ``.venv/bin/python -m pytest -m seat``); the one-line error is part of the fast suite.
"""
from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from cs451 import KIT_ROOT
from cs451.gl import LINUX_LIBRARIES
from cs451.grading.results import total_score
from cs451.imageio import load_png
from cs451.stages import stage_names

from conftest import clean_env, world_readable_dir
from seats.no_x import LIBRARY_DIRS, hidden_libraries, hiding, without_x

pytestmark = pytest.mark.skipif(os.geteuid() != 0 or not shutil.which("unshare") or not sys.platform.startswith("linux"),
                                reason="hiding libraries needs root and unshare on Linux")

CS451 = Path(sys.prefix) / "bin" / "cs451"


def run_without(command: list[str], home: Path, hide: list[Path] | None = None, timeout: float = 1800
                ) -> subprocess.CompletedProcess:
    """``command`` through the kit's console script's venv, in a clean environment, with ``hide`` (default: X's
    libraries) unloadable."""
    env = clean_env(home, CS451.parent)
    wrapped = without_x(command) if hide is None else hiding(hide, command)
    return subprocess.run(wrapped, cwd=KIT_ROOT, env=env, capture_output=True, text=True, timeout=timeout)


@pytest.mark.spawns
def test_the_hidden_set_is_what_a_server_without_x_lacks(tmp_path):
    names = {p.name for p in hidden_libraries()}
    assert {"libGL.so.1", "libGLX.so.0", "libXrender.so.1"} & names, sorted(names)
    assert not {"libEGL.so.1", "libOpenGL.so.0"} & names
    probe = "import ctypes\nfor n in ('libGL.so.1', 'libXrender.so.1'):\n    try:\n        ctypes.CDLL(n); print(n)\n" \
            "    except OSError:\n        pass\n"
    done = run_without([sys.executable, "-c", probe], tmp_path / "home")
    assert done.returncode == 0 and done.stdout.strip() == "", done.stdout + done.stderr


@pytest.mark.spawns
def test_a_missing_gl_library_is_named_in_one_line_with_its_package(tmp_path):
    # libOpenGL.so.0, and the libGL names the loaders fall back to (libGL.so from a -dev package, libGL.so.1)
    gl = [p for d in LIBRARY_DIRS if d.is_dir() for pattern in (LINUX_LIBRARIES["libgl"] + "*", "libGL.so*")
          for p in d.glob(pattern)]
    assert any(p.name.startswith(LINUX_LIBRARIES["libgl"]) for p in gl), "no libOpenGL.so.0 here to hide"
    done = run_without([str(CS451), "render", "sphere", "-o", str(tmp_path / "s.png")], tmp_path / "home", hide=gl)
    assert done.returncode != 0
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in done.stderr, done.stderr
    assert "libOpenGL.so.0 cannot be loaded" in lines[0] and "apt-get install libopengl0" in lines[0], lines[0]
    assert not (tmp_path / "s.png").exists()


@pytest.mark.spawns
@pytest.mark.seat
@pytest.mark.parametrize("stage", stage_names())
def test_every_stage_renders_grades_and_demos_without_x(stage, tmp_path):
    home = tmp_path / "home"
    out = tmp_path / f"{stage}.png"
    done = run_without([str(CS451), "render", "--stage", stage, _scene(stage), "-o", str(out)], home)
    assert done.returncode == 0, done.stderr[-2000:]
    assert load_png(out).max() > 0

    submission = world_readable_dir("cs451-nox-sub-")
    try:   # a readable copy of a reference left behind would make every later grading refuse (the canary finds it)
        shutil.copytree(KIT_ROOT / "reference" / stage, submission / stage, ignore=shutil.ignore_patterns("__pycache__"))
        results = tmp_path / "results.json"
        done = run_without([str(CS451), "grade", stage, "--submission", str(submission), "--results", str(results)],
                           home)
    finally:
        shutil.rmtree(submission, ignore_errors=True)
    assert done.returncode == 0, done.stdout[-2000:] + done.stderr[-2000:]
    graded = json.loads(results.read_text())
    points = sum(t["max_score"] for t in graded["tests"])
    assert points > 0 and total_score(graded) == pytest.approx(points), done.stdout[-3000:]
    assert "bubblewrap" in done.stdout + done.stderr + graded.get("output", "")

    demo = tmp_path / "demo"
    done = run_without([str(CS451), "demo", stage, "--no-window", "--frames", "2", "-o", str(demo)], home)
    assert done.returncode == 0, done.stderr[-2000:]
    assert list(demo.glob("*.png")), sorted(p.name for p in demo.iterdir()) if demo.exists() else "no folder"


def _scene(stage: str) -> str:
    """A scene the stage draws: the bundled scene named after it, else the Cornell box (asked of the stage)."""
    from cs451.scene import BUNDLED_DIR, load_scene
    from cs451.stages import get_stage
    name = stage if (BUNDLED_DIR / f"{stage}.json").exists() else "cornell-box"
    assert get_stage(stage).draws_scene(load_scene(name)), f"stage {stage} draws neither its own scene nor the box"
    return name
